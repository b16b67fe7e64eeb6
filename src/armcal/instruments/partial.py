"""Partial coordinates: an instrument that reads some of the tool point's coordinates.

A dial indicator, a laser displacement sensor, a constraint rig or a CMM with a
coordinate missing reads the tool point ``p`` (base frame) along some of the
axes of its own frame: ``y_k = e_k . R^T (p - t)`` for the axes ``k`` it reads
(``reads``, a subset of x, y, z), where ``R``, ``t`` are its orientation and
origin.  A row of a measurement file gives any of those coordinates (its
``x_mm``, ``y_mm``, ``z_mm`` cells, empty where it did not read one); each is a
feature of the instrument (:attr:`Coordinates.labels`) and one number of its own,
with the sigma of its axis.

**Parameters.**  Small moves from where the user says the instrument roughly
is, ``(R0, t0)``: ``R = R0 E_a E_b E_c``, three turns about the instrument's own
axes (``instrument.rx``, ``.ry``, ``.rz``, rad), and ``t = t0 + R d`` with ``d``
its shift along its own axes (``instrument.x``, ``.y``, ``.z``, mm), so that
``y_k = e_k . R^T (p - t0) - d_k``.  The turns are taken in the order x, y, z,
except for an instrument of one axis, whose own turn is taken last (z: x, y, z;
x: y, z, x; y: z, x, y), so that ``R e_k`` does not depend on it at all.

**What partial coordinates cannot see.**  A shift of the whole arm along an
axis the instrument does not read changes no reading: ``d_j`` of an unread axis
is held (:attr:`Coordinates.held`).  An instrument of one axis cannot see a
turn about that axis either (``R e_k`` above), which is held too.  With two axes
or three it sees the arm's whole pose, as a tracker does.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np

from ..models.spatial.chain import rpy_matrix
from ..noise import NoiseModel
from .base import (
    Defaults,
    Instrument,
    feature_index,
    same_features,
    turned_frame,
    turns_between,
)

__all__ = ["AXES", "Coordinates"]

#: The axes a partial instrument may read, in its frame's order.
AXES = ("x", "y", "z")


@dataclass(frozen=True, eq=False)
class Coordinates(Defaults):
    """Partial coordinates (module notes).

    Attributes
    ----------
    reads : tuple of str
        The axes the instrument reads, in the order x, y, z (a subset).
    xyz_mm : ndarray, shape (3,)
        Where the user says the instrument's origin roughly is (base frame, mm).
    rpy_deg : ndarray, shape (3,)
        Its orientation, roll, pitch and yaw as in URDF (``Rz Ry Rx``), degrees.
    """

    reads: tuple[str, ...]
    xyz_mm: np.ndarray
    rpy_deg: np.ndarray

    def __post_init__(self) -> None:
        reads = tuple(self.reads)
        if not reads or len(set(reads)) != len(reads) or not set(reads) <= set(AXES):
            raise ValueError("reads must name some of the axes x, y, z, each once")
        object.__setattr__(self, "reads", tuple(a for a in AXES if a in reads))
        for name in ("xyz_mm", "rpy_deg"):
            value = np.asarray(getattr(self, name), dtype=float)
            if value.shape != (3,) or not np.all(np.isfinite(value)):
                raise ValueError(f"{name} must be 3 finite numbers")
            object.__setattr__(self, name, value)

    @property
    def kind(self) -> str:
        return "partial"

    @property
    def labels(self) -> tuple[str, ...]:
        """The axes it reads: every row's coordinate along one is a feature."""
        return self.reads

    @property
    def dim(self) -> int:
        return 1

    @property
    def param_names(self) -> tuple[str, ...]:
        return tuple(f"instrument.{c}" for c in ("x", "y", "z", "rx", "ry", "rz"))

    @property
    def param_units(self) -> tuple[str, ...]:
        return ("mm",) * 3 + ("rad",) * 3

    @property
    def start(self) -> np.ndarray:
        return np.zeros(6)

    @property
    def held(self) -> tuple[str, ...]:
        """The shifts along the axes it does not read; with one axis, the turn about it."""
        out = [f"instrument.{a}" for a in AXES if a not in self.reads]
        if len(self.reads) == 1:
            out.append(f"instrument.r{self.reads[0]}")
        return tuple(out)

    @property
    def unseen(self) -> str:
        read = " and ".join(self.reads)
        if len(self.reads) == 3:
            return (
                "reading x, y and z it sees the arm as a tracker does: the arm's pose in its "
                "frame is the instrument's own placement"
            )
        missing = " or ".join(a for a in AXES if a not in self.reads)
        words = (
            f"reading only {read}, it cannot see the arm move along the instrument's "
            f"{missing} ax{'es' if len(self.reads) == 1 else 'is'}"
        )
        if len(self.reads) == 1:
            words += f", nor turn about its {read} axis"
        return words

    @property
    def marks(self) -> tuple[tuple[str, np.ndarray], ...]:
        return (("instrument", self.xyz_mm),)

    @property
    def label_column(self) -> str | None:
        return None

    @property
    def reading_columns(self) -> tuple[str, ...]:
        return tuple(f"{a}_mm" for a in self.reads)

    @property
    def constrained(self) -> bool:
        """False: it reads the tool wherever it is."""
        return False

    @property
    def reads_every_feature(self) -> bool:
        """True: a row reads every axis, one column each (empty where it did not)."""
        return True

    def feature_sigma(self, noise: NoiseModel) -> np.ndarray | None:
        """Every axis's std (mm) from the robot file's ``sigma_mm = [sx, sy, sz]`` where
        they differ; None for one sigma.  ValueError for a laser tracker's model or a
        covariance with correlations (rows of one number each have none)."""
        if noise.tracker is not None:
            raise ValueError(
                "a laser tracker's noise model is for 3-D points; give sigma_mm per axis "
                "[sx, sy, sz]"
            )
        cov = np.asarray(noise.covariance_mm2, dtype=float)
        if cov.shape == (1, 1) or noise.isotropic_instrument:
            return None
        if cov.shape != (3, 3) or np.count_nonzero(cov - np.diag(np.diagonal(cov))):
            raise ValueError(
                "partial coordinates are read one at a time: give sigma_mm as one number or "
                "one per axis [sx, sy, sz], not a covariance"
            )
        return np.sqrt(np.diagonal(cov))[[AXES.index(a) for a in self.reads]]

    @cached_property
    def _order(self) -> tuple[int, int, int]:
        """The axes of the three turns, in order (module notes)."""
        if len(self.reads) == 1:
            k = AXES.index(self.reads[0])
            return ((k + 1) % 3, (k + 2) % 3, k)
        return (0, 1, 2)

    @cached_property
    def _frame(self) -> np.ndarray:
        """``R0`` ``(3, 3)``."""
        return rpy_matrix(np.radians(self.rpy_deg))

    def rotation(self, params: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """``R`` ``(..., 3, 3)`` at ``params`` ``(..., 6)`` and its derivatives by the turns
        about x, y and z ``(..., 3, 3, 3)`` (the turn first)."""
        return turned_frame(self._frame, np.asarray(params, dtype=float)[..., 3:], self._order)

    def params_of(self, true: Instrument) -> np.ndarray:
        """The shift and the turns that put the instrument where ``true`` is
        (:func:`~armcal.instruments.base.turns_between`), and ``d = R^T (t - t0)``."""
        same_features(self, true)
        assert isinstance(true, Coordinates)
        r = true._frame
        return np.concatenate(
            [r.T @ (true.xyz_mm - self.xyz_mm), turns_between(self._frame, r, self._order)]
        )

    def out_of_reach(self, reach_mm: float) -> str | None:
        return None

    def _axes(self, feature: np.ndarray | None, m: int) -> np.ndarray:
        """Every row's axis index (0, 1, 2 for x, y, z)."""
        index = feature_index(feature, m, self.labels)
        return np.array([AXES.index(a) for a in self.reads])[index]

    def reading(
        self, points: np.ndarray, feature: np.ndarray | None, params: np.ndarray
    ) -> np.ndarray:
        """``e_k . R^T (p - t0) - d_k`` ``(..., m, 1)`` (mm)."""
        k = self._axes(feature, np.shape(points)[-2])
        params = np.asarray(params, dtype=float)
        r, _ = self.rotation(params)
        axes = np.swapaxes(r, -1, -2)[..., k, :]  # R e_k of every row (..., m, 3)
        value = np.sum(axes * (points - self.xyz_mm), axis=-1) - params[..., k]
        return value[..., None]

    def miss(
        self, points: np.ndarray, feature: np.ndarray | None, params: np.ndarray
    ) -> np.ndarray:
        """0: it reads the tool wherever it is."""
        return np.zeros((*np.broadcast_shapes(np.shape(points)[:-1]), 1))

    def derivatives(
        self, points: np.ndarray, feature: np.ndarray | None, params: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray]:
        """``R e_k`` ``(..., m, 1, 3)``; -1 at ``d_k`` and ``dR/da e_k . (p - t0)`` at the
        turns ``(..., m, 1, 6)``."""
        m = np.shape(points)[-2]
        k = self._axes(feature, m)
        r, by = self.rotation(params)
        axes = np.swapaxes(r, -1, -2)[..., k, :]  # (..., m, 3)
        turned = np.moveaxis(np.swapaxes(by, -1, -2)[..., k, :], -3, -2)  # (..., m, 3, 3)
        offset = points - self.xyz_mm
        shape = np.broadcast_shapes(axes.shape[:-1], offset.shape[:-1])
        out = np.zeros((*shape, 1, 6))
        out[..., 0, 3:] = np.einsum("...ta,...a->...t", turned, offset)
        out[..., np.arange(m), 0, k] = -1.0
        return np.broadcast_to(axes, (*shape, 3))[..., None, :], out

    def curvatures(
        self, points: np.ndarray, feature: np.ndarray | None, params: np.ndarray
    ) -> tuple[np.ndarray | None, np.ndarray | None]:
        """None (a reading is linear in the point) and ``dR/da e_k`` at the turns ``(...,
        m, 1, 6, 3)``."""
        m = np.shape(points)[-2]
        k = self._axes(feature, m)
        _, by = self.rotation(params)
        turned = np.moveaxis(np.swapaxes(by, -1, -2)[..., k, :], -3, -2)  # (..., m, 3, 3)
        shape = np.broadcast_shapes(turned.shape[:-2], np.shape(points)[:-1])
        out = np.zeros((*shape, 1, 6, 3))
        out[..., 0, 3:, :] = turned
        return None, out
