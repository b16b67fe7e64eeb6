"""Modified Fedorov exchange for the D-criterion over a candidate set of poses."""

from __future__ import annotations

import numpy as np

from ..errors import ArmcalError, action
from ..models import FitModel
from .plans import repeated_poses

__all__ = [
    "exchange_indices",
    "exchange_plan",
]


def _swap_ratios(a_xx: np.ndarray, a_xi: np.ndarray, a_ii: np.ndarray) -> np.ndarray:
    """``det M' / det M`` ``(N, m)`` of every swap, from the ``2 x 2`` blocks in closed form.

    The ratio is ``det [[A, B], [-B^T, D]]`` with ``A = I + a_xx`` (candidate ``x``,
    ``(N, 2, 2)``), ``B = a_xi`` (given as ``(N, 2, m, 2)``, ``B[x, r, i, s]``) and
    ``D = I - a_ii`` (plan pose ``i``, ``(m, 2, 2)``).  ``A = I + F_x M^-1 F_x^T``
    is positive definite with ``det A >= 1``, so the Schur complement gives
    ``det A det(D + B^T A^-1 B)``; every ``2 x 2`` inverse and determinant is
    written out, elementwise over the ``N x m`` pairs -- a few arrays of that
    size, no batched LU of ``N m`` matrices of ``4 x 4``.
    """
    a11 = 1.0 + a_xx[:, 0, 0, None]
    a12 = a_xx[:, 0, 1, None]
    a21 = a_xx[:, 1, 0, None]
    a22 = 1.0 + a_xx[:, 1, 1, None]
    det_a = a11 * a22 - a12 * a21
    b11, b12 = a_xi[:, 0, :, 0], a_xi[:, 0, :, 1]
    b21, b22 = a_xi[:, 1, :, 0], a_xi[:, 1, :, 1]
    # adj(A) B = det A * A^-1 B
    t11 = a22 * b11 - a12 * b21
    t12 = a22 * b12 - a12 * b22
    t21 = a11 * b21 - a21 * b11
    t22 = a11 * b22 - a21 * b12
    # det A * (D + B^T A^-1 B) = det A * D + B^T adj(A) B
    s11 = det_a * (1.0 - a_ii[:, 0, 0]) + b11 * t11 + b21 * t21
    s12 = det_a * (-a_ii[:, 0, 1]) + b11 * t12 + b21 * t22
    s21 = det_a * (-a_ii[:, 1, 0]) + b12 * t11 + b22 * t21
    s22 = det_a * (1.0 - a_ii[:, 1, 1]) + b12 * t12 + b22 * t22
    return (s11 * s22 - s12 * s21) / det_a


def _add_most_informative(
    blocks: np.ndarray, index: np.ndarray, count: int, ridge: np.ndarray
) -> np.ndarray:
    """``index`` and ``count`` more candidates, each the unused one adding the most information.

    Adding pose ``x`` multiplies ``det M`` by ``det(I_2 + F_x M^-1 F_x^T)``
    (``M`` with a small ridge while the poses so far do not determine it).
    """
    chosen = index.tolist()
    info = np.einsum("iap,iaq->pq", blocks[chosen], blocks[chosen])
    for _ in range(count):
        g = blocks @ np.linalg.inv(info + ridge)
        a_xx = g @ np.swapaxes(blocks, -1, -2)  # (N, 2, 2)
        gain = (1 + a_xx[:, 0, 0]) * (1 + a_xx[:, 1, 1]) - a_xx[:, 0, 1] * a_xx[:, 1, 0]
        gain[chosen] = -np.inf
        x = int(np.argmax(gain))
        chosen.append(x)
        info = info + blocks[x].T @ blocks[x]
    return np.array(chosen, dtype=np.intp)


