"""Plain-numpy floors of ``armcal design`` on a six-axis arm: from a pool, and without one.

What a competent engineer would write with numpy alone to choose ``m`` poses for a
calibration and bound how good they are, on the arm of :mod:`floors_spatial` (its
config, kinematics and Jacobian: the same parameters armcal identifies, the same
whitened rows, every target of every pose):

* **from a pool** (``design --candidates POOL``): every pool pose's blocks, the
  D-optimal weights by the multiplicative algorithm (Silvey et al.'s exponent 4, to
  ``max d <= 1.003 p``), the ``m`` poses of largest weight, Mitchell's DETMAX, and the
  Kiefer-Wolfowitz bound over the pool (exact: a finite set), the work armcal's
  pool design does;
* **without a pool** (``design``): numpy has no optimizer over joint angles, so the
  floor is the same pool design on ``count`` poses uniform within the limits: what
  the open tools do, and what a free design must beat, in quality and near in cost.

Each prints a JSON with its certified efficiency and the ``log det`` of its plan's
normalized information; ``bench_design_floor.py`` compares plans by ``log det`` in these
same coordinates (a ratio of determinants does not depend on the basis).

Usage::

    python benchmarks/floors_design.py pool CONFIG POOL_CSV M OUT_CSV
    python benchmarks/floors_design.py free CONFIG M COUNT SEED OUT_CSV
"""

from __future__ import annotations

import sys

import numpy as np
from floors_spatial import Arm, dumps, kinematics, load_config, read_plan, rows_of_plan


def design_blocks(arm: Arm, q: np.ndarray) -> np.ndarray:
    """Every pose's whitened free columns, all its targets' rows: ``(N, 3 k, p_f)``."""
    free = np.flatnonzero(arm.free)
    rows, target = rows_of_plan(arm, q)
    kin = kinematics(arm, rows, target, arm.nominal(), columns=free)
    assert kin.columns is not None
    return kin.columns.reshape(q.shape[0], -1, free.size) / arm.sigma


def pose_variances(blocks: np.ndarray, m_inv: np.ndarray) -> np.ndarray:
    """``tr(M^-1 F_x^T F_x)`` of every pose ``(N,)``."""
    rows = blocks.reshape(-1, blocks.shape[-1])
    return np.sum((rows @ m_inv) * rows, axis=1).reshape(blocks.shape[0], -1).sum(axis=1)


def weighted(blocks: np.ndarray, weights: np.ndarray) -> np.ndarray:
    rows = blocks.reshape(-1, blocks.shape[-1])
    return rows.T @ (rows * np.repeat(weights, blocks.shape[1])[:, None])


def d_optimal_weights(blocks: np.ndarray, tolerance: float = 3e-3) -> np.ndarray:
    """The multiplicative algorithm (Silvey et al.'s exponent 4) until ``max d <= p (1 +
    tolerance)``, at most 300 updates: the weights of the lowest ``log det M + max d``."""
    count, _, p = blocks.shape
    w = np.full(count, 1.0 / count)
    best, best_gap = w, np.inf
    for _ in range(301):
        information = weighted(blocks, w)
        d = pose_variances(blocks, np.linalg.inv(information))
        gap = np.linalg.slogdet(information)[1] + d.max()
        if gap < best_gap:
            best, best_gap = w, gap
        if d.max() <= p * (1 + tolerance):
            break
        w = w * (d / p) ** 4
        w /= w.sum()
    return best


def detmax(blocks: np.ndarray, chosen: list[int]) -> list[int]:
    """Mitchell's DETMAX, excursions of one pose: add the pose of largest variance, drop
    the one whose removal costs least, until the pose added is the one dropped."""
    m = len(chosen)
    for _ in range(2000):
        plan = blocks[chosen].reshape(-1, blocks.shape[-1])
        information = plan.T @ plan
        added = int(np.argmax(pose_variances(blocks, np.linalg.inv(information))))
        grown = np.linalg.inv(information + blocks[added].T @ blocks[added])
        members = [*chosen, added]
        rows = blocks[members]
        keep = np.eye(rows.shape[1]) - rows @ grown @ np.swapaxes(rows, -1, -2)
        sign, logdet = np.linalg.slogdet(keep)
        dropped = int(np.argmax(np.where(sign > 0, logdet, -np.inf)))
        if dropped == m or members[dropped] == added:
            break
        chosen = [i for j, i in enumerate(members) if j != dropped]
    return chosen


def pool_design(arm: Arm, pool: np.ndarray, m: int, out: str) -> None:
    """A plan of ``m`` poses from ``pool`` and its certificate over the pool: weights, the
    ``m`` largest, DETMAX, then the Kiefer-Wolfowitz bound ``(det M_plan / det M(w))^(1/p)
    exp(1 - max d / p)`` and the plan-only bound, exact over the pool; the plan's
    ``log det`` of its normalized information, what a comparison with armcal's needs."""
    blocks = design_blocks(arm, pool)
    p = blocks.shape[-1]
    weights = d_optimal_weights(blocks)
    chosen = detmax(blocks, [int(i) for i in np.argsort(-weights)[:m]])
    plan = blocks[chosen].reshape(-1, p)
    plan_m = plan.T @ plan / (m * len(arm.targets))
    star = weighted(blocks, weights) / len(arm.targets)
    logdet_plan, logdet_star = np.linalg.slogdet(plan_m)[1], np.linalg.slogdet(star)[1]
    d_star = pose_variances(blocks, np.linalg.inv(star)) / len(arm.targets)
    d_plan = pose_variances(blocks, np.linalg.inv(plan_m)) / len(arm.targets)
    kw = np.exp((logdet_plan - logdet_star) / p + 1 - d_star.max() / p)
    names = ",".join(f"q{j + 1}_deg" for j in range(pool.shape[1]))
    np.savetxt(out, np.degrees(pool[chosen]), delimiter=",", header=names, comments="", fmt="%.9f")
    doc = {
        "certified_d_efficiency": float(min(1.0, max(kw, np.exp(1 - d_plan.max() / p)))),
        "log_det": float(logdet_plan),
    }
    print(dumps(doc))


def design_from_pool(arm: Arm, pool: str, m: str, out: str) -> None:
    """``design --candidates POOL``: :func:`pool_design` on the file's poses."""
    pool_design(arm, read_plan(arm, pool), int(m), out)


def design_free(arm: Arm, m: str, count: str, seed: str, out: str) -> None:
    """``design`` without a pool: what numpy alone would do, :func:`pool_design` on
    ``count`` poses uniform within the limits (``default_rng(seed)``)."""
    lo, hi = arm.limits[:, 0], arm.limits[:, 1]
    pool = np.random.default_rng(int(seed)).uniform(lo, hi, (int(count), lo.size))
    pool_design(arm, pool, int(m), out)


FLOORS = {"pool": design_from_pool, "free": design_free}

if __name__ == "__main__":
    FLOORS[sys.argv[1]](load_config(sys.argv[2]), *sys.argv[3:])
