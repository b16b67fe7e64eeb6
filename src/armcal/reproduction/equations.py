"""The printed equations of Sections II-V, each computed and compared with what the paper prints.

The references are independent of armcal's own kinematics: model (1) is
evaluated from its printed double sum (:func:`paper_model`), Jacobians and the
gradient of the least-squares function (3) by central differences of that sum,
and the information matrix (17)-(19) from those Jacobians.  Each check returns
an :class:`~armcal.reproduction.catalogue.EquationCheck` whose words come from
:data:`~armcal.reproduction.catalogue.EQUATIONS` and whose numbers and verdict
come from here.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from ..criteria import d_efficiency
from ..doe.plans import random_plan
from ..errors import ArmcalError
from ..models import (
    PlanarArm,
    forward_kinematics,
    identifiability,
    link_angles,
    paper_from_user_matrix,
)
from ..models.planar.criteria import dstar, information_matrix, inverse_information
from ..models.planar.plans import orthogonal_plan
from ..paper import PAPER_FIGURE1_POSES, PAPER_RANGE_POSES, PAPER_TABLE3, paper_arm
from .algorithm import solve_gauss_newton
from .catalogue import (
    DERIVATIVE_LABELS,
    READING_LABELS,
    ROWS,
    EquationCheck,
    equation_check,
    fill,
)

__all__ = [
    "EXACT_RTOL",
    "FD_RTOL",
    "FD_STEP",
    "RANDOM_PLANS",
    "SimulationEvidence",
    "check_equations",
    "max_random_rank",
    "paper_model",
]


#: Step of the central differences (mm for lengths, rad for angles).
FD_STEP = 1e-5

#: Relative agreement asked of a central difference.  Its error is about
#: ``h^2 |f'''| / 6 + eps |f| / h``: for the 4-link arm (lengths up to 260 mm,
#: positions up to 660 mm) below 1e-8 of the largest entry compared.
FD_RTOL = 1e-7

#: Relative agreement asked of an algebraic identity evaluated in floating point
#: (a solve of a system whose condition number is below 1e6).
EXACT_RTOL = 1e-9

#: Random plans drawn for each statement "over random plans".
RANDOM_PLANS = 200

#: Random plans per number of poses when searching for the largest Jacobian rank;
#: a random plan has the generic (largest) rank with probability 1.
RANK_PLANS = 20


@dataclass(frozen=True)
class SimulationEvidence:
    """What the Monte Carlo runs of Table III say about eq. (12)-(16).

    Attributes
    ----------
    trials : int
        Trials per configuration.
    parameters : int
        Parameters summed over the identifiable configurations.
    worst_bias_ratio : float
        Largest ``|mean - truth| / (4 std / sqrt(N))``.
    worst_std_deviation : float
        Largest ``|simulated std / predicted std - 1|`` (prediction: eq. 16 at the truth).
    """

    trials: int
    parameters: int
    worst_bias_ratio: float
    worst_std_deviation: float


def paper_model(lengths: np.ndarray, q: np.ndarray, dl: np.ndarray, dq: np.ndarray) -> np.ndarray:
    """Eq. (1) as printed: ``x = sum_i (l_i + dl_i) cos(sum_(j<=i) (q_j + dq_j))``, y with sin.

    Parameters
    ----------
    lengths : ndarray, shape (n,)
        Nominal link lengths (mm).
    q : ndarray, shape (m, n)
        Joint angles (rad).
    dl, dq : ndarray, shape (n,)
        Length deviations (mm) and joint offsets (rad).

    Returns
    -------
    ndarray, shape (m, 2)
        Tip positions (mm).

    Examples
    --------
    >>> paper_model(np.array([2.0, 1.0]), np.array([[0.0, np.pi / 2]]),
    ...             np.zeros(2), np.zeros(2)).round(12).tolist()
    [[2.0, 1.0]]
    """
    angle = np.cumsum(q + dq, axis=-1)
    length = lengths + dl
    return np.stack(
        [np.sum(length * np.cos(angle), axis=-1), np.sum(length * np.sin(angle), axis=-1)],
        axis=-1,
    )


def _model_paper(lengths: np.ndarray, q: np.ndarray, params: np.ndarray) -> np.ndarray:
    """Eq. (1) at the paper's ``DeltaPi = (dtheta, dl)``: ``dq_k = dtheta_k - dtheta_(k-1)``."""
    n = lengths.size
    return paper_model(lengths, q, params[n:], np.diff(params[:n], prepend=0.0))


