"""Corrected joint commands: the calibrated arm goes where the nominal program meant.

**Compensation** (:func:`compensate`) corrects a robot program: for every
commanded pose ``q0`` it finds joint commands ``q`` with which the calibrated
arm puts its target where the nominal arm would have, ``p_cal(q) = p_nom(q0)``,
in the robot's own frame (the instrument's pose is never "corrected",
:meth:`~armcal.models.interface.FitModel.in_robot_frame`).  When the arm has
joints to spare (``n >= d + k``: 3 in the plane) the tool's orientation is kept
too.  Newton's method from ``q0`` with minimum-norm steps, the rest of the joint
space pulled back towards ``q0`` (``dq = -J^+ r + (I - J^+ J)(q0 - q)``), so the
remaining redundancy goes to the smallest joint change.  A pose the iteration
cannot reach (out of reach, at a singularity) or whose correction leaves a
joint limit is listed as uncorrectable and keeps its command: never clipped.

A model of joint compliance also takes out the joints' deflection under the
program's load; every family works through
:class:`~armcal.models.interface.FitModel`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from .models import CalibratedArm, Conditions, FitModel, Loads
from .models.information import tip_variances
from .numerics import rms

__all__ = [
    "Compensation",
    "compensate",
]


@dataclass(frozen=True, eq=False)
class Compensation:
    """Corrected joint commands of a program and what they buy.

    Attributes
    ----------
    q : ndarray, shape (m, n)
        Corrected joint commands, rad; an uncorrectable pose keeps its own.
    corrected : ndarray of bool, shape (m,)
        Whether every pose was corrected.
    reasons : tuple of str
        Why a pose was not corrected ("" for the corrected ones).
    position_before_mm : ndarray, shape (m,)
        Where the calibrated arm puts the target at the original command, from
        where the nominal program meant: the error compensation removes, mm.
    position_after_mm : ndarray, shape (m,)
        The calibrated model's uncertainty (RMS) at the corrected command: the
        error left after compensation, as the calibration predicts it, mm.
    orientation_before_deg, orientation_after_deg : ndarray, shape (m,), or None
        The same for the tool's orientation (when it is kept), deg.
    commanded : ndarray, shape (m, n)
        The program's own commands, rad.
    """

    q: np.ndarray
    corrected: np.ndarray
    reasons: tuple[str, ...]
    position_before_mm: np.ndarray
    position_after_mm: np.ndarray
    orientation_before_deg: np.ndarray | None
    orientation_after_deg: np.ndarray | None
    commanded: np.ndarray

    def __repr__(self) -> str:
        s = self.summary()
        return (
            f"Compensation({int(np.count_nonzero(self.corrected))} of {self.q.shape[0]} poses "
            f"corrected; predicted RMS per point {s['rms_before_mm']:.4g} mm before, "
            f"{s['rms_after_mm']:.4g} mm after)"
        )

    @property
    def largest_change_deg(self) -> float:
        """The largest change of a joint command, deg."""
        return float(np.max(np.degrees(np.abs(self.q - self.commanded)), initial=0.0))

    @property
    def uncorrectable(self) -> np.ndarray:
        """0-based indices of the poses left uncorrected."""
        return np.flatnonzero(~self.corrected)

    def summary(self) -> dict[str, float | None]:
        """RMS of the predicted errors before and after over the corrected poses.

        Positions per point (both coordinates together, mm; ``rms_before_mm`` and
        ``rms_after_mm`` are the same under their PRODUCT.md names), the tool's
        orientation per pose (its angle, deg; None without one).
        """
        ok = self.corrected
        before, after = rms(self.position_before_mm[ok]), rms(self.position_after_mm[ok])
        out: dict[str, float | None] = {
            "rms_before_mm": before,
            "rms_after_mm": after,
            "rms_before_per_point_mm": before,
            "rms_after_per_point_mm": after,
            "orientation_rms_before_per_pose_deg": None,
            "orientation_rms_after_per_pose_deg": None,
        }
        if self.orientation_before_deg is not None and self.orientation_after_deg is not None:
            out["orientation_rms_before_per_pose_deg"] = rms(self.orientation_before_deg[ok])
            out["orientation_rms_after_per_pose_deg"] = rms(self.orientation_after_deg[ok])
        return out


class _Goal:
    """Where the nominal program meant the tool, and the calibrated arm's residual from it."""

    def __init__(
        self,
        model: FitModel,
        params: np.ndarray,
        program: Conditions,
        orientation: bool,
    ) -> None:
        self.model, self.params, self.program = model, params, program
        # The nominal arm where the calibrated one stands (its targets, in its frame).
        nominal = np.where(model.instrument_params, params, 0.0)
        self.position = model.positions(program, nominal)
        self.angle = model.orientation(program, nominal) if orientation else None
        self.scale = model.angle_scale_mm  # an angle counted as the arc at full reach

    def rows(self, q: np.ndarray, active: np.ndarray) -> Conditions:
        """The conditions of the rows ``active`` at commands ``q`` (their targets and loads)."""
        sub = self.program.take(active)
        return Conditions(q, sub.target, sub.loads)

    def residual(self, q: np.ndarray, active: np.ndarray) -> np.ndarray:
        """``(a, d [+ k])``: position (mm) and, keeping the orientation, its angles as arcs."""
        rows = self.rows(q, active)
        r = self.model.positions(rows, self.params) - self.position[active]
        if self.angle is None:
            return r
        turn = self.model.orientation_error(
            self.model.orientation(rows, self.params), self.angle[active]
        )
        return np.concatenate([r, self.scale * turn], axis=1)

    def jacobian(self, q: np.ndarray, active: np.ndarray) -> np.ndarray:
        """``d residual / dq`` ``(a, d [+ k], n)``, at the deflected pose under load.

        The deflection's own change with ``q`` (about 1e-3 of a step) only slows
        Newton's convergence from quadratic to fast linear.
        """
        rows = self.rows(q, active)
        jac = self.model.joint_jacobian(rows, self.params)
        if self.angle is None:
            return jac
        turn = self.scale * self.model.orientation_joint_jacobian(rows, self.params)
        return np.concatenate([jac, turn], axis=1)


