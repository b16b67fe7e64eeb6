"""D-optimal designs whose poses also choose their payload: geometry plus joint compliance.

A design point is a pose *and* the payload carried there, chosen among given
values (e.g. 0 and the rated payload): which poses to load, and how many.  The
model says which loads matter and which parameters a plan of them identifies
(:meth:`~armcal.models.interface.FitModel.design_loads`).  The information of a
point is ``F^T F`` for the block ``F`` of the whitened free columns
(:meth:`~armcal.models.interface.FitModel.plan_information`) at the nominal
model, its columns scaled by their RMS over the candidates (D-efficiency ratios
do not depend on that scale).

How a plan is made (:func:`design_with_loads`):

1. Random feasible poses (joint limits and the instrument's view) times every
   payload make the candidates; the multiplicative algorithm gives the
   D-optimal weights on them.
2. The weights rounded to ``m`` points, then the modified Fedorov exchange
   (:func:`armcal.doe.exchange.exchange_indices`) for one point in the plane a
   pose, DETMAX (:func:`armcal.doe.pool.detmax_indices`) for several rows a pose
   (a spatial arm's targets).
3. A continuous polish moves every pose uphill in ``log det M`` (the gradient
   of ``log det`` in pose ``i`` is that of ``d_i(x) = tr(M^-1 F_x^T F_x)`` with
   ``M`` held), within the limits and the view; the payloads stay.

The certificate is the Kiefer-Wolfowitz bound of :mod:`armcal.doe.certificate`
for this model: for a near-optimal weighted design ``xi*`` (multiplicative
algorithm on the candidates and the maximizers of its variance function found
by ascent), the plan's D-efficiency relative to every design over the feasible
poses and the given payloads is at least
``(det M_plan / det M(xi*))^(1/p) exp(1 - max_x d(x, xi*) / p)``.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from ..criteria import d_efficiency
from ..errors import ArmcalError
from ..models import FitModel, Loads, PlanInformation, equations_per_pose
from ..numerics import log_det
from .certificate import Certificate
from .designer import Design
from .exchange import exchange_indices
from .order import ORDERS, joint_travel, order_poses
from .plans import feasible_poses
from .pool import detmax_indices
from .weights import multiplicative_weights

__all__ = [
    "design_with_loads",
]


def _variance(blocks: np.ndarray, m_inv: np.ndarray) -> np.ndarray:
    """``d(x) = tr(M^-1 F_x^T F_x)`` ``(k,)`` of points given by their blocks ``(k, r, p_f)``."""
    return np.einsum("kap,pq,kaq->k", blocks, m_inv, blocks)


class _Points:
    """(pose, payload) points of a model: their blocks ``(k, r, p_f)`` in the design's
    column scale (:class:`~armcal.models.information.BlockInformation`) and their
    variance function."""

    def __init__(self, model: FitModel, scale: np.ndarray) -> None:
        self.model, self.scale = model, scale

    def _information(self, q: np.ndarray, payload: np.ndarray) -> PlanInformation:
        return self.model.plan_information(q, Loads.create(q.shape[0], payload))

    def blocks(self, q: np.ndarray, payload: np.ndarray) -> np.ndarray:
        return self._information(q, payload).blocks() / self.scale

    def variance(self, q: np.ndarray, payload: np.ndarray, m_inv: np.ndarray) -> np.ndarray:
        """``d(x) = tr(M^-1 F_x^T F_x)`` ``(k,)``."""
        return _variance(self.blocks(q, payload), m_inv)

    def gradient(self, q: np.ndarray, payload: np.ndarray, m_inv: np.ndarray) -> np.ndarray:
        """The gradient ``(k, n)`` of ``d`` in every joint (rad): the model's pullback where
        it has one (:meth:`~armcal.models.interface.PlanInformation.pose_variance`), else
        central differences."""
        information = self._information(q, payload)
        scaled = m_inv / np.outer(self.scale, self.scale)  # the blocks' own columns
        return information.pose_variance(scaled)[1] * information.rows_per_pose


def _ascend(
    points: _Points,
    model: FitModel,
    q: np.ndarray,
    payload: np.ndarray,
    m_inv: np.ndarray,
    *,
    steps: int = 60,
    step0: float = 0.2,
) -> np.ndarray:
    """Hill-climb ``d(x)`` from every start within the limits and the region (k, n)."""
    q = q.copy()
    lo, hi = model.joint_limits[:, 0], model.joint_limits[:, 1]
    value = points.variance(q, payload, m_inv)
    size = np.full(q.shape[0], step0)
    for _ in range(steps):
        grad = points.gradient(q, payload, m_inv)
        norm = np.linalg.norm(grad, axis=1, keepdims=True)
        trial = np.clip(q + size[:, None] * grad / np.where(norm > 0, norm, 1.0), lo, hi)
        new = points.variance(trial, payload, m_inv)
        ok = (new > value) & model.feasible(trial[:, None, :])[:, 0]
        q[ok], value[ok] = trial[ok], new[ok]
        size = np.where(ok, size * 1.5, size * 0.5)
        if np.all(size < 1e-6):
            break
    return q


def _information(blocks: np.ndarray, weights: np.ndarray) -> np.ndarray:
    return np.einsum("x,xap,xaq->pq", weights, blocks, blocks)


def _polish(
    points: _Points, model: FitModel, q: np.ndarray, payload: np.ndarray, *, rounds: int = 40
) -> np.ndarray:
    """Move every pose uphill in ``log det M`` of the plan (payloads fixed)."""
    m = q.shape[0]
    lo, hi = model.joint_limits[:, 0], model.joint_limits[:, 1]
    info = _information(points.blocks(q, payload), np.full(m, 1.0 / m))
    best = float(log_det(info))
    size = 0.05
    for _ in range(rounds):
        m_inv = np.linalg.inv(info)
        grad = points.gradient(q, payload, m_inv)
        norm = np.linalg.norm(grad, axis=1, keepdims=True)
        trial = np.clip(q + size * grad / np.where(norm > 0, norm, 1.0), lo, hi)
        inside = model.feasible(trial[:, None, :])[:, 0]
        trial[~inside] = q[~inside]
        new_info = _information(points.blocks(trial, payload), np.full(m, 1.0 / m))
        value = float(log_det(new_info))
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
    model: FitModel,
    pool_q: np.ndarray,
    pool_w: np.ndarray,
    rounds: int,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """A near-D-optimal weighted design: its points, payloads, weights and information."""
    p = points.model.n_free
    q, w = pool_q, pool_w
    weights = np.full(q.shape[0], 1.0 / q.shape[0])
    for _ in range(rounds):
        blocks = points.blocks(q, w)
        weights = multiplicative_weights(blocks, weights, 300)
        m_inv = np.linalg.inv(_information(blocks, weights))
        d = _variance(blocks, m_inv)
        starts = np.argsort(-d)[: 4 * p]
        found = _ascend(points, model, q[starts], w[starts], m_inv)
        keep = weights > 1e-6 / q.shape[0]
        mean = weights[keep].sum() / np.count_nonzero(keep)
        q = np.concatenate([q[keep], found])
        w = np.concatenate([w[keep], w[starts]])
        weights = np.concatenate([weights[keep], np.full(found.shape[0], mean)])
        weights /= weights.sum()
    blocks = points.blocks(q, w)
    weights = multiplicative_weights(blocks, weights, 1000)
    keep = weights > 1e-6
    q, w, weights = q[keep], w[keep], weights[keep] / weights[keep].sum()
    info = _information(blocks[keep], weights)  # a point's block is its own: slice, not redo
    return q, w, weights, info


def _max_variance(
    points: _Points,
    model: FitModel,
    m_inv: np.ndarray,
    seeds_q: np.ndarray,
    seeds_w: np.ndarray,
    values: np.ndarray,
    rng: np.random.Generator,
    search: int,
) -> float:
    """A thorough ``max_x d(x)`` over feasible poses and every payload: search, then ascent."""
    sample = feasible_poses(model, search, rng=rng)
    q = np.concatenate([seeds_q, np.repeat(sample, values.size, axis=0)])
    w = np.concatenate([seeds_w, np.tile(values, sample.shape[0])])
    d = points.variance(q, w, m_inv)
    starts = np.argsort(-d)[:64]
    found = _ascend(points, model, q[starts], w[starts], m_inv, steps=100)
    return float(max(d.max(), points.variance(found, w[starts], m_inv).max()))


def _design_request(
    model: FitModel, m: int, payloads: Sequence[float] | None, order: str
) -> tuple[FitModel, np.ndarray]:
    """The model a plan of these payloads identifies and the payload values (kg), once the
    request is checked: a known order, points that depend on the load, enough equations."""
    if order not in ORDERS:
        raise ArmcalError(f"unknown order {order!r}; choose one of {', '.join(ORDERS)}")
    chosen = model.design_loads(payloads)
    if chosen is None:
        raise ArmcalError(f"the points of {model.name} do not depend on the load: use design()")
    design_model, values = chosen
    p = design_model.n_free
    per_pose = equations_per_pose(design_model)
    if per_pose * m < p:
        raise ArmcalError(
            f"{m} poses give {per_pose * m} equations for {p} parameters "
            f"({', '.join(design_model.param_names)}); design at least {-(-p // per_pose)} poses"
        )
    return design_model, values


def _candidate_pool(
    model: FitModel,
    design_model: FitModel,
    values: np.ndarray,
    candidates: int,
    rng: np.random.Generator,
) -> tuple[_Points, np.ndarray, np.ndarray]:
    """The candidate points: random feasible poses times every payload ``(k, n)``, ``(k,)``,
    with the design's column scale (their blocks' RMS); refused if they identify nothing."""
    pool = feasible_poses(model, candidates, rng=rng)
    pool_q = np.repeat(pool, values.size, axis=0)
    pool_w = np.tile(values, pool.shape[0])
    pool_information = design_model.plan_information(pool_q, Loads.create(pool_w.size, pool_w))
    pool_information.check_identifiable()
    raw = pool_information.blocks()
    scale = np.sqrt(np.mean(raw**2, axis=(0, 1)))
    scale = np.where(scale > 0, scale, 1.0)
    return _Points(design_model, scale), pool_q, pool_w  # pool blocks: raw / scale


def _exact_plan(
    points: _Points,
    model: FitModel,
    pool_q: np.ndarray,
    pool_w: np.ndarray,
    m: int,
    rounds: int,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The plan's poses and payloads (steps 1-3 of the module notes), and the support
    poses and payloads of the reference design it was rounded from."""
    # The reference design first: its support seeds the exact plan.
    ref_q, ref_w, ref_weights, _ = _reference_design(points, model, pool_q, pool_w, rounds)
    cand_q = np.concatenate([ref_q, pool_q])
    cand_w = np.concatenate([ref_w, pool_w])
    blocks = points.blocks(cand_q, cand_w)
    counts = np.floor(ref_weights * m).astype(int)
    start = np.repeat(np.arange(ref_q.shape[0]), counts)[:m]
    if blocks.shape[-2] == 2:  # one point in the plane: the modified Fedorov exchange
        index = exchange_indices(blocks, start, m)
    else:  # several rows a pose: DETMAX from the reference design rounded up
        ranked = np.argsort(-(ref_weights * m - counts), kind="stable")
        rest = np.resize(ranked, m - start.size)
        index = detmax_indices(blocks, np.concatenate([start, rest]))
    q, w = cand_q[index], cand_w[index]
    return _polish(points, model, q, w), w, ref_q, ref_w


