"""A distance: a ballbar or a draw-wire sensor reads the tool point's distance from a pivot.

A row reports ``|p - c| - offset`` (mm): the distance of the tool point ``p`` from
the pivot ``c`` (base frame), less the reading's unknown offset (a ballbar's
nominal length, a draw-wire sensor's zero).  Unknowns: ``pivot.x``, ``pivot.y``,
``pivot.z`` (mm, starting where the user says the pivot roughly is) and
``offset`` (mm, starting at 0: the reading's zero is what it is).  A pose can be
measured only within the instrument's range of distances.

**What a distance cannot see.**  Turning the whole arm about the pivot keeps
every distance: three turns.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .base import Contact, Instrument, feature_index, same_features

__all__ = ["Distance"]


@dataclass(frozen=True, eq=False)
class Distance(Contact):
    """A distance from one pivot (module notes).

    Attributes
    ----------
    pivot_mm : ndarray, shape (3,)
        Where the user says the pivot roughly is (base frame, mm).
    range_mm : tuple of float
        The distances ``|p - c|`` the instrument can read, mm (a ballbar's travel).
    offset_mm : float
        The reading's offset where it is known (a virtual lab's truth); a user's starts
        at 0.
    """

    pivot_mm: np.ndarray
    range_mm: tuple[float, float]
    offset_mm: float = 0.0

    def __post_init__(self) -> None:
        pivot = np.asarray(self.pivot_mm, dtype=float)
        if pivot.shape != (3,) or not np.all(np.isfinite(pivot)):
            raise ValueError("the pivot's position must be 3 finite numbers (mm)")
        low, high = (float(v) for v in self.range_mm)
        if not 0.0 <= low < high or not np.isfinite(high):
            raise ValueError("the range must be two distances 0 <= low < high (mm)")
        object.__setattr__(self, "pivot_mm", pivot)
        object.__setattr__(self, "range_mm", (low, high))
        if not np.isfinite(self.offset_mm):
            raise ValueError("the offset must be a finite number (mm)")
        object.__setattr__(self, "offset_mm", float(self.offset_mm))

    @property
    def kind(self) -> str:
        return "distance"

    @property
    def labels(self) -> tuple[str, ...]:
        return ("pivot",)

    @property
    def dim(self) -> int:
        return 1

    @property
    def param_names(self) -> tuple[str, ...]:
        return ("pivot.x", "pivot.y", "pivot.z", "offset")

    @property
    def param_units(self) -> tuple[str, ...]:
        return ("mm",) * 4

    @property
    def start(self) -> np.ndarray:
        return np.append(self.pivot_mm, self.offset_mm)

    @property
    def unseen(self) -> str:
        return (
            "a distance cannot see the arm turn about its pivot: three turns of the whole "
            "arm about the pivot keep every distance"
        )

    @property
    def marks(self) -> tuple[tuple[str, np.ndarray], ...]:
        return (("pivot", self.pivot_mm),)

    @property
    def label_column(self) -> str | None:
        return None

    @property
    def reading_columns(self) -> tuple[str, ...]:
        return ("distance_mm",)

    def params_of(self, true: Instrument) -> np.ndarray:
        """``true``'s pivot and offset."""
        same_features(self, true)
        return np.asarray(true.start, dtype=float)

    def out_of_reach(self, reach_mm: float) -> str | None:
        """The tool's distances from the pivot lie within ``|c| -+ reach`` (the triangle
        inequality): a range outside them is out of reach."""
        far = float(np.linalg.norm(self.pivot_mm))
        low, high = max(0.0, far - reach_mm), far + reach_mm
        if self.range_mm[0] > high or self.range_mm[1] < low:
            return (
                f"the range {self.range_mm[0]:g}..{self.range_mm[1]:g} mm is out of reach: the "
                f"tool's distances from the pivot lie within {low:.6g}..{high:.6g} mm"
            )
        return None

    def miss(
        self, points: np.ndarray, feature: np.ndarray | None, params: np.ndarray
    ) -> np.ndarray:
        """``(..., m, 1)``: how far (mm) each point lies outside the range, 0 within it."""
        centre = np.asarray(params, dtype=float)[..., None, :3]
        size = np.linalg.norm(points - centre, axis=-1, keepdims=True)
        return size - np.clip(size, *self.range_mm)

    def reading(
        self, points: np.ndarray, feature: np.ndarray | None, params: np.ndarray
    ) -> np.ndarray:
        """``|p - c| - offset`` ``(..., m, 1)`` (mm)."""
        feature_index(feature, np.shape(points)[-2], self.labels)
        params = np.asarray(params, dtype=float)
        size = np.linalg.norm(points - params[..., None, :3], axis=-1, keepdims=True)
        return size - params[..., None, 3:4]

    def derivatives(
        self, points: np.ndarray, feature: np.ndarray | None, params: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray]:
        """The unit vector from the pivot ``(..., m, 1, 3)``; its negative and -1 for the
        pivot and the offset ``(..., m, 1, 4)``."""
        params = np.asarray(params, dtype=float)
        offset = points - params[..., None, :3]
        unit = offset / np.linalg.norm(offset, axis=-1, keepdims=True)
        by_params = np.concatenate([-unit, np.full((*unit.shape[:-1], 1), -1.0)], axis=-1)
        return unit[..., None, :], by_params[..., None, :]

    def curvatures(
        self, points: np.ndarray, feature: np.ndarray | None, params: np.ndarray
    ) -> tuple[np.ndarray | None, np.ndarray | None]:
        """``(I - u u^T) / r`` ``(..., m, 1, 3, 3)`` (``u`` the unit vector from the pivot,
        ``r`` the distance), its negative for the pivot and 0 for the offset ``(..., m, 1,
        4, 3)``."""
        params = np.asarray(params, dtype=float)
        offset = points - params[..., None, :3]
        size = np.linalg.norm(offset, axis=-1, keepdims=True)
        unit = offset / size
        bend = (np.eye(3) - unit[..., :, None] * unit[..., None, :]) / size[..., None]
        by_params = np.concatenate([-bend, np.zeros((*bend.shape[:-2], 1, 3))], axis=-2)
        return bend[..., None, :, :], by_params[..., None, :, :]
