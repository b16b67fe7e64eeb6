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
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any, Literal

import numpy as np

from .arm import PlanarArm, forward_kinematics, wrap_angle
from .criteria import inverse_information
from .errors import ArmcalError, ArmcalWarning
from .numerics import LinearLeastSquares, factor_least_squares
from .observability import check_identifiable, conditioning_warning, scaled_jacobian

__all__ = [
    "METHODS",
    "Calibration",
    "identify",
    "solve_closed_form",
    "solve_gauss_newton",
]


Method = Literal["auto", "closed-form", "gauss-newton"]


def _factor(arm: PlanarArm, q: np.ndarray) -> LinearLeastSquares:
    """The plan's factorization; raises :class:`NotIdentifiableError` for a singular plan."""
    factor = factor_least_squares(scaled_jacobian(arm, q))
    if not bool(factor.svd.full_rank):
        check_identifiable(arm, q, svd=factor.svd)  # raises, naming the unseen combinations
    return factor


def _link_phasors_fit(factor: LinearLeastSquares, xy: np.ndarray) -> np.ndarray:
    """Least-squares ``v = (Im z_1..n, Re z_1..n, [x0, y0])`` ``(N, p)`` of sets ``xy (N, m, 2)``.

    The tip is ``sqrt(m) H v`` (:func:`armcal.criteria.scaled_jacobian`), so
    ``v = H^+ y / sqrt(m)``: one projection ``Q^T y`` and a ``p x p`` product per set.
    """
    m = xy.shape[-2]
    return factor.solve(xy.reshape(-1, 2 * m)) / np.sqrt(m)


def _closed_form_params(arm: PlanarArm, v: np.ndarray) -> np.ndarray:
    n = arm.n_joints
    z = v[:, n : 2 * n] + 1j * v[:, :n]
    # dq_k = dtheta_k - dtheta_(k-1), wrapped into (-pi, pi], is the angle of
    # z_k conj(z_(k-1)) (z_0 = 1): one angle instead of n angles, a diff and a wrap.
    relative = z.copy()
    relative[:, 1:] *= z[:, :-1].conj()
    return np.concatenate(
        [np.abs(z) - arm.link_lengths, np.angle(relative), v[:, 2 * n :]], axis=-1
    )


