"""Benchmark: armcal at scale -- identify, design, simulate and reproduce, each against a baseline.

What it measures
----------------
Four figures, each against a baseline measured in the same run, and whether
each meets its target:

1. ``identify``, n = 12 links, m = 10^4 poses (a random arm with lengths in
   [50, 300] mm, a plan uniform in the joint limits, deviations of a few mm /
   about a degree, sigma = 0.1 mm noise, all from the seed):

   * wall time of ``armcal.identify`` against a plain NumPy Gauss-Newton
     written here (:func:`numpy_gauss_newton`: residual, Jacobian and
     ``numpy.linalg.lstsq`` step per iteration, from zero deviations, until the
     step is below 1e-12 of the reach), on the same data; both estimates must
     agree.  Target: within 3x.
   * peak memory of the ``armcal identify`` command on a file of that data,
     against ``armcal --version`` (the interpreter and the imports).  Target:
     < 300 MB.

2. ``armcal design --poses 100000`` on paper-4link (no limits), plan written
   with ``-o``: wall time and peak memory, against the same command with
   ``--poses 20``.  Targets: <= 10 s and < 500 MB.

3. ``monte_carlo()`` with the defaults of ``armcal simulate``: 10 000 trials of
   the paper's 20-pose orthogonal plan, paper-4link with the paper's
   deviations, sigma 0.1 mm, 1000 test poses uniform in the limits, closed
   form.  Baseline: the floor of any Monte Carlo of this plan (:func:`floor`):
   the noise draw, one batched linear solve for all trials (the normal
   equations of the model linear in the link phasors, every trial a
   right-hand side of one ``numpy.linalg.solve``) and the map from link
   phasors to (dl, dq).  Target: within 2x.  Also at 10^6 trials (the floor
   in chunks of 10^5 trials there, so that it fits in memory).

4. ``armcal reproduce -o DIR`` with its defaults (10 000 trials, 10 000 random
   plans): wall time, against the same command with ``--trials 2
   --random-plans 2`` (its fixed cost: imports, tables, figures, the
   poses-needed search).  Target: <= 20 s.

Timing: functions are timed as the minimum over several interleaved runs
(timer and machine noise only ever add time); commands run in a fresh child
of a fresh measuring process, whose peak resident memory comes from
``os.wait4`` (``ru_maxrss``): the least wall time of 3 runs (``design``) or 2
(``reproduce``), the largest peak.
The table goes to stdout and to ``benchmarks/RESULTS.md`` with the date and
the machine (``nproc``, load average at the start: the machines are shared).

Usage::

    .venv/bin/python benchmarks/bench_scale.py [--seed S] [--quick] [--no-write]

``--quick`` skips the 10^6-trial Monte Carlo and ``reproduce``.
"""

from __future__ import annotations

import argparse
import tempfile
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from baselines import numpy_gauss_newton
from measure import armcal_argv, at_end, machine_and_date, measure

from armcal import PlanarArm, forward_kinematics, identify, load_robot
from armcal.doe import orthogonal_plan, random_plan
from armcal.files import format_measurements_csv
from armcal.models.planar.closed_form import solve_closed_form
from armcal.simulate import monte_carlo
from armcal.synthesis import synthesize_measurements

RESULTS = Path(__file__).with_name("RESULTS.md")


# --------------------------------------------------------------------------- measuring


def best_times(
    functions: list[Callable[[], object]], *, repeats: int, budget: float = 5.0
) -> list[float]:
    """Least wall time of each function over ``repeats`` rounds, run in turn within a round.

    Interleaving gives contenders the same machine load; a round slower than
    ``budget`` seconds ends the measurement early.
    """
    best = [float("inf")] * len(functions)
    for _ in range(repeats):
        spent = 0.0
        for i, function in enumerate(functions):
            start = time.perf_counter()
            function()
            elapsed = time.perf_counter() - start
            best[i] = min(best[i], elapsed)
            spent += elapsed
        if spent > budget:
            break
    return best


def run_command(args: list[str], *, runs: int = 1) -> tuple[float, float]:
    """Least wall seconds and largest peak memory (MB) of ``python -m armcal ARGS`` over runs.

    Each run is a fresh child of a fresh measuring process (:mod:`measure`).
    """
    seconds, peak = float("inf"), 0.0
    for _ in range(runs):
        run_seconds, run_peak = measure(armcal_argv(args))
        seconds, peak = min(seconds, run_seconds), max(peak, run_peak)
    return seconds, peak


# --------------------------------------------------------------------------- baselines


def regressor(lengths: np.ndarray, q: np.ndarray) -> np.ndarray:
    """Real design matrix ``(2m, 2n)`` of the model linear in the link phasors (rows x, y)."""
    unit = np.exp(1j * np.cumsum(q, axis=1))
    cols = np.concatenate([unit, 1j * unit], axis=1)
    return np.stack([cols.real, cols.imag], axis=1).reshape(2 * q.shape[0], -1)


