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

Uncertainty is ``cov = sigma^2 (J^T J)^-1`` at the solution (paper eq. 16), with
``sigma`` given by the user or estimated as ``s^2 = RSS / (2m - p)``.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any, Literal

import numpy as np

from .arm import (
    PlanarArm,
    forward_kinematics,
    link_angles,
    paper_from_user_matrix,
    wrap_angle,
)
from .criteria import check_identifiable, inverse_information
from .errors import ArmcalError, ArmcalWarning

__all__ = [
    "METHODS",
    "Calibration",
    "identify",
    "solve_closed_form",
    "solve_gauss_newton",
]


Method = Literal["auto", "closed-form", "gauss-newton"]


def _regressor(arm: PlanarArm, q: np.ndarray) -> np.ndarray:
    """Real design matrix ``(2m, p)`` of the linear model in ``(Re z, Im z, x0, y0)``.

    Rows alternate x, y per pose.  Columns: ``Re z_k``, ``Im z_k`` for every link,
    then ``x0, y0`` with a base offset.
    """
    unit = np.exp(1j * np.cumsum(q, axis=-1))  # (m, n)
    cols = [unit, 1j * unit]
    if arm.base_offset:
        cols.append(np.broadcast_to(np.array([1.0, 1j]), (q.shape[0], 2)))
    a = np.concatenate(cols, axis=-1)
    return np.stack([a.real, a.imag], axis=1).reshape(2 * q.shape[0], -1)


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

    Notes
    -----
    Solves ``min ||A w - y||`` for ``w = (Re z, Im z, x0, y0)`` with the
    SVD-based pseudo-inverse of ``A`` (:func:`numpy.linalg.pinv`), then ``dl_k = |z_k| - l_k``,
    ``dtheta_k = arg z_k`` and ``dq_k = wrap(dtheta_k - dtheta_{k-1})``.
    The plan must identify every parameter (:func:`check_identifiable`).

    Examples
    --------
    >>> arm = PlanarArm([2.0, 1.0])
    >>> q = np.radians([[0, 0], [0, 90], [90, 90], [45, -120]])
    >>> truth = np.array([0.1, -0.05, 0.01, -0.02])
    >>> est = solve_closed_form(arm, q, forward_kinematics(arm, q, truth))
    >>> bool(np.allclose(est, truth, atol=1e-12))
    True
    """
    q = np.asarray(q, dtype=float)
    xy = np.asarray(xy, dtype=float)
    batched = xy.ndim == 3
    # One SVD-based pseudo-inverse of the plan's regressor serves every set: the
    # solution is the same as lstsq's, and N sets cost one matrix product.
    pseudo_inverse = np.linalg.pinv(_regressor(arm, q))  # (p, 2m)
    w = xy.reshape(-1, 2 * q.shape[0]) @ pseudo_inverse.T  # (N, p)
    n = arm.n_joints
    z = w[:, :n] + 1j * w[:, n : 2 * n]
    dtheta = np.angle(z)
    dq = wrap_angle(np.diff(dtheta, axis=-1, prepend=0.0))
    params = np.concatenate([np.abs(z) - arm.link_lengths, dq, w[:, 2 * n :]], axis=-1)
    return params if batched else params[0]


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

    Notes
    -----
    Step 1 starts from ``DeltaPi = 0``; Steps 2-3 evaluate model (1) and solve the
    linearized problem (11) at the current estimate (the Jacobian (7)-(8) uses the
    corrected lengths and angles of Step 4); Step 5 repeats until the step is below
    the tolerance.

    Every set still iterating is solved at once.  In phasor form the model is
    ``x + i y = b + sum_k z_k u_k`` with ``u_k = exp(i theta_k(q))`` fixed by the
    plan and ``z_k = (l_k + dl_k) exp(i dtheta_k)``, so each Jacobian column is a
    per-set coefficient times a plan-only column ``v_a`` (``i z_k u_k`` for
    ``dtheta_k``, ``exp(i dtheta_k) u_k`` for ``dl_k``, ``1`` and ``i`` for the
    base).  The normal matrix is then ``Re(conj(g_a) g_b W_ab)`` with the plan's
    ``W = V^H V`` computed once, and ``J^T r = Re(conj(g) V^H r)``: the stacked
    normal equations of all sets cost a few matrix products and one batched
    :func:`numpy.linalg.solve`.  Columns are scaled to unit norm first, so mm
    and rad weigh alike; rounding in a step is corrected by the next iteration,
    whose residual is exact, so the converged estimate is accurate to round-off
    whenever ``cond(D J^T J D) * eps < 1``.

    Examples
    --------
    >>> arm = PlanarArm([2.0, 1.0])
    >>> q = np.radians([[0, 0], [0, 90], [90, 90], [45, -120]])
    >>> truth = np.array([0.1, -0.05, 0.01, -0.02])
    >>> est, iterations, converged = solve_gauss_newton(arm, q, forward_kinematics(arm, q, truth))
    >>> bool(np.allclose(est, truth, atol=1e-12)), bool(converged)
    (True, True)
    """
    q = np.asarray(q, dtype=float)
    xy = np.asarray(xy, dtype=float)
    batched = xy.ndim == 3
    xy = xy.reshape(-1, q.shape[0], 2)
    measured = xy[..., 0] + 1j * xy[..., 1]  # (N, m)
    n, p, sets = arm.n_joints, arm.n_params, xy.shape[0]
    unit = np.exp(1j * link_angles(q))  # (m, n), plan only
    columns = [unit, unit] + [np.ones((q.shape[0], 2))] * arm.base_offset
    basis = np.concatenate(columns, axis=1)  # (m, p): v_a
    gram = basis.conj().T @ basis  # W
    column_norms = np.sqrt(np.diagonal(gram).real)
    step_scale = np.ones(p)
    step_scale[:n] = arm.link_lengths  # rad -> mm at the link tip
    threshold = tol * float(np.sum(arm.link_lengths))
    paper = np.zeros((sets, p))  # (dtheta, dl, [x0, y0]) of every set
    iterations = np.zeros(sets, dtype=int)
    active = np.arange(sets)
    for _ in range(max_iter):
        current = paper[active]
        rotation = np.exp(1j * current[:, :n])
        z = (arm.link_lengths + current[:, n : 2 * n]) * rotation
        coefficients = [1j * z, rotation]
        base = 0.0
        if arm.base_offset:
            base = current[:, 2 * n] + 1j * current[:, 2 * n + 1]
            coefficients.append(np.broadcast_to(np.array([1.0, 1j]), (active.size, 2)))
        # Column norms |g_a| sqrt(W_aa), folded into g: the scaled normal matrix
        # has a unit diagonal.
        g = np.concatenate(coefficients, axis=1)  # (k, p)
        norms = np.abs(g) * column_norms
        g = g.conj() / norms  # conj(g) D
        residual = measured[active] - z @ unit.T - np.reshape(base, (-1, 1))
        scaled = (g[:, :, None] * g.conj()[:, None, :] * gram).real
        rhs = (g * (residual @ basis.conj())).real
        step = np.linalg.solve(scaled, rhs[..., None])[..., 0] / norms
        paper[active] += step
        iterations[active] += 1
        active = active[np.max(np.abs(step * step_scale), axis=1) > threshold]
        if active.size == 0:
            break
    converged = np.ones(sets, dtype=bool)
    converged[active] = False
    to_user = np.linalg.inv(paper_from_user_matrix(n, base_offset=arm.base_offset))
    params = paper @ to_user.T
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
    sigma : float
        Measurement noise (1 std, mm) used for ``covariance``.
    sigma_source : {"given", "estimated"}
        Whether ``sigma`` was given or estimated as ``sqrt(RSS / (2m - p))``.
    residuals : ndarray, shape (m, 2)
        Measured minus fitted positions in mm.
    iterations : int
        Linearized solves (1 for the closed form).
    converged : bool
        Whether the solver met its tolerance.
    pose_labels : tuple of str
        A label for every pose (the measurement file's ``pose`` column, or 1..m).
    warnings : tuple of ArmcalWarning
        What makes the result suspicious (e.g. a solver that did not converge);
        empty when nothing does.
    """

    arm: PlanarArm
    method: str
    params: np.ndarray
    covariance: np.ndarray
    sigma: float
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
        If the plan cannot identify every parameter.
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
    check_identifiable(arm, q)
    given = sigma if sigma is not None else arm.sigma
    dof = 2 * m - arm.n_params
    if given is None and dof <= 0:
        raise ArmcalError(
            f"{m} poses leave no residual to estimate sigma from ({2 * m} equations, "
            f"{arm.n_params} parameters); give the instrument noise with --sigma or measure "
            "more poses"
        )
    params, iterations, converged = METHODS[method](arm, q, xy, tol=tol, max_iter=max_iter)
    if not np.all(np.isfinite(params)):
        raise ArmcalError("the fit overflowed; check that positions are in mm and plausible")
    residuals = xy - forward_kinematics(arm, q, params)
    covariance = inverse_information(arm, q, params)
    if covariance is None:  # identifiable at nominal, so only for absurd deviations
        raise ArmcalError("the Jacobian is singular at the estimate; check the data")
    if given is None:
        sigma_value, source = float(np.sqrt(np.sum(residuals**2) / dof)), "estimated"
    else:
        sigma_value, source = float(given), "given"
    labels = tuple(str(i) for i in range(1, m + 1)) if pose_labels is None else tuple(pose_labels)
    warnings = []
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
        sigma=sigma_value,
        sigma_source=source,
        residuals=residuals,
        iterations=int(iterations),
        converged=bool(converged),
        pose_labels=labels,
        warnings=tuple(warnings),
    )
