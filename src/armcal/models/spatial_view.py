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

from .spatial_kinematics import ChainKinematics

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
    ) -> tuple[np.ndarray, np.ndarray]:
        """Every pose's constraints ``(..., m, c)`` and gradients ``(..., m, c, n)`` from the
        kinematics (robot frame, with derivatives) of its ``count`` target rows, the
        targets at ``local`` ``(k, 3)`` in the tip frame."""
        assert kin.joint_jacobian is not None and kin.tip_angular is not None
        rows = kin.points.shape[-2]
        index = np.zeros(rows, dtype=int) if target is None else np.asarray(target)
        reach = np.einsum("...ij,...j->...i", kin.rotation, local[index])  # flange to target
        turn = np.swapaxes(
            np.cross(np.swapaxes(kin.tip_angular, -1, -2), reach[..., None, :]), -1, -2
        )
        g, dg = self.constraints(
            kin.points,
            kin.joint_jacobian,
            kin.rotation,
            kin.tip_angular,
            index,
            kin.points - reach,
            kin.joint_jacobian - turn,
        )
        m = rows // count
        return (
            g.reshape(*g.shape[:-2], m, -1),
            dg.reshape(*dg.shape[:-3], m, -1, dg.shape[-1]),
        )

    def constraints(
        self,
        points: np.ndarray,
        point_jacobian: np.ndarray,
        rotation: np.ndarray,
        angular: np.ndarray,
        target: np.ndarray,
        flange: np.ndarray,
        flange_jacobian: np.ndarray,
    ) -> tuple[np.ndarray, np.ndarray]:
        """Values ``(..., m, k)`` and gradients ``(..., m, k, n)`` of every row's constraints.

        Parameters
        ----------
        points, point_jacobian : ndarray, shape (..., m, 3) and (..., m, 3, n)
            The rows' target points (robot frame) and their derivatives in the readings.
        rotation, angular : ndarray, shape (..., m, 3, 3) and (..., m, 3, n)
            The tip frame and its angular velocity per reading.
        target : ndarray of int, shape (m,)
            Every row's target (for its normal).
        flange, flange_jacobian : ndarray, shape (..., m, 3) and (..., m, 3, n)
            The flange's origin and its derivative, for the floor.
        """
        values, grads = [], []
        offset = points - self.position
        if self.range_mm is not None:
            low, high = self.range_mm
            square = np.sum(offset**2, axis=-1)
            d_square = 2.0 * np.einsum("...i,...in->...n", offset, point_jacobian)
            scale = 2.0 * high
            values += [(high**2 - square) / scale, (square - low**2) / scale]
            grads += [-d_square / scale, d_square / scale]
        if self.box is not None:
            for axis in range(3):
                lo, hi = self.box[axis]
                values += [points[..., axis] - lo, hi - points[..., axis]]
                grads += [point_jacobian[..., axis, :], -point_jacobian[..., axis, :]]
        if self.acceptance is not None and self.normals is not None:
            local = self.normals[target]  # (m, 3)
            normal = np.einsum("...ij,...j->...i", rotation, local)
            to_instrument = -offset
            distance = np.linalg.norm(to_instrument, axis=-1, keepdims=True)
            sight = to_instrument / distance
            scale = ACCEPTANCE_SCALE_MM
            values.append(scale * (np.sum(normal * sight, axis=-1) - np.cos(self.acceptance)))
            # d normal = w x normal; d sight = -(I - s s^T) dp / |c - p|
            d_normal = np.cross(np.swapaxes(angular, -1, -2), normal[..., None, :])  # (..., n, 3)
            project = np.eye(3) - sight[..., :, None] * sight[..., None, :]
            d_sight = (
                -np.einsum("...ij,...jn->...in", project, point_jacobian) / distance[..., None]
            )
            grads.append(
                scale * np.einsum("...ni,...i->...n", d_normal, sight)
                + scale * np.einsum("...i,...in->...n", normal, d_sight)
            )
        if self.floor_z is not None:
            values.append(points[..., 2] - self.floor_z)
            grads.append(point_jacobian[..., 2, :])
            values.append(flange[..., 2] - self.floor_z)
            grads.append(flange_jacobian[..., 2, :])
        return np.stack(values, axis=-1), np.stack(grads, axis=-2)
