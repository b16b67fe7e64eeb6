"""The plane of motion of 3-D instrument data: fitted, projected, mirrored.

A laser tracker or a CMM reports ``x, y, z`` in its own frame.  A planar arm
moves its targets in parallel planes (each target may sit at its own height
on the end effector), so the data are fitted with one normal and one offset
per target: the smallest right singular vector of the points, each centred on
its own target's centroid, is the least-squares normal (total least squares).
:mod:`armcal.instrument` identifies in it.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from ..errors import ArmcalError

__all__ = [
    "Plane",
    "fit_plane",
]


@dataclass(frozen=True, eq=False)
class Plane:
    """The plane of motion in the instrument frame.

    Attributes
    ----------
    origin : ndarray, shape (3,)
        A point of the plane (the centroid of the fitted points), mm.
    axes : ndarray, shape (3, 3)
        Rows ``u``, ``v``, ``n``: in-plane axes and the unit normal,
        right-handed (``u x v = n``).
    offsets : ndarray, shape (T,)
        Every target's plane along ``n`` from ``origin``, mm (one entry when
        the data have no targets).
    labels : tuple of str
        The targets' labels, in the order of ``offsets`` (empty without targets).
    rms_mm, max_mm : float
        RMS and largest out-of-plane distance of the fitted points, mm.
    out_of_plane : ndarray, shape (m,), or None
        Signed distance of every fitted point from its target's plane, mm (None
        for a plane read back from a calibration file).
    """

    origin: np.ndarray
    axes: np.ndarray
    offsets: np.ndarray
    labels: tuple[str, ...]
    rms_mm: float
    max_mm: float
    out_of_plane: np.ndarray | None = None

    @property
    def normal(self) -> np.ndarray:
        """The unit normal ``n`` ``(3,)``."""
        return self.axes[2]

    def to_plane(self, xyz: np.ndarray) -> np.ndarray:
        """In-plane coordinates ``(m, 2)`` of points ``xyz`` ``(m, 3)`` (mm)."""
        return (np.asarray(xyz, dtype=float) - self.origin) @ self.axes[:2].T

    def distance(self, xyz: np.ndarray, target: np.ndarray | None = None) -> np.ndarray:
        """Signed distance ``(m,)`` of points from their target's plane, mm."""
        height = (np.asarray(xyz, dtype=float) - self.origin) @ self.normal
        return height - self.offsets[0 if target is None else target]

    def from_plane(self, xy: np.ndarray, target: np.ndarray | None = None) -> np.ndarray:
        """Instrument coordinates ``(m, 3)`` of in-plane points ``(m, 2)`` (their target plane)."""
        xy = np.asarray(xy, dtype=float)
        height = self.offsets[0 if target is None else target]
        return self.origin + xy @ self.axes[:2] + np.multiply.outer(height, self.normal)

    def mirrored(self) -> Plane:
        """The same plane seen from its other side: ``v`` and ``n`` reversed."""
        axes = self.axes * np.array([[1.0], [-1.0], [-1.0]])
        flipped = None if self.out_of_plane is None else -self.out_of_plane
        return replace(self, axes=axes, offsets=-self.offsets, out_of_plane=flipped)

    def to_dict(self) -> dict[str, Any]:
        """JSON form: origin, axes, per-target offsets, out-of-plane RMS and max (mm)."""
        return {
            "origin_mm": self.origin.tolist(),
            "u": self.axes[0].tolist(),
            "v": self.axes[1].tolist(),
            "normal": self.axes[2].tolist(),
            "offsets_mm": {
                label: float(d)
                for label, d in zip(self.labels or ("",), self.offsets, strict=True)
            },
            "out_of_plane_rms_per_point_mm": self.rms_mm,
            "out_of_plane_max_mm": self.max_mm,
        }

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> Plane:
        """The plane of a calibration document (:meth:`to_dict`); raises KeyError/ValueError."""
        axes = np.array([data["u"], data["v"], data["normal"]], dtype=float)
        origin = np.array(data["origin_mm"], dtype=float)
        if axes.shape != (3, 3) or origin.shape != (3,):
            raise ValueError("plane: origin_mm needs 3 numbers and u, v, normal 3 each")
        if not np.allclose(axes @ axes.T, np.eye(3), atol=1e-9):
            raise ValueError("plane: u, v, normal must be orthonormal")
        if np.linalg.det(axes) < 0:
            raise ValueError("plane: u, v, normal must be right-handed (u x v = normal)")
        labels = tuple(data["offsets_mm"])
        offsets = np.array([float(data["offsets_mm"][k]) for k in labels])
        # the per-point RMS distance; files of armcal before 0.2 name it out_of_plane_rms_mm
        key = "out_of_plane_rms_per_point_mm"
        rms = float(data[key] if key in data else data["out_of_plane_rms_mm"])
        largest = float(data["out_of_plane_max_mm"])
        return cls(origin, axes, offsets, () if labels == ("",) else labels, rms, largest)


