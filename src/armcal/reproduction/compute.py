"""The paper's Sections V-VI recomputed: Tables I-III, Figures 1-2, and where the paper differs."""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

import numpy as np

from ..criteria import CRITERIA, predicted_std
from ..doe.plans import random_plan
from ..errors import ArmcalError
from ..models import PlanarArm, identifiability
from ..models.information import display_std
from ..models.planar.criteria import (
    information_matrix,
    inverse_information,
    optimality_sums,
    scaled_information,
)
from ..models.planar.plans import orthogonal_plan
from ..paper import (
    PAPER_100_POSE_ANGLES_DEG,
    PAPER_DIGIT,
    PAPER_FIGURE1_POSES,
    PAPER_GOAL_LENGTH_MM,
    PAPER_GOAL_POSES,
    PAPER_RANGE_LENGTH_MM,
    PAPER_RANGE_POSES,
    PAPER_SIGMA_MM,
    PAPER_TABLE3,
    paper_arm,
)
from ..progress import ProgressCallback
from ..simulate import monte_carlo
from .catalogue import ROWS, Disagreement, EquationCheck, disagreement, fill
from .equations import RANK_PLANS, SimulationEvidence, check_equations, max_random_rank
from .study import PlanStudy, random_plan_study

__all__ = [
    "TABLE_COLUMNS",
    "Reproduction",
    "reproduce",
]


TABLE_COLUMNS = {
    "table1": ("links", "poses", "condition", "paper_notation", "value", "satisfied"),
    "table2": (
        "links",
        "poses",
        "parameter",
        "unit",
        "information_diagonal",
        "paper_formula",
        "formula_value",
        "largest_off_diagonal",
        "analytic_std",
        "formula_std",
        "agrees",
    ),
    # One row per value printed in Table III.
    "table3": (
        "links",
        "poses",
        "parameter",
        "compared_with",
        "unit",
        "analytic_std",
        "simulated_std",
        "paper_value",
        "computable",
        "agrees",
        "joint_offset_std",
        "note",
    ),
}


_LINKS = (2, 3, 4)


_POSES = tuple(sorted({m for _, m in PAPER_TABLE3}))


_FIGURE2_POSES = tuple(range(4, 31))


#: Random plans behind the A-criterion statement of Section V.
_A_CRITERION_PLANS = 2000


@dataclass(frozen=True, eq=False)
class Reproduction:
    """Everything ``armcal reproduce`` writes.

    Attributes
    ----------
    tables : dict of str to list of dict
        ``table1``, ``table2``, ``table3``: rows keyed by :data:`TABLE_COLUMNS`
        (``None`` for an empty cell).  ``table3`` has one row per value printed
        in the paper's Table III.
    figure1 : PlanStudy
        Random 10-pose plans of the 4-link arm.
    figure2 : dict of str to ndarray
        Accuracy against the number of poses ``poses``: ``analytic_*``,
        ``simulated_*`` (orthogonal plans), ``random_mean_*`` and
        ``random_median_*`` for ``length`` (mm), ``angle`` (worst joint offset,
        deg) and ``position`` (RMS tip error after calibration, mm).
    equations : list of EquationCheck
        Every printed equation of Sections II-V, computed, with its verdict.
    disagreements : list of Disagreement
        Tables, sentences and equations where the paper differs, with causes.
    trials : int
        Monte Carlo trials per configuration.
    random_plans : int
        Random plans per study.
    seed : int
    sigma_mm : float
    seconds : float
    """

    tables: dict[str, list[dict]]
    figure1: PlanStudy
    figure2: dict[str, np.ndarray]
    equations: list[EquationCheck]
    disagreements: list[Disagreement]
    trials: int
    random_plans: int
    seed: int
    sigma_mm: float
    seconds: float

    @property
    def worst_std_disagreement(self) -> float:
        """``max |simulated std / analytic std - 1|`` over Table III's identifiable rows."""
        rows = self.tables["table3"]
        judged = [
            r for r in rows if r["analytic_std"] is not None and r["simulated_std"] is not None
        ]
        return max(abs(r["simulated_std"] / r["analytic_std"] - 1) for r in judged)

    @property
    def std_sampling_error(self) -> float:
        """Relative std of a sample std from :attr:`trials` normal draws, ``1 / sqrt(2 N)``."""
        return 1.0 / math.sqrt(2 * self.trials)

    def printed_values(self) -> dict[str, int]:
        """Table III's printed values, each counted once.

        Returns
        -------
        dict of str to int
            ``printed``: values printed; ``agree``: within one unit of the last
            printed digit of the computed value; ``differ``: computable but not
            agreeing; ``not_computable``: in configurations no plan identifies.
        """
        rows = self.tables["table3"]
        computable = [r for r in rows if r["computable"] == "yes"]
        agree = sum(r["agrees"] == "yes" for r in computable)
        return {
            "printed": len(rows),
            "agree": agree,
            "differ": len(computable) - agree,
            "not_computable": len(rows) - len(computable),
        }


