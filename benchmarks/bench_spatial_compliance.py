"""Benchmark: joint compliance of a spatial arm -- what it costs and what it buys.

What it measures
----------------
One run, one seeded ``numpy.random.Generator``.  The robot is the built-in
``industrial-6r`` with three reflectors (``[100, 0, 150]``, ``[-50, 86.6,
150]``, ``[-50, -86.6, 150]`` mm in the flange frame), illustrative link
masses (350, 150, 200, 60, 20, 5 kg, each at its joint's origin) and a 165 kg
payload 100 mm off the flange; its J2 and J3 are compliant (0.2 and 0.4
urad/(N m)), and its geometry has the built-in truth's errors and tracker
pose.  Rows are poses uniform within the limits, every pose measured at the
three reflectors, every other pose under the payload; isotropic noise
0.02 mm, which ``identify`` is told.

1. **Cost.** ``identify()`` with compliance at m = 10^4 rows (masses known;
   and the lumped mode) against ``identify()`` of the rigid arm on rows of
   the same poses measured without sag (what the same campaign costs without
   compliance).  Targets: <= 2.5x (masses known), <= 3x (lumped).  Peak
   memory of the ``armcal identify`` command on the 10^4-row file with
   compliance, against the same command with ``--no-compliance`` on the
   sagless file: target <= 1.5x.
2. **What it buys.** The position RMS per point on 1000 held-out poses
   (random payloads of 0 or 165 kg) after calibration with compliance,
   against geometry alone from the same 40-pose campaign (published 6R
   tracker results halve the error left by the geometry): target <= 0.5x.
3. **Design.** A 40-pose design of poses and payloads (0 or 165 kg, masses
   known) with its certificate: its time against the rigid arm's design of
   40 poses with certificate (target <= 60 s), and the certified
   D-efficiency (target >= 0.95).

Timing: wall time of one call each (the figures are seconds, the noise a few
per cent); the commands run in a fresh child of a fresh measuring process
(:mod:`measure`).  The table goes to stdout and to
``benchmarks/RESULTS_SPATIAL_COMPLIANCE.md``.

Usage::

    .venv/bin/python benchmarks/bench_spatial_compliance.py [--seed S] [--no-write]
"""

from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path

import numpy as np
from bench_scale import Row, finish
from measure import armcal_argv, machine_and_date, measure

from armcal.doe import design, design_with_loads
from armcal.files import format_measurements_csv, load_spatial_robot, load_spatial_truth
from armcal.files.spatial import BUILTIN_SPATIAL_ROBOTS
from armcal.identification import identify
from armcal.models import CompliantSpatialArm, Loads, SpatialArm, SpatialElastics
from armcal.validation import validate

RESULTS = Path(__file__).with_name("RESULTS_SPATIAL_COMPLIANCE.md")
MASSES = [350.0, 150.0, 200.0, 60.0, 20.0, 5.0]
PAYLOAD = 165.0
SIGMA_MM = 0.02
TARGETS = {"A": [100.0, 0.0, 150.0], "B": [-50.0, 86.6, 150.0], "C": [-50.0, -86.6, 150.0]}
ROBOT = f"""name = "cell-6r"
urdf = "{{urdf}}"
base_link = "base_link"
tip_link = "flange"
joint_map = [[1, 0, 0, 0, 0, 0], [0, 1, 0, 0, 0, 0], [0, 1, 1, 0, 0, 0],
             [0, 0, 0, 1, 0, 0], [0, 0, 0, 0, 1, 0], [0, 0, 0, 0, 0, 1]]
joint_limits_deg = [[-185, 185], [-60, 76], [-132, 150], [-360, 360], [-125, 125], [-360, 360]]
[measurement]
sigma_mm = {SIGMA_MM}
[targets]
{chr(10).join(f"{k} = {{ xyz_mm = {v} }}" for k, v in TARGETS.items())}
[elastostatic]
link_masses_kg = {MASSES}
payload_kg = {PAYLOAD}
payload_com_mm = [0, 0, 100]
"""


def arm_of() -> SpatialArm:
    arm = load_spatial_robot("industrial-6r").arm
    positions = np.array(list(TARGETS.values()))
    return arm.replace(targets=tuple(TARGETS), target_positions=positions, view=None)


def elastics(lumped: bool) -> SpatialElastics:
    return SpatialElastics.create(
        6,
        mass_kg=None if lumped else MASSES,
        com_mm=None if lumped else np.zeros((6, 3)),
        payload_kg=PAYLOAD,
        payload_com_mm=[0.0, 0.0, 100.0],
    )


def poses(m: int, rng: np.random.Generator) -> tuple[np.ndarray, Loads]:
    lo, hi = arm_of().joint_limits.T
    q = lo + (hi - lo) * rng.random((m, 6))
    return q, Loads.create(m, np.where(rng.random(m) < 0.5, 0.0, PAYLOAD))


def truth_of(model: CompliantSpatialArm) -> np.ndarray:
    geometry = load_spatial_truth(load_spatial_robot("industrial-6r").default_truth, model.arm)
    compliance = np.zeros(model.n_compliance)
    compliance[model.compliance_names.index("k2")] = 0.2e-6
    compliance[model.compliance_names.index("k3")] = 0.4e-6
    return np.concatenate([geometry, compliance])


def measured(model, q, loads, truth, rng):
    rows = model.plan_conditions(q, loads)
    points = model.positions(rows, truth)
    return rows, points + rng.normal(0.0, SIGMA_MM, points.shape)


