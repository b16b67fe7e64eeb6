"""Constrained optimization of a plan: batched gradient ascent, then a quasi-Newton polish."""

from __future__ import annotations

import numpy as np

from ..criteria import CRITERIA, Criterion
from ..errors import ArmcalError
from ..models import FitModel
from ..progress import ProgressCallback, share
from .ascent import adam_ascent, penalty_weight, to_q, to_u, view_penalty
from .plans import feasible_poses, random_plan

__all__ = [
    "RESTORE_MARGIN",
    "optimize_plan",
    "restore_view",
]


def _criterion_value_and_gradient(
    model: FitModel, q: np.ndarray, criterion: Criterion
) -> tuple[np.ndarray, np.ndarray]:
    """``log efficiency`` ``(...)`` of plans ``q`` ``(..., m, n)`` and its gradient in ``q``.

    On the model's normalized information
    (:meth:`~armcal.models.interface.FitModel.plan_information`): the paper's
    ``Fs`` for its model, the weighted information over the free parameters
    otherwise.
    """
    crit = criterion
    info = model.plan_information(q)
    m, p = q.shape[-2] * info.rows_per_pose, model.n_free  # rows: every target of every pose
    fs = info.information()
    sign, logdet = np.linalg.slogdet(fs)
    singular = (sign <= 0) | (logdet < -40.0 * p)
    fs = np.where(singular[..., None, None], fs + 1e-6 * np.eye(p), fs)
    value = np.log(np.clip(crit.efficiency(fs), 1e-300, None))
    phi = crit.log_gradient(fs) / m
    return value, info.gradient(phi)


def optimize_plan(
    model: FitModel,
    m: int,
    *,
    criterion: str | Criterion = "D",
    rng: np.random.Generator | int | None = None,
    starts: int | None = None,
    steps: int | None = None,
    polish: int = 3,
    initial: np.ndarray | None = None,
    progress: ProgressCallback | None = None,
) -> np.ndarray:
    """Maximize a criterion over the ``m x n`` joint angles within the limits and region.

    Parameters
    ----------
    model : FitModel
    m : int
        Number of poses.
    criterion : {"D", "A", "E"} or Criterion
        Key of :data:`armcal.criteria.CRITERIA`, or a criterion made for the task
        (:func:`armcal.doe.task.task_criterion`).
    rng : numpy.random.Generator or int or None
        Seeds the random starts; the same seed gives the same plan.
    starts : int, optional
        Random starting plans, optimized together (batched); default the model's
        :attr:`~armcal.models.interface.FitModel.design_effort`.
    steps : int, optional
        Adam iterations of the batched ascent (default likewise).
    polish : int
        Best starts polished by a quasi-Newton solver with exact bounds
        (L-BFGS-B, or SLSQP with the region constraints).
    initial : ndarray, shape (k, m, n), optional
        Extra starting plans (e.g. an analytic plan that breaks a constraint).
    progress : callable, optional
        ``progress(done, total)`` as the ascent and the polish advance.

    Returns
    -------
    ndarray, shape (m, n)
        The best feasible plan found (rad).

    Notes
    -----
    The ascent works in ``u`` with ``q = c + h sin u`` (``c, h`` the middle and
    half-width of each joint's range), so every iterate is inside the limits; the
    region enters as a quadratic penalty whose weight grows during the ascent.
    The gradient of ``log efficiency`` is analytic: with ``Phi = d log eff / dF``,
    ``d/dtheta_ij = 2 <J_i Phi, dJ_i/dtheta_ij>`` and ``dJ/dtheta`` just turns the
    two columns of link ``j`` by 90 degrees.
    """
    if isinstance(criterion, str):
        if criterion not in CRITERIA:
            raise ArmcalError(
                f"unknown criterion {criterion!r}; choose one of {', '.join(CRITERIA)}"
            )
        criterion = CRITERIA[criterion]
    rng = np.random.default_rng(rng)
    effort = model.design_effort
    starts = effort.starts if starts is None else starts
    steps = effort.steps if steps is None else steps
    n = model.n_joints
    viewed = model.has_view
    q0 = np.stack([random_plan(model, m, rng=rng) for _ in range(starts)])
    if viewed:
        q0[:, :, :] = feasible_poses(model, starts * m, rng=rng).reshape(starts, m, n)
    if initial is not None:
        q0 = np.concatenate([np.asarray(initial, dtype=float).reshape(-1, m, n), q0])

    def objective(u: np.ndarray, step: int):
        q, dq_du = to_q(model, u)
        value, grad = _criterion_value_and_gradient(model, q, criterion)
        penalty, grad_pen = view_penalty(model, q)
        weight = penalty_weight(model, step / steps)
        return value - weight * penalty, (grad - weight * grad_pen) * dq_du

    # The ascent's last value is the score at its end, with the penalty's full weight.
    u, score = adam_ascent(
        objective,
        to_u(model, q0),
        steps=steps,
        learning_rate=0.05,
        progress=share(progress, 0.0, 0.5),
    )
    q_final, _ = to_q(model, u)
    order = np.argsort(-score, kind="stable")
    best_q, best_value = None, -np.inf
    chosen = order[:polish]
    for rank, index in enumerate(chosen):
        part = share(
            progress, 0.5 + 0.5 * rank / len(chosen), 0.5 + 0.5 * (rank + 1) / len(chosen)
        )
        q = _polish(model, q_final[index], criterion, viewed, effort.polish, part)
        if viewed and not np.all(model.feasible(q)):  # SLSQP stopped outside: step back in
            q = restore_view(model, q)
        if not np.all(model.feasible(q)):
            continue
        v = float(_criterion_value_and_gradient(model, q, criterion)[0])
        if v > best_value + 1e-12:
            best_q, best_value = q, v
    if best_q is None:
        raise ArmcalError(
            f"the optimizer found no {m}-pose plan of {model.name} with every pose inside the "
            "measurement region; widen the region or the joint limits"
        )
    return best_q


