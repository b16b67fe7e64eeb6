"""The paper's Sections V-VI recomputed: Tables I-III and Figures 1-2."""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

import numpy as np

from ..criteria import (
    information_matrix,
    inverse_information,
    optimality_sums,
    std_from_covariance,
)
from ..doe.plans import orthogonal_plan, random_plan
from ..paper import PAPER_DIGIT, PAPER_FIGURE1_POSES, PAPER_SIGMA_MM, PAPER_TABLE3, paper_arm
from ..progress import ProgressCallback
from ..simulate import PlanStudy, monte_carlo, random_plan_study
from .catalogue import Disagreement, _disagreements

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
    "table3": (
        "links",
        "poses",
        "parameter",
        "unit",
        "analytic_std",
        "simulated_std",
        "paper_value",
        "agrees",
        "note",
    ),
}


_LINKS = (2, 3, 4)


_POSES = (3, 20)


_FIGURE2_POSES = tuple(range(4, 31))


@dataclass(frozen=True, eq=False)
class Reproduction:
    """Everything ``armcal reproduce`` writes.

    Attributes
    ----------
    tables : dict of str to list of dict
        ``table1``, ``table2``, ``table3``: rows keyed by :data:`TABLE_COLUMNS`
        (``None`` for an empty cell).
    figure1 : PlanStudy
        Random 10-pose plans of the 4-link arm.
    figure2 : dict of str to ndarray
        Accuracy against the number of poses ``poses``: ``analytic_*``,
        ``simulated_*`` (orthogonal plans), ``random_mean_*`` and
        ``random_median_*`` for ``length`` (mm), ``angle`` (worst joint offset,
        deg) and ``position`` (RMS tip error after calibration, mm).
    disagreements : list of Disagreement
    trials : int
        Monte Carlo trials per configuration.
    random_plans : int
        Random plans per study.
    seed : int
    sigma : float
    seconds : float
    """

    tables: dict[str, list[dict]]
    figure1: PlanStudy
    figure2: dict[str, np.ndarray]
    disagreements: list[Disagreement]
    trials: int
    random_plans: int
    seed: int
    sigma: float
    seconds: float


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


def _table3(
    sigma: float, trials: int, rng: np.random.Generator, progress: ProgressCallback
) -> tuple[list[dict], dict[tuple[int, int], np.ndarray]]:
    rows: list[dict] = []
    plans: dict[tuple[int, int], np.ndarray] = {}
    for step, (n, m) in enumerate((n, m) for n in _LINKS for m in _POSES):
        arm, truth = paper_arm(n)
        paper = PAPER_TABLE3[(n, m)]
        if 2 * m < arm.n_params:
            note = (
                f"not identifiable: {m} poses give {2 * m} equations for {arm.n_params} "
                f"parameters, so no plan can separate them; the paper's value is the "
                f"formula sigma/sqrt(m) used beyond its validity"
            )
            for kind, unit in (("dl", "mm"), ("dq", "deg"), ("dtheta", "deg")):
                for k in range(n):
                    printed = paper["dq" if kind == "dtheta" else kind][k]
                    rows.append(_row(n, m, f"{kind}{k + 1}", unit, None, None, printed, note))
            continue
        q = orthogonal_plan(arm, m)
        plans[(n, m)] = q
        mc = monte_carlo(arm, q, truth, sigma, trials, rng=rng)
        inverse = inverse_information(arm, q)
        assert inverse is not None  # an orthogonal plan with 2m >= p identifies everything
        predicted = sigma**2 * inverse
        analytic = std_from_covariance(arm, predicted)
        square = 2 * m == arm.n_params
        for k in range(n):
            note = "exactly determined (2m = p): zero residual, sigma must be known" * square
            rows.append(
                _row(n, m, f"dl{k + 1}", "mm", analytic[k], mc.std[k], paper["dl"][k], note)
            )
        for k in range(n):
            note = (
                "dq1 = dtheta1"
                if k == 0
                else f"joint offset dq{k + 1} = dtheta{k + 1} - dtheta{k}: the paper's "
                f"'dq' column is the cumulative angle, compare the dtheta{k + 1} row"
            )
            rows.append(
                _row(
                    n, m, f"dq{k + 1}", "deg", analytic[n + k], mc.std[n + k], paper["dq"][k], note
                )
            )
        theta_analytic = np.degrees(_cumulative(predicted, n))
        theta_simulated = np.degrees(_cumulative(mc.covariance, n))
        for k in range(n):
            rows.append(
                _row(
                    n,
                    m,
                    f"dtheta{k + 1}",
                    "deg",
                    theta_analytic[k],
                    theta_simulated[k],
                    paper["dq"][k],
                    "paper's 'dq': link angle theta_k = q_1 + ... + q_k (eq. 1)",
                )
            )
        progress(step + 1, len(_LINKS) * len(_POSES))
    return rows, plans


def _row(n, m, name, unit, analytic, simulated, printed, note) -> dict:
    agrees = analytic is not None and abs(analytic - printed) <= PAPER_DIGIT * (1 + 1e-9)
    return {
        "links": n,
        "poses": m,
        "parameter": name,
        "unit": unit,
        "analytic_std": None if analytic is None else float(analytic),
        "simulated_std": None if simulated is None else float(simulated),
        "paper_value": printed,
        "agrees": "yes" if agrees else "no",
        "note": note,
    }


def _figure2(
    sigma: float,
    trials: int,
    random_plans: int,
    rng: np.random.Generator,
    progress: ProgressCallback,
) -> dict[str, np.ndarray]:
    arm, truth = paper_arm(4)
    n, lengths = arm.n_joints, arm.link_lengths
    test_q = random_plan(arm, 1000, rng)
    worst = max(1 / lengths[0], *np.hypot(1 / lengths[1:], 1 / lengths[:-1]))
    curves: dict[str, list[float]] = {}

    def put(key: str, value: float) -> None:
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
    """Recompute the paper's Section V-VI results.

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
    total = configurations + 1 + len(_FIGURE2_POSES)

    def stage(offset: int) -> ProgressCallback:
        def report(done: int, _: int) -> None:
            if progress is not None:
                progress(offset + done, total)

        return report

    table3, plans = _table3(sigma, trials, rng, stage(0))
    arm4, _ = paper_arm(4)
    # Three poses cannot calibrate the 4-link arm; Tables I-II also show its smallest plan.
    plans = dict(sorted({**plans, (4, 4): orthogonal_plan(arm4, 4)}.items()))
    study = random_plan_study(arm4, PAPER_FIGURE1_POSES, random_plans, sigma=sigma, rng=rng)
    stage(configurations)(1, 1)
    figure2 = _figure2(sigma, trials, random_plans, rng, stage(configurations + 1))
    return Reproduction(
        tables={
            "table1": _table1(plans),
            "table2": _table2(plans, sigma),
            "table3": table3,
        },
        figure1=study,
        figure2=figure2,
        disagreements=_disagreements(table3, sigma, rng),
        trials=int(trials),
        random_plans=int(random_plans),
        seed=int(seed),
        sigma=float(sigma),
        seconds=time.perf_counter() - start,
    )