def _cumulative(cov: np.ndarray, n: int) -> np.ndarray:
    """Std ``(n,)`` of the paper's link angles ``dtheta_k = dq_1 + ... + dq_k`` (rad)."""
    lower = np.tril(np.ones((n, n)))
    block = cov[n : 2 * n, n : 2 * n]
    return np.sqrt(np.diag(lower @ block @ lower.T))


def _notation(key: str) -> str:
    """Table I notation of an optimality sum: ``cos(q2+q3)`` -> ``sum c23``."""
    kind, joints = key[:3], key[4:-1].split("+")
    first, last = joints[0][1:], joints[-1][1:]
    letter = "c" if kind == "cos" else "s"
    return f"sum {letter}{first if first == last else first + last}"


def _table1(plans: dict[tuple[int, int], np.ndarray]) -> list[dict]:
    rows = []
    for (n, m), q in plans.items():
        arm, _ = paper_arm(n)
        for key, value in optimality_sums(arm, q).items():
            rows.append(
                {
                    "links": n,
                    "poses": m,
                    "condition": f"sum {key} = 0",
                    "paper_notation": _notation(key),
                    "value": value,
                    "satisfied": "yes" if abs(value) <= 1e-9 * m else "no",
                }
            )
    return rows


def _table2(plans: dict[tuple[int, int], np.ndarray], sigma: float) -> list[dict]:
    rows = []
    for (n, m), q in plans.items():
        arm, _ = paper_arm(n)
        info = information_matrix(arm, q)  # paper order (dtheta, dl)
        off = np.abs(info - np.diag(np.diag(info))).max()
        cov = sigma**2 * np.linalg.inv(info)
        for k in range(n):
            length = float(arm.link_lengths[k])
            for name, index, formula, value, std, unit in (
                (
                    f"dtheta{k + 1}",
                    k,
                    f"m*l{k + 1}^2",
                    m * length**2,
                    math.degrees(sigma / (math.sqrt(m) * length)),
                    "deg",
                ),
                (f"dl{k + 1}", n + k, "m", float(m), sigma / math.sqrt(m), "mm"),
            ):
                analytic = math.sqrt(cov[index, index]) * (180 / math.pi if unit == "deg" else 1)
                rows.append(
                    {
                        "links": n,
                        "poses": m,
                        "parameter": name,
                        "unit": unit,
                        "information_diagonal": float(info[index, index]),
                        "paper_formula": formula,
                        "formula_value": value,
                        "largest_off_diagonal": float(off),
                        "analytic_std": analytic,
                        "formula_std": std,
                        "agrees": "yes"
                        if math.isclose(info[index, index], value, rel_tol=1e-12)
                        and math.isclose(analytic, std, rel_tol=1e-9)
                        else "no",
                    }
                )
    return rows


def _agrees(computed: float | None, printed: float) -> bool:
    """Whether ``printed`` is within one unit of its last digit of ``computed``."""
    return computed is not None and abs(computed - printed) <= PAPER_DIGIT * (1 + 1e-9)


