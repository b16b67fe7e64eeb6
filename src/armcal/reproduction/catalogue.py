"""The words of the comparison with the paper, as data: where, what it says, what is computed, why.

Every :class:`Entry` holds the static texts of one finding -- where in the paper,
what the paper says, a template for what is computed and a template for why
they differ.  The computation (:mod:`~armcal.reproduction.compute`,
:mod:`~armcal.reproduction.equations`) decides the verdicts and fills the
templates with the numbers it computed through :func:`disagreement` and
:func:`equation_check`; this module computes nothing.

Templates use :meth:`str.format` fields; a list or tuple value is written
element by element with the field's format spec, separated by commas.
"""

from __future__ import annotations

import string
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

__all__ = [
    "DERIVATIVE_LABELS",
    "DISAGREEMENTS",
    "EQUATIONS",
    "READING_LABELS",
    "ROWS",
    "Disagreement",
    "Entry",
    "EquationCheck",
    "disagreement",
    "equation_check",
    "fill",
]


@dataclass(frozen=True)
class Entry:
    """The static texts of one finding.

    Attributes
    ----------
    where : str
        Equation, table or sentence of the paper (may hold template fields).
    paper : str
        What the paper says.
    computed : str
        Template of what armcal computes.
    cause : str
        Template of why the two differ (shown only when they do).
    """

    where: str
    paper: str
    computed: str
    cause: str


@dataclass(frozen=True)
class Disagreement:
    """One place where the paper and the recomputation differ.

    Attributes
    ----------
    where : str
        Equation, table or sentence of the paper.
    paper : str
        What the paper says.
    computed : str
        What armcal computes.
    cause : str
        Why they differ.
    """

    where: str
    paper: str
    computed: str
    cause: str


@dataclass(frozen=True)
class EquationCheck:
    """One printed equation, computed and compared.

    Attributes
    ----------
    key : str
        Key of :data:`EQUATIONS`.
    where : str
        The equation(s) of the paper.
    paper : str
        What the paper prints.
    evidence : str
        The computed numbers behind the verdict.
    agrees : bool
        Whether the computation confirms the printed equation as it stands.
    cause : str
        Why it differs (empty when it agrees).
    values : dict
        The computed values that filled ``evidence`` and decided ``agrees``.
    """

    key: str
    where: str
    paper: str
    evidence: str
    agrees: bool
    cause: str
    values: Mapping[str, Any] = field(default_factory=dict)

    @property
    def verdict(self) -> str:
        """``"agrees"`` or ``"differs"``."""
        return "agrees" if self.agrees else "differs"

    def disagreement(self) -> Disagreement | None:
        """The finding as a :class:`Disagreement`, or None when the equation agrees."""
        if self.agrees:
            return None
        return Disagreement(self.where, self.paper, self.evidence, self.cause)


class _Formatter(string.Formatter):
    """``str.format`` that writes lists and tuples element by element."""

    def format_field(self, value: Any, format_spec: str) -> str:
        if isinstance(value, list | tuple):
            return ", ".join(self.format_field(v, format_spec) for v in value)
        return super().format_field(value, format_spec)


_FORMATTER = _Formatter()


def fill(template: str, values: Mapping[str, Any]) -> str:
    """``template`` with its fields replaced by ``values`` (lists written element by element).

    Examples
    --------
    >>> fill("{x:.2f} mm; {ys:.1f} deg", {"x": 0.0224, "ys": [0.5, 0.25]})
    '0.02 mm; 0.5, 0.2 deg'
    """
    return _FORMATTER.vformat(template, (), values)


def disagreement(key: str, **values: Any) -> Disagreement:
    """The :data:`DISAGREEMENTS` entry ``key`` filled with computed ``values``."""
    entry = DISAGREEMENTS[key]
    return Disagreement(
        fill(entry.where, values),
        fill(entry.paper, values),
        fill(entry.computed, values),
        fill(entry.cause, values),
    )


