"""D-optimal experiments for geometry plus joint compliance, the payload a design variable.

A design point is a pose *and* the payload carried there, chosen among given
values (e.g. 0 and the rated payload): which poses to load, and how many.  The
information of a point is ``F^T F`` for the ``2 x p`` block ``F`` of the
whitened free columns of :meth:`armcal.models.compliance.CompliantArm.jacobian` at the
nominal arm, its columns scaled by their RMS over the candidates (D-efficiency
ratios do not depend on that scale).

How a plan is made (:func:`design_compliant`):

1. Random feasible poses (joint limits and region) times every payload make the
   candidates; the multiplicative algorithm gives the D-optimal weights on them.
2. Greedy selection from the weights' support and the modified Fedorov exchange
   (:func:`armcal.doe.exchange.exchange_indices`) pick ``m`` points.
3. A continuous polish moves every pose uphill in ``log det M`` (the gradient
   of ``log det`` in pose ``i`` is that of ``d_i(x) = tr(M^-1 F_x^T F_x)`` with
   ``M`` held), within the limits and the region; the payloads stay.

The certificate is the Kiefer-Wolfowitz bound of :mod:`armcal.doe.certificate`
for this model: for a near-optimal weighted design ``xi*`` (multiplicative
algorithm on the candidates and the maximizers of its variance function found
by ascent), the plan's D-efficiency relative to every design over the feasible
poses and the given payloads is at least
``(det M_plan / det M(xi*))^(1/p) exp(1 - max_x d(x, xi*) / p)``.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from ..errors import ArmcalError
from ..models import CompliantArm, Elastostatic, Loads, PlanarArm
from ..models.information import display_std, predicted_covariance, whitened_blocks
from ..numerics import scaled_svd
from .certificate import _weights_multiplicative
from .exchange import exchange_indices
from .order import ORDERS, joint_travel, order_poses
from .plans import feasible, feasible_poses

__all__ = [
    "CompliantDesign",
    "CompliantQuality",
    "d_efficiency_compliant",
    "design_compliant",
    "evaluate_compliant",
    "payload_values",
]


def payload_values(elastic: Elastostatic, given: Sequence[float] | None) -> tuple[float, ...]:
    """The payloads a design may use: ``given``, else 0 and the robot file's payload."""
    if given is not None:
        values = sorted({float(v) for v in given})
        if not values or any(not np.isfinite(v) or v < 0 for v in values):
            raise ArmcalError(f"payloads must be finite and not negative (kg), got {list(given)}")
        return tuple(values)
    return (0.0, elastic.payload_kg) if elastic.payload_kg > 0 else (0.0,)


@dataclass(frozen=True, eq=False)
class CompliantDesign:
    """A plan of poses and payloads for geometry plus joint compliance.

    Attributes
    ----------
    model : CompliantArm
        The parameters designed for (the arm's free ones, then ``k``/``c``).
    q : ndarray, shape (m, n)
        Joint angles (rad).
    payload_kg : ndarray, shape (m,)
        The payload of every pose.
    payloads : tuple of float
        The payload values the design could choose from.
    certified_d_efficiency : float
        Lower bound on the D-efficiency relative to the best design over the
        feasible poses and these payloads (Kiefer-Wolfowitz).
    plan_only_bound : float
        ``exp(1 - max_x d(x, plan) / p)``, the looser bound from the plan alone.
    max_variance : float
        ``max_x d(x, xi*)`` found (``p`` at the optimum).
    covariance : ndarray, shape (p + P, p + P)
        Predicted covariance at ``sigma_mm`` (internal units).
    sigma_mm : float
    joint_travel : float
        Joint travel of the plan in its order (rad).
    order : str
    """

    model: CompliantArm
    q: np.ndarray
    payload_kg: np.ndarray
    payloads: tuple[float, ...]
    certified_d_efficiency: float
    plan_only_bound: float
    max_variance: float
    covariance: np.ndarray
    sigma_mm: float
    joint_travel: float
    order: str

    @property
    def loads(self) -> Loads:
        return Loads.create(self.q.shape[0], self.payload_kg)

    @property
    def predicted_std(self) -> np.ndarray:
        """Predicted std of every parameter in display units (mm, deg, urad/(N*m), mdeg/m)."""
        return display_std(self.model, self.covariance)

    def payload_counts(self) -> dict[float, int]:
        """How many poses carry each payload value."""
        return {v: int(np.count_nonzero(self.payload_kg == v)) for v in self.payloads}