def _plan_certificate(
    points: _Points,
    model: FitModel,
    plan: tuple[np.ndarray, np.ndarray],
    reference: tuple[np.ndarray, np.ndarray],
    values: np.ndarray,
    rng: np.random.Generator,
    search: int,
) -> Certificate:
    """The Kiefer-Wolfowitz certificate of the plan's poses and payloads ``plan``, against
    the reference design (support ``reference``) refined once more with the plan."""
    q, w = plan
    p = points.model.n_free
    plan_info = _information(points.blocks(q, w), np.full(q.shape[0], 1.0 / q.shape[0]))
    ref_q, ref_w, ref_weights, star_info = _reference_design(
        points,
        model,
        np.concatenate([reference[0], q]),
        np.concatenate([reference[1], w]),
        1,
    )
    ref_inv = np.linalg.inv(star_info)
    max_star = _max_variance(points, model, ref_inv, ref_q, ref_w, values, rng, search)
    max_plan = _max_variance(
        points, model, np.linalg.inv(plan_info), q, w, values, rng, search // 4
    )
    kw = np.exp((log_det(plan_info) - log_det(star_info)) / p + 1.0 - max_star / p)
    plan_only = float(np.exp(1.0 - max_plan / p))
    return Certificate(
        certified_d_efficiency=float(min(1.0, max(kw, plan_only))),
        plan_only_bound=plan_only,
        reference_d_efficiency=float(np.exp(log_det(star_info) / p)),
        max_variance=float(max_star),
        support=ref_q,
        weights=ref_weights,
    )


