"""What an instrument can measure of a spatial arm: its volume, the reflectors' acceptance
angle and the floor, as smooth constraints of the poses.

Before any data the instrument's place is given in the robot's base frame
(``[instrument]`` of the robot file).  Every constraint is a value ``g >= 0``
inside, scaled to millimetres (or to the cosine of an angle), with its gradient
in the readings from the chain's joint Jacobian, so the plan optimizer keeps it
(:func:`armcal.doe.ascent.view_penalty`, SLSQP's constraints) and every
returned pose is checked against it (:meth:`SpatialView.feasible`):

* **range**: a tracker measures between ``range_mm[0]`` and ``range_mm[1]`` from
  its origin: ``(r_max^2 - |p - c|^2) / (2 r_max)`` and
  ``(|p - c|^2 - r_min^2) / (2 r_max)`` (mm near the boundary);
* **box**: a measuring volume ``[lo, hi]`` per axis (a camera's, a CMM's):
  ``p - lo`` and ``hi - p``;
* **acceptance angle**: a reflector (an SMR, about +-30 degrees) or a marker
  returns the beam only when its normal ``n`` (in the tip frame) faces the
  instrument: ``n_w . (c - p) / |c - p| - cos(theta) >= 0``, times
  :data:`ACCEPTANCE_SCALE_MM`;
* **floor**: every target and the flange stay above ``z = floor_z_mm``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .kinematics import ChainKinematics

__all__ = [
    "ACCEPTANCE_SCALE_MM",
    "SpatialView",
]

#: The acceptance angle's constraint, a difference of cosines, counted as millimetres at
#: this distance, like the others: an optimizer's penalty weighs them alike.
ACCEPTANCE_SCALE_MM = 1000.0


@dataclass(frozen=True, eq=False)
class SpatialView:
    """The instrument's place and reach, in the robot's base frame (mm, rad).

    Attributes
    ----------
    position : ndarray, shape (3,)
        The instrument's origin (a tracker's head).
    range_mm : tuple of float or None
        Least and greatest distance it measures from its origin.
    box : ndarray, shape (3, 2), or None
        A measuring volume, ``[lo, hi]`` per axis.
    acceptance : float or None
        A reflector's half acceptance angle (rad), with the targets' ``normals``.
    normals : ndarray, shape (k, 3), or None
        Every target's normal in the tip frame (unit), for the acceptance angle.
    floor_z : float or None
        The floor's height; the targets and the flange stay above it.
    """

    position: np.ndarray
    range_mm: tuple[float, float] | None = None
    box: np.ndarray | None = None
    acceptance: float | None = None
    normals: np.ndarray | None = None
    floor_z: float | None = None

    def of_rows(
        self, kin: ChainKinematics, local: np.ndarray, target: np.ndarray | None, count: int
    ) -> tuple[np.ndarray, np.ndarray | None]:
        """Every pose's constraints ``(..., m, c)`` and gradients ``(..., m, c, n)`` from the
        kinematics (robot frame) of its ``count`` target rows, the targets at ``local``
        ``(k, 3)`` in the tip frame; no gradients from kinematics without derivatives."""
        rows = kin.points.shape[-2]
        index = np.zeros(rows, dtype=int) if target is None else np.asarray(target)
        reach = np.einsum("...ij,...j->...i", kin.rotation, local[index])  # flange to target
        moving = None
        if kin.joint_jacobian is not None and kin.tip_angular is not None:
            turn = np.swapaxes(
                np.cross(np.swapaxes(kin.tip_angular, -1, -2), reach[..., None, :]), -1, -2
            )
            moving = (kin.joint_jacobian, kin.tip_angular, kin.joint_jacobian - turn)
        g, dg = self.constraints(kin.points, kin.rotation, index, kin.points - reach, moving)
        m = rows // count
        values = g.reshape(*g.shape[:-2], m, -1)
        return values, None if dg is None else dg.reshape(*dg.shape[:-3], m, -1, dg.shape[-1])

    def constraints(
        self,
        points: np.ndarray,
        rotation: np.ndarray,
        target: np.ndarray,
        flange: np.ndarray,
        moving: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None,
    ) -> tuple[np.ndarray, np.ndarray | None]:
        """Values ``(..., m, k)`` and gradients ``(..., m, k, n)`` of every row's constraints.

        Parameters
        ----------
        points : ndarray, shape (..., m, 3)
            The rows' target points (robot frame).
        rotation : ndarray, shape (..., m, 3, 3)
            The tip frame.
        target : ndarray of int, shape (m,)
            Every row's target (for its normal).
        flange : ndarray, shape (..., m, 3)
            The flange's origin, for the floor.
        moving : tuple of ndarray, each (..., m, 3, n), optional
            The points' derivatives in the readings, the tip frame's angular
            velocity per reading and the flange's derivative; without them, no
            gradients (None).
        """
        values, grads = [], []
        offset = points - self.position
        if self.range_mm is not None:
            low, high = self.range_mm
            square = np.sum(offset**2, axis=-1)
            scale = 2.0 * high
            values += [(high**2 - square) / scale, (square - low**2) / scale]
            if moving is not None:
                d_square = 2.0 * np.einsum("...i,...in->...n", offset, moving[0])
                grads += [-d_square / scale, d_square / scale]
        if self.box is not None:
            for axis in range(3):
                lo, hi = self.box[axis]
                values += [points[..., axis] - lo, hi - points[..., axis]]
                if moving is not None:
                    grads += [moving[0][..., axis, :], -moving[0][..., axis, :]]
        if self.acceptance is not None and self.normals is not None:
            normal = np.einsum("...ij,...j->...i", rotation, self.normals[target])
            distance = np.linalg.norm(offset, axis=-1, keepdims=True)
            sight = -offset / distance  # towards the instrument
            scale = ACCEPTANCE_SCALE_MM
            values.append(scale * (np.sum(normal * sight, axis=-1) - np.cos(self.acceptance)))
            if moving is not None:  # d normal = w x normal; d sight = -(I - s s^T) dp / |c - p|
                point_jacobian, angular = moving[0], moving[1]
                d_normal = np.cross(np.swapaxes(angular, -1, -2), normal[..., None, :])
                project = np.eye(3) - sight[..., :, None] * sight[..., None, :]
                d_sight = (
                    -np.einsum("...ij,...jn->...in", project, point_jacobian) / distance[..., None]
                )
                grads.append(
                    scale * np.einsum("...ni,...i->...n", d_normal, sight)
                    + scale * np.einsum("...i,...in->...n", normal, d_sight)
                )
        if self.floor_z is not None:
            values += [points[..., 2] - self.floor_z, flange[..., 2] - self.floor_z]
            if moving is not None:
                grads += [moving[0][..., 2, :], moving[2][..., 2, :]]
        found = np.stack(values, axis=-1)
        return found, None if moving is None else np.stack(grads, axis=-2)
