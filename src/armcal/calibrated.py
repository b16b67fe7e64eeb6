"""A calibrated arm: the nominal model, its identified deviations and their covariance.

What ``identify`` hands on to ``validate``, ``compensate`` and ``export``,
whether it comes from a :class:`~armcal.identification.Calibration` in memory
or from a calibration file (:func:`armcal.io.read_calibration`).

Two frames matter.  The *instrument frame* is where measurements live: with a
base offset or 3-D data, the base pose ``x0, y0`` (and ``phi0``) places the
arm in it.  The *robot frame* is the arm's own: its base at the origin, the
link angles read from the joints.  Compensation and export work in the robot
frame, so they never "correct" where the instrument stood
(:meth:`CalibratedArm.robot_params`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .arm import PlanarArm
from .plane import Plane

__all__ = [
    "BASE_POSE",
    "CalibratedArm",
]

#: The parameters that place the arm in the instrument frame, not part of the robot.
BASE_POSE = ("x0", "y0", "phi0")


@dataclass(frozen=True, eq=False)
class CalibratedArm:
    """The nominal arm with its identified deviations.

    Attributes
    ----------
    arm : PlanarArm
        The nominal arm calibrated (joint map, targets, base pose, fixed
        parameters, noise model).
    params : ndarray, shape (p,)
        Identified user deviations in internal units (mm, rad).
    covariance : ndarray, shape (p, p)
        Their covariance in internal units (mm, rad); zero rows and columns
        for fixed parameters.
    sigma_mm : float
        The instrument noise (1 std, mm) the calibration used.
    plane : Plane or None
        The plane of motion of 3-D data (instrument frame), else None.
    """

    arm: PlanarArm
    params: np.ndarray
    covariance: np.ndarray
    sigma_mm: float
    plane: Plane | None = None

    @property
    def robot_mask(self) -> np.ndarray:
        """Boolean ``(p,)``: the robot's own parameters (not its pose in the instrument)."""
        return np.array([name not in BASE_POSE for name in self.arm.param_names])

    def robot_params(self) -> np.ndarray:
        """The deviations with the base pose set to 0: the calibrated arm in its own frame."""
        return np.where(self.robot_mask, self.params, 0.0)

    def base_pose_params(self) -> np.ndarray:
        """Only the base pose (``x0, y0, phi0``), deviations 0: the nominal arm where it stood."""
        return np.where(self.robot_mask, 0.0, self.params)

    def robot_covariance(self) -> np.ndarray:
        """The covariance ``(p, p)`` of the robot's own parameters (base pose rows and columns 0).

        The marginal covariance: the base pose's uncertainty is the instrument's,
        not the robot's.
        """
        keep = self.robot_mask
        return self.covariance * np.outer(keep, keep)
