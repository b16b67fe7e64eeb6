"""The six-axis numpy floors of ``make bench`` (benchmarks/floors_spatial.py) give armcal's
answers.

Every floor runs in-process on a tiny case (the built-in industrial-6r with three
reflectors, 30 poses, 90 rows) and is compared with armcal's library on the same
rows, so a floor that drifts from what armcal computes fails here, not only in a
benchmark nobody runs.  Tolerances:

* kinematics: 1e-9 mm (mm per rad): round-off of coordinates of a few metres is
  about 1e-12 mm;
* estimates (identify, simulate): 1e-6 of their std: both converge to round-off,
  the benchmark's own criterion;
* derived figures (validate, evaluate): 1e-9 relatively: the same formulas from the
  same parameters, in another order of operations;
* corrected commands: 1e-6 deg: both stop within 1e-9 mm of the goal, which fixes a
  command to about 1e-9 mm over the goal Jacobian's smallest singular value
  (a few mm/rad at worst here, well under 1e-7 deg).
"""

from __future__ import annotations

import importlib.util
import json
import sys
from pathlib import Path

import numpy as np
import pytest

from armcal import identify, load_robot
from armcal.compensation import compensate
from armcal.criteria import evaluate_plan
from armcal.doe import random_plan
from armcal.files import calibration_document, format_measurements_csv, to_json
from armcal.files import read_calibration as armcal_calibration
from armcal.files.spatial import load_spatial_truth
from armcal.synthesis import synthesize_measurements
from armcal.validation import validate
from armcal.workflow.plan import simulate_plan

FLOORS = Path(__file__).parents[1] / "benchmarks" / "floors_spatial.py"
ROBOTS = Path(__file__).parents[1] / "src" / "armcal" / "robots"
SIGMA_MM = 0.03
POSES = 30


def _load_floors():
    spec = importlib.util.spec_from_file_location("floors_spatial", FLOORS)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module  # its dataclasses look their module up there
    spec.loader.exec_module(module)
    return module


fs = _load_floors()


