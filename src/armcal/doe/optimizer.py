"""Constrained optimization of a plan: batched gradient ascent, then a quasi-Newton polish."""

from __future__ import annotations

import numpy as np

from ..criteria import CRITERIA, weighted_information
from ..errors import ArmcalError
from ..models import PlanarArm, every_target, forward_kinematics, joint_jacobian
from .model import information_gradient, pose_model
from .model import q_from_theta_gradient as _q_from_theta_gradient
from .plans import feasible, feasible_poses, random_plan

__all__ = [
    "optimize_plan",
]


def _criterion_value_and_gradient(
    arm: PlanarArm, q: np.ndarray, criterion: str
) -> tuple[np.ndarray, np.ndarray]:
    """``log efficiency`` ``(...)`` of plans ``q`` ``(..., m, n)`` and its gradient in ``q``.

    On the model's information (:mod:`armcal.doe.model`): the paper's
    normalized ``Fs`` for the standard model, the weighted information over the
    free parameters otherwise.
    """
    crit = CRITERIA[criterion]
    model = pose_model(arm, q)
    m, p = model.columns.shape[-2], arm.n_free  # rows: every target of every pose
    fs = weighted_information(model.columns, np.full(model.columns.shape[:-1], 1.0 / m))
    sign, logdet = np.linalg.slogdet(fs)
    singular = (sign <= 0) | (logdet < -40.0 * p)
    fs = np.where(singular[..., None, None], fs + 1e-6 * np.eye(p), fs)
    value = np.log(np.clip(crit.efficiency(fs), 1e-300, None))
    phi = crit.log_gradient(fs) / m
    return value, information_gradient(arm, model, phi)


