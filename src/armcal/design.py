"""Calibration plans: analytic optimal plans, constrained optimization, exchange, certificates.

A plan is an array of joint angles ``q`` of shape ``(m, n)`` in rad.  Plans are
judged by the criteria of :mod:`armcal.criteria` on the Hadamard-normalized
information matrix ``Fs`` (1 for the paper's orthogonal plans).

* :func:`orthogonal_plan` / :func:`analytic_plan` -- plans meeting the paper's
  conditions (21) / Table I exactly, placed inside the joint limits and the
  measurement region when they can be;
* :func:`optimize_plan` -- many seeded starts of batched gradient ascent on the
  criterion (analytic gradient), joint limits by a smooth change of variables,
  the region by a penalty; the best starts are polished by L-BFGS-B (or SLSQP
  with the exact region constraints);
* :func:`exchange_plan` -- modified Fedorov exchange over a candidate set with
  rank-2 determinant updates;
* :func:`certify` -- a lower bound on the plan's D-efficiency relative to the
  best possible plan within the constraints (Kiefer-Wolfowitz equivalence theorem);
* :func:`design` -- all of the above behind one call (``method="auto"``).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

import numpy as np

from .arm import PlanarArm, forward_kinematics, link_angles, wrap_angle
from .criteria import (
    CRITERIA,
    d_efficiency,
    scaled_columns,
    scaled_information,
    weighted_information,
)
from .errors import ArmcalError

__all__ = [
    "METHODS",
    "Certificate",
    "Design",
    "analytic_plan",
    "certify",
    "design",
    "exchange_plan",
    "feasible",
    "feasible_poses",
    "optimize_plan",
    "orthogonal_plan",
    "random_plan",
]

Method = Literal["auto", "analytic", "optimize", "exchange"]
METHODS = ("auto", "analytic", "optimize", "exchange")


def orthogonal_plan(arm: PlanarArm, m: int, *, q1: float = 0.0) -> np.ndarray:
    """A plan that meets the paper's optimality conditions (21) / Table I exactly.

    Parameters
    ----------
    arm : PlanarArm
    m : int
        Number of poses; at least ``n`` (``n + 1`` with a base offset).
    q1 : float
        Angle of joint 1 (rad) for every pose when the base is not identified.

    Returns
    -------
    ndarray, shape (m, n)
        Joint angles in rad, wrapped into ``(-pi, pi]``.

    Notes
    -----
    Pose ``k = 0..m-1`` sets ``q_j = 2 pi k / m`` for ``j >= 2``, so
    ``theta_j - theta_i = (j - i) 2 pi k / m`` and
    ``sum_k exp(i (theta_j - theta_i)) = 0`` whenever ``0 < j - i < m``: the
    off-diagonal sums ``c_ij, s_ij`` of eq. (18) vanish and the information
    matrix is ``diag(m l_i^2, m)`` (Table II).  With a base offset the sums
    ``sum_k exp(i theta_j)`` must vanish too, so joint 1 also steps by
    ``2 pi k / m`` (then ``theta_j = 2 pi j k / m``, which needs ``m > n``).
    Joint limits and the measurement region are not considered here.

    Examples
    --------
    >>> np.degrees(orthogonal_plan(PlanarArm([2.0, 1.0]), 4)).round(9).tolist()
    [[0.0, 0.0], [0.0, 90.0], [0.0, 180.0], [0.0, -90.0]]
    """
    n = arm.n_joints
    min_poses = n + 1 if arm.base_offset else n
    if m < min_poses:
        raise ArmcalError(
            f"an orthogonal plan for {arm.name} needs at least {min_poses} poses, got {m}"
        )
    step = 2 * np.pi * np.arange(m) / m
    q = np.tile(step[:, None], (1, n))
    if not arm.base_offset:
        q[:, 0] = q1
    return wrap_angle(q)


def random_plan(
    arm: PlanarArm, m: int, rng: np.random.Generator | int | None = None
) -> np.ndarray:
    """``m`` poses drawn uniformly within the joint limits.

    Parameters
    ----------
    arm : PlanarArm
    m : int
        Number of poses.
    rng : numpy.random.Generator or int or None
        Random source or seed.

    Returns
    -------
    ndarray, shape (m, n)
        Joint angles in rad.

    Examples
    --------
    >>> random_plan(PlanarArm([1.0, 1.0, 1.0]), 5, rng=0).shape
    (5, 3)
    """
    rng = np.random.default_rng(rng)
    lo, hi = arm.joint_limits[:, 0], arm.joint_limits[:, 1]
    return rng.uniform(lo, hi, size=(m, arm.n_joints))


# --------------------------------------------------------------------------- feasibility


def feasible(arm: PlanarArm, q: np.ndarray, *, tol: float = 1e-9) -> np.ndarray:
    """Mask ``(..., m)`` of poses inside the joint limits and (if any) the measurement region."""
    ok = np.all(arm.within_limits(q, tol=tol), axis=-1)
    if arm.region is not None:
        ok &= arm.region.contains(forward_kinematics(arm, q), tol=tol)
    return ok


def feasible_poses(
    arm: PlanarArm, k: int, rng: np.random.Generator | int | None = None
) -> np.ndarray:
    """``k`` poses ``(k, n)`` uniform in the joint limits, restricted to the region.

    Raises
    ------
    ArmcalError
        If fewer than 1 in 10 000 random poses reach the measurement region.
    """
    rng = np.random.default_rng(rng)
    found: list[np.ndarray] = []
    count, drawn = 0, 0
    while count < k:
        batch = random_plan(arm, max(4 * k, 1000), rng)
        drawn += batch.shape[0]
        batch = batch[feasible(arm, batch)]
        found.append(batch)
        count += batch.shape[0]
        if count == 0 and drawn >= 10_000:
            raise ArmcalError(
                f"{arm.name}: no random pose within the joint limits puts the tip inside the "
                "measurement region; check the region and the limits"
            )
    return np.concatenate(found)[:k]


# --------------------------------------------------------------------------- analytic


def analytic_plan(arm: PlanarArm, m: int) -> np.ndarray:
    """An orthogonal plan (Table I) placed inside the joint limits and region, if one fits.

    The conditions are invariant to a common shift ``alpha`` of joints 2..n and,
    without a base offset, to the angle of joint 1 in each pose; with a base
    offset, to a common rotation of joint 1.  These freedoms are searched on a
    fine grid for the placement with the largest margin to the limits and region.

    Raises
    ------
    ArmcalError
        If no such placement keeps every pose within the limits and region (use
        :func:`optimize_plan` then).
    """
    base = orthogonal_plan(arm, m)
    n = arm.n_joints
    grid = np.linspace(-np.pi, np.pi, 721)[:-1]
    lo, hi = arm.joint_limits[:, 0], arm.joint_limits[:, 1]
    # Common shift of joints 2..n: margin of every candidate shift (grid, m, n-1).
    shifted = wrap_angle(base[None, :, 1:] + grid[:, None, None])
    margin = np.minimum(shifted - lo[1:], hi[1:] - shifted).min(axis=(1, 2), initial=np.inf)
    if margin.max() < 0:
        raise ArmcalError(
            f"no orthogonal {m}-pose plan fits the joint limits of {arm.name}: joints 2..{n} "
            f"would each need {m} angles spaced {360 / m:g} deg apart"
        )
    q = base.copy()
    q[:, 1:] = shifted[int(np.argmax(margin))]
    if arm.base_offset:
        rotated = wrap_angle(base[None, :, 0] + grid[:, None])  # (grid, m)
        candidates = np.repeat(q[None], grid.size, axis=0)
        candidates[:, :, 0] = rotated
        score = _placement_margin(arm, candidates).min(axis=1)
        if score.max() < 0:
            raise ArmcalError(
                f"no rotation of the orthogonal {m}-pose plan keeps every pose of {arm.name} "
                "inside the joint limits and measurement region"
            )
        return candidates[int(np.argmax(score))]
    # Joint 1 is free pose by pose: choose the angle with the largest margin.
    candidates = np.repeat(q[None], grid.size, axis=0)
    candidates[:, :, 0] = grid[:, None]
    score = _placement_margin(arm, candidates)  # (grid, m)
    best = np.argmax(score, axis=0)
    if np.any(score[best, np.arange(m)] < 0):
        raise ArmcalError(
            f"no angle of joint 1 puts every pose of the orthogonal {m}-pose plan of {arm.name} "
            "inside the measurement region"
        )
    q[:, 0] = grid[best]
    return q


def _placement_margin(arm: PlanarArm, q: np.ndarray) -> np.ndarray:
    """Smallest margin (rad for limits, mm for the region) of each pose ``(..., m)``."""
    lo, hi = arm.joint_limits[:, 0], arm.joint_limits[:, 1]
    margin = np.minimum(q - lo, hi - q).min(axis=-1)
    if arm.region is not None:
        g, _ = arm.region.constraints(forward_kinematics(arm, q))
        margin = np.minimum(margin, g.min(axis=-1))
    return margin


# --------------------------------------------------------------------------- gradients


def _theta_gradient(arm: PlanarArm, columns: np.ndarray, phi: np.ndarray) -> np.ndarray:
    """``d/dtheta_j <Phi, J_i^T J_i> = 2 <J_i Phi, dJ_i/dtheta_j>`` ``(..., m, n)``.

    The two columns of link ``j`` turn with ``theta_j`` (derivative ``i * column``);
    the base columns are constant.
    """
    n = arm.n_joints
    g = columns @ phi  # (..., m, p) complex, since phi is real
    t = np.real(g.conj() * 1j * columns)
    return 2.0 * (t[..., :n] + t[..., n : 2 * n])


def _q_from_theta_gradient(grad_theta: np.ndarray) -> np.ndarray:
    """theta_j = q_1 + ... + q_j, so d/dq_a = sum over j >= a of d/dtheta_j."""
    return np.cumsum(grad_theta[..., ::-1], axis=-1)[..., ::-1]


def _criterion_value_and_gradient(
    arm: PlanarArm, q: np.ndarray, criterion: str
) -> tuple[np.ndarray, np.ndarray]:
    """``log efficiency`` ``(...)`` of plans ``q`` ``(..., m, n)`` and its gradient in ``q``."""
    crit = CRITERIA[criterion]
    columns = scaled_columns(arm, q)
    m = q.shape[-2]
    fs = weighted_information(columns, np.full(q.shape[:-1], 1.0 / m))
    sign, logdet = np.linalg.slogdet(fs)
    singular = (sign <= 0) | (logdet < -40.0 * arm.n_params)
    fs = np.where(singular[..., None, None], fs + 1e-6 * np.eye(arm.n_params), fs)
    value = np.log(np.clip(crit.efficiency(fs), 1e-300, None))
    phi = crit.log_gradient(fs) / m
    return value, _q_from_theta_gradient(_theta_gradient(arm, columns, phi))


def _region_constraints(arm: PlanarArm, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Region constraint values ``g (..., m, k)`` (>= 0 inside) and ``dg/dq (..., m, k, n)``."""
    unit = np.exp(1j * link_angles(q))
    tip = np.sum(arm.link_lengths * unit, axis=-1)
    g, dg = arm.region.constraints(np.stack([tip.real, tip.imag], axis=-1))  # dg (..., m, k, 2)
    d_tip = 1j * arm.link_lengths * unit  # d tip / d theta_j, complex (..., m, n)
    grad_theta = dg[..., :1] * d_tip.real[..., None, :] + dg[..., 1:] * d_tip.imag[..., None, :]
    return g, _q_from_theta_gradient(grad_theta)


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


