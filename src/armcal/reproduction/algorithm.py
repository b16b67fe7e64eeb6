"""The paper's iterative algorithm (Section III, Steps 1-5), as it is printed: Gauss-Newton.

armcal identifies with the closed form of :mod:`armcal.models.planar.closed_form`
and, for every other model, the one Gauss-Newton loop of
:mod:`armcal.identification.solvers`.  This module keeps the algorithm the paper
prints -- start from ``DeltaPi = 0``, linearize, solve (11), correct, repeat --
for the reproduction's check of it (:mod:`armcal.reproduction.equations`), in
the paper's own parametrization and batched over measurement sets.
"""

from __future__ import annotations

import numpy as np

from ..models import Conditions, PlanarArm, wrap_angle
from ..models.planar.closed_form import as_sets, link_phasors_fit, plan_factor, user_from_links

__all__ = [
    "solve_gauss_newton",
]


def _gauss_newton(
    arm: PlanarArm, v: np.ndarray, *, tol: float, max_iter: int
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Gauss-Newton iterations from zero deviations towards the fitted phasors ``v (N, p)``."""
    n = arm.n_links
    lengths = arm.link_nominal
    sets = v.shape[0]
    target = v[:, n : 2 * n] + 1j * v[:, :n]  # least-squares z_k of every set
    step_scale = np.ones(arm.n_paper)
    step_scale[:n] = lengths  # rad -> mm at the link tip
    threshold = tol * float(np.sum(arm.link_lengths))
    paper = np.zeros((sets, arm.n_paper))  # (dtheta, dl, [x0, y0]) of every set
    iterations = np.zeros(sets, dtype=int)
    failed = np.zeros(sets, dtype=bool)
    active = np.arange(sets)
    for _ in range(max_iter):
        current = paper[active]
        rotation = np.exp(1j * current[:, :n])
        length = lengths + current[:, n : 2 * n]
        # The linearized least-squares step (11): K^-1 (v_fit - v(current)), each
        # link's phasor residual turned back by dtheta_k, its normal part over L_k.
        turned = (target[active] - length * rotation) * rotation.conj()
        with np.errstate(divide="ignore", invalid="ignore"):
            d_theta = turned.imag / length
        step = np.concatenate([d_theta, turned.real, v[active, 2 * n :] - current[:, 2 * n :]], 1)
        paper[active] += step
        iterations[active] += 1
        finite = np.all(np.isfinite(step), axis=1)
        failed[active[~finite]] = True
        moving = np.max(np.abs(step * step_scale), axis=1, initial=0.0) > threshold
        active = active[finite & moving]
        if active.size == 0:
            break
    converged = ~failed
    converged[active] = False
    # The same point of the model in canonical form, as the closed form reports it:
    # (L, dtheta) and (-L, dtheta + pi) give the same link, so a negative length
    # is flipped, and joint offsets are wrapped into (-pi, pi].
    length = lengths + paper[:, n : 2 * n]
    flipped = length < 0
    dtheta = paper[:, :n] + np.pi * flipped
    dl = np.where(flipped, -length, length) - lengths
    if not arm.standard_map:
        return user_from_links(arm, dl, dtheta, paper[:, 2 * n :]), iterations, converged
    dq = wrap_angle(np.diff(dtheta, axis=-1, prepend=0.0))
    params = np.concatenate([dl, dq, paper[:, 2 * n :]], axis=-1)
    return params, iterations, converged


def solve_gauss_newton(
    arm: PlanarArm,
    q: np.ndarray,
    xy: np.ndarray,
    *,
    tol: float = 1e-12,
    max_iter: int = 50,
    target: np.ndarray | None = None,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The paper's iterative algorithm (Section III, Steps 1-5) as Gauss-Newton; batched.

    Parameters
    ----------
    arm : PlanarArm
    q : ndarray, shape (m, n)
        Joint angles in rad (shared by every measurement set).
    xy : ndarray, shape (m, 2) or (N, m, 2)
        Measured positions in mm; a leading axis holds ``N`` independent sets.
    tol : float
        A set has converged when its largest step, in mm (angles times their
        link length), is below ``tol`` times the arm's reach.
    max_iter : int
        Iteration cap; sets still moving then have ``converged = False``.
    target : ndarray of int, shape (m,), optional
        Every row's target, for an arm with several.

    Returns
    -------
    params : ndarray, shape (p,) or (N, p)
        User deviations (mm, rad).
    iterations : ndarray of int, shape () or (N,)
        Linearized solves performed for each set (paper eq. 11).
    converged : ndarray of bool, shape () or (N,)
        Whether the step tolerance was met within ``max_iter``.

    Raises
    ------
    NotIdentifiableError
        If the plan cannot identify every parameter (``check_identifiable`` of
        :mod:`~armcal.models.planar.information`).

    Notes
    -----
    Step 1 starts from ``DeltaPi = 0``; Steps 2-3 evaluate model (1) and solve the
    linearized problem (11) at the current estimate (the Jacobian (7)-(8) uses the
    corrected lengths and angles of Step 4); Step 5 repeats until the step is below
    the tolerance.

    How Step 3 is solved.  The model is linear in the link phasors: the tip is
    ``A w`` with the plan-only regressor ``A = sqrt(m) H``
    (:func:`armcal.models.scaled_jacobian`) and ``w = w(DeltaPi)``, so the
    Jacobian of a set at its estimate is ``J = A K`` with ``K = dw/dDeltaPi``
    ``(p x p)``.  Per link ``K`` is a rotation by ``dtheta_k`` times
    ``diag(L_k, 1)``: with unit-norm columns ``J D = A R`` for an orthogonal ``R``,
    so ``J D`` has the singular values of ``A`` and its SVD is that of the plan's
    triangle ``Q^T A`` (one thin QR of ``A``, shared by every set and iteration)
    turned by ``R``.  The minimum-norm least-squares step of (11) is therefore
    ``K^-1 A^+ (y - A w) = K^-1 (A^+ y - w)``: ``A^+ y`` (the rank policy's
    pseudo-inverse, ``cond(J)`` accurate, never ``cond(J)^2``) is computed once
    per set, and each iteration turns every link's phasor residual back by
    ``dtheta_k`` and divides its normal part by ``L_k`` -- the same iterates as
    forming ``J`` and solving (11), for every active set at once, with nothing
    that can raise :class:`numpy.linalg.LinAlgError`.  The residual part
    ``A^+ y - w`` is formed exactly at each iterate, so the iteration converges
    to round-off however ill-conditioned the plan: its accuracy is that of
    ``A^+ y``, the same as the closed form's.

    Examples
    --------
    >>> from armcal.models import forward_kinematics
    >>> arm = PlanarArm([2.0, 1.0])
    >>> q = np.radians([[0, 0], [0, 90], [90, 90], [45, -120]])
    >>> truth = np.array([0.1, -0.05, 0.01, -0.02])
    >>> est, iterations, converged = solve_gauss_newton(arm, q, forward_kinematics(arm, q, truth))
    >>> bool(np.allclose(est, truth, atol=1e-12)), bool(converged)
    (True, True)
    """
    batched = np.ndim(xy) == 3
    q, sets = as_sets(arm, q, xy)
    v = link_phasors_fit(plan_factor(arm, Conditions(q, target)), sets)
    params, iterations, converged = _gauss_newton(arm, v, tol=tol, max_iter=max_iter)
    if batched:
        return params, iterations, converged
    return params[0], iterations[0], converged[0]