def equation_check(key: str, *, agrees: bool, **values: Any) -> EquationCheck:
    """The :data:`EQUATIONS` entry ``key`` filled with computed ``values`` and its verdict."""
    entry = EQUATIONS[key]
    return EquationCheck(
        key=key,
        where=fill(entry.where, values),
        paper=fill(entry.paper, values),
        evidence=fill(entry.computed, values),
        agrees=bool(agrees),
        cause="" if agrees else fill(entry.cause, values),
        values=dict(values),
    )


#: Tables, figures and sentences of the paper that differ from the recomputation.
DISAGREEMENTS: dict[str, Entry] = {
    "table3_repeated": Entry(
        where="Table III, {links} links, {poses} poses, {names}",
        paper="{printed} {unit}",
        computed="{analytic:.4g} {unit} analytic (sigma/sqrt({poses})); simulated {simulated:.4g}",
        cause="the printed value is the {other_poses}-pose value ({other:.4g} {unit}, which "
        "rounds to it), repeated in the {poses}-pose column",
    ),
    "table3_differs": Entry(
        where="Table III, {links} links, {poses} poses, {names}",
        paper="{printed} {unit}",
        computed="{analytic:.4g} {unit} analytic; simulated {simulated:.4g}",
        cause="no configuration of the table gives the printed value",
    ),
    "table3_not_computable": Entry(
        where="Table III, {links} links, {poses} poses",
        paper="accuracies of all {params} parameters: dL = {printed_dl:g} mm, "
        "dq = {printed_dq:g} deg",
        computed="cannot be computed: {poses} poses give {equations} equations for {params} "
        "parameters; the largest Jacobian rank over {plans} random {poses}-pose plans is "
        "{rank} < {params}, so no plan identifies the parameters. The closed forms of "
        "eq. (25) at m = {poses} give {formula_dl:.4f} mm and {formula_dq:.4f} deg",
        cause="the printed numbers are the closed forms of eq. (25) evaluated at m = {poses} "
        "beyond their validity (they need an identifying plan, m >= {min_poses} poses for "
        "{links} links); they cannot come from a simulation",
    ),
    "table3_not_computable_unexplained": Entry(
        where="Table III, {links} links, {poses} poses",
        paper="accuracies of all {params} parameters: dL = {printed_dl:g} mm, "
        "dq = {printed_dq:g} deg",
        computed="cannot be computed: {poses} poses give {equations} equations for {params} "
        "parameters; the largest Jacobian rank over {plans} random {poses}-pose plans is "
        "{rank} < {params}",
        cause="no plan of {poses} poses identifies the parameters; the printed numbers cannot "
        "come from a simulation",
    ),
    "table3_dq_label": Entry(
        where="Table III, 'dq' columns (and the sigma_qi of eq. (25))",
        paper="labelled dq, the joint offsets; e.g. {links} links, {poses} poses, "
        "dq{k}: {printed:g} deg",
        computed="of the {total} printed 'dq' values that can be computed, {theta_agree} agree "
        "with the std of the cumulative link angle dtheta_k = dq_1 + ... + dq_k and "
        "{dq_agree} with the std of the joint offset dq_k (e.g. dq{k}: joint offset "
        "{joint:.4g} deg, dtheta{k} {theta:.4g} deg)",
        cause="the paper identifies dtheta_k (Section II: parameters {{dl_i, dtheta_i}}), whose "
        "std is sigma/(sqrt(m) l_k); the joint offset dq_k = dtheta_k - dtheta_(k-1) has std "
        "sigma/sqrt(m) sqrt(1/l_k^2 + 1/l_(k-1)^2) for k >= 2. table3.csv compares each "
        "printed 'dq' with dtheta_k and shows the joint-offset std beside it",
    ),
    "table1_notation": Entry(
        where="Table I, 3-links notation",
        paper="s_3i = sin(q_2i + q_3i)",
        computed="the condition sum s23 = 0 ({s23:.1e} on the generated plans) uses "
        "sin(q2 + q3); sum s3 = 0 ({s3:.1e}) uses sin(q3): two conditions, two symbols",
        cause="typo: s_3i for s_23i",
    ),
    "a_criterion": Entry(
        where="Section V: 'it is not reasonable to use the A-criterion because the trace of "
        "the matrix sum J^T J does not depend on the plan'",
        paper="A-criterion not applicable",
        computed="tr(sum J^T J) over {plans} random {poses}-pose plans of the 4-link arm: "
        "{trace_min:.8g}..{trace_max:.8g} (constant indeed); but the A-criterion is "
        "tr((sum J^T J)^-1), whose efficiency ranges {a_min:.3g}..{a_max:.3g} over the same "
        "plans (1 for orthogonal plans)",
        cause="the A-criterion was confused with the trace of the information matrix; armcal "
        "offers it (design --criterion A)",
    ),
    "section6_range": Entry(
        where="Section VI: 'the identification error reduces from {printed_from:g} mm to "
        "{printed_to:g} mm while the experiment number increases from {m_from} to {m_to}'",
        paper="{printed_from:g} mm at {m_from} poses, {printed_to:g} mm at {m_to} poses",
        computed="length std {length_from:.4g} mm at {m_from} poses, {length_to:.4g} mm at "
        "{m_to} poses (sigma/sqrt(m)); at {m_to} poses dtheta1 has std {theta1_to:.4g} deg",
        cause="the sentence mixes columns of Table III: {printed_from:g} mm is the "
        "{m_to}-pose length accuracy and {printed_to:g} the {m_to}-pose angle accuracy (deg)",
    ),
    "section6_range_unexplained": Entry(
        where="Section VI: 'the identification error reduces from {printed_from:g} mm to "
        "{printed_to:g} mm while the experiment number increases from {m_from} to {m_to}'",
        paper="{printed_from:g} mm at {m_from} poses, {printed_to:g} mm at {m_to} poses",
        computed="length std {length_from:.4g} mm at {m_from} poses, {length_to:.4g} mm at "
        "{m_to} poses (sigma/sqrt(m))",
        cause="neither number is the length accuracy at its number of poses",
    ),
    "section6_goal": Entry(
        where="Section VI: 'to satisfy an accuracy of {goal:g} mm for linear parameters it is "
        "required to carry out {poses} experiments'",
        paper="{poses} poses for {goal:g} mm, giving {angles:g} deg for the angles",
        computed="{poses} poses give {std_at:.4g} mm; {goal:g} mm needs {needed} poses "
        "(smallest m whose orthogonal plan reaches it, found by bisection; {before} poses "
        "give {std_before:.6g} mm). At {poses} poses the angles dtheta_k have std "
        "{theta:.4f} deg against the printed {angles:g}: {angles_agree}",
        cause="sigma/sqrt({poses}) = {std_at:.4g} mm: the length claim is off by a factor "
        "{factor:.3g} in accuracy, {factor_poses:.3g} in poses",
    ),
}