# --------------------------------------------------------------------------- optimizer


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
    q0 = np.stack([random_plan(arm, m, rng) for _ in range(starts)])
    if arm.region is not None:
        q0[:, :, :] = feasible_poses(arm, starts * m, rng).reshape(starts, m, arm.n_joints)
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
    margin = 1e-6  # mm inside the region, so that round-off never puts a tip outside

    def region_values(x: np.ndarray) -> np.ndarray:
        g, _ = arm.region.constraints(forward_kinematics(arm, x.reshape(m, n)))
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


# --------------------------------------------------------------------------- exchange


def _blocks(arm: PlanarArm, q: np.ndarray) -> np.ndarray:
    """Real scaled Jacobian blocks ``(k, 2, p)`` of poses ``q`` ``(k, n)``."""
    columns = scaled_columns(arm, q)
    return np.stack([columns.real, columns.imag], axis=-2)


def exchange_plan(
    arm: PlanarArm,
    m: int,
    candidates: np.ndarray,
    *,
    start: np.ndarray | None = None,
    rng: np.random.Generator | int | None = None,
    max_swaps: int = 1000,
) -> np.ndarray:
    """Modified Fedorov exchange for the D-criterion over a candidate set.

    Parameters
    ----------
    arm : PlanarArm
    m : int
        Number of poses.
    candidates : ndarray, shape (N, n)
        Poses the plan may use (rad), e.g. poses the robot can really reach.
    start : ndarray, shape (m, n), optional
        Starting plan (its poses join the candidates); random candidates otherwise.
    rng : numpy.random.Generator or int or None
        Seeds the random start.
    max_swaps : int
        Cap on the number of exchanges.

    Returns
    -------
    ndarray, shape (m, n)

    Notes
    -----
    Each step makes the best swap of a plan pose ``i`` for a candidate ``x``
    over all ``(i, x)`` pairs at once.  With ``F_i, F_x`` the ``2 x p`` Jacobian
    blocks, ``M' = M - F_i^T F_i + F_x^T F_x`` and

        det M' / det M = det(I_4 + C U^T M^-1 U),  U = [F_x^T, F_i^T],  C = diag(I, -I),

    the rank-2 update formula ``det(M + F^T F) = det M det(I_2 + F M^-1 F^T)``
    applied twice; every ratio is a 4 x 4 determinant, computed for all pairs in
    one vectorized call.  Poses may repeat (an exact design may replicate a point).
    """
    rng = np.random.default_rng(rng)
    candidates = np.asarray(candidates, dtype=float)
    if start is None:
        index = rng.choice(candidates.shape[0], size=m, replace=candidates.shape[0] < m)
    else:
        candidates = np.concatenate([np.asarray(start, dtype=float), candidates])
        index = np.arange(m)
    blocks = _blocks(arm, candidates)  # (N, 2, p)
    eye2, p = np.eye(2), arm.n_params
    ridge = 1e-10 * np.eye(p)
    for _ in range(max_swaps):
        design_blocks = blocks[index]  # (m, 2, p)
        info = np.einsum("iap,iaq->pq", design_blocks, design_blocks)
        m_inv = np.linalg.inv(info + ridge)
        g = blocks @ m_inv  # (N, 2, p)
        a_xx = g @ np.swapaxes(blocks, -1, -2)  # (N, 2, 2)
        a_xi = np.einsum("xap,ibp->xiab", g, design_blocks)  # (N, m, 2, 2)
        a_ii = design_blocks @ m_inv @ np.swapaxes(design_blocks, -1, -2)  # (m, 2, 2)
        top = np.concatenate([np.broadcast_to(eye2 + a_xx[:, None], a_xi.shape), a_xi], axis=-1)
        bottom = np.concatenate(
            [-np.swapaxes(a_xi, -1, -2), np.broadcast_to(eye2 - a_ii, a_xi.shape)], axis=-1
        )
        ratio = np.linalg.det(np.concatenate([top, bottom], axis=-2))  # (N, m)
        x, i = np.unravel_index(int(np.argmax(ratio)), ratio.shape)
        if ratio[x, i] <= 1.0 + 1e-12:
            break
        index = index.copy()
        index[i] = x
    return candidates[index]