def floor(
    lengths: np.ndarray,
    q: np.ndarray,
    clean: np.ndarray,
    sigma: float,
    trials: int,
    rng: np.random.Generator,
    *,
    chunk: int | None = None,
) -> np.ndarray:
    """The least any Monte Carlo of this plan must do: noise, one solve, the map to (dl, dq).

    Per chunk of trials (all at once by default): draw the noise, solve the
    normal equations of the linear model for every trial in one
    ``numpy.linalg.solve`` call (trials as right-hand sides), and map the link
    phasors to ``dl = |z| - l``, ``dq_k = wrap(arg z_k - arg z_{k-1})``.
    Returns the estimates of the last chunk ``(size, 2n)`` (mm, rad).
    """
    n = lengths.size
    design_matrix = regressor(lengths, q)
    normal = design_matrix.T @ design_matrix
    flat = clean.reshape(-1)
    chunk = trials if chunk is None else chunk
    done = 0
    while done < trials:
        size = min(chunk, trials - done)
        y = rng.standard_normal((size, flat.size))
        y *= sigma
        y += flat
        w = np.linalg.solve(normal, design_matrix.T @ y.T).T  # one solve, `size` right-hand sides
        z = w[:, :n] + 1j * w[:, n:]
        theta = np.angle(z)
        dq = np.diff(theta, axis=1, prepend=0.0)
        dq = np.mod(dq + np.pi, 2 * np.pi) - np.pi
        estimates = np.concatenate([np.abs(z) - lengths, dq], axis=1)
        done += size
    return estimates


# --------------------------------------------------------------------------- the four figures


@dataclass
class Row:
    figure: str
    value: float
    unit: str
    baseline_name: str
    baseline: float
    target: str
    meets: bool
    ratio: bool = True  # whether value / baseline is meaningful


def bench_identify(seed: int, folder: Path) -> list[Row]:
    rng = np.random.default_rng(seed)
    arm = PlanarArm(rng.uniform(50.0, 300.0, 12), name="random-12link")
    q = random_plan(arm, 10_000, rng=rng)
    truth = arm.params_from_display(rng.uniform(-3.0, 3.0, 12), rng.uniform(-1.0, 1.0, 12))
    xy = synthesize_measurements(arm, q, truth, 0.1, rng=rng)

    calibration = identify(arm, q, xy, sigma=0.1)
    baseline = numpy_gauss_newton(arm.link_lengths, q, xy)
    difference = np.max(np.abs((calibration.params - baseline) * arm.display_scale))
    print(
        f"identify n=12 m=10^4: armcal ({calibration.method}) and numpy Gauss-Newton agree to "
        f"{difference:.1e} (mm, deg)"
    )
    if difference > 1e-6:
        raise RuntimeError("armcal identify and the numpy Gauss-Newton disagree")
    t_armcal, t_numpy = best_times(
        [
            lambda: identify(arm, q, xy, sigma=0.1),
            lambda: numpy_gauss_newton(arm.link_lengths, q, xy),
        ],
        repeats=5,
    )

    robot = folder / "robot12.toml"
    robot.write_text(
        'name = "random-12link"\n'
        f"link_lengths_mm = [{', '.join(repr(float(v)) for v in arm.link_lengths)}]\n"
    )
    measurements = folder / "meas12.csv"
    measurements.write_text(format_measurements_csv(q, xy))
    _, peak = run_command(
        [
            "identify",
            "--robot",
            str(robot),
            "--measurements",
            str(measurements),
            "--sigma",
            "0.1",
            "-o",
            str(folder / "calibration12.json"),
        ]
    )
    _, startup = run_command(["--version"])
    return [
        Row(
            "identify(), n=12, m=10^4: wall time",
            t_armcal,
            "s",
            "numpy lstsq Gauss-Newton",
            t_numpy,
            "<= 3x baseline",
            t_armcal <= 3 * t_numpy,
        ),
        Row(
            "armcal identify on that file: peak memory",
            peak,
            "MB",
            "armcal --version",
            startup,
            "< 300 MB",
            peak < 300,
        ),
    ]


def bench_design(folder: Path) -> list[Row]:
    big = folder / "plan100000.csv"
    seconds, peak = run_command(["design", "--poses", "100000", "-o", str(big)], runs=3)
    small_seconds, small_peak = run_command(
        ["design", "--poses", "20", "-o", str(folder / "plan20.csv")], runs=3
    )
    return [
        Row(
            "armcal design --poses 100000: wall time",
            seconds,
            "s",
            "design --poses 20",
            small_seconds,
            "<= 10 s",
            seconds <= 10,
        ),
        Row(
            "armcal design --poses 100000: peak memory",
            peak,
            "MB",
            "design --poses 20",
            small_peak,
            "< 500 MB",
            peak < 500,
        ),
    ]


