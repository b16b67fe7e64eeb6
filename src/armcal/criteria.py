"""Quality of a calibration plan: information matrix, optimality criteria, predicted accuracy.

Everything here is a pure function of a plan ``q`` (joint angles, rad, shape
``(m, n)`` or batched ``(..., m, n)``) at the nominal parameters, with unit
measurement noise unless ``sigma`` is given.

**Scaling.** The information matrix ``F = sum_i J_i^T J_i`` (paper eq. 16-19) in
the paper's parametrization ``(dtheta, dl, [x0, y0])`` mixes mm^2 and mm^2/rad^2.
Every criterion is computed on the *Hadamard-normalized* matrix

    Fs = D F D,   D = diag(1 / sqrt(F_opt)),   F_opt = diag(m l_i^2, m, [m, m])

where ``F_opt`` is the information matrix of an orthogonal plan (paper eq. 24,
Table II).  Since the diagonal of ``F`` is ``(m l_i^2, m, [m, m])`` for *every*
plan, ``Fs`` has a unit diagonal, and Hadamard's inequality gives
``det Fs <= 1`` with equality iff ``F`` is diagonal -- the paper's optimality
conditions (21).  So every efficiency below is 1 exactly for orthogonal plans
and smaller otherwise.

**One rank policy.**  ``Fs = H^T H`` with ``H``
(:func:`armcal.observability.scaled_jacobian`) the Jacobian of the nominal arm
in the paper's parametrization with unit-norm columns, rows divided by
``sqrt(m)``.  At *any* deviations the paper Jacobian with unit-norm columns is
``H`` times an orthogonal matrix (each link's two columns turn by
``dtheta_k``), so the singular values of ``H`` alone decide, through
:mod:`armcal.numerics`, whether a plan is identifiable
(:func:`armcal.observability.identifiability`), its covariance
(:func:`inverse_information_batch`),
its efficiencies and observability indices, and whether results carry an
``ill-conditioned`` warning.  They are computed from a thin QR of ``H``, never
from the eigenvalues of ``Fs``, which cannot resolve a relative singular value
below ``sqrt(eps) ~ 1e-8``.

**Weighted and reduced models.**  With anisotropic or encoder noise
(:mod:`armcal.noise`) or fixed parameters, ``H`` is the whitened Jacobian in the
coordinates of the free parameters (:func:`armcal.observability.model_basis`):
every criterion is then the same function of the weighted information matrix
``H^T H``, no longer Hadamard-normalized (its diagonal depends on the plan), so
an efficiency compares plans of one model but is not 1 at its optimum; the
certificate of :mod:`armcal.doe` says how far from the optimum a plan is.  The
paper's conditions (21), its D* and the orthogonal plans assume isotropic iid
noise and every parameter free.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from .errors import ArmcalWarning
from .models import (
    PlanarArm,
    check_identifiable,
    conditioning_warning,
    covariance_factor,
    jacobian,
    model_columns,
    plan_rows,
    plan_svd,
    scaled_jacobian,
    unit_trace,
    weighted_user_jacobian,
)
from .numerics import COND_WARN, RANK_RTOL, ScaledSVD, spd_inverse

__all__ = [
    "COND_WARN",
    "CRITERIA",
    "RANK_RTOL",
    "Criterion",
    "DStar",
    "PlanQuality",
    "PositionAccuracy",
    "d_efficiency",
    "dstar",
    "efficiencies",
    "evaluate_plan",
    "information_matrix",
    "inverse_information",
    "inverse_information_batch",
    "model_singular_values",
    "observability_indices",
    "optimality_sums",
    "position_accuracy",
    "position_rms",
    "predicted_std",
    "scaled_information",
    "std_from_covariance",
    "weighted_information",
    "weighted_user_jacobian",
]


def information_matrix(arm: PlanarArm, q: np.ndarray) -> np.ndarray:
    """Information matrix ``F = sum_i J_i^T J_i`` in the paper's parametrization.

    Parameters
    ----------
    arm : PlanarArm
    q : ndarray, shape (..., m, n)
        Plans (joint angles in rad); leading axes batch over plans.

    Returns
    -------
    ndarray, shape (..., p, p)
        Per unit noise variance: ``cov = sigma^2 F^-1`` (paper eq. 16).
    """
    jac = jacobian(arm, q, parametrization="paper")
    return np.einsum("...mki,...mkj->...ij", jac, jac)


def weighted_information(columns: np.ndarray, weights: np.ndarray) -> np.ndarray:
    """``sum_i w_i J_i^T J_i`` ``(..., p, p)`` from complex columns and weights ``(..., m)``."""
    return np.einsum("...m,...ma,...mb->...ab", weights, columns.conj(), columns).real


def scaled_information(arm: PlanarArm, q: np.ndarray) -> np.ndarray:
    """Hadamard-normalized information ``Fs = D F D`` ``(..., p, p)`` with unit diagonal."""
    columns = model_columns(arm, np.asarray(q, dtype=float))
    return weighted_information(columns, np.full(columns.shape[:-1], 1 / columns.shape[-2]))


def inverse_information_batch(
    arm: PlanarArm,
    q: np.ndarray,
    params: np.ndarray | None = None,
    *,
    svd: ScaledSVD | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """``(J^T J)^-1`` in the user parametrization for a stack of plans, with an identifiable mask.

    Parameters
    ----------
    arm : PlanarArm
    q : ndarray, shape (..., m, n)
        Plans (rad); leading axes batch over plans.
    params : ndarray, shape (p,) or (..., p), optional
        Deviations at which to linearize (nominal when omitted).
    svd : ScaledSVD, optional
        ``plan_svd(arm, q)`` when the caller has it already (it does not depend
        on ``params``).

    Returns
    -------
    inverse : ndarray, shape (..., p, p)
        ``(J^T J)^-1`` (mm, rad); entries of singular plans are ``inf``.
    identifiable : ndarray of bool, shape (...)
        False where the rank policy (:data:`armcal.numerics.RANK_RTOL` on the
        singular values of :func:`scaled_jacobian`) calls the plan singular --
        the test of :func:`identifiability` -- or a link has length 0 at ``params``.

    Notes
    -----
    ``J = sqrt(m) H T^-1`` with ``T`` explicit (a rotation and a division by the
    link length per link), so ``(J^T J)^-1 = T V S^-2 V^T T^T / m`` from the SVD
    of ``H``: accurate to ``cond(H) eps``, with no Gram matrix inverted.
    """
    g, ok = covariance_factor(arm, q, params, svd)
    safe = np.where(ok[..., None, None], g, 0.0)
    inverse = safe @ np.swapaxes(safe, -1, -2)
    return np.where(ok[..., None, None], inverse, np.inf), ok


def inverse_information(
    arm: PlanarArm,
    q: np.ndarray,
    params: np.ndarray | None = None,
    *,
    svd: ScaledSVD | None = None,
) -> np.ndarray | None:
    """``(J^T J)^-1`` ``(p, p)`` in the user parametrization (mm, rad), or None if singular.

    See :func:`inverse_information_batch`; singular means what
    :func:`identifiability` calls not identifiable.
    """
    inverse, ok = inverse_information_batch(arm, q, params, svd=svd)
    return inverse if bool(ok) else None


def _logdet(fs: np.ndarray) -> np.ndarray:
    sign, logdet = np.linalg.slogdet(fs)  # LU-based: never raises for a finite matrix
    return np.where(sign > 0, logdet, -np.inf)


def d_efficiency(arm: PlanarArm, q: np.ndarray) -> np.ndarray:
    """D-efficiency ``(det F / det F_opt)^(1/p)`` of plans ``q`` ``(..., m, n)``.

    1 exactly for plans meeting the paper's conditions (21); 0 for plans that
    cannot identify every parameter (the rank policy of :mod:`armcal.numerics`).
    Computed as ``(s_1 ... s_p)^(2/p)`` from the singular values of
    :func:`scaled_jacobian`.

    Examples
    --------
    >>> from armcal.doe import orthogonal_plan
    >>> arm = PlanarArm([260.0, 180.0, 120.0, 100.0])
    >>> round(float(d_efficiency(arm, orthogonal_plan(arm, 20))), 12)
    1.0
    >>> float(d_efficiency(arm, np.zeros((6, 4))))   # six identical poses
    0.0
    """
    return CRITERIA["D"].from_singular_values(model_singular_values(arm, q))


def model_singular_values(
    arm: PlanarArm, q: np.ndarray, svd: ScaledSVD | None = None
) -> np.ndarray:
    """Singular values ``(..., p_f)`` of :func:`scaled_jacobian`, those the policy drops set to 0.

    For the paper's model the columns have unit norm and these are the policy's
    own.  For a weighted or reduced model (:attr:`PlanarArm.standard` false) they
    are the singular values of the unnormalized matrix, so that the criteria
    measure the weighted information, not only how orthogonal the columns are.
    """
    svd = plan_svd(arm, q) if svd is None else svd
    if arm.standard:
        return svd.truncated
    raw = np.linalg.svd(scaled_jacobian(arm, q), compute_uv=False)
    return np.where(svd.kept, raw, 0.0)


@dataclass(frozen=True)
class DStar:
    """The paper's D* pair (eq. 20) with ``C' = C / m`` and ``S' = S / m``.

    Attributes
    ----------
    det_c : float or ndarray
        ``det(C')``, at most 1 (Hadamard), 1 exactly at the optimum.
    abs_det_s : float or ndarray
        ``|det(S')|``, 0 at the optimum and identically 0 for odd ``n``.

    Notes
    -----
    ``c_jk = sum_i cos(theta_j - theta_k)`` and ``s_jk = sum_i sin(theta_j - theta_k)``
    (eq. 18).  The paper prints ``C' = [c_jk / n]``; but ``c_jj = m`` for every plan,
    so only division by the number of poses ``m`` gives ``det C' = 1`` at the
    optimum (``C = m I``) as the paper states -- ``/n`` is a typo.  ``S`` is
    skew-symmetric (``s_kj = -s_jk``), so ``det S = det S^T = (-1)^n det S``
    vanishes for odd ``n`` whatever the plan: ``|det S'|`` only carries information
    for even ``n``, and minimizing it is not the same as making ``S = 0``.
    """

    det_c: np.ndarray
    abs_det_s: np.ndarray


def _relative_sums(arm: PlanarArm, q: np.ndarray) -> np.ndarray:
    """``sum_i exp(i (theta_j - theta_k))`` ``(..., n, n)``: ``C + i S`` of eq. (18)."""
    unit = np.exp(1j * arm.link_angles(q))
    return np.einsum("...mj,...mk->...jk", unit, unit.conj())


def dstar(arm: PlanarArm, q: np.ndarray) -> DStar:
    """The paper's D* criterion pair ``det(C')``, ``|det(S')|`` (eq. 20), see :class:`DStar`."""
    m = np.shape(q)[-2]
    sums = _relative_sums(arm, q) / m
    # The paper's own numbers: plain determinants of n x n matrices with entries in
    # [-1, 1] (no overflow); numpy's LU determinant returns 0 for a singular matrix.
    return DStar(np.linalg.det(sums.real), np.abs(np.linalg.det(sums.imag)))


def optimality_sums(arm: PlanarArm, q: np.ndarray) -> dict[str, float]:
    """Every sum of the paper's optimality conditions (21) / Table I, by name.

    For ``1 <= j < k <= n`` the keys ``"cos(q{j+1}+...+q{k})"`` and
    ``"sin(...)"`` hold ``sum_i cos(theta_k - theta_j)`` and the sine, i.e. the
    paper's ``c_jk, s_jk``; with a base offset ``"cos(q1+...+qj)"`` sums (from
    the base columns) are included.  All vanish for an optimal plan.

    Examples
    --------
    >>> from armcal.doe import orthogonal_plan
    >>> sums = optimality_sums(PlanarArm([2.0, 1.0]), orthogonal_plan(PlanarArm([2.0, 1.0]), 3))
    >>> sorted(sums), max(abs(v) for v in sums.values()) < 1e-12
    (['cos(q2)', 'sin(q2)'], True)
    """
    q = np.asarray(q, dtype=float)
    n = arm.n_joints
    # theta_0 = 0 stands for the base: its pairs appear only when the base is identified.
    theta = np.concatenate([np.zeros((q.shape[0], 1)), arm.link_angles(q)], axis=1)
    out: dict[str, float] = {}
    for j in range(0 if arm.base_offset else 1, n + 1):
        for k in range(j + 1, n + 1):
            label = "+".join(f"q{a}" for a in range(j + 1, k + 1))
            angle = theta[:, k] - theta[:, j]
            out[f"cos({label})"] = float(np.sum(np.cos(angle)))
            out[f"sin({label})"] = float(np.sum(np.sin(angle)))
    return out


def _eigvalsh(fs: np.ndarray) -> np.ndarray:
    return np.clip(np.linalg.eigvalsh(fs), 0.0, None)


@dataclass(frozen=True)
class Criterion:
    """A larger-is-better design criterion on the normalized information ``Fs``.

    Attributes
    ----------
    name : str
        Registry key (``"D"``, ``"A"``, ``"E"``).
    description : str
        Formula and source, for help texts and reports.
    efficiency : callable
        ``Fs (..., p, p) -> (...)``, 1 for orthogonal plans: the smooth objective
        of the optimizer.
    log_gradient : callable
        ``Fs (..., p, p) -> (..., p, p)``: the symmetric matrix gradient of
        ``log efficiency`` with respect to ``Fs`` (used by the optimizer).
    from_singular_values : callable
        ``s (..., p) -> (...)``: the same efficiency from the singular values of
        :func:`scaled_jacobian` (``Fs`` has eigenvalues ``s^2``), with those the
        rank policy calls zero set to 0 -- what every evaluation reports, so a
        plan :func:`identifiability` rejects has efficiency 0.
    """

    name: str
    description: str
    efficiency: Callable[[np.ndarray], np.ndarray]
    log_gradient: Callable[[np.ndarray], np.ndarray]
    from_singular_values: Callable[[np.ndarray], np.ndarray]


# The gradients invert Fs with spd_inverse, which cannot raise: the optimizer
# regularizes a singular Fs before asking, and other callers pass identifiable plans.


def _d_eff(fs: np.ndarray) -> np.ndarray:
    return np.exp(_logdet(fs) / fs.shape[-1])


def _d_grad(fs: np.ndarray) -> np.ndarray:
    return spd_inverse(fs) / fs.shape[-1]


def _d_from_s(s: np.ndarray) -> np.ndarray:
    with np.errstate(divide="ignore"):
        return np.exp(2.0 * np.mean(np.log(s), axis=-1))  # 0 when a value is 0


def _a_eff(fs: np.ndarray) -> np.ndarray:
    values = _eigvalsh(fs)
    with np.errstate(divide="ignore"):
        return fs.shape[-1] / np.sum(1.0 / values, axis=-1)  # 0 when singular


def _a_grad(fs: np.ndarray) -> np.ndarray:
    inv = spd_inverse(fs)
    inv2 = inv @ inv
    return inv2 / np.trace(inv, axis1=-2, axis2=-1)[..., None, None]


def _a_from_s(s: np.ndarray) -> np.ndarray:
    with np.errstate(divide="ignore"):
        return s.shape[-1] / np.sum(1.0 / s**2, axis=-1)  # 0 when a value is 0


def _e_eff(fs: np.ndarray) -> np.ndarray:
    return _eigvalsh(fs)[..., 0]


def _e_grad(fs: np.ndarray) -> np.ndarray:
    values, vectors = np.linalg.eigh(fs)
    v = vectors[..., :, 0]
    # The smallest eigenvalue, floored like spd_inverse's: eigh knows it to p eps lambda_max.
    floor = fs.shape[-1] * np.finfo(float).eps * values[..., -1]
    smallest = np.maximum(values[..., 0], np.maximum(floor, np.finfo(float).tiny))
    return v[..., :, None] * v[..., None, :] / smallest[..., None, None]


def _e_from_s(s: np.ndarray) -> np.ndarray:
    return np.min(s, axis=-1) ** 2


#: The design criteria by name.  All are computed on the Hadamard-normalized
#: information matrix and equal 1 for the paper's orthogonal plans.
CRITERIA: dict[str, Criterion] = {
    "D": Criterion(
        "D",
        "D-efficiency (det Fs)^(1/p): volume of the confidence ellipsoid (Kiefer 1959)",
        _d_eff,
        _d_grad,
        _d_from_s,
    ),
    "A": Criterion(
        "A",
        "A-efficiency p / tr(Fs^-1): mean variance of the scaled parameters",
        _a_eff,
        _a_grad,
        _a_from_s,
    ),
    "E": Criterion(
        "E",
        "E-efficiency lambda_min(Fs): worst-determined direction of the scaled parameters",
        _e_eff,
        _e_grad,
        _e_from_s,
    ),
}


def efficiencies(
    arm: PlanarArm, q: np.ndarray, *, svd: ScaledSVD | None = None
) -> dict[str, np.ndarray]:
    """Every criterion of :data:`CRITERIA` for plans ``q`` ``(..., m, n)``, by name.

    From the singular values of :func:`scaled_jacobian`; 0 for a plan the rank
    policy calls singular.
    """
    s = model_singular_values(arm, q, svd)
    return {name: crit.from_singular_values(s) for name, crit in CRITERIA.items()}


def observability_indices(
    arm: PlanarArm, q: np.ndarray, *, svd: ScaledSVD | None = None
) -> dict[str, np.ndarray]:
    """Observability indices on the singular values of the column-scaled Jacobian.

    With ``s_1 >= ... >= s_p`` the singular values of ``J D / sqrt(m)`` (``D`` the
    Hadamard scaling: :func:`scaled_jacobian`, so ``s_i = sqrt(eig(Fs))`` and all
    equal 1 at the optimum):

    * ``O1 = (s_1 ... s_p)^(1/p)`` (Borm & Menq 1991; equals ``sqrt(D-efficiency)``),
    * ``O2 = s_p / s_1``, the inverse condition number (Driels & Pathre 1990),
    * ``O3 = s_p``, the minimum singular value (Nahvi et al. 1994),
    * ``O4 = s_p^2 / s_1``, the noise amplification index (Nahvi & Hollerbach 1996).

    All are larger-is-better and 1 for orthogonal plans; all are 0 for a plan
    the rank policy calls singular.
    """
    s = model_singular_values(arm, q, svd)
    with np.errstate(divide="ignore"):
        return {
            "O1": np.exp(np.mean(np.log(s), axis=-1)),
            "O2": s[..., -1] / s[..., 0],
            "O3": s[..., -1],
            "O4": s[..., -1] ** 2 / s[..., 0],
        }


def predicted_std(
    arm: PlanarArm,
    q: np.ndarray,
    sigma: float,
    params: np.ndarray | None = None,
    *,
    svd: ScaledSVD | None = None,
) -> np.ndarray:
    """Predicted standard errors of the user parameters in display units (mm, deg).

    Parameters
    ----------
    arm : PlanarArm
    q : ndarray, shape (..., m, n)
        Plans (rad); leading axes batch over plans.
    sigma : float
        Measurement noise (1 std, mm).
    params : ndarray, shape (p,), optional
        Deviations at which to linearize (nominal when omitted).
    svd : ScaledSVD, optional
        The plan's :func:`~armcal.observability.plan_svd`, when the caller has it
        already (it is computed otherwise).

    Returns
    -------
    ndarray, shape (..., p)
        ``sqrt(diag(sigma^2 (J^T J)^-1))``, ``J`` in the user parametrization
        (``dl``, ``dq``, ``[x0, y0]``).  Infinite entries mean the plan cannot
        identify the parameters.
    """
    inverse, _ = inverse_information_batch(arm, q, params, svd=svd)
    return std_from_covariance(arm, sigma**2 * inverse)


def std_from_covariance(arm: PlanarArm, covariance: np.ndarray) -> np.ndarray:
    """Standard deviations ``(..., p)`` in display units (mm, deg) of a covariance in mm, rad.

    ``covariance`` has shape ``(..., p, p)`` in the user parametrization; ``inf``
    entries (singular plans) stay ``inf``.
    """
    return np.sqrt(np.diagonal(covariance, axis1=-2, axis2=-1)) * arm.display_scale


@dataclass(frozen=True)
class PositionAccuracy:
    """Predicted end-effector position error after calibration at test poses.

    Attributes
    ----------
    rms_mm : float
        ``sqrt(mean_x sigma^2 tr(J0(x) F^-1 J0(x)^T))``: RMS over the test poses.
    max_mm : float
        The same at the worst test pose.
    per_pose_mm : ndarray, shape (k,)
        Predicted RMS error at each test pose.
    """

    rms_mm: float
    max_mm: float
    per_pose_mm: np.ndarray


def position_accuracy(
    arm: PlanarArm,
    q: np.ndarray,
    test_q: np.ndarray,
    sigma: float,
    *,
    svd: ScaledSVD | None = None,
) -> PositionAccuracy:
    """Predicted positioning accuracy after calibration with plan ``q`` at poses ``test_q``.

    Parameters
    ----------
    arm : PlanarArm
    q : ndarray, shape (m, n)
        The calibration plan (rad).
    test_q : ndarray, shape (k, n)
        Poses where the calibrated arm will work (rad).
    sigma : float
        Measurement noise (1 std, mm).
    svd : ScaledSVD, optional
        The plan's :func:`~armcal.observability.plan_svd`, when the caller has it
        already (it is computed otherwise).

    Returns
    -------
    PositionAccuracy

    Notes
    -----
    The error of the predicted tip position at ``x`` has covariance
    ``sigma^2 J0(x) F^-1 J0(x)^T``; its trace is the mean squared position error.
    For an orthogonal plan it equals ``2 n sigma^2 / m`` at every pose
    (``2 (n + 1) sigma^2 / m`` with a base offset).  With ``F^-1 = G G^T`` from
    the rank policy's SVD (:func:`inverse_information_batch`) the variance is
    ``||J0(x) G||^2``, non-negative by construction.

    Raises
    ------
    NotIdentifiableError
        If the plan cannot identify every parameter (:func:`check_identifiable`).
    """
    q = np.asarray(q, dtype=float)
    svd = plan_svd(arm, q) if svd is None else svd
    check_identifiable(arm, q, svd=svd)
    g, _ = covariance_factor(arm, q, None, svd)  # finite: same policy, positive lengths
    rows, target, _ = plan_rows(arm, test_q, None)  # every target of a test pose
    j0 = jacobian(arm, rows, target=target)  # (k, 2, p), user parametrization like g
    per_pose = sigma * np.sqrt(np.sum((j0 @ g) ** 2, axis=(-2, -1)))
    return PositionAccuracy(
        float(np.sqrt(np.mean(per_pose**2))), float(np.max(per_pose)), per_pose
    )


def position_rms(arm: PlanarArm, inverse: np.ndarray, test_q: np.ndarray, sigma: float):
    """Predicted RMS tip error ``(...)`` after calibration, from ``(J^T J)^-1`` ``(..., p, p)``.

    ``sigma sqrt(tr(F^-1 G))`` with ``G = mean_x J(x)^T J(x)`` over the test poses:
    the mean over test poses of ``sigma^2 tr(J(x) F^-1 J(x)^T)``.
    """
    rows, target, _ = plan_rows(arm, test_q, None)
    j0 = jacobian(arm, rows, target=target)  # (k, 2, p), user parametrization like `inverse`
    gram = np.einsum("kia,kib->ab", j0, j0) / j0.shape[0]
    return sigma * np.sqrt(np.clip(np.einsum("...ab,ba->...", inverse, gram), 0.0, None))


@dataclass(frozen=True, eq=False)
class PlanQuality:
    """Everything known about a plan before measuring, for a given noise level.

    Attributes
    ----------
    n_poses : int
    sigma_mm : float
        Measurement noise assumed (mm).
    efficiencies : dict of str to float
        D, A, E efficiencies (1 for orthogonal plans).
    observability : dict of str to float
        O1..O4 (see :func:`observability_indices`).
    dstar : DStar
        The paper's ``det C'``, ``|det S'|``.
    optimality_sums : dict of str to float
        Table I sums (see :func:`optimality_sums`).
    predicted_std : ndarray, shape (p,)
        Standard errors of the user parameters in mm / deg.
    position : PositionAccuracy
        Predicted positioning accuracy after calibration at the test poses.
    warnings : tuple of ArmcalWarning
        An ``ill-conditioned`` warning when the plan's condition number exceeds
        ``COND_WARN`` (see :func:`conditioning_warning`); empty otherwise.
    normalized : bool
        Whether the efficiencies are relative to an optimum of 1
        (:func:`~armcal.models.planar_information.unit_trace`); otherwise they
        are criteria of the weighted information, comparing plans of one model.
    """

    n_poses: int
    sigma_mm: float
    efficiencies: dict[str, float]
    observability: dict[str, float]
    dstar: DStar
    optimality_sums: dict[str, float]
    predicted_std: np.ndarray
    position: PositionAccuracy
    warnings: tuple[ArmcalWarning, ...] = ()
    normalized: bool = True

    def __repr__(self) -> str:
        eff = self.efficiencies
        return (
            f"PlanQuality({self.n_poses} poses, sigma {self.sigma_mm:g} mm: D {eff['D']:.4f}, "
            f"A {eff['A']:.4f}, E {eff['E']:.4f}; predicted position RMS "
            f"{self.position.rms_mm:.4g} mm)"
        )


def evaluate_plan(
    arm: PlanarArm, q: np.ndarray, *, sigma: float, test_q: np.ndarray
) -> PlanQuality:
    """Criteria, predicted std and positioning accuracy of plan ``q`` ``(m, n)``.

    ``test_q`` ``(k, n)`` are the poses where positioning accuracy matters.

    Raises
    ------
    NotIdentifiableError
        If the plan cannot identify every parameter (:func:`check_identifiable`):
        such a plan has no finite predicted accuracy to report.

    Examples
    --------
    >>> from armcal.doe import orthogonal_plan, random_plan
    >>> arm = PlanarArm([260.0, 180.0, 120.0, 100.0])
    >>> quality = evaluate_plan(arm, orthogonal_plan(arm, 20), sigma=0.1,
    ...                         test_q=random_plan(arm, 50, rng=0))
    >>> bool(np.isclose(quality.position.rms_mm, 0.1 * np.sqrt(2 * 4 / 20), rtol=1e-12))
    True
    """
    q = np.asarray(q, dtype=float)
    svd = plan_svd(arm, q)  # one factorization of the plan serves every figure below
    info = check_identifiable(arm, q, svd=svd)
    warning = conditioning_warning(arm, info)
    return PlanQuality(
        n_poses=int(q.shape[0]),
        sigma_mm=float(sigma),
        efficiencies={k: float(v) for k, v in efficiencies(arm, q, svd=svd).items()},
        observability={k: float(v) for k, v in observability_indices(arm, q, svd=svd).items()},
        dstar=dstar(arm, q),
        optimality_sums=optimality_sums(arm, q),
        predicted_std=predicted_std(arm, q, sigma, svd=svd),
        position=position_accuracy(arm, q, test_q, sigma, svd=svd),
        warnings=() if warning is None else (warning,),
        normalized=unit_trace(arm),
    )