@pytest.fixture(scope="module")
def case(tmp_path_factory):
    """The arm (armcal's and the floor's), its truth, and a plan's measurements on file."""
    folder = tmp_path_factory.mktemp("floors")
    text = (ROBOTS / "industrial-6r.toml").read_text()
    text = text.replace('urdf = "industrial-6r.urdf"', f'urdf = "{ROBOTS / "industrial-6r.urdf"}"')
    reflectors = {"A": [100.0, 0.0, 150.0], "B": [-50.0, 86.6, 150.0], "C": [-50.0, -86.6, 150.0]}
    targets = "".join(f"{k} = {{ xyz_mm = {v} }}\n" for k, v in reflectors.items())
    robot = folder / "cell.toml"
    robot.write_text(f"{text}\n[measurement]\nsigma_mm = {SIGMA_MM}\n\n[targets]\n{targets}")
    truth_file = folder / "truth.toml"
    truth_file.write_text((ROBOTS / "industrial-6r-truth.toml").read_text())
    arm = load_robot(str(robot)).arm
    truth = load_spatial_truth(truth_file, arm)
    rng = np.random.default_rng(37)
    q = random_plan(arm, POSES, rng=rng)
    rows = arm.plan_conditions(q)
    held = arm.prepared(rows, arm.positions(rows, truth))
    points = synthesize_measurements(arm, rows.q, truth, rng=rng, target=rows.target)
    labels = [str(i // 3 + 1) for i in range(rows.m)]
    names = [arm.targets[t] for t in rows.target]
    meas = folder / "meas.csv"
    meas.write_text(format_measurements_csv(rows.q, points, labels, names))
    config = folder / "floor.json"
    config.write_text(json.dumps(fs.config_of(arm, list(held.fixed), truth)))
    return {
        "folder": folder,
        "arm": arm,
        "truth": truth,
        "q": q,
        "rows": rows,
        "points": points,
        "meas": str(meas),
        "floor": fs.load_config(str(config)),
        "rng": rng,
    }


def _calibration(case):
    """armcal's calibration of the case's rows, and its file."""
    rows = case["rows"]
    cal = identify(case["arm"], rows.q, case["points"], target=rows.target)
    path = case["folder"] / "cal.json"
    if not path.exists():
        path.write_text(to_json(calibration_document(cal)))
    return cal, str(path)


def _plan_file(path: Path, q: np.ndarray) -> str:
    header = ",".join(f"q{j + 1}_deg" for j in range(q.shape[1]))
    np.savetxt(path, np.degrees(q), fmt="%.15g", delimiter=",", header=header, comments="")
    return str(path)


def test_kinematics_and_jacobians_are_armcals(case):
    arm, floor, rows = case["arm"], case["floor"], case["rows"]
    params = case["truth"] + case["rng"].normal(scale=0.01, size=case["truth"].size)
    every = np.arange(params.size)
    kin = fs.kinematics(floor, rows.q, rows.target, params, columns=every, joints=True)
    assert floor.names == list(arm.param_names)
    np.testing.assert_allclose(kin.points, arm.positions(rows, params), rtol=0, atol=1e-9)
    np.testing.assert_allclose(kin.columns, arm.jacobian(rows, params), rtol=0, atol=1e-9)
    np.testing.assert_allclose(kin.joint, arm.joint_jacobian(rows, params), rtol=0, atol=1e-9)
    turning = arm.orientation_joint_jacobian(rows, params)
    np.testing.assert_allclose(kin.angular, turning, rtol=0, atol=1e-12)


def test_identify_floor_gives_armcals_estimates(case):
    cal, _ = _calibration(case)
    out = case["folder"] / "floor-cal.json"
    fs.identify(case["floor"], case["meas"], str(out))
    found = {p["name"]: p for p in json.loads(out.read_text())["parameters"]}
    free = cal.model.free
    assert [found[name]["fixed"] for name in cal.names] == (~free).tolist()
    values = np.array([found[name]["value"] for name in cal.names])
    std = np.array([found[name]["std"] for name in cal.names])
    assert np.max(np.abs(values - cal.values)[free] / cal.std[free]) < 1e-6
    np.testing.assert_allclose(std[free], cal.std[free], rtol=1e-9)


def test_validate_floor_gives_armcals_figures(case, capsys):
    _, path = _calibration(case)
    arm, rng = case["arm"], case["rng"]
    held = arm.plan_conditions(random_plan(arm, 10, rng=rng))
    points = synthesize_measurements(arm, held.q, case["truth"], rng=rng, target=held.target)
    labels = [str(i // 3 + 1) for i in range(held.m)]
    names = [arm.targets[t] for t in held.target]
    meas = case["folder"] / "held.csv"
    meas.write_text(format_measurements_csv(held.q, points, labels, names))
    ours = validate(armcal_calibration(path), held.q, points, target=held.target).summary()
    fs.validate(case["floor"], path, str(meas))
    theirs = json.loads(capsys.readouterr().out)
    for key in ("rms_before_mm", "rms_after_mm", "max_after_mm", "p95_before_mm"):
        assert theirs[key] == pytest.approx(ours[key], rel=1e-9), key
    for key in ("predicted_rms_after_per_point_mm", "model_rms_per_point_mm"):
        assert theirs[key] == pytest.approx(ours[key], rel=1e-9), key


def test_compensate_floor_gives_armcals_commands(case):
    _, path = _calibration(case)
    arm = case["arm"]
    program = random_plan(arm, POSES, rng=case["rng"])
    ours = compensate(armcal_calibration(path), program, target=["A"] * POSES)
    out = case["folder"] / "floor-corrected.csv"
    plan = _plan_file(case["folder"] / "prog.csv", program)
    fs.compensate(case["floor"], path, plan, "A", str(out))
    table = np.loadtxt(out, delimiter=",", skiprows=1, usecols=[0, 1, 2, 3, 4, 5, 7])
    assert table[:, -1].astype(bool).tolist() == ours.corrected.tolist()
    assert np.count_nonzero(ours.corrected) > POSES // 2  # the comparison is not empty
    np.testing.assert_allclose(table[:, :6], np.degrees(ours.q), rtol=0, atol=1e-6)


def test_evaluate_floor_gives_armcals_quality(case, capsys):
    arm, floor = case["arm"], case["floor"]
    test_q = random_plan(arm, 20, rng=case["rng"])
    quality = evaluate_plan(arm, case["q"], sigma=SIGMA_MM, test_q=test_q)
    assert sorted(quality.model.fixed) == sorted(floor.fixed)
    plan = _plan_file(case["folder"] / "plan.csv", case["q"])
    fs.evaluate(floor, plan, _plan_file(case["folder"] / "test.csv", test_q))
    theirs = json.loads(capsys.readouterr().out)
    for name in "DAE":
        key = f"{name.lower()}_efficiency"
        assert theirs[key] == pytest.approx(quality.efficiencies[name], rel=1e-9)
    std = np.array([theirs["predicted_std"][name] for name in arm.param_names])
    np.testing.assert_allclose(std, quality.predicted_std, rtol=1e-9)
    assert quality.position is not None
    assert theirs["predicted_position_rms_mm"] == pytest.approx(quality.position.rms_mm, rel=1e-9)


def test_simulate_floor_gives_armcals_monte_carlo(case, capsys):
    arm = case["arm"]
    result = simulate_plan(arm, case["q"], case["truth"], trials=3, seed=5)
    fs.simulate(case["floor"], _plan_file(case["folder"] / "plan.csv", case["q"]), "3", "5")
    theirs = json.loads(capsys.readouterr().out)
    scale = arm.display_scale
    free = result.model.free
    std = result.predicted_std  # display units
    for key, ours in (("truth", result.truth), ("empirical_mean", result.mean)):
        found = np.array([theirs[key][name] for name in arm.param_names])
        assert np.max(np.abs(found - ours * scale)[free] / std[free]) < 1e-6, key
    spread = np.array([theirs["empirical_std"][name] for name in arm.param_names])
    assert np.max(np.abs(spread - result.std)[free] / std[free]) < 1e-6
    predicted = np.array([theirs["predicted_std"][name] for name in arm.param_names])
    np.testing.assert_allclose(predicted[free], std[free], rtol=1e-9)
