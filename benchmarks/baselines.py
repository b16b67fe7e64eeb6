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
