"""Fixed points: every row's tool point sits in one of several fixed points.

A fixed point (a cone, a ball socket, a pin) is ``c_k`` in the robot's base
frame; a row reports the tool point's offset from it, ``p - c_k`` (mm; 0 where
the tool sits in it).  Unknowns: every point's position, ``{label}.x``,
``{label}.y``, ``{label}.z`` (mm), starting where the user says it roughly is.

**What a fixed point cannot see.**  Turning the whole arm about a point keeps
the tool in it: three turns about one point, and about the line through two
(one turn) with two points.  Nor can points alone see scale beyond what the
arm's own lengths fix (a known distance between two fixes it).

**A known distance** (a calibrated bar between two cones) ties one point to
another: ``c_B = c_A + d R0 Rx(a) Ry(b) e_z``, ``R0`` the rotation from ``e_z`` to
the direction from A to B where the user says they roughly are
(:func:`~armcal.instruments.base.z_to`); B's parameters are the two small turns
``B.rx = a``, ``B.ry = b`` (rad), starting at 0, and the distance holds exactly.
A point is tied to at most one other, which is itself free.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from functools import cached_property

import numpy as np

from .base import Instrument, MeetsAtZero, feature_index, same_features, z_to

__all__ = ["FixedPoints"]


@dataclass(frozen=True, eq=False)
class FixedPoints(MeetsAtZero):
    """Seatings in one or several fixed points (module notes).

    Attributes
    ----------
    points : mapping of str to array of shape (3,)
        Every point by its label (a row's ``point`` column): where it roughly is, mm.
    known : tuple of (str, str, float)
        Known distances ``(A, B, d)`` (mm): B is tied to A at ``d`` (module notes).
    """

    points: Mapping[str, np.ndarray] = field(default_factory=dict)
    known: tuple[tuple[str, str, float], ...] = ()
    _tied: dict[str, tuple[str, float]] = field(init=False, repr=False, default_factory=dict)

    def __post_init__(self) -> None:
        if not self.points:
            raise ValueError("a fixed-point instrument needs at least one point")
        found = {}
        for label, xyz in self.points.items():
            value = np.asarray(xyz, dtype=float)
            if value.shape != (3,) or not np.all(np.isfinite(value)):
                raise ValueError(f"point {label}: its position must be 3 finite numbers (mm)")
            found[label] = value
        object.__setattr__(self, "points", found)
        tied: dict[str, tuple[str, float]] = {}
        for anchor, child, size in self.known:
            for label in (anchor, child):
                if label not in found:
                    raise ValueError(
                        f"known distance {anchor}-{child}: {label!r} is not a point; the "
                        f"points are {', '.join(found)}"
                    )
            if anchor == child or not (np.isfinite(size) and size > 0):
                raise ValueError(
                    f"known distance {anchor}-{child}: give two points and a distance > 0 (mm)"
                )
            if child in tied or anchor in tied or child in {a for a, _ in tied.values()}:
                raise ValueError(
                    f"known distance {anchor}-{child}: a point is tied to at most one other, "
                    "which is itself free (give each bar from a point no bar ends at)"
                )
            if np.linalg.norm(found[child] - found[anchor]) == 0:
                raise ValueError(f"known distance {anchor}-{child}: the two points coincide")
            tied[child] = (anchor, float(size))
        object.__setattr__(self, "known", tuple((a, b, float(d)) for a, b, d in self.known))
        object.__setattr__(self, "_tied", tied)

    @property
    def kind(self) -> str:
        return "point"

    @property
    def labels(self) -> tuple[str, ...]:
        return tuple(self.points)

    @property
    def dim(self) -> int:
        return 3

    @cached_property
    def _slots(self) -> tuple[tuple[int, int], ...]:
        """Every point's first parameter and count: 3 for a free point, 2 for a tied one."""
        out, at = [], 0
        for label in self.labels:
            count = 2 if label in self._tied else 3
            out.append((at, count))
            at += count
        return tuple(out)

    @cached_property
    def _frames(self) -> dict[str, np.ndarray]:
        """``R0`` of every tied point: from ``e_z`` to the rough direction from its anchor."""
        frames = {}
        for child, (anchor, _) in self._tied.items():
            way = self.points[child] - self.points[anchor]
            frames[child] = z_to(way / np.linalg.norm(way))
        return frames

    @property
    def param_names(self) -> tuple[str, ...]:
        names: list[str] = []
        for label in self.labels:
            axes = ("rx", "ry") if label in self._tied else ("x", "y", "z")
            names += [f"{label}.{c}" for c in axes]
        return tuple(names)

    @property
    def param_units(self) -> tuple[str, ...]:
        return tuple("rad" if n.endswith((".rx", ".ry")) else "mm" for n in self.param_names)

    @property
    def start(self) -> np.ndarray:
        return np.concatenate(
            [np.zeros(2) if k in self._tied else self.points[k] for k in self.labels]
        )

    @property
    def unseen(self) -> str:
        if len(self.points) == 1:
            return (
                "a fixed point cannot see the arm turn about it: three turns of the whole "
                "arm about the point keep the tool in it"
            )
        return (
            "fixed points cannot see the arm turn about the line through two of them when "
            "they all lie on it"
        )

    @property
    def marks(self) -> tuple[tuple[str, np.ndarray], ...]:
        return tuple(self.points.items())

    @property
    def label_column(self) -> str | None:
        return "point"

    @property
    def reading_columns(self) -> tuple[str, ...]:
        return ()

    def params_of(self, true: Instrument) -> np.ndarray:
        """``true``'s points' positions; a tied point's turns towards where ``true`` has
        it (ValueError where ``true``'s points are not the known distance apart)."""
        same_features(self, true)
        assert isinstance(true, FixedPoints)
        out: list[np.ndarray] = []
        for label in self.labels:
            if label not in self._tied:
                out.append(true.points[label])
                continue
            anchor, size = self._tied[label]
            way = true.points[label] - true.points[anchor]
            far = float(np.linalg.norm(way))
            if abs(far - size) > 1e-9 * max(size, 1.0):
                raise ValueError(
                    f"the true points {anchor} and {label} are {far:.9g} mm apart, not the "
                    f"known {size:g} mm"
                )
            u = self._frames[label].T @ (way / far)
            out.append(np.array([np.arctan2(-u[1], u[2]), np.arcsin(np.clip(u[0], -1.0, 1.0))]))
        return np.concatenate(out).astype(float)

    def out_of_reach(self, reach_mm: float) -> str | None:
        for label, xyz in self.points.items():
            far = float(np.linalg.norm(xyz))
            if far > reach_mm:
                return (
                    f"point {label!r} lies {far:.6g} mm from the base, beyond the tool's "
                    f"reach ({reach_mm:.6g} mm)"
                )
        return None

    def _centres(self, params: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Every point's position ``(..., K, 3)`` and its Jacobian ``(..., K, 3, t)``."""
        params = np.asarray(params, dtype=float)
        lead = params.shape[:-1]
        t = params.shape[-1]
        centres = np.zeros((*lead, len(self.points), 3))
        jac = np.zeros((*lead, len(self.points), 3, t))
        slot = dict(zip(self.labels, self._slots, strict=True))
        for k, label in enumerate(self.labels):  # free points first: the tied need them
            at, count = slot[label]
            if count == 3:
                centres[..., k, :] = params[..., at : at + 3]
                jac[..., k, :, at : at + 3] = np.eye(3)
        for k, label in enumerate(self.labels):
            at, count = slot[label]
            if count == 3:
                continue
            anchor, size = self._tied[label]
            j = self.labels.index(anchor)
            a, b = params[..., at], params[..., at + 1]
            ca, sa, cb, sb = np.cos(a), np.sin(a), np.cos(b), np.sin(b)
            frame = self._frames[label]
            u = np.stack([sb, -sa * cb, ca * cb], axis=-1)
            du_da = np.stack([np.zeros_like(a), -ca * cb, -sa * cb], axis=-1)
            du_db = np.stack([cb, sa * sb, -ca * sb], axis=-1)
            centres[..., k, :] = centres[..., j, :] + size * (u @ frame.T)
            jac[..., k, :, :] = jac[..., j, :, :]
            jac[..., k, :, at] = size * (du_da @ frame.T)
            jac[..., k, :, at + 1] = size * (du_db @ frame.T)
        return centres, jac

    def reading(
        self, points: np.ndarray, feature: np.ndarray | None, params: np.ndarray
    ) -> np.ndarray:
        """Offsets ``(..., m, 3)`` (mm) of ``points`` from their fixed points."""
        k = feature_index(feature, np.shape(points)[-2], self.labels)
        return points - self._centres(params)[0][..., k, :]

    def curvatures(
        self, points: np.ndarray, feature: np.ndarray | None, params: np.ndarray
    ) -> tuple[np.ndarray | None, np.ndarray | None]:
        """None and None: a reading is linear in the point, and its derivative by the
        parameters does not depend on it."""
        return None, None

    def derivatives(
        self, points: np.ndarray, feature: np.ndarray | None, params: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray]:
        """The identity ``(..., m, 3, 3)`` and minus the row's point's Jacobian ``(..., m,
        3, t)`` (``-I`` at a free point's own parameters)."""
        m = np.shape(points)[-2]
        k = feature_index(feature, m, self.labels)
        jac = self._centres(params)[1]
        shape = np.broadcast_shapes(np.shape(points)[:-2], np.shape(params)[:-1])
        by_params = np.broadcast_to(-jac[..., k, :, :], (*shape, m, 3, jac.shape[-1]))
        by_points = np.broadcast_to(np.eye(3), (*shape, m, 3, 3))
        return by_points, by_params