# --------------------------------------------------------------------------- certificate


@dataclass(frozen=True, eq=False)
class Certificate:
    """A lower bound on a plan's D-efficiency relative to the best possible plan.

    Attributes
    ----------
    certified_d_efficiency : float
        ``(det M_plan / det M*)^(1/p)`` is at least this for every ``M*`` reachable
        within the joint limits and region, exact plans and weighted designs alike.
    plan_only_bound : float
        The looser bound ``exp(1 - max_x d(x, plan) / p)``.
    reference_d_efficiency : float
        D-efficiency (Hadamard-normalized) of the best weighted design found.
    max_variance : float
        ``max_x d(x, xi*)`` over the feasible poses searched (``>= p``; ``= p`` at
        the optimum).
    support : ndarray, shape (k, n)
        Support poses (rad) of the best weighted design ``xi*``.
    weights : ndarray, shape (k,)
        Their weights (sum 1).
    """

    certified_d_efficiency: float
    plan_only_bound: float
    reference_d_efficiency: float
    max_variance: float
    support: np.ndarray
    weights: np.ndarray


def _variance_function(arm: PlanarArm, q: np.ndarray, m_inv: np.ndarray):
    """``d(x) = tr(M^-1 I(x))`` ``(k,)`` of poses ``q`` ``(k, n)`` and its gradient ``(k, n)``."""
    columns = scaled_columns(arm, q)[:, None, :]  # one pose per "plan"
    value = np.einsum("kma,ab,kmb->k", columns.conj(), m_inv, columns).real
    grad = _q_from_theta_gradient(_theta_gradient(arm, columns, m_inv))[:, 0, :]
    return value, grad


