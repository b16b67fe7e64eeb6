"""D-optimal weights over a finite set of poses, from their information blocks.

A weighted design ``xi`` puts weight ``w_x`` on pose ``x``; its normalized
information is ``M(xi) = sum_x w_x F_x^T F_x`` for every pose's real blocks
``F_x`` ``(r, p)`` (``r`` rows: every target, every coordinate), and its
variance function ``d(x, xi) = tr(M(xi)^-1 F_x^T F_x)``.  The D-optimal weights
have ``max_x d = p`` (Kiefer-Wolfowitz), and any weights give the bound
``log det M* <= log det M(xi) + max_x d(x, xi) - p`` used by the certificates.

* :func:`variances` -- ``d(x, xi)`` of every pose, as matrix products;
* :func:`multiplicative_weights` -- the multiplicative algorithm, a fixed number
  of iterations on every pose;
* :func:`optimal_weights` -- the same algorithm run to a tolerance, keeping the
  weights of the tightest bound;
* :func:`newton_weights` -- Newton's method on the simplex, for a few hundred
  candidates, where the multiplicative algorithm is slow near the optimum.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..numerics import spd_inverse

__all__ = [
    "POWER",
    "TOLERANCE",
    "OptimalWeights",
    "information",
    "multiplicative_weights",
    "newton_weights",
    "optimal_weights",
    "variances",
]


#: Rows of blocks :func:`variances` multiplies at a time: its temporaries stay about
#: ``VARIANCE_ROWS p`` numbers (a certificate's 20 000 photos of 96 rows each, p = 42:
#: two temporaries of 650 MB at once before).
VARIANCE_ROWS = 1 << 16


def variances(blocks: np.ndarray, m_inv: np.ndarray) -> np.ndarray:
    """``d(x) = tr(m_inv F_x^T F_x)`` ``(N,)`` of blocks ``(N, r, p)``: matrix products of
    the stacked rows, not a three-operand contraction, a few thousand poses at a time."""
    count, per_pose, p = blocks.shape
    rows = blocks.reshape(-1, p)
    out = np.empty(rows.shape[0])
    step = max(1, VARIANCE_ROWS // per_pose) * per_pose  # whole poses
    for start in range(0, rows.shape[0], step):
        part = rows[start : start + step]
        out[start : start + step] = np.sum((part @ m_inv) * part, axis=1)
    return out.reshape(count, per_pose).sum(axis=1)


def information(blocks: np.ndarray, weights: np.ndarray) -> np.ndarray:
    """``M = sum_x w_x F_x^T F_x`` ``(p, p)`` of blocks ``(N, r, p)``: one matrix product of
    the stacked rows."""
    rows = blocks.reshape(-1, blocks.shape[-1])
    return rows.T @ (rows * np.repeat(weights, blocks.shape[1])[:, None])


def multiplicative_weights(
    blocks: np.ndarray, weights: np.ndarray, iterations: int, *, power: float = 1.0
) -> np.ndarray:
    """Multiplicative algorithm for D-optimal weights (Titterington 1976; Silvey et al. 1978):
    ``w_x <- w_x (d(x) / p)^power``.  ``power`` 1 never decreases ``det M``; Silvey et al.'s
    larger powers take fewer iterations to the same optimum, without that guarantee.

    ``M(xi)`` stays positive definite: the pool holds the (identifiable) plan's
    own poses or the support of an earlier positive definite design, and every
    weight stays positive.  The inverse is
    :func:`~armcal.numerics.spd_inverse`, which cannot raise whatever round-off does.
    """
    p = blocks.shape[-1]
    for _ in range(iterations):
        d = variances(blocks, spd_inverse(information(blocks, weights)))
        weights = weights * (d / p) ** power
        weights /= weights.sum()
    return weights


@dataclass(frozen=True, eq=False)
class OptimalWeights:
    """Near D-optimal weights over a finite set of poses.

    Attributes
    ----------
    weights : ndarray, shape (N,)
        Every pose's weight (sum 1).
    m_inv : ndarray, shape (p, p)
        ``M(xi)^-1`` of the weights.
    variances : ndarray, shape (N,)
        ``d(x, xi)`` of every pose: its maximum is the exact maximum over the set,
        what the Kiefer-Wolfowitz bound needs.
    iterations : int
        Multiplicative updates made.
    """

    weights: np.ndarray
    m_inv: np.ndarray
    variances: np.ndarray
    iterations: int

    @property
    def max_variance(self) -> float:
        return float(self.variances.max())


#: Silvey et al.'s exponent for :func:`optimal_weights`: on a six-axis arm's pool of 10^4
#: poses (33 free parameters, three targets) exponent 4 reaches ``max d <= 1.003 p`` in 50
#: updates where 2 takes 99; 8 oscillates and never gets there.
POWER = 4.0

#: Relative excess of ``max d`` over ``p`` at which :func:`optimal_weights` stops: the
#: weights' D-efficiency is then at least ``exp(-0.003)`` (Kiefer-Wolfowitz), so a
#: certificate built on them is within 0.3 % of the one the optimal weights would give.
TOLERANCE = 3e-3


def optimal_weights(
    blocks: np.ndarray,
    weights: np.ndarray | None = None,
    *,
    tolerance: float = TOLERANCE,
    iterations: int = 300,
    power: float = POWER,
) -> OptimalWeights:
    """The multiplicative algorithm on ``blocks`` ``(N, r, p)`` until ``max d <= p (1 +
    tolerance)``, or ``iterations`` updates: the weights of the tightest bound met.

    Parameters
    ----------
    blocks : ndarray, shape (N, r, p)
        Every pose's information blocks; together of rank ``p``.
    weights : ndarray, shape (N,), optional
        Starting weights (default uniform); a pose of weight 0 starts at the
        smallest positive weight, so that every pose stays a candidate.
    tolerance, iterations, power : float, int, float
        See :data:`TOLERANCE` and :data:`POWER`.

    Notes
    -----
    With an exponent above 1 an update may lower ``det M``; any weights give a valid
    Kiefer-Wolfowitz bound, and the weights kept are those of the lowest upper
    bound ``log det M + max d - p`` on ``log det M*``: the tightest bound of those seen.
    An update that lowers ``det M`` is made again with exponent 1, which never does
    (Titterington 1976): on rank-1 blocks (one reading a pose, a plane's touches)
    exponent 4 alone oscillated and never came within 8.9 p of the optimum in 3000
    updates, where this reaches ``max d <= 1.003 p`` in 237 (2540 touches, p = 26).
    Each update costs two products of the ``N r`` stacked rows with ``p`` columns: no
    ``(N, p, p)`` intermediate.
    """
    count, _, p = blocks.shape
    w = np.full(count, 1.0 / count) if weights is None else np.array(weights, dtype=float)
    positive = w > 0
    w = np.where(positive, w, w[positive].min() if positive.any() else 1.0)
    w /= w.sum()
    goal = p * (1 + tolerance)
    best: OptimalWeights | None = None
    best_gap = np.inf
    before, last, last_d = -np.inf, w, np.ones(count)
    for done in range(iterations + 1):
        gram = information(blocks, w)
        sign, logdet = np.linalg.slogdet(gram)
        logdet = logdet if sign > 0 else -np.inf
        if logdet < before and power != 1.0:  # the exponent overshot: exponent 1 instead
            w = _updated(last, last_d, p, 1.0)
            gram = information(blocks, w)
            sign, logdet = np.linalg.slogdet(gram)
            logdet = logdet if sign > 0 else -np.inf
        m_inv = spd_inverse(gram)
        d = variances(blocks, m_inv)
        # log det M + max d - p bounds log det M* from above (Kiefer-Wolfowitz): keep the
        # weights of the lowest bound, which a certificate then divides by.
        gap = logdet + d.max()
        if best is None or gap < best_gap:
            best, best_gap = OptimalWeights(w, m_inv, d, done), gap
        if d.max() <= goal or done == iterations:
            break
        before, last, last_d = logdet, w, d
        w = _updated(w, d, p, power)
    assert best is not None
    return best


def _updated(w: np.ndarray, d: np.ndarray, p: int, power: float) -> np.ndarray:
    """One multiplicative update of the weights ``w`` with variances ``d``."""
    out = w * (d / p) ** power
    return out / out.sum()


#: Where :func:`newton_weights` hands over from the multiplicative algorithm: ``max d <=
#: 1.01 p``; from a plan's weights mixed with 112 candidates (a six-axis arm, p = 33) its
#: projected steps then reach ``max d <= p (1 + 1e-6)`` in 5 iterations.
NEWTON_START = 1e-2


def _weight_hessian(blocks: np.ndarray, m_inv: np.ndarray) -> np.ndarray:
    """``H_xy = ||F_x M^-1 F_y^T||_F^2`` ``(A, A)`` of blocks ``(A, r, p)``, the cheaper way.

    Few rows a pose (a tracker's 3): the squares of the rows' cross products, ``(A r)^2
    p`` work.  Many (a photo's 96 corner coordinates, more than ``sqrt(p)``): with ``M^-1
    = L L^T``, ``H_xy = tr(M^-1 G_x M^-1 G_y) = <S_x, S_y>`` for ``S_x = (F_x L)^T (F_x
    L)``, ``A r p^2 + A^2 p^2`` work and ``A p^2`` memory, not ``(A r)^2`` (a camera's 300
    candidates: 6.6 GB)."""
    count, per_pose, p = blocks.shape
    if per_pose * per_pose <= p:
        rows = blocks.reshape(-1, p)
        cross = (rows @ m_inv @ rows.T) ** 2
        return cross.reshape(count, per_pose, count, per_pose).sum(axis=(1, 3))
    values, vectors = np.linalg.eigh((m_inv + m_inv.T) / 2)
    root = vectors * np.sqrt(np.clip(values, 0.0, None))  # M^-1 = root root^T
    turned = blocks @ root  # F_x L (A, r, p)
    square = np.swapaxes(turned, -1, -2) @ turned  # S_x (A, p, p)
    flat = square.reshape(count, p * p)
    return flat @ flat.T


def _newton_step(
    blocks: np.ndarray, m_inv: np.ndarray, d: np.ndarray, active: np.ndarray, damping: float
) -> np.ndarray:
    """The damped Newton step of ``-log det M`` on the ``active`` candidates' weights, their
    sum held: ``[H + mu I, 1; 1^T, 0] [s; -lambda] = [d; 0]`` with ``H_xy = ||F_x M^-1
    F_y^T||_F^2`` and ``mu = damping`` times its mean diagonal.  ``H`` has rank at most
    ``p (p + 1) / 2`` however many candidates: the damping makes every step one along
    which ``det M`` grows, a true Newton step as it goes to 0."""
    hessian = _weight_hessian(blocks[active], m_inv)
    hessian += damping * np.trace(hessian) / active.size * np.eye(active.size)
    ones = np.ones((active.size, 1))
    system = np.block([[hessian, ones], [ones.T, np.zeros((1, 1))]])
    return np.linalg.solve(system, np.append(d[active], 0.0))[:-1]


def newton_weights(
    blocks: np.ndarray,
    weights: np.ndarray,
    *,
    tolerance: float = 1e-6,
    iterations: int = 100,
) -> OptimalWeights:
    """D-optimal weights on few candidates ``(N, r, p)`` by Newton's method on the simplex,
    from ``weights`` ``(N,)``, those of positive weight brought within
    :data:`NEWTON_START` of their optimum by :func:`optimal_weights` first.

    Notes
    -----
    ``f(w) = -log det M(w)`` has gradient ``-d`` and Hessian ``H_xy = ||F_x M^-1
    F_y^T||_F^2``.  Each iteration takes the damped Newton step (:func:`_newton_step`)
    on the *active* candidates (positive weight, or ``d > p``: those whose weight would
    grow), with their weights' sum held, projected on the simplex (a weight taken below
    0 leaves at 0); the damping grows tenfold while ``f`` does not fall, as in
    Levenberg-Marquardt, and shrinks after a step that succeeds.  It stops at ``max d <=
    p (1 + tolerance)``, the optimum by the equivalence theorem.  An iteration costs
    ``O((A r)^2 p)`` for ``A`` active candidates: for a few hundred, far less than the
    hundreds of multiplicative updates it replaces.
    """
    p = blocks.shape[-1]
    # Newton's method converges fast near the optimum, and from afar its steps leave the
    # simplex at once: the multiplicative algorithm first, to within 1 %.
    # Only on the candidates of positive weight: one of weight 0 comes in by the active set.
    w = np.asarray(weights, dtype=float) / np.sum(weights)
    started = np.flatnonzero(w > 0)
    warm = optimal_weights(blocks[started], w[started], tolerance=NEWTON_START, iterations=200)
    w = np.zeros(len(w))
    w[started] = warm.weights
    goal = p * (1 + tolerance)

    def state(w: np.ndarray) -> tuple[float, np.ndarray, np.ndarray]:
        gram = information(blocks, w)
        sign, logdet = np.linalg.slogdet(gram)
        m_inv = spd_inverse(gram)
        return (logdet if sign > 0 else -np.inf), m_inv, variances(blocks, m_inv)

    logdet, m_inv, d = state(w)
    done, damping = 0, 1e-10
    while done < iterations and d.max() > goal and damping < 1e6:
        done += 1
        active = np.flatnonzero((w > 0) | (d > p))
        step = _newton_step(blocks, m_inv, d, active, damping)
        while np.any(blocked := (w[active] == 0) & (step < 0)):  # at 0 and falling: out
            active = active[~blocked]
            step = _newton_step(blocks, m_inv, d, active, damping)
        trial = w.copy()
        trial[active] = np.maximum(w[active] + step, 0.0)  # projected: below 0 leaves
        trial /= trial.sum()
        trial_logdet, trial_inv, trial_d = state(trial)
        if trial_logdet > logdet:
            w, logdet, m_inv, d = trial, trial_logdet, trial_inv, trial_d
            damping = max(damping / 10, 1e-10)
        else:  # a shorter, steeper step (Levenberg-Marquardt)
            damping *= 10
    return OptimalWeights(w, m_inv, d, done)
