"""Virtual spatial arms: synthesize, evaluate, simulate and poses-needed on the built-ins.

The Monte Carlo criterion is the contract's (the issue: empirical std within 5 %
of the predicted std at 2000 trials or more).  With N trials an empirical std has
a relative standard error of ``1 / sqrt(2 (N - 1))``: 1.1 % at 4000 trials, so
5 % is more than four standard errors and a correct prediction passes.
"""

from __future__ import annotations

import json

import numpy as np
import pytest

from armcal.demo_spatial import SPATIAL_DEMO_FILES
from armcal.doe import random_plan
from armcal.files import load_spatial_robot, load_spatial_truth
from armcal.files.spatial import ROBOT_FOLDER
from armcal.identification import identify
from armcal.workflow import simulate_plan
from helpers import run_cli
from helpers_spatial import plan_file

ROBOTS = ("industrial-6r", "cobot-6r", "arm-7r")


@pytest.mark.parametrize("robot", ROBOTS)
def test_the_built_in_truths_are_virtual_arms_with_every_error(robot):
    spec = load_spatial_robot(robot)
    truth = load_spatial_truth(spec.default_truth, spec.arm)
    errors = truth[~spec.arm.instrument_params]
    # Every placement error and zero is set, each 0.1-0.5 mm or 0.01-0.05 deg (the file).
    shown = np.abs(errors * spec.arm.display_scale[~spec.arm.instrument_params])
    assert np.all((shown >= 0.01) & (shown <= 0.5))
    assert np.linalg.norm(truth[:3]) > 1000.0  # a tracker metres away


def test_synthesize_then_identify_recovers_the_built_in_truth(tmp_path):
    plan_file(tmp_path, "cobot-6r")
    result = run_cli(
        tmp_path, "synthesize", "--robot", "cobot-6r", "--plan", "plan.csv", "--sigma", "0",
        "-o", "meas.csv",
    )  # fmt: skip
    assert result.returncode == 0, result.stderr
    result = run_cli(
        tmp_path, "identify", "--robot", "cobot-6r", "--measurements", "meas.csv", "--json"
    )
    assert result.returncode == 0, result.stderr
    document = json.loads(result.stdout)
    # Noiseless: the fit reproduces the virtual arm's points to round-off (the file has
    # 17 significant digits).
    assert document["residual_rms_mm"] < 1e-9
    assert document["poses"] == 30


def test_evaluate_and_simulate_a_plan_from_the_command_line(tmp_path):
    plan_file(tmp_path, "industrial-6r", m=40)
    result = run_cli(
        tmp_path, "evaluate", "--robot", "industrial-6r", "--plan", "plan.csv", "--sigma",
        "0.03", "--json",
    )  # fmt: skip
    assert result.returncode == 0, result.stderr
    quality = json.loads(result.stdout)
    assert 0.0 < quality["predicted_position_rms_mm"] < 0.03
    result = run_cli(
        tmp_path, "simulate", "--robot", "industrial-6r", "--plan", "plan.csv", "--sigma",
        "0.03", "--trials", "300", "--json",
    )  # fmt: skip
    assert result.returncode == 0, result.stderr
    sim = json.loads(result.stdout)
    # The same set, and the robot's predicted std as evaluate's: they do not depend on
    # where the instrument stands; the truth's errors (a few tenths of a mm against metres)
    # change the Jacobian by 1e-3 or less.
    assert sim["predicted_std"].keys() == quality["predicted_std"].keys()
    for name, value in quality["predicted_std"].items():
        if name.startswith(("j", "dq")):
            assert sim["predicted_std"][name] == pytest.approx(value, rel=1e-2)


def test_poses_needed_finds_the_smallest_designed_plan_that_reaches(tmp_path):
    """The plan found reaches the goal, checked by evaluate, and one pose fewer does not."""
    result = run_cli(
        tmp_path, "poses-needed", "--robot", "industrial-6r", "--position-rms-mm", "0.03",
        "--sigma", "0.03", "--json", "-o", "plan.csv",
    )  # fmt: skip
    assert result.returncode == 0, result.stderr
    found = json.loads(result.stdout)
    m = found["poses"]
    # At least the identifiable count's worth of equations (27 parameters, 3 per pose).
    assert m >= 9
    result = run_cli(
        tmp_path, "evaluate", "--robot", "industrial-6r", "--plan", "plan.csv", "--sigma",
        "0.03", "--json",
    )  # fmt: skip
    checked = json.loads(result.stdout)
    assert checked["poses"] == m
    assert checked["predicted_position_rms_mm"] <= 0.03
    assert checked["predicted_position_rms_mm"] == pytest.approx(found["achieved"], rel=1e-9)
    assert found["with_one_pose_less"] > 0.03