#: The printed equations of Sections II-V, in the paper's order.
EQUATIONS: dict[str, Entry] = {
    "model": Entry(
        where="Eq. (1)-(2): the geometric model",
        paper="x = sum_i (l_i + dl_i) cos(sum_(j<=i) (q_j + dq_j)), y alike with sin",
        computed="the printed double sum and armcal's forward kinematics agree to {diff:.1e} mm "
        "at {poses} random poses of the 4-link arm with the paper's deviations",
        cause="armcal's model is not the paper's eq. (1)",
    ),
    "gradient_angles": Entry(
        where="Eq. (3)-(4): dF/d(dtheta_k) with inner sums 'sum_(l=i)^n'",
        paper="the inner sums run over l = i..n, i the experiment index",
        computed="twice the printed expression against central differences of F (3) at "
        "{poses} random poses of the 4-link arm, relative differences: as printed "
        "(l = i..n) {literal_dtheta:.1e} against dF/d(dtheta_k), {literal_dq:.1e} against "
        "dF/d(dq_k); l = k..n {upto_dtheta:.1e} and {upto_dq:.1e}; l = k alone "
        "{single_dtheta:.1e} and {single_dq:.1e}. Within {rtol:.0e}: {matches}",
        cause="the lower bound i (the experiment index) is a typo; the numbers support "
        "{matches}: for the derivative named, dF/d(dtheta_k) (the paper's parameter), only "
        "the single term l = k",
    ),
    "gradient_lengths": Entry(
        where="Eq. (3), (5): dF/d(dl_k)",
        paper="sum_i [cos(theta_k + dtheta_k) (f_x - x_i) + sin(theta_k + dtheta_k) "
        "(f_y - y_i)] = 0",
        computed="twice the printed expression against central differences of F (3): "
        "relative difference {diff:.1e}",
        cause="the printed expression is not proportional to dF/d(dl_k)",
    ),
    "gradient_scale": Entry(
        where="Eq. (4)-(5): scale of the derivatives",
        paper="the expressions are dF/d(dtheta_k) and dF/d(dl_k)",
        computed="central differences of F divided by the printed expressions (the l = k "
        "reading of (4)): {ratio_angles:.9g} for (4), {ratio_lengths:.9g} for (5)",
        cause="F (3) is a sum of squares, so its derivatives carry a factor 2 that (4)-(5) "
        "drop; harmless, since the expressions are set to zero",
    ),
    "linearization": Entry(
        where="Eq. (6): P_i = P_0i + J_i DeltaPi",
        paper="the linearization of (1) at the nominal parameters",
        computed="remainder max |f(t DeltaPi) - P_0 - J t DeltaPi| at the paper's 4-link "
        "deviations: {err_full:.3g} mm at t = 1, {err_half:.3g} mm at t = 1/2, ratio "
        "{ratio:.3f} (4 for a second-order remainder)",
        cause="the remainder is not of second order: (6) is not the linearization of (1)",
    ),
    "jacobian_columns": Entry(
        where="Eq. (7)-(8): the Jacobian J_i = [J_xq J_xl; J_yq J_yl]",
        paper="J_xq = [-l_1 sin theta_1 ... -l_n sin theta_n], J_yq = [l_1 cos theta_1 ...], "
        "J_xl = [cos theta_1 ...], J_yl = [sin theta_1 ...]",
        computed="against central differences of model (1) at the nominal parameters and at "
        "the paper's deviations (lengths and angles corrected as in Step 4), {poses} random "
        "poses of the 4-link arm: the angular columns differ by {vs_dtheta:.1e} (relative) "
        "from the derivatives with respect to dtheta_k, the cumulative link angle, and by "
        "{vs_dq:.2g} from those with respect to the joint offsets dq_k; the length columns "
        "by {vs_dl:.1e}. So the 'q' of J_xq, J_yq stands for dtheta",
        cause="the printed columns are not the derivatives of (1) with respect to "
        "DeltaPi = {{dtheta_i, dl_i}}",
    ),
    "jacobian_last_entry": Entry(
        where="Eq. (8): last entry of J_yq",
        paper="J_yq = [l_1 cos theta_1 ... l_j cos theta_j]",
        computed="the last angular column of the y row (central differences) equals "
        "l_n cos theta_n to {err_n:.1e} (relative); l_j cos theta_j with j = 1..{n_minus} "
        "is off by at least {err_other:.2g}",
        cause="typo: index j for n (the row ends with l_n cos theta_n, like J_xq)",
    ),
    "least_squares": Entry(
        where="Eq. (9)-(11): the linearized least-squares solution",
        paper="sum J_i^T J_i DeltaPi = sum J_i^T DeltaP_i; DeltaPi = (J_a^T J_a)^-1 J_a^T "
        "DeltaP_a with J_a = [J_1 J_2 ... J_m]^T",
        computed="the normal equations (10) and an SVD least-squares solve (numpy lstsq) of J_a "
        "({rows} x {cols}) agree to {diff:.1e} (relative) when J_a stacks the J_i vertically "
        "(read literally, [J_1 ... J_m]^T would be {literal_rows} x {literal_cols}). One "
        "solve from DeltaPi = 0 on noiseless data leaves errors up to {step_mm:.2g} mm and "
        "{step_deg:.2g} deg (second order in DeltaPi): hence the iterations of Steps 1-5",
        cause="(10) and (11) do not give the least-squares solution of (9)",
    ),
    "algorithm": Entry(
        where="Section III, Steps 1-5 (links j = 1..n in Step 4)",
        paper="iterating (11) and correcting l_j, theta_j recovers the parameters exactly "
        "from error-free data",
        computed="armcal.reproduction.algorithm.solve_gauss_newton on noiseless data of the "
        "paper's deviations, {plans} plans (Table III's identifiable ones and a random "
        "{poses}-pose plan of the 4-link arm): {converged} of {plans} converged, within "
        "{iterations} iterations; largest error {err_mm:.1e} mm, {err_deg:.1e} deg",
        cause="the iteration does not recover error-free data exactly",
    ),
    "algorithm_index": Entry(
        where="Section III, Step 4: 'j = 1..m'",
        paper="l_j = l_j + dl_j, theta_ji = theta_ji + dtheta_j, j = 1..m",
        computed="there are n links to correct; of the Table III configurations (n, m) = "
        "{configurations}, the printed range 1..m runs past the n links in {over} ({extra} "
        "indices of links that do not exist) and stops short of them in {under} ({missing} "
        "links never corrected)",
        cause="typo: j = 1..n (m counts poses, n links)",
    ),
    "unbiased": Entry(
        where="Eq. (12)-(14): unbiased estimates",
        paper="E(DeltaPi) = (J_a^T J_a)^-1 J_a^T DeltaP_a, the true deviations",
        computed="Monte Carlo ({trials} trials per identifiable Table III configuration, "
        "{count} parameters): the largest |bias| is {ratio:.2f} of 4 std/sqrt(N)",
        cause="the estimates are biased beyond their sampling error",
    ),
    "covariance": Entry(
        where="Eq. (15)-(16): cov(DeltaPi) = sigma^2 (sum J_i^T J_i)^-1",
        paper="the sandwich (15) reduces to (16) for iid errors",
        computed="(15) with E(eps_a eps_a^T) = sigma^2 I_2m equals (16) to {sandwich:.1e} "
        "(relative); Monte Carlo std against (16): largest relative difference {mc:.3f} over "
        "{count} parameters ({trials} trials; sampling allows 4/sqrt(2N) = {allowed:.3f})",
        cause="the Monte Carlo scatter does not follow (16)",
    ),
    "covariance_size": Entry(
        where="Eq. (15)-(16): 'E(eps_a eps_a^T) = sigma^2 I_2n, of size 2n x 2n'",
        paper="I_2n",
        computed="eps_a stacks the 2 coordinates of the m poses: E(eps_a eps_a^T) is 2m x 2m "
        "as J_a (2m x 2n) requires; in the Table III configurations 2m = {two_m} against "
        "2n = {two_n}",
        cause="typo: n (links) for m (poses)",
    ),
    "information_diagonal_blocks": Entry(
        where="Eq. (17)-(19): blocks A and D",
        paper="A = [l_j l_k c_jk] = L C L, D = [c_jk] = C, c_jk = sum_i cos(theta_j - theta_k)",
        computed="sum J_i^T J_i from central-difference Jacobians of (1), {poses} random "
        "poses of the 4-link arm: relative difference {a:.1e} for A, {d:.1e} for D",
        cause="the printed blocks are not those of sum J_i^T J_i",
    ),
    "information_diagonal": Entry(
        where="Eq. (18): 'A_jj = m l_j l_k; B_jj = C_jj = 0; D_jj = m'",
        paper="A_jj = m l_j l_k",
        computed="the diagonal of A is m l_j^2 to {a:.1e} (relative); m l_j l_k with k != j "
        "is off by at least {off:.2g}; largest |B_jj|, |C_jj| {b:.1e} of the largest |B_jk|; "
        "largest |D_jj - m| {d:.1e}",
        cause="typo: A_jj = m l_j^2 (k = j on the diagonal)",
    ),
    "information_off_diagonal_blocks": Entry(
        where="Eq. (17), (19): blocks B and C",
        paper="B = C = [l_j s_jk]; (19): upper right L S, lower left (L S)^T, with "
        "s_jk = sum_i sin(theta_j - theta_k)",
        computed="sum J_i^T J_i from central-difference Jacobians, {poses} random poses of the "
        "4-link arm, relative differences: upper right B against L S {b_plus:.2g}, against "
        "-L S {b_minus:.1e}; lower left C against B {c_b:.2g}, against B^T {c_bt:.1e}, "
        "against (L S)^T {c_plus:.2g}",
        cause="sign and transpose: dp/d(dtheta_j) . dp/d(dl_k) = l_j sin(theta_k - theta_j), "
        "so B = -L S = L S^T (S is antisymmetric) and C = B^T = S L; B = C does not hold. "
        "(19) holds with s_jk = sum_i sin(theta_k - theta_j). No consequence for (21), which "
        "asks S = 0",
    ),
    "dstar_normalization": Entry(
        where="Eq. (20): C' = [c_jk / n], S' = [s_jk / n]",
        paper="det(C') = 1 for the optimal plans (Section V, Figure 1)",
        computed="orthogonal {poses}-pose plan of the {links}-link arm: det(C/n) = "
        "{det_over_n:.4g}, det(C/m) = {det_over_m:.6g}",
        cause="c_jj = m (not n), so the normalization that makes det(C') = 1 at the optimum is "
        "C/m; with /n, det C' = (m/n)^n",
    ),
    "dstar_determinant": Entry(
        where="Eq. (20): |det(S')| -> min",
        paper="minimizing |det S'| (with det C' max) enforces s_jk = 0",
        computed="S is antisymmetric, so det S = 0 for every plan when n is odd: over {plans} "
        "random {poses}-pose plans of the 3-link arm, largest |det S'| = {det_max:.1e} while "
        "the largest |s_jk|/m is {s_max:.2f}",
        cause="det S' = 0 is necessary, not sufficient, for S = 0, and for odd n it says "
        "nothing; armcal maximizes the determinant of the whole normalized matrix "
        "(D-efficiency), whose maximum 1 holds exactly when C and S vanish off the diagonal",
    ),
    "d_optimality": Entry(
        where="Eq. (21): c_jk = s_jk = 0 (j != k) gives the D-optimal plan",
        paper="the conditions (21) correspond to D-optimality",
        computed="the orthogonal plans of Tables I-III meet (21) and have D-efficiency 1 to "
        "{orthogonal:.1e}; the largest D-efficiency of {plans} random {poses}-pose plans of "
        "the 4-link arm is {random_max:.3f} (Hadamard's inequality: at most 1, with equality "
        "only when (21) holds)",
        cause="plans meeting (21) are not D-optimal",
    ),
    "sum_derivatives": Entry(
        where="Eq. (22): derivatives of c_jk, s_jk",
        paper="dc_jk/dtheta_b = -s_jk (b = j), s_jk (b = k), else 0; ds_jk/dtheta_b = c_jk "
        "(b = j), -c_jk (b = k), else 0",
        computed="central differences, {poses} random poses of the 4-link arm, theta_b changed "
        "by the same amount in every pose: relative difference {common:.1e}; changed in one "
        "pose only, the derivative is that pose's term alone (off by {single:.2g}), so "
        "theta_b stands for a common change",
        cause="the printed derivatives are wrong",
    ),
    "stationarity": Entry(
        where="Eq. (23): dC/dtheta_b = dS/dtheta_b = 0 at the optimum",
        paper="the derivatives vanish, which guarantees the maximum of the determinant",
        computed="at the orthogonal {poses}-pose plan of the 4-link arm: largest |dc_jk/dtheta_b|,"
        " |ds_jk/dtheta_b| {common:.1e} (common change) and largest |d det C'/dtheta_b| in a "
        "single pose {single:.1e}; det C' <= 1 on all {plans} random plans (largest "
        "{det_max:.3f}), so the stationary point is the maximum (Hadamard)",
        cause="the plan meeting (21) is not a stationary point of det C'",
    ),
    "covariance_optimal": Entry(
        where="Eq. (24): cov = sigma^2 [m L L, 0; 0, I]",
        paper="var(dtheta_i) = sigma^2 m l_i^2, var(dl_i) = sigma^2",
        computed="sigma^2 (sum J^T J)^-1 at the orthogonal {poses}-pose plan of the 4-link arm "
        "= sigma^2 diag((m L L)^-1, I/m): var(dtheta1) = {var_theta:.3e} rad^2 against the "
        "printed {paper_theta:.3e}, var(dl1) = {var_length:.3e} mm^2 against {paper_length:.3e}",
        cause="the inverse and the 1/m of the second block were dropped; eq. (25), which "
        "follows from the correct form, is right",
    ),
    "accuracy_optimal": Entry(
        where="Eq. (25): sigma_qi = sigma/(sqrt(m) l_i), sigma_Li = sigma/sqrt(m)",
        paper="the std of the angular and linear parameters of an optimal plan",
        computed="sqrt(diag(sigma^2 (sum J^T J)^-1)) at the orthogonal {poses}-pose plan of the "
        "4-link arm: relative difference {theta:.1e} for the angles dtheta_i, {length:.1e} for "
        "the lengths. Read as joint offsets dq_i (the label q_i), whose std is "
        "sigma/sqrt(m) sqrt(1/l_i^2 + 1/l_(i-1)^2) for i >= 2, it is off by up to {dq:.2g} "
        "(see Table III 'dq')",
        cause="the closed forms do not match the covariance of an optimal plan",
    ),
    "minimum_poses": Entry(
        where="Minimum number of poses (Table III's 3-pose column; Section VI's 'from 4 to 20')",
        paper="3 poses calibrate the 3- and 4-link arms (Table III); the 4-link study starts "
        "at 4 poses (Section VI)",
        computed="smallest m of full Jacobian rank (armcal.models.identifiability, largest "
        "rank over {plans} random plans per m) and smallest m of an orthogonal plan "
        "(armcal.doe.orthogonal_plan, D-efficiency 1): {table}. Implied by the paper: "
        "{implied}",
        cause="m poses give 2m equations: 3 poses suffice for the 3-link arm's 6 parameters "
        "only (exactly determined: no residual left to estimate sigma), never for the "
        "4-link arm's 8; the 4 poses of Section VI are the minimum for 4 links without a "
        "base offset (with one, n + 1)",
    ),
}


