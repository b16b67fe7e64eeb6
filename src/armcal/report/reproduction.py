"""The paper recomputed as text and JSON: ``report.md`` and the command's summary."""

from __future__ import annotations

from ..paper import PAPER_DIGIT
from ..reproduction.compute import TABLE_COLUMNS, Reproduction
from .common import markdown

__all__ = [
    "format_reproduction",
    "reproduction_summary",
]


def _not_computable(result: Reproduction) -> str:
    """``"4 links with 3 poses"``: the Table III configurations no plan can calibrate."""
    configurations = sorted(
        {(r["links"], r["poses"]) for r in result.tables["table3"] if r["computable"] == "no"}
    )
    return ", ".join(f"{n} links with {m} poses" for n, m in configurations) or "none"


def _counts_line(result: Reproduction) -> str:
    counts = result.printed_values()
    return (
        f"{counts['agree']} of the paper's {counts['printed']} printed values agree, "
        f"{counts['differ']} differ, {counts['not_computable']} cannot be computed "
        f"({_not_computable(result)}: no plan identifies the parameters)"
    )


def _equations_line(result: Reproduction) -> str:
    differing = [c for c in result.equations if not c.agrees]
    return (
        f"{len(result.equations)} printed equations checked by computing them: "
        f"{len(result.equations) - len(differing)} agree, {len(differing)} differ"
    )


def _setup_lines(result: Reproduction) -> list[str]:
    """The report's title and its set-up section: arms, noise, plans, seed, the counts."""
    return [
        "# The paper's Sections II-VI, recomputed by armcal",
        "",
        "Klimchik et al., *Design of Experiments for Calibration of Planar Anthropomorphic "
        "Manipulators*. Every number below is computed; the paper's values appear only "
        "in the `paper_value` column and in the comparison.",
        "",
        "## Set-up",
        "",
        "- Arms: the paper's 2-, 3- and 4-link arms, l = 260, 180, 120, 100 mm, true "
        "deviations dl = 1.5, -0.6, -0.4, 0.7 mm and dq = 0.5, -0.5, 0.7, -0.3 deg "
        "(built-in robots `paper-2link`, `paper-3link`, `paper-4link`), no joint limits.",
        f"- Noise: sigma = {result.sigma_mm:g} mm per coordinate, iid normal.",
        f"- Plans: orthogonal plans meeting Table I exactly (`armcal.doe.orthogonal_plan`: "
        f"q1 = 0, q2 = ... = qn = 360 k / m deg); Monte Carlo with {result.trials} trials per "
        f"configuration (closed-form solver); {result.random_plans} random plans (uniform "
        "joint angles) per random study.",
        f"- Seed {result.seed}; the whole reproduction took {result.seconds:.1f} s.",
        "- Table III has one row per printed value, each compared once: a printed dL_k with "
        "the std of dl_k, a printed 'dq_k' with the std of the cumulative link angle "
        "dtheta_k = dq_1 + ... + dq_k, the paper's parameter (the std of the joint offset "
        "dq_k is shown beside it, `joint_offset_std`). `analytic_std`: "
        "sqrt(diag(sigma^2 (J^T J)^-1)) at the nominal geometry; `simulated_std`: the std "
        "over the trials. `agrees` is yes when the printed value is within "
        f"{PAPER_DIGIT} (one unit of its last digit) of `analytic_std`; `computable` is no "
        "when no plan of that many poses identifies the parameters.",
        f"- Table III: {_counts_line(result)}.",
        f"- Simulated and analytic std agree to within "
        f"{100 * result.worst_std_disagreement:.1f} % in every identifiable configuration "
        f"(sampling error of a std from {result.trials} trials: "
        f"{100 * result.std_sampling_error:.1f} %).",
        f"- Equations: {_equations_line(result)} (section 'Equations checked').",
        "",
    ]


def _table_lines(result: Reproduction) -> list[str]:
    """Tables I-III as markdown, each under its heading."""
    return [
        "## Table I: optimality conditions on the generated plans (`table1.csv`)",
        "",
        *markdown(result.tables["table1"], TABLE_COLUMNS["table1"]),
        "",
        "## Table II: information matrix and analytic accuracy (`table2.csv`)",
        "",
        *markdown(result.tables["table2"], TABLE_COLUMNS["table2"]),
        "",
        "## Table III: identification accuracy, analytic and simulated (`table3.csv`)",
        "",
        *markdown(result.tables["table3"], TABLE_COLUMNS["table3"]),
        "",
    ]


