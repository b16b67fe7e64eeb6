"""A certified lower bound on a plan's D-efficiency (Kiefer-Wolfowitz equivalence theorem)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..criteria import attains_unit_bound, d_efficiency
from ..models import FitModel
from ..models.information import identifying
from ..numerics import ScaledSVD, scaled_svd, spd_inverse
from ..progress import ProgressCallback, share
from .ascent import adam_ascent, penalty_weight, to_q, to_u, view_penalty
from .plans import feasible_poses

__all__ = [
    "CLOSE_ENOUGH",
    "POOL_CERTIFICATE_ITERATIONS",
    "Certificate",
    "certify",
    "certify_pool",
    "multiplicative_weights",
]

#: A plan whose own variance function certifies at least this (``exp(1 - max d / p)``)
#: is not compared with a searched weighted design: that could add at most ``1 - bound``.
CLOSE_ENOUGH = 0.999


@dataclass(frozen=True, eq=False)
class Certificate:
    """A lower bound on a plan's D-efficiency relative to the best possible plan.

    Everything is in the model's design coordinates
    (:meth:`~armcal.models.interface.FitModel.plan_information`): ``p`` is the
    number of free parameters and ``M`` the normalized information of the
    whitened free-parameter columns -- the paper's ``Fs`` for its model.

    Attributes
    ----------
    certified_d_efficiency : float
        ``(det M_plan / det M*)^(1/p)`` is at least this for every ``M*`` reachable
        within the joint limits and region, exact plans and weighted designs alike.
    plan_only_bound : float
        The looser bound ``exp(1 - max_x d(x, plan) / p)``.
    reference_d_efficiency : float
        ``(det M(xi*))^(1/p)`` of the best weighted design ``xi*`` found, in the
        normalization of :func:`armcal.criteria.d_efficiency` (Hadamard-normalized
        for the paper's model; at most 1 wherever
        :attr:`~armcal.models.interface.FitModel.information_bound` holds).
    max_variance : float
        ``max_x d(x, xi*)`` over the feasible poses searched (``>= p``; ``= p`` at
        the optimum).
    support : ndarray, shape (k, n)
        Support poses (rad) of the best weighted design ``xi*``.
    weights : ndarray, shape (k,)
        Their weights (sum 1).
    max_pose : ndarray, shape (n,), or None
        The pose (rad) where the search found ``max_variance``: where the best
        weighted design is least informed (None for a certificate without a search).
    pool_size : int or None
        For a plan from a pool of candidate poses (:func:`certify_pool`): how many
        distinct poses the pool holds, and every bound is relative to the best
        design over them, not over every feasible pose; None otherwise.
    """

    certified_d_efficiency: float
    plan_only_bound: float
    reference_d_efficiency: float
    max_variance: float
    support: np.ndarray
    weights: np.ndarray
    max_pose: np.ndarray | None = None
    pool_size: int | None = None

    def __repr__(self) -> str:
        over = (
            "every feasible pose"
            if self.pool_size is None
            else f"the {self.pool_size} distinct candidate poses"
        )
        return (
            f"Certificate(D-efficiency >= {self.certified_d_efficiency:.4f} against the best "
            f"design over {over}; plan-only bound {self.plan_only_bound:.4f})"
        )

    def reference_inverse(self, model: FitModel) -> np.ndarray:
        """``M(xi*)^-1`` of the reference design (its support and weights) by the rank
        policy: the matrix whose variance function ``max_variance`` bounds."""
        return _weighted_svd(_pose_blocks(model, self.support), self.weights).inverse_gram()[0]


def _variance_function(model: FitModel, q: np.ndarray, m_inv: np.ndarray):
    """``d(x) = tr(M^-1 I(x))`` ``(k,)`` of poses ``q`` ``(k, n)`` and its gradient ``(k, n)``."""
    return model.plan_information(q).pose_variance(m_inv)


def _pose_blocks(model: FitModel, q: np.ndarray) -> np.ndarray:
    """Every pose's real blocks ``(k, r, p_f)`` scaled to its information per row (``/ T``)."""
    info = model.plan_information(q)
    return info.blocks() / np.sqrt(info.rows_per_pose)