def _model_user(lengths: np.ndarray, q: np.ndarray, params: np.ndarray) -> np.ndarray:
    """Eq. (1) at the user's ``(dl, dq)``."""
    n = lengths.size
    return paper_model(lengths, q, params[:n], params[n : 2 * n])


def _central(f: Callable[[np.ndarray], np.ndarray | float], x: np.ndarray) -> np.ndarray:
    """Central differences ``(..., p)`` of ``f`` at ``x`` ``(p,)``, step :data:`FD_STEP`."""
    columns = []
    for a in range(x.size):
        step = np.zeros_like(x)
        step[a] = FD_STEP
        columns.append((np.asarray(f(x + step)) - np.asarray(f(x - step))) / (2 * FD_STEP))
    return np.stack(columns, axis=-1)


def _rel(value: np.ndarray, reference: np.ndarray) -> float:
    """Largest difference relative to the largest entry of ``reference``."""
    return float(np.max(np.abs(np.asarray(value) - reference)) / np.max(np.abs(reference)))


def _printed_jacobian(lengths: np.ndarray, theta: np.ndarray) -> np.ndarray:
    """Eq. (7)-(8) ``(m, 2, 2n)``: columns ``[J_q, J_l]`` with ``l``, ``theta`` as given."""
    x = np.concatenate([-lengths * np.sin(theta), np.cos(theta)], axis=-1)
    y = np.concatenate([lengths * np.cos(theta), np.sin(theta)], axis=-1)
    return np.stack([x, y], axis=-2)


