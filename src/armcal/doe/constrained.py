"""Ascent of a function of poses over the poses that meet an instrument (the certificate's).

Two kinds of instrument constraint, two ascents; both keep every iterate on the
constrained set and take a step only where the function grows:

* :func:`projected_ascent` -- poses on a thin set (a touch of a plane, a seating in a
  point, a distance within a ballbar's range): a step along the gradient projected
  onto the constraint's tangent, taken back onto the instrument;
* :func:`bounded_ascent` -- poses within a region with an inside (a camera's image
  less its margin, every corner of the board in it): a step along the gradient
  projected onto the region's linearization, its bounds near and far at once
  (:meth:`~armcal.models.interface.FitModel.view_constraints`), a least-distance
  problem (:func:`~armcal.numerics.nearest_in`).  A step that follows one bound leaves another: the
  tangent of a single probe stalled at the image's corners, where several corners
  of the board touch its edges (a camera's variance function climbed from 58.4 to
  65.5 on restarts that found more room).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from ..models import FitModel
from ..numerics import nearest_in

__all__ = [
    "PROJECTED_SMALLEST",
    "PROJECTED_STEP",
    "TANGENT_PROBE",
    "bounded_ascent",
    "projected_ascent",
]

#: ``objective(q, gradient) -> (value (k,), gradient (k, n) or None)`` of poses ``q``
#: ``(k, n)``: the gradient only where asked (a trial's value decides whether it is kept).
Objective = Callable[[np.ndarray, bool], tuple[np.ndarray, np.ndarray | None]]

#: The first joint step of a constrained ascent (rad), and the smallest: a pose whose step
#: has shrunk below it is at its local maximum to round-off of ``d`` (a step of 1e-9 rad
#: changes ``d`` by about 1e-18 of its scale near a maximum).
PROJECTED_STEP, PROJECTED_SMALLEST = 0.05, 1e-9

#: How far (rad) a pose is moved along the gradient to find the constraint's tangent: the
#: meeting's second-order error (the curvature times this squared, ~1e-12) stays below
#: the round-off of the difference (its floor 1e-13 rad over this, ~1e-7 relative).
TANGENT_PROBE = 1e-6

#: A step's growth after a success and its shrinking after a failure, pose by pose.
GROW, SHRINK = 1.5, 0.4


def projected_ascent(
    model: FitModel, objective: Objective, starts: np.ndarray, *, steps: int
) -> np.ndarray:
    """Ascent of ``objective`` over the poses that meet the instrument (a touch, a seating, a
    distance within range): a step along its gradient projected onto the
    constraint's tangent, taken back onto the instrument by the smallest joint change
    (:meth:`~armcal.models.interface.FitModel.meeting_poses`), kept where the value
    grows and the pose meets it and is feasible; the step grows by :data:`GROW` after a
    success and shrinks by :data:`SHRINK` after a failure, pose by pose, until every
    step is below :data:`PROJECTED_SMALLEST`.  Every pose returned meets the instrument
    (the starts do).

    The tangent is the meeting of a pose moved :data:`TANGENT_PROBE` rad along the
    gradient, divided by that: the gradient less its part across the constraint, to
    first order.  Stepping along the raw gradient would stall short of a maximum, where
    the gradient stands nearly across the constraint: what the step gains along it is
    then less than what its curvature costs on the way back."""

    def direction(q: np.ndarray, unit: np.ndarray, size: np.ndarray) -> np.ndarray:
        probe, probed = model.meeting_poses(q + TANGENT_PROBE * unit)
        tangent = np.where(probed[:, None], (probe - q) / TANGENT_PROBE, unit)
        return size[:, None] * _unit(tangent)

    return _step_ascent(model, objective, starts, direction, steps=steps)


def bounded_ascent(
    model: FitModel, objective: Objective, starts: np.ndarray, *, steps: int
) -> np.ndarray:
    """Ascent of ``objective`` over the poses within the instrument's view (a region with
    an inside: :meth:`~armcal.models.interface.FitModel.view_constraints` ``g >= 0``)
    and the joint limits: the step ``s`` along the unit gradient, moved to the nearest
    step ``delta`` that keeps the linearized constraints, ``g + dg . delta >= 0`` and
    ``lower <= q + delta <= upper`` (:func:`~armcal.numerics.nearest_in`), then
    taken back onto the view by the smallest joint change where the curvature left a
    corner outside (:meth:`~armcal.models.interface.FitModel.meeting_poses`); kept
    where the value grows and the pose meets the instrument, the steps' sizes as in
    :func:`projected_ascent`.  At a maximum on the view's edges the projected step
    vanishes and the size shrinks to :data:`PROJECTED_SMALLEST`."""
    lower, upper = model.joint_limits[:, 0], model.joint_limits[:, 1]

    def nearest(q: np.ndarray, v: np.ndarray) -> np.ndarray:
        """The steps nearest ``v`` ``(k, n)`` that keep the view's and the limits'
        linearizations at ``q`` (rows ``A delta >= b``)."""
        found = model.view_constraints(q[:, None, :])
        assert found is not None, "a bounded ascent needs the view's constraints"
        g, dg = found[0][:, 0], found[1][:, 0]  # (k, c), (k, c, n)
        eye = np.eye(q.shape[1])
        step = np.array(v, dtype=float)
        for i in range(q.shape[0]):
            a = np.concatenate([dg[i], eye, -eye])
            b = np.concatenate([-g[i], lower - q[i], q[i] - upper])
            step[i] = nearest_in(a, b, step[i])
        return step

    def direction(q: np.ndarray, unit: np.ndarray, size: np.ndarray) -> np.ndarray:
        return nearest(q, size[:, None] * unit)

    def settle(q: np.ndarray) -> np.ndarray:
        """Trials the view's curvature left a little outside, moved in by the nearest
        steps of its linearization (an active set of every bound at once: the meeting's
        Newton steps on the corners outside push those on the edge out, and crawl)."""
        for _ in range(SETTLE_STEPS):
            q = q + nearest(q, np.zeros_like(q))
        return q

    return _step_ascent(model, objective, starts, direction, steps=steps, settle=settle)


#: Nearest-step corrections of a bounded ascent's trial: the linearization's error falls
#: quadratically, from a step's curvature (~1e-3 px) to round-off in two.
SETTLE_STEPS = 2


def _step_ascent(
    model: FitModel,
    objective: Objective,
    starts: np.ndarray,
    direction: Callable[[np.ndarray, np.ndarray, np.ndarray], np.ndarray],
    *,
    steps: int,
    settle: Callable[[np.ndarray], np.ndarray] | None = None,
) -> np.ndarray:
    """The ascent both share: ``direction(q, unit gradient, size) -> step`` of the live
    poses, the trial moved by ``settle`` where given and taken back onto the instrument,
    within the limits, kept where it meets it and the value grows; the trials' values
    first, the gradient only of those kept."""
    lower, upper = model.joint_limits[:, 0], model.joint_limits[:, 1]
    q = np.array(starts, dtype=float)
    value, grad = _with_gradient(objective, q)
    size = np.full(q.shape[0], PROJECTED_STEP)
    for _ in range(steps):
        live = np.flatnonzero(size >= PROJECTED_SMALLEST)
        if not live.size:
            break
        step = direction(q[live], _unit(grad[live]), size[live])
        trial = np.clip(q[live] + step, lower, upper)
        if settle is not None:
            trial = np.clip(settle(trial), lower, upper)
        trial, met = model.meeting_poses(trial)
        trial_value, _ = objective(trial, False)
        better = met & model.feasible(trial) & (trial_value > value[live])
        kept = live[better]
        if kept.size:
            q[kept], value[kept] = trial[better], trial_value[better]
            grad[kept] = _with_gradient(objective, q[kept])[1]
        size[live] = np.where(better, size[live] * GROW, size[live] * SHRINK)
    return q


def _with_gradient(objective: Objective, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    value, grad = objective(q, True)
    assert grad is not None
    return value, grad


def _unit(v: np.ndarray) -> np.ndarray:
    norm = np.linalg.norm(v, axis=-1, keepdims=True)
    return v / np.where(norm > 0, norm, 1.0)
