"""What a calibration buys: validation on held-out poses, corrected joint commands.

**Validation** (:func:`validate`) compares measured positions with the nominal
model and with the calibrated one.  Both are placed where the calibration put
the arm in the instrument frame (its base pose ``x0, y0, phi0``): the
instrument's pose is not the robot's error, so "before" is the nominal
geometry at the calibrated base pose.  Next to the measured errors it gives
the error the calibration predicts for a measurement:
``sqrt(tr(J C J^T) + tr(Sigma))``, the model's uncertainty at the pose (``J``
the Jacobian in the user parameters, ``C`` their covariance) plus the
instrument's noise.  A calibrated error far above it means the model misses
something.

**Compensation** (:func:`compensate`) corrects a robot program: for every
commanded pose ``q0`` it finds joint commands ``q`` with which the calibrated
arm puts its target where the nominal arm would have, ``p_cal(q) = p_nom(q0)``,
in the robot's own frame (the base pose is the instrument's and is never
"corrected").  With ``n >= 3`` joints the tool's direction is kept too,
``phi_cal(q) = phi_nom(q0)``.  Newton's method from ``q0`` with minimum-norm
steps, the rest of the joint space pulled back towards ``q0``
(``dq = -J^+ r + (I - J^+ J)(q0 - q)``), so the remaining redundancy
(``n > 3``) goes to the smallest joint change.  A pose the iteration cannot
reach (out of reach, at a singularity) or whose correction leaves a joint
limit is listed as uncorrectable and keeps its command: never clipped.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .errors import ArmcalError, NotIdentifiableError
from .identification import identify
from .models import (
    CalibratedArm,
    Elastostatic,
    Loads,
    PlanarArm,
    check_target,
    forward_kinematics,
    jacobian,
    joint_jacobian,
    tool_angles,
    wrap_angle,
)
from .noise import NoiseModel

__all__ = [
    "Compensation",
    "CrossValidation",
    "Validation",
    "compensate",
    "cross_validate",
    "predicted_errors",
    "validate",
]


def _rms(values: np.ndarray) -> float:
    return float(np.sqrt(np.mean(values**2))) if values.size else 0.0


@dataclass(frozen=True, eq=False)
class Validation:
    """Positioning errors of the nominal and the calibrated model on held-out poses.

    Attributes
    ----------
    before : ndarray, shape (m, 2)
        Measured minus nominal position (at the calibrated base pose), mm.
    after : ndarray, shape (m, 2)
        Measured minus calibrated position, mm.
    predicted_mm : ndarray, shape (m,)
        The calibrated error a measurement is expected to show (RMS over the
        noise and the calibration's uncertainty), mm.
    model_mm : ndarray, shape (m,)
        The calibrated model's own uncertainty at the pose (RMS), mm.
    positions : ndarray, shape (m, 2)
        The measured positions (in the plane for 3-D data), mm.
    out_of_plane_mm : ndarray, shape (m,), or None
        For 3-D data: each point's distance from its target's plane, mm.
    """

    before: np.ndarray
    after: np.ndarray
    predicted_mm: np.ndarray
    model_mm: np.ndarray
    positions: np.ndarray
    out_of_plane_mm: np.ndarray | None = None

    @property
    def before_mm(self) -> np.ndarray:
        """Euclidean error ``(m,)`` of the nominal model, mm."""
        return np.hypot(self.before[:, 0], self.before[:, 1])

    @property
    def after_mm(self) -> np.ndarray:
        """Euclidean error ``(m,)`` of the calibrated model, mm."""
        return np.hypot(self.after[:, 0], self.after[:, 1])

    def summary(self) -> dict[str, float]:
        """RMS, max and 95 % quantile before and after, and the predicted RMS after (mm)."""
        before, after = self.before_mm, self.after_mm
        return {
            "rms_before_mm": _rms(before),
            "rms_after_mm": _rms(after),
            "max_before_mm": float(np.max(before)),
            "max_after_mm": float(np.max(after)),
            "p95_before_mm": float(np.percentile(before, 95)),
            "p95_after_mm": float(np.percentile(after, 95)),
            "predicted_rms_after_mm": _rms(self.predicted_mm),
            "model_rms_mm": _rms(self.model_mm),
        }


def _noise(cal: CalibratedArm) -> NoiseModel:
    """The noise of one measurement: the arm's model, else isotropic at the calibration's sigma."""
    return cal.arm.noise if cal.arm.noise is not None else NoiseModel.isotropic(cal.sigma_mm)


def predicted_errors(
    cal: CalibratedArm,
    q: np.ndarray,
    *,
    target: np.ndarray | None = None,
    row_sigma: np.ndarray | None = None,
    loads: Loads | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """The calibrated model's uncertainty and a measurement's expected error ``(m,)`` each, mm.

    ``sqrt(tr(J C J^T))`` in the instrument frame (base pose included) and
    ``sqrt(tr(J C J^T) + tr(Sigma_i))`` with the noise of the measurement.

    Examples
    --------
    >>> arm = PlanarArm([2.0, 1.0])
    >>> cal = CalibratedArm(arm, np.zeros(4), np.zeros((4, 4)), 0.01)
    >>> [v.round(6).tolist() for v in predicted_errors(cal, np.zeros((1, 2)))]
    [[0.0], [0.014142]]
    """
    q = np.asarray(q, dtype=float)
    j, covariance = cal.position_jacobian(q, loads=loads, target=target)  # (m, 2, p)
    model = np.einsum("mia,ab,mib->m", j, covariance, j)
    noise = cal.arm.pose_covariances(q, cal.params, row_sigma, target=target, noise=_noise(cal))
    total = model + np.trace(noise, axis1=-2, axis2=-1)
    return np.sqrt(np.clip(model, 0.0, None)), np.sqrt(np.clip(total, 0.0, None))


def validate(
    cal: CalibratedArm,
    q: np.ndarray,
    points: np.ndarray,
    *,
    target: np.ndarray | None = None,
    row_sigma: np.ndarray | None = None,
    loads: Loads | None = None,
) -> Validation:
    """Positioning error before and after calibration on held-out measurements.

    Parameters
    ----------
    cal : CalibratedArm
    q : ndarray, shape (m, n)
        Joint angles of the held-out poses, rad.
    points : ndarray, shape (m, 2) or (m, 3)
        Measured positions in the instrument frame, mm: 2-D, or 3-D for a
        calibration from 3-D data (projected into its plane).
    target : ndarray of int, shape (m,), optional
        Every row's target, for an arm with several.
    row_sigma : ndarray, shape (m,), optional
        Per-row instrument noise (mm) for the predicted error.
    loads : Loads, optional
        Every row's payload and tip force, for a calibration with compliance
        (default: the robot file's payload).  The nominal model has none.

    Returns
    -------
    Validation

    Raises
    ------
    ArmcalError
        For 2-D points with a 3-D calibration or the other way round.

    Examples
    --------
    >>> arm = PlanarArm([2.0, 1.0])
    >>> truth = arm.params_from_display([0.01, 0.0], [0.5, 0.0])
    >>> cal = CalibratedArm(arm, truth, np.zeros((4, 4)), 0.001)
    >>> q = np.radians([[0.0, 30.0], [45.0, -60.0]])
    >>> v = validate(cal, q, forward_kinematics(arm, q, truth))
    >>> bool(v.summary()["rms_before_mm"] > 0.02), float(v.summary()["rms_after_mm"])
    (True, 0.0)
    """
    q = np.asarray(q, dtype=float)
    points = np.asarray(points, dtype=float)
    target = check_target(cal.arm, q, target)
    out_of_plane = None
    if cal.plane is not None:
        if points.shape[-1] != 3:
            raise ArmcalError(
                "the calibration was made from 3-D data: validate with x_mm, y_mm and z_mm"
            )
        out_of_plane = cal.plane.distance(points, target)
        xy = cal.plane.to_plane(points)
    else:
        if points.shape[-1] != 2:
            raise ArmcalError(
                "the calibration was made from 2-D data: validate with x_mm and y_mm (no z_mm)"
            )
        xy = points
    nominal = forward_kinematics(cal.arm, q, cal.base_pose_params(), target=target)
    calibrated = cal.positions(q, loads=loads, target=target)
    model, predicted = predicted_errors(cal, q, target=target, row_sigma=row_sigma, loads=loads)
    return Validation(xy - nominal, xy - calibrated, predicted, model, xy, out_of_plane)


@dataclass(frozen=True, eq=False)
class CrossValidation:
    """K-fold prediction errors: every pose predicted by a calibration made without it.

    Attributes
    ----------
    folds : int
        Number of folds ``K``.
    fold : ndarray of int, shape (m,)
        The fold (0..K-1) every row was held out in.
    errors : ndarray, shape (m, 2)
        Measured minus predicted position of every row, by the calibration of
        the other folds, mm.
    predicted_mm : ndarray, shape (m,)
        The error that calibration predicts for the row (its uncertainty and
        the instrument noise), mm.
    """

    folds: int
    fold: np.ndarray
    errors: np.ndarray
    predicted_mm: np.ndarray

    @property
    def errors_mm(self) -> np.ndarray:
        """Euclidean prediction error ``(m,)`` of every row, mm."""
        return np.hypot(self.errors[:, 0], self.errors[:, 1])

    def summary(self) -> dict[str, float | int]:
        """``folds``, RMS and max prediction error and the predicted RMS (mm)."""
        return {
            "folds": self.folds,
            "rms_mm": _rms(self.errors_mm),
            "max_mm": float(np.max(self.errors_mm)),
            "predicted_rms_mm": _rms(self.predicted_mm),
        }


def cross_validate(
    arm: PlanarArm,
    q: np.ndarray,
    xy: np.ndarray,
    folds: int,
    *,
    groups: np.ndarray | None = None,
    target: np.ndarray | None = None,
    sigma: float | None = None,
    row_sigma: np.ndarray | None = None,
    rng: np.random.Generator | int | None = None,
    elastic: Elastostatic | None = None,
    loads: Loads | None = None,
) -> CrossValidation:
    """K-fold cross-validation of the calibration of ``arm`` from in-plane data.

    Parameters
    ----------
    arm : PlanarArm
        The model identified (noise model and fixed parameters included).
    q : ndarray, shape (m, n)
        Joint angles, rad.
    xy : ndarray, shape (m, 2)
        Measured positions in the frame identified in (the plane for 3-D data), mm.
    folds : int
        ``K >= 2``: every fold is left out once and predicted by the others.
    groups : ndarray, shape (m,), optional
        Rows that belong together (the targets measured at one pose) stay in
        one fold; every row its own group by default.
    target, sigma, row_sigma, elastic, loads
        As for :func:`armcal.identification.identify`.
    rng : numpy.random.Generator or int or None
        Shuffles the groups into folds.

    Returns
    -------
    CrossValidation

    Raises
    ------
    ArmcalError
        If ``K`` is out of range or some fold's complement cannot identify the
        parameters (too few poses for ``K`` folds).
    """
    rng = np.random.default_rng(rng)
    q = np.asarray(q, dtype=float)
    m = q.shape[0]
    keys = np.arange(m) if groups is None else np.unique(groups, return_inverse=True)[1]
    count = int(keys.max()) + 1
    if not 2 <= folds <= count:
        raise ArmcalError(f"--cross-validate needs 2 to {count} folds (the poses), got {folds}")
    of_group = np.empty(count, dtype=int)
    of_group[rng.permutation(count)] = np.arange(count) % folds
    fold = of_group[keys]
    errors = np.empty((m, 2))
    predicted = np.empty(m)
    for k in range(folds):
        held = fold == k
        train = ~held
        sub = None if target is None else target[train]
        try:
            cal = identify(
                arm,
                q[train],
                xy[train],
                sigma=sigma,
                row_sigma=None if row_sigma is None else row_sigma[train],
                target=sub,
                elastic=elastic,
                loads=None if loads is None else loads.take(train),
            )
        except NotIdentifiableError:
            raise ArmcalError(
                f"with {folds} folds, the poses left after holding out fold {k + 1} cannot "
                "identify every parameter; use fewer folds or measure more poses"
            ) from None
        test = None if target is None else target[held]
        fitted = cal.calibrated()
        held_loads = None if loads is None else loads.take(held)
        errors[held] = xy[held] - fitted.positions(q[held], loads=held_loads, target=test)
        rows = None if row_sigma is None else row_sigma[held]
        predicted[held] = predicted_errors(
            fitted, q[held], target=test, row_sigma=rows, loads=held_loads
        )[1]
    return CrossValidation(folds, fold, errors, predicted)


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
        The same for the tool's direction (``n >= 3``), deg.
    """

    q: np.ndarray
    corrected: np.ndarray
    reasons: tuple[str, ...]
    position_before_mm: np.ndarray
    position_after_mm: np.ndarray
    orientation_before_deg: np.ndarray | None
    orientation_after_deg: np.ndarray | None

    @property
    def uncorrectable(self) -> np.ndarray:
        """0-based indices of the poses left uncorrected."""
        return np.flatnonzero(~self.corrected)

    def summary(self) -> dict[str, float | None]:
        """RMS of the predicted errors before and after (mm, deg) over the corrected poses."""
        ok = self.corrected
        out: dict[str, float | None] = {
            "rms_before_mm": _rms(self.position_before_mm[ok]),
            "rms_after_mm": _rms(self.position_after_mm[ok]),
            "orientation_rms_before_deg": None,
            "orientation_rms_after_deg": None,
        }
        if self.orientation_before_deg is not None and self.orientation_after_deg is not None:
            out["orientation_rms_before_deg"] = _rms(self.orientation_before_deg[ok])
            out["orientation_rms_after_deg"] = _rms(self.orientation_after_deg[ok])
        return out


def _residual(
    arm: PlanarArm,
    q: np.ndarray,
    params: np.ndarray,
    target: np.ndarray | None,
    goal: np.ndarray,
    goal_angle: np.ndarray | None,
    scale: float,
    deflection: np.ndarray | None = None,
) -> np.ndarray:
    """``(m, k)``: position (mm) and, with an orientation goal, ``scale`` times its angle (mm)."""
    r = forward_kinematics(arm, q, params, target=target, deflection=deflection) - goal
    if goal_angle is None:
        return r
    turn = tool_angles(arm, q, params, target=target) - goal_angle
    if deflection is not None:  # the tool turns with every joint's deflection
        turn = turn + np.sum(deflection, axis=-1)
    return np.column_stack([r, scale * wrap_angle(turn)])


def _solve_jacobian(
    arm: PlanarArm,
    q: np.ndarray,
    params: np.ndarray,
    target,
    orientation: bool,
    scale: float,
    deflection: np.ndarray | None = None,
) -> np.ndarray:
    """``d residual / dq`` ``(m, k, n)``: the joint Jacobian, with the tool angle's row.

    Under load, at the deflected pose; the deflection's own change with ``q``
    (about 1e-3 of a step) only slows Newton's convergence from quadratic to fast linear.
    """
    jac = joint_jacobian(arm, q, params, target=target, deflection=deflection)
    if not orientation:
        return jac
    row = scale * arm.joint_map[-1]  # the tool turns with the last link angle
    return np.concatenate([jac, np.broadcast_to(row, (q.shape[0], 1, arm.n_joints))], axis=1)


def compensate(
    cal: CalibratedArm,
    q_program: np.ndarray,
    *,
    target: np.ndarray | None = None,
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
        Keep the tool's direction too; default for arms of 3 or more joints.
    tol_mm : float
        A pose is corrected when the calibrated arm reaches the goal within
        this distance (mm; the tool angle's residual counted at the reach).
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
    arm = cal.arm
    q0 = np.asarray(q_program, dtype=float)
    target = check_target(arm, q0, target)
    n = arm.n_joints
    keep_angle = n >= 3 if orientation is None else bool(orientation)
    robot = cal.robot_params()
    scale = float(np.sum(arm.link_nominal))  # an angle counted as the tip's arc at full reach
    goal = forward_kinematics(arm, q0, None, target=target)
    goal_angle = tool_angles(arm, q0, None, target=target) if keep_angle else None
    model = cal.robot_compliance()
    if model is not None and loads is None:
        loads = Loads.create(q0.shape[0], model.elastic.payload_kg)
    values = cal.compliance_values

    def deflection(rows: np.ndarray) -> np.ndarray | None:
        if model is None or loads is None or values is None:
            return None
        return model.deflection(q[rows], robot, values, loads.take(rows))

    q = q0.copy()
    everyone = np.arange(q.shape[0])
    residual = _residual(arm, q, robot, target, goal, goal_angle, scale, deflection(everyone))
    at_program = residual.copy()  # where the program's own commands take the tool
    done = np.zeros(q.shape[0], dtype=bool)
    for _ in range(max_iter):
        done = np.linalg.norm(residual, axis=1) <= tol_mm
        active = np.flatnonzero(~done)
        if active.size == 0:
            break
        sub = None if target is None else target[active]
        bend = deflection(active)
        jac = _solve_jacobian(arm, q[active], robot, sub, keep_angle, scale, bend)
        pinv = np.linalg.pinv(jac, rcond=1e-10)  # (a, n, k)
        step = -np.einsum("ank,ak->an", pinv, residual[active])
        # Minimum-norm steps, and whatever the goal leaves free drifts back towards q0.
        null = np.eye(n) - pinv @ jac
        step += np.einsum("anm,am->an", null, q0[active] - q[active])
        q[active] += step
        residual[active] = _residual(
            arm,
            q[active],
            robot,
            sub,
            goal[active],
            None if goal_angle is None else goal_angle[active],
            scale,
            deflection(active),
        )
    done = np.linalg.norm(residual, axis=1) <= tol_mm
    reasons = [
        "" if ok else "no joint command reaches it (out of reach or at a singularity)"
        for ok in done
    ]
    inside = arm.within_limits(q)
    for i in np.flatnonzero(done & ~np.all(inside, axis=1)):
        j = int(np.flatnonzero(~inside[i])[0])
        lo, hi = np.degrees(arm.joint_limits[j])
        reasons[i] = (
            f"joint {j + 1} would need {np.degrees(q[i, j]):.4g} deg, beyond its limits "
            f"[{lo:g}, {hi:g}] deg"
        )
        done[i] = False
    q = np.where(done[:, None], q, q0)
    if model is None or values is None:
        covariance = cal.robot_covariance()
        j_user = jacobian(arm, q, robot, target=target)
    else:
        covariance = cal.robot_full_covariance()
        j_user = model.jacobian(q, np.concatenate([robot, values]), loads)
    before = np.linalg.norm(at_program[:, :2], axis=1)
    after = np.sqrt(np.clip(np.einsum("mia,ab,mib->m", j_user, covariance, j_user), 0, None))
    turn_before = turn_after = None
    if keep_angle:
        assert goal_angle is not None
        turn_before = np.degrees(np.abs(at_program[:, 2]) / scale)
        # The tool angle moves with the last link vector's angle deviation only.
        k = arm.n_links
        last = k - arm.n_target_links + (0 if target is None else target)
        g = np.zeros((q.shape[0], arm.n_params))
        g[:, k : 2 * k] = arm.angle_map[last]
        if model is not None:  # and with every compliance parameter's deflection
            g = np.concatenate([g, model.loads(q, robot, loads)], axis=-1)
        variance = np.einsum("ma,ab,mb->m", g, covariance, g)
        turn_after = np.degrees(np.sqrt(np.clip(variance, 0.0, None)))
    return Compensation(q, done, tuple(reasons), before, after, turn_before, turn_after)