class _Points:
    """Blocks ``(k, 2, p_f)`` of (pose, payload) points in the design's column scale."""

    def __init__(self, model: CompliantArm, scale: np.ndarray) -> None:
        self.model, self.scale = model, scale

    def blocks(self, q: np.ndarray, payload: np.ndarray) -> np.ndarray:
        loads = Loads.create(q.shape[0], payload)
        jac = whitened_blocks(self.model, self.model.conditions(q, loads=loads))  # (k, 2, p_f)
        return jac / self.scale

    def variance(self, q: np.ndarray, payload: np.ndarray, m_inv: np.ndarray) -> np.ndarray:
        """``d(x) = tr(M^-1 F_x^T F_x)`` ``(k,)``."""
        f = self.blocks(q, payload)
        return np.einsum("kap,pq,kaq->k", f, m_inv, f)

    def gradient(
        self, q: np.ndarray, payload: np.ndarray, m_inv: np.ndarray, h: float = 1e-6
    ) -> np.ndarray:
        """Central-difference gradient ``(k, n)`` of ``d`` in every joint (rad)."""
        n = q.shape[1]
        grad = np.empty(q.shape)
        for j in range(n):
            step = np.zeros(n)
            step[j] = h
            grad[:, j] = (
                self.variance(q + step, payload, m_inv) - self.variance(q - step, payload, m_inv)
            ) / (2 * h)
        return grad


def _ascend(
    points: _Points,
    arm: PlanarArm,
    q: np.ndarray,
    payload: np.ndarray,
    m_inv: np.ndarray,
    *,
    steps: int = 60,
    step0: float = 0.2,
) -> np.ndarray:
    """Hill-climb ``d(x)`` from every start within the limits and the region (k, n)."""
    q = q.copy()
    lo, hi = arm.joint_limits[:, 0], arm.joint_limits[:, 1]
    value = points.variance(q, payload, m_inv)
    size = np.full(q.shape[0], step0)
    for _ in range(steps):
        grad = points.gradient(q, payload, m_inv)
        norm = np.linalg.norm(grad, axis=1, keepdims=True)
        trial = np.clip(q + size[:, None] * grad / np.where(norm > 0, norm, 1.0), lo, hi)
        new = points.variance(trial, payload, m_inv)
        ok = (new > value) & feasible(arm, trial[:, None, :])[:, 0]
        q[ok], value[ok] = trial[ok], new[ok]
        size = np.where(ok, size * 1.5, size * 0.5)
        if np.all(size < 1e-6):
            break
    return q


def _information(blocks: np.ndarray, weights: np.ndarray) -> np.ndarray:
    return np.einsum("x,xap,xaq->pq", weights, blocks, blocks)


def _logdet(matrix: np.ndarray) -> float:
    sign, value = np.linalg.slogdet(matrix)
    return float(value) if sign > 0 else -np.inf


def _polish(
    points: _Points, arm: PlanarArm, q: np.ndarray, payload: np.ndarray, *, rounds: int = 40
) -> np.ndarray:
    """Move every pose uphill in ``log det M`` of the plan (payloads fixed)."""
    m = q.shape[0]
    lo, hi = arm.joint_limits[:, 0], arm.joint_limits[:, 1]
    info = _information(points.blocks(q, payload), np.full(m, 1.0 / m))
    best = _logdet(info)
    size = 0.05
    for _ in range(rounds):
        m_inv = np.linalg.inv(info)
        grad = points.gradient(q, payload, m_inv)
        norm = np.linalg.norm(grad, axis=1, keepdims=True)
        trial = np.clip(q + size * grad / np.where(norm > 0, norm, 1.0), lo, hi)
        inside = feasible(arm, trial[:, None, :])[:, 0]
        trial[~inside] = q[~inside]
        new_info = _information(points.blocks(trial, payload), np.full(m, 1.0 / m))
        value = _logdet(new_info)
        if value > best + 1e-12:
            q, info, best = trial, new_info, value
            size *= 1.5
        else:
            size *= 0.5
            if size < 1e-7:
                break
    return q


