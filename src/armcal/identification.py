"""Identification of the deviations from measured (joint angles, position) pairs.

Two solvers reach the same least-squares optimum (paper eq. 3):

* ``"closed-form"`` (the default, ``method="auto"``): the planar model is
  *linear* in the complex link vectors ``z_k = (l_k + dl_k) exp(i dtheta_k)``
  and the base ``x0 + i y0``::

      x + i y = (x0 + i y0) + sum_k z_k exp(i theta_k)

  so one linear least-squares solve gives the global optimum, and
  ``z_k -> (dl_k, dtheta_k) = (|z_k| - l_k, arg z_k)`` maps it back (a bijection
  for ``|z_k| > 0``).  No iterations, no starting point, and it batches over
  trials: many measurement sets share one factorization.
* ``"gauss-newton"``: the paper's iterative algorithm (Section III, Steps 1-5),
  Gauss-Newton on the full nonlinear model in the paper's parametrization,
  starting from zero deviations, with a step tolerance and an iteration cap.

Both rest on one thin QR of the plan's regressor ``H``
(:func:`armcal.criteria.scaled_jacobian`, ``2m x p``, memory ``O(m p)``) and the
SVD of its ``p x p`` triangle, with the rank policy of :mod:`armcal.numerics`:
no normal equations, so accuracy degrades with ``cond(J)``, never ``cond(J)^2``,
and a singular plan is a :class:`~armcal.errors.NotIdentifiableError` that names
the unseen combinations, never a :class:`numpy.linalg.LinAlgError`.

Uncertainty is ``cov = sigma^2 (J^T J)^-1`` at the solution (paper eq. 16), with
``sigma`` given by the user or estimated as ``s^2 = RSS / (2m - p)``.

**Weighted and reduced models** (:attr:`armcal.arm.PlanarArm.standard` false).
With a noise model (:mod:`armcal.noise`) every pose's rows and residual are
whitened by ``W_i`` (``W_i^T W_i = sigma_ref^2 Sigma_i^-1``), which turns
weighted least squares into ordinary least squares:

* every parameter free: the closed form on whitened rows (still linear in the
  link phasors, so still the global optimum).  With encoder noise ``Sigma_i``
  depends on the estimate (errors in variables): the whitening is re-evaluated
  at the estimate and the solve repeated until it no longer moves;
* fixed parameters: Gauss-Newton over the free parameters (user
  parametrization, the whitening re-evaluated at every iterate), started from
  the unconstrained closed form with the fixed deviations set to 0 when the plan
  identifies the full model, else from zero.

The covariance is then the generalized-least-squares one,
``sigma_ref^2 (J_w^T J_w)^-1`` over the free parameters.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from functools import cached_property
from typing import Any, Literal, cast

import numpy as np

from .criteria import covariance_factor
from .diagnostics import (
    FEW_DOF,
    OUTLIER_ALPHA,
    GoodnessOfFit,
    Outlier,
    PoseTest,
    goodness_of_fit,
    studentized_test,
)
from .errors import ArmcalError, ArmcalWarning
from .models import (
    CalibratedArm,
    Compliance,
    Elastostatic,
    Loads,
    PlanarArm,
    Plane,
    barely_identifiable_warning,
    check_compliance_identifiable,
    check_identifiable,
    check_target,
    compliance_identifiability,
    conditioning_warning,
    forward_kinematics,
    jacobian,
    listing,
    paper_from_user,
    plan_svd,
    scaled_columns,
    scaled_jacobian,
    wrap_angle,
)
from .noise import NoiseModel
from .numerics import (
    LinearLeastSquares,
    factor_least_squares,
    scaled_svd,
    solve_least_squares,
)

__all__ = [
    "HUBER_K",
    "METHODS",
    "Calibration",
    "identify",
    "solve_closed_form",
    "solve_gauss_newton",
    "solve_model",
]


Method = Literal["auto", "closed-form", "gauss-newton"]


def _factor(arm: PlanarArm, q: np.ndarray, target: np.ndarray | None = None) -> LinearLeastSquares:
    """The plan's factorization; raises :class:`NotIdentifiableError` for a singular plan."""
    factor = factor_least_squares(scaled_jacobian(arm, q, target))
    if not bool(factor.svd.full_rank):
        # raises, naming the unseen combinations
        check_identifiable(arm, q, svd=factor.svd, target=target)
    return factor


def _link_phasors_fit(factor: LinearLeastSquares, xy: np.ndarray) -> np.ndarray:
    """Least-squares ``v = (Im z_1..n, Re z_1..n, [x0, y0])`` ``(N, p)`` of sets ``xy (N, m, 2)``.

    The tip is ``sqrt(m) H v`` (:func:`armcal.criteria.scaled_jacobian`), so
    ``v = H^+ y / sqrt(m)``: one projection ``Q^T y`` and a ``p x p`` product per set.
    """
    m = xy.shape[-2]
    return factor.solve(xy.reshape(-1, 2 * m)) / np.sqrt(m)


def _closed_form_params(arm: PlanarArm, v: np.ndarray) -> np.ndarray:
    k = arm.n_links
    z = v[:, k : 2 * k] + 1j * v[:, :k]
    if not arm.standard_map:
        return _user_from_links(arm, np.abs(z) - arm.link_nominal, np.angle(z), v[:, 2 * k :])
    # dq_k = dtheta_k - dtheta_(k-1), wrapped into (-pi, pi], is the angle of
    # z_k conj(z_(k-1)) (z_0 = 1): one angle instead of n angles, a diff and a wrap.
    relative = z.copy()
    relative[:, 1:] *= z[:, :-1].conj()
    return np.concatenate(
        [np.abs(z) - arm.link_lengths, np.angle(relative), v[:, 2 * k :]], axis=-1
    )


def _user_from_links(
    arm: PlanarArm, dl: np.ndarray, dtheta: np.ndarray, base: np.ndarray
) -> np.ndarray:
    """User deviations ``(N, p)`` of link-vector deviations ``(N, K)`` and base ``(N, 2)``.

    Solves ``P_free user_free = (dtheta, dl, base)`` (:func:`armcal.arm.paper_from_user`;
    fixed parameters 0).  The link angles are first put on one branch around the
    first link vector's (a base rotation can turn them all near +-pi), and for a
    joint map of integers the angle parameters are wrapped into (-pi, pi]: whole
    turns of them turn every link vector by whole turns.
    """
    first = dtheta[:, :1]
    dtheta = first + wrap_angle(dtheta - first)
    paper = np.concatenate([dtheta, dl, base], axis=-1)
    free = arm.free
    user = np.zeros((paper.shape[0], arm.n_params))
    user[:, free] = np.linalg.solve(paper_from_user(arm)[:, free], paper.T).T
    angles = arm.angle_params
    if np.array_equal(arm.joint_map, np.round(arm.joint_map)):
        user[:, angles] = wrap_angle(user[:, angles])
    return user