def _maximize_variance(
    arm: PlanarArm, m_inv: np.ndarray, starts: np.ndarray, *, steps: int = 150
) -> np.ndarray:
    """Batched ascent of ``d(x)`` from ``starts (k, n)`` within the limits (near the region)."""

    def objective(u: np.ndarray, step: int):
        q, dq_du = _to_q(arm, u)
        value, grad = _variance_function(arm, q, m_inv)
        penalty, grad_pen = _region_penalty(arm, q[:, None, :])
        weight = _penalty_weight(arm, step / steps) * 1e3
        return value - weight * penalty, (grad - weight * grad_pen[:, 0]) * dq_du

    u, _ = _adam_ascent(objective, _to_u(arm, starts), steps=steps, learning_rate=0.05)
    return _to_q(arm, u)[0]


def _corner_poses(arm: PlanarArm, rng: np.random.Generator) -> np.ndarray:
    """Poses with every joint at a limit (joint 1 random when the base is not identified)."""
    n = arm.n_joints
    if n > 10:
        return np.empty((0, n))
    grid = np.array(np.meshgrid(*[[0, 1]] * n, indexing="ij")).reshape(n, -1).T
    corners = arm.joint_limits[np.arange(n), grid]
    if not arm.base_offset:
        corners[:, 0] = rng.uniform(arm.joint_limits[0, 0], arm.joint_limits[0, 1], len(corners))
    return corners[feasible(arm, corners[:, None, :])[:, 0]]