def _maximize_variance(
    model: FitModel,
    m_inv: np.ndarray,
    starts: np.ndarray,
    *,
    steps: int = 150,
    progress: ProgressCallback | None = None,
) -> np.ndarray:
    """Batched ascent of ``d(x)`` from ``starts (k, n)`` within the limits (near the view)."""

    def objective(u: np.ndarray, step: int):
        q, dq_du = to_q(model, u)
        value, grad = _variance_function(model, q, m_inv)
        penalty, grad_pen = view_penalty(model, q[:, None, :])
        weight = penalty_weight(model, step / steps) * 1e3
        return value - weight * penalty, (grad - weight * grad_pen[:, 0]) * dq_du

    u, _ = adam_ascent(
        objective, to_u(model, starts), steps=steps, learning_rate=0.05, progress=progress
    )
    return to_q(model, u)[0]


def _corner_poses(model: FitModel, rng: np.random.Generator) -> np.ndarray:
    """Poses with every joint at a limit (joint 1 random where its angle does not matter)."""
    n = model.n_joints
    if n > 10:
        return np.empty((0, n))
    grid = np.array(np.meshgrid(*[[0, 1]] * n, indexing="ij")).reshape(n, -1).T
    limits = model.joint_limits
    corners = limits[np.arange(n), grid]
    if model.rotation_invariant:
        corners[:, 0] = rng.uniform(limits[0, 0], limits[0, 1], len(corners))
    return corners[model.feasible(corners[:, None, :])[:, 0]]


def multiplicative_weights(
    blocks: np.ndarray, weights: np.ndarray, iterations: int, *, power: float = 1.0
):
    """Multiplicative algorithm for D-optimal weights (Titterington 1976; Silvey et al. 1978):
    ``w_x <- w_x (d(x) / p)^power``.  ``power`` 1 never decreases ``det M``; Silvey et al.'s
    larger powers take fewer iterations to the same optimum, without that guarantee.

    ``M(xi)`` stays positive definite: the pool holds the (identifiable) plan's
    own poses or the support of an earlier positive definite design, and every
    weight stays positive.  The inverse is
    :func:`~armcal.numerics.spd_inverse`, which cannot raise whatever round-off does.
    """
    p = blocks.shape[-1]
    rows = blocks.reshape(-1, p)  # (N r, p): matrix products, not three-operand einsums
    per_pose = blocks.shape[1]
    for _ in range(iterations):
        weighted = rows * np.repeat(weights, per_pose)[:, None]
        m_inv = spd_inverse(rows.T @ weighted)  # sum_x w_x F_x^T F_x
        d = np.sum((rows @ m_inv) * rows, axis=1).reshape(-1, per_pose).sum(axis=1)
        weights = weights * (d / p) ** power
        weights /= weights.sum()
    return weights


def _weighted_svd(blocks: np.ndarray, weights: np.ndarray) -> ScaledSVD:
    """The rank policy's SVD of ``M(xi) = sum_x w_x I(x)``, from its square-root factor.

    Rows ``sqrt(w_x) F_x`` (``F_x`` the poses' scaled blocks, :func:`_pose_blocks`) have
    Gram matrix ``M(xi)``: its inverse and ``log det`` come from singular values, not
    from inverting ``M``.
    """
    weighted = blocks * np.sqrt(weights)[:, None, None]
    return scaled_svd(weighted.reshape(-1, blocks.shape[-1]))


