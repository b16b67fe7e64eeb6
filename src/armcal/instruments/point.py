"""Fixed points: every row's tool point sits in one of several fixed points.

A fixed point (a cone, a ball socket, a pin) is ``c_k`` in the robot's base
frame; a row reports the tool point's offset from it, ``p - c_k`` (mm; 0 where
the tool sits in it).  Unknowns: every point's position, ``{label}.x``,
``{label}.y``, ``{label}.z`` (mm), starting where the user says it roughly is.

**What a fixed point cannot see.**  Turning the whole arm about a point keeps
the tool in it: three turns about one point, and about the line through two
(one turn) with two points.  Nor can points alone see scale beyond what the
arm's own lengths fix (a known distance between two fixes it).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np

from .base import Instrument, MeetsAtZero, feature_index, same_features

__all__ = ["FixedPoints"]


@dataclass(frozen=True, eq=False)
class FixedPoints(MeetsAtZero):
    """Seatings in one or several fixed points (module notes).

    Attributes
    ----------
    points : mapping of str to array of shape (3,)
        Every point by its label (a row's ``point`` column): where it roughly is, mm.
    """

    points: Mapping[str, np.ndarray] = field(default_factory=dict)

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

    @property
    def kind(self) -> str:
        return "point"

    @property
    def labels(self) -> tuple[str, ...]:
        return tuple(self.points)

    @property
    def dim(self) -> int:
        return 3

    @property
    def param_names(self) -> tuple[str, ...]:
        return tuple(f"{k}.{c}" for k in self.labels for c in ("x", "y", "z"))

    @property
    def param_units(self) -> tuple[str, ...]:
        return ("mm",) * (3 * len(self.points))

    @property
    def start(self) -> np.ndarray:
        return np.concatenate(list(self.points.values()))

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
    def label_column(self) -> str | None:
        return "point"

    @property
    def reading_columns(self) -> tuple[str, ...]:
        return ()

    def params_of(self, true: Instrument) -> np.ndarray:
        """``true``'s points' positions."""
        same_features(self, true)
        return np.asarray(true.start, dtype=float)

    def out_of_reach(self, reach_mm: float) -> str | None:
        for label, xyz in self.points.items():
            far = float(np.linalg.norm(xyz))
            if far > reach_mm:
                return (
                    f"point {label!r} lies {far:.6g} mm from the base, beyond the tool's "
                    f"reach ({reach_mm:.6g} mm)"
                )
        return None

    def reading(
        self, points: np.ndarray, feature: np.ndarray | None, params: np.ndarray
    ) -> np.ndarray:
        """Offsets ``(..., m, 3)`` (mm) of ``points`` from their fixed points."""
        k = feature_index(feature, np.shape(points)[-2], self.labels)
        centres = np.asarray(params, dtype=float).reshape(*np.shape(params)[:-1], -1, 3)
        return points - centres[..., k, :]

    def curvatures(
        self, points: np.ndarray, feature: np.ndarray | None, params: np.ndarray
    ) -> tuple[np.ndarray | None, np.ndarray | None]:
        """None and None: a reading is linear in the point and in the fixed point."""
        return None, None

    def derivatives(
        self, points: np.ndarray, feature: np.ndarray | None, params: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray]:
        """The identity ``(..., m, 3, 3)`` and ``-I`` at the row's point ``(..., m, 3, 3K)``."""
        m = np.shape(points)[-2]
        k = feature_index(feature, m, self.labels)
        shape = np.broadcast_shapes(np.shape(points)[:-2], np.shape(params)[:-1])
        by_params = np.zeros((*shape, m, 3, 3 * len(self.points)))
        rows = np.arange(m)
        for c in range(3):
            by_params[..., rows, c, 3 * k + c] = -1.0
        by_points = np.broadcast_to(np.eye(3), (*shape, m, 3, 3))
        return by_points, by_params