def _weights_multiplicative(blocks: np.ndarray, weights: np.ndarray, iterations: int):
    """Multiplicative algorithm for D-optimal weights (Titterington 1976; Silvey et al. 1978)."""
    p = blocks.shape[-1]
    info = np.einsum("xap,xaq->xpq", blocks, blocks)  # (N, p, p)
    for _ in range(iterations):
        m_inv = np.linalg.inv(np.einsum("x,xpq->pq", weights, info))
        d = np.einsum("xap,pq,xaq->x", blocks, m_inv, blocks)
        weights = weights * d / p
        weights /= weights.sum()
    return weights


def certify(
    arm: PlanarArm,
    q: np.ndarray,
    *,
    rng: np.random.Generator | int | None = None,
    candidates: int = 3000,
    rounds: int = 4,
    search: int = 20000,
) -> Certificate:
    """Certify a plan's D-efficiency against the best possible plan within the constraints.

    Parameters
    ----------
    arm : PlanarArm
    q : ndarray, shape (m, n)
        The plan (rad); must identify every parameter.
    rng : numpy.random.Generator or int or None
        Seeds the random candidates and searches.
    candidates : int
        Random feasible poses for the weighted (approximate) design.
    rounds : int
        Rounds of adding the maximizer of the variance function to the candidates.
    search : int
        Random feasible poses from which the final maximization of ``d`` starts.

    Returns
    -------
    Certificate

    Notes
    -----
    For a weighted design ``xi`` with normalized information ``M(xi)`` and
    ``d(x, xi) = tr(M(xi)^-1 I(x))``, the Kiefer-Wolfowitz equivalence theorem
    gives ``max_x d(x, xi) >= p`` and, by concavity of ``log det``,
    ``log det M* <= log det M(xi) + max_x d(x, xi) - p`` for the best design ``M*``
    over the feasible poses.  Hence the plan's efficiency relative to ``M*`` is at
    least ``(det M_plan / det M(xi*))^(1/p) exp(1 - max_x d(x, xi*) / p)``.
    ``xi*`` comes from the multiplicative algorithm on random feasible poses,
    corners and the plan's own poses, refined by adding the maximizers of ``d``.
    The final ``max_x d`` is a multistart ascent from the best of ``search``
    random feasible poses (plus the support); ascent iterates that stray slightly
    outside the region only raise the maximum, which keeps the bound safe.  The
    Hadamard bound ``det Fs <= 1`` is a certificate too, so the result is never
    below the plan's own D-efficiency.
    """
    rng = np.random.default_rng(rng)
    q = np.asarray(q, dtype=float)
    p = arm.n_params
    if float(d_efficiency(arm, q)) >= 1.0 - 1e-12:
        # Fs = I: the Hadamard bound is attained, and d(x) = tr(Is(x)) = p at every pose.
        return Certificate(1.0, 1.0, 1.0, float(p), q, np.full(q.shape[0], 1.0 / q.shape[0]))
    pool = np.concatenate([q, _corner_poses(arm, rng), feasible_poses(arm, candidates, rng)])
    weights = np.full(pool.shape[0], 1.0 / pool.shape[0])
    for _ in range(rounds):
        weights = _weights_multiplicative(_blocks(arm, pool), weights, 300)
        m_inv = np.linalg.inv(weighted_information(scaled_columns(arm, pool), weights))
        d, _ = _variance_function(arm, pool, m_inv)
        top = pool[np.argsort(-d)[: 4 * p]]
        found = _maximize_variance(arm, m_inv, top)
        found = found[feasible(arm, found[:, None, :])[:, 0]]
        keep = weights > 1e-6 / pool.shape[0]
        pool = np.concatenate([pool[keep], found])
        weights = np.concatenate([weights[keep], np.full(found.shape[0], 1e-3 / pool.shape[0])])
        weights /= weights.sum()
    weights = _weights_multiplicative(_blocks(arm, pool), weights, 1000)
    support_mask = weights > 1e-6
    support, support_w = pool[support_mask], weights[support_mask] / weights[support_mask].sum()
    m_star = weighted_information(scaled_columns(arm, support), support_w)
    m_plan = scaled_information(arm, q)
    max_star = _max_variance(arm, np.linalg.inv(m_star), support, rng, search)
    max_plan = _max_variance(arm, np.linalg.inv(m_plan), q, rng, search)
    logdet_plan = np.linalg.slogdet(m_plan)[1]
    logdet_star = np.linalg.slogdet(m_star)[1]
    kw = np.exp((logdet_plan - logdet_star) / p + 1.0 - max_star / p)
    plan_only = np.exp(1.0 - max_plan / p)
    hadamard = np.exp(logdet_plan / p)
    return Certificate(
        certified_d_efficiency=float(min(1.0, max(kw, plan_only, hadamard))),
        plan_only_bound=float(plan_only),
        reference_d_efficiency=float(np.exp(logdet_star / p)),
        max_variance=float(max_star),
        support=support,
        weights=support_w,
    )