def _reference_support(
    model: FitModel,
    distinct: np.ndarray,
    rng: np.random.Generator,
    candidates: int,
    rounds: int,
    parts: list[ProgressCallback | None],
) -> tuple[np.ndarray, np.ndarray]:
    """The support poses ``(k, n)`` and weights ``(k,)`` of a near-D-optimal weighted
    design ``xi*``: the multiplicative algorithm on the plan's poses, the corners and
    random feasible poses, refined ``rounds`` times by the maximizers of ``d``."""
    p = model.n_free
    pool = np.concatenate(
        [
            distinct,
            _corner_poses(model, rng),
            feasible_poses(model, candidates, rng=rng),
        ]
    )
    weights = np.full(pool.shape[0], 1.0 / pool.shape[0])
    for round_ in range(rounds):
        blocks = _pose_blocks(model, pool)
        weights = multiplicative_weights(blocks, weights, 150, power=2.0)
        m_inv, _ = _weighted_svd(blocks, weights).inverse_gram()
        # Ascend d from its largest values in the pool and in fresh random poses: the
        # maximizers of a weighted model (encoder noise) can lie in narrow regions
        # that the first candidates missed.
        fresh = feasible_poses(model, candidates, rng=rng)
        starts = []
        for poses in (pool, fresh):
            d, _ = _variance_function(model, poses, m_inv)
            starts.append(poses[np.argsort(-d)[: 4 * p]])
        found = _maximize_variance(
            model, m_inv, np.concatenate(starts), progress=parts[1 + round_]
        )
        found = found[model.feasible(found[:, None, :])[:, 0]]
        keep = weights > 1e-6 / pool.shape[0]
        pool = np.concatenate([pool[keep], found])
        # New points start at the mean weight: the multiplicative algorithm grows a
        # weight only by the factor d(x) / p per iteration, too slowly from a tiny one.
        mean_weight = weights[keep].sum() / np.count_nonzero(keep)
        weights = np.concatenate([weights[keep], np.full(found.shape[0], mean_weight)])
        weights /= weights.sum()
    weights = multiplicative_weights(_pose_blocks(model, pool), weights, 500, power=2.0)
    support_mask = weights > 1e-6
    return pool[support_mask], weights[support_mask] / weights[support_mask].sum()


