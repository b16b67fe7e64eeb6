"""Where the instrument can measure: regions of the plane, in the robot's base frame.

A region says which tip positions the instrument sees (a tracker's range, a
camera's field of view).  Plans are designed within it and checked against it
(:mod:`armcal.doe`).  Each region gives a boolean test and smooth constraint
values with their gradient, for the optimizer.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = [
    "Annulus",
    "Box",
    "Region",
]


@dataclass(frozen=True)
class Annulus:
    """Measurement region: points whose distance from ``center`` lies in ``[r_min, r_max]``.

    Attributes
    ----------
    center : tuple of float
        ``(x, y)`` in mm, in the robot's base frame.
    r_min, r_max : float
        Radii in mm; ``r_min = 0`` makes a disc.
    """

    center: tuple[float, float]
    r_min: float
    r_max: float

    def contains(self, xy: np.ndarray, *, tol: float = 1e-9) -> np.ndarray:
        """Boolean mask ``(...)`` of points ``xy`` ``(..., 2)`` inside the annulus."""
        r = np.hypot(xy[..., 0] - self.center[0], xy[..., 1] - self.center[1])
        return (r >= self.r_min - tol) & (r <= self.r_max + tol)

    def constraints(self, xy: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Smooth constraint values ``g (..., k)``, ``>= 0`` inside, and ``dg/dxy (..., k, 2)``.

        ``g = ((r_max^2 - r^2), (r^2 - r_min^2)) / r_max`` (mm), the second only
        when ``r_min > 0``.
        """
        d = xy - np.asarray(self.center)
        r2 = np.sum(d**2, axis=-1)
        g = [(self.r_max**2 - r2) / self.r_max]
        dg = [-2.0 * d / self.r_max]
        if self.r_min > 0:
            g.append((r2 - self.r_min**2) / self.r_max)
            dg.append(2.0 * d / self.r_max)
        return np.stack(g, axis=-1), np.stack(dg, axis=-2)


@dataclass(frozen=True)
class Box:
    """Measurement region: the axis-aligned rectangle ``x in [x_lo, x_hi], y in [y_lo, y_hi]``.

    Attributes
    ----------
    x, y : tuple of float
        ``(lo, hi)`` bounds in mm, in the robot's base frame.
    """

    x: tuple[float, float]
    y: tuple[float, float]

    def contains(self, xy: np.ndarray, *, tol: float = 1e-9) -> np.ndarray:
        """Boolean mask ``(...)`` of points ``xy`` ``(..., 2)`` inside the box."""
        px, py = xy[..., 0], xy[..., 1]
        return (
            (px >= self.x[0] - tol)
            & (px <= self.x[1] + tol)
            & (py >= self.y[0] - tol)
            & (py <= self.y[1] + tol)
        )

    def constraints(self, xy: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Constraint values ``g (..., 4)``, ``>= 0`` inside (mm), and ``dg/dxy (..., 4, 2)``."""
        px, py = xy[..., 0], xy[..., 1]
        g = np.stack([px - self.x[0], self.x[1] - px, py - self.y[0], self.y[1] - py], axis=-1)
        dg = np.array([[1.0, 0.0], [-1.0, 0.0], [0.0, 1.0], [0.0, -1.0]])
        return g, np.broadcast_to(dg, (*xy.shape[:-1], 4, 2))


Region = Annulus | Box