def _max_variance(
    arm: PlanarArm, m_inv: np.ndarray, seeds: np.ndarray, rng: np.random.Generator, search: int
) -> float:
    """A thorough ``max_x d(x)`` over feasible poses: random search, then multistart ascent."""
    sample = np.concatenate([seeds, _corner_poses(arm, rng), feasible_poses(arm, search, rng)])
    d, _ = _variance_function(arm, sample, m_inv)
    starts = sample[np.argsort(-d)[:64]]
    found = _maximize_variance(arm, m_inv, starts, steps=300)
    d_found, _ = _variance_function(arm, found, m_inv)
    if arm.region is not None:  # count iterates that stray outside only a little
        g, _ = arm.region.constraints(forward_kinematics(arm, found[:, None, :]))
        d_found = np.where(g.min(axis=(-2, -1)) > -1e-3, d_found, -np.inf)
    return float(max(d.max(), d_found.max()))


# --------------------------------------------------------------------------- design


@dataclass(frozen=True, eq=False)
class Design:
    """An optimal calibration plan and what is known about its quality.

    Attributes
    ----------
    arm : PlanarArm
    q : ndarray, shape (m, n)
        The plan's joint angles in rad.
    criterion : str
        Criterion optimized (key of :data:`armcal.criteria.CRITERIA`).
    method : str
        How the plan was made: ``analytic``, ``optimize``, ``optimize+exchange`` or
        ``exchange``.
    d_efficiency : float
        ``(det F / det F_opt)^(1/p)``: relative to the unconstrained optimum.
    certificate : Certificate or None
        Lower bound relative to the best plan within the constraints (None when
        not asked for).
    notes : tuple of str
        Why a method was not used (e.g. the analytic plan breaks the limits).
    """

    arm: PlanarArm
    q: np.ndarray
    criterion: str
    method: str
    d_efficiency: float
    certificate: Certificate | None
    notes: tuple[str, ...]


