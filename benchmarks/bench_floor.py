"""Benchmark: every armcal command that takes poses, at 10^5 poses, against a plain numpy floor.

What it measures
----------------
Each command runs as a real ``armcal`` process on files, and against it the
floor of the same work (:mod:`floors`): the same input files read with
``numpy.loadtxt``/``json.load``, the same linear algebra in plain numpy, the
same output written with ``numpy.savetxt``/``json.dump``, also as a fresh
process (so both pay an interpreter's start-up: armcal's imports are part of
its cost, numpy's of the floor's).  Per command: the least wall time of each
over interleaved runs (timer and machine noise only ever add time), their
ratio, and the largest peak resident memory of each (``os.wait4``,
:mod:`measure`).  The target is a ratio within 2x; where a command is above it,
``EXTRA`` below names the work it does that its floor does not, and the
results say it.

The data, all from the seed:

* a 4-link arm with the paper's lengths (260, 180, 120, 100 mm), no joint
  limits, sigma 0.1 mm, deviations of a few tenths of a mm / degree;
  plans and programs of 10^5 poses uniform within +-170 deg;
* the tracker arm of docs/tracker.md (3 links, a belt-driven wrist, 3
  reflectors, base offset), 10^5 poses measured at each reflector (3 x 10^5
  rows), the points turned into a tracker's frame 2.3 m away.

Commands and floors:

``identify`` (2-D, 1 target)
    floor: ``lstsq`` of the model linear in the link vectors, the covariance
    ``sigma^2 (H^T H)^-1`` mapped to (dl, dq), the residuals; a JSON with the
    parameters, covariance, correlation and every row's residual and
    standardized residual.  Both estimates must agree.
``identify`` (3-D, 3 targets)
    floor: the plane (one normal from the 3x3 scatter of the points centred per
    target), both sides fitted in the plane, the better kept, then as above.
``validate``
    floor: nominal and calibrated positions of held-out measurements, the
    predicted error ``sqrt(tr(J C J^T) + 2 sigma^2)``, RMS/max/95 %.
``compensate``
    floor: batched Newton with minimum-norm steps (tip and tool direction,
    redundancy pulled back to the command), the limits, ``savetxt``.
``evaluate``
    floor: the information matrix, D/A/E efficiency, predicted std, and the
    predicted error at 1000 test poses.
``simulate`` (10^4 and 10^5 poses, :data:`TRIALS` trials)
    floor: noise, one QR solve per chunk of trials (trials as right-hand
    sides), the map to (dl, dq), mean and std, and the tip RMS at 1000 test
    poses; its growth from 10^4 to 10^5 poses against the floor's (linear in
    the plan's size: 10 times the poses, at most 10 times the time).
``synthesize``
    floor: forward kinematics of the truth, noise, ``savetxt``.
``design --poses 100000`` (and with ``--order none``)
    floor: the orthogonal plan design finds for this arm (built directly), its
    quality as for ``evaluate``, ``savetxt``.
``export``
    floor: ``json.load`` of the calibration (its 10^5 residual rows) and the
    robot TOML.

Usage::

    .venv/bin/python benchmarks/bench_floor.py [--seed S] [--poses M] [--repeats R] [--no-write]
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from measure import armcal_argv, at_end, machine_and_date, measure

RESULTS = Path(__file__).with_name("RESULTS_FLOOR.md")
FLOORS = str(Path(__file__).with_name("floors.py"))

#: Simulated trials per Monte Carlo (the default 10 000 would take minutes at 10^5 poses
#: for both contenders alike: the work per trial is the same linear solve).
TRIALS = 1000

#: What a command does that its floor does not (said in the results where it is above 2x).
EXTRA = {
    "identify 2-D": "the studentized outlier test (every row's hat block, from its Jacobian), "
    "the goodness-of-fit test, the rank analysis of the scaled Jacobian (SVD), the checks "
    "of every row (limits, reach) and of a unit mistake",
    "identify 3-D, 3 targets": "as identify 2-D, and the plane's planarity test",
    "validate": "the checks of every row (limits, reach), the per-row noise model",
    "compensate": "rank-safe Newton steps (an SVD pseudo-inverse per pose and step, up to 50 "
    "steps for the poses not yet converged), the reason for every pose left uncorrected, "
    "and the predicted error left after compensation, position and orientation",
    "evaluate": "the observability indices O1-O4, the paper's D* (det C', |det S'|) and "
    "Table I sums, the rank analysis that names unseen combinations",
    "simulate": "the quantiles of the tip error (a subsample of trial and test pose pairs), "
    "the bias test, the noise model (encoder noise, per-axis sigma)",
    "synthesize": "the noise model, positions written as the shortest text that reads back "
    "(repr, about 0.5 us a value) instead of %.17g",
    "design": "the ordering of the poses for joint travel (a nearest-neighbour tour over a "
    "k-d tree and a local search, with scipy.spatial's import) and the certificate of the "
    "plan's efficiency (a Kiefer-Wolfowitz bound); 'design --order none' is without the "
    "ordering",
    "export": "the validation of the whole calibration file",
}


def extra(name: str) -> str:
    """:data:`EXTRA` of a case (the simulate cases share one)."""
    return EXTRA["simulate" if name.startswith("simulate") else name.split(" --")[0]]


ARM4 = {
    "lengths": [260.0, 180.0, 120.0, 100.0],
    "limits": [[-180.0, 180.0]] * 4,
    "sigma": 0.1,
    "truth_dl": [0.8, -0.5, 0.3, -0.2],
    "truth_dq_deg": [0.4, -0.3, 0.6, 0.2],
}
WRIST = {
    "lengths": [450.0, 350.0, 150.0],
    "limits": [[-160.0, 160.0], [-140.0, 140.0], [-170.0, 170.0]],
    "joint_map": [[1, 0, 0], [1, 1, 0], [0, 0, 1]],
    "targets": [["tcp", 150.0, 0.0], ["left", 110.0, 25.0], ["right", 110.0, -25.0]],
    "sigma": 0.015,
    "truth_dl": [0.85, -0.62, 0.31, -0.18, 0.44],
    "truth_dq_deg": [0.42, -0.35, 0.30, 0.45, 0.08],
}


# --------------------------------------------------------------------------- the files


def write_inputs(folder: Path, poses: int, seed: int) -> None:
    """Robot files, floor configs, plans and a program; measurements come from armcal itself."""
    rng = np.random.default_rng(seed)
    (folder / "arm4.toml").write_text(
        'name = "bench-4link"\n'
        f"link_lengths_mm = {ARM4['lengths']}\n"
        f"[measurement]\nsigma_mm = {ARM4['sigma']}\n"
    )
    (folder / "truth4.toml").write_text(
        f"dl_mm = {ARM4['truth_dl']}\ndq_deg = {ARM4['truth_dq_deg']}\n"
    )
    truth4 = ARM4["truth_dl"] + np.radians(np.cumsum(ARM4["truth_dq_deg"])).tolist()
    (folder / "arm4.json").write_text(json.dumps({**ARM4, "truth": truth4}))
    targets = "".join(
        f"{label} = {{ length_mm = {length}, angle_deg = {angle} }}\n"
        for label, length, angle in WRIST["targets"]
    )
    (folder / "wrist.toml").write_text(
        'name = "belt-wrist"\n'
        f"link_lengths_mm = {WRIST['lengths']}\n"
        f"joint_limits_deg = {WRIST['limits']}\n"
        "base_offset = true\n"
        f"joint_map = {WRIST['joint_map']}\n"
        f"[measurement]\nsigma_mm = {WRIST['sigma']}\n"
        f"[targets]\n{targets}"
    )
    (folder / "wtruth.toml").write_text(
        f"dl_mm = {WRIST['truth_dl']}\ndq_deg = {WRIST['truth_dq_deg']}\n"
    )
    (folder / "wrist.json").write_text(json.dumps({**WRIST, "base": True, "rotation": True}))
    header4 = "q1_deg,q2_deg,q3_deg,q4_deg"
    for name, m in (
        ("plan", poses),
        ("plan-small", poses // 10),
        ("test", poses),
        ("prog", poses),
        ("pool", poses),
    ):
        q = rng.uniform(-170.0, 170.0, (m, 4))
        np.savetxt(
            folder / f"{name}.csv", q, fmt="%.9f", delimiter=",", header=header4, comments=""
        )
    limits = np.array(WRIST["limits"])
    q = rng.uniform(limits[:, 0] + 5, limits[:, 1] - 5, (poses, 3))
    np.savetxt(
        folder / "wplan.csv",
        q,
        fmt="%.9f",
        delimiter=",",
        header="q1_deg,q2_deg,q3_deg",
        comments="",
    )


def armcal(folder: Path, *args: str) -> None:
    """Run ``armcal ARGS`` in ``folder`` (set-up, not timed)."""
    seconds, _ = measure(armcal_argv([*args]))
    del seconds


def tracker_file(folder: Path, seed: int) -> None:
    """``wplane.csv`` (armcal synthesize's in-plane rows) as a tracker's 3-D file.

    The plane tilted 8 deg and turned 62 deg, the base 2.3 m away, each reflector
    at its own height, noise of sigma along the normal (as docs/tracker.md).
    """
    rng = np.random.default_rng(seed + 1)
    source = folder / "wplane.csv"
    header = source.open().readline().strip().split(",")
    text = np.loadtxt(source, delimiter=",", skiprows=1, dtype=str)
    col = {name: i for i, name in enumerate(header)}
    xy = text[:, [col["x_mm"], col["y_mm"]]].astype(float)
    labels = text[:, col["target"]]
    heights = {"tcp": 0.0, "left": 8.0, "right": -5.0}
    z = np.vectorize(heights.get)(labels) + rng.normal(0.0, WRIST["sigma"], labels.size)
    turn, tilt = np.radians([62.0, 8.0])
    c, s = np.cos(turn), np.sin(turn)
    rz = np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])
    c, s = np.cos(tilt), np.sin(tilt)
    rx = np.array([[1, 0, 0], [0, c, -s], [0, s, c]])
    points = np.column_stack([xy, z]) @ (rz @ rx).T + [2150.0, -640.0, -310.0]
    joints = [col[f"q{j}_deg"] for j in (1, 2, 3)]
    rows = np.column_stack(
        [text[:, col["pose"]], labels, text[:, joints], np.char.mod("%.4f", points)]
    )
    np.savetxt(
        folder / "tracker.csv",
        rows,
        fmt="%s",
        delimiter=",",
        header="pose,target,q1_deg,q2_deg,q3_deg,x_mm,y_mm,z_mm",
        comments="",
    )


def prepare(folder: Path, poses: int, seed: int) -> None:
    write_inputs(folder, poses, seed)
    f = str(folder)
    synth = ["synthesize", "--robot", f"{f}/arm4.toml", "--truth", f"{f}/truth4.toml"]
    armcal(folder, *synth, "--plan", f"{f}/plan.csv", "--seed", "1", "-o", f"{f}/meas.csv")
    armcal(folder, *synth, "--plan", f"{f}/test.csv", "--seed", "2", "-o", f"{f}/test-meas.csv")
    armcal(
        folder,
        "identify",
        "--robot",
        f"{f}/arm4.toml",
        "--measurements",
        f"{f}/meas.csv",
        "-o",
        f"{f}/cal.json",
    )
    armcal(
        folder,
        "synthesize",
        "--robot",
        f"{f}/wrist.toml",
        "--truth",
        f"{f}/wtruth.toml",
        "--plan",
        f"{f}/wplan.csv",
        "--seed",
        "3",
        "-o",
        f"{f}/wplane.csv",
    )
    tracker_file(folder, seed)


# --------------------------------------------------------------------------- the cases


@dataclass
class Case:
    name: str
    armcal: list[str]
    floor: list[str]


def cases(folder: Path, poses: int) -> list[Case]:
    f = str(folder)
    arm4, wrist = f"{f}/arm4.json", f"{f}/wrist.json"
    robot = ["--robot", f"{f}/arm4.toml"]
    truth = ["--truth", f"{f}/truth4.toml"]
    simulate = ["simulate", *robot, *truth, "--trials", str(TRIALS), "--seed", "0", "--plan"]
    return [
        Case(
            "identify 2-D",
            ["identify", *robot, "--measurements", f"{f}/meas.csv", "-o", f"{f}/cal-run.json"],
            ["identify", arm4, f"{f}/meas.csv", f"{f}/floor-cal.json"],
        ),
        Case(
            "identify 3-D, 3 targets",
            [
                "identify",
                "--robot",
                f"{f}/wrist.toml",
                "--measurements",
                f"{f}/tracker.csv",
                "-o",
                f"{f}/wcal.json",
            ],
            ["identify-3d", wrist, f"{f}/tracker.csv", f"{f}/floor-wcal.json"],
        ),
        Case(
            "validate",
            ["validate", "--calibration", f"{f}/cal.json", "--measurements", f"{f}/test-meas.csv"],
            ["validate", arm4, f"{f}/cal.json", f"{f}/test-meas.csv"],
        ),
        Case(
            "compensate",
            [
                "compensate",
                "--calibration",
                f"{f}/cal.json",
                "--program",
                f"{f}/prog.csv",
                "-o",
                f"{f}/corrected.csv",
            ],
            ["compensate", arm4, f"{f}/cal.json", f"{f}/prog.csv", f"{f}/floor-corrected.csv"],
        ),
        Case(
            "evaluate",
            ["evaluate", *robot, "--plan", f"{f}/plan.csv"],
            ["evaluate", arm4, f"{f}/plan.csv"],
        ),
        Case(
            f"simulate {poses // 10:,} poses",
            [*simulate, f"{f}/plan-small.csv"],
            ["simulate", arm4, f"{f}/plan-small.csv", str(TRIALS), "0"],
        ),
        Case(
            "simulate",
            [*simulate, f"{f}/plan.csv"],
            ["simulate", arm4, f"{f}/plan.csv", str(TRIALS), "0"],
        ),
        Case(
            "synthesize",
            [
                "synthesize",
                *robot,
                *truth,
                "--plan",
                f"{f}/plan.csv",
                "--seed",
                "1",
                "-o",
                f"{f}/meas-run.csv",
            ],
            ["synthesize", arm4, f"{f}/plan.csv", "1", f"{f}/floor-meas.csv"],
        ),
        Case(
            "design",
            ["design", *robot, "--poses", str(poses), "-o", f"{f}/design.csv"],
            ["design", arm4, str(poses), f"{f}/floor-design.csv"],
        ),
        Case(
            "design --order none",
            ["design", *robot, "--poses", str(poses), "--order", "none", "-o", f"{f}/design.csv"],
            ["design", arm4, str(poses), f"{f}/floor-design.csv"],
        ),
        Case(
            "design --candidates (20 of the pool)",
            [
                "design",
                *robot,
                "--candidates",
                f"{f}/pool.csv",
                "--poses",
                "20",
                "-o",
                f"{f}/design-pool.csv",
            ],
            ["design-pool", arm4, f"{f}/pool.csv", "20", f"{f}/floor-design-pool.csv"],
        ),
        Case(
            "export",
            ["export", "--calibration", f"{f}/cal.json", "--robot-toml", f"{f}/exported.toml"],
            ["export", arm4, f"{f}/cal.json", f"{f}/floor-exported.toml"],
        ),
    ]


@dataclass
class Row:
    name: str
    armcal_s: float
    floor_s: float
    armcal_mb: float
    floor_mb: float

    @property
    def ratio(self) -> float:
        return self.armcal_s / self.floor_s


def run_case(case: Case, repeats: int, budget: float = 60.0) -> Row:
    """Least wall time and largest peak of the command and its floor, run in turn."""
    row = Row(case.name, float("inf"), float("inf"), 0.0, 0.0)
    for _ in range(repeats):
        a_s, a_mb = measure(armcal_argv(case.armcal))
        f_s, f_mb = measure([sys.executable, FLOORS, *case.floor])
        row.armcal_s, row.floor_s = min(row.armcal_s, a_s), min(row.floor_s, f_s)
        row.armcal_mb, row.floor_mb = max(row.armcal_mb, a_mb), max(row.floor_mb, f_mb)
        if a_s + f_s > budget:
            break
    return row


def agreement(folder: Path) -> list[str]:
    """How far apart armcal's and the floor's calibrations are: they do the same fit."""
    lines = []
    for mine, floor, what in (
        ("cal-run.json", "floor-cal.json", "identify 2-D"),
        ("wcal.json", "floor-wcal.json", "identify 3-D"),
    ):
        ours = {
            p["name"]: p["value"] for p in json.loads((folder / mine).read_text())["parameters"]
        }
        theirs = json.loads((folder / floor).read_text())["parameters"]
        shared = [(ours[p["name"]], p["value"]) for p in theirs if p["name"].startswith("dl")]
        worst = max(abs(a - b) for a, b in shared)
        lines.append(f"{what}: armcal and the floor agree on every dl to {worst:.1e} mm")
        if worst > 1e-6:
            raise RuntimeError(f"{what}: armcal and its floor disagree")
    return lines


def table(rows: list[Row], poses: int) -> list[str]:
    header = ["command", "armcal s", "floor s", "ratio", "armcal MB", "floor MB"]
    lines = ["| " + " | ".join(header) + " |", "|---|" + "---:|" * (len(header) - 1)]
    for r in rows:
        lines.append(
            f"| {r.name} | {r.armcal_s:.3f} | {r.floor_s:.3f} | {r.ratio:.2f}x | "
            f"{r.armcal_mb:.0f} | {r.floor_mb:.0f} |"
        )
    small = next(r for r in rows if r.name.startswith("simulate ") and "poses" in r.name)
    big = next(r for r in rows if r.name == "simulate")
    growth = f"x{big.armcal_s / small.armcal_s:.1f} | x{big.floor_s / small.floor_s:.1f}"
    lines.append(f"| simulate growth, {poses // 10:,} to {poses:,} poses | {growth} | | | |")
    return lines


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seed", type=int, default=0, help="random seed (default 0)")
    parser.add_argument("--poses", type=int, default=100_000, help="poses (default 10^5)")
    parser.add_argument("--repeats", type=int, default=3, help="interleaved runs (default 3)")
    parser.add_argument("--only", help="run the cases whose name starts with this")
    parser.add_argument("--no-write", action="store_true", help=f"do not write {RESULTS.name}")
    args = parser.parse_args()

    machine, date = machine_and_date()
    print(f"armcal floor benchmark, {date}, {args.poses:,} poses\n{machine}\n", flush=True)
    rows = []
    with tempfile.TemporaryDirectory(prefix="armcal-floor-") as tmp:
        folder = Path(tmp)
        prepare(folder, args.poses, args.seed)
        for case in cases(folder, args.poses):
            if args.only and not case.name.startswith(args.only):
                continue
            row = run_case(case, args.repeats)
            rows.append(row)
            print(
                f"{row.name:<28} armcal {row.armcal_s:7.3f} s {row.armcal_mb:6.0f} MB   "
                f"floor {row.floor_s:7.3f} s {row.floor_mb:6.0f} MB   ratio {row.ratio:5.2f}x",
                flush=True,
            )
        checks = agreement(folder) if not args.only else []
    machine = at_end(machine)
    lines = table(rows, args.poses) if not args.only else []
    notes = [f"- {r.name}: {extra(r.name)}" for r in rows if r.ratio > 2]
    print("\n".join(["", *checks, machine, *lines, *notes]))
    if not args.no_write and not args.only:
        RESULTS.write_text(
            "# Floor benchmark results\n\n"
            "Written by `benchmarks/bench_floor.py` (`make bench`); see its docstring for what "
            "each command and its floor do. Times are the least of interleaved runs of "
            "fresh processes; peak memory is their largest resident set.\n\n"
            f"- date: {date}\n- machine: {machine}\n- seed: {args.seed}, "
            f"{args.poses:,} poses, {TRIALS} trials per Monte Carlo\n"
            + "".join(f"- {c}\n" for c in checks)
            + "\n"
            + "\n".join(lines)
            + "\n"
            + ("\nAbove 2x, the extra work:\n\n" + "\n".join(notes) + "\n" if notes else "")
        )
        print(f"\nwrote {RESULTS}")


if __name__ == "__main__":
    main()