def exchange_plan(
    model: FitModel,
    m: int,
    candidates: np.ndarray,
    *,
    start: np.ndarray | None = None,
    rng: np.random.Generator | int | None = None,
    max_swaps: int = 1000,
    distinct: bool = False,
) -> np.ndarray:
    """Modified Fedorov exchange for the D-criterion of the arm's model over a candidate set.

    One planar point per pose (its swaps are evaluated from ``2 x 2`` blocks in
    closed form): an arm with several targets is designed by :func:`optimize_plan`.

    Parameters
    ----------
    model : FitModel
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
    distinct : bool
        Take every candidate pose at most once, so that no two poses of the plan
        are equal (:func:`armcal.doe.plans.repeated_poses`; see Notes).

    Returns
    -------
    ndarray, shape (m, n)

    Raises
    ------
    ArmcalError
        If ``distinct`` and fewer than ``m`` candidates are distinct.

    Notes
    -----
    Each step makes the best swap of a plan pose ``i`` for a candidate ``x``
    over all ``(i, x)`` pairs at once.  With ``F_i, F_x`` the ``2 x p`` Jacobian
    blocks, ``M' = M - F_i^T F_i + F_x^T F_x`` and

        det M' / det M = det(I_4 + C U^T M^-1 U),  U = [F_x^T, F_i^T],  C = diag(I, -I),

    the rank-2 update formula ``det(M + F^T F) = det M det(I_2 + F M^-1 F^T)``
    applied twice; every ratio is a 4 x 4 determinant, evaluated for all pairs at
    once from its 2 x 2 blocks (:func:`_swap_ratios`).  Poses may repeat (an
    exact design may replicate a point) unless ``distinct``: then equal
    candidates count once (the start's poses first), the start's repeated poses
    are replaced one by one by the unused candidate that adds the most
    information (largest ``det(I_2 + F_x M^-1 F_x^T)``), and a swap only takes a
    candidate the plan does not hold.
    """
    targets = len(model.target_labels)
    if targets > 1:
        raise ArmcalError(
            f"exchange evaluates one point per pose, and {model.name} has "
            f"{targets} targets; use {action('method', 'optimize')} (or auto)"
        )
    rng = np.random.default_rng(rng)
    candidates = np.asarray(candidates, dtype=float)
    if start is not None:
        candidates = np.concatenate([np.asarray(start, dtype=float), candidates])
    repeated = repeated_poses(candidates) if distinct else np.zeros(len(candidates), bool)
    if distinct:
        if np.count_nonzero(~repeated) < m:
            raise ArmcalError(
                f"distinct poses: only {np.count_nonzero(~repeated)} of the candidate poses "
                f"are distinct, fewer than the {m} poses of the plan"
            )
        candidates = candidates[~repeated]
    if start is None:
        index = rng.choice(candidates.shape[0], size=m, replace=candidates.shape[0] < m)
    else:  # the start's poses, less its repeated ones (replaced below)
        index = np.arange(m)[~repeated[:m]]
    blocks = model.plan_information(candidates).blocks()  # (N, 2, p_f): a pose's information
    index = exchange_indices(blocks, index, m, max_swaps=max_swaps, distinct=distinct)
    return candidates[index]


def exchange_indices(
    blocks: np.ndarray,
    index: np.ndarray,
    m: int,
    *,
    max_swaps: int = 1000,
    distinct: bool = False,
) -> np.ndarray:
    """Modified Fedorov exchange over candidates given by their real blocks ``(N, 2, p)``.

    ``index`` holds the starting candidates (fewer than ``m`` are filled up with
    the most informative ones); returns the ``m`` chosen indices.  Every block has
    2 rows (one planar point; :func:`_swap_ratios` writes out the ``2 x 2`` blocks).  The engine of
    :func:`exchange_plan`, for any model whose candidates carry ``2 x p``
    information blocks (e.g. poses with a payload, :mod:`armcal.doe.loads`).
    """
    if blocks.shape[-2] != 2:
        raise ArmcalError(
            f"exchange evaluates one point in the plane per pose (2 rows), got {blocks.shape[-2]} "
            f"rows per pose; use {action('method', 'optimize')} (or auto)"
        )
    p = blocks.shape[-1]
    ridge = 1e-10 * np.eye(p)
    if index.size < m:
        index = _add_most_informative(blocks, index, m - index.size, ridge)
    for _ in range(max_swaps):
        design_blocks = blocks[index]  # (m, 2, p)
        info = np.einsum("iap,iaq->pq", design_blocks, design_blocks)
        m_inv = np.linalg.inv(info + ridge)
        g = blocks @ m_inv  # (N, 2, p)
        a_xx = g @ np.swapaxes(blocks, -1, -2)  # (N, 2, 2)
        # a_xi[x, r, i, s] = (F_x M^-1 F_i^T)_rs: one matrix product, (N, 2, m, 2)
        a_xi = (g.reshape(-1, p) @ design_blocks.reshape(-1, p).T).reshape(
            blocks.shape[0], 2, m, 2
        )
        a_ii = design_blocks @ m_inv @ np.swapaxes(design_blocks, -1, -2)  # (m, 2, 2)
        ratio = _swap_ratios(a_xx, a_xi, a_ii)  # (N, m)
        if distinct:
            ratio[index] = 0.0  # a candidate the plan holds: it would repeat
        x, i = np.unravel_index(int(np.argmax(ratio)), ratio.shape)
        if ratio[x, i] <= 1.0 + 1e-12:
            break
        index = index.copy()
        index[i] = x
    return index
