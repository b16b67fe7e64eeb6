"""Contact with planes: every row's tool point touches one of several planes.

A plane ``k`` is ``n_k . p = d_k`` in the robot's base frame, ``n_k`` a unit
normal and ``d_k`` its offset (mm).  A row reports the signed distance of the
tool point from its plane, ``n_k . p - d_k`` (mm; 0 where it touches).

**Parameters.**  A normal is two small turns from where the user says it
roughly points, ``n0_k``: ``n_k = R0_k Rx(a) Ry(b) e_z`` with ``R0_k`` the
rotation from ``e_z`` to ``n0_k`` (:func:`~armcal.instruments.base.z_to`), so
``u = Rx(a) Ry(b) e_z = (sin b, -sin a cos b, cos a cos b)``; the parameters are
``{label}.rx = a``, ``{label}.ry = b`` (rad) and ``{label}.offset = d_k`` (mm),
starting at ``0, 0, d0_k``.  Two turns and an offset are a plane's three degrees
of freedom, and the turns stay small, far from the parametrization's poles.

**What a plane cannot see.**  Moving the tool along the plane, or turning it
about a normal, leaves every touch on it: the shift of the whole arm along a
plane and its turn about the plane's normal.  With several planes whose normals
span space, only turns about an axis every normal contains stay unseen.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from functools import cached_property

import numpy as np

from .base import Instrument, MeetsAtZero, feature_index, same_features, z_to

__all__ = ["Plane", "Planes"]


@dataclass(frozen=True)
class Plane:
    """Where the user says a plane roughly is: ``normal . p = offset_mm`` (base frame).

    Attributes
    ----------
    normal : ndarray, shape (3,)
        Its normal, made unit length.
    offset_mm : float
        Its signed distance from the base's origin along the normal, mm.
    """

    normal: np.ndarray
    offset_mm: float

    def __post_init__(self) -> None:
        normal = np.asarray(self.normal, dtype=float)
        size = float(np.linalg.norm(normal)) if normal.shape == (3,) else 0.0
        if not np.isfinite(size) or size == 0.0:
            raise ValueError("a plane's normal must be 3 finite numbers, not all 0")
        if not np.isfinite(self.offset_mm):
            raise ValueError("a plane's offset must be a finite number (mm)")
        object.__setattr__(self, "normal", normal / size)
        object.__setattr__(self, "offset_mm", float(self.offset_mm))


@dataclass(frozen=True, eq=False)
class Planes(MeetsAtZero):
    """Touches of one or several planes (module notes).

    Attributes
    ----------
    planes : mapping of str to Plane
        Every plane by its label (a row's ``plane`` column), where it roughly is.
    """

    planes: Mapping[str, Plane] = field(default_factory=dict)

    def __post_init__(self) -> None:
        if not self.planes:
            raise ValueError("a plane instrument needs at least one plane")
        object.__setattr__(self, "planes", dict(self.planes))

    @property
    def kind(self) -> str:
        return "plane"

    @property
    def labels(self) -> tuple[str, ...]:
        return tuple(self.planes)

    @property
    def dim(self) -> int:
        return 1

    @property
    def param_names(self) -> tuple[str, ...]:
        return tuple(f"{k}.{c}" for k in self.labels for c in ("rx", "ry", "offset"))

    @property
    def param_units(self) -> tuple[str, ...]:
        return ("rad", "rad", "mm") * len(self.planes)

    @property
    def start(self) -> np.ndarray:
        return np.array([[0.0, 0.0, p.offset_mm] for p in self.planes.values()]).ravel()

    @property
    def unseen(self) -> str:
        if len(self.planes) == 1:
            return (
                "a plane cannot see the tool move along it: a shift of the whole arm along "
                "the plane and a turn about its normal leave every touch on it"
            )
        return (
            "planes cannot see the tool move along all of them at once: a shift along "
            "every plane and a turn about an axis every normal contains leave every touch "
            "where it is"
        )

    @property
    def marks(self) -> tuple[tuple[str, np.ndarray], ...]:
        return tuple((k, p.offset_mm * p.normal) for k, p in self.planes.items())

    @property
    def label_column(self) -> str | None:
        return "plane"

    @property
    def reading_columns(self) -> tuple[str, ...]:
        return ()

    def params_of(self, true: Instrument) -> np.ndarray:
        """The turns and offsets that put each plane where ``true``'s is: with ``u = R0^T n``,
        ``b = asin(u_x)`` and ``a = atan2(-u_y, u_z)`` (module notes)."""
        same_features(self, true)
        assert isinstance(true, Planes)
        out = []
        for frame, plane in zip(self._frames, true.planes.values(), strict=True):
            u = frame.T @ plane.normal
            out.append(
                [np.arctan2(-u[1], u[2]), np.arcsin(np.clip(u[0], -1.0, 1.0)), plane.offset_mm]
            )
        return np.array(out).ravel()

    def out_of_reach(self, reach_mm: float) -> str | None:
        for label, plane in self.planes.items():
            if abs(plane.offset_mm) > reach_mm:
                return (
                    f"plane {label!r} lies {abs(plane.offset_mm):.6g} mm from the base, beyond "
                    f"the tool's reach ({reach_mm:.6g} mm)"
                )
        return None

    @cached_property
    def _frames(self) -> np.ndarray:
        """``R0_k`` ``(K, 3, 3)``: from ``e_z`` to each plane's rough normal."""
        return np.stack([z_to(p.normal) for p in self.planes.values()])

    def normals(self, params: np.ndarray) -> np.ndarray:
        """Every plane's unit normal ``(..., K, 3)`` at ``params`` ``(..., 3K)``."""
        a, b, _ = self._split(params)
        return np.einsum("kij,...kj->...ki", self._frames, _turned(a, b))

    def _split(self, params: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        p = np.asarray(params, dtype=float).reshape(*np.shape(params)[:-1], len(self.planes), 3)
        return p[..., 0], p[..., 1], p[..., 2]

    def reading(
        self, points: np.ndarray, feature: np.ndarray | None, params: np.ndarray
    ) -> np.ndarray:
        """Signed distances ``(..., m, 1)`` (mm) of ``points`` from their planes."""
        k = feature_index(feature, np.shape(points)[-2], self.labels)
        _, _, offset = self._split(params)
        normal = self.normals(params)[..., k, :]  # (..., m, 3)
        return (np.sum(normal * points, axis=-1) - offset[..., k])[..., None]

    def derivatives(
        self, points: np.ndarray, feature: np.ndarray | None, params: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray]:
        """``d reading / d points`` ``(..., m, 1, 3)`` (the normal) and ``d reading /
        d params`` ``(..., m, 1, 3K)``: ``R0 du/da . p``, ``R0 du/db . p`` and -1 at the
        row's plane, 0 at the others."""
        m = np.shape(points)[-2]
        k = feature_index(feature, m, self.labels)
        a, b, _ = self._split(params)
        frames = self._frames[k]  # (m, 3, 3)
        ca, sa, cb, sb = np.cos(a[..., k]), np.sin(a[..., k]), np.cos(b[..., k]), np.sin(b[..., k])
        zero = np.zeros_like(ca)
        du_da = np.stack([zero, -ca * cb, -sa * cb], axis=-1)
        du_db = np.stack([cb, sa * sb, -ca * sb], axis=-1)
        u = np.stack([sb, -sa * cb, ca * cb], axis=-1)
        normal = np.einsum("mij,...mj->...mi", frames, u)
        by_a = np.sum(np.einsum("mij,...mj->...mi", frames, du_da) * points, axis=-1)
        by_b = np.sum(np.einsum("mij,...mj->...mi", frames, du_db) * points, axis=-1)
        shape = np.broadcast_shapes(np.shape(by_a), np.shape(points)[:-1])
        out = np.zeros((*shape, 1, 3 * len(self.planes)))
        rows = np.arange(m)
        out[..., rows, 0, 3 * k] = by_a
        out[..., rows, 0, 3 * k + 1] = by_b
        out[..., rows, 0, 3 * k + 2] = -1.0
        return np.broadcast_to(normal, (*shape, 3))[..., None, :], out

    def curvatures(
        self, points: np.ndarray, feature: np.ndarray | None, params: np.ndarray
    ) -> tuple[np.ndarray | None, np.ndarray | None]:
        """None (a reading is linear in the point) and ``R0 du/da``, ``R0 du/db`` at the
        row's plane's turns ``(..., m, 1, 3K, 3)``."""
        m = np.shape(points)[-2]
        k = feature_index(feature, m, self.labels)
        a, b, _ = self._split(params)
        frames = self._frames[k]
        ca, sa, cb, sb = np.cos(a[..., k]), np.sin(a[..., k]), np.cos(b[..., k]), np.sin(b[..., k])
        zero = np.zeros_like(ca)
        by_a = np.einsum("mij,...mj->...mi", frames, np.stack([zero, -ca * cb, -sa * cb], -1))
        by_b = np.einsum("mij,...mj->...mi", frames, np.stack([cb, sa * sb, -ca * sb], -1))
        shape = np.broadcast_shapes(np.shape(by_a)[:-1], np.shape(points)[:-1])
        out = np.zeros((*shape, 1, 3 * len(self.planes), 3))
        rows = np.arange(m)
        out[..., rows, 0, 3 * k, :] = by_a
        out[..., rows, 0, 3 * k + 1, :] = by_b
        return None, out


def _turned(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """``Rx(a) Ry(b) e_z`` ``(..., 3)``."""
    return np.stack([np.sin(b), -np.sin(a) * np.cos(b), np.cos(a) * np.cos(b)], axis=-1)
