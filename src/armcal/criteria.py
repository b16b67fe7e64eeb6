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

**One rank policy.**  ``Fs = H^T H`` with ``H`` (:func:`scaled_jacobian`) the
Jacobian of the nominal arm in the paper's parametrization with unit-norm
columns, rows divided by ``sqrt(m)``.  At *any* deviations the paper Jacobian
with unit-norm columns is ``H`` times an orthogonal matrix (each link's two
columns turn by ``dtheta_k``), so the singular values of ``H`` alone decide,
through :mod:`armcal.numerics`, whether a plan is identifiable
(:func:`identifiability`), its covariance (:func:`inverse_information_batch`),
its efficiencies and observability indices, and whether results carry an
``ill-conditioned`` warning.  They are computed from a thin QR of ``H``, never
from the eigenvalues of ``Fs``, which cannot resolve a relative singular value
below ``sqrt(eps) ~ 1e-8``.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

from .arm import PlanarArm, jacobian, link_angles, paper_from_user_matrix
from .errors import ArmcalWarning, NotIdentifiableError
from .numerics import COND_WARN, RANK_RTOL, ScaledSVD, scaled_svd, spd_inverse

__all__ = [
    "COND_WARN",
    "CRITERIA",
    "RANK_RTOL",
    "Criterion",
    "DStar",
    "Identifiability",
    "PlanQuality",
    "PositionAccuracy",
    "check_identifiable",
    "conditioning_warning",
    "d_efficiency",
    "dstar",
    "efficiencies",
    "evaluate_plan",
    "identifiability",
    "information_matrix",
    "inverse_information",
    "inverse_information_batch",
    "observability_indices",
    "optimality_sums",
    "plan_svd",
    "position_accuracy",
    "position_rms",
    "predicted_std",
    "scaled_columns",
    "scaled_information",
    "scaled_jacobian",
    "std_from_covariance",
    "weighted_information",
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


def scaled_columns(arm: PlanarArm, q: np.ndarray) -> np.ndarray:
    """Hadamard-scaled Jacobian columns ``(..., m, p)`` in the paper's order, as complex numbers.

    Row x of the real Jacobian is the real part, row y the imaginary part;
    column ``dtheta_k`` (``i l_k e^{i theta_k}``) is divided by ``l_k``.
    """
    unit = np.exp(1j * link_angles(q))
    cols = [1j * unit, unit]
    if arm.base_offset:
        cols.append(np.broadcast_to(np.array([1.0, 1j]), (*np.shape(q)[:-1], 2)))
    return np.concatenate(cols, axis=-1)


def weighted_information(columns: np.ndarray, weights: np.ndarray) -> np.ndarray:
    """``sum_i w_i J_i^T J_i`` ``(..., p, p)`` from complex columns and weights ``(..., m)``."""
    return np.einsum("...m,...ma,...mb->...ab", weights, columns.conj(), columns).real


def scaled_information(arm: PlanarArm, q: np.ndarray) -> np.ndarray:
    """Hadamard-normalized information ``Fs = D F D`` ``(..., p, p)`` with unit diagonal."""
    q = np.asarray(q, dtype=float)
    return weighted_information(scaled_columns(arm, q), np.full(q.shape[:-1], 1 / q.shape[-2]))


def scaled_jacobian(arm: PlanarArm, q: np.ndarray) -> np.ndarray:
    """The policy's matrix ``H`` ``(..., 2m, p)``: the Hadamard-normalized nominal Jacobian.

    The real form of :func:`scaled_columns` divided by ``sqrt(m)``: rows alternate
    x, y per pose, columns are the paper's ``(dtheta, dl, [x0, y0])``, every
    column has unit norm and ``H^T H = Fs``.  Its singular values are 1 for an
    orthogonal plan.

    It is also the plan's regressor of the model that is linear in the links:
    the tip is ``sqrt(m) H v`` with ``v = (Im z_1..n, Re z_1..n, [x0, y0])`` and
    ``z_k = (l_k + dl_k) exp(i dtheta_k)`` (see :mod:`armcal.identification`).
    """
    q = np.asarray(q, dtype=float)
    columns = scaled_columns(arm, q) / np.sqrt(q.shape[-2])
    real = np.stack([columns.real, columns.imag], axis=-2)  # (..., m, 2, p)
    return real.reshape(*q.shape[:-2], 2 * q.shape[-2], arm.n_params)


def plan_svd(arm: PlanarArm, q: np.ndarray) -> ScaledSVD:
    """Singular values and right singular vectors of :func:`scaled_jacobian` (batched).

    Thin factorizations only (:func:`armcal.numerics.scaled_svd`): memory
    ``O(m p)`` per plan.
    """
    return scaled_svd(scaled_jacobian(arm, q))


def _user_from_scaled(arm: PlanarArm, params: np.ndarray | None) -> np.ndarray:
    """``T`` ``(..., p, p)``: user deviations ``= T u`` for a change ``u`` in ``H``'s coordinates.

    At deviations ``params`` the user Jacobian is ``sqrt(m) H T^-1``: with
    ``phi_k = dtheta_k`` and ``L_k = l_k + dl_k``, a change ``u`` of link ``k``'s
    two coordinates gives ``dtheta_k = (cos phi u_theta - sin phi u_l) / L_k``,
    ``dl_k = sin phi u_theta + cos phi u_l`` (a rotation, then a division by the
    length), and ``dq_k = dtheta_k - dtheta_(k-1)``.  Explicit, so nothing is
    inverted; ``inf`` entries for a link of length 0.
    """
    n, p = arm.n_joints, arm.n_params
    values = np.zeros(p) if params is None else np.asarray(params, dtype=float)
    if values.shape[-1] != p:
        raise ValueError(
            f"params must have shape (..., {p}) for {arm.param_names}, got {values.shape}"
        )
    phi = np.cumsum(values[..., n : 2 * n], axis=-1)
    length = arm.link_lengths + values[..., :n]
    cos, sin = np.cos(phi), np.sin(phi)
    with np.errstate(divide="ignore", invalid="ignore"):
        inverse_length = 1.0 / length
    paper = np.zeros((*values.shape[:-1], p, p))
    k = np.arange(n)
    paper[..., k, k] = cos * inverse_length
    paper[..., k, n + k] = -sin * inverse_length
    paper[..., n + k, k] = sin
    paper[..., n + k, n + k] = cos
    if arm.base_offset:
        paper[..., 2 * n :, 2 * n :] = np.eye(2)
    user = np.empty_like(paper)
    user[..., :n, :] = paper[..., n : 2 * n, :]
    with np.errstate(invalid="ignore"):
        user[..., n : 2 * n, :] = np.diff(paper[..., :n, :], axis=-2, prepend=0.0)
    user[..., 2 * n :, :] = paper[..., 2 * n :, :]
    return user


def _covariance_factor(
    arm: PlanarArm, q: np.ndarray, params: np.ndarray | None, svd: ScaledSVD | None = None
) -> tuple[np.ndarray, np.ndarray]:
    """``G`` ``(..., p, p)`` with ``(J^T J)^-1 = G G^T`` (user parametrization) and the ok mask."""
    q = np.asarray(q, dtype=float)
    factor, ok = (plan_svd(arm, q) if svd is None else svd).inverse_gram_factor()
    to_user = _user_from_scaled(arm, params)
    with np.errstate(invalid="ignore", over="ignore"):
        g = to_user @ np.where(ok[..., None, None], factor, 0.0) / np.sqrt(q.shape[-2])
    ok = ok & np.all(np.isfinite(g), axis=(-2, -1))
    return np.where(ok[..., None, None], g, np.inf), ok


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
    g, ok = _covariance_factor(arm, q, params, svd)
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
    return CRITERIA["D"].from_singular_values(plan_svd(arm, q).truncated)


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


def _relative_sums(q: np.ndarray) -> np.ndarray:
    """``sum_i exp(i (theta_j - theta_k))`` ``(..., n, n)``: ``C + i S`` of eq. (18)."""
    unit = np.exp(1j * link_angles(q))
    return np.einsum("...mj,...mk->...jk", unit, unit.conj())


def dstar(arm: PlanarArm, q: np.ndarray) -> DStar:
    """The paper's D* criterion pair ``det(C')``, ``|det(S')|`` (eq. 20), see :class:`DStar`."""
    m = np.shape(q)[-2]
    sums = _relative_sums(q) / m
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
    theta = np.concatenate([np.zeros((q.shape[0], 1)), link_angles(q)], axis=1)
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


def efficiencies(arm: PlanarArm, q: np.ndarray) -> dict[str, np.ndarray]:
    """Every criterion of :data:`CRITERIA` for plans ``q`` ``(..., m, n)``, by name.

    From the singular values of :func:`scaled_jacobian`; 0 for a plan the rank
    policy calls singular.
    """
    s = plan_svd(arm, q).truncated
    return {name: crit.from_singular_values(s) for name, crit in CRITERIA.items()}


def observability_indices(arm: PlanarArm, q: np.ndarray) -> dict[str, np.ndarray]:
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
    s = plan_svd(arm, q).truncated
    with np.errstate(divide="ignore"):
        return {
            "O1": np.exp(np.mean(np.log(s), axis=-1)),
            "O2": s[..., -1] / s[..., 0],
            "O3": s[..., -1],
            "O4": s[..., -1] ** 2 / s[..., 0],
        }


def predicted_std(
    arm: PlanarArm, q: np.ndarray, sigma: float, params: np.ndarray | None = None
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

    Returns
    -------
    ndarray, shape (..., p)
        ``sqrt(diag(sigma^2 (J^T J)^-1))``, ``J`` in the user parametrization
        (``dl``, ``dq``, ``[x0, y0]``).  Infinite entries mean the plan cannot
        identify the parameters.
    """
    inverse, _ = inverse_information_batch(arm, q, params)
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
    arm: PlanarArm, q: np.ndarray, test_q: np.ndarray, sigma: float
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
    check_identifiable(arm, q)
    g, _ = _covariance_factor(arm, q, None)  # finite: same policy, positive lengths
    j0 = jacobian(arm, test_q)  # (k, 2, p), user parametrization like g
    per_pose = sigma * np.sqrt(np.sum((j0 @ g) ** 2, axis=(-2, -1)))
    return PositionAccuracy(
        float(np.sqrt(np.mean(per_pose**2))), float(np.max(per_pose)), per_pose
    )


def position_rms(arm: PlanarArm, inverse: np.ndarray, test_q: np.ndarray, sigma: float):
    """Predicted RMS tip error ``(...)`` after calibration, from ``(J^T J)^-1`` ``(..., p, p)``.

    ``sigma sqrt(tr(F^-1 G))`` with ``G = mean_x J(x)^T J(x)`` over the test poses:
    the mean over test poses of ``sigma^2 tr(J(x) F^-1 J(x)^T)``.
    """
    j0 = jacobian(arm, test_q)  # (k, 2, p), user parametrization like `inverse`
    gram = np.einsum("kia,kib->ab", j0, j0) / j0.shape[0]
    return sigma * np.sqrt(np.clip(np.einsum("...ab,ba->...", inverse, gram), 0.0, None))


@dataclass(frozen=True)
class Identifiability:
    """Rank analysis of a plan's column-scaled Jacobian (:func:`scaled_jacobian`).

    Attributes
    ----------
    rank : int
        Numerical rank: singular values above ``RANK_RTOL`` times the largest
        (:mod:`armcal.numerics`).
    n_params : int
        Number of parameters ``p``.
    singular_values : ndarray, shape (p,)
        Singular values of the Jacobian with unit-norm columns divided by
        ``sqrt(m)``, descending (zeros when ``2m < p``); all 1 for an orthogonal plan.
    unidentifiable : tuple of str
        Parameters that have a component in the null space (cannot be identified).
    combinations : tuple of str
        A basis of the null space written as parameter combinations in display
        units (mm, deg), each with leading coefficient 1: moving the parameters
        along one of these changes no measured position to first order.
    poorly_determined : tuple of str
        The same for every direction whose relative singular value is at most
        ``1 / COND_WARN`` (the null space included): what an ``ill-conditioned``
        warning names.
    joints_to_vary : tuple of int
        Joints (1-based) whose angles the plan should vary more to see the
        unseen or poorly determined combinations: for a combination of the
        parameters of links ``a..b`` (the base counting as link 0), joints
        ``a+1..b`` set their relative angles.
    """

    rank: int
    n_params: int
    singular_values: np.ndarray
    unidentifiable: tuple[str, ...]
    combinations: tuple[str, ...]
    poorly_determined: tuple[str, ...] = ()
    joints_to_vary: tuple[int, ...] = ()

    @property
    def identifiable(self) -> bool:
        """True when the Jacobian has full column rank."""
        return self.rank == self.n_params

    @property
    def condition_number(self) -> float:
        """Ratio of largest to smallest singular value (inf when one is 0)."""
        s = self.singular_values
        if s.size < self.n_params or s[-1] == 0:
            return float("inf")
        return float(s[0] / s[-1])

    @property
    def ill_conditioned(self) -> bool:
        """Identifiable, but with a condition number above ``COND_WARN``."""
        return self.identifiable and self.condition_number > COND_WARN


def _combination(vector: np.ndarray, names: Sequence[str], *, drop: float = 1e-6) -> str:
    # Leading coefficient 1 (the echelon pivot), so combinations read "dl1 - dl2";
    # terms below `drop` times the leading one are left out.
    leading = np.flatnonzero(np.abs(vector) > drop * np.max(np.abs(vector)))[0]
    coeffs = vector / vector[leading]
    terms = []
    for c, name in zip(coeffs, names, strict=True):
        if abs(c) < drop:
            continue
        mag = "" if abs(abs(c) - 1) < 1e-9 else f"{abs(c):.3g}*"
        sign = "-" if c < 0 else "+"
        terms.append(f"{sign} {mag}{name}")
    text = " ".join(terms)
    return text[2:] if text.startswith("+ ") else "-" + text[2:]


def _scaled_from_user_nominal(arm: PlanarArm) -> np.ndarray:
    """``T0^-1`` ``(p, p)``: ``u = diag(l, 1, [1, 1]) P user`` at zero deviations (explicit)."""
    n = arm.n_joints
    scale = np.ones(arm.n_params)
    scale[:n] = arm.link_lengths  # u_theta_k = l_k dtheta_k, in mm
    return paper_from_user_matrix(n, base_offset=arm.base_offset) * scale[:, None]


def _link_of(arm: PlanarArm) -> np.ndarray:
    """The link (1..n; 0 for the base) each user parameter belongs to."""
    links = np.arange(1, arm.n_joints + 1)
    return np.concatenate([links, links, [0, 0] if arm.base_offset else []]).astype(int)


def _joints_to_vary(arm: PlanarArm, rows: np.ndarray, drop: float) -> tuple[int, ...]:
    joints: set[int] = set()
    link_of = _link_of(arm)
    for row in rows:
        involved = link_of[np.abs(row) > drop * np.max(np.abs(row))]
        lo, hi = int(involved.min()), int(involved.max())
        joints.update(range(lo + 1, hi + 1) if hi > lo else [max(hi, 1)])
    return tuple(sorted(joints))


def identifiability(
    arm: PlanarArm, q: np.ndarray, *, svd: ScaledSVD | None = None
) -> Identifiability:
    """Rank of the Jacobian of a plan, on scaled columns, by the one rank policy.

    Parameters
    ----------
    arm : PlanarArm
    q : ndarray, shape (m, n)
        Joint angles of the plan in rad.
    svd : ScaledSVD, optional
        ``plan_svd(arm, q)`` when the caller has it already.

    Returns
    -------
    Identifiability

    Notes
    -----
    The singular values are those of :func:`scaled_jacobian` (thin QR, then SVD
    of the ``p x p`` triangle: memory ``O(m p)``).  They do not depend on the
    deviations: at any deviations the paper Jacobian with unit-norm columns is
    that matrix times an orthogonal one, so the nominal model suffices.  Null
    and poorly determined directions are mapped to the user parameters and
    shown in display units (mm, deg).

    Examples
    --------
    >>> arm = PlanarArm([2.0, 1.0])
    >>> info = identifiability(arm, np.zeros((3, 2)))   # three identical poses
    >>> info.rank, info.unidentifiable
    (2, ('dl1', 'dl2', 'dq1', 'dq2'))
    """
    if svd is None:
        svd = plan_svd(arm, q)
    rank = int(svd.rank)
    to_user = _user_from_scaled(arm, None)
    names = arm.param_names
    null = svd.directions(RANK_RTOL) @ to_user.T  # rows: unseen directions (mm, rad)
    weak = svd.directions(1.0 / COND_WARN) @ to_user.T
    bad: tuple[str, ...] = ()
    if null.shape[0]:
        # Which parameters the null space touches, judged on the user Jacobian with
        # unit-norm columns: |J_user e_j| = sqrt(m) |S V^T (c * T0^-1 e_j)|.
        user_columns = svd.column_norms[:, None] * _scaled_from_user_nominal(arm)
        user_norms = np.linalg.norm(svd.singular_values[:, None] * (svd.vt @ user_columns), axis=0)
        basis, _ = np.linalg.qr((null * user_norms).T)  # orthonormal, (p, k)
        weights = np.linalg.norm(basis, axis=1)
        bad = tuple(n for n, w in zip(names, weights, strict=True) if w > 1e-8)
    display = arm.display_scale  # a direction in mm, rad shown in mm, deg
    null_rows = _row_echelon(null * display)
    # A poorly determined direction is only near the null space of a nearby plan:
    # terms below the 3 significant digits shown of the leading one are left out.
    weak_drop = 1e-3
    weak_rows = _row_echelon(weak * display, tol=weak_drop)
    if null.shape[0]:
        joints = _joints_to_vary(arm, null_rows, 1e-6)
    else:
        joints = _joints_to_vary(arm, weak_rows, weak_drop)
    return Identifiability(
        rank=rank,
        n_params=arm.n_params,
        singular_values=svd.singular_values,
        unidentifiable=bad,
        combinations=tuple(_combination(v, names) for v in null_rows),
        poorly_determined=tuple(_combination(v, names, drop=weak_drop) for v in weak_rows),
        joints_to_vary=joints,
    )


def _row_echelon(basis: np.ndarray, *, tol: float = 1e-9) -> np.ndarray:
    """Reduced row echelon form of a basis ``(k, p)``: the same span, sparse rows.

    The SVD returns an arbitrary rotation of the null space; the echelon form
    gives each unseen combination a parameter of its own (e.g. ``dl1 - dl2``
    and ``dq1 - 3*dq2`` rather than two mixtures of all four).  Entries below
    ``tol`` times the largest are not used as pivots.
    """
    rows = basis.copy()
    scale = np.max(np.abs(rows)) if rows.size else 0.0
    pivot_row = 0
    for col in range(rows.shape[1]):
        if pivot_row == rows.shape[0]:
            break
        best = pivot_row + int(np.argmax(np.abs(rows[pivot_row:, col])))
        if abs(rows[best, col]) <= tol * scale:
            continue
        rows[[pivot_row, best]] = rows[[best, pivot_row]]
        rows[pivot_row] /= rows[pivot_row, col]
        others = np.arange(rows.shape[0]) != pivot_row
        rows[others] -= np.outer(rows[others, col], rows[pivot_row])
        pivot_row += 1
    return rows


def _listing(items: Sequence[object]) -> str:
    """``"a"``, ``"a and b"``, ``"a, b and c"``."""
    words = [str(item) for item in items]
    return words[0] if len(words) == 1 else ", ".join(words[:-1]) + " and " + words[-1]


def _joints_phrase(joints: Sequence[int]) -> str:
    return ("joint " if len(joints) == 1 else "joints ") + _listing(joints)


def check_identifiable(
    arm: PlanarArm, q: np.ndarray, *, svd: ScaledSVD | None = None
) -> Identifiability:
    """Raise :class:`NotIdentifiableError` unless the plan ``q`` identifies every parameter.

    The message counts poses and parameters, names the parameters that cannot be
    identified and up to three unseen combinations, and says how to fix the plan.
    ``svd`` is ``plan_svd(arm, q)`` when the caller has it already.
    """
    q = np.asarray(q, dtype=float)
    m = q.shape[0]
    p = arm.n_params
    min_poses = -(-p // 2)
    info = identifiability(arm, q, svd=svd)
    if info.identifiable:
        return info
    shown = "; ".join(info.combinations[:3])
    more = f" (and {len(info.combinations) - 3} more)" if len(info.combinations) > 3 else ""
    if m < min_poses:
        why = (
            f"{m} poses give {2 * m} equations for {p} parameters; "
            f"measure at least {min_poses} poses"
        )
    else:
        joints = info.joints_to_vary
        why = (
            f"add poses in which {_joints_phrase(joints)} "
            f"{'takes' if len(joints) == 1 else 'take'} several different angles (armcal design)"
        )
    raise NotIdentifiableError(
        f"the {m} poses cannot identify all {p} parameters of {arm.name} "
        f"(Jacobian rank {info.rank} of {p}): not identifiable: {', '.join(info.unidentifiable)}; "
        f"unseen combinations: {shown}{more}; {why}",
        list(info.combinations),
    )


def conditioning_warning(arm: PlanarArm, info: Identifiability) -> ArmcalWarning | None:
    """An ``ill-conditioned`` warning for a plan above ``COND_WARN``, else None.

    Names the poorly determined combinations (the right singular vectors of the
    smallest singular values, in echelon form like the unseen combinations),
    how much less precise they are than with an orthogonal plan, and which
    joints to move more.

    Examples
    --------
    >>> arm = PlanarArm([2.0, 1.0])
    >>> q = np.column_stack([np.linspace(-3, 3, 8), 1e-7 * np.arange(8)])  # q2 barely moves
    >>> text = conditioning_warning(arm, identifiability(arm, q)).message
    >>> text.startswith("the plan determines dl1 - dl2 and dq1 - 3*dq2 poorly")
    True
    >>> text.endswith("measure poses in which joint 2 moves more (armcal design)")
    True
    """
    if not info.ill_conditioned:
        return None
    cond = info.condition_number
    combos = list(info.poorly_determined[:3])
    if len(info.poorly_determined) > 3:
        combos.append(f"{len(info.poorly_determined) - 3} more")
    joints = info.joints_to_vary
    verb = "moves" if len(joints) == 1 else "move"
    round_off = cond * np.finfo(float).eps * float(np.sum(arm.link_lengths))
    return ArmcalWarning(
        "ill-conditioned",
        f"the plan determines {_listing(combos)} poorly: the condition number of its "
        f"scaled Jacobian is {cond:.2g} (above {COND_WARN:.0e}), so these combinations are "
        f"up to {cond:.2g} times less precise than with an orthogonal plan, and round-off "
        f"alone can shift them by about {round_off:.1g} mm; measure poses in which "
        f"{_joints_phrase(joints)} {verb} more (armcal design)",
    )


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
    info = check_identifiable(arm, q)
    warning = conditioning_warning(arm, info)
    return PlanQuality(
        n_poses=int(q.shape[0]),
        sigma_mm=float(sigma),
        efficiencies={k: float(v) for k, v in efficiencies(arm, q).items()},
        observability={k: float(v) for k, v in observability_indices(arm, q).items()},
        dstar=dstar(arm, q),
        optimality_sums=optimality_sums(arm, q),
        predicted_std=predicted_std(arm, q, sigma),
        position=position_accuracy(arm, q, test_q, sigma),
        warnings=() if warning is None else (warning,),
    )
