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
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

from .arm import PlanarArm, jacobian, link_angles
from .errors import NotIdentifiableError

__all__ = [
    "CRITERIA",
    "RANK_RTOL",
    "Criterion",
    "DStar",
    "Identifiability",
    "PlanQuality",
    "PositionAccuracy",
    "check_identifiable",
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
    "position_accuracy",
    "position_rms",
    "predicted_std",
    "scaled_columns",
    "scaled_information",
    "std_from_covariance",
    "weighted_information",
]


#: Relative singular-value threshold of the column-scaled Jacobian below which a
#: direction in parameter space counts as not identifiable.  A plan that close
#: to singular would give standard errors more than 1e10 times the best-case ones.
RANK_RTOL = 1e-10


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


def inverse_information_batch(
    arm: PlanarArm, q: np.ndarray, params: np.ndarray | None = None
) -> tuple[np.ndarray, np.ndarray]:
    """``(J^T J)^-1`` in the user parametrization for a stack of plans, with an identifiable mask.

    Parameters
    ----------
    arm : PlanarArm
    q : ndarray, shape (..., m, n)
        Plans (rad); leading axes batch over plans.
    params : ndarray, shape (p,) or (..., p), optional
        Deviations at which to linearize (nominal when omitted).

    Returns
    -------
    inverse : ndarray, shape (..., p, p)
        ``(J^T J)^-1`` (mm, rad); rows of singular plans are ``inf``.
    identifiable : ndarray of bool, shape (...)
        False where a singular value of the column-scaled Jacobian is below
        ``RANK_RTOL`` times the largest -- the test of
        :func:`armcal.criteria.identifiability`.
    """
    jac = jacobian(arm, q, params)
    jac = jac.reshape(*jac.shape[:-3], -1, arm.n_params)
    norms = np.linalg.norm(jac, axis=-2)
    norms[norms == 0] = 1.0
    _, s, vt = np.linalg.svd(jac / norms[..., None, :], full_matrices=False)
    ok = (s.shape[-1] == arm.n_params) & (s[..., -1] > RANK_RTOL * s[..., 0])
    safe = np.where(ok[..., None], s, 1.0)
    inverse = np.einsum("...ki,...k,...kj->...ij", vt, 1 / safe**2, vt)
    inverse /= norms[..., :, None] * norms[..., None, :]
    return np.where(ok[..., None, None], inverse, np.inf), ok


def inverse_information(
    arm: PlanarArm, q: np.ndarray, params: np.ndarray | None = None
) -> np.ndarray | None:
    """``(J^T J)^-1`` ``(p, p)`` in the user parametrization (mm, rad), or None if singular.

    Computed from the SVD of the column-scaled Jacobian at ``params`` (nominal
    when omitted); singular means a singular value below ``RANK_RTOL`` times the
    largest, the same test as :func:`armcal.criteria.identifiability`.
    """
    inverse, ok = inverse_information_batch(arm, q, params)
    return inverse if bool(ok) else None


def _logdet(fs: np.ndarray) -> np.ndarray:
    sign, logdet = np.linalg.slogdet(fs)
    return np.where(sign > 0, logdet, -np.inf)


