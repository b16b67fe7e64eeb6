"""A certified lower bound on a plan's D-efficiency (Kiefer-Wolfowitz equivalence theorem)."""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from ..criteria import attains_unit_bound, d_efficiency
from ..models import FitModel
from ..models.information import identifying
from ..numerics import ScaledSVD, scaled_svd, spd_inverse
from ..progress import ProgressCallback, share
from .ascent import adam_ascent, penalty_weight, to_q, to_u, view_penalty
from .constrained import bounded_ascent, projected_ascent
from .plans import feasible_poses
from .pool import pool_blocks
from .weights import information, newton_weights, optimal_weights, variances

__all__ = [
    "CLOSE_ENOUGH",
    "Certificate",
    "certify",
    "certify_pool",
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

    def rebased(self, model: FitModel, q: np.ndarray) -> Certificate | None:
        """The same reference design's bound for another plan ``q`` of the same ``model``
        (a plan chosen after this certificate, from poses that include its support):
        ``(det M_q / det M(xi*))^(1/p) exp(1 - max_variance / p)``, no search, as the
        bound rests on ``xi*`` alone; None where it cannot be (a certificate without
        a searched reference design, or one over a pool, or a plan that does not identify
        the model as it is).  Its plan-only bound is not searched: 0."""
        q = np.asarray(q, dtype=float)
        if self.pool_size is not None or self.reference_d_efficiency <= 0.0:
            return None
        if identifying(model, model.plan_conditions(q)) is not model:
            return None
        p = model.n_free
        logdet_plan = float(model.plan_information(q).svd().log_det_gram())
        logdet_star = p * float(np.log(self.reference_d_efficiency))
        kw = float(np.exp((logdet_plan - logdet_star) / p + 1.0 - self.max_variance / p))
        hadamard = float(np.exp(logdet_plan / p)) if model.information_bound else 0.0
        return replace(
            self, certified_d_efficiency=float(min(1.0, max(kw, hadamard))), plan_only_bound=0.0
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
    bounded: bool = False,
) -> np.ndarray:
    """Batched ascent of ``d(x)`` from ``starts (k, n)`` within the limits (near the view);
    over the poses that meet the instrument where a pose must, or where ``bounded`` asks
    (a turn's range: :attr:`~armcal.models.interface.DesignEffort.bounded`): within its
    view where that is a region with an inside
    (:func:`~armcal.doe.constrained.bounded_ascent`, a camera's image), else on the thin
    set of poses that meet it (:func:`~armcal.doe.constrained.projected_ascent`)."""
    if model.constrained or bounded:

        def variance(q: np.ndarray, gradient: bool) -> tuple[np.ndarray, np.ndarray | None]:
            if gradient:
                return _variance_function(model, q, m_inv)
            return variances(_pose_blocks(model, q), m_inv), None

        ascent = bounded_ascent if model.has_view else projected_ascent
        return ascent(model, variance, starts, steps=2 * steps)

    def objective(u: np.ndarray, step: int):
        q, dq_du = to_q(model, u)
        value, grad = _variance_function(model, q, m_inv)
        penalty, grad_pen = view_penalty(model, q[:, None, :])
        weight = penalty_weight(model, step / steps) * 1e3
        return value - weight * penalty, (grad - weight * grad_pen[:, 0]) * dq_du

    u, _ = adam_ascent(
        objective, to_u(model, starts), steps=steps, learning_rate=0.05, progress=progress
    )
    return _newton_polish(model, m_inv, to_q(model, u)[0])


#: Newton iterations that finish every ascent, and the step of the central differences
#: of the analytic gradient that give their Hessian (rad; truncation ~1e-10 of it).
POLISH_ITERATIONS, POLISH_STEP = 3, 1e-5


def _newton_polish(model: FitModel, m_inv: np.ndarray, q: np.ndarray) -> np.ndarray:
    """Ascent ends ``q`` ``(k, n)`` taken to their local maxima of ``d`` to round-off:
    Adam's last steps are small but not zero, and the bound needs the maximum itself.

    Newton's step ``-H^-1 g`` with ``H`` from central differences of the analytic
    gradient (all ``2 n`` shifts of every pose in one batch), its eigenvalues held at
    most ``-1e-9 |H|`` (a direction in which ``d`` does not change, such as joint 1 of
    an arm measured in its own frame, takes no step); within the limits, and kept only
    where ``d`` grows and the pose stays feasible."""
    k, n = q.shape
    lower, upper = model.joint_limits[:, 0], model.joint_limits[:, 1]
    value, grad = _variance_function(model, q, m_inv)
    shifts = POLISH_STEP * np.eye(n)
    for _ in range(POLISH_ITERATIONS):
        shifted = np.concatenate([q[:, None, :] + shifts, q[:, None, :] - shifts], axis=1)
        _, around = _variance_function(model, shifted.reshape(-1, n), m_inv)
        around = around.reshape(k, 2, n, n)
        hessian = (around[:, 0] - around[:, 1]) / (2 * POLISH_STEP)  # [k, j, :] = d g / d q_j
        hessian = (hessian + np.swapaxes(hessian, -1, -2)) / 2
        values, vectors = np.linalg.eigh(hessian)
        floor = 1e-9 * np.abs(values).max(axis=-1, keepdims=True)
        values = np.minimum(values, -floor)
        step = -np.einsum("kij,kj,klj,kl->ki", vectors, 1 / values, vectors, grad)
        trial = np.clip(q + step, lower, upper)
        trial_value, trial_grad = _variance_function(model, trial, m_inv)
        better = (trial_value > value) & model.feasible(trial[:, None, :])[:, 0]
        q = np.where(better[:, None], trial, q)
        value = np.where(better, trial_value, value)
        grad = np.where(better[:, None], trial_grad, grad)
    return q


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
    corners = corners[model.feasible(corners[:, None, :])[:, 0]]
    moved, met = model.meeting_poses(corners)  # where a pose must meet the instrument
    return moved[met]


def _weighted_svd(blocks: np.ndarray, weights: np.ndarray) -> ScaledSVD:
    """The rank policy's SVD of ``M(xi) = sum_x w_x I(x)``, from its square-root factor.

    Rows ``sqrt(w_x) F_x`` (``F_x`` the poses' scaled blocks, :func:`_pose_blocks`) have
    Gram matrix ``M(xi)``: its inverse and ``log det`` come from singular values, not
    from inverting ``M``.
    """
    weighted = blocks * np.sqrt(weights)[:, None, None]
    return scaled_svd(weighted.reshape(-1, blocks.shape[-1]))


#: Ascents of the variance function per search, from the poses where it is largest: a
#: few ascents from the best points of the sample, not many from random ones.
ASCENT_STARTS = 32

#: The starts are chosen among this many times :data:`ASCENT_STARTS` of the best poses, at
#: least :data:`SPREAD_RAD` apart (:func:`_spread_starts`).
SPREAD_POOL = 8
SPREAD_RAD = 0.5

#: Adam steps of every ascent (:func:`_maximize_variance`); the last search of a
#: certificate takes twice as many, its maximum being the one the bound rests on.
ASCENT_STEPS = 60

#: The weighted design's tolerance (:func:`~armcal.doe.weights.newton_weights`): its
#: candidates are few (the plan's poses, the sample's best, the ascents' maxima), so
#: Newton's method takes it to the optimum over them.
REFERENCE_TOLERANCE = 1e-6

#: The plan's share of the weighted design's starting weights (the other candidates share
#: the rest).
PLAN_SHARE = 0.9

#: Weights below this share of the largest are dropped from the reference design before
#: its bound is computed: the design reported is the one certified, and it stays short.
SMALLEST_WEIGHT = 1e-3


@dataclass(frozen=True, eq=False)
class _Poses:
    """Poses ``(k, n)`` and their scaled blocks ``(k, r, p)`` (:func:`_pose_blocks`),
    computed once and searched with every variance function."""

    q: np.ndarray
    blocks: np.ndarray

    def __add__(self, other: _Poses) -> _Poses:
        return _Poses(
            np.concatenate([self.q, other.q]), np.concatenate([self.blocks, other.blocks])
        )

    def take(self, index: np.ndarray) -> _Poses:
        return _Poses(self.q[index], self.blocks[index])


def _poses(model: FitModel, q: np.ndarray) -> _Poses:
    return _Poses(q, _pose_blocks(model, q))


@dataclass(frozen=True, eq=False)
class _Maximum:
    """``max d`` over a sample and the ascents from its best poses: the value, where, and
    the poses the ascents found."""

    value: float
    pose: np.ndarray
    found: _Poses
    sample_values: np.ndarray  # d over the sample searched


def _search_maximum(
    model: FitModel,
    m_inv: np.ndarray,
    sample: _Poses,
    *,
    steps: int,
    progress: ProgressCallback | None,
    starts: int = ASCENT_STARTS,
    bounded: bool = False,
) -> _Maximum:
    """``max_x d(x)`` over ``sample`` (its blocks, no kinematics) and over ascents from its
    ``starts`` largest values (:func:`_spread_starts`); ascent iterates that stray outside
    the view by more than 1e-3 mm do not count.  ``bounded``: a bound rests on this
    maximum, so a model whose effort asks it keeps to its view step by step
    (:attr:`~armcal.models.interface.DesignEffort.bounded`)."""
    d = variances(sample.blocks, m_inv)
    first = sample.q[_spread_starts(sample.q, d, starts)]
    step_by_step = bounded and model.design_effort.bounded
    found = _poses(
        model,
        _maximize_variance(
            model, m_inv, first, steps=steps, progress=progress, bounded=step_by_step
        ),
    )
    d_found = variances(found.blocks, m_inv)
    constraints = model.view_constraints(found.q[:, None, :])
    if constraints is not None:  # count iterates that stray outside only a little
        d_found = np.where(constraints[0].min(axis=(-2, -1)) > -1e-3, d_found, -np.inf)
    if d.max() >= d_found.max():
        return _Maximum(float(d.max()), sample.q[int(np.argmax(d))], found, d)
    return _Maximum(float(d_found.max()), found.q[int(np.argmax(d_found))], found, d)


def _spread_starts(q: np.ndarray, d: np.ndarray, count: int = ASCENT_STARTS) -> np.ndarray:
    """``count`` poses of ``q`` where ``d`` is largest, spread over its hills:
    best first, a pose of the :data:`SPREAD_POOL` best taken only if it lies at least
    :data:`SPREAD_RAD` (largest joint difference) from every pose taken, the rest of the
    count filled by the best left.  The best points of a sample crowd on one hill, and
    ascents from them all climb it: a dense search found another, higher one (the
    industrial arm with three reflectors, 33.040 against 33.019)."""
    order = np.argsort(-d)
    pool = order[: SPREAD_POOL * count]
    taken: list[int] = []
    for i in pool:
        if len(taken) == count:
            break
        if not taken or np.min(np.max(np.abs(q[taken] - q[i]), axis=-1)) >= SPREAD_RAD:
            taken.append(int(i))
    chosen = set(taken)
    left = [int(i) for i in order[: 2 * count] if int(i) not in chosen]
    return np.array(taken + left[: count - len(taken)], dtype=int)


def _trimmed(blocks: np.ndarray, weights: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The weights without those below :data:`SMALLEST_WEIGHT` of the largest (sum 1) and
    ``M`` of what is left."""
    weights = np.where(weights >= SMALLEST_WEIGHT * weights.max(), weights, 0.0)
    weights /= weights.sum()
    kept = weights > 0
    return weights, information(blocks[kept], weights[kept])


def _reference_design(
    model: FitModel,
    candidates: _Poses,
    sample: _Poses,
    start: np.ndarray,
    rounds: int,
    parts: list[ProgressCallback | None],
    last_starts: int,
) -> tuple[_Poses, np.ndarray, np.ndarray, _Maximum]:
    """A near-D-optimal weighted design ``xi*`` over ``candidates``, refined ``rounds`` times
    by the maximizers of its variance function, and that function's maximum: its support,
    weights, information ``M(xi*)`` and :class:`_Maximum`; the first ``len(start)``
    candidates are the plan's distinct poses, ``start`` their share of it.  The last search
    (twice the steps, ``last_starts`` ascents) is of the design returned, so the bound uses
    the maximum of the very weights reported."""
    # Start from the plan (its poses lead the candidates, at its own weights): near the
    # optimum already, where the multiplicative algorithm is slow to arrive from uniform.
    weights = np.full(
        candidates.q.shape[0], (1 - PLAN_SHARE) / (candidates.q.shape[0] - len(start))
    )
    weights[: len(start)] = PLAN_SHARE * start
    for round_ in range(rounds):
        weights, star = _trimmed(
            candidates.blocks,
            newton_weights(candidates.blocks, weights, tolerance=REFERENCE_TOLERANCE).weights,
        )
        last = round_ == rounds - 1
        maximum = _search_maximum(
            model,
            spd_inverse(star),
            candidates + sample,
            steps=ASCENT_STEPS * (2 if last else 1),
            progress=parts[1 + round_],
            starts=last_starts if last else ASCENT_STARTS,
            bounded=last,  # the search the bound rests on
        )
        if last:
            kept = weights > 0
            return candidates.take(np.flatnonzero(kept)), weights[kept], star, maximum
        feasible = model.feasible(maximum.found.q[:, None, :])[:, 0]
        candidates = candidates + maximum.found.take(np.flatnonzero(feasible))
        weights = np.concatenate([weights, np.zeros(int(np.count_nonzero(feasible)))])
    raise AssertionError("a reference design takes at least one round")


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
        Poses of the sample where the plan's variance function is largest that join
        the weighted (approximate) design's candidates.
    rounds : int, optional
        Rounds of adding the maximizers of the variance function to the candidates.
    search : int, optional
        Random feasible poses of the sample: every variance function is evaluated on
        them (their blocks computed once) and ascended from the best of them.

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
    ``xi*`` comes from Newton's method on the simplex
    (:func:`~armcal.doe.weights.newton_weights`, started from the plan) on the
    plan's poses, the sample's poses where the plan is least informed and the
    maximizers of the plan's ``d``, refined by adding the maximizers of its own.
    Every ``max_x d`` is the sample's (its blocks computed once) and that of
    :data:`ASCENT_STARTS` ascents from its largest values; the last one, on which the
    bound rests, takes twice the steps.  Ascent iterates that stray slightly
    outside the region only raise the maximum, which keeps the bound safe.
    Weights below :data:`SMALLEST_WEIGHT` of the largest are dropped before the
    bound is computed: the design reported is the one certified.
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
    candidates = effort.reference if candidates is None else candidates
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
    parts = [share(progress, k / (rounds + 1), (k + 1) / (rounds + 1)) for k in range(rounds + 1)]
    # The sample's blocks, once: every variance function below is searched on them first.
    sample = _poses(
        model,
        np.concatenate(
            [distinct, _corner_poses(model, rng), feasible_poses(model, search, rng=rng)]
        ),
    )
    plan_max = _search_maximum(  # a bound rests on it: the plan-only one
        model, plan_inverse, sample, steps=2 * ASCENT_STEPS, progress=parts[0], bounded=True
    )
    logdet_plan = float(plan.log_det_gram())
    plan_only = np.exp(1.0 - plan_max.value / p)
    hadamard = np.exp(logdet_plan / p) if bounded else 0.0
    if plan_only >= CLOSE_ENOUGH:  # the plan is its own reference design
        return Certificate(
            certified_d_efficiency=float(min(1.0, max(plan_only, hadamard))),
            plan_only_bound=float(plan_only),
            reference_d_efficiency=float(np.exp(logdet_plan / p)),
            max_variance=plan_max.value,
            max_pose=plan_max.pose,
            support=distinct,
            weights=counts / q.shape[0],
        )
    # The weighted design's candidates: the plan's poses, where its variance function is
    # largest in the sample, and where the ascents found it largest.
    largest = np.argsort(-plan_max.sample_values)[:candidates]
    others = np.setdiff1d(largest, np.arange(distinct.shape[0]))
    best = np.concatenate([np.arange(distinct.shape[0]), others])
    support, weights, star, star_max = _reference_design(
        model,
        sample.take(best) + plan_max.found,
        sample,
        counts / q.shape[0],
        rounds,
        parts,
        effort.last_starts or ASCENT_STARTS,
    )
    sign, logdet_star = np.linalg.slogdet(star)
    kw = 0.0
    if sign > 0:  # not expected otherwise (xi* is near D-optimal); the other bounds hold
        kw = float(np.exp((logdet_plan - logdet_star) / p + 1.0 - star_max.value / p))
    return Certificate(
        certified_d_efficiency=float(min(1.0, max(kw, plan_only, hadamard))),
        plan_only_bound=float(plan_only),
        reference_d_efficiency=float(np.exp(logdet_star / p)) if sign > 0 else 0.0,
        max_variance=star_max.value,
        max_pose=star_max.pose,
        support=support.q,
        weights=weights,
    )


def certify_pool(
    model: FitModel,
    q: np.ndarray,
    pool: np.ndarray,
    *,
    blocks: np.ndarray | None = None,
    weights: np.ndarray | None = None,
) -> Certificate:
    """Certify a plan taken from ``pool`` against the best design over the pool's poses.

    Parameters
    ----------
    model : FitModel
    q : ndarray, shape (m, n)
        The plan (rad), every pose a pose of ``pool``; must identify every parameter.
    pool : ndarray, shape (N, n)
        The candidate poses (rad) a plan may take (a cell's collision-free poses).
    blocks : ndarray, shape (N, r, p_f), optional
        The pool's information blocks (:meth:`PlanInformation.blocks`) where the
        caller has them (the pool's design computed them).
    weights : ndarray, shape (N,), optional
        Weights the caller found on the pool (the pool's design): the weighted design
        starts from them.

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
    (:func:`~armcal.doe.weights.optimal_weights`, from the pool design's own where
    given; any weights give a valid bound, better ones a tighter), without those below
    :data:`SMALLEST_WEIGHT` of the largest: the design reported is the one certified.
    The plan is a design over the pool too: its own bound
    ``exp(1 - max_x d(x, plan) / p)``.  Where every design has ``det M <= 1``
    (:attr:`~armcal.models.interface.FitModel.information_bound`) so has the pool's
    best, and ``det M_plan^(1/p)`` is a bound as well.
    """
    q = np.asarray(q, dtype=float)
    pool = np.asarray(pool, dtype=float)
    prepared = identifying(model, model.plan_conditions(q))  # a spatial arm as loaded
    if prepared is not model:  # the caller's blocks are of other columns
        blocks = weights = None
    model, p = prepared, prepared.n_free
    plan_information = model.plan_information(q)
    plan_information.check_identifiable()
    plan = plan_information.svd()
    logdet_plan = float(plan.log_det_gram())
    plan_inverse, _ = plan.inverse_gram()
    if blocks is None:
        blocks = pool_blocks(model, pool)
    scaled = blocks / np.sqrt(plan_information.rows_per_pose)  # the plan's normalization
    plan_only = float(np.exp(1.0 - variances(scaled, plan_inverse).max() / p))
    found = optimal_weights(scaled, weights)
    weights, star = _trimmed(scaled, found.weights)
    d_star = variances(scaled, spd_inverse(star))  # exact over the pool: no search
    kept = np.flatnonzero(weights > 0)
    logdet_star = float(np.linalg.slogdet(star)[1])
    kw = float(np.exp((logdet_plan - logdet_star) / p + 1.0 - d_star.max() / p))
    hadamard = float(np.exp(logdet_plan / p)) if model.information_bound else 0.0
    return Certificate(
        certified_d_efficiency=float(min(1.0, max(kw, plan_only, hadamard))),
        plan_only_bound=plan_only,
        reference_d_efficiency=float(np.exp(logdet_star / p)),
        max_variance=float(d_star.max()),
        support=pool[kept],
        weights=weights[kept],
        max_pose=pool[int(np.argmax(d_star))],
        pool_size=int(np.unique(pool, axis=0).shape[0]),
    )