def _configuration_rows(
    n: int,
    m: int,
    notes: list[str],
    analytic: np.ndarray | None = None,
    simulated: np.ndarray | None = None,
    joint_offsets: np.ndarray | None = None,
) -> list[dict]:
    """The ``2n`` rows of one Table III configuration, one per printed value.

    ``analytic`` and ``simulated`` hold the std of ``dl_1..dl_n`` (mm) then of
    ``dtheta_1..dtheta_n`` (deg), the quantities the printed dL and 'dq' are
    compared with; ``joint_offsets`` the std of ``dq_1..dq_n`` (deg).  None
    when the configuration cannot be computed.
    """
    printed = PAPER_TABLE3[(n, m)]
    rows = []
    for i in range(2 * n):
        k, is_length = i % n, i < n
        computed = None if analytic is None else float(analytic[i])
        value = printed["dl" if is_length else "dq"][k]
        rows.append(
            {
                "links": n,
                "poses": m,
                "parameter": f"{'dL' if is_length else 'dq'}{k + 1}",
                "compared_with": f"{'dl' if is_length else 'dtheta'}{k + 1}",
                "unit": "mm" if is_length else "deg",
                "analytic_std": computed,
                "simulated_std": None if simulated is None else float(simulated[i]),
                "paper_value": value,
                "computable": "no" if computed is None else "yes",
                "agrees": "yes" if _agrees(computed, value) else "no",
                "joint_offset_std": None
                if joint_offsets is None or is_length
                else float(joint_offsets[k]),
                "note": notes[i],
            }
        )
    return rows


def _identifying_plan(arm: PlanarArm, m: int) -> np.ndarray | None:
    """The orthogonal ``m``-pose plan if it identifies every parameter, else None."""
    try:
        q = orthogonal_plan(arm, m)
    except ArmcalError:
        return None
    return q if identifiability(arm, q).identifiable else None


def _table3(
    sigma: float, trials: int, rng: np.random.Generator, progress: ProgressCallback
) -> tuple[list[dict], dict[tuple[int, int], np.ndarray], dict, SimulationEvidence]:
    """Rows of Table III, the plans used, the ranks of the others and the Monte Carlo summary."""
    rows: list[dict] = []
    plans: dict[tuple[int, int], np.ndarray] = {}
    ranks: dict[tuple[int, int], int] = {}
    parameters, worst_bias, worst_std = 0, 0.0, 0.0
    for step, (n, m) in enumerate((n, m) for n in _LINKS for m in _POSES):
        arm, truth = paper_arm(n)
        q = _identifying_plan(arm, m)
        if q is None:
            rank = max_random_rank(arm, m, rng)
            if rank == arm.n_params:  # pragma: no cover - orthogonal plans exist for m >= n
                raise RuntimeError(f"{m} random poses identify {arm.name}: use them")
            ranks[(n, m)] = rank
            note = fill(
                ROWS["note_not_computable"],
                {"poses": m, "equations": 2 * m, "params": arm.n_params, "rank": rank},
            )
            rows += _configuration_rows(n, m, [note] * (2 * n))
            progress(step + 1, len(_LINKS) * len(_POSES))
            continue
        plans[(n, m)] = q
        mc = monte_carlo(arm, q, truth, sigma, trials, rng=rng)
        parameters += arm.n_params
        worst_bias = max(worst_bias, float(np.max(np.abs(mc.bias) / mc.bias_limit)))
        worst_std = max(worst_std, float(np.max(np.abs(mc.std / mc.predicted_std - 1))))
        inverse = inverse_information(arm, q)
        assert inverse is not None  # _identifying_plan checked the rank
        predicted = sigma**2 * inverse
        analytic = display_std(arm, predicted)
        exact = ROWS["note_exact"] if 2 * m == arm.n_params else ""
        notes = [exact] * n + [
            fill(ROWS["note_dq1" if k == 0 else "note_dq"], {"k": k + 1}) for k in range(n)
        ]
        rows += _configuration_rows(
            n,
            m,
            notes,
            analytic=np.concatenate([analytic[:n], np.degrees(_cumulative(predicted, n))]),
            simulated=np.concatenate([mc.std[:n], np.degrees(_cumulative(mc.covariance, n))]),
            joint_offsets=analytic[n : 2 * n],
        )
        progress(step + 1, len(_LINKS) * len(_POSES))
    evidence = SimulationEvidence(
        trials=int(trials),
        parameters=parameters,
        worst_bias_ratio=worst_bias,
        worst_std_deviation=worst_std,
    )
    return rows, plans, ranks, evidence


