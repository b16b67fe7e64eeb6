"""Where the instrument stands and where the targets sit, from the data alone.

A fit of a spatial arm needs a start near the answer: the base pose in the
instrument's frame (a tracker 4 m away, turned by 120 degrees, is common) and
every target's position on the tool.  :func:`register` finds both in closed
form from the nominal arm and the measured points, with no guess from the user:

1. Every measured point is ``p_i = R (t_i + S_i a) + b``: ``(S_i, t_i)`` the
   nominal tip frame at the row's readings, ``a`` the target in the tip frame,
   ``(R, b)`` the base pose.  The product ``R S_i a`` is linear in the nine
   unknowns ``C_kl = R[:, k] a_l``, so ``(R, b, C)`` solve one linear least-squares
   problem (the lifting of bilinear registration).
2. ``R`` is projected onto the rotations (the polar factor, Arun et al. 1987),
   then ``(b, a)`` solved again with ``R`` held: linear.

Where the poses do not turn the tool enough for step 1 (its rows are rank
deficient), the targets start at their nominal positions and the rotation is
the best fit of those points (Arun's SVD), refined by alternating the two
linear steps.
"""

from __future__ import annotations

import numpy as np

from .chain import rotation_vector, vector_rotation

__all__ = [
    "REGISTER_ROWS",
    "best_rotation",
    "mean_rotation",
    "register",
    "register_turns",
    "registered_targets",
]

#: Rows a registration uses at most, evenly spaced through the data: the start of a
#: fit needs a few dozen poses, and the lifted problem costs ``O(rows)`` memory.
REGISTER_ROWS = 3000


def best_rotation(source: np.ndarray, destination: np.ndarray) -> np.ndarray:
    """The rotation ``R`` ``(d, d)`` minimizing ``sum |R s_i + b - d_i|^2`` over ``b`` too
    (points ``(m, d)``: in space, or in the plane).

    Arun, Huang and Blostein (1987), with the reflection guard.

    Examples
    --------
    >>> turn = np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])
    >>> pts = np.random.default_rng(0).normal(size=(5, 3))
    >>> bool(np.allclose(best_rotation(pts, pts @ turn.T), turn))
    True
    """
    s = source - source.mean(axis=0)
    d = destination - destination.mean(axis=0)
    return _polar(d.T @ s)


def mean_rotation(rotations: np.ndarray) -> np.ndarray:
    """The rotation ``(3, 3)`` nearest rotations ``(m, 3, 3)`` in the Frobenius norm: the
    polar factor of their sum (Moakher 2002, the chordal mean).

    Examples
    --------
    >>> turn = np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])
    >>> bool(np.allclose(mean_rotation(np.stack([turn, turn])), turn))
    True
    """
    return _polar(np.sum(rotations, axis=0))


def register_turns(
    tips: np.ndarray, seen: np.ndarray, target: np.ndarray, turns: np.ndarray
) -> np.ndarray:
    """Every measured target's orientation on the tip ``(k, 3)`` (rotation vectors): the
    mean (:func:`mean_rotation`) of ``T_i^T R_i`` over its rows, ``T_i`` ``(m, 3, 3)`` the
    tip frames and ``R_i`` the measured orientations, in the instrument's frame; the
    others keep ``turns``."""
    local = np.swapaxes(tips, -1, -2) @ seen
    out = np.array(turns, dtype=float)
    for t in np.unique(target):
        out[t] = rotation_vector(mean_rotation(local[target == t]))
    return out


def _polar(matrix: np.ndarray) -> np.ndarray:
    """The rotation nearest ``matrix`` ``(d, d)`` (its polar factor, det +1)."""
    u, _, vt = np.linalg.svd(matrix)
    flip = np.ones(matrix.shape[-1])
    flip[-1] = np.sign(np.linalg.det(u @ vt)) or 1.0
    return u @ np.diag(flip) @ vt


def _with_rotation(
    rotation: np.ndarray,
    frames: np.ndarray,
    origins: np.ndarray,
    target: np.ndarray,
    points: np.ndarray,
    k: int,
    weights: np.ndarray,
) -> tuple[np.ndarray, np.ndarray]:
    """``(b, a)`` minimizing the residual with the rotation held: one linear solve."""
    m = points.shape[0]
    a_cols = np.zeros((m, 3, 3 + 3 * k))
    a_cols[:, :, :3] = np.eye(3)
    rs = rotation @ frames  # (m, 3, 3)
    for t in range(k):
        rows = target == t
        a_cols[rows, :, 3 + 3 * t : 6 + 3 * t] = rs[rows]
    rhs = points - origins @ rotation.T
    w = np.sqrt(weights)[:, None, None]
    sol = np.linalg.lstsq(
        (w * a_cols).reshape(-1, 3 + 3 * k), (w[..., 0] * rhs).ravel(), rcond=None
    )[0]
    return sol[:3], sol[3:].reshape(k, 3)