def certify(
    model: FitModel,
    q: np.ndarray,
    *,
    rng: np.random.Generator | int | None = None,
    candidates: int | None = None,
    rounds: int | None = None,
    search: int | None = None,
    progress: ProgressCallback | None = None,
) -> Certificate:
    """Certify a plan's D-efficiency against the best possible plan within the constraints.

    Parameters
    ----------
    model : FitModel
        A model the plan does not identify as given (a spatial arm as loaded, with
        parameters no plan separates) is certified as the plan identifies it
        (:func:`~armcal.models.information.identifying`), as :func:`design` does.
    q : ndarray, shape (m, n)
        The plan (rad); must identify every parameter.
    rng : numpy.random.Generator or int or None
        Seeds the random candidates and searches.
    candidates : int, optional
        Random feasible poses for the weighted (approximate) design.
    rounds : int, optional
        Rounds of adding the maximizer of the variance function to the candidates.
    search : int, optional
        Random feasible poses from which the final maximization of ``d`` starts.

        Each defaults to the model's
        :attr:`~armcal.models.interface.FitModel.design_effort`.
    progress : callable, optional
        ``progress(done, total)`` as the searches advance.

    Returns
    -------
    Certificate

    Raises
    ------
    NotIdentifiableError
        If the plan cannot identify every parameter: its D-efficiency is 0, and
        there is nothing to certify.

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
    outside the region only raise the maximum, which keeps the bound safe.
    The plan itself is a design too (``xi`` = its poses): its own bound
    ``exp(1 - max_x d(x, plan) / p)`` comes first, and when it reaches
    :data:`CLOSE_ENOUGH` the plan is the reference and no ``xi*`` is searched
    for (it could raise the bound by at most ``1 - CLOSE_ENOUGH``).
    The theorem holds for any per-pose information ``I(x)``: weighted (anisotropic,
    correlated or encoder noise) and reduced (fixed parameters) models are
    certified against their own optimum, over their own columns.

    Where every pose's information has trace ``p``
    (:attr:`~armcal.models.interface.FitModel.information_bound`; for a planar
    arm :func:`~armcal.models.planar.information.unit_trace`: the paper's model,
    isotropic iid noise with only lengths, base or leading offsets fixed, or every parameter free
    without encoder noise) every design has ``tr M = p``, so ``det M* <= 1``
    (Hadamard's bound for the paper's unit diagonal; AM-GM in general) is a
    certificate too: the result is then never below the plan's own
    D-efficiency, and a plan with ``M = I`` (an orthogonal plan) is certified 1
    without a search.  Other models have no such bound; only the two above apply.
    """
    rng = np.random.default_rng(rng)
    effort = model.design_effort
    candidates = effort.candidates if candidates is None else candidates
    rounds = effort.rounds if rounds is None else rounds
    search = effort.search if search is None else search
    q = np.asarray(q, dtype=float)
    model = identifying(model, model.plan_conditions(q))  # a spatial arm as loaded: prepared
    p = model.n_free
    plan_information = model.plan_information(q)
    plan = plan_information.svd()
    plan_information.check_identifiable()
    bounded = model.information_bound
    # Round-off of the m-term sums in Fs grows like m eps: attains_unit_bound allows
    # it, or a large orthogonal plan would miss this shortcut and run the whole search.
    if bounded and attains_unit_bound(
        model, q, float(d_efficiency(model, q, info=plan_information))
    ):
        # M = I: the bound det M <= 1 is attained, and d(x) = tr(I(x)) = p at every pose.
        return Certificate(1.0, 1.0, 1.0, float(p), q, np.full(q.shape[0], 1.0 / q.shape[0]))
    # The plan's distinct poses: a large plan is a smaller one repeated (designer), and
    # the pool's and the search's costs are per pose.
    distinct, counts = np.unique(q, axis=0, return_counts=True)
    plan_inverse, _ = plan.inverse_gram()
    parts = [share(progress, k / (rounds + 2), (k + 1) / (rounds + 2)) for k in range(rounds + 2)]
    max_plan, plan_pose = _max_variance(model, plan_inverse, distinct, rng, search, parts[0])
    logdet_plan = float(plan.log_det_gram())
    plan_only = np.exp(1.0 - max_plan / p)
    hadamard = np.exp(logdet_plan / p) if bounded else 0.0
    if plan_only >= CLOSE_ENOUGH:  # the plan is its own reference design
        return Certificate(
            certified_d_efficiency=float(min(1.0, max(plan_only, hadamard))),
            plan_only_bound=float(plan_only),
            reference_d_efficiency=float(np.exp(logdet_plan / p)),
            max_variance=max_plan,
            max_pose=plan_pose,
            support=distinct,
            weights=counts / q.shape[0],
        )
    support, support_w = _reference_support(model, distinct, rng, candidates, rounds, parts)
    star = _weighted_svd(_pose_blocks(model, support), support_w)
    # Fs = H^T H with H the plan's scaled Jacobian: inverses and log dets from SVDs.
    star_inverse, star_ok = star.inverse_gram()
    if bool(star_ok):
        max_star, max_pose = _max_variance(model, star_inverse, support, rng, search, parts[-1])
        logdet_star = float(star.log_det_gram())
    else:  # not expected (xi* is near D-optimal); the other bounds still hold
        max_star, logdet_star, max_pose = np.inf, -np.inf, None
    kw = np.exp((logdet_plan - logdet_star) / p + 1.0 - max_star / p) if bool(star_ok) else 0.0
    return Certificate(
        certified_d_efficiency=float(min(1.0, max(kw, plan_only, hadamard))),
        plan_only_bound=float(plan_only),
        reference_d_efficiency=float(np.exp(logdet_star / p)),
        max_variance=float(max_star),
        max_pose=max_pose,
        support=support,
        weights=support_w,
    )


#: Iterations of the multiplicative algorithm (Silvey et al.'s power 2) for the best
#: weighted design over a pool: on a six-axis arm's 1000-pose pool (30 free parameters)
#: they certify within 0.001 of 1000 iterations of power 1, at a quarter of the time.
POOL_CERTIFICATE_ITERATIONS = 300