def _table3_wrong_values(table3: list[dict]) -> list[Disagreement]:
    """Printed values of Table III that differ, by configuration and unit: each group
    either another column's values repeated or simply different."""
    found: list[Disagreement] = []
    value = {
        (r["links"], r["poses"], r["parameter"]): r["analytic_std"]
        for r in table3
        if r["computable"] == "yes"
    }
    groups: dict[tuple[int, int, str], list[dict]] = {}
    for r in table3:
        if r["computable"] == "yes" and r["agrees"] == "no":
            groups.setdefault((r["links"], r["poses"], r["unit"]), []).append(r)
    for (n, m, unit), wrong in groups.items():
        # Is the printed value another column's value, repeated?
        other = next(
            (
                m2
                for m2 in _POSES
                if m2 != m
                and all(
                    _agrees(value.get((n, m2, r["parameter"])), r["paper_value"]) for r in wrong
                )
            ),
            None,
        )
        fields = {
            "links": n,
            "poses": m,
            "unit": unit,
            "names": ", ".join(r["parameter"] for r in wrong),
            "printed": [r["paper_value"] for r in wrong],
            "analytic": [r["analytic_std"] for r in wrong],
            "simulated": [r["simulated_std"] for r in wrong],
        }
        if other is None:
            found.append(disagreement("table3_differs", **fields))
        else:
            others = [value[(n, other, r["parameter"])] for r in wrong]
            found.append(
                disagreement("table3_repeated", other_poses=other, other=others, **fields)
            )
    return found


def _table3_not_computable(
    ranks: dict[tuple[int, int], int], sigma: float, rng: np.random.Generator
) -> list[Disagreement]:
    """The configurations the paper prints that no plan can calibrate: whether its values
    are the formulas of an orthogonal plan, and how many poses would do."""
    found: list[Disagreement] = []
    for (n, m), rank in sorted(ranks.items()):
        arm, _ = paper_arm(n)
        printed = PAPER_TABLE3[(n, m)]
        formula_dl = sigma / math.sqrt(m)
        formula_dq = np.degrees(sigma / (math.sqrt(m) * arm.link_lengths)).tolist()
        explained = all(_agrees(formula_dl, v) for v in printed["dl"]) and all(
            _agrees(f, v) for f, v in zip(formula_dq, printed["dq"], strict=True)
        )
        min_poses = m + 1
        while max_random_rank(arm, min_poses, rng) < arm.n_params:
            min_poses += 1
        found.append(
            disagreement(
                "table3_not_computable" if explained else "table3_not_computable_unexplained",
                links=n,
                poses=m,
                params=arm.n_params,
                equations=2 * m,
                plans=RANK_PLANS,
                rank=rank,
                printed_dl=list(printed["dl"]),
                printed_dq=list(printed["dq"]),
                formula_dl=formula_dl,
                formula_dq=formula_dq,
                min_poses=min_poses,
            )
        )
    return found


def _table3_dq_label(table3: list[dict]) -> list[Disagreement]:
    """Table III's 'dq_k' columns when they agree with the joint offsets' std rather than
    the cumulative angles' the paper's text names (one example kept)."""
    angles = [r for r in table3 if r["compared_with"].startswith("dtheta")]
    computable = [r for r in angles if r["computable"] == "yes"]
    as_joint = [r for r in computable if _agrees(r["joint_offset_std"], r["paper_value"])]
    mislabelled = [r for r in computable if r not in as_joint]
    if not mislabelled:
        return []
    example = max(mislabelled, key=lambda r: (r["links"], r["poses"], r["parameter"]))
    return [
        disagreement(
            "table3_dq_label",
            links=example["links"],
            poses=example["poses"],
            k=example["parameter"][2:],
            printed=example["paper_value"],
            total=len(computable),
            theta_agree=sum(r["agrees"] == "yes" for r in computable),
            dq_agree=len(as_joint),
            joint=example["joint_offset_std"],
            theta=example["analytic_std"],
        )
    ]


def _table3_disagreements(
    table3: list[dict], ranks: dict[tuple[int, int], int], sigma: float, rng: np.random.Generator
) -> list[Disagreement]:
    """Where Table III differs: wrong values, configurations no plan can calibrate, and
    the label of its joint-offset columns."""
    return [
        *_table3_wrong_values(table3),
        *_table3_not_computable(ranks, sigma, rng),
        *_table3_dq_label(table3),
    ]


def _length_std(arm: PlanarArm, m: int, sigma: float) -> float:
    """Largest length std (mm) of the orthogonal ``m``-pose plan."""
    return float(predicted_std(arm, orthogonal_plan(arm, m), sigma)[: arm.n_joints].max())