def compensate(
    cal: CalibratedArm,
    q_program: ArrayLike,
    *,
    target: ArrayLike | None = None,
    orientation: bool | None = None,
    tol_mm: float = 1e-9,
    max_iter: int = 50,
    loads: Loads | None = None,
) -> Compensation:
    """Corrected joint commands: the calibrated arm goes where the nominal program meant.

    Parameters
    ----------
    cal : CalibratedArm
    q_program : ndarray, shape (m, n)
        The program's joint commands, rad (within the joint limits).
    target : ndarray of int, shape (m,), optional
        The target (tool point) every command is meant for, on an arm with several.
    orientation : bool, optional
        Keep the tool's orientation too; default where the arm has the joints
        (``n >= d + k``: 3 joints in the plane).
    tol_mm : float
        A pose is corrected when the calibrated arm reaches the goal within
        this distance (mm; the tool's angles counted as arcs at the reach).
    max_iter : int
        Newton iterations at most.
    loads : Loads, optional
        The program's payload and tip force per row, for a calibration with
        compliance (default: the robot file's payload): the corrected commands
        also take out the joints' predicted deflection under that load.

    Returns
    -------
    Compensation

    Examples
    --------
    >>> from armcal.models import PlanarArm, forward_kinematics
    >>> arm = PlanarArm([260.0, 180.0, 120.0])
    >>> truth = arm.params_from_display([1.0, -0.5, 0.3], [0.4, -0.2, 0.3])
    >>> cal = CalibratedArm(arm, truth, np.zeros((6, 6)), 0.01)
    >>> q0 = np.radians([[10.0, 40.0, -30.0], [-50.0, 70.0, 20.0]])
    >>> result = compensate(cal, q0)
    >>> reached = forward_kinematics(arm, result.q, truth)
    >>> bool(np.allclose(reached, forward_kinematics(arm, q0), atol=1e-9))
    True
    >>> result.corrected.tolist()
    [True, True]
    """
    model, robot = cal.in_robot_frame()
    program = model.conditions(q_program, target=target, loads=loads)
    q0 = program.q
    n, dim = model.n_joints, model.point_dim
    keep = n >= dim + model.orientation_dim if orientation is None else bool(orientation)
    goal = _Goal(model, robot, program, keep)
    q = q0.copy()
    everyone = np.arange(q.shape[0])
    residual = goal.residual(q, everyone)
    at_program = residual.copy()  # where the program's own commands take the tool
    done = np.zeros(q.shape[0], dtype=bool)
    for _ in range(max_iter):
        done = np.linalg.norm(residual, axis=1) <= tol_mm
        active = np.flatnonzero(~done)
        if active.size == 0:
            break
        jac = goal.jacobian(q[active], active)
        pinv = np.linalg.pinv(jac, rcond=1e-10)  # (a, n, k)
        step = -np.einsum("ank,ak->an", pinv, residual[active])
        # Minimum-norm steps, and whatever the goal leaves free drifts back towards q0.
        null = np.eye(n) - pinv @ jac
        step += np.einsum("anm,am->an", null, q0[active] - q[active])
        q[active] += step
        residual[active] = goal.residual(q[active], active)
    done = np.linalg.norm(residual, axis=1) <= tol_mm
    reasons = [
        "" if ok else "no joint command reaches it (out of reach or at a singularity)"
        for ok in done
    ]
    limits = model.joint_limits
    inside = model.within_limits(q)
    for i in np.flatnonzero(done & ~np.all(inside, axis=1)):
        j = int(np.flatnonzero(~inside[i])[0])
        lo, hi = np.degrees(limits[j])
        reasons[i] = (
            f"joint {j + 1} would need {np.degrees(q[i, j]):.4g} deg, beyond its limits "
            f"[{lo:g}, {hi:g}] deg"
        )
        done[i] = False
    q = np.where(done[:, None], q, q0)
    final = goal.rows(q, everyone)
    covariance = cal.robot_covariance()
    before = np.linalg.norm(at_program[:, :dim], axis=1)
    after = np.sqrt(tip_variances(model.jacobian(final, robot), covariance))
    turn_before = turn_after = None
    if keep:
        arcs = np.linalg.norm(at_program[:, dim:], axis=1)
        turn_before = np.degrees(arcs / goal.scale)
        angles = model.orientation_jacobian(final, robot)  # (m, k, p)
        turn_after = np.degrees(np.sqrt(tip_variances(angles, covariance)))
    return Compensation(q, done, tuple(reasons), before, after, turn_before, turn_after, q0)