def _relative_sums(theta: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``c_jk``, ``s_jk`` of eq. (18) ``(..., n, n)`` from link angles ``(..., m, n)``."""
    diff = theta[..., :, :, None] - theta[..., :, None, :]
    return np.cos(diff).sum(axis=-3), np.sin(diff).sum(axis=-3)


def max_random_rank(arm: PlanarArm, m: int, rng: np.random.Generator) -> int:
    """Largest Jacobian rank over :data:`RANK_PLANS` random ``m``-pose plans."""
    return max(identifiability(arm, random_plan(arm, m, rng=rng)).rank for _ in range(RANK_PLANS))


@dataclass(frozen=True)
class _Setting:
    """The data every check shares: the 4-link arm, a random plan and noiseless data."""

    arm: PlanarArm
    lengths: np.ndarray
    truth_user: np.ndarray
    truth_paper: np.ndarray
    to_user: np.ndarray
    q: np.ndarray
    xy: np.ndarray
    sigma: float

    @property
    def n(self) -> int:
        return self.arm.n_joints


def _check_model(s: _Setting) -> EquationCheck:
    printed = _model_user(s.lengths, s.q, s.truth_user)
    diff = float(np.max(np.abs(printed - forward_kinematics(s.arm, s.q, s.truth_user))))
    return equation_check("model", agrees=diff <= 1e-9, diff=diff, poses=s.q.shape[0])


def _gradient_checks(s: _Setting) -> list[EquationCheck]:
    """Eq. (4)-(5) against central differences of F (3), at half the true deviations."""
    n = s.n
    point = s.truth_paper / 2

    def objective_paper(params: np.ndarray) -> float:
        return float(np.sum((_model_paper(s.lengths, s.q, params) - s.xy) ** 2))

    def objective_user(params: np.ndarray) -> float:
        return float(np.sum((_model_user(s.lengths, s.q, params) - s.xy) ** 2))

    grad_paper = _central(objective_paper, point)
    grad_dq = _central(objective_user, s.to_user @ point)[n : 2 * n]
    derivatives = {"dtheta": grad_paper[:n], "dq": grad_dq}
    length = s.lengths + point[n:]
    angle = link_angles(s.q) + point[:n]
    residual = _model_paper(s.lengths, s.q, point) - s.xy  # f - measured, (m, 2)
    # The bracketed term of (4) for link l in experiment i, shape (m, n).
    term = length * (-np.sin(angle) * residual[:, :1] + np.cos(angle) * residual[:, 1:])
    poses = np.arange(s.q.shape[0])[:, None]
    links = np.arange(n)[None, :]
    readings = {
        # sum_(l=i)^n with i the experiment index: the same number for every k.
        "literal": np.full(n, np.sum(np.where(links >= poses, term, 0.0))),
        "upto": np.cumsum(term.sum(axis=0)[::-1])[::-1],  # l = k..n
        "single": term.sum(axis=0),  # l = k
    }
    errors = {
        (reading, wrt): _rel(2 * value, derivatives[wrt])
        for reading, value in readings.items()
        for wrt in derivatives
    }
    matched = [
        f"{READING_LABELS[reading]} = {DERIVATIVE_LABELS[wrt]}"
        for (reading, wrt), error in errors.items()
        if error <= FD_RTOL
    ]
    angles = equation_check(
        "gradient_angles",
        agrees=errors[("literal", "dtheta")] <= FD_RTOL,
        poses=s.q.shape[0],
        rtol=FD_RTOL,
        matches="; ".join(matched) or ROWS["no_match"],
        **{f"{reading}_{wrt}": error for (reading, wrt), error in errors.items()},
    )
    printed_lengths = np.sum(
        np.cos(angle) * residual[:, :1] + np.sin(angle) * residual[:, 1:], axis=0
    )
    lengths = equation_check(
        "gradient_lengths",
        agrees=_rel(2 * printed_lengths, grad_paper[n:]) <= FD_RTOL,
        diff=_rel(2 * printed_lengths, grad_paper[n:]),
    )
    single = readings["single"]
    ratio_angles = float(derivatives["dtheta"] @ single / (single @ single))
    ratio_lengths = float(grad_paper[n:] @ printed_lengths / (printed_lengths @ printed_lengths))
    scale = equation_check(
        "gradient_scale",
        agrees=max(abs(ratio_angles - 1), abs(ratio_lengths - 1)) <= FD_RTOL,
        ratio_angles=ratio_angles,
        ratio_lengths=ratio_lengths,
    )
    return [angles, lengths, scale]


def _check_linearization(s: _Setting) -> EquationCheck:
    zero = np.zeros(2 * s.n)
    nominal = _model_paper(s.lengths, s.q, zero)
    jac = _central(lambda p: _model_paper(s.lengths, s.q, p), zero)

    def remainder(t: float) -> float:
        moved = _model_paper(s.lengths, s.q, t * s.truth_paper)
        return float(np.max(np.abs(moved - nominal - jac @ (t * s.truth_paper))))

    full, half = remainder(1.0), remainder(0.5)
    ratio = full / half
    # Third-order terms shift the ratio by about |DeltaPi| (1e-2 rad): 4 +- 0.5 is ample.
    return equation_check(
        "linearization",
        agrees=3.5 <= ratio <= 4.5,
        err_full=full,
        err_half=half,
        ratio=ratio,
    )


def _jacobian_checks(s: _Setting) -> list[EquationCheck]:
    """Eq. (7)-(8) against central differences of (1) at the nominal and the true deviations."""
    n = s.n
    vs_dtheta, vs_dq, vs_dl = [], [], []
    last = np.zeros((2, n))  # (point, j): l_j cos theta_j against the last y column
    for i, point in enumerate((np.zeros(2 * n), s.truth_paper)):
        fd_paper = _central(lambda p: _model_paper(s.lengths, s.q, p), point)
        fd_user = _central(lambda p: _model_user(s.lengths, s.q, p), s.to_user @ point)
        length = s.lengths + point[n:]
        theta = link_angles(s.q) + point[:n]
        printed = _printed_jacobian(length, theta)
        vs_dtheta.append(_rel(printed[..., :n], fd_paper[..., :n]))
        vs_dq.append(_rel(printed[..., :n], fd_user[..., n : 2 * n]))
        vs_dl.append(_rel(printed[..., n:], fd_paper[..., n:]))
        column = fd_paper[:, 1, n - 1]
        for j in range(n):
            last[i, j] = _rel(length[j] * np.cos(theta[:, j]), column)
    columns = equation_check(
        "jacobian_columns",
        agrees=max(vs_dtheta) <= FD_RTOL and max(vs_dl) <= FD_RTOL,
        poses=s.q.shape[0],
        vs_dtheta=max(vs_dtheta),
        vs_dq=min(vs_dq),
        vs_dl=max(vs_dl),
    )
    worst = last.max(axis=0)
    last_entry = equation_check(
        "jacobian_last_entry",
        # The printed index j is free: the entry is right only if every j gives it.
        agrees=bool(np.all(worst <= FD_RTOL)),
        err_n=float(worst[n - 1]),
        err_other=float(worst[: n - 1].min()),
        n_minus=n - 1,
    )
    return [columns, last_entry]


def _check_least_squares(s: _Setting) -> EquationCheck:
    n, m = s.n, s.q.shape[0]
    zero = np.zeros(2 * n)
    jac = _printed_jacobian(s.lengths, link_angles(s.q))  # (8) at the nominal parameters
    delta = s.xy - _model_paper(s.lengths, s.q, zero)  # DeltaP_i
    normal = np.linalg.solve(
        np.einsum("mki,mkj->ij", jac, jac), np.einsum("mki,mk->i", jac, delta)
    )  # (10)
    stacked = jac.reshape(2 * m, 2 * n)  # J_a: the J_i one below the other
    solution = np.linalg.lstsq(stacked, delta.reshape(-1), rcond=None)[0]
    error = solution - s.truth_paper
    return equation_check(
        "least_squares",
        agrees=_rel(normal, solution) <= EXACT_RTOL,
        diff=_rel(normal, solution),
        rows=2 * m,
        cols=2 * n,
        literal_rows=2 * n * m,  # [J_1 ... J_m] side by side is 2 x 2nm; transposed 2nm x 2
        literal_cols=2,
        step_mm=float(np.max(np.abs(error[n:]))),
        step_deg=float(np.degrees(np.max(np.abs(error[:n])))),
    )


def _algorithm_checks(
    s: _Setting, plans: dict[tuple[int, int], np.ndarray], configurations: list[tuple[int, int]]
) -> list[EquationCheck]:
    """Steps 1-5 on noiseless data, and the index range of Step 4."""
    converged, iterations, err_mm, err_deg = 0, 0, 0.0, 0.0
    cases = [(paper_arm(n), q) for (n, _), q in plans.items()]
    cases.append(((s.arm, s.truth_user), s.q))
    for (arm, truth), q in cases:
        n = arm.n_joints
        xy = _model_user(arm.link_lengths, q, truth)
        estimate, used, ok = solve_gauss_newton(arm, q, xy)
        error = np.abs(estimate - truth) * arm.display_scale
        converged += bool(ok)
        iterations = max(iterations, int(used))
        err_mm = max(err_mm, float(error[:n].max()))
        err_deg = max(err_deg, float(error[n : 2 * n].max()))
    algorithm = equation_check(
        "algorithm",
        agrees=converged == len(cases) and max(err_mm, err_deg) <= EXACT_RTOL,
        plans=len(cases),
        poses=s.q.shape[0],
        converged=converged,
        iterations=iterations,
        err_mm=err_mm,
        err_deg=err_deg,
    )
    # Step 4 corrects j = 1..m; the model has links 1..n.
    extra = sum(max(m - n, 0) for n, m in configurations)
    missing = sum(max(n - m, 0) for n, m in configurations)
    index = equation_check(
        "algorithm_index",
        agrees=extra == 0 and missing == 0,
        configurations=", ".join(f"({n}, {m})" for n, m in configurations),
        over=sum(m > n for n, m in configurations),
        under=sum(m < n for n, m in configurations),
        extra=extra,
        missing=missing,
    )
    return [algorithm, index]


def _covariance_checks(
    s: _Setting, simulation: SimulationEvidence, configurations: list[tuple[int, int]]
) -> list[EquationCheck]:
    """Eq. (12)-(16) from the Monte Carlo runs and the sandwich algebra."""
    unbiased = equation_check(
        "unbiased",
        agrees=simulation.worst_bias_ratio <= 1.0,
        trials=simulation.trials,
        count=simulation.parameters,
        ratio=simulation.worst_bias_ratio,
    )
    m = s.q.shape[0]
    jac = _printed_jacobian(s.lengths, link_angles(s.q)).reshape(2 * m, -1)
    inverse = np.linalg.inv(jac.T @ jac)
    # E(eps_a eps_a^T) = sigma^2 I_2m, kept as its diagonal (one entry per measured
    # coordinate) so that no 2m x 2m matrix is formed.
    noise = np.full(2 * m, s.sigma**2)
    sandwich = _rel(inverse @ (jac.T * noise) @ jac @ inverse, s.sigma**2 * inverse)
    allowed = 4 / math.sqrt(2 * simulation.trials)
    covariance = equation_check(
        "covariance",
        agrees=sandwich <= EXACT_RTOL and simulation.worst_std_deviation <= allowed,
        sandwich=sandwich,
        mc=simulation.worst_std_deviation,
        count=simulation.parameters,
        trials=simulation.trials,
        allowed=allowed,
    )
    two_m = [2 * m for _, m in configurations]
    two_n = [2 * n for n, _ in configurations]
    size = equation_check("covariance_size", agrees=two_m == two_n, two_m=two_m, two_n=two_n)
    return [unbiased, covariance, size]


def _information_checks(s: _Setting) -> list[EquationCheck]:
    """Eq. (17)-(19) against sum J_i^T J_i built from central-difference Jacobians."""
    n, m = s.n, s.q.shape[0]
    jac = _central(lambda p: _model_paper(s.lengths, s.q, p), np.zeros(2 * n))
    info = np.einsum("mki,mkj->ij", jac, jac)
    a, b, c, d = info[:n, :n], info[:n, n:], info[n:, :n], info[n:, n:]
    cos_sums, sin_sums = _relative_sums(link_angles(s.q))
    ell = np.diag(s.lengths)
    blocks = equation_check(
        "information_diagonal_blocks",
        agrees=max(_rel(a, ell @ cos_sums @ ell), _rel(d, cos_sums)) <= FD_RTOL,
        poses=m,
        a=_rel(a, ell @ cos_sums @ ell),
        d=_rel(d, cos_sums),
    )
    diagonal = np.diag(a)
    printed = m * np.outer(s.lengths, s.lengths)  # m l_j l_k for every k
    off = np.abs(diagonal[:, None] - printed) / diagonal[:, None]
    off_min = float(off[~np.eye(n, dtype=bool)].min())
    diag_check = equation_check(
        "information_diagonal",
        agrees=bool(np.all(off <= FD_RTOL)),  # k is free in "m l_j l_k"
        a=_rel(diagonal, m * s.lengths**2),
        off=off_min,
        b=float(max(np.abs(np.diag(b)).max(), np.abs(np.diag(c)).max()) / np.abs(b).max()),
        d=float(np.abs(np.diag(d) - m).max()),
    )
    ls = ell @ sin_sums
    bc = {
        "b_plus": _rel(b, ls),
        "b_minus": _rel(b, -ls),
        "c_b": _rel(c, b),
        "c_bt": _rel(c, b.T),
        "c_plus": _rel(c, ls.T),
    }
    off_blocks = equation_check(
        "information_off_diagonal_blocks",
        # (17): B = C = L S; (19): B = L S, C = (L S)^T.
        agrees=max(bc["b_plus"], bc["c_b"], bc["c_plus"]) <= FD_RTOL,
        poses=m,
        **bc,
    )
    return [blocks, diag_check, off_blocks]


def _dstar_normalization(s: _Setting, optimal: np.ndarray) -> EquationCheck:
    """Eq. (20): ``det(C / n)`` of the orthogonal plan is 1 (``det(C / m)`` is not)."""
    n, m = s.n, optimal.shape[0]
    cos_opt, _ = _relative_sums(link_angles(optimal))
    det_over_n = float(np.linalg.det(cos_opt / n))
    det_over_m = float(np.linalg.det(cos_opt / m))
    return equation_check(
        "dstar_normalization",
        agrees=abs(det_over_n - 1) <= EXACT_RTOL,
        poses=m,
        links=n,
        det_over_n=det_over_n,
        det_over_m=det_over_m,
    )


def _dstar_determinant(m: int, rng: np.random.Generator) -> EquationCheck:
    """Eq. (21) on random 3-link plans: ``|det S'| = 0`` does not force ``S = 0``."""
    arm3, _ = paper_arm(3)
    odd = random_plan(arm3, RANDOM_PLANS * m, rng=rng).reshape(RANDOM_PLANS, m, 3)
    _, sin_odd = _relative_sums(link_angles(odd))
    det_max = float(np.abs(np.linalg.det(sin_odd / m)).max())
    s_max = float(np.abs(sin_odd / m).max())
    return equation_check(
        "dstar_determinant",
        # The criterion enforces S = 0 only if |det S'| = 0 forces it.
        agrees=not (det_max <= EXACT_RTOL and s_max > 1e-6),
        plans=RANDOM_PLANS,
        poses=m,
        det_max=det_max,
        s_max=s_max,
    )


def _d_optimality(
    s: _Setting, plans: dict[tuple[int, int], np.ndarray], random4: np.ndarray
) -> EquationCheck:
    """Eq. (22): the orthogonal plans are D-optimal, random plans ``random4`` below 1."""
    orthogonal = max(
        abs(1 - float(d_efficiency(paper_arm(k)[0], q))) for (k, _), q in plans.items()
    )
    random_max = float(d_efficiency(s.arm, random4).max())
    return equation_check(
        "d_optimality",
        agrees=orthogonal <= EXACT_RTOL and random_max < 1,
        orthogonal=orthogonal,
        plans=RANDOM_PLANS,
        poses=random4.shape[-2],
        random_max=random_max,
    )


def _sums(theta: np.ndarray) -> np.ndarray:
    """The relative sums ``C`` and ``S`` ``(2, n, n)`` of link angles ``theta`` ``(m, n)``."""
    return np.stack(_relative_sums(theta))


def _printed_derivatives(theta: np.ndarray, b: int) -> np.ndarray:
    """The paper's derivatives ``(2, n, n)`` of ``C`` and ``S`` in ``theta_b``."""
    n = theta.shape[-1]
    cos_sums, sin_sums = _relative_sums(theta)
    out = np.zeros((2, n, n))
    out[0, b, :], out[1, b, :] = -sin_sums[b, :], cos_sums[b, :]  # b = j
    out[0, :, b], out[1, :, b] = sin_sums[:, b], -cos_sums[:, b]  # b = k
    out[:, b, b] = 0.0  # j = k = b: c_bb = m and s_bb = 0 are constant
    return out


def _common_shift(theta: np.ndarray, b: int) -> np.ndarray:
    """Central differences ``(2, n, n)`` of the sums, ``theta_b`` shifted at every pose."""
    n = theta.shape[-1]
    return _central(lambda t: _sums(theta + t[0] * np.eye(n)[b]), np.zeros(1))[..., 0]


def _single_shift(theta: np.ndarray, b: int) -> np.ndarray:
    """Central differences ``(2, n, n)`` of the sums, ``theta_b`` shifted at the first pose."""
    unit = np.zeros_like(theta)
    unit[0, b] = 1.0
    return _central(lambda t: _sums(theta + t[0] * unit), np.zeros(1))[..., 0]


def _sum_derivatives(s: _Setting) -> EquationCheck:
    """Eq. (23): the printed derivatives of the sums against central differences."""
    n = s.n
    theta = link_angles(s.q)
    expected = np.stack([_printed_derivatives(theta, b) for b in range(n)])
    return equation_check(
        "sum_derivatives",
        agrees=_rel(np.stack([_common_shift(theta, b) for b in range(n)]), expected) <= FD_RTOL,
        poses=s.q.shape[0],
        common=_rel(np.stack([_common_shift(theta, b) for b in range(n)]), expected),
        single=_rel(np.stack([_single_shift(theta, b) for b in range(n)]), expected),
    )


def _stationarity(s: _Setting, optimal: np.ndarray, random4: np.ndarray) -> EquationCheck:
    """The orthogonal plan is stationary (derivatives of the sums and of ``det C'`` 0) and
    no random plan ``random4`` has a larger ``det C'``."""
    m, n = optimal.shape
    theta_opt = link_angles(optimal)
    common = float(np.abs(np.stack([_common_shift(theta_opt, b) for b in range(n)])).max())

    def det_c(flat: np.ndarray) -> float:
        cos_sums, _ = _relative_sums(flat.reshape(m, n))
        return float(np.linalg.det(cos_sums / m))

    single = float(np.abs(_central(det_c, theta_opt.reshape(-1))).max())
    det_random = float(dstar(s.arm, random4).det_c.max())
    return equation_check(
        "stationarity",
        # Derivatives of sums of m unit terms: round-off of m eps / h.
        agrees=common <= m * FD_RTOL and single <= FD_RTOL and det_random <= 1 + EXACT_RTOL,
        poses=m,
        common=common,
        single=single,
        plans=RANDOM_PLANS,
        det_max=det_random,
    )


def _dstar_checks(
    s: _Setting, plans: dict[tuple[int, int], np.ndarray], rng: np.random.Generator
) -> list[EquationCheck]:
    """Eq. (20)-(23): the D* normalization and determinant, D-optimality, derivatives."""
    m = PAPER_FIGURE1_POSES
    optimal = orthogonal_plan(s.arm, m)
    normalization = _dstar_normalization(s, optimal)
    determinant = _dstar_determinant(m, rng)  # draws from rng before the 4-link plans
    random4 = random_plan(s.arm, RANDOM_PLANS * m, rng=rng).reshape(RANDOM_PLANS, m, s.n)
    return [
        normalization,
        determinant,
        _d_optimality(s, plans, random4),
        _sum_derivatives(s),
        _stationarity(s, optimal, random4),
    ]


def _optimal_accuracy_checks(s: _Setting) -> list[EquationCheck]:
    """Eq. (24)-(25) at the orthogonal plan of the Table III 20-pose column."""
    n, m = s.n, max(m for _, m in PAPER_TABLE3)
    q = orthogonal_plan(s.arm, m)
    cov = s.sigma**2 * np.linalg.inv(information_matrix(s.arm, q))  # paper order
    printed = s.sigma**2 * np.concatenate([m * s.lengths**2, np.ones(n)])
    covariance = equation_check(
        "covariance_optimal",
        agrees=_rel(np.diag(cov), printed) <= EXACT_RTOL,
        poses=m,
        var_theta=float(cov[0, 0]),
        paper_theta=float(printed[0]),
        var_length=float(cov[n, n]),
        paper_length=float(printed[n]),
    )
    std = np.sqrt(np.diag(cov))
    formula_angle = s.sigma / (math.sqrt(m) * s.lengths)
    formula_length = np.full(n, s.sigma / math.sqrt(m))
    inverse = inverse_information(s.arm, q)
    assert inverse is not None  # an orthogonal plan identifies every parameter
    joint_offsets = s.sigma * np.sqrt(np.diag(inverse)[n : 2 * n])
    theta_diff = _rel(std[:n], formula_angle)
    length_diff = _rel(std[n:], formula_length)
    accuracy = equation_check(
        "accuracy_optimal",
        agrees=max(theta_diff, length_diff) <= EXACT_RTOL,
        poses=m,
        theta=theta_diff,
        length=length_diff,
        dq=float(np.max(np.abs(joint_offsets / formula_angle - 1))),
    )
    return [covariance, accuracy]


def _check_minimum_poses(rng: np.random.Generator) -> EquationCheck:
    """Smallest m by rank and by orthogonal plan, for n = 2, 3, 4 with and without a base."""
    lengths = paper_arm(4)[0].link_lengths
    found: dict[tuple[int, bool], tuple[int, int]] = {}
    for n in (2, 3, 4):
        for base in (False, True):
            arm = PlanarArm(lengths[:n], base_offset=base)
            m = 1
            while max_random_rank(arm, m, rng) < arm.n_params:
                m += 1
            # Fewer poses identify nothing, so no plan with fewer is orthogonal.
            for orthogonal in range(m, m + arm.n_params + 1):
                try:
                    q = orthogonal_plan(arm, orthogonal)
                except ArmcalError:
                    continue
                if abs(1 - float(d_efficiency(arm, q))) <= EXACT_RTOL:
                    break
            else:  # pragma: no cover - the Fourier plans exist for every m > n
                raise RuntimeError(f"no orthogonal plan for {arm.name} up to {orthogonal} poses")
            found[(n, base)] = (m, orthogonal)
    table = "; ".join(
        fill(
            ROWS["minimum_poses"],
            {
                "links": n,
                "rank": found[(n, False)][0],
                "orthogonal": found[(n, False)][1],
                "rank_base": found[(n, True)][0],
                "orthogonal_base": found[(n, True)][1],
            },
        )
        for n in (2, 3, 4)
    )
    smallest = min(m for _, m in PAPER_TABLE3)
    implied = [(n, m, "Table III") for n, m in sorted(PAPER_TABLE3) if m == smallest]
    implied.append((4, PAPER_RANGE_POSES[0], "Section VI"))
    enough = [m >= found[(n, False)][0] for n, m, _ in implied]
    return equation_check(
        "minimum_poses",
        agrees=all(enough),
        plans=RANK_PLANS,
        table=table,
        implied="; ".join(
            fill(
                ROWS["implied_enough" if ok else "implied_too_few"],
                {"links": n, "poses": m, "source": source},
            )
            for (n, m, source), ok in zip(implied, enough, strict=True)
        ),
        minimum={f"{n}{'+base' if base else ''}": value for (n, base), value in found.items()},
    )


def check_equations(
    *,
    sigma: float,
    plans: dict[tuple[int, int], np.ndarray],
    configurations: list[tuple[int, int]],
    simulation: SimulationEvidence,
    rng: np.random.Generator,
) -> list[EquationCheck]:
    """Every printed equation of Sections II-V, computed and compared, in the paper's order.

    Parameters
    ----------
    sigma : float
        Measurement noise (mm).
    plans : dict of (int, int) to ndarray
        The identifiable Table III configurations ``(links, poses)`` and their plans (rad).
    configurations : list of (int, int)
        Every Table III configuration, identifiable or not.
    simulation : SimulationEvidence
        The Monte Carlo runs behind Table III.
    rng : numpy.random.Generator
        Random plans.

    Returns
    -------
    list of EquationCheck
        In the order of :data:`~armcal.reproduction.catalogue.EQUATIONS`.
    """
    arm, truth = paper_arm(4)
    to_paper = paper_from_user_matrix(arm.n_joints)
    q = random_plan(arm, PAPER_FIGURE1_POSES, rng=rng)
    setting = _Setting(
        arm=arm,
        lengths=arm.link_lengths,
        truth_user=truth,
        truth_paper=to_paper @ truth,
        to_user=np.linalg.inv(to_paper),
        q=q,
        xy=_model_user(arm.link_lengths, q, truth),
        sigma=sigma,
    )
    checks = [
        _check_model(setting),
        *_gradient_checks(setting),
        _check_linearization(setting),
        *_jacobian_checks(setting),
        _check_least_squares(setting),
        *_algorithm_checks(setting, plans, configurations),
        *_covariance_checks(setting, simulation, configurations),
        *_information_checks(setting),
        *_dstar_checks(setting, plans, rng),
        *_optimal_accuracy_checks(setting),
        _check_minimum_poses(rng),
    ]
    return checks