#: Margin (in the constraints' units, mm) by which :func:`restore_view` steps inside.
RESTORE_MARGIN = 1e-4


def restore_view(model: FitModel, q: np.ndarray, *, iterations: int = 30) -> np.ndarray:
    """Poses ``(m, n)`` moved back inside the view by the least joint change: Gauss-Newton
    on each pose's violated constraints (the minimum-norm step of their linearization,
    Fletcher 1987, 12.3), within the limits.  Poses already inside stay as they are."""
    lower, upper = model.joint_limits[:, 0], model.joint_limits[:, 1]
    q = np.array(q, dtype=float)
    for _ in range(iterations):
        found = model.view_constraints(q)
        if found is None:
            return q
        g, dg = found  # (m, k), (m, k, n)
        active = g < RESTORE_MARGIN
        if not active.any():
            break
        rows = np.where(active[..., None], dg, 0.0)
        need = np.where(active, 2 * RESTORE_MARGIN - g, 0.0)
        step = np.linalg.pinv(rows, rcond=1e-10) @ need[..., None]  # (m, n, 1)
        q = np.clip(q + step[..., 0], lower, upper)
    return q


def _polish(
    model: FitModel,
    q: np.ndarray,
    criterion: Criterion,
    viewed: bool,
    iterations: int,
    progress: ProgressCallback | None,
) -> np.ndarray:
    """Local refinement of one plan with exact bounds (and exact view constraints)."""
    from scipy.optimize import Bounds, minimize  # ~0.3 s to import: keep it off `import armcal`

    m, n = q.shape
    lower, upper = np.tile(model.joint_limits[:, 0], m), np.tile(model.joint_limits[:, 1], m)
    bounds = Bounds(lower, upper)

    evaluations = 0

    def negative(x: np.ndarray):
        nonlocal evaluations
        evaluations += 1
        if progress is not None and evaluations % 10 == 0:  # about one per iteration
            progress(min(evaluations, iterations), iterations)
        value, grad = _criterion_value_and_gradient(model, x.reshape(m, n), criterion)
        return -float(value), -grad.ravel()

    x0 = np.clip(q.ravel(), lower, upper)
    if not viewed:
        result = minimize(
            negative,
            x0,
            jac=True,
            method="L-BFGS-B",
            bounds=bounds,
            options={"maxiter": iterations, "ftol": 1e-15, "gtol": 1e-10},
        )
        return result.x.reshape(m, n)
    margin = 1e-6  # mm inside the view, so that round-off never puts a point outside

    def constraints(x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        values = model.view_constraints(x.reshape(m, n))
        assert values is not None
        return values

    def region_values(x: np.ndarray) -> np.ndarray:
        return constraints(x)[0].ravel() - margin

    def region_jacobian(x: np.ndarray) -> np.ndarray:
        dg = constraints(x)[1]  # (m, k, n): pose i only moves g_i
        k = dg.shape[1]
        jac = np.zeros((m, k, m, n))
        jac[np.arange(m), :, np.arange(m), :] = dg
        return jac.reshape(m * k, m * n)

    result = minimize(
        negative,
        x0,
        jac=True,
        method="SLSQP",
        bounds=bounds,
        constraints=[{"type": "ineq", "fun": region_values, "jac": region_jacobian}],
        options={"maxiter": 300, "ftol": 1e-12},
    )
    return np.clip(result.x, lower, upper).reshape(m, n)
