"""D-optimal plans restricted to a pool of poses the user knows are safe.

A cell's program often comes with poses known to be free of collision; a plan
must then take its poses from that pool.  :func:`pool_plan` works for any family
and any number of rows per pose, on the poses' information blocks:

1. the continuous D-optimal weights on the pool (the multiplicative algorithm to
   a tolerance, :func:`armcal.doe.weights.optimal_weights`), which the plan's
   certificate starts from (:class:`PoolPlan`);
2. the ``m`` poses of largest weight -- the plan of the open tools' pool method,
   where it stops;
3. an exchange from there that never lowers ``det M`` (Mitchell's DETMAX, 1974,
   with excursions of one pose): add the pool pose of largest variance
   ``d(x) = tr(M^-1 I(x))``, then drop the plan pose whose removal costs least,
   ``det(I - F_i M'^-1 F_i^T)`` largest, until the pose added is the one dropped.

:func:`detmax_indices` is step 3 alone, for any candidates' blocks (poses with
a payload, :mod:`armcal.doe.loads`, of several rows each).

Every pose of the result is a pool pose, so it satisfies whatever the pool
satisfies.  A plan of more poses than the pool holds repeats pool poses (a pose
measured twice adds its information twice); with ``distinct`` every pool pose
counts once and such a plan is refused.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import ArmcalError, action
from ..models import FitModel
from ..numerics import spd_inverse
from .plans import DISTINCT_TOLERANCE, repeated_poses
from .weights import information, multiplicative_weights, optimal_weights, variances

__all__ = [
    "BLOCK_CHUNK",
    "PoolPlan",
    "detmax_indices",
    "distinct_count",
    "pool_blocks",
    "pool_design",
    "pool_plan",
    "pool_weights_plan",
]

#: Iterations of the multiplicative algorithm for the pool's continuous design.
POOL_WEIGHT_ITERATIONS = 500

#: Exchanges at most (each adds one pose and drops one).
MAX_EXCHANGES = 2000


def _largest_weights(blocks: np.ndarray, m: int) -> np.ndarray:
    """Indices ``(m,)`` of the poses of largest continuous D-optimal weight, from the pool's
    information blocks ``(N, r, p_f)``; a pool of fewer than ``m`` poses is taken in that
    order again and again (every pose as often as the others, within one)."""
    weights = np.full(blocks.shape[0], 1.0 / blocks.shape[0])
    weights = multiplicative_weights(blocks, weights, POOL_WEIGHT_ITERATIONS)
    return np.resize(np.argsort(-weights, kind="stable"), m)


def pool_weights_plan(model: FitModel, m: int, pool: np.ndarray) -> np.ndarray:
    """Indices ``(m,)`` of the ``m`` pool poses of largest continuous D-optimal weight: the
    pool method of the open tools (a convex relaxation, then a threshold)."""
    return _largest_weights(model.plan_information(pool).blocks(), m)


def distinct_count(pool: np.ndarray) -> int:
    """How many poses of ``pool`` ``(N, n)`` are distinct: poses within
    :data:`~armcal.doe.plans.DISTINCT_TOLERANCE` rad of an earlier one on every joint
    count once (:func:`~armcal.doe.plans.repeated_poses`)."""
    return int(np.count_nonzero(~repeated_poses(np.asarray(pool, dtype=float))))


@dataclass(frozen=True, eq=False)
class PoolPlan:
    """A plan from a pool and the work behind it, which its certificate reuses.

    Attributes
    ----------
    index : ndarray of int, shape (m,)
        The plan's poses, as indices into the pool.
    blocks : ndarray, shape (N, r, p_f) or None
        Every pool pose's information blocks; None where only the distinct poses
        were used.
    weights : ndarray, shape (N,) or None
        The pool's near D-optimal weights (:func:`~armcal.doe.weights.optimal_weights`)
        that started the exchange; None with ``blocks``.
    """

    index: np.ndarray
    blocks: np.ndarray | None
    weights: np.ndarray | None


#: Poses whose information blocks are computed at once: the kinematics behind them holds
#: every parameter's screw at every row, several times the blocks' size (a six-axis arm's
#: pool of 10^4 poses peaked at 212 MB in one piece).
BLOCK_CHUNK = 1000


def pool_blocks(model: FitModel, q: np.ndarray) -> np.ndarray:
    """Every pose's information blocks ``(N, r, p_f)`` (:meth:`PlanInformation.blocks`),
    :data:`BLOCK_CHUNK` poses at a time: memory of the blocks, not of the kinematics."""
    parts = np.array_split(q, max(1, -(-q.shape[0] // BLOCK_CHUNK)))
    return np.concatenate([model.plan_information(part).blocks() for part in parts])


def pool_plan(model: FitModel, m: int, pool: np.ndarray, *, distinct: bool = False) -> np.ndarray:
    """Indices ``(m,)`` into ``pool`` ``(N, n)`` of a D-optimal ``m``-pose plan from it
    (:func:`pool_design`)."""
    return pool_design(model, m, pool, distinct=distinct).index


def pool_design(model: FitModel, m: int, pool: np.ndarray, *, distinct: bool = False) -> PoolPlan:
    """A D-optimal ``m``-pose plan from ``pool`` ``(N, n)`` (module notes); poses may repeat
    where the exchange finds a repeat best, and must where the pool holds fewer than ``m``
    poses -- unless ``distinct``: then no two poses of the plan are equal (within
    :data:`~armcal.doe.plans.DISTINCT_TOLERANCE`).

    Raises ArmcalError when the pool's poses cannot identify every free parameter, or
    ``distinct`` and the pool holds fewer than ``m`` distinct poses.
    """
    pool = np.asarray(pool, dtype=float)
    if pool.shape[0] < 1:
        raise ArmcalError("the candidate pool is empty")
    usable = ~repeated_poses(pool) if distinct else np.ones(pool.shape[0], dtype=bool)
    count = int(np.count_nonzero(usable))
    if distinct and count < m:
        raise ArmcalError(
            f"distinct poses: the {pool.shape[0]} candidate poses hold {count} distinct ones "
            f"(within {DISTINCT_TOLERANCE:g} rad on every joint), fewer than the {m} poses "
            f"asked for; use {action('poses', count)} or fewer, or give more candidates"
        )
    index = np.flatnonzero(usable)
    blocks = pool_blocks(model, pool[index])  # once: the weights and the exchange
    p = blocks.shape[-1]
    everything = information(blocks, np.ones(blocks.shape[0]))
    if np.linalg.matrix_rank(everything) < p:
        raise ArmcalError(
            f"the {pool.shape[0]} candidate poses cannot identify the {p} free parameters "
            "of " + model.name + " together; add poses that move every joint"
        )
    weights = optimal_weights(blocks).weights
    start = np.resize(np.argsort(-weights, kind="stable"), m)
    chosen = index[detmax_indices(blocks, start, distinct=distinct)]
    if distinct and count < pool.shape[0]:
        return PoolPlan(chosen, None, None)
    return PoolPlan(chosen, blocks, weights)


def detmax_indices(blocks: np.ndarray, start: np.ndarray, *, distinct: bool = False) -> np.ndarray:
    """Mitchell's DETMAX with excursions of one pose (module notes) from the ``m`` indices
    ``start`` into the candidates' information blocks ``(N, r, p_f)``, any ``r``: the
    ``m`` indices it ends with, ``det M`` never lower than the start's.  With
    ``distinct`` (a start of distinct indices) a pose the plan holds is never added."""
    chosen = [int(i) for i in start]
    m = len(chosen)
    for _ in range(MAX_EXCHANGES):
        plan = blocks[chosen]
        gram = information(plan, np.ones(m))
        inverse = spd_inverse(gram)
        variance = variances(blocks, inverse)
        if distinct:
            variance[chosen] = -np.inf
            if not np.isfinite(variance).any():  # the plan holds every candidate
                break
        added = int(np.argmax(variance))
        grown = gram + blocks[added].T @ blocks[added]
        grown_inverse = spd_inverse(grown)
        members = np.array([*chosen, added])
        rows = blocks[members]  # (m + 1, r, p)
        keep = np.eye(rows.shape[1]) - rows @ grown_inverse @ np.swapaxes(rows, -1, -2)
        sign, logdet = np.linalg.slogdet(keep)
        dropped = int(np.argmax(np.where(sign > 0, logdet, -np.inf)))
        if dropped == m or members[dropped] == added:  # the pose added would leave again
            break
        chosen = [int(i) for j, i in enumerate(members) if j != dropped]
    return np.array(chosen, dtype=int)