def design_with_loads(
    model: FitModel,
    m: int,
    *,
    payloads: Sequence[float] | None = None,
    rng: np.random.Generator | int | None = None,
    candidates: int | None = None,
    rounds: int = 3,
    search: int | None = None,
    order: str = "travel",
) -> Design:
    """A D-optimal plan of ``m`` poses and their payloads for a model whose points depend on
    the load (joint compliance).

    Parameters
    ----------
    model : FitModel
        With its limits, view, noise model and fixed parameters; its
        :meth:`~armcal.models.interface.FitModel.design_loads` says which
        parameters a plan of these payloads identifies.
    m : int
        Number of poses.
    payloads : sequence of float, optional
        Payloads (kg) a pose may carry; default 0 and the robot file's payload.
    rng : numpy.random.Generator or int or None
    candidates, rounds, search
        Random feasible poses of the candidate pool; rounds of adding the
        variance function's maximizers to the reference design; random poses
        the final search of ``max d`` starts from.  Default: the model's
        :attr:`~armcal.models.interface.FitModel.design_effort`.
    order : {"travel", "none"}
        Order the poses for short joint travel (:func:`armcal.doe.order.order_poses`).

    Returns
    -------
    Design
        With ``payload_kg`` (every pose's) and ``payloads`` (the choices), the
        model the plan identifies (:attr:`Design.model`) and the certificate.

    Raises
    ------
    ArmcalError
        If the model's points do not depend on the load.
    NotIdentifiableError
        If no plan of these poses and payloads can identify every parameter
        (e.g. ``k`` and ``c`` with a single payload in the lumped mode).
    """
    design_model, values = _design_request(model, m, payloads, order)
    rng = np.random.default_rng(rng)
    effort = model.design_effort
    candidates = effort.candidates if candidates is None else candidates
    search = effort.search if search is None else search
    points, pool_q, pool_w = _candidate_pool(model, design_model, values, candidates, rng)
    q, w, ref_q, ref_w = _exact_plan(points, model, pool_q, pool_w, m, rounds)
    certificate = _plan_certificate(points, model, (q, w), (ref_q, ref_w), values, rng, search)
    travel_found = joint_travel(q)
    if order == "travel":
        perm = order_poses(q)
        q, w = q[perm], w[perm]
    plan_information = design_model.plan_information(q, Loads.create(m, w))
    plan_information.check_identifiable()
    return Design(
        model=design_model,
        q=q,
        criterion="D",
        method="exchange+polish",
        d_efficiency=float(d_efficiency(design_model, q, info=plan_information)),
        certificate=certificate,
        note_texts=(),
        order=order,
        joint_travel=joint_travel(q),
        joint_travel_unordered=travel_found,
        distinct=False,
        payload_kg=w,
        payloads=tuple(float(v) for v in values),
    )
