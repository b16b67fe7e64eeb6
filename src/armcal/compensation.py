"""Corrected joint commands: the calibrated arm goes where the nominal program meant.

**Compensation** (:func:`compensate`) corrects a robot program: for every
commanded pose ``q0`` it finds joint commands ``q`` with which the calibrated
arm puts its target where the nominal arm would have, ``p_cal(q) = p_nom(q0)``,
in the robot's own frame (the instrument's pose is never "corrected",
:meth:`~armcal.models.interface.FitModel.in_robot_frame`).  When the arm has
joints to spare (``n >= d + k``: 3 in the plane) the tool's orientation is kept
too.  A pose the iteration cannot reach (out of reach, at a singularity), whose
correction is not small (near a singularity) or whose correction leaves a joint
limit is listed as uncorrectable and keeps its command: never clipped.

**The iteration** is Levenberg-Marquardt in trust-region form (More 1978), all
poses at once: each step minimises ``|r + J dq|`` within a radius ``|dq| <= D``
(rad), taken from the SVD of the goal Jacobian ``J`` as
``dq = -V diag(s / (s^2 + mu)) U^T r``, with ``mu = 0`` (Newton's step) when that
step is within the radius and otherwise the ``mu`` that puts it on the radius
(Hebden's iteration).  A step is kept when the residual falls by at least a
small fraction of what the linear model promised; the radius shrinks
after a poor step and grows back, up to the pose's bound, after a good one.
Well-conditioned poses take Newton's steps undamped from the first iteration
and converge quadratically to round-off; near a singularity the steps stay
short, so the iteration cannot jump to another branch of the inverse
kinematics.  Where the arm has joints to spare, the rest of the joint space is
pulled back towards ``q0`` (``(I - V V^T)(q0 - q)``), so the redundancy goes to
the smallest joint change.

**The bound.**  A revolute joint turned by ``dq`` moves the tool by at most
``dq R`` (``R`` the arm's reach) and turns it by at most ``dq``, so a pose whose
tool misses by ``e`` mm and ``a`` rad has an error *as an angle*
``eps = hypot(e / R, a)``; its correction moves some joint by at least
``eps / n``, and a well-conditioned arm corrects it with joint changes of 1-4
``eps`` (the median over random poses within the limits is 1.4-2.9 on the
built-in arms, planar and spatial).  A correction that needs more
than :data:`MAX_AMPLIFICATION` ``eps`` on a joint, five times the top of that
range, is amplified by the arm's geometry: the goal Jacobian (in units of the
reach) has a singular value below ``1 / MAX_AMPLIFICATION`` along the error,
as at a wrist within about 3 deg of ``J5 = 0`` or a wrist centre near the axis
of ``J1``.  Such a correction is not the calibration's (the calibration's
errors are tenths of a mm and hundredths of a degree per joint) and is refused
with the reason *near a singularity* and the joint change it needs.  The
iteration never leaves that bound (a step that would take a joint beyond it stops
on it), so it never wanders off to another branch; a pose that needs more stalls on it.

A model of joint compliance also takes out the joints' deflection under the
program's load; every family works through
:class:`~armcal.models.interface.FitModel`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from .identification.result import Calibration, calibrated_arm
from .models import CalibratedArm, Conditions, FitModel, Loads, position_jacobian
from .models.information import tip_variances
from .numerics import RANK_RTOL, rms

__all__ = [
    "MAX_AMPLIFICATION",
    "Compensation",
    "Payload",
    "compensate",
]

#: The largest change of a joint a correction may make, in units of the pose's error
#: as an angle (module notes): five times what a well-conditioned arm needs (1-4).
MAX_AMPLIFICATION = 20.0

#: A trust-region step is kept when the residual's squared norm falls by at least this
#: fraction of the fall the linear model predicts (More 1978; Nocedal & Wright,
#: Algorithm 4.1, eta): any real progress, but not an increase.
_ACCEPT_RATIO = 1e-4

#: Below this ratio of actual to predicted fall the linear model was poor over the step:
#: the radius is quartered.  Above :data:`_GOOD_FIT` a step on the radius doubles it.
_POOR_FIT = 0.25
_GOOD_FIT = 0.75

#: Hebden's iterations for the damping that puts a step on its radius: each is Newton's
#: step on ``1 / |dq(mu)| - 1 / D``, nearly linear in ``mu``, so a few give the radius
#: to a fraction of a percent; the step is then scaled onto the radius exactly.
_HEBDEN_STEPS = 8


@dataclass(frozen=True)
class Payload:
    """The payload a compensation corrected the sag under: the smallest and largest (kg)
    and where it came from (the program's ``payload_kg`` column, the ``payload_kg``
    argument, or the calibration's default, what its robot file or its data carried)."""

    low_kg: float
    high_kg: float
    source: str


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
        where the nominal arm registered on its own puts it (the calibration's
        baseline; without one, the nominal arm at the calibrated instrument pose):
        the error a user without calibration sees, mm.
    position_after_mm : ndarray, shape (m,)
        The calibrated model's uncertainty (RMS) at the corrected command: the
        error left after compensation, as the calibration predicts it, mm.
    orientation_before_deg, orientation_after_deg : ndarray, shape (m,), or None
        The same for the tool's orientation (when it is kept), deg.
    commanded : ndarray, shape (m, n)
        The program's own commands, rad.
    bound_deg : ndarray, shape (m,)
        The largest change of a joint the correction of each pose may make:
        :data:`MAX_AMPLIFICATION` times the pose's error as an angle, deg.
    """

    q: np.ndarray
    corrected: np.ndarray
    reasons: tuple[str, ...]
    position_before_mm: np.ndarray
    position_after_mm: np.ndarray
    orientation_before_deg: np.ndarray | None
    orientation_after_deg: np.ndarray | None
    commanded: np.ndarray
    bound_deg: np.ndarray

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
        self.dim = model.position_dim  # a 6-DoF instrument's orientation rows aside
        self.position = model.positions(program, nominal)[..., : self.dim]
        self.angle = model.orientation(program, nominal) if orientation else None
        self.scale = model.angle_scale_mm  # an angle counted as an arc of this radius (mm)
        self.width = self.dim + (0 if self.angle is None else self.angle.shape[-1])

    def rows(self, q: np.ndarray, active: np.ndarray) -> Conditions:
        """The conditions of the rows ``active`` at commands ``q`` (their targets and loads)."""
        sub = self.program.take(active)
        return Conditions(q, sub.target, sub.loads)

    def _residual(self, rows: Conditions, active: np.ndarray) -> np.ndarray:
        """``(a, d [+ k])`` at the rows ``active``: position (mm) and, keeping the
        orientation, its angles as arcs."""
        r = self.model.positions(rows, self.params)[..., : self.dim] - self.position[active]
        if self.angle is None:
            return r
        turn = self.model.orientation_turn(rows, self.params, self.angle[active])
        return np.concatenate([r, self.scale * turn], axis=1)

    def linearized(self, q: np.ndarray, active: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The residual ``(a, d [+ k])`` (position, mm, and keeping the orientation, its
        angles as arcs) and its :meth:`jacobian` at once: a block's residual comes from the
        pass of its Jacobian (the iteration needs both at every trial it keeps)."""
        residual = np.empty((active.size, self.width))
        jacobian = np.empty((*residual.shape, q.shape[1]))
        for rows, part in self.rows(q, active).blocks():
            jacobian[part] = self._jacobian(rows)
            residual[part] = self._residual(rows, active[part])
        return residual, jacobian

    def error_angle(self, residual: np.ndarray) -> np.ndarray:
        """``(a,)``: a residual as one angle (rad), its position seen from the arm's reach.

        A joint turned by ``dq`` moves the tool by at most ``dq`` times the reach and
        turns it by at most ``dq``: this is the smallest joint change that could remove
        the residual, give or take the number of joints.
        """
        dim = self.dim
        shift = np.linalg.norm(residual[:, :dim], axis=1) / self.model.reach_mm
        turn = np.linalg.norm(residual[:, dim:], axis=1) / self.scale
        return np.hypot(shift, turn)

    def jacobian(self, q: np.ndarray, active: np.ndarray) -> np.ndarray:
        """``d residual / dq`` ``(a, d [+ k], n)``, at the deflected pose under load.

        The deflection's own change with ``q`` (about 1e-3 of a step) only slows
        Newton's convergence from quadratic to fast linear.
        """
        # A block's whole Jacobians at a time.
        return np.concatenate([self._jacobian(rows) for rows, _ in self.rows(q, active).blocks()])

    def _jacobian(self, rows: Conditions) -> np.ndarray:
        # The tool's first: a model may keep that pass for the point's (SpatialArm).
        turn = None
        if self.angle is not None:
            turn = self.scale * self.model.orientation_joint_jacobian(rows, self.params)
        jac = self.model.joint_jacobian(rows, self.params)[..., : self.dim, :]
        return jac if turn is None else np.concatenate([jac, turn], axis=1)


@dataclass(frozen=True, eq=False)
class _Step:
    """A trust-region step of every active row and what the linear model promises.

    Attributes
    ----------
    dq : ndarray, shape (a, n)
        The step, rad: the damped least-squares step within the radius, plus the pull
        of the joints the goal leaves free back towards ``q0``.
    gain : ndarray, shape (a,)
        ``|r|^2 - |r + J dq|^2``: the fall of the squared residual the linear model
        predicts (mm^2).
    on_radius : ndarray of bool, shape (a,)
        Whether the step was damped onto its radius (Newton's step was longer).
    """

    dq: np.ndarray
    gain: np.ndarray
    on_radius: np.ndarray


def _trust_region_step(
    jac: np.ndarray, residual: np.ndarray, radius: np.ndarray, pull: np.ndarray
) -> _Step:
    """Levenberg-Marquardt steps ``(a, n)`` with ``|dq| <= radius`` (module notes).

    ``jac`` ``(a, k, n)``, ``residual`` ``(a, k)``, ``radius`` ``(a,)`` (rad) and
    ``pull`` ``(a, n)``, the way back to ``q0``.  Singular values at or below
    :data:`~armcal.numerics.RANK_RTOL` of a row's largest count as zero: the step
    does not move along them, and the pull may.

    A square Jacobian whose condition number is surely below ``1 / RANK_RTOL`` (by the
    bound of :data:`_NEWTON_COND`) and whose Newton step is within the radius takes that
    step as it is (``mu = 0``, every singular value kept, nothing left for the pull): from
    an LU solve, not an SVD, which every other row gets.
    """
    newton = _newton_steps(jac, residual, radius)
    if newton is not None:
        easy, dq, gain = newton
        hard = ~easy
        if hard.any():
            rest = _svd_step(jac[hard], residual[hard], radius[hard], pull[hard])
            dq[hard], gain[hard] = rest.dq, rest.gain
            on_radius = np.zeros(easy.size, dtype=bool)
            on_radius[hard] = rest.on_radius
            return _Step(dq, gain, on_radius)
        return _Step(dq, gain, np.zeros(easy.size, dtype=bool))
    return _svd_step(jac, residual, radius, pull)


#: A square Jacobian ``J`` ``(n, n)`` with ``|det J| / |J|_F^n`` above the inverse of this
#: bound has every singular value kept (``RANK_RTOL`` = 1e-10) with a margin of 100:
#: ``s_min >= |det J| / s_max^(n-1)`` (the other singular values are at most ``s_max``), so
#: ``s_min / s_max >= |det J| / s_max^n >= |det J| / |J|_F^n``.  The bound is pessimistic,
#: and the rows it turns away take the SVD's step, the same one: on 10^5 poses of the
#: built-in industrial 6R uniform within its limits, the goal Jacobian's (mm) bound has a
#: median of 5e-6 where its condition number's is 31, and it turns away 0.4 % of them.
_NEWTON_COND = 1e8


def _newton_steps(
    jac: np.ndarray, residual: np.ndarray, radius: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
    """For square goal Jacobians: which rows take Newton's step as it is (module notes of
    :func:`_trust_region_step`), their steps ``-J^-1 r`` (zero elsewhere) and gains
    ``|r|^2`` (the linear model's whole residual goes); None where the Jacobians are not
    square."""
    a, k, n = jac.shape
    if k != n or a == 0:
        return None
    sign, logdet = np.linalg.slogdet(jac)
    with np.errstate(divide="ignore"):
        frobenius = np.log(np.sqrt(np.einsum("akn,akn->a", jac, jac)))
    sure = np.flatnonzero((sign != 0) & (logdet - n * frobenius > -np.log(_NEWTON_COND)))
    dq = np.zeros((a, n))
    dq[sure] = -np.linalg.solve(jac[sure], residual[sure][..., None])[..., 0]
    easy = np.zeros(a, dtype=bool)
    easy[sure] = np.einsum("an,an->a", dq[sure], dq[sure]) <= radius[sure] ** 2
    return easy, dq, np.einsum("ak,ak->a", residual, residual)


def _svd_step(
    jac: np.ndarray, residual: np.ndarray, radius: np.ndarray, pull: np.ndarray
) -> _Step:
    """:func:`_trust_region_step` from the SVD of every row's Jacobian."""
    u, s, vt = np.linalg.svd(jac, full_matrices=False)  # (a, k, r), (a, r), (a, r, n)
    kept = s > RANK_RTOL * s[:, :1]
    s = np.where(kept, s, 0.0)
    c = np.einsum("akr,ak->ar", u, residual)  # the residual in the range's basis
    f = s * c
    mu = np.zeros(s.shape[0])
    on_radius = np.zeros(s.shape[0], dtype=bool)
    for _ in range(_HEBDEN_STEPS):
        denom = s**2 + mu[:, None]
        w = np.divide(f, denom, out=np.zeros_like(f), where=kept)  # -dq in the basis vt
        length = np.linalg.norm(w, axis=1)
        long = length > radius
        on_radius |= long
        if not np.any(long):
            break
        # Newton's step on 1 / |w(mu)| - 1 / radius (d|w|^2/dmu = -2 tail).
        tail = np.sum(np.divide(f**2, denom**3, out=np.zeros_like(f), where=kept), axis=1)
        ratio = np.divide(length, radius, out=np.ones_like(length), where=long)
        mu += np.divide(length**2 * (ratio - 1.0), tail, out=np.zeros_like(mu), where=long)
    # Hebden's iterates approach the radius from outside: the last one goes onto it.
    w *= np.minimum(1.0, radius / np.where(length > 0, length, 1.0))[:, None]
    gain = np.sum(c**2 - (c - s * w) ** 2, axis=1)
    back = np.einsum("arn,an->ar", vt, pull) * kept
    free = pull - np.einsum("ar,arn->an", back, vt)
    return _Step(free - np.einsum("ar,arn->an", w, vt), gain, on_radius)


def _singular_reasons(
    goal: _Goal,
    q: np.ndarray,
    failed: np.ndarray,
    beyond: np.ndarray,
    bound: np.ndarray,
    at_program: np.ndarray,
) -> list[str]:
    """Why each pose of ``failed`` was not corrected ("" for the others).

    A pose whose iteration left its bound needs more than the bound: the reason gives
    what the linearized correction at the program's command needs where that is more.
    A pose whose iteration stalled within its bound gives the condition number of the
    goal Jacobian where it stopped (a pose out of reach stops at a singularity too).
    """
    reasons = [""] * q.shape[0]
    q0 = goal.program.q
    eps = np.degrees(goal.error_angle(at_program))
    limit = np.degrees(bound)
    rows = np.flatnonzero(failed & beyond)
    if rows.size:
        jac = goal.jacobian(q0[rows], rows)
        linear = np.degrees(
            np.abs(np.linalg.pinv(jac, rcond=RANK_RTOL) @ at_program[rows, :, None])
        )
        for i, need in zip(rows, linear[:, :, 0], strict=True):
            k = int(np.argmax(need))
            allowed = f"{MAX_AMPLIFICATION:g} times the tool's error as an angle, {eps[i]:.3g} deg"
            if need[k] > limit[i]:
                reasons[i] = (
                    f"near a singularity: the linearized correction needs {need[k]:.4g} deg "
                    f"on joint {k + 1}, more than the {limit[i]:.3g} deg allowed ({allowed})"
                )
            else:
                k = int(np.argmax(np.abs(q[i] - q0[i])))
                reasons[i] = (
                    f"near a singularity: the correction needs more than {limit[i]:.3g} deg "
                    f"on joint {k + 1} ({allowed})"
                )
    rows = np.flatnonzero(failed & ~beyond)
    if rows.size:
        s = np.linalg.svd(goal.jacobian(q[rows], rows), compute_uv=False)
        condition = np.divide(
            s[:, 0], s[:, -1], out=np.full(rows.size, np.inf), where=s[:, -1] > 0
        )
        for i, cond in zip(rows, condition, strict=True):
            reasons[i] = (
                f"near a singularity or out of reach: no command within {limit[i]:.3g} deg of "
                f"the program's on every joint reaches it (the goal Jacobian's condition "
                f"number there is {cond:.3g})"
            )
    return reasons


def _iterate(
    goal: _Goal,
    q0: np.ndarray,
    residual: np.ndarray,
    jacobian: np.ndarray,
    bound: np.ndarray,
    tol_mm: float,
    max_iter: int,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The trust-region iteration from the program's commands ``q0``, where the goal's
    ``residual`` and ``jacobian`` are given (module notes): the commands reached ``(m,
    n)``, their residuals, and which poses left their bound.

    A trial's residual and Jacobian come from one pass (:meth:`_Goal.linearized`): most
    trials are kept, and the next step needs the Jacobian there.  ``jacobian`` is
    overwritten with the Jacobian at the commands reached.
    """
    model = goal.model
    q = q0.copy()
    residual = residual.copy()
    radius = bound.copy()  # the trust region's, for the step's 2-norm (rad)
    # The squared miss at the start of the last _SLOW_STEPS iterations.
    history = np.full((_SLOW_STEPS, q.shape[0]), np.inf)
    for turn in range(max_iter):
        norm2 = np.sum(residual**2, axis=1)
        # A radius that moves the tool by less than tol_mm can no longer make progress;
        # nor, here, can steps that lowered the miss by less than _SLOW_FALL over the
        # last _SLOW_STEPS (near a singularity, or along the bound towards a goal beyond).
        slow = norm2 > _SLOW_FALL * history[turn % _SLOW_STEPS]
        history[turn % _SLOW_STEPS] = norm2
        moving = (radius * model.reach_mm > tol_mm) & ~slow
        active = np.flatnonzero((norm2 > tol_mm**2) & moving)
        if active.size == 0:
            break
        jac, back = jacobian[active], q0[active] - q[active]
        step = _trust_region_step(jac, residual[active], radius[active], back)
        trial, gain = _within_bound(step, jac, residual[active], -back, bound[active])
        trial += q0[active]
        after, at_trial = goal.linearized(trial, active)
        fall = norm2[active] - np.sum(after**2, axis=1)
        fit = np.divide(fall, gain, out=np.zeros_like(fall), where=gain > 0)
        good = step.on_radius & (fit > _GOOD_FIT)
        radius[active] = np.where(
            fit < _POOR_FIT,
            radius[active] / 4,
            np.where(good, np.minimum(2 * radius[active], bound[active]), radius[active]),
        )
        taken = fit > _ACCEPT_RATIO
        rows = active[taken]
        q[rows], residual[rows], jacobian[rows] = trial[taken], after[taken], at_trial[taken]
    # Left with a joint on its bound: the way on went beyond it.
    beyond = np.max(np.abs(q - q0), axis=1) >= (1 - _ON_BOUND) * bound
    return q, residual, beyond


#: A pose stops where its squared miss is more than this fraction of what it was
#: :data:`_SLOW_STEPS` iterations before: Newton's steps converge quadratically, and a
#: trust region that doubles after every good step reaches them within a few; a pose
#: that took 8 steps to lower its miss by less than 10x is near a singularity, or moves
#: along its bound towards a goal beyond it.
_SLOW_FALL = 0.01
_SLOW_STEPS = 8

#: A joint within this fraction of its bound is on it (where a clipped step put it).
_ON_BOUND = 1e-9


def _within_bound(
    step: _Step, jac: np.ndarray, residual: np.ndarray, offset: np.ndarray, bound: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """The trial's offset from the program's commands ``(a, n)``, each joint's clipped to
    its pose's ``bound`` (from ``offset``, where the commands are now), and the gain the
    linear model predicts for the step taken.

    A step that would take a joint beyond its bound stops there (a projected step): the
    iteration never leaves the bound, and a correction within it that an iterate would
    have overshot on the way is still found; one that needs more stalls on the bound.
    """
    moved = offset + step.dq
    clipped = np.clip(moved, -bound[:, None], bound[:, None])
    cut = np.any(clipped != moved, axis=1)
    gain = step.gain.copy()
    if cut.any():
        dq = clipped[cut] - offset[cut]
        linear = residual[cut] + np.einsum("akn,an->ak", jac[cut], dq)
        gain[cut] = np.sum(residual[cut] ** 2, axis=1) - np.sum(linear**2, axis=1)
    return clipped, gain


def _refuse_beyond_limits(
    model: FitModel, q: np.ndarray, done: np.ndarray, reasons: list[str]
) -> None:
    """Mark every corrected pose whose commands leave a joint limit as not corrected
    (``done`` and ``reasons`` changed in place), naming the joint and what it needs."""
    limits = model.joint_limits
    inside = model.within_limits(q)
    for i in np.flatnonzero(done & ~np.all(inside, axis=1)):
        j = int(np.flatnonzero(~inside[i])[0])
        slide = model.joint_kinds[j] == "P"  # a prismatic joint's reading is in mm
        (lo, hi), value = (
            (limits[j], q[i, j]) if slide else (np.degrees(limits[j]), np.degrees(q[i, j]))
        )
        unit = "mm" if slide else "deg"
        reasons[i] = (
            f"joint {j + 1} would need {_beyond(value, lo, hi)} {unit}, beyond its limits "
            f"[{lo:g}, {hi:g}] {unit}"
        )
        done[i] = False


def _accuracy(
    cal: CalibratedArm,
    goal: _Goal,
    robot: np.ndarray,
    final: Conditions,
    at_program: np.ndarray,
) -> tuple[np.ndarray, np.ndarray, np.ndarray | None, np.ndarray | None]:
    """The tool's error without the correction and its predicted std with it: position
    (mm) and, keeping the orientation, angle (deg); the angles None otherwise."""
    model, program, dim = goal.model, goal.program, goal.dim
    covariance = cal.robot_covariance()
    before = np.linalg.norm(at_program[:, :dim], axis=1)
    turn_before = (
        None
        if goal.angle is None
        else np.degrees(np.linalg.norm(at_program[:, dim:], axis=1) / goal.scale)
    )
    if cal.baseline is not None:  # the arm without calibration: the nominal one, registered
        # Each arm's points and tool from one pass of its own (the pass is kept on the rows).
        arm = cal.model.arm
        baseline = arm.positions(program, cal.baseline)
        reference = None if goal.angle is None else arm.orientation(program, cal.baseline)
        before = np.linalg.norm((cal.positions(program) - baseline)[:, :dim], axis=1)
        if reference is not None:
            turn = cal.model.orientation_turn(program, cal.params, reference)
            turn_before = np.degrees(np.linalg.norm(turn, axis=1))
    after, turn_after = np.empty(final.m), np.empty(final.m)
    for rows, part in final.blocks():  # a block's Jacobians (m, d, p) at a time
        if goal.angle is not None:  # the tool's first (see _Goal.jacobian)
            angles = model.orientation_jacobian(rows, robot)  # (m, k, p)
            turn_after[part] = np.degrees(np.sqrt(tip_variances(angles, covariance)))
        after[part] = np.sqrt(tip_variances(position_jacobian(model, rows, robot), covariance))
    if goal.angle is None:
        return before, after, None, None
    return before, after, turn_before, turn_after


def compensate(
    cal: Calibration | CalibratedArm,
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
    cal : Calibration or CalibratedArm
        What :func:`~armcal.identification.identify` returns, or a calibrated arm
        (:func:`~armcal.files.read_calibration`).
    q_program : ndarray, shape (m, n)
        The program's joint commands, rad (within the joint limits).
    target : ndarray of int or sequence of str, shape (m,), optional
        The target (tool point) every command is meant for, on an arm with several:
        its index or its label.
    orientation : bool, optional
        Keep the tool's orientation too; default where the arm has the joints
        (``n >= d + k``: 3 joints in the plane).
    tol_mm : float
        A pose is corrected when the calibrated arm reaches the goal within
        this distance (mm; the tool's angles counted as arcs at the reach).
    max_iter : int
        Trust-region steps at most (Newton's steps on well-conditioned poses).
    loads : Loads, optional
        The program's payload and tip force per row, for a calibration with
        compliance (default: the robot file's payload): the corrected commands
        also take out the joints' predicted deflection under that load.

    Returns
    -------
    Compensation
        Every pose either corrected within its bound (``bound_deg``; module notes)
        or kept, with the reason: near a singularity, out of reach, beyond a limit.

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
    cal = calibrated_arm(cal)
    model, robot = cal.in_robot_frame()
    program = model.conditions(q_program, target=target, loads=loads)
    q0 = program.q
    n, dim = model.n_joints, model.position_dim
    keep = n >= dim + model.orientation_dim if orientation is None else bool(orientation)
    goal = _Goal(model, robot, program, keep)
    everyone = np.arange(q0.shape[0])
    # Where the program's own commands take the tool, and the goal's Jacobian there.
    at_program, jacobian = goal.linearized(q0, everyone)
    bound = MAX_AMPLIFICATION * goal.error_angle(at_program)  # rad, per pose
    q, residual, beyond = _iterate(goal, q0, at_program, jacobian, bound, tol_mm, max_iter)
    del jacobian  # the iteration's
    done = np.linalg.norm(residual, axis=1) <= tol_mm  # within the bound: it never leaves it
    reasons = _singular_reasons(goal, q, ~done, beyond, bound, at_program)
    _refuse_beyond_limits(model, q, done, reasons)
    q = np.where(done[:, None], q, q0)
    final = goal.rows(q, everyone)
    before, after, turn_before, turn_after = _accuracy(cal, goal, robot, final, at_program)
    return Compensation(
        q, done, tuple(reasons), before, after, turn_before, turn_after, q0, np.degrees(bound)
    )


def _beyond(value: float, lo: float, hi: float) -> str:
    """``value`` with 4 significant digits, or as many more as it takes for the printed
    value to lie visibly beyond the printed limits ``[lo:g, hi:g]`` (-170.0004 beside
    -170, where 4 digits would print -170, which reads as within the limits).

    Examples
    --------
    >>> _beyond(-170.00041, -170.0, 170.0), _beyond(171.04, -170.0, 170.0)
    ('-170.0004', '171')
    """
    low, high = float(f"{lo:g}"), float(f"{hi:g}")
    for digits in range(4, 18):
        text = f"{value:.{digits}g}"
        if not low <= float(text) <= high:
            return text
    return repr(float(value))