def _as_sets(arm: PlanarArm, q: np.ndarray, xy: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    q = np.asarray(q, dtype=float)
    xy = np.asarray(xy, dtype=float)
    if q.ndim != 2 or q.shape[1] != arm.n_joints:
        raise ValueError(f"q must have shape (m, {arm.n_joints}) in rad, got {q.shape}")
    if xy.shape[-2:] != (q.shape[0], 2) or xy.ndim not in (2, 3):
        raise ValueError(f"xy must have shape ({q.shape[0]}, 2) or (N, {q.shape[0]}, 2) in mm")
    return q, xy.reshape(-1, q.shape[0], 2)


def solve_closed_form(arm: PlanarArm, q: np.ndarray, xy: np.ndarray) -> np.ndarray:
    """Exact least-squares deviations by one linear solve; batched over measurement sets.

    Parameters
    ----------
    arm : PlanarArm
    q : ndarray, shape (m, n)
        Joint angles in rad (shared by every measurement set).
    xy : ndarray, shape (m, 2) or (N, m, 2)
        Measured positions in mm; a leading axis holds ``N`` independent sets.

    Returns
    -------
    ndarray, shape (p,) or (N, p)
        User deviations ``[dl (mm), dq (rad), (x0, y0) (mm)]``.

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
    params = _closed_form_params(arm, _link_phasors_fit(_factor(arm, q), sets))
    return params if batched else params[0]


def _gauss_newton(
    arm: PlanarArm, v: np.ndarray, *, tol: float, max_iter: int
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Gauss-Newton iterations from zero deviations towards the fitted phasors ``v (N, p)``."""
    n = arm.n_joints
    sets = v.shape[0]
    target = v[:, n : 2 * n] + 1j * v[:, :n]  # least-squares z_k of every set
    step_scale = np.ones(arm.n_params)
    step_scale[:n] = arm.link_lengths  # rad -> mm at the link tip
    threshold = tol * float(np.sum(arm.link_lengths))
    paper = np.zeros((sets, arm.n_params))  # (dtheta, dl, [x0, y0]) of every set
    iterations = np.zeros(sets, dtype=int)
    failed = np.zeros(sets, dtype=bool)
    active = np.arange(sets)
    for _ in range(max_iter):
        current = paper[active]
        rotation = np.exp(1j * current[:, :n])
        length = arm.link_lengths + current[:, n : 2 * n]
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
    length = arm.link_lengths + paper[:, n : 2 * n]
    flipped = length < 0
    dtheta = paper[:, :n] + np.pi * flipped
    dl = np.where(flipped, -length, length) - arm.link_lengths
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
    v = _link_phasors_fit(_factor(arm, q), sets)
    params, iterations, converged = _gauss_newton(arm, v, tol=tol, max_iter=max_iter)
    if batched:
        return params, iterations, converged
    return params[0], iterations[0], converged[0]


@dataclass(frozen=True, eq=False)
class Calibration:
    """Identified deviations with their uncertainty and the fit's residuals.

    Attributes
    ----------
    arm : PlanarArm
        The nominal arm that was calibrated.
    method : str
        Solver used: ``"closed-form"`` or ``"gauss-newton"``.
    params : ndarray, shape (p,)
        User deviations in internal units: ``dl`` (mm), ``dq`` (rad), ``x0, y0`` (mm).
    covariance : ndarray, shape (p, p)
        ``sigma^2 (J^T J)^-1`` in internal units (mm, rad).
    sigma_mm : float
        Measurement noise (1 std, mm) used for ``covariance``.
    sigma_source : {"given", "estimated"}
        Whether ``sigma_mm`` was given or estimated as ``sqrt(RSS / (2m - p))``.
    residuals : ndarray, shape (m, 2)
        Measured minus fitted positions in mm.
    iterations : int
        Linearized solves (1 for the closed form).
    converged : bool
        Whether the solver met its tolerance.
    pose_labels : tuple of str
        A label for every pose (the measurement file's ``pose`` column, or 1..m).
    warnings : tuple of ArmcalWarning
        What makes the result suspicious: an ``ill-conditioned`` plan (condition
        number above :data:`armcal.numerics.COND_WARN`, naming the poorly
        determined combinations), a solver that did not converge; empty when
        nothing does.
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

    @property
    def n_poses(self) -> int:
        """Number of measured poses ``m``."""
        return int(self.residuals.shape[0])

    @property
    def dof(self) -> int:
        """Residual degrees of freedom ``2m - p``."""
        return 2 * self.n_poses - self.arm.n_params

    @property
    def names(self) -> tuple[str, ...]:
        """Parameter names ``dl1.., dq1.., (x0, y0)``."""
        return self.arm.param_names

    @property
    def units(self) -> tuple[str, ...]:
        """Display units of the parameters (``mm`` or ``deg``)."""
        return self.arm.param_units

    @property
    def values(self) -> np.ndarray:
        """Parameter values ``(p,)`` in display units (mm, deg)."""
        return self.params * self.arm.display_scale

    @property
    def covariance_display(self) -> np.ndarray:
        """Covariance ``(p, p)`` in display units (mm, deg)."""
        s = self.arm.display_scale
        return self.covariance * np.outer(s, s)

    @property
    def std(self) -> np.ndarray:
        """Standard errors ``(p,)`` in display units (mm, deg)."""
        return np.sqrt(np.diag(self.covariance_display))

    @property
    def correlation(self) -> np.ndarray:
        """Correlation matrix ``(p, p)`` of the estimates."""
        d = np.sqrt(np.diag(self.covariance))
        return self.covariance / np.outer(d, d)

    @property
    def pose_residuals(self) -> np.ndarray:
        """Euclidean residual of every pose ``(m,)`` in mm."""
        return np.hypot(self.residuals[:, 0], self.residuals[:, 1])

    @property
    def residual_rms(self) -> float:
        """RMS of all ``2m`` residual coordinates in mm, ``sqrt(RSS / 2m)``."""
        return float(np.sqrt(np.mean(self.residuals**2)))

    @property
    def residual_max(self) -> float:
        """Largest Euclidean residual of a pose, in mm."""
        return float(np.max(self.pose_residuals))


def _closed_form(arm: PlanarArm, q: np.ndarray, xy: np.ndarray, **_: object):
    return solve_closed_form(arm, q, xy), 1, True


#: Solvers by name; each takes ``xy`` of shape ``(m, 2)`` or ``(N, m, 2)`` and returns
#: ``(params, iterations, converged)``, batched alike.
METHODS: dict[str, Callable[..., tuple[np.ndarray, Any, Any]]] = {
    "closed-form": _closed_form,
    "gauss-newton": solve_gauss_newton,
}


def identify(
    arm: PlanarArm,
    q: np.ndarray,
    xy: np.ndarray,
    *,
    method: Method = "auto",
    sigma: float | None = None,
    pose_labels: Sequence[str] | None = None,
    tol: float = 1e-12,
    max_iter: int = 50,
) -> Calibration:
    """Identify the deviations of ``arm`` from measured poses.

    Parameters
    ----------
    arm : PlanarArm
    q : ndarray, shape (m, n)
        Commanded joint angles in rad.
    xy : ndarray, shape (m, 2)
        Measured end-effector positions in mm, in the instrument frame.
    method : {"auto", "closed-form", "gauss-newton"}
        ``"auto"`` is the closed form, exact for this model (see module notes).
    sigma : float, optional
        Measurement noise (1 std, mm).  Defaults to ``arm.sigma``; when neither is
        set it is estimated from the residuals, which needs ``2m > p``.
    pose_labels : sequence of str, optional
        Labels of the poses for reports; ``"1".."m"`` by default.
    tol, max_iter
        Gauss-Newton step tolerance (relative to the reach) and iteration cap.

    Returns
    -------
    Calibration

    Raises
    ------
    NotIdentifiableError
        If the plan cannot identify every parameter (the rank policy of
        :mod:`armcal.numerics`); the message names the unseen combinations.
    ArmcalError
        If ``sigma`` must be estimated but ``2m = p`` leaves no residual freedom.

    Examples
    --------
    >>> arm = PlanarArm([260.0, 180.0])
    >>> q = np.radians([[0, 0], [0, 90], [0, 180], [0, -90]])
    >>> truth = arm.params_from_display([1.5, -0.6], [0.5, -0.5])
    >>> cal = identify(arm, q, forward_kinematics(arm, q, truth), sigma=0.1)
    >>> cal.values.round(9).tolist(), cal.std.round(4).tolist()
    ([1.5, -0.6, 0.5, -0.5], [0.05, 0.05, 0.011, 0.0194])
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
    if method == "auto":
        method = "closed-form"
    if method not in METHODS:
        raise ArmcalError(f"unknown method {method!r}; choose one of auto, {', '.join(METHODS)}")
    factor = factor_least_squares(scaled_jacobian(arm, q))  # one thin QR for everything
    info = check_identifiable(arm, q, svd=factor.svd)
    given = sigma if sigma is not None else arm.sigma
    dof = 2 * m - arm.n_params
    if given is None and dof <= 0:
        raise ArmcalError(
            f"{m} poses leave no residual to estimate sigma from ({2 * m} equations, "
            f"{arm.n_params} parameters); give the instrument noise with --sigma or measure "
            "more poses"
        )
    v = _link_phasors_fit(factor, xy[None])
    if method == "closed-form":
        params, iterations, converged = _closed_form_params(arm, v)[0], 1, True
    else:
        fitted, steps, done = _gauss_newton(arm, v, tol=tol, max_iter=max_iter)
        params, iterations, converged = fitted[0], int(steps[0]), bool(done[0])
    if not np.all(np.isfinite(params)):
        raise ArmcalError("the fit overflowed; check that positions are in mm and plausible")
    residuals = xy - forward_kinematics(arm, q, params)
    covariance = inverse_information(arm, q, params, svd=factor.svd)
    if covariance is None:  # identifiable at nominal, so only for absurd deviations
        raise ArmcalError("the Jacobian is singular at the estimate; check the data")
    source: Literal["given", "estimated"]
    if given is None:
        sigma_value, source = float(np.sqrt(np.sum(residuals**2) / dof)), "estimated"
    else:
        sigma_value, source = float(given), "given"
    labels = tuple(str(i) for i in range(1, m + 1)) if pose_labels is None else tuple(pose_labels)
    warnings = [w for w in (conditioning_warning(arm, info),) if w is not None]
    if not converged:
        warnings.append(
            ArmcalWarning(
                "not-converged",
                f"{method} did not converge in {int(iterations)} iterations; "
                "try --method closed-form",
            )
        )
    return Calibration(
        arm=arm,
        method=method,
        params=params,
        covariance=sigma_value**2 * covariance,
        sigma_mm=sigma_value,
        sigma_source=source,
        residuals=residuals,
        iterations=int(iterations),
        converged=bool(converged),
        pose_labels=labels,
        warnings=tuple(warnings),
    )