def _region_constraints(arm: PlanarArm, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Region constraint values ``g (..., m, k)`` (>= 0 inside) and ``dg/dq (..., m, k, n)``."""
    region = arm.region
    assert region is not None, "callers check arm.region first"
    if arm.n_target_links > 1:
        return _targets_region_constraints(arm, q)
    unit = np.exp(1j * arm.link_angles(q))
    tip = np.sum(arm.link_lengths * unit, axis=-1)
    g, dg = region.constraints(np.stack([tip.real, tip.imag], axis=-1))  # dg (..., m, k, 2)
    d_tip = 1j * arm.link_lengths * unit  # d tip / d theta_j, complex (..., m, n)
    grad_theta = dg[..., :1] * d_tip.real[..., None, :] + dg[..., 1:] * d_tip.imag[..., None, :]
    return g, _q_from_theta_gradient(arm, grad_theta)


def _targets_region_constraints(arm: PlanarArm, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """:func:`_region_constraints` with several targets: every target's point inside."""
    assert arm.region is not None
    rows, target = every_target(arm, q)
    tip = forward_kinematics(arm, rows, target=target)
    g, dg = arm.region.constraints(tip)  # (..., m T, k), (..., m T, k, 2)
    dg_dq = dg @ joint_jacobian(arm, rows, target=target)  # (..., m T, k, n)
    count, n = arm.n_target_links, arm.n_joints
    shape = (*q.shape[:-1], count * g.shape[-1])
    return g.reshape(shape), dg_dq.reshape(*shape, n)


def _region_penalty(arm: PlanarArm, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``sum min(0, g)^2`` over poses and constraints ``(...)`` and its gradient in ``q``."""
    if arm.region is None:
        return np.zeros(q.shape[:-2]), np.zeros_like(q)
    g, dg = _region_constraints(arm, q)
    violation = np.minimum(g, 0.0)
    grad = np.einsum("...k,...kn->...n", 2.0 * violation, dg)
    return np.sum(violation**2, axis=(-2, -1)), grad


def _to_u(arm: PlanarArm, q: np.ndarray) -> np.ndarray:
    """Unconstrained variables ``u`` with ``q = c + h sin u`` (``c, h``: middle, half-width)."""
    lo, hi = arm.joint_limits[:, 0], arm.joint_limits[:, 1]
    return np.arcsin(np.clip((q - (lo + hi) / 2) / ((hi - lo) / 2), -1.0, 1.0))


def _to_q(arm: PlanarArm, u: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Joint angles within the limits and ``dq/du`` for the variables of :func:`_to_u`."""
    lo, hi = arm.joint_limits[:, 0], arm.joint_limits[:, 1]
    half = (hi - lo) / 2
    return (lo + hi) / 2 + half * np.sin(u), half * np.cos(u)


def _adam_ascent(
    objective, u: np.ndarray, *, steps: int, learning_rate: float
) -> tuple[np.ndarray, np.ndarray]:
    """Batched Adam ascent of ``objective(u, step) -> (value (S,), grad like u)``."""
    first = np.zeros_like(u)
    second = np.zeros_like(u)
    beta1, beta2, eps = 0.9, 0.999, 1e-12
    for step in range(1, steps + 1):
        _, grad = objective(u, step)
        first = beta1 * first + (1 - beta1) * grad
        second = beta2 * second + (1 - beta2) * grad**2
        lr = learning_rate * (0.05 + 0.95 * (1 - step / steps))  # anneal to refine
        u = u + lr * (first / (1 - beta1**step)) / (np.sqrt(second / (1 - beta2**step)) + eps)
    value, _ = objective(u, steps)
    return u, value


def _penalty_weight(arm: PlanarArm, progress: float) -> float:
    reach = float(np.sum(arm.link_lengths))
    return 10.0 ** (1.0 + 5.0 * progress) / reach**2


def optimize_plan(
    arm: PlanarArm,
    m: int,
    *,
    criterion: str = "D",
    rng: np.random.Generator | int | None = None,
    starts: int = 48,
    steps: int = 400,
    polish: int = 3,
    initial: np.ndarray | None = None,
) -> np.ndarray:
    """Maximize a criterion over the ``m x n`` joint angles within the limits and region.

    Parameters
    ----------
    arm : PlanarArm
    m : int
        Number of poses.
    criterion : {"D", "A", "E"}
        Key of :data:`armcal.criteria.CRITERIA`.
    rng : numpy.random.Generator or int or None
        Seeds the random starts; the same seed gives the same plan.
    starts : int
        Random starting plans, optimized together (batched).
    steps : int
        Adam iterations of the batched ascent.
    polish : int
        Best starts polished by a quasi-Newton solver with exact bounds
        (L-BFGS-B, or SLSQP with the region constraints).
    initial : ndarray, shape (k, m, n), optional
        Extra starting plans (e.g. an analytic plan that breaks a constraint).

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
    if criterion not in CRITERIA:
        raise ArmcalError(f"unknown criterion {criterion!r}; choose one of {', '.join(CRITERIA)}")
    rng = np.random.default_rng(rng)
    q0 = np.stack([random_plan(arm, m, rng=rng) for _ in range(starts)])
    if arm.region is not None:
        q0[:, :, :] = feasible_poses(arm, starts * m, rng=rng).reshape(starts, m, arm.n_joints)
    if initial is not None:
        q0 = np.concatenate([np.asarray(initial, dtype=float).reshape(-1, m, arm.n_joints), q0])

    def objective(u: np.ndarray, step: int):
        q, dq_du = _to_q(arm, u)
        value, grad = _criterion_value_and_gradient(arm, q, criterion)
        penalty, grad_pen = _region_penalty(arm, q)
        weight = _penalty_weight(arm, step / steps)
        return value - weight * penalty, (grad - weight * grad_pen) * dq_du

    u, _ = _adam_ascent(objective, _to_u(arm, q0), steps=steps, learning_rate=0.05)
    q_final, _ = _to_q(arm, u)
    value, _ = _criterion_value_and_gradient(arm, q_final, criterion)
    penalty, _ = _region_penalty(arm, q_final)
    order = np.argsort(-(value - _penalty_weight(arm, 1.0) * penalty), kind="stable")
    best_q, best_value = None, -np.inf
    for index in order[:polish]:
        q = _polish(arm, q_final[index], criterion)
        if not np.all(feasible(arm, q)):
            continue
        v = float(_criterion_value_and_gradient(arm, q, criterion)[0])
        if v > best_value + 1e-12:
            best_q, best_value = q, v
    if best_q is None:
        raise ArmcalError(
            f"the optimizer found no {m}-pose plan of {arm.name} with every pose inside the "
            "measurement region; widen the region or the joint limits"
        )
    return best_q


def _polish(arm: PlanarArm, q: np.ndarray, criterion: str) -> np.ndarray:
    """Local refinement of one plan with exact bounds (and exact region constraints)."""
    from scipy.optimize import Bounds, minimize  # ~0.3 s to import: keep it off `import armcal`

    m, n = q.shape
    lower, upper = np.tile(arm.joint_limits[:, 0], m), np.tile(arm.joint_limits[:, 1], m)
    bounds = Bounds(lower, upper)

    def negative(x: np.ndarray):
        value, grad = _criterion_value_and_gradient(arm, x.reshape(m, n), criterion)
        return -float(value), -grad.ravel()

    x0 = np.clip(q.ravel(), lower, upper)
    if arm.region is None:
        result = minimize(
            negative,
            x0,
            jac=True,
            method="L-BFGS-B",
            bounds=bounds,
            options={"maxiter": 500, "ftol": 1e-15, "gtol": 1e-10},
        )
        return result.x.reshape(m, n)
    region = arm.region
    margin = 1e-6  # mm inside the region, so that round-off never puts a tip outside

    def region_values(x: np.ndarray) -> np.ndarray:
        if arm.n_target_links > 1:
            g, _ = _region_constraints(arm, x.reshape(m, n))
        else:
            g, _ = region.constraints(forward_kinematics(arm, x.reshape(m, n)))
        return g.ravel() - margin

    def region_jacobian(x: np.ndarray) -> np.ndarray:
        _, dg = _region_constraints(arm, x.reshape(m, n))  # (m, k, n): pose i only moves g_i
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