def register(
    frames: np.ndarray,
    origins: np.ndarray,
    target: np.ndarray,
    points: np.ndarray,
    nominal_targets: np.ndarray,
    weights: np.ndarray | None = None,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The base pose and the targets' positions that best explain ``points``.

    Parameters
    ----------
    frames : ndarray, shape (m, 3, 3)
        The nominal tip frame's rotation at every row (robot base frame).
    origins : ndarray, shape (m, 3)
        The nominal tip position at every row (mm).
    target : ndarray of int, shape (m,)
        Every row's target.
    points : ndarray, shape (m, 3)
        The measured points (mm, instrument frame).
    nominal_targets : ndarray, shape (k, 3)
        Where the targets are thought to be (the fallback's start).
    weights : ndarray, shape (m,), optional
        0 leaves a row out.

    Returns
    -------
    rotation : ndarray, shape (3, 3)
    translation : ndarray, shape (3,)
    targets : ndarray, shape (k, 3)
    """
    m, k = points.shape[0], nominal_targets.shape[0]
    weights = np.ones(m) if weights is None else np.asarray(weights, dtype=float)
    if m > REGISTER_ROWS:  # a start needs no more rows; the fit uses them all
        rows = np.linspace(0, m - 1, REGISTER_ROWS).astype(int)
        frames, origins, target, points, weights = (
            frames[rows],
            origins[rows],
            target[rows],
            points[rows],
            weights[rows],
        )
        m = REGISTER_ROWS
    # Step 1: unknowns vec(R) (9, row-major), b (3), C_t (27 per target).
    n_unknown = 12 + 27 * k
    design = np.zeros((m, 3, n_unknown))
    for row in range(3):
        design[:, row, 3 * row : 3 * row + 3] = origins
        design[:, row, 9 + row] = 1.0
    for t in range(k):
        rows = target == t
        # (R S a)_r = sum_{k,l} S[k, l] C_kl[r]; C_kl stored at 12 + 27 t + 9 k + 3 l + r.
        start = 12 + 27 * t
        for kk in range(3):
            for ll in range(3):
                for r in range(3):
                    design[rows, r, start + 9 * kk + 3 * ll + r] = frames[rows, kk, ll]
    w = np.sqrt(weights)[:, None, None]
    flat = (w * design).reshape(-1, n_unknown)
    used = np.any(flat != 0, axis=0)
    sol, _, rank, _ = np.linalg.lstsq(flat[:, used], (w[..., 0] * points).ravel(), rcond=None)
    if rank == int(np.sum(used)) and used[:12].all():
        full = np.zeros(n_unknown)
        full[used] = sol
        rotation = _polar(full[:9].reshape(3, 3))
    else:
        tips = origins + np.einsum("mij,mj->mi", frames, nominal_targets[target])
        rotation = best_rotation(tips[weights > 0], points[weights > 0])
    targets = nominal_targets
    for _ in range(3 if rank == int(np.sum(used)) else 20):
        translation, targets = _with_rotation(
            rotation, frames, origins, target, points, k, weights
        )
        tips = origins + np.einsum("mij,mj->mi", frames, targets[target])
        keep = weights > 0
        rotation = best_rotation(tips[keep], points[keep])
    translation, targets = _with_rotation(rotation, frames, origins, target, points, k, weights)
    return rotation, translation, targets


def registered_targets(
    tips: np.ndarray,
    target: np.ndarray,
    points: np.ndarray,
    found: np.ndarray,
    nominal: np.ndarray,
    turns: np.ndarray,
    *,
    known: bool,
    oriented: bool,
    row_frames: np.ndarray | None,
) -> tuple[np.ndarray, np.ndarray]:
    """The targets after a registration: positions ``(k, 3)`` and turns ``(k, 3)``.

    The positions :func:`register` ``found`` for the targets the rows measure, the
    ``nominal`` ones where the robot file gives them (``known``) or no row measures
    them; for a 6-DoF instrument (``oriented``) the turns of :func:`register_turns`
    from the rows' own orientations (``points[:, 3:]``, about ``row_frames`` where
    anchored), ``tips`` ``(m, 3, 3)`` the registered tip frames; else ``turns``.
    """
    measured = np.zeros(len(nominal), dtype=bool)
    measured[np.unique(target)] = True
    positions = nominal if known else np.where(measured[:, None], found, nominal)
    if oriented:  # a 6-DoF instrument's orientations: the rows' own, in its frame
        seen = vector_rotation(points[:, 3:])
        seen = seen if row_frames is None else seen @ row_frames
        turns = register_turns(tips, seen, target, turns)
    return positions, turns