def d_efficiency(arm: PlanarArm, q: np.ndarray) -> np.ndarray:
    """D-efficiency ``(det F / det F_opt)^(1/p)`` of plans ``q`` ``(..., m, n)``.

    1 exactly for plans meeting the paper's conditions (21); 0 for plans that
    cannot identify every parameter.

    Examples
    --------
    >>> from armcal.doe import orthogonal_plan
    >>> arm = PlanarArm([260.0, 180.0, 120.0, 100.0])
    >>> round(float(d_efficiency(arm, orthogonal_plan(arm, 20))), 12)
    1.0
    """
    return np.exp(_logdet(scaled_information(arm, q)) / arm.n_params)


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
        ``Fs (..., p, p) -> (...)``, 1 for orthogonal plans.
    log_gradient : callable
        ``Fs (..., p, p) -> (..., p, p)``: the symmetric matrix gradient of
        ``log efficiency`` with respect to ``Fs`` (used by the optimizer).
    """

    name: str
    description: str
    efficiency: Callable[[np.ndarray], np.ndarray]
    log_gradient: Callable[[np.ndarray], np.ndarray]


def _d_eff(fs: np.ndarray) -> np.ndarray:
    return np.exp(_logdet(fs) / fs.shape[-1])


def _d_grad(fs: np.ndarray) -> np.ndarray:
    return np.linalg.inv(fs) / fs.shape[-1]


def _a_eff(fs: np.ndarray) -> np.ndarray:
    values = _eigvalsh(fs)
    with np.errstate(divide="ignore"):
        return fs.shape[-1] / np.sum(1.0 / values, axis=-1)  # 0 when singular


def _a_grad(fs: np.ndarray) -> np.ndarray:
    inv = np.linalg.inv(fs)
    inv2 = inv @ inv
    return inv2 / np.trace(inv, axis1=-2, axis2=-1)[..., None, None]


def _e_eff(fs: np.ndarray) -> np.ndarray:
    return _eigvalsh(fs)[..., 0]


def _e_grad(fs: np.ndarray) -> np.ndarray:
    values, vectors = np.linalg.eigh(fs)
    v = vectors[..., :, 0]
    return v[..., :, None] * v[..., None, :] / values[..., 0, None, None]


#: The design criteria by name.  All are computed on the Hadamard-normalized
#: information matrix and equal 1 for the paper's orthogonal plans.
CRITERIA: dict[str, Criterion] = {
    "D": Criterion(
        "D",
        "D-efficiency (det Fs)^(1/p): volume of the confidence ellipsoid (Kiefer 1959)",
        _d_eff,
        _d_grad,
    ),
    "A": Criterion(
        "A",
        "A-efficiency p / tr(Fs^-1): mean variance of the scaled parameters",
        _a_eff,
        _a_grad,
    ),
    "E": Criterion(
        "E",
        "E-efficiency lambda_min(Fs): worst-determined direction of the scaled parameters",
        _e_eff,
        _e_grad,
    ),
}


def efficiencies(arm: PlanarArm, q: np.ndarray) -> dict[str, np.ndarray]:
    """Every criterion of :data:`CRITERIA` for plans ``q`` ``(..., m, n)``, by name."""
    fs = scaled_information(arm, q)
    return {name: crit.efficiency(fs) for name, crit in CRITERIA.items()}


def observability_indices(arm: PlanarArm, q: np.ndarray) -> dict[str, np.ndarray]:
    """Observability indices on the singular values of the column-scaled Jacobian.

    With ``s_1 >= ... >= s_p`` the singular values of ``J D / sqrt(m)`` (``D`` the
    Hadamard scaling, so ``s_i = sqrt(eig(Fs))`` and all equal 1 at the optimum):

    * ``O1 = (s_1 ... s_p)^(1/p)`` (Borm & Menq 1991; equals ``sqrt(D-efficiency)``),
    * ``O2 = s_p / s_1``, the inverse condition number (Driels & Pathre 1990),
    * ``O3 = s_p``, the minimum singular value (Nahvi et al. 1994),
    * ``O4 = s_p^2 / s_1``, the noise amplification index (Nahvi & Hollerbach 1996).

    All are larger-is-better and 1 for orthogonal plans.
    """
    s = np.sqrt(_eigvalsh(scaled_information(arm, q)))[..., ::-1]
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
    (``2 (n + 1) sigma^2 / m`` with a base offset).
    """
    f_inv = np.linalg.inv(information_matrix(arm, q))
    j0 = jacobian(arm, test_q, parametrization="paper")  # (k, 2, p)
    var = np.einsum("kip,pr,kir->k", j0, f_inv, j0)
    per_pose = sigma * np.sqrt(np.clip(var, 0.0, None))
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
    """Rank analysis of a plan's column-scaled Jacobian.

    Attributes
    ----------
    rank : int
        Numerical rank (singular values above ``RANK_RTOL`` times the largest).
    n_params : int
        Number of parameters ``p``.
    singular_values : ndarray, shape (min(2m, p),)
        Singular values of the Jacobian with unit-norm columns, descending.
    unidentifiable : tuple of str
        Parameters that have a component in the null space (cannot be identified).
    combinations : tuple of str
        A basis of the null space written as parameter combinations in display
        units (mm, deg), each with leading coefficient 1: moving the parameters
        along one of these changes no measured position to first order.
    """

    rank: int
    n_params: int
    singular_values: np.ndarray
    unidentifiable: tuple[str, ...]
    combinations: tuple[str, ...]

    @property
    def identifiable(self) -> bool:
        """True when the Jacobian has full column rank."""
        return self.rank == self.n_params

    @property
    def condition_number(self) -> float:
        """Ratio of largest to smallest singular value (inf when rank deficient)."""
        s = self.singular_values
        if s.size < self.n_params or s[-1] == 0:
            return float("inf")
        return float(s[0] / s[-1])


def _combination(vector: np.ndarray, names: Sequence[str]) -> str:
    # Leading coefficient 1 (the echelon pivot), so combinations read "dl1 - dl2".
    leading = np.flatnonzero(np.abs(vector) > 1e-6 * np.max(np.abs(vector)))[0]
    coeffs = vector / vector[leading]
    terms = []
    for c, name in zip(coeffs, names, strict=True):
        if abs(c) < 1e-6:
            continue
        mag = "" if abs(abs(c) - 1) < 1e-9 else f"{abs(c):.3g}*"
        sign = "-" if c < 0 else "+"
        terms.append(f"{sign} {mag}{name}")
    text = " ".join(terms)
    return text[2:] if text.startswith("+ ") else "-" + text[2:]