def _as_sets(arm: PlanarArm, q: np.ndarray, xy: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    q = np.asarray(q, dtype=float)
    xy = np.asarray(xy, dtype=float)
    if q.ndim != 2 or q.shape[1] != arm.n_joints:
        raise ValueError(f"q must have shape (m, {arm.n_joints}) in rad, got {q.shape}")
    if xy.shape[-2:] != (q.shape[0], 2) or xy.ndim not in (2, 3):
        raise ValueError(f"xy must have shape ({q.shape[0]}, 2) or (N, {q.shape[0]}, 2) in mm")
    return q, xy.reshape(-1, q.shape[0], 2)


def solve_closed_form(
    arm: PlanarArm, q: np.ndarray, xy: np.ndarray, *, target: np.ndarray | None = None
) -> np.ndarray:
    """Exact least-squares deviations by one linear solve; batched over measurement sets.

    Parameters
    ----------
    arm : PlanarArm
    q : ndarray, shape (m, n)
        Joint angles in rad (shared by every measurement set).
    xy : ndarray, shape (m, 2) or (N, m, 2)
        Measured positions in mm; a leading axis holds ``N`` independent sets.
    target : ndarray of int, shape (m,), optional
        Every row's target, for an arm with several.

    Returns
    -------
    ndarray, shape (p,) or (N, p)
        User deviations ``[dl (mm), dq (rad), (x0, y0) (mm), (phi0) (rad)]``.

    Raises
    ------
    NotIdentifiableError
        If the plan cannot identify every parameter (:func:`check_identifiable`).

    Notes
    -----
    Solves ``min ||A w - y||`` for the link phasors ``w`` by a thin QR of the
    plan's regressor and the SVD of its triangle (the rank policy of
    :mod:`armcal.numerics`), then ``dl_k = |z_k| - l_k``, ``dtheta_k = arg z_k``
    and ``dq_k = wrap(dtheta_k - dtheta_{k-1})``.  Round-off errs by about
    ``cond(H) eps`` of the link lengths (:func:`armcal.criteria.scaled_jacobian`).

    Examples
    --------
    >>> arm = PlanarArm([2.0, 1.0])
    >>> q = np.radians([[0, 0], [0, 90], [90, 90], [45, -120]])
    >>> truth = np.array([0.1, -0.05, 0.01, -0.02])
    >>> est = solve_closed_form(arm, q, forward_kinematics(arm, q, truth))
    >>> bool(np.allclose(est, truth, atol=1e-12))
    True
    """
    batched = np.ndim(xy) == 3
    q, sets = _as_sets(arm, q, xy)
    params = _closed_form_params(arm, _link_phasors_fit(_factor(arm, q, target), sets))
    return params if batched else params[0]


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
        return _user_from_links(arm, dl, dtheta, paper[:, 2 * n :]), iterations, converged
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
        If the plan cannot identify every parameter (:func:`check_identifiable`).

    Notes
    -----
    Step 1 starts from ``DeltaPi = 0``; Steps 2-3 evaluate model (1) and solve the
    linearized problem (11) at the current estimate (the Jacobian (7)-(8) uses the
    corrected lengths and angles of Step 4); Step 5 repeats until the step is below
    the tolerance.

    How Step 3 is solved.  The model is linear in the link phasors: the tip is
    ``A w`` with the plan-only regressor ``A = sqrt(m) H``
    (:func:`armcal.criteria.scaled_jacobian`) and ``w = w(DeltaPi)``, so the
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
    >>> arm = PlanarArm([2.0, 1.0])
    >>> q = np.radians([[0, 0], [0, 90], [90, 90], [45, -120]])
    >>> truth = np.array([0.1, -0.05, 0.01, -0.02])
    >>> est, iterations, converged = solve_gauss_newton(arm, q, forward_kinematics(arm, q, truth))
    >>> bool(np.allclose(est, truth, atol=1e-12)), bool(converged)
    (True, True)
    """
    batched = np.ndim(xy) == 3
    q, sets = _as_sets(arm, q, xy)
    v = _link_phasors_fit(_factor(arm, q, target), sets)
    params, iterations, converged = _gauss_newton(arm, v, tol=tol, max_iter=max_iter)
    if batched:
        return params, iterations, converged
    return params[0], iterations[0], converged[0]


def _model_noise(arm: PlanarArm) -> NoiseModel:
    """The arm's noise model, or unit isotropic noise (weights are relative)."""
    return arm.noise if arm.noise is not None else NoiseModel.isotropic(1.0)


def _whitening(
    arm: PlanarArm,
    q: np.ndarray,
    params: np.ndarray | None,
    row_sigma: np.ndarray | None,
    pose_weights: np.ndarray | None,
    target: np.ndarray | None = None,
) -> np.ndarray | None:
    """``W_i`` ``(..., m, 2, 2)`` times ``sqrt(pose weight)``; None when it is the identity."""
    noise = _model_noise(arm)
    if noise.isotropic_iid and row_sigma is None:
        w = None
    else:
        at = params if noise.joint_sigma is not None else None
        w = arm.whitening(q, at, row_sigma, target=target, noise=noise)
    if pose_weights is None:
        return w
    root = np.sqrt(pose_weights)[..., None, None]
    return root * (np.eye(2) if w is None else w)


def _for_sets(pose_weights: np.ndarray | None, active: np.ndarray) -> np.ndarray | None:
    """The pose weights of the sets ``active``: shared ``(m,)`` weights serve every set."""
    if pose_weights is None or pose_weights.ndim == 1:
        return pose_weights
    return pose_weights[active]


def _check_closed_form(arm: PlanarArm, method: str) -> None:
    """The closed form is linear in the link phasors: it needs every parameter free."""
    if method == "closed-form" and not arm.complete:
        raise ArmcalError(
            f"the closed form needs every parameter free, but {', '.join(arm.fixed)} "
            f"{'is' if len(arm.fixed) == 1 else 'are'} fixed; use --method gauss-newton or auto"
        )


def _apply(w: np.ndarray | None, rows: np.ndarray) -> np.ndarray:
    """``W_i`` applied to per-pose rows ``(..., m, 2, k)``."""
    return rows if w is None else w @ rows


def _step_size(arm: PlanarArm, step: np.ndarray) -> np.ndarray:
    """Largest change ``(N,)`` of a step ``(N, p)`` in mm (angles times the reach beyond them)."""
    n = arm.n_links
    scale = np.ones(arm.n_params)
    if arm.standard_map:
        # dq_j moves every link from j outwards: the tip by up to the reach beyond joint j.
        scale[n : 2 * n] = np.cumsum(arm.link_lengths[::-1])[::-1]
    else:  # dq_j turns link vector k by A_kj; phi0 turns them all
        scale[n : 2 * n] = arm.link_nominal @ np.abs(arm.angle_map)
        if arm.base_rotation:
            scale[-1] = float(np.sum(arm.link_nominal))
    return np.max(np.abs(step * scale), axis=-1, initial=0.0)


def _weighted_closed_form(
    arm: PlanarArm,
    q: np.ndarray,
    xy: np.ndarray,
    w: np.ndarray | None,
    target: np.ndarray | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """Closed-form deviations ``(N, p)`` of sets ``xy (N, m, 2)`` on whitened rows, and full rank.

    The regressor of the link phasors (:func:`scaled_columns` in real form),
    each pose's two rows and measurement multiplied by ``W_i``: one batched
    least-squares solve per set (one shared factorization when ``w`` does not
    depend on the set).
    """
    columns = scaled_columns(arm, q, target)  # (m, p): tip = sum_k columns_k v_k
    blocks = np.stack([columns.real, columns.imag], axis=-2)  # (m, 2, p)
    m, p = q.shape[0], arm.n_paper
    if w is None or w.ndim == 3:  # one regressor for every set
        regressor = _apply(w, blocks).reshape(2 * m, p)
        rhs = _apply(w, xy[..., None])[..., 0].reshape(-1, 2 * m)
        factor = factor_least_squares(regressor)
        v, ok = factor.solve(rhs), np.full(rhs.shape[0], bool(factor.svd.full_rank))
    else:
        regressor = (w @ blocks).reshape(-1, 2 * m, p)
        rhs = (w @ xy[..., None])[..., 0].reshape(-1, 2 * m)
        v, ok, _ = solve_least_squares(regressor, rhs)
    return _closed_form_params(arm, v), ok


def solve_model(
    arm: PlanarArm,
    q: np.ndarray,
    xy: np.ndarray,
    *,
    row_sigma: np.ndarray | None = None,
    pose_weights: np.ndarray | None = None,
    start: np.ndarray | None = None,
    method: Method = "auto",
    tol: float = 1e-12,
    max_iter: int = 50,
    check_plan: bool = True,
    target: np.ndarray | None = None,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Weighted least squares over the free parameters of any model; batched over sets.

    Parameters
    ----------
    arm : PlanarArm
        Its noise model (:mod:`armcal.noise`) weights the poses; its fixed
        parameters stay at 0.
    q : ndarray, shape (m, n)
        Joint angles in rad, shared by every set.
    xy : ndarray, shape (m, 2) or (N, m, 2)
        Measured positions in mm.
    row_sigma : ndarray, shape (m,), optional
        Per-row instrument noise (mm), replacing the instrument covariance.
    pose_weights : ndarray, shape (m,) or (N, m), optional
        Extra weights per pose (robust fitting, leaving poses out with 0).
    start : ndarray, shape (p,) or (N, p), optional
        Gauss-Newton's starting point (see the module notes for the default).
    method : {"auto", "closed-form", "gauss-newton"}
        ``"auto"``: the weighted closed form when every parameter is free, else
        Gauss-Newton.  ``"gauss-newton"`` starts from ``start``, else (with fixed
        parameters) from the closed form of the model with every parameter free, projected
        onto the free ones, or zero.
    tol, max_iter
        A set has converged when its largest step moves the tip by less than
        ``tol`` times the reach (mm); iteration cap.
    check_plan : bool
        Check that the poses identify the model (skip only when the caller has).
    target : ndarray of int, shape (m,), optional
        Every row's target, for an arm with several.

    Returns
    -------
    params : ndarray, shape (p,) or (N, p)
    iterations : ndarray of int, shape () or (N,)
    converged : ndarray of bool, shape () or (N,)

    Raises
    ------
    NotIdentifiableError
        If the poses with positive weight cannot identify the free parameters.
    ArmcalError
        For ``method="closed-form"`` with fixed parameters.

    Examples
    --------
    >>> arm = PlanarArm([2.0, 1.0], sigma=0.01, fixed=("dl2",))
    >>> q = np.radians([[0, 0], [0, 90], [90, 90], [45, -120]])
    >>> truth = np.array([0.1, 0.0, 0.01, -0.02])
    >>> est, _, converged = solve_model(arm, q, forward_kinematics(arm, q, truth))
    >>> bool(np.allclose(est, truth, atol=1e-12)), bool(converged)
    (True, True)
    """
    batched = np.ndim(xy) == 3
    q, sets = _as_sets(arm, q, xy)
    n_sets = sets.shape[0]
    if pose_weights is not None:
        pose_weights = np.broadcast_to(np.asarray(pose_weights, dtype=float), sets.shape[:-1])
        if pose_weights.shape[0] == 1 or np.all(pose_weights == pose_weights[:1]):
            pose_weights = pose_weights[0]
    used = (
        np.ones(q.shape[0], bool)
        if pose_weights is None
        else np.any(np.atleast_2d(pose_weights) > 0, axis=0)
    )
    if check_plan:
        sub = _rows_of(target, used)
        check_identifiable(arm, q[used], svd=plan_svd(arm, q[used], sub), target=sub)
    all_free = arm.complete
    _check_closed_form(arm, method)
    joint_noise = _model_noise(arm).joint_sigma is not None
    threshold = tol * float(np.sum(arm.link_lengths))
    params = np.zeros((n_sets, arm.n_params))
    iterations = np.zeros(n_sets, dtype=int)
    converged = np.zeros(n_sets, dtype=bool)
    if all_free and method != "gauss-newton":
        # Weighted closed form; with encoder noise the weights follow the estimate.
        w = _whitening(arm, q, None, row_sigma, pose_weights, target)
        params, ok = _weighted_closed_form(arm, q, sets, w, target)
        iterations[:] = 1
        converged[:] = ok
        if joint_noise:
            active = np.arange(n_sets)
            for _ in range(max_iter):
                # (N, p) deviations: per-set whitening (N, m, 2, 2)
                weights = _for_sets(pose_weights, active)
                w = _whitening(arm, q, params[active], row_sigma, weights, target)
                new, ok = _weighted_closed_form(arm, q, sets[active], w, target)
                moved = _step_size(arm, wrap_angle(new - params[active]))
                params[active] = new
                iterations[active] += 1
                active = active[ok & (moved > threshold)]
                if active.size == 0:
                    break
            converged[active] = False
    else:
        if start is not None:
            params[:] = np.broadcast_to(np.asarray(start, dtype=float), params.shape)
        elif method != "gauss-newton" or not all_free:
            # The closed form of the model with every parameter free, projected onto the
            # free ones: from zero, a far-turned base (3-D data) can lead Gauss-Newton to
            # the mirrored arm (-L, dq + 180 deg), which fits as well.
            full = arm.replace(fixed=())
            if plan_svd(full, q[used], _rows_of(target, used)).full_rank:
                w = _whitening(full, q, None, row_sigma, pose_weights, target)
                params, _ = _weighted_closed_form(full, q, sets, w, target)
                params = _onto_free(arm, full, params)
            elif arm.base_rotation:
                params = _base_start(arm, q[used], sets[:, used], _rows_of(target, used))
        params = params * arm.free
        params, iterations, converged = _gauss_newton_model(
            arm, q, sets, params, row_sigma, pose_weights, threshold, max_iter, target
        )
    if batched:
        return params, iterations, converged
    return params[0], iterations[0], converged[0]


def _gauss_newton_model(
    arm: PlanarArm,
    q: np.ndarray,
    sets: np.ndarray,
    params: np.ndarray,
    row_sigma: np.ndarray | None,
    pose_weights: np.ndarray | None,
    threshold: float,
    max_iter: int,
    target: np.ndarray | None = None,
    compliance: Compliance | None = None,
    loads: Loads | None = None,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Gauss-Newton over the free user parameters, whitened rows, every active set at once.

    With ``compliance`` the parameters are the deviations then the compliance
    (:mod:`armcal.elastostatic`), the model its deflected tip under ``loads``,
    and a compliance step is measured by the tip motion it causes.
    """
    p = arm.n_params
    if compliance is None:
        free, n_free = arm.free, arm.n_free

        def tip(current: np.ndarray) -> np.ndarray:
            return forward_kinematics(arm, q, current, target=target)

        def columns(current: np.ndarray) -> np.ndarray:
            return jacobian(arm, q, current, target=target)

    else:
        free, n_free = compliance.all_free, compliance.n_free
        model = compliance  # bound for the closures
        tip_per_unit = model.typical_scale(q, loads) * float(np.sum(arm.link_lengths))

        def tip(current: np.ndarray) -> np.ndarray:
            return model.tip(q, current, loads)

        def columns(current: np.ndarray) -> np.ndarray:
            return model.jacobian(q, current, loads)

    n_sets = sets.shape[0]
    iterations = np.zeros(n_sets, dtype=int)
    failed = np.zeros(n_sets, dtype=bool)
    previous = np.full(n_sets, np.inf)
    active = np.arange(n_sets)
    floor = 1e-9 * float(np.sum(arm.link_lengths))  # round-off floor of a stalled step
    for _ in range(max_iter):
        current = params[active]
        weights = _for_sets(pose_weights, active)
        w = _whitening(arm, q, current[:, :p], row_sigma, weights, target)
        jac = columns(current)[..., free]  # (N, m, 2, p_f)
        residual = sets[active] - tip(current)
        rows = _apply(w, jac).reshape(active.size, -1, n_free)
        rhs = _apply(w, residual[..., None])[..., 0].reshape(active.size, -1)
        step, _, _ = solve_least_squares(rows, rhs)
        full_step = np.zeros((active.size, free.size))
        full_step[:, free] = step
        params[active] = current + full_step
        iterations[active] += 1
        finite = np.all(np.isfinite(full_step), axis=1)
        failed[active[~finite]] = True
        size = _step_size(arm, full_step[:, :p])
        if compliance is not None:
            bent = np.max(np.abs(full_step[:, p:]) * tip_per_unit, axis=-1, initial=0.0)
            size = np.maximum(size, bent)
        stalled = (size >= 0.5 * previous[active]) & (size < floor)
        previous[active] = size
        active = active[finite & (size > threshold) & ~stalled]
        if active.size == 0:
            break
    converged = ~failed
    converged[active] = False
    angles = np.flatnonzero(arm.angle_params)
    params[:, angles] = wrap_angle(params[:, angles])
    return params, iterations, converged


def _rows_of(target: np.ndarray | None, used: np.ndarray) -> np.ndarray | None:
    """The targets of the rows ``used`` (None stays None)."""
    return None if target is None else target[used]


def _base_start(
    arm: PlanarArm, q: np.ndarray, sets: np.ndarray, target: np.ndarray | None
) -> np.ndarray:
    """A start ``(N, p)`` that turns (and moves) the nominal arm onto each set of points.

    The rotation that best maps the nominal tips onto the measured ones, about
    their centroids when the base offset is free (the 2-D Procrustes solution),
    so that Gauss-Newton starts in the right basin however far the fitted plane's
    axes turn the base.
    """
    names = arm.param_names
    params = np.zeros((sets.shape[0], arm.n_params))
    nominal = forward_kinematics(arm, q, np.zeros(arm.n_params), target=target)
    a, b = nominal[:, 0] + 1j * nominal[:, 1], sets[..., 0] + 1j * sets[..., 1]
    if arm.base_offset:
        a, b = a - a.mean(), b - b.mean(axis=-1, keepdims=True)
    turn = np.angle(np.sum(np.conj(a) * b, axis=-1))
    if "phi0" in names and "phi0" not in arm.fixed:
        params[:, names.index("phi0")] = turn
    if arm.base_offset and "x0" not in arm.fixed and "y0" not in arm.fixed:
        shift = (sets[..., 0] + 1j * sets[..., 1]).mean(axis=-1) - np.exp(1j * turn) * (
            nominal[:, 0] + 1j * nominal[:, 1]
        ).mean()
        params[:, names.index("x0")], params[:, names.index("y0")] = shift.real, shift.imag
    return params


def _onto_free(arm: PlanarArm, full: PlanarArm, params: np.ndarray) -> np.ndarray:
    """Deviations ``(N, p)`` of the complete ``full`` arm as a start for ``arm``'s free ones.

    Without a base rotation the two share their parameters.  With one, the
    complete arm holds the rotation's partner, which ``arm`` may free while
    holding another parameter on the rotation's direction: the start is moved
    along that direction so that the one ``arm`` holds is 0 (the same tip).
    """
    if not arm.base_rotation:
        return params
    direction = arm.rotation_direction
    held = [i for i, name in enumerate(arm.param_names) if name in arm.fixed]
    on_direction = [i for i in held if abs(direction[i]) > 1e-12]
    if not on_direction:
        return params
    i = on_direction[0]
    return params - np.outer(params[:, i] / direction[i], direction)


def solve_compliant(
    model: Compliance,
    q: np.ndarray,
    xy: np.ndarray,
    loads: Loads | None,
    *,
    row_sigma: np.ndarray | None = None,
    pose_weights: np.ndarray | None = None,
    start: np.ndarray | None = None,
    tol: float = 1e-12,
    max_iter: int = 50,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Weighted least squares of geometry plus joint compliance; batched over sets.

    Parameters
    ----------
    model : Compliance
        The arm (noise model, fixed parameters) and its loads (:mod:`armcal.elastostatic`).
    q : ndarray, shape (m, n)
    xy : ndarray, shape (m, 2) or (N, m, 2)
    loads : Loads or None
        Every row's payload and tip force (None: the robot file's payload).
    row_sigma, pose_weights, tol, max_iter
        As for :func:`solve_model`.
    start : ndarray, shape (p + P,) or (N, p + P), optional
        Starting point; by default the geometry-only least-squares fit (the
        closed form where every geometric parameter is free) with no compliance.

    Returns
    -------
    params : ndarray, shape (p + P,) or (N, p + P)
        User deviations (mm, rad) then compliance (rad/(N m), rad/m).
    iterations, converged
        As for :func:`solve_model`.

    Notes
    -----
    Gauss-Newton on the whitened rows of :meth:`Compliance.jacobian` (the
    deflected model), every active set at once; the step and stopping rule are
    those of :func:`solve_model`, with a compliance step measured by the tip
    motion it causes.
    """
    batched = np.ndim(xy) == 3
    arm = model.arm
    q, sets = _as_sets(arm, q, xy)
    n_sets = sets.shape[0]
    p = arm.n_params
    total = p + model.n_params
    free = model.all_free
    if pose_weights is not None:
        pose_weights = np.broadcast_to(np.asarray(pose_weights, dtype=float), sets.shape[:-1])
    params = np.zeros((n_sets, total))
    if start is not None:
        params[:] = np.broadcast_to(np.asarray(start, dtype=float), params.shape)
    else:
        geometry, _, _ = solve_model(
            arm, q, sets, row_sigma=row_sigma, pose_weights=pose_weights, check_plan=False
        )
        params[:, :p] = geometry
    params = params * free
    threshold = tol * float(np.sum(arm.link_lengths))
    params, iterations, converged = _gauss_newton_model(
        arm,
        q,
        sets,
        params,
        row_sigma,
        pose_weights,
        threshold,
        max_iter,
        compliance=model,
        loads=loads,
    )
    if batched:
        return params, iterations, converged
    return params[0], iterations[0], converged[0]


@dataclass(frozen=True, eq=False)
class ComplianceFit:
    """The identified joint compliance of a :class:`Calibration`.

    Attributes
    ----------
    model : Compliance
        The parameters (names, units) and the loads model.
    values : ndarray, shape (P,)
        Compliance in internal units (rad/(N m) for ``k``, rad/m for ``c``).
    covariance : ndarray, shape (p + P, p + P)
        Covariance of the geometry and compliance together (internal units).
    geometry_only_rms_mm : float or None
        Residual RMS of a fit without compliance on the same poses, for the report.
    max_deflection_rad : ndarray, shape (n,), or None
        The largest fitted deflection of every joint over the poses.
    """

    model: Compliance
    values: np.ndarray
    covariance: np.ndarray
    geometry_only_rms_mm: float | None = None
    max_deflection_rad: np.ndarray | None = None


@dataclass(frozen=True, eq=False)
class Calibration:
    """Identified deviations with their uncertainty, the fit's residuals and its diagnostics.

    Attributes
    ----------
    arm : PlanarArm
        The nominal arm that was calibrated, with the noise model and fixed
        parameters used.
    method : str
        Solver used: ``"closed-form"`` or ``"gauss-newton"``.
    params : ndarray, shape (p,)
        User deviations in internal units: ``dl`` (mm), ``dq`` (rad), ``x0, y0`` (mm);
        0 for fixed parameters.
    covariance : ndarray, shape (p, p)
        ``sigma^2 (J_w^T J_w)^-1`` over the free parameters in internal units
        (mm, rad), zero rows and columns for fixed ones.
    sigma_mm : float
        Measurement noise (1 std, mm) used for ``covariance``: the noise model's
        reference (:attr:`armcal.noise.NoiseModel.sigma_mm`), or estimated.
    sigma_source : {"given", "estimated"}
        Whether the noise was given (robot file, ``sigma``, per-row sigma) or
        estimated as ``sqrt(RSS / (2m - p_f))``.
    residuals : ndarray, shape (m, 2)
        Measured minus fitted positions in mm, for every pose.
    iterations : int
        Linearized solves (1 for the closed form).
    converged : bool
        Whether the solver met its tolerance.
    pose_labels : tuple of str
        A label for every pose (the measurement file's ``pose`` column, or 1..m).
    warnings : tuple of ArmcalWarning
        What makes the result suspicious (codes ``fit-inconsistent``,
        ``few-dof``, ``outlier``, ``ill-conditioned``, ``not-converged``).
    goodness_of_fit : GoodnessOfFit or None
        The chi-square test over the poses in the fit (:mod:`armcal.diagnostics`).
    standardized_residuals : ndarray, shape (m, 2) or None
        ``W_i e_i / sigma`` of every pose: ``N(0, I)`` under the noise model.
    outliers : tuple of Outlier
        Poses the studentized test flags, removed from the fit or not.
    used : ndarray of bool, shape (m,) or None
        Poses in the final fit (all unless a robust fit left outliers out).
    rows : tuple of int
        1-based data row of every pose in its file.
    robust : bool
        Whether the fit was robust (Huber, then the outlier test and a refit).
    target : ndarray of int, shape (m,), or None
        Every pose's target (index into ``arm.targets``) on an arm with several.
    plane : Plane or None
        The plane of motion fitted to 3-D instrument data
        (:class:`armcal.instrument.Plane`), in whose coordinates ``residuals``
        and the base pose are; None for 2-D data.
    compliance : ComplianceFit or None
        The joint compliance identified with the geometry (:mod:`armcal.elastostatic`);
        ``params`` and ``covariance`` stay the geometric ones, and ``names``,
        ``values`` and ``std`` list both.
    loads : Loads or None
        The rows' payloads and tip forces, for a fit with compliance.
    """

    arm: PlanarArm
    method: str
    params: np.ndarray
    covariance: np.ndarray
    sigma_mm: float
    sigma_source: Literal["given", "estimated"]
    residuals: np.ndarray
    iterations: int
    converged: bool
    pose_labels: tuple[str, ...]
    warnings: tuple[ArmcalWarning, ...] = ()
    goodness_of_fit: GoodnessOfFit | None = None
    standardized_residuals: np.ndarray | None = None
    outliers: tuple[Outlier, ...] = ()
    used: np.ndarray | None = None
    rows: tuple[int, ...] = ()
    robust: bool = False
    target: np.ndarray | None = None
    plane: Plane | None = None
    compliance: ComplianceFit | None = None
    loads: Loads | None = None

    def calibrated(self) -> CalibratedArm:
        """The arm with these deviations, for validation, compensation and export."""
        c = self.compliance
        return CalibratedArm(
            self.arm,
            self.params,
            self.covariance,
            self.sigma_mm,
            self.plane,
            compliance=None if c is None else c.model,
            compliance_values=None if c is None else c.values,
            full_covariance=None if c is None else c.covariance,
        )

    @property
    def n_free(self) -> int:
        """Free parameters of the fit (geometry and compliance)."""
        return self.arm.n_free + (0 if self.compliance is None else self.compliance.model.n_params)

    @property
    def n_poses(self) -> int:
        """Number of measured poses ``m`` (including any left out of the fit)."""
        return int(self.residuals.shape[0])

    @property
    def n_used(self) -> int:
        """Number of poses in the final fit."""
        return self.n_poses if self.used is None else int(np.count_nonzero(self.used))

    @property
    def dof(self) -> int:
        """Residual degrees of freedom ``2 m_used - p_f``."""
        return 2 * self.n_used - self.n_free

    @property
    def names(self) -> tuple[str, ...]:
        """Parameter names ``dl1.., dq1.., (x0, y0)``, then any compliance ``k1..``/``c1..``."""
        if self.compliance is not None:
            return self.compliance.model.all_names
        return self.arm.param_names

    @property
    def units(self) -> tuple[str, ...]:
        """Display units of the parameters (``mm``, ``deg``, ``urad/(N*m)``, ``mdeg/m``)."""
        if self.compliance is not None:
            return self.compliance.model.all_units
        return self.arm.param_units

    @property
    def display_scale(self) -> np.ndarray:
        """Internal to display units of every parameter in :attr:`names`."""
        if self.compliance is not None:
            return self.compliance.model.all_scale
        return self.arm.display_scale

    def _all_covariance(self) -> np.ndarray:
        return self.covariance if self.compliance is None else self.compliance.covariance

    @property
    def values(self) -> np.ndarray:
        """Parameter values ``(p,)`` in display units (mm, deg)."""
        if self.compliance is not None:
            return np.concatenate([self.params, self.compliance.values]) * self.display_scale
        return self.params * self.arm.display_scale

    @property
    def covariance_display(self) -> np.ndarray:
        """Covariance ``(p, p)`` in display units (mm, deg)."""
        s = self.display_scale
        return self._all_covariance() * np.outer(s, s)

    @property
    def std(self) -> np.ndarray:
        """Standard errors ``(p,)`` in display units (mm, deg); 0 for fixed parameters."""
        return np.sqrt(np.diag(self.covariance_display))

    @property
    def correlation(self) -> np.ndarray:
        """Correlation matrix ``(p, p)`` of the estimates (identity rows for fixed ones)."""
        covariance = self._all_covariance()
        d = np.sqrt(np.diag(covariance))
        safe = np.where(d > 0, d, 1.0)
        corr = covariance / np.outer(safe, safe)
        fixed = d == 0
        corr[fixed, :] = 0.0
        corr[:, fixed] = 0.0
        corr[fixed, fixed] = 1.0
        return corr

    @property
    def pose_residuals(self) -> np.ndarray:
        """Euclidean residual of every pose ``(m,)`` in mm."""
        return np.hypot(self.residuals[:, 0], self.residuals[:, 1])

    def _used_residuals(self) -> np.ndarray:
        return self.residuals if self.used is None else self.residuals[self.used]

    @property
    def residual_rms(self) -> float:
        """RMS of the residual coordinates of the poses in the fit, in mm."""
        return float(np.sqrt(np.mean(self._used_residuals() ** 2)))

    @property
    def residual_max(self) -> float:
        """Largest Euclidean residual of a pose in the fit, in mm."""
        used = self._used_residuals()
        return float(np.max(np.hypot(used[:, 0], used[:, 1])))


def _closed_form(
    arm: PlanarArm, q: np.ndarray, xy: np.ndarray, *, target: np.ndarray | None = None, **_: object
):
    if not arm.standard:
        return solve_model(arm, q, xy, method="closed-form", target=target)
    return solve_closed_form(arm, q, xy, target=target), 1, True


def _gauss_newton_any(arm: PlanarArm, q: np.ndarray, xy: np.ndarray, **kwargs: Any):
    if not arm.standard:
        return solve_model(arm, q, xy, method="gauss-newton", **kwargs)
    return solve_gauss_newton(arm, q, xy, **kwargs)


#: Solvers by name; each takes ``xy`` of shape ``(m, 2)`` or ``(N, m, 2)`` and returns
#: ``(params, iterations, converged)``, batched alike.  Weighted or reduced arms go
#: through :func:`solve_model` (the closed form needs every parameter free).
METHODS: dict[str, Callable[..., tuple[np.ndarray, Any, Any]]] = {
    "closed-form": _closed_form,
    "gauss-newton": _gauss_newton_any,
}

#: Huber's tuning constant for the radial (2-D) residual of a pose: a clean pose
#: has a standardized residual below it with probability 0.95 (chi-square, 2 dof),
#: so clean data keep weight 1 almost everywhere and the fit stays efficient.
#: (The chi-square law with 2 dof has survival function ``exp(-x / 2)``.)
HUBER_K = float(np.sqrt(-2.0 * np.log(0.05)))


class _Fit:
    """One least-squares fit and everything the diagnostics need, for all m poses.

    ``factor`` (``G`` with ``(J_w^T J_w)^-1 = G G^T`` over the used poses) and
    ``leverage`` (``B_i B_i^T``, ``(m, 2, 2)``) are computed on first use: the
    robust iterations only need the residuals.
    """

    def __init__(
        self,
        problem: _Problem,
        params: np.ndarray,
        used: np.ndarray,
        iterations: int,
        converged: bool,
    ) -> None:
        arm, q, target = problem.arm, problem.q, problem.target
        self.params, self.used = params, used
        self.iterations, self.converged = iterations, converged
        self.residuals = problem.xy - problem.predict(params)  # mm
        w = _whitening(arm, q, params[: arm.n_params], problem.row_sigma, None, target)
        if w is not None and problem.row_sigma is not None:  # to the rows' own reference
            w = w * (_reference_sigma(arm, problem.row_sigma) / _model_noise(arm).sigma_mm)
        self._w, self._arm, self._q, self._problem = w, arm, q, problem
        # W_i e_i, in mm of the reference noise
        self.whitened = self.residuals if w is None else (w @ self.residuals[:, :, None])[:, :, 0]

    @cached_property
    def _jacobian(self) -> np.ndarray:
        return _apply(self._w, self._problem.free_jacobian(self.params))  # (m, 2, p_f)

    @cached_property
    def factor(self) -> np.ndarray:
        if self._problem.plain and self.used.all():  # from the plan's own SVD
            factor, ok = covariance_factor(
                self._arm,
                self._q,
                self.params,
                self._problem.plan_factor.svd,
                target=self._problem.target,
            )
            factor = factor[..., self._arm.free, :]
        else:
            svd = scaled_svd(self._jacobian[self.used].reshape(-1, self._problem.n_free))
            factor, ok = svd.inverse_gram_factor()
        if not bool(ok):  # identifiable at nominal, so only for absurd deviations
            raise ArmcalError("the Jacobian is singular at the estimate; check the data")
        return factor

    @cached_property
    def leverage(self) -> np.ndarray:
        b = self._jacobian @ self.factor
        return b @ np.swapaxes(b, -1, -2)


class _Problem:
    """The data of one identification and the fits made on it."""

    def __init__(
        self,
        arm: PlanarArm,
        q: np.ndarray,
        xy: np.ndarray,
        row_sigma: np.ndarray | None,
        method: str,
        tol: float,
        max_iter: int,
        target: np.ndarray | None = None,
    ) -> None:
        self.arm, self.q, self.xy, self.row_sigma = arm, q, xy, row_sigma
        self.target = target
        self.method, self.tol, self.max_iter = method, tol, max_iter
        #: The plain case (paper's model, every pose, no weights) shares one thin QR
        #: of the plan's regressor between the check, the solve and the covariance.
        self.plain = arm.standard and row_sigma is None

    @cached_property
    def plan_factor(self) -> LinearLeastSquares:
        """The plan's factorization (:func:`_factor`): raises if it is not identifiable."""
        return _factor(self.arm, self.q, self.target)

    @property
    def n_free(self) -> int:
        """Free parameters of the model."""
        return self.arm.n_free

    @property
    def free(self) -> np.ndarray:
        """Free mask over every parameter ``(p,)``."""
        return self.arm.free

    def predict(self, params: np.ndarray) -> np.ndarray:
        """Model positions ``(m, 2)`` (mm) of every pose."""
        return forward_kinematics(self.arm, self.q, params, target=self.target)

    def free_jacobian(self, params: np.ndarray) -> np.ndarray:
        """Unwhitened Jacobian ``(m, 2, p_f)`` over the free parameters."""
        return jacobian(self.arm, self.q, params, target=self.target)[..., self.arm.free]

    def identifiable(self, used: np.ndarray) -> bool:
        """Whether the poses ``used`` identify every free parameter."""
        return _identifiable(self.arm, self.q[used], _rows_of(self.target, used))

    def _rows(self, used: np.ndarray) -> np.ndarray | None:
        return None if self.row_sigma is None else self.row_sigma[used]

    def solve(
        self,
        used: np.ndarray,
        *,
        weights: np.ndarray | None = None,
        start: np.ndarray | None = None,
    ) -> tuple[np.ndarray, int, bool]:
        """Deviations fitted to the poses in ``used`` (times ``weights``, if given)."""
        arm, q, xy = self.arm, self.q[used], self.xy[used]
        target = _rows_of(self.target, used)
        kwargs: dict[str, Any] = {"tol": self.tol, "max_iter": self.max_iter, "target": target}
        if weights is None and start is None and self.plain and used.all():
            v = _link_phasors_fit(self.plan_factor, xy[None])
            if self.method == "closed-form":
                return _closed_form_params(arm, v)[0], 1, True
            fitted, steps, done = _gauss_newton(arm, v, tol=self.tol, max_iter=self.max_iter)
            return fitted[0], int(steps[0]), bool(done[0])
        if weights is None and start is None and self.plain:
            if self.method == "closed-form":
                return solve_closed_form(arm, q, xy, target=target), 1, True
            params, steps, done = solve_gauss_newton(arm, q, xy, **kwargs)
            return params, int(steps), bool(done)
        method = self.method if start is None else "gauss-newton"
        if start is not None and arm.complete and method == "gauss-newton":
            method = "auto" if self.method == "closed-form" else method
        params, steps, done = solve_model(
            arm,
            q,
            xy,
            row_sigma=self._rows(used),
            pose_weights=None if weights is None else weights[used],
            start=start if method == "gauss-newton" else None,
            method=cast(Method, method),
            check_plan=False,
            **kwargs,
        )
        return params, int(steps), bool(done)

    def fit(
        self,
        used: np.ndarray,
        *,
        weights: np.ndarray | None = None,
        start: np.ndarray | None = None,
    ) -> _Fit:
        params, steps, done = self.solve(used, weights=weights, start=start)
        return _Fit(self, params, used, steps, done)


class _CompliantProblem(_Problem):
    """Geometry plus joint compliance (:mod:`armcal.elastostatic`): always Gauss-Newton."""

    def __init__(
        self,
        model: Compliance,
        loads: Loads,
        q: np.ndarray,
        xy: np.ndarray,
        row_sigma: np.ndarray | None,
        tol: float,
        max_iter: int,
    ) -> None:
        super().__init__(model.arm, q, xy, row_sigma, "gauss-newton", tol, max_iter)
        self.model, self.loads = model, loads
        self.plain = False

    @property
    def n_free(self) -> int:
        return self.model.n_free

    @property
    def free(self) -> np.ndarray:
        return self.model.all_free

    def predict(self, params: np.ndarray) -> np.ndarray:
        return self.model.tip(self.q, params, self.loads)

    def free_jacobian(self, params: np.ndarray) -> np.ndarray:
        return self.model.jacobian(self.q, params, self.loads)[..., self.model.all_free]

    def identifiable(self, used: np.ndarray) -> bool:
        if 2 * int(np.count_nonzero(used)) < self.n_free:
            return False
        info, _ = compliance_identifiability(self.model, self.q[used], self.loads.take(used))
        return info.identifiable

    def solve(
        self,
        used: np.ndarray,
        *,
        weights: np.ndarray | None = None,
        start: np.ndarray | None = None,
    ) -> tuple[np.ndarray, int, bool]:
        params, steps, done = solve_compliant(
            self.model,
            self.q[used],
            self.xy[used],
            self.loads.take(used),
            row_sigma=self._rows(used),
            pose_weights=None if weights is None else weights[used],
            start=start,
            tol=self.tol,
            max_iter=self.max_iter,
        )
        return params, int(steps), bool(done)


def _reference_sigma(arm: PlanarArm, row_sigma: np.ndarray | None) -> float:
    """The noise every whitened residual is measured in (mm).

    The noise model's reference; with per-row sigma, ``sqrt(1 / mean(1 / s_i^2))``,
    the isotropic noise that carries the same information (:mod:`armcal.noise`).
    """
    if row_sigma is not None:
        return float(np.sqrt(1.0 / np.mean(1.0 / row_sigma**2)))
    return _model_noise(arm).sigma_mm


def _test(problem: _Problem, fit: _Fit, used: np.ndarray, sigma: float, given: bool) -> PoseTest:
    return studentized_test(
        fit.whitened / sigma, fit.leverage, used, problem.n_free, sigma_given=given
    )


def _scale(fit: _Fit, used: np.ndarray, dof: int) -> float:
    """``sqrt(RSS_w / dof)`` over the poses in the fit (mm of the reference noise)."""
    return float(np.sqrt(np.sum(fit.whitened[used] ** 2) / dof))


def _identifiable(arm: PlanarArm, q: np.ndarray, target: np.ndarray | None = None) -> bool:
    return 2 * q.shape[0] >= arm.n_free and bool(plan_svd(arm, q, target).full_rank)


def _robust_fit(
    problem: _Problem, sigma: float | None, fit: _Fit
) -> tuple[_Fit, np.ndarray, np.ndarray, ArmcalWarning | None]:
    """Huber IRLS from the least-squares ``fit`` to every pose, then test, leave out, refit.

    Returns the final fit, the poses in it, the poses flagged as outliers, and a
    warning when the outliers could not be left out without losing identifiability.
    When most poses disagree with the fit, nothing is an outlier: the model, the
    units or sigma are wrong, which the goodness of fit reports.
    """
    m = problem.q.shape[0]
    everyone = np.ones(m, dtype=bool)
    weights = np.ones(m)
    for _ in range(100):
        distance = np.hypot(fit.whitened[:, 0], fit.whitened[:, 1])
        if sigma is None:  # a robust scale: the median squared distance of chi2(2) is 2 ln 2
            scale = float(np.sqrt(np.median(distance**2) / (2 * np.log(2))))
            scale = max(scale, np.finfo(float).tiny)
        else:
            scale = sigma
        new = np.minimum(1.0, HUBER_K * scale / np.maximum(distance, np.finfo(float).tiny))
        fit = problem.fit(everyone, weights=new, start=fit.params)
        if np.max(np.abs(new - weights)) < 1e-9:
            break
        weights = new
    # The core: poses Huber left at full weight, if they identify the model.
    used = weights >= 1.0
    if not problem.identifiable(used):
        used = everyone
    fit = problem.fit(used, start=fit.params)
    for _ in range(20):
        dof = 2 * int(np.count_nonzero(used)) - problem.n_free
        scale = sigma if sigma is not None else _scale(fit, used, max(dof, 1))
        test = _test(problem, fit, used, scale, sigma is not None)
        keep = ~test.flagged
        if np.array_equal(keep, used):
            return fit, used, ~used, None
        if 2 * np.count_nonzero(keep) < m:
            everything = problem.fit(everyone, start=fit.params)
            return everything, everyone, ~everyone, None
        if not problem.identifiable(keep):
            warning = ArmcalWarning(
                "outliers-kept",
                f"leaving out the {int(np.count_nonzero(~keep))} flagged poses would leave too "
                "few poses to identify every parameter, so they stay in the fit; "
                "measure more poses",
            )
            return problem.fit(everyone, start=fit.params), everyone, ~keep, warning
        used = keep
        fit = problem.fit(used, start=fit.params)
    return fit, used, ~used, None


def _outlier_warning(outliers: Sequence[Outlier], robust: bool) -> ArmcalWarning:
    shown = [
        f"row {o.row} (pose {o.pose}: residual {o.residual_mm:.3g} mm, "
        f"studentized {o.studentized:.3g})"
        for o in outliers[:5]
    ]
    more = f" and {len(outliers) - 5} more" if len(outliers) > 5 else ""
    what = "outlier" if len(outliers) == 1 else "outliers"
    if robust:
        action = "left out of the fit; check these measurements"
    else:
        action = "rerun with --robust to fit without them, or check these measurements"
    return ArmcalWarning(
        "outlier",
        f"{len(outliers)} {what} at the {OUTLIER_ALPHA:g} family-wise level: "
        f"{listing(shown)}{more}; {action}",
    )


#: Above this p-value the joint compliance does not lower the residual more than noise would.
COMPLIANCE_UNSEEN_P = 0.05


def _compliance_unseen_warning(
    fit: ComplianceFit,
    geometry_whitened: np.ndarray,
    whitened: np.ndarray,
    residuals: np.ndarray,
    dof: int,
) -> ArmcalWarning | None:
    """A ``compliance-unseen`` warning when the data do not show the joint compliance.

    The nested-model F test: with ``c`` compliance parameters and ``dof``
    residual degrees of freedom of the full fit, ``F = ((RSS_geometry - RSS) / c)
    / (RSS / dof)`` follows F(c, dof) when the joints do not deflect.  Both sums
    are of the *whitened* residuals (``W_i e_i``), the quantity each weighted
    fit minimised: with per-row sigma or another noise model, unweighted sums
    would be dominated by the noisiest rows and say nothing about the fit.  A
    p-value above :data:`COMPLIANCE_UNSEEN_P` means the loads in the data are too
    small (or the joints too stiff) to tell the compliance from noise: its values
    are then undetermined, however finite.  ``residuals`` (unweighted, mm) give
    the RMS the message shows.
    """
    from scipy import stats  # imported on use: `import armcal` stays light

    c = fit.values.size
    rss, rss_geometry = float(np.sum(whitened**2)), float(np.sum(geometry_whitened**2))
    if dof <= 0 or c == 0 or rss <= 0:
        return None
    f_value = max(rss_geometry - rss, 0.0) / c / (rss / dof)
    p_value = float(stats.f.sf(f_value, c, dof))
    if p_value <= COMPLIANCE_UNSEEN_P:
        return None
    model = fit.model
    std = np.sqrt(np.diag(fit.covariance)[-c:]) * model.display_scale
    shown = ", ".join(
        f"{name} = {v:.3g} ± {s:.3g} {unit}"
        for name, unit, v, s in zip(
            model.names, model.units, fit.values * model.display_scale, std, strict=True
        )
    )
    return ArmcalWarning(
        "compliance-unseen",
        f"the data do not show the joint compliance: it lowers the residual RMS only from "
        f"{fit.geometry_only_rms_mm:.4g} to {np.sqrt(np.mean(residuals**2)):.4g} mm, no more "
        f"than noise would (F test p = {p_value:.2g}), and its values are undetermined "
        f"({shown}); load the arm more (payload_kg) or fit the geometry alone "
        "(--no-compliance)",
    )


def _fit_warning(
    fit: GoodnessOfFit, sigma: float, suggested: float, flagged: int
) -> ArmcalWarning:
    causes = (
        f"outliers ({flagged} flagged; try --robust)" if flagged else "outliers (try --robust)"
    )
    return ArmcalWarning(
        "fit-inconsistent",
        f"the fit is inconsistent with sigma = {sigma:.3g} mm: chi2 = {fit.chi2:.4g} on "
        f"{fit.dof} degrees of freedom (p = {fit.p_value:.2g}); likely causes, in order: "
        f"{causes}; a wrong unit (angles in radians, positions in metres); a model that "
        "misses an effect (base offset, a wrong robot file, compliance under load); or sigma "
        f"too small (the residuals suggest about {suggested:.3g} mm)",
    )


def identify(
    arm: PlanarArm,
    q: np.ndarray,
    xy: np.ndarray,
    *,
    method: Method = "auto",
    sigma: float | None = None,
    pose_labels: Sequence[str] | None = None,
    rows: Sequence[int] | None = None,
    row_sigma: np.ndarray | None = None,
    robust: bool = False,
    tol: float = 1e-12,
    max_iter: int = 50,
    target: np.ndarray | None = None,
    elastic: Elastostatic | None = None,
    loads: Loads | None = None,
) -> Calibration:
    """Identify the deviations of ``arm`` from measured poses, and judge the fit.

    Parameters
    ----------
    arm : PlanarArm
        The nominal arm, with its noise model (:mod:`armcal.noise`) and fixed
        parameters.
    q : ndarray, shape (m, n)
        Commanded joint angles in rad.
    xy : ndarray, shape (m, 2)
        Measured end-effector positions in mm, in the instrument frame.
    method : {"auto", "closed-form", "gauss-newton"}
        ``"auto"`` is the closed form (exact for this model, see module notes)
        when every parameter is free, else Gauss-Newton.
    sigma : float, optional
        Instrument noise (1 std, mm), replacing the noise model's instrument
        part (encoder noise stays).  Without it and without a noise model on the
        arm or ``row_sigma``, sigma is estimated from the residuals, which needs
        ``2m > p_f``.
    pose_labels : sequence of str, optional
        Labels of the poses for reports; ``"1".."m"`` by default.
    rows : sequence of int, optional
        1-based data rows of the poses in their file, for reports; ``1..m`` by default.
    row_sigma : ndarray, shape (m,), optional
        Per-row instrument noise (mm), for instruments that report each point's
        uncertainty; replaces the instrument covariance row by row.
    robust : bool
        Fit with Huber's M-estimator from the least-squares fit, flag outliers
        by the studentized test (:mod:`armcal.diagnostics`), leave them out and
        refit until the set is stable.
    tol, max_iter
        Gauss-Newton step tolerance (relative to the reach) and iteration cap.
    target : ndarray of int, shape (m,), optional
        Every pose's target (index into ``arm.targets``), for an arm with several.
    elastic : Elastostatic, optional
        Identify the joint compliance under these loads with the geometry
        (:mod:`armcal.elastostatic`; Gauss-Newton from the geometry-only fit).
    loads : Loads, optional
        Every pose's payload and tip force (default: the robot file's payload).

    Returns
    -------
    Calibration

    Raises
    ------
    NotIdentifiableError
        If the plan cannot identify every free parameter (the rank policy of
        :mod:`armcal.numerics`); the message names the unseen combinations.
    ArmcalError
        If ``sigma`` must be estimated but ``2m = p_f`` leaves no residual freedom.

    Notes
    -----
    Without ``robust`` the fit is least squares on every pose, and the outlier
    test still runs: flagged poses are listed and warned about, not removed.
    Why Huber: the model is linear in the link phasors, so Huber's objective is
    convex there -- one optimum, reached from the closed form whatever the
    outliers -- and a pose's influence is bounded by its weight
    ``min(1, k sigma / |r_i|)``, so gross outliers barely move the fit the test
    then judges; clean poses keep weight 1 (``k`` is the 95 % point of a clean
    pose's radial residual, :data:`HUBER_K`).  The final estimate is ordinary
    (weighted) least squares on the poses kept, so its covariance is the usual one.

    Examples
    --------
    >>> arm = PlanarArm([260.0, 180.0])
    >>> q = np.radians([[0, 0], [0, 90], [0, 180], [0, -90]])
    >>> truth = arm.params_from_display([1.5, -0.6], [0.5, -0.5])
    >>> cal = identify(arm, q, forward_kinematics(arm, q, truth), sigma=0.1)
    >>> cal.values.round(9).tolist(), cal.std.round(4).tolist()
    ([1.5, -0.6, 0.5, -0.5], [0.05, 0.05, 0.011, 0.0194])
    >>> cal.goodness_of_fit.dof, [w.code for w in cal.warnings]
    (4, [])
    """
    q = np.asarray(q, dtype=float)
    xy = np.asarray(xy, dtype=float)
    m = q.shape[0]
    if q.ndim != 2 or q.shape[1] != arm.n_joints:
        raise ValueError(f"q must have shape (m, {arm.n_joints}) in rad, got {q.shape}")
    if xy.shape != (m, 2):
        raise ValueError(f"xy must have shape ({m}, 2) in mm, got {xy.shape}")
    if not (np.all(np.isfinite(q)) and np.all(np.isfinite(xy))):
        raise ArmcalError("joint angles and positions must be finite")
    target = check_target(arm, q, target)
    if row_sigma is not None:
        row_sigma = np.asarray(row_sigma, dtype=float)
        if row_sigma.shape != (m,) or not np.all(np.isfinite(row_sigma) & (row_sigma > 0)):
            raise ArmcalError("per-row sigma must be positive and finite, one value per pose")
    if method == "auto":
        method = "closed-form" if arm.complete and elastic is None else "gauss-newton"
    if elastic is not None and method == "closed-form":
        raise ArmcalError(
            "the closed form fits the geometry only; joint compliance needs --method "
            "gauss-newton (or auto)"
        )
    if method not in METHODS:
        raise ArmcalError(f"unknown method {method!r}; choose one of auto, {', '.join(METHODS)}")
    _check_closed_form(arm, method)
    if sigma is not None:
        noise = arm.noise
        arm = arm.replace(
            noise=NoiseModel.isotropic(sigma)
            if noise is None
            else noise.with_instrument_sigma(sigma)
        )
    given = arm.noise is not None or row_sigma is not None
    problem: _Problem
    model: Compliance | None = None
    if elastic is not None:
        loads = Loads.create(m, elastic.payload_kg) if loads is None else loads
        if loads.n_rows != m:
            raise ValueError(f"loads must have {m} rows, got {loads.n_rows}")
        if target is not None:
            raise ArmcalError(
                "joint compliance is modelled for one target on the end effector; "
                "measure one target per pose, or leave out [elastostatic]"
            )
        model = Compliance.for_loads(arm, elastic, loads)
        problem = _CompliantProblem(model, loads, q, xy, row_sigma, tol, max_iter)
        info, _ = check_compliance_identifiable(model, q, loads)
    else:
        problem = _Problem(arm, q, xy, row_sigma, method, tol, max_iter, target)
        plan = problem.plan_factor.svd if problem.plain else plan_svd(arm, q, target)
        info = check_identifiable(arm, q, svd=plan, target=target)
    n_free = problem.n_free
    dof_all = 2 * m - n_free
    if not given and dof_all <= 0:
        raise ArmcalError(
            f"{m} poses leave no residual to estimate sigma from ({2 * m} equations, "
            f"{n_free} parameters); give the instrument noise with --sigma or measure "
            "more poses"
        )
    reference = _reference_sigma(arm, row_sigma)
    everyone = np.ones(m, dtype=bool)
    extra: list[ArmcalWarning] = []
    robust_sigma = reference if given else None
    least_squares = problem.fit(everyone)
    fit, used = least_squares, everyone
    if robust:
        fit, used, flagged, kept_warning = _robust_fit(problem, robust_sigma, least_squares)
        if kept_warning is not None:
            extra.append(kept_warning)
    dof = 2 * int(np.count_nonzero(used)) - n_free
    source: Literal["given", "estimated"]
    if given:
        sigma_value, source = reference, "given"
    else:
        sigma_value, source = _scale(fit, used, max(dof, 1)), "estimated"
    standardized = fit.whitened / sigma_value
    test = _test(problem, fit, used, sigma_value, given)
    if not robust:
        flagged = test.flagged
    if not robust and np.any(test.flagged):
        # Gross outliers pull a least-squares fit towards them and inflate every
        # residual, so the poses to flag are those the robust procedure would
        # leave out, judged against its fit; this fit keeps them.
        clean, kept, flagged, _ = _robust_fit(problem, robust_sigma, least_squares)
        clean_dof = 2 * int(np.count_nonzero(kept)) - n_free
        scale = reference if given else _scale(clean, kept, max(clean_dof, 1))
        test = _test(problem, clean, kept, scale, given)
    labels = tuple(str(i) for i in range(1, m + 1)) if pose_labels is None else tuple(pose_labels)
    row_numbers = tuple(range(1, m + 1)) if rows is None else tuple(int(r) for r in rows)
    distance = np.hypot(fit.residuals[:, 0], fit.residuals[:, 1])
    outliers = tuple(
        Outlier(
            index=int(i),
            row=row_numbers[i],
            pose=labels[i],
            target=None if target is None else arm.targets[target[i]].label,
            residual_mm=float(distance[i]),
            studentized=float(test.statistic[i]),
            p_value=float(test.p_value[i]),
            removed=not bool(used[i]),
        )
        for i in np.flatnonzero(flagged)
    )
    fit_test = goodness_of_fit(standardized[used], dof, sigma_given=given)
    conditioning = (
        conditioning_warning(arm, info) if model is None else barely_identifiable_warning(info)
    )
    warnings = [w for w in (conditioning,) if w is not None]
    if not fit.converged:
        warnings.append(
            ArmcalWarning(
                "not-converged",
                f"{method} did not converge in {fit.iterations} iterations; "
                "try --method closed-form",
            )
        )
    if outliers:
        warnings.append(_outlier_warning(outliers, robust))
    warnings.extend(extra)
    if given and dof < FEW_DOF:
        more = -(-(FEW_DOF - dof) // 2)
        warnings.append(
            ArmcalWarning(
                "few-dof",
                f"{int(np.count_nonzero(used))} poses leave {dof} degrees of freedom for "
                f"{n_free} parameters: too few to judge the fit against sigma or to find "
                f"outliers; measure at least {more} more "
                f"{'pose' if more == 1 else 'poses'}",
            )
        )
    if not fit_test.consistent:
        suggested = sigma_value * float(np.sqrt((fit_test.chi2 or 0.0) / max(dof, 1)))
        warnings.append(
            _fit_warning(fit_test, sigma_value, suggested, int(np.count_nonzero(test.flagged)))
        )
    g = np.zeros((problem.free.size, n_free))
    g[problem.free] = fit.factor
    covariance = sigma_value**2 * (g @ g.T)
    p = arm.n_params
    compliance = None
    if model is not None:
        # The geometry alone, fitted as the compliant model was: weighted by the same
        # noise model and per-row sigma, on the same poses, so that the F test compares
        # the sums of squares each fit minimised (whitened residuals, in one unit).
        geometry = _Problem(arm, q, xy, row_sigma, "auto", tol, max_iter).fit(used)
        assert loads is not None
        bent = model.deflection(q, fit.params[:p], fit.params[p:], loads)
        compliance = ComplianceFit(
            model,
            fit.params[p:],
            covariance,
            float(np.sqrt(np.mean(geometry.residuals[used] ** 2))),
            np.max(np.abs(bent), axis=0),
        )
        unseen = _compliance_unseen_warning(
            compliance, geometry.whitened[used], fit.whitened[used], fit.residuals[used], dof
        )
        if unseen is not None and conditioning is None:
            warnings.append(unseen)
    return Calibration(
        arm=arm,
        method=method,
        params=fit.params[:p],
        covariance=covariance[:p, :p],
        sigma_mm=float(sigma_value),
        sigma_source=source,
        residuals=fit.residuals,
        iterations=int(fit.iterations),
        converged=bool(fit.converged),
        pose_labels=labels,
        warnings=tuple(warnings),
        goodness_of_fit=fit_test,
        standardized_residuals=standardized,
        outliers=outliers,
        used=used,
        rows=row_numbers,
        robust=bool(robust),
        target=target,
        compliance=compliance,
        loads=loads if model is not None else None,
    )