def _figure_lines(result: Reproduction) -> list[str]:
    """Figures 1-2, each with what it shows."""
    study = result.figure1.summary()
    return [
        "## Figure 1: random 10-pose plans of the 4-link arm (`figure1.png`)",
        "",
        "![Figure 1](figure1.png)",
        "",
        f"det(D') = D-efficiency^p over {result.random_plans} random plans: median "
        f"{study['det_d_median']:.3g}, max {study['det_d_max']:.3g} "
        f"(orthogonal plan: 1); {100 * study['det_d_below_half']:.1f} % of the "
        "plans are below 0.5. det(C') median "
        f"{study['det_c_median']:.3g} (optimum 1), |det(S')| median "
        f"{study['abs_det_s_median']:.3g} (optimum 0). This confirms the paper's "
        "qualitative claim that random plans are poor.",
        "",
        "## Figure 2: accuracy against the number of poses, 4-link arm (`figure2.png`)",
        "",
        "![Figure 2](figure2.png)",
        "",
        "Curve 1: analytic, orthogonal plans; x: simulated orthogonal plans; curve 2: "
        f"random plans, mean and median over {result.random_plans} plans of the predicted "
        "accuracy (the mean is dominated by nearly singular plans at small m).",
        "",
    ]


def _check_lines(result: Reproduction) -> list[str]:
    """The printed equations checked, one numbered item each with its verdict."""
    lines = [
        "## Equations checked",
        "",
        "Each printed equation of Sections II-V, computed: model (1) from its printed double "
        "sum, Jacobians and gradients by central differences of it, information matrices "
        "from those Jacobians, the algorithm with "
        "`armcal.reproduction.algorithm.solve_gauss_newton`.",
        "",
    ]
    for i, check in enumerate(result.equations, start=1):
        lines += [
            f"{i}. **{check.where}: {check.verdict}.** Paper: {check.paper}. "
            f"Computed: {check.evidence}.",
            "",
        ]
    return lines


def _disagreement_lines(result: Reproduction) -> list[str]:
    """Where the paper differs, one numbered item each with its cause."""
    lines = ["## Where this differs from the paper", ""]
    for i, d in enumerate(result.disagreements, start=1):
        lines += [
            f"{i}. **{d.where}.** Paper: {d.paper}. Computed: {d.computed}. Cause: {d.cause}.",
            "",
        ]
    return lines


def format_reproduction(result: Reproduction) -> str:
    """``report.md``: set-up, Tables I-III, Figures 1-2, equations checked, disagreements."""
    lines = [
        *_setup_lines(result),
        *_table_lines(result),
        *_figure_lines(result),
        *_check_lines(result),
        *_disagreement_lines(result),
    ]
    return "\n".join(lines)


def reproduction_summary(result: Reproduction) -> tuple[dict, list[str]]:
    """The JSON document and the text lines of ``armcal reproduce``.

    Parameters
    ----------
    result : Reproduction

    Returns
    -------
    document : dict
        ``trials``, ``random_plans``, ``seed``, ``seconds``; Table III's printed
        values counted once each: ``printed_values``, ``printed_values_agreeing``,
        ``printed_values_differing``, ``printed_values_not_computable`` (and
        ``table3_rows``, one per printed value); ``equations`` (each printed
        equation with its verdict), ``equations_differing``; ``disagreements``
        (where the paper differs).  The caller adds ``files``.
    lines : list of str
        What was reproduced, the counts, and every disagreement; the caller
        adds the line naming the files written.
    """
    counts = result.printed_values()
    document = {
        "trials": result.trials,
        "random_plans": result.random_plans,
        "seed": result.seed,
        "seconds": result.seconds,
        "table3_rows": len(result.tables["table3"]),
        "printed_values": counts["printed"],
        "printed_values_agreeing": counts["agree"],
        "printed_values_differing": counts["differ"],
        "printed_values_not_computable": counts["not_computable"],
        "equations": [{"equation": c.where, "verdict": c.verdict} for c in result.equations],
        "equations_differing": sum(not c.agrees for c in result.equations),
        "disagreements": [d.where for d in result.disagreements],
    }
    lines = [
        f"reproduced the paper's Tables I-III and Figures 1-2 with {result.trials} trials "
        f"per configuration (seed {result.seed}) in {result.seconds:.1f} s",
        f"Table III: {_counts_line(result)}",
        _equations_line(result),
        f"{len(result.disagreements)} places where the paper differs (causes in report.md):",
        *(f"  - {d.where}" for d in result.disagreements),
    ]
    return document, lines