def _poses_for_length_std(arm: PlanarArm, goal: float, sigma: float) -> int:
    """Smallest ``m`` whose orthogonal plan reaches a length std ``goal``, by bisection.

    The std of an orthogonal plan decreases with ``m``, so doubling then
    halving finds the smallest ``m`` in O(log m) evaluations of O(m) each.
    """

    def reaches(m: int) -> bool:
        return _length_std(arm, m, sigma) <= goal * (1 + 1e-9)

    low = arm.n_joints  # fewest poses of an orthogonal plan
    if reaches(low):
        return low
    high = 2 * low
    while not reaches(high):
        low, high = high, 2 * high
    while high - low > 1:
        middle = (low + high) // 2
        low, high = (low, middle) if reaches(middle) else (middle, high)
    return high


def _text_disagreements(
    table1: list[dict], sigma: float, rng: np.random.Generator
) -> list[Disagreement]:
    """Table I's notation and the sentences of Sections V-VI."""
    found: list[Disagreement] = []
    three = [r for r in table1 if r["links"] == 3]
    found.append(
        disagreement(
            "table1_notation",
            s23=max(abs(r["value"]) for r in three if r["paper_notation"] == "sum s23"),
            s3=max(abs(r["value"]) for r in three if r["paper_notation"] == "sum s3"),
        )
    )
    arm4, _ = paper_arm(4)
    n = arm4.n_joints
    plans = random_plan(arm4, _A_CRITERION_PLANS * PAPER_FIGURE1_POSES, rng=rng).reshape(
        _A_CRITERION_PLANS, PAPER_FIGURE1_POSES, n
    )
    trace = np.trace(information_matrix(arm4, plans), axis1=-2, axis2=-1)
    a_eff = CRITERIA["A"].efficiency(scaled_information(arm4, plans))
    found.append(
        disagreement(
            "a_criterion",
            plans=_A_CRITERION_PLANS,
            poses=PAPER_FIGURE1_POSES,
            trace_min=float(trace.min()),
            trace_max=float(trace.max()),
            a_min=float(a_eff.min()),
            a_max=float(a_eff.max()),
        )
    )
    m_from, m_to = PAPER_RANGE_POSES
    printed_from, printed_to = PAPER_RANGE_LENGTH_MM
    length_from, length_to = _length_std(arm4, m_from, sigma), _length_std(arm4, m_to, sigma)
    theta1_to = float(predicted_std(arm4, orthogonal_plan(arm4, m_to), sigma)[n])  # dq1 = dtheta1
    if not (_agrees(length_from, printed_from) and _agrees(length_to, printed_to)):
        explained = _agrees(length_to, printed_from) and _agrees(theta1_to, printed_to)
        found.append(
            disagreement(
                "section6_range" if explained else "section6_range_unexplained",
                printed_from=printed_from,
                printed_to=printed_to,
                m_from=m_from,
                m_to=m_to,
                length_from=length_from,
                length_to=length_to,
                theta1_to=theta1_to,
            )
        )
    std_at = _length_std(arm4, PAPER_GOAL_POSES, sigma)
    if not std_at <= PAPER_GOAL_LENGTH_MM * (1 + 1e-9):
        needed = _poses_for_length_std(arm4, PAPER_GOAL_LENGTH_MM, sigma)
        inverse = inverse_information(arm4, orthogonal_plan(arm4, PAPER_GOAL_POSES))
        assert inverse is not None  # orthogonal plans identify every parameter
        theta = np.degrees(_cumulative(sigma**2 * inverse, n))
        angles_agree = all(
            _agrees(t, p) for t, p in zip(theta, PAPER_100_POSE_ANGLES_DEG, strict=True)
        )
        found.append(
            disagreement(
                "section6_goal",
                goal=PAPER_GOAL_LENGTH_MM,
                poses=PAPER_GOAL_POSES,
                angles=list(PAPER_100_POSE_ANGLES_DEG),
                std_at=std_at,
                needed=needed,
                before=needed - 1,
                std_before=_length_std(arm4, needed - 1, sigma),
                theta=theta.tolist(),
                angles_agree=ROWS["angles_agree" if angles_agree else "angles_differ"],
                factor=std_at / PAPER_GOAL_LENGTH_MM,
                factor_poses=needed / PAPER_GOAL_POSES,
            )
        )
    return found