#: Row templates the computation joins into longer texts.
ROWS: dict[str, str] = {
    "minimum_poses": "{links} links: {rank} ({orthogonal} orthogonal), with a base offset "
    "{rank_base} ({orthogonal_base})",
    "implied_enough": "{links} links with {poses} poses ({source}): enough",
    "implied_too_few": "{links} links with {poses} poses ({source}): too few",
    "angles_agree": "they agree",
    "angles_differ": "they differ",
    "no_match": "no reading",
    "note_not_computable": "cannot be computed: {poses} poses give {equations} equations for "
    "{params} parameters (largest Jacobian rank over random plans: {rank}), so no plan "
    "identifies them",
    "note_exact": "exactly determined (2m = p): zero residual, sigma must be known",
    "note_dq1": "dq1 = dtheta1",
    "note_dq": "printed 'dq' compared with the cumulative angle dtheta{k} (the sum of "
    "dq1..dq{k}); the joint offset dq{k} has joint_offset_std",
}


#: The three readings of the inner sums of eq. (4).
READING_LABELS: dict[str, str] = {
    "literal": "l = i..n (as printed)",
    "upto": "l = k..n",
    "single": "l = k alone",
}


#: The two derivatives a reading of eq. (4) may equal.
DERIVATIVE_LABELS: dict[str, str] = {
    "dtheta": "dF/d(dtheta_k)",
    "dq": "dF/d(dq_k)",
}