def certify_pool(model: FitModel, q: np.ndarray, pool: np.ndarray) -> Certificate:
    """Certify a plan taken from ``pool`` against the best design over the pool's poses.

    Parameters
    ----------
    model : FitModel
    q : ndarray, shape (m, n)
        The plan (rad), every pose a pose of ``pool``; must identify every parameter.
    pool : ndarray, shape (N, n)
        The candidate poses (rad) a plan may take (a cell's collision-free poses).

    Returns
    -------
    Certificate
        With ``pool_size`` the number of distinct pool poses; ``max_pose`` is the
        pool pose where the reference design is least informed.

    Raises
    ------
    NotIdentifiableError
        If the plan cannot identify every parameter.

    Notes
    -----
    The Kiefer-Wolfowitz bound of :func:`certify` with the feasible poses replaced by
    the pool's: a finite set, so ``max_x d(x, xi)`` is exact, no search.  For any
    weighted design ``xi`` over the pool ``log det M* <= log det M(xi) + max_x d(x, xi)
    - p`` for the best design ``M*`` over the pool (concavity of ``log det``), so the
    plan's efficiency relative to it is at least ``(det M_plan / det M(xi*))^(1/p)
    exp(1 - max_x d(x, xi*) / p)``, ``xi*`` the multiplicative algorithm's weights
    (:data:`POOL_CERTIFICATE_ITERATIONS` iterations of power 2; any weights give a
    valid bound, better ones a tighter).  The plan is a design over the pool too: its own bound
    ``exp(1 - max_x d(x, plan) / p)``.  Where every design has ``det M <= 1``
    (:attr:`~armcal.models.interface.FitModel.information_bound`) so has the pool's
    best, and ``det M_plan^(1/p)`` is a bound as well.
    """
    q = np.asarray(q, dtype=float)
    pool = np.asarray(pool, dtype=float)
    model = identifying(model, model.plan_conditions(q))  # a spatial arm as loaded: prepared
    p = model.n_free
    plan_information = model.plan_information(q)
    plan_information.check_identifiable()
    plan = plan_information.svd()
    logdet_plan = float(plan.log_det_gram())
    poses = np.unique(pool, axis=0)  # a copy adds no pose a design could weigh
    plan_inverse, _ = plan.inverse_gram()
    pool_information = model.plan_information(poses)  # once: both variances and the blocks
    d_plan, _ = pool_information.pose_variance(plan_inverse)
    plan_only = float(np.exp(1.0 - d_plan.max() / p))
    blocks = pool_information.blocks() / np.sqrt(pool_information.rows_per_pose)
    weights = np.full(poses.shape[0], 1.0 / poses.shape[0])
    weights = multiplicative_weights(blocks, weights, POOL_CERTIFICATE_ITERATIONS, power=2.0)
    star = _weighted_svd(blocks, weights)
    star_inverse, _ = star.inverse_gram()
    d_star, _ = pool_information.pose_variance(star_inverse)
    logdet_star = float(star.log_det_gram())
    kw = float(np.exp((logdet_plan - logdet_star) / p + 1.0 - d_star.max() / p))
    hadamard = float(np.exp(logdet_plan / p)) if model.information_bound else 0.0
    support = weights > 1e-6
    return Certificate(
        certified_d_efficiency=float(min(1.0, max(kw, plan_only, hadamard))),
        plan_only_bound=plan_only,
        reference_d_efficiency=float(np.exp(logdet_star / p)),
        max_variance=float(d_star.max()),
        support=poses[support],
        weights=weights[support] / weights[support].sum(),
        max_pose=poses[int(np.argmax(d_star))],
        pool_size=int(poses.shape[0]),
    )


def _max_variance(
    model: FitModel,
    m_inv: np.ndarray,
    seeds: np.ndarray,
    rng: np.random.Generator,
    search: int,
    progress: ProgressCallback | None = None,
) -> tuple[float, np.ndarray]:
    """A thorough ``max_x d(x)`` over feasible poses, and where: random search, then
    multistart ascent."""
    sample = np.concatenate(
        [seeds, _corner_poses(model, rng), feasible_poses(model, search, rng=rng)]
    )
    d, _ = _variance_function(model, sample, m_inv)
    starts = sample[np.argsort(-d)[:64]]
    found = _maximize_variance(model, m_inv, starts, steps=300, progress=progress)
    d_found, _ = _variance_function(model, found, m_inv)
    constraints = model.view_constraints(found[:, None, :])
    if constraints is not None:  # count iterates that stray outside only a little
        d_found = np.where(constraints[0].min(axis=(-2, -1)) > -1e-3, d_found, -np.inf)
    if d.max() >= d_found.max():
        return float(d.max()), sample[int(np.argmax(d))]
    return float(d_found.max()), found[int(np.argmax(d_found))]
