"""Modified Fedorov exchange for the D-criterion over a candidate set of poses."""

from __future__ import annotations

import numpy as np

from ..arm import PlanarArm
from ..observability import model_columns

__all__ = [
    "exchange_plan",
]


def _blocks(arm: PlanarArm, q: np.ndarray) -> np.ndarray:
    """Real blocks ``(k, 2, p_f)`` of the model's columns of poses ``q`` ``(k, n)``.

    ``F_x^T F_x`` is the information of pose ``x`` in the model
    (:func:`armcal.observability.model_columns`: whitened, free parameters).
    """
    columns = model_columns(arm, q)
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
    """Modified Fedorov exchange for the D-criterion of the arm's model over a candidate set.

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
    eye2, p = np.eye(2), arm.n_free
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