def bench_simulate(seed: int, quick: bool) -> list[Row]:
    spec = load_robot("paper-4link")
    arm, truth = spec.arm, spec.default_truth
    assert truth is not None
    q = orthogonal_plan(arm, 20)
    test_q = random_plan(arm, 1000, rng=np.random.default_rng(seed))  # as armcal simulate
    clean = forward_kinematics(arm, q, truth)
    lengths = arm.link_lengths

    # The floor's estimates are the closed form's: same problem, another factorization.
    check = floor(lengths, q, clean, 0.1, 50, np.random.default_rng(seed))
    noise = np.random.default_rng(seed).standard_normal((50, *clean.shape))
    difference = np.max(np.abs(check - solve_closed_form(arm, q, clean + 0.1 * noise)))
    if difference > 1e-9:
        raise RuntimeError("the floor does not compute the closed-form estimates")

    rows = []
    sizes = [(10_000, 31)] if quick else [(10_000, 31), (1_000_000, 3)]
    for trials, repeats in sizes:
        chunk = None if trials <= 100_000 else 100_000
        t_mc, t_floor = best_times(
            [
                lambda t=trials: monte_carlo(arm, q, truth, 0.1, t, rng=seed, test_q=test_q),
                lambda t=trials, c=chunk: floor(
                    lengths, q, clean, 0.1, t, np.random.default_rng(seed), chunk=c
                ),
            ],
            repeats=repeats,
            budget=60,
        )
        rows.append(
            Row(
                f"monte_carlo(), {trials:,} trials, 1000 test poses",
                t_mc,
                "s",
                "floor: noise + one solve + map",
                t_floor,
                "<= 2x baseline",
                t_mc <= 2 * t_floor,
            )
        )
    return rows


def bench_reproduce(folder: Path) -> list[Row]:
    seconds, _ = run_command(["reproduce", "-o", str(folder / "reproduce")])
    fixed, _ = run_command(
        [
            "reproduce",
            "-o",
            str(folder / "reproduce-fixed"),
            "--trials",
            "2",
            "--random-plans",
            "2",
        ]
    )
    return [
        Row(
            "armcal reproduce -o DIR: wall time",
            seconds,
            "s",
            "--trials 2 --random-plans 2",
            fixed,
            "<= 20 s",
            seconds <= 20,
        )
    ]


# --------------------------------------------------------------------------- report


def table(rows: list[Row]) -> list[str]:
    header = ["figure", "armcal", "baseline", "baseline value", "ratio", "target", "meets"]
    cells = [
        [
            r.figure,
            f"{r.value:.4g} {r.unit}",
            r.baseline_name,
            f"{r.baseline:.4g} {r.unit}",
            f"{r.value / r.baseline:.2f}x" if r.ratio and r.baseline > 0 else "",
            r.target,
            "yes" if r.meets else "NO",
        ]
        for r in rows
    ]
    return [
        "| " + " | ".join(header) + " |",
        "|" + "---|" * len(header),
        *("| " + " | ".join(row) + " |" for row in cells),
    ]


def finish(
    rows: list[Row],
    machine: str,
    date: str,
    results: Path | None,
    heading: str,
    about: str,
    settings: str,
) -> None:
    """Print the rows' table with the machine's load at the end, and write it to ``results``
    (None: do not write) under ``# heading``, the paragraph ``about``, the date, the
    machine and the run's ``settings`` (``seed: 0``)."""
    lines = table(rows)
    machine = at_end(machine)
    print(f"\n{machine}")
    print("\n".join(lines))
    if results is None:
        return
    results.write_text(
        f"# {heading}\n\n{about}\n\n- date: {date}\n- machine: {machine}\n- {settings}\n\n"
        + "\n".join(lines)
        + "\n"
    )
    print(f"\nwrote {results}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seed", type=int, default=0, help="random seed (default 0)")
    parser.add_argument("--quick", action="store_true", help="skip 10^6 trials and reproduce")
    parser.add_argument("--no-write", action="store_true", help="do not write RESULTS.md")
    args = parser.parse_args()

    machine, date = machine_and_date()
    print(f"armcal scale benchmark, {date}\n{machine}\n")
    with tempfile.TemporaryDirectory(prefix="armcal-bench-") as tmp:
        folder = Path(tmp)
        # The in-process timings first: identify at m = 10^4 allocates gigabytes on
        # main, and a process that has done so times small arrays less steadily.
        simulate = bench_simulate(args.seed, args.quick)
        rows = bench_identify(args.seed, folder) + bench_design(folder) + simulate
        if not args.quick:
            rows += bench_reproduce(folder)
    finish(
        rows,
        machine,
        date,
        None if args.no_write else RESULTS,
        "Scale benchmark results",
        "Written by `benchmarks/bench_scale.py` (`make bench`); see its docstring for what "
        "each figure and baseline is. Times are the minimum over several runs; commands "
        "run in a fresh process, peak memory is its maximum resident set size.",
        f"seed: {args.seed}{' (quick: no 10^6 trials, no reproduce)' if args.quick else ''}",
    )


if __name__ == "__main__":
    main()