def identifiability(arm: PlanarArm, q: np.ndarray) -> Identifiability:
    """Rank of the Jacobian of a plan at the nominal parameters, on scaled columns.

    Parameters
    ----------
    arm : PlanarArm
    q : ndarray, shape (m, n)
        Joint angles of the plan in rad.

    Returns
    -------
    Identifiability

    Notes
    -----
    Columns mix mm/mm and mm/rad, so each is scaled to unit norm before the SVD;
    the rank does not depend on the deviations (a rotation of each link's pair of
    columns maps nominal to actual Jacobian), so the nominal model suffices.

    Examples
    --------
    >>> arm = PlanarArm([2.0, 1.0])
    >>> info = identifiability(arm, np.zeros((3, 2)))   # three identical poses
    >>> info.rank, info.unidentifiable
    (2, ('dl1', 'dl2', 'dq1', 'dq2'))
    """
    jac = jacobian(arm, q).reshape(-1, arm.n_params)
    norms = np.linalg.norm(jac, axis=0)
    norms[norms == 0] = 1.0
    _, s, vt = np.linalg.svd(jac / norms, full_matrices=True)
    s_max = s[0] if s.size else 0.0
    rank = int(np.sum(s > RANK_RTOL * s_max)) if s_max > 0 else 0
    null = vt[rank:]  # rows span the null space of the scaled Jacobian
    names = arm.param_names
    bad = tuple(n for n, w in zip(names, np.linalg.norm(null, axis=0), strict=True) if w > 1e-8)
    # Undo the column scaling, show in display units (mm, deg), and pick the sparse basis.
    combos = tuple(_combination(v, names) for v in _row_echelon(null / norms / arm.display_scale))
    return Identifiability(rank, arm.n_params, s, bad, combos)


def _row_echelon(basis: np.ndarray, *, tol: float = 1e-9) -> np.ndarray:
    """Reduced row echelon form of a basis ``(k, p)``: the same span, sparse rows.

    The SVD returns an arbitrary rotation of the null space; the echelon form
    gives each unseen combination a parameter of its own (e.g. ``dl1 - dl2``
    and ``dq1 - 3*dq2`` rather than two mixtures of all four).
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


def check_identifiable(arm: PlanarArm, q: np.ndarray) -> Identifiability:
    """Raise :class:`NotIdentifiableError` unless the plan ``q`` identifies every parameter.

    The message counts poses and parameters, names the parameters that cannot be
    identified and up to three unseen combinations, and says how to fix the plan.
    """
    m = q.shape[0]
    p = arm.n_params
    min_poses = -(-p // 2)
    info = identifiability(arm, q)
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
        why = "add poses in which every joint takes several different angles (armcal design)"
    raise NotIdentifiableError(
        f"the {m} poses cannot identify all {p} parameters of {arm.name} "
        f"(Jacobian rank {info.rank} of {p}): not identifiable: {', '.join(info.unidentifiable)}; "
        f"unseen combinations: {shown}{more}; {why}",
        list(info.combinations),
    )


@dataclass(frozen=True, eq=False)
class PlanQuality:
    """Everything known about a plan before measuring, for a given noise level.

    Attributes
    ----------
    n_poses : int
    sigma : float
        Measurement noise assumed (mm).
    identifiable : bool
        Whether the plan identifies every parameter.
    efficiencies : dict of str to float
        D, A, E efficiencies (1 for orthogonal plans, 0 when not identifiable).
    observability : dict of str to float
        O1..O4 (see :func:`observability_indices`).
    dstar : DStar
        The paper's ``det C'``, ``|det S'|``.
    optimality_sums : dict of str to float
        Table I sums (see :func:`optimality_sums`).
    predicted_std : ndarray, shape (p,)
        Standard errors of the user parameters in mm / deg (inf if not identifiable).
    position : PositionAccuracy or None
        Predicted positioning accuracy after calibration at the test poses
        (None if not identifiable).
    """

    n_poses: int
    sigma: float
    identifiable: bool
    efficiencies: dict[str, float]
    observability: dict[str, float]
    dstar: DStar
    optimality_sums: dict[str, float]
    predicted_std: np.ndarray
    position: PositionAccuracy | None


def evaluate_plan(
    arm: PlanarArm, q: np.ndarray, *, sigma: float, test_q: np.ndarray
) -> PlanQuality:
    """Criteria, predicted std and positioning accuracy of plan ``q`` ``(m, n)``.

    ``test_q`` ``(k, n)`` are the poses where positioning accuracy matters.

    Examples
    --------
    >>> from armcal.doe import orthogonal_plan, random_plan
    >>> arm = PlanarArm([260.0, 180.0, 120.0, 100.0])
    >>> quality = evaluate_plan(arm, orthogonal_plan(arm, 20), sigma=0.1,
    ...                         test_q=random_plan(arm, 50, rng=0))
    >>> bool(np.isclose(quality.position.rms_mm, 0.1 * np.sqrt(2 * 4 / 20), rtol=1e-12))
    True
    """
    std = predicted_std(arm, q, sigma)
    identifiable = bool(np.all(np.isfinite(std)))
    return PlanQuality(
        n_poses=int(q.shape[0]),
        sigma=float(sigma),
        identifiable=identifiable,
        efficiencies={k: float(v) for k, v in efficiencies(arm, q).items()},
        observability={k: float(v) for k, v in observability_indices(arm, q).items()},
        dstar=dstar(arm, q),
        optimality_sums=optimality_sums(arm, q),
        predicted_std=std,
        position=position_accuracy(arm, q, test_q, sigma) if identifiable else None,
    )