def timed(call) -> tuple[float, object]:
    start = time.perf_counter()
    out = call()
    return time.perf_counter() - start, out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seed", type=int, default=0, help="random seed (default 0)")
    parser.add_argument("--no-write", action="store_true", help="do not write the results")
    args = parser.parse_args()
    machine, date = machine_and_date()
    print(f"armcal spatial compliance benchmark, {date}\n{machine}\n")
    rng = np.random.default_rng(args.seed)
    arm = arm_of()
    q, loads = poses(10_000 // 3, rng)
    model = CompliantSpatialArm.for_loads(arm, elastics(False), loads)
    truth = truth_of(model)
    rows, points = measured(model, q, loads, truth, rng)
    flat = truth.copy()
    flat[arm.n_params :] = 0.0
    _, sagless = measured(model, q, loads, flat, rng)
    fit = dict(target=rows.target, sigma=SIGMA_MM)
    t_rigid, _ = timed(lambda: identify(arm, rows.q, sagless, **fit))
    t_known, _ = timed(lambda: identify(model, rows.q, points, loads=rows.loads, **fit))
    lumped = CompliantSpatialArm.for_loads(arm, elastics(True), loads)
    t_lumped, _ = timed(lambda: identify(lumped, rows.q, points, loads=rows.loads, **fit))

    with tempfile.TemporaryDirectory() as folder:
        work = Path(folder)
        source = BUILTIN_SPATIAL_ROBOTS["industrial-6r"].with_suffix(".urdf")
        (work / "cell.toml").write_text(ROBOT.replace("{urdf}", str(source)))
        labels = np.array(list(TARGETS))[rows.target]
        for name, data in (("sag.csv", points), ("rigid.csv", sagless)):
            text = format_measurements_csv(
                rows.q, data, targets=labels, payload_kg=rows.loads.payload_kg
            )
            (work / name).write_text(text)
        common = ["identify", "--robot", str(work / "cell.toml"), "-o", str(work / "out.json")]
        _, mb_known = measure(armcal_argv([*common, "--measurements", str(work / "sag.csv")]))
        _, mb_rigid = measure(
            armcal_argv([*common, "--measurements", str(work / "rigid.csv"), "--no-compliance"])
        )

    # What it buys: a 40-pose campaign, 1000 held-out poses
    q40, loads40 = poses(40, rng)
    campaign, observed = measured(model, q40, loads40, truth, rng)
    on_campaign = dict(target=campaign.target, sigma=SIGMA_MM)
    with_compliance = identify(model, campaign.q, observed, loads=campaign.loads, **on_campaign)
    alone = identify(arm, campaign.q, observed, **on_campaign)
    q_test, loads_test = poses(1000, rng)
    test, test_points = measured(model, q_test, loads_test, truth, rng)
    rms = []
    for cal in (with_compliance, alone):
        check = validate(
            cal.calibrated(), test.q, test_points, target=test.target, loads=test.loads
        )
        rms.append(check.summary()["rms_after_per_point_mm"])

    ready = model.prepared(model.plan_conditions(q40, loads40))  # the identifiable set
    t_design, made = timed(lambda: design_with_loads(ready, 40, payloads=(0.0, PAYLOAD), rng=rng))
    t_rigid_design, _ = timed(lambda: design(arm.prepared(arm.plan_conditions(q)), 40, rng=rng))
    assert made.certificate is not None
    certified = made.certificate.certified_d_efficiency
    print(
        f"held-out RMS per point: {rms[0]:.4g} mm with compliance, {rms[1]:.4g} mm geometry "
        f"alone; design {t_design:.1f} s, certified {certified:.4f}"
    )
    rows_out = [
        Row("identify(), m=10^4 rows, 3 targets, masses known: wall time", t_known, "s",
            "identify() of the rigid arm, sagless rows", t_rigid, "<= 2.5x baseline",
            t_known <= 2.5 * t_rigid),
        Row("identify(), m=10^4 rows, lumped mode: wall time", t_lumped, "s",
            "identify() of the rigid arm, sagless rows", t_rigid, "<= 3x baseline",
            t_lumped <= 3.0 * t_rigid),
        Row("armcal identify on the 10^4-row file: peak memory", mb_known, "MB",
            "--no-compliance on the sagless file", mb_rigid, "<= 1.5x baseline",
            mb_known <= 1.5 * mb_rigid),
        Row("held-out RMS per point after calibration, 1000 poses", rms[0], "mm",
            "geometry alone, same 40-pose campaign", rms[1], "<= 0.5x baseline",
            rms[0] <= 0.5 * rms[1]),
        Row("design of 40 poses and payloads with certificate: time", t_design, "s",
            "the rigid arm's 40-pose design with certificate", t_rigid_design, "<= 60 s",
            t_design <= 60.0),
        Row("that design: certified D-efficiency", certified, "", "", 0.0, ">= 0.95",
            certified >= 0.95, ratio=False),
    ]  # fmt: skip
    finish(
        rows_out,
        machine,
        date,
        None if args.no_write else RESULTS,
        "Spatial compliance benchmark results",
        "Written by `benchmarks/bench_spatial_compliance.py` (`make bench`); see its "
        "docstring for what each figure and baseline is.",
        f"seed: {args.seed}",
    )


if __name__ == "__main__":
    main()
