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

from .compliance import Compliance, Loads
from .planar import PlanarArm
from .planar_kinematics import forward_kinematics, jacobian
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
    compliance : Compliance or None
        The joint-compliance model identified with the geometry, else None.
    compliance_values : ndarray, shape (P,), or None
        Its parameters in internal units.
    full_covariance : ndarray, shape (p + P, p + P), or None
        Covariance of geometry and compliance together.
    """

    arm: PlanarArm
    params: np.ndarray
    covariance: np.ndarray
    sigma_mm: float
    plane: Plane | None = None
    compliance: Compliance | None = None
    compliance_values: np.ndarray | None = None
    full_covariance: np.ndarray | None = None

    def all_params(self, params: np.ndarray | None = None) -> np.ndarray:
        """Geometry ``params`` (default: the identified ones) followed by the compliance."""
        geometry = self.params if params is None else params
        if self.compliance_values is None:
            return geometry
        return np.concatenate([geometry, self.compliance_values])

    def positions(
        self,
        q: np.ndarray,
        params: np.ndarray | None = None,
        *,
        loads: Loads | None = None,
        target: np.ndarray | None = None,
    ) -> np.ndarray:
        """Where the arm with geometry ``params`` (default: identified) puts the tip, mm.

        With compliance the tip is deflected under ``loads`` (default: the
        robot file's payload); ``target`` picks each row's target.
        """
        geometry = self.params if params is None else params
        if self.compliance is None:
            return forward_kinematics(self.arm, q, geometry, target=target)
        return self.compliance.tip(q, self.all_params(geometry), loads)

    def position_jacobian(
        self, q: np.ndarray, *, loads: Loads | None = None, target: np.ndarray | None = None
    ) -> tuple[np.ndarray, np.ndarray]:
        """Jacobian ``(m, 2, p[+P])`` of the tip at the estimate and the matching covariance."""
        if self.compliance is None:
            return jacobian(self.arm, q, self.params, target=target), self.covariance
        assert self.full_covariance is not None
        return self.compliance.jacobian(q, self.all_params(), loads), self.full_covariance

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

    def robot_compliance(self) -> Compliance | None:
        """The compliance model with gravity turned into the robot's own frame (by ``-phi0``)."""
        model = self.compliance
        if model is None or not self.arm.base_rotation or model.elastic.gravity is None:
            return model
        phi0 = float(self.params[-1])
        g = complex(*model.elastic.gravity) * np.exp(-1j * phi0)
        elastic = model.elastic.with_gravity(np.array([g.real, g.imag]))
        return Compliance(model.arm, elastic, model.known_loads)

    def robot_full_covariance(self) -> np.ndarray:
        """Covariance of the robot's geometry and compliance (base pose rows and columns 0)."""
        if self.full_covariance is None:
            return self.robot_covariance()
        extra = self.full_covariance.shape[0] - self.arm.n_params
        keep = np.concatenate([self.robot_mask, np.ones(extra, dtype=bool)])
        return self.full_covariance * np.outer(keep, keep)

    def robot_covariance(self) -> np.ndarray:
        """The covariance ``(p, p)`` of the robot's own parameters (base pose rows and columns 0).

        The marginal covariance: the base pose's uncertainty is the instrument's,
        not the robot's.
        """
        keep = self.robot_mask
        return self.covariance * np.outer(keep, keep)
