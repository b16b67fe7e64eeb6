"""A calibrated arm: a fit model, its identified parameters and their covariance.

What ``identify`` hands on to ``validate``, ``compensate`` and ``export``,
whether it comes from a :class:`~armcal.identification.Calibration` in memory or from
a calibration file (:func:`armcal.files.read_calibration`).  It works for every
family of arm (:class:`~armcal.models.interface.FitModel`).

Two frames matter.  The *instrument frame* is where measurements live: the
model's instrument parameters (the planar arm's base pose ``x0, y0, phi0``)
place the arm in it.  The *robot frame* is the arm's own: its base at the
origin, the link angles read from the joints.  Compensation and export work in
the robot frame, so they never "correct" where the instrument stood
(:meth:`CalibratedArm.in_robot_frame`).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from .interface import Conditions, FitModel, position_jacobian
from .plane import Plane

__all__ = [
    "CalibratedArm",
]


@dataclass(frozen=True, eq=False)
class CalibratedArm:
    """A model with its identified parameters.

    Attributes
    ----------
    model : FitModel
        The model calibrated (its geometry, targets, base pose, fixed
        parameters and noise model; for a compliant arm also the loads model).
    params : ndarray, shape (p,)
        Identified parameters in internal units (mm, rad, ...).
    covariance : ndarray, shape (p, p)
        Their covariance in internal units; zero rows and columns for fixed
        parameters.
    sigma_mm : float
        The instrument noise (1 std, mm) the calibration used.
    plane : Plane or None
        The plane of motion of 3-D data (instrument frame), else None.
    training_rows : Conditions or None
        The rows the calibration was fitted to (joint readings, targets, loads), where
        known: in memory, and in the file of a calibration with an effect (joint
        compliance), whose rigid export is judged on them
        (:func:`armcal.export_rigid.rigid_export`).
    baseline : ndarray, shape (p_arm,), or None
        The nominal arm registered on its own to the calibration's rows: the
        geometric arm's parameters (:attr:`FitModel.arm`), its instrument pose and
        targets fitted and everything else nominal.  What a user has without
        calibrating, and what validation compares the calibration with; None for a
        calibration that did not record it.

    Examples
    --------
    >>> from armcal.models import PlanarArm
    >>> CalibratedArm(PlanarArm([2.0, 1.0], name="two"), np.zeros(4), np.zeros((4, 4)), 0.01)
    CalibratedArm(two: 4 parameters, sigma 0.01 mm)
    """

    model: FitModel
    params: np.ndarray
    covariance: np.ndarray
    sigma_mm: float
    plane: Plane | None = None
    training_rows: Conditions | None = None
    baseline: np.ndarray | None = None

    def __repr__(self) -> str:
        where = ", 3-D data in a plane" if self.plane is not None else ""
        return (
            f"CalibratedArm({self.model.name}: {self.model.n_params} parameters, "
            f"sigma {self.sigma_mm:g} mm{where})"
        )

    @property
    def arm(self) -> Any:
        """The geometric arm of the model (:attr:`FitModel.arm`)."""
        return self.model.arm

    def positions(self, conditions: Conditions, params: np.ndarray | None = None) -> np.ndarray:
        """Where the arm with ``params`` (default: the identified ones) puts the points, mm."""
        return self.model.positions(conditions, self.params if params is None else params)

    def position_jacobian(self, conditions: Conditions) -> np.ndarray:
        """Jacobian ``(m, d, p)`` of the points' positions at the estimate."""
        return position_jacobian(self.model, conditions, self.params)

    @property
    def robot_mask(self) -> np.ndarray:
        """Boolean ``(p,)``: the robot's own parameters (not its pose in the instrument)."""
        return ~self.model.instrument_params

    def instrument_pose_params(self) -> np.ndarray:
        """Only the instrument's parameters, every other 0: the nominal arm where it stood."""
        return np.where(self.robot_mask, 0.0, self.params)

    def baseline_positions(self, conditions: Conditions) -> np.ndarray:
        """Where the nominal arm registered on its own (:attr:`baseline`) puts the points
        of ``conditions`` (a rigid arm: loads play no part), mm.

        Raises ValueError for a calibration without a baseline.
        """
        if self.baseline is None:
            raise ValueError("the calibration has no baseline (the nominal arm registered)")
        return self.model.arm.positions(conditions, self.baseline)

    def alone(self) -> CalibratedArm:
        """The calibration of the arm alone (:meth:`FitModel.alone`): itself for one
        measured by a tracker; for one measured by a plane, fixed points or a distance,
        the arm in the frame the instrument was placed in, what the instrument could not
        see held at nominal (its training rows kept, its baseline the nominal arm)."""
        model, params, covariance = self.model.alone(self.params, self.covariance)
        if model is self.model:
            return self
        return CalibratedArm(model, params, covariance, self.sigma_mm, None, None, None)

    def in_robot_frame(self) -> tuple[FitModel, np.ndarray]:
        """The model and parameters in the robot's own frame (the instrument's pose out)."""
        return self.model.in_robot_frame(self.params)

    def robot_params(self) -> np.ndarray:
        """The geometric arm's parameters in its own frame: the instrument's pose set to 0."""
        return self.model.arm_params(self.in_robot_frame()[1])

    def robot_covariance(self) -> np.ndarray:
        """The covariance ``(p, p)`` of the robot's own parameters (instrument rows 0).

        The marginal covariance: the instrument pose's uncertainty is the
        instrument's, not the robot's.
        """
        keep = self.robot_mask
        return self.covariance * np.outer(keep, keep)

    @property
    def arm_params(self) -> np.ndarray:
        """The identified parameters of the geometric arm (:attr:`arm`)."""
        return self.model.arm_params(self.params)
