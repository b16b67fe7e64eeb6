"""Baselines the benchmarks measure armcal against, written here without armcal.

Each is the obvious way to do the job with numpy alone, so a ratio against it
says what armcal's design buys.
"""

from __future__ import annotations

import numpy as np


def numpy_gauss_newton(
    lengths: np.ndarray, q: np.ndarray, xy: np.ndarray, *, tol: float = 1e-12, max_iter: int = 50
) -> np.ndarray:
    """The textbook Gauss-Newton on model (1): deviations ``[dl (mm), dq (rad)]``.

    Every iteration evaluates the residual and the 2m x 2n Jacobian at the
    current estimate and takes the ``numpy.linalg.lstsq`` step; it stops when
    the step, in mm at the tip, is below ``tol`` times the reach.
    """
    n = lengths.size
    theta = np.cumsum(q, axis=1)
    measured = xy[:, 0] + 1j * xy[:, 1]
    dl, dq = np.zeros(n), np.zeros(n)
    threshold = tol * lengths.sum()
    for _ in range(max_iter):
        unit = np.exp(1j * (theta + np.cumsum(dq)))  # (m, n)
        residual = measured - unit @ (lengths + dl)
        d_dtheta = 1j * unit * (lengths + dl)
        d_dq = np.cumsum(d_dtheta[:, ::-1], axis=1)[:, ::-1]  # dq_j moves links j..n
        columns = np.concatenate([unit, d_dq], axis=1)
        jac = np.concatenate([columns.real, columns.imag])
        step = np.linalg.lstsq(jac, np.concatenate([residual.real, residual.imag]), rcond=None)[0]
        dl += step[:n]
        dq += step[n:]
        if max(np.abs(step[:n]).max(), np.abs(step[n:]).max() * lengths.sum()) < threshold:
            break
    return np.concatenate([dl, dq])


def argsort_by_joint1(q: np.ndarray) -> np.ndarray:
    """The trivial order of poses ``q`` ``(m, n)``: ascending joint 1."""
    return np.argsort(q[:, 0], kind="stable")


def nearest_neighbour_order(q: np.ndarray) -> np.ndarray:
    """The plain nearest-neighbour path through poses ``q`` ``(m, n)`` from pose 0 (L1).

    Each step asks a k-d tree of the poses not yet visited for the ``k`` nearest
    (``k`` growing until one is unvisited); the tree is rebuilt when half of its
    poses have been visited, so that queries stay short.
    """
    from scipy.spatial import cKDTree

    m = q.shape[0]
    visited = np.zeros(m, dtype=bool)
    order = np.empty(m, dtype=np.intp)
    current = 0
    remaining = np.arange(m)
    tree = cKDTree(q)
    since_build = 0
    for step in range(m):
        order[step] = current
        visited[current] = True
        since_build += 1
        if step == m - 1:
            break
        if 2 * since_build > remaining.size:
            remaining = np.flatnonzero(~visited)
            tree = cKDTree(q[remaining])
            since_build = 0
        k = 8
        while True:
            k = min(k, remaining.size)
            _, found = tree.query(q[current], k=k, p=1)
            candidates = remaining[np.atleast_1d(found)]
            free = candidates[~visited[candidates]]
            if free.size:
                current = int(free[0])
                break
            k *= 4
    return order