def design(
    arm: PlanarArm,
    m: int,
    *,
    criterion: str = "D",
    method: Method = "auto",
    rng: np.random.Generator | int | None = None,
    candidates: np.ndarray | None = None,
    with_certificate: bool = True,
) -> Design:
    """An optimal ``m``-pose plan within the arm's joint limits and measurement region.

    Parameters
    ----------
    arm : PlanarArm
    m : int
        Number of poses; at least ``ceil(p / 2)``.
    criterion : {"D", "A", "E"}
        Criterion to maximize (the certificate is always for D).
    method : {"auto", "analytic", "optimize", "exchange"}
        ``auto`` takes the analytic plan when it fits the constraints, else
        optimizes and (for D) polishes by exchange over feasible candidates.
    rng : numpy.random.Generator or int or None
        The same seed gives the same plan.
    candidates : ndarray, shape (N, n), optional
        Poses the robot can really reach, for ``exchange`` (default: random
        feasible poses).
    with_certificate : bool
        Certify the plan (:func:`certify`); searches that design many plans
        skip it.

    Returns
    -------
    Design
    """
    if criterion not in CRITERIA:
        raise ArmcalError(f"unknown criterion {criterion!r}; choose one of {', '.join(CRITERIA)}")
    if method not in METHODS:
        raise ArmcalError(f"unknown method {method!r}; choose one of {', '.join(METHODS)}")
    min_poses = -(-arm.n_params // 2)
    if m < min_poses:
        raise ArmcalError(
            f"{m} poses give {2 * m} equations for the {arm.n_params} parameters of {arm.name}; "
            f"use --poses {min_poses} or more"
        )
    rng = np.random.default_rng(rng)
    notes: list[str] = []
    q, used = None, method
    if method in ("auto", "analytic"):
        try:
            q, used = analytic_plan(arm, m), "analytic"
        except ArmcalError as exc:
            if method == "analytic":
                raise
            notes.append(f"analytic plan not feasible ({exc}); optimized instead")
    if q is None and method == "exchange":
        pool = feasible_poses(arm, 4000, rng) if candidates is None else candidates
        q = exchange_plan(arm, m, pool, rng=rng)
        if criterion != "D":
            notes.append("exchange maximizes D; the plan was not tuned for " + criterion)
    elif q is None:
        q, used = optimize_plan(arm, m, criterion=criterion, rng=rng), "optimize"
        if criterion == "D":
            pool = feasible_poses(arm, 4000, rng) if candidates is None else candidates
            polished = exchange_plan(arm, m, pool, start=q, rng=rng)
            if float(d_efficiency(arm, polished)) > float(d_efficiency(arm, q)) * (1 + 1e-12):
                q, used = polished, "optimize+exchange"
    q = np.asarray(q, dtype=float)
    return Design(
        arm=arm,
        q=q,
        criterion=criterion,
        method=used,
        d_efficiency=float(d_efficiency(arm, q)),
        certificate=certify(arm, q, rng=rng) if with_certificate else None,
        notes=tuple(notes),
    )