def test_a_held_reflector_keeps_the_robot_file_s_position(tmp_path):
    """--fix A.z holds A at the robot file's 340 mm, not at 0."""
    urdf = ROBOT_FOLDER / "industrial-6r.urdf"
    robot = tmp_path / "robot.toml"
    robot.write_text(
        f"urdf = {json.dumps(str(urdf))}\n[targets]\nA = {{ xyz_mm = [0, 0, 340] }}\n",
        encoding="utf-8",
    )
    arm = load_spatial_robot(robot).arm
    truth = arm.nominal.copy()
    truth[:3] = [2500.0, 1000.0, -300.0]
    cond = arm.plan_conditions(random_plan(arm, 30, rng=2))
    points = arm.positions(cond, truth)
    cal = identify(arm.with_fixed(["A.z"]), cond.q, points, target=cond.target)
    assert cal.params[arm.param_names.index("A.z")] == pytest.approx(340.0, abs=1e-9)
    assert cal.residual_rms < 1e-9


@pytest.mark.slow
@pytest.mark.parametrize("robot", ROBOTS)
def test_monte_carlo_agrees_with_the_predicted_std(robot):
    spec = load_spatial_robot(robot)
    arm = spec.arm.with_noise(None)
    truth = load_spatial_truth(spec.default_truth, arm)
    q = random_plan(arm, 40, rng=5)
    result = simulate_plan(arm, q, truth, trials=4000, seed=1)
    free = result.model.free
    ratio = result.std[free] / result.predicted_std[free]
    assert np.all(np.abs(ratio - 1.0) < 0.05), ratio
    # Unbiased to first order: every mean within 4 standard errors of the truth.
    assert np.all(np.abs(result.bias[free]) <= result.bias_limit[free])


def test_the_six_axis_demo_calibrates_compensates_and_exports(tmp_path):
    """``armcal demo --robot industrial-6r``: three reflectors found from the data, a
    tracker's noise, cross-validation, compensation and export, each usable by the CLI."""
    result = run_cli(tmp_path, "demo", "--robot", "industrial-6r", "-o", "out", "--json")
    assert result.returncode == 0, result.stderr
    document = json.loads(result.stdout)
    # 4R + 2P + 3k for 6 revolute joints and 3 reflectors.
    assert sum(not p["fixed"] for p in document["parameters"]) == 33
    story = result.stderr + (tmp_path / "out" / "report.md").read_text(encoding="utf-8")
    assert "laser tracker" in story and "cross-validation (5 folds)" in story
    after = float(story.split("true error RMS ")[1].split(" mm after")[0].split(", ")[1])
    assert after < 0.01  # the reflector's true error, against errors of tenths of a mm
    files = sorted(p.name for p in (tmp_path / "out").iterdir() if not p.name.startswith("."))
    assert files == sorted(SPATIAL_DEMO_FILES)
    # The calibration and the files it goes with work with the other commands.
    out = tmp_path / "out"
    validated = run_cli(
        out, "validate", "--calibration", "calibration.json", "--measurements",
        "validation.csv", "--json",
    )  # fmt: skip
    assert validated.returncode == 0, validated.stderr
    assert json.loads(validated.stdout)["rms_after_mm"] < 0.05
    compensated = run_cli(
        out, "compensate", "--calibration", "calibration.json", "--program", "program.csv",
        "-o", "again.csv",
    )  # fmt: skip
    assert compensated.returncode == 0, compensated.stderr
    # The same commands from the calibration file (its numbers round-trip to the last bit
    # or so: 1e-9 deg is far below any controller's resolution).
    again, demo = (
        np.loadtxt(out / name, delimiter=",", skiprows=1, usecols=range(6))
        for name in ("again.csv", "program_corrected.csv")
    )
    np.testing.assert_allclose(again, demo, rtol=0, atol=1e-9)
    exported = load_spatial_robot(out / "robot_calibrated.toml").arm
    assert exported.n_joints == 6