def _in_plane_axis(normal: np.ndarray) -> np.ndarray:
    """The plane's first axis ``u``: the instrument's ``x`` axis projected onto the plane.

    A rule, not the data's largest spread: a singular vector's sign (and, for data that
    spread alike in two directions, its direction) depends on the order of the rows and
    on the LAPACK build, and would turn the base rotation ``phi0`` by up to 180 deg.
    Where the normal lies within 30 deg of ``x`` (``x`` nearly normal to the plane), the
    instrument's ``y`` axis is projected instead.
    """
    for axis in np.eye(3)[:2]:
        projected = axis - (axis @ normal) * normal
        norm = float(np.linalg.norm(projected))
        if norm >= 0.5:  # the axis is at least 30 deg from the normal
            return projected / norm
    # Only a normal within 30 deg of both x and y gets here: impossible, as x and y
    # are 90 deg apart.
    raise AssertionError("no instrument axis lies in the plane")


def fit_plane(
    xyz: np.ndarray,
    target: np.ndarray | None = None,
    labels: tuple[str, ...] = (),
) -> Plane:
    """Fit the plane of motion: one normal, one offset per target (total least squares).

    Parameters
    ----------
    xyz : ndarray, shape (m, 3)
        Measured points in the instrument frame, mm.
    target : ndarray of int, shape (m,), optional
        Every point's target (index into ``labels``); all one target when omitted.
    labels : tuple of str
        The targets' labels.

    Returns
    -------
    Plane
        ``u`` the instrument's ``x`` axis projected onto the plane (its ``y`` axis
        for a plane nearly normal to ``x``), ``n`` the least-squares normal,
        its sign such that ``n`` points to the instrument's ``+z`` side (or
        ``+x``, ``+y`` if the plane is vertical); :func:`identify_3d` then picks
        the side the arm explains.

    Raises
    ------
    ArmcalError
        If the points do not span a plane (fewer than 3, or all on a line).

    Examples
    --------
    >>> xyz = np.array([[0, 0, 5], [1, 0, 5], [0, 2, 5], [3, 1, 5.0]])
    >>> plane = fit_plane(xyz)
    >>> plane.normal.round(12).tolist(), round(plane.rms_mm, 12)
    ([0.0, 0.0, 1.0], 0.0)
    """
    xyz = np.asarray(xyz, dtype=float)
    m = xyz.shape[0]
    count = max(1, len(labels))
    index = np.zeros(m, dtype=int) if target is None else np.asarray(target)
    centroids = np.zeros((count, 3))
    for t in range(count):
        mine = index == t
        if np.any(mine):
            centroids[t] = xyz[mine].mean(axis=0)
    centred = xyz - centroids[index]
    if m < 3:
        raise ArmcalError(f"{m} points cannot define the plane of motion; measure at least 3")
    _, s, vt = np.linalg.svd(centred, full_matrices=False)
    if s.size < 3 or s[1] <= 1e-9 * s[0]:
        raise ArmcalError(
            "the 3-D points lie on a line, not in a plane; measure poses that move the "
            "target across the plane of motion"
        )
    normal = vt[2]
    # A sign the data cannot give: towards the instrument's first axis with a component.
    lead = next(c for c in (2, 0, 1) if abs(normal[c]) > 1e-12)
    if normal[lead] < 0:
        normal = -normal
    u = _in_plane_axis(normal)
    v = np.cross(normal, u)
    origin = xyz.mean(axis=0)
    offsets = (centroids - origin) @ normal
    height = (xyz - origin) @ normal - offsets[index]
    rms, largest = float(np.sqrt(np.mean(height**2))), float(np.max(np.abs(height)))
    return Plane(origin, np.array([u, v, normal]), offsets, tuple(labels), rms, largest, height)