def _reference_design(
    points: _Points,
    arm: PlanarArm,
    pool_q: np.ndarray,
    pool_w: np.ndarray,
    rounds: int,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """A near-D-optimal weighted design: its points, payloads, weights and ``M^-1``."""
    p = points.model.n_free
    q, w = pool_q, pool_w
    weights = np.full(q.shape[0], 1.0 / q.shape[0])
    for _ in range(rounds):
        weights = _weights_multiplicative(points.blocks(q, w), weights, 300)
        m_inv = np.linalg.inv(_information(points.blocks(q, w), weights))
        d = points.variance(q, w, m_inv)
        starts = np.argsort(-d)[: 4 * p]
        found = _ascend(points, arm, q[starts], w[starts], m_inv)
        keep = weights > 1e-6 / q.shape[0]
        mean = weights[keep].sum() / np.count_nonzero(keep)
        q = np.concatenate([q[keep], found])
        w = np.concatenate([w[keep], w[starts]])
        weights = np.concatenate([weights[keep], np.full(found.shape[0], mean)])
        weights /= weights.sum()
    weights = _weights_multiplicative(points.blocks(q, w), weights, 1000)
    keep = weights > 1e-6
    q, w, weights = q[keep], w[keep], weights[keep] / weights[keep].sum()
    m_inv = np.linalg.inv(_information(points.blocks(q, w), weights))
    return q, w, weights, m_inv


def _max_variance(
    points: _Points,
    arm: PlanarArm,
    m_inv: np.ndarray,
    seeds_q: np.ndarray,
    seeds_w: np.ndarray,
    values: np.ndarray,
    rng: np.random.Generator,
    search: int,
) -> float:
    """A thorough ``max_x d(x)`` over feasible poses and every payload: search, then ascent."""
    sample = feasible_poses(arm, search, rng=rng)
    q = np.concatenate([seeds_q, np.repeat(sample, values.size, axis=0)])
    w = np.concatenate([seeds_w, np.tile(values, sample.shape[0])])
    d = points.variance(q, w, m_inv)
    starts = np.argsort(-d)[:64]
    found = _ascend(points, arm, q[starts], w[starts], m_inv, steps=100)
    return float(max(d.max(), points.variance(found, w[starts], m_inv).max()))


def design_compliant(
    arm: PlanarArm,
    elastic: Elastostatic,
    m: int,
    *,
    payloads: Sequence[float] | None = None,
    sigma: float = 0.1,
    rng: np.random.Generator | int | None = None,
    candidates: int = 3000,
    rounds: int = 3,
    search: int = 20000,
    order: str = "travel",
) -> CompliantDesign:
    """A D-optimal plan of ``m`` poses and payloads for geometry plus joint compliance.

    Parameters
    ----------
    arm : PlanarArm
        With its limits, region, noise model and fixed parameters.
    elastic : Elastostatic
        Gravity, masses and payload (:mod:`armcal.elastostatic`).
    m : int
        Number of poses.
    payloads : sequence of float, optional
        Payloads (kg) a pose may carry; default 0 and the robot file's payload.
    sigma : float
        Instrument noise (mm) of the predicted covariance.
    rng : numpy.random.Generator or int or None
    candidates, rounds, search
        Random feasible poses of the candidate pool; rounds of adding the
        variance function's maximizers to the reference design; random poses
        the final search of ``max d`` starts from.
    order : {"travel", "none"}
        Order the poses for short joint travel (:func:`armcal.doe.order.order_poses`).

    Returns
    -------
    CompliantDesign

    Raises
    ------
    NotIdentifiableError
        If no plan of these poses and payloads can identify every parameter
        (e.g. ``k`` and ``c`` with a single payload in the lumped mode).
    """
    if order not in ORDERS:
        raise ArmcalError(f"unknown order {order!r}; choose one of {', '.join(ORDERS)}")
    if arm.n_target_links > 1:
        raise ArmcalError(
            f"{arm.name} has {arm.n_target_links} targets: plans for joint compliance are "
            "designed for one target per pose (exchange weighs a pose by one point); design "
            "for the target the tool carries, then measure every target at its poses"
        )
    rng = np.random.default_rng(rng)
    values = np.array(payload_values(elastic, payloads))
    model = CompliantArm.for_loads(arm, elastic, Loads.create(values.size, values))
    p = model.n_free
    if 2 * m < p:
        raise ArmcalError(
            f"{m} poses give {2 * m} equations for {p} parameters "
            f"({', '.join(model.param_names)}); design at least {-(-p // 2)} poses"
        )
    pool = feasible_poses(arm, candidates, rng=rng)
    pool_q = np.repeat(pool, values.size, axis=0)
    pool_w = np.tile(values, pool.shape[0])
    pool_rows = model.conditions(pool_q, loads=Loads.create(pool_w.size, pool_w))
    model.check_identifiable(pool_rows)
    raw = whitened_blocks(model, pool_rows)
    scale = np.sqrt(np.mean(raw**2, axis=(0, 1)))
    scale = np.where(scale > 0, scale, 1.0)
    points = _Points(model, scale)
    # The reference design first: its support seeds the exact plan.
    ref_q, ref_w, ref_weights, ref_inv = _reference_design(points, arm, pool_q, pool_w, rounds)
    cand_q = np.concatenate([ref_q, pool_q])
    cand_w = np.concatenate([ref_w, pool_w])
    blocks = points.blocks(cand_q, cand_w)
    counts = np.floor(ref_weights * m).astype(int)
    start = np.repeat(np.arange(ref_q.shape[0]), counts)[:m]
    index = exchange_indices(blocks, start, m)
    q, w = cand_q[index], cand_w[index]
    q = _polish(points, arm, q, w)
    plan_blocks = points.blocks(q, w)
    plan_info = _information(plan_blocks, np.full(m, 1.0 / m))
    # The certificate, against the reference design refined once more with the plan.
    ref_q, ref_w, ref_weights, ref_inv = _reference_design(
        points,
        arm,
        np.concatenate([ref_q, q]),
        np.concatenate([ref_w, w]),
        1,
    )
    star_info = _information(points.blocks(ref_q, ref_w), ref_weights)
    max_star = _max_variance(points, arm, ref_inv, ref_q, ref_w, values, rng, search)
    max_plan = _max_variance(points, arm, np.linalg.inv(plan_info), q, w, values, rng, search // 4)
    kw = np.exp((_logdet(plan_info) - _logdet(star_info)) / p + 1.0 - max_star / p)
    plan_only = float(np.exp(1.0 - max_plan / p))
    certified = float(min(1.0, max(kw, plan_only)))
    travel = joint_travel(q)
    if order == "travel":
        perm = order_poses(q)
        q, w = q[perm], w[perm]
        travel = joint_travel(q)
    loads = Loads.create(m, w)
    rows = model.conditions(q, loads=loads)
    model.check_identifiable(rows)
    covariance, _ = predicted_covariance(model, rows, sigma)
    return CompliantDesign(
        model=model,
        q=q,
        payload_kg=w,
        payloads=tuple(float(v) for v in values),
        certified_d_efficiency=certified,
        plan_only_bound=plan_only,
        max_variance=float(max_star),
        covariance=covariance,
        sigma_mm=float(sigma),
        joint_travel=float(travel),
        order=order,
    )


def d_efficiency_compliant(model: CompliantArm, q: np.ndarray, loads: Loads) -> float:
    """``det(M)^(1/p)`` of the plan's information with unit-norm columns (at most 1).

    Hadamard's bound makes 1 the value of a plan whose columns are orthogonal;
    the number compares plans of one model (the certificate of
    :func:`design_compliant` says how far a plan is from the best).  The plan is
    measured at every target of every pose.
    """
    jac = whitened_blocks(model, model.plan_conditions(q, loads))
    svd = scaled_svd(jac.reshape(-1, model.n_free))
    s = svd.truncated
    with np.errstate(divide="ignore"):
        return float(np.exp(2.0 * np.sum(np.log(s)) / model.n_free))


@dataclass(frozen=True, eq=False)
class CompliantQuality:
    """A plan's quality for geometry plus joint compliance, before measuring.

    Attributes
    ----------
    model : CompliantArm
    n_poses : int
    sigma_mm : float
        Instrument noise assumed (mm).
    predicted_std : ndarray, shape (p,)
        Every parameter's predicted std in display units (0 for a fixed one).
    d_efficiency : float
        :func:`d_efficiency_compliant`: compares plans of this model.
    payload_counts : dict of float to int
        How many poses carry each payload (kg).
    """

    model: CompliantArm
    n_poses: int
    sigma_mm: float
    predicted_std: np.ndarray
    d_efficiency: float
    payload_counts: dict[float, int]


def evaluate_compliant(
    model: CompliantArm, q: np.ndarray, loads: Loads, sigma: float
) -> CompliantQuality:
    """Predicted std and D-efficiency of plan ``q`` with payloads ``loads``, at noise ``sigma``.

    Raises NotIdentifiableError when the poses and loads cannot identify every parameter.
    """
    rows = model.plan_conditions(q, loads)
    model.check_identifiable(rows)
    covariance, _ = predicted_covariance(model, rows, sigma)
    std = np.where(model.free, display_std(model, covariance), 0.0)
    values, counts = np.unique(loads.payload_kg, return_counts=True)
    return CompliantQuality(
        model,
        int(q.shape[0]),
        float(sigma),
        std,
        d_efficiency_compliant(model, q, loads),
        {float(v): int(c) for v, c in zip(values, counts, strict=True)},
    )