def _figure2(
    sigma: float,
    trials: int,
    random_plans: int,
    rng: np.random.Generator,
    progress: ProgressCallback,
) -> dict[str, np.ndarray]:
    arm, truth = paper_arm(4)
    n, lengths = arm.n_joints, arm.link_lengths
    test_q = random_plan(arm, 1000, rng=rng)
    worst = max(1 / lengths[0], *np.hypot(1 / lengths[1:], 1 / lengths[:-1]))
    curves: dict[str, list[float]] = {}

    def put(key: str, value: float | np.floating) -> None:
        curves.setdefault(key, []).append(float(value))

    for i, m in enumerate(_FIGURE2_POSES):
        root = math.sqrt(m)
        put("analytic_length", sigma / root)
        put("analytic_angle", math.degrees(sigma * worst / root))
        put("analytic_position", sigma * math.sqrt(2 * n / m))
        mc = monte_carlo(
            arm, orthogonal_plan(arm, m), truth, sigma, trials, rng=rng, test_q=test_q
        )
        put("simulated_length", np.sqrt(np.mean(mc.std[:n] ** 2)))
        put("simulated_angle", mc.std[n : 2 * n].max())
        put("simulated_position", mc.position.rms_mm if mc.position else math.nan)
        study = random_plan_study(arm, m, random_plans, sigma=sigma, rng=rng, test_q=test_q)
        length = np.sqrt(np.mean(study.std[:, :n] ** 2, axis=1))
        angle = study.std[:, n : 2 * n].max(axis=1)
        for key, values in (
            ("length", length),
            ("angle", angle),
            ("position", study.position_rms),
        ):
            put(f"random_mean_{key}", np.mean(values))
            put(f"random_median_{key}", np.median(values))
        progress(i + 1, len(_FIGURE2_POSES))
    out = {key: np.array(values) for key, values in curves.items()}
    out["poses"] = np.array(_FIGURE2_POSES)
    return out


def reproduce(
    *,
    trials: int = 10_000,
    random_plans: int = 10_000,
    seed: int = 0,
    sigma: float = PAPER_SIGMA_MM,
    progress: ProgressCallback | None = None,
) -> Reproduction:
    """Recompute the paper's Section V-VI results and check its equations.

    Parameters
    ----------
    trials : int
        Monte Carlo trials per configuration (the paper: 10 000).
    random_plans : int
        Random plans for Figure 1 and for each point of Figure 2's random curve.
    seed : int
        Seeds everything; the same seed gives the same numbers.
    sigma : float
        Measurement noise (mm); the paper's 0.1 by default.
    progress : callable, optional
        ``progress(done, total)`` as the work advances.

    Returns
    -------
    Reproduction
    """
    start = time.perf_counter()
    rng = np.random.default_rng(seed)
    configurations = len(_LINKS) * len(_POSES)
    total = configurations + 2 + len(_FIGURE2_POSES)

    def stage(offset: int) -> ProgressCallback:
        def report(done: int, _: int) -> None:
            if progress is not None:
                progress(offset + done, total)

        return report

    table3, plans, ranks, evidence = _table3(sigma, trials, rng, stage(0))
    arm4, _ = paper_arm(4)
    # Three poses cannot calibrate the 4-link arm; Tables I-II also show its smallest plan.
    shown = dict(sorted({**plans, (4, 4): orthogonal_plan(arm4, 4)}.items()))
    table1 = _table1(shown)
    study = random_plan_study(arm4, PAPER_FIGURE1_POSES, random_plans, sigma=sigma, rng=rng)
    stage(configurations)(1, 1)
    figure2 = _figure2(sigma, trials, random_plans, rng, stage(configurations + 1))
    equations = check_equations(
        sigma=sigma,
        plans=plans,
        configurations=sorted(PAPER_TABLE3),
        simulation=evidence,
        rng=rng,
    )
    stage(configurations + 1 + len(_FIGURE2_POSES))(1, 1)
    disagreements = [
        *_table3_disagreements(table3, ranks, sigma, rng),
        *_text_disagreements(table1, sigma, rng),
        *(d for d in (check.disagreement() for check in equations) if d is not None),
    ]
    return Reproduction(
        tables={"table1": table1, "table2": _table2(shown, sigma), "table3": table3},
        figure1=study,
        figure2=figure2,
        equations=equations,
        disagreements=disagreements,
        trials=int(trials),
        random_plans=int(random_plans),
        seed=int(seed),
        sigma_mm=float(sigma),
        seconds=time.perf_counter() - start,
    )
