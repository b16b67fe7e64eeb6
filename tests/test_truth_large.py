"""A virtual arm far from its nominal model is said to be another arm (truth-large).

A truth file whose ``robot`` key names another arm with the same joint kinds (a UR5's
URDF under an industrial 6R's robot file), or whose deviations are in the wrong unit,
was simulated without a word (issue 34's battery, S3_t_robot_other).  synthesize and
simulate now warn ``truth-large`` on stderr and in the JSON, for every family, by the
model's own deviation bounds; a calibration-sized truth gives no such warning.
"""

from __future__ import annotations

import json

import numpy as np

from armcal.files.spatial import BUILTIN_SPATIAL_ROBOTS
from armcal.models import LARGE_PLACEMENT_FRACTION, PlanarArm
from armcal.models.planar.arm import LARGE_LENGTH_FRACTION
from armcal.plausibility import truth_warning
from helpers import run_cli

PLANAR = """name = "bench3"
link_lengths_mm = [300.0, 250.0, 150.0]
joint_limits_deg = [[-170, 170], [-150, 150], [-150, 150]]
[measurement]
sigma_mm = 0.05
"""

PLAN = "q1_deg,q2_deg,q3_deg\n" + "\n".join(
    ",".join(f"{v:.3f}" for v in row)
    for row in np.random.default_rng(3).uniform(-140, 140, (12, 3))
)


def _codes(stdout: str) -> list[str]:
    return [w["code"] for w in json.loads(stdout)["warnings"]]


def test_the_bound_is_the_models_own():
    """Link 2 of 250 mm: 10 % of it (25 mm) is the bound of dl2; just below it is quiet."""
    arm = PlanarArm([300.0, 250.0, 150.0])
    bound = LARGE_LENGTH_FRACTION * 250.0
    quiet = arm.params_from_display([0.0, 0.99 * bound, 0.0], [0.0, 0.0, 0.0])
    loud = arm.params_from_display([0.0, 1.01 * bound, 0.0], [0.0, 0.0, 0.0])
    assert truth_warning(arm, quiet) is None
    found = truth_warning(arm, loud)
    assert found is not None and found.code == "truth-large"
    assert f"dl2 = {1.01 * bound:.4g} mm" in found.message


def test_a_planar_truth_in_the_wrong_unit_warns_at_synthesize_and_simulate(tmp_path):
    (tmp_path / "robot.toml").write_text(PLANAR)
    (tmp_path / "plan.csv").write_text(PLAN + "\n")
    # the calibration-sized truth of ok.toml with its link errors 100 times too large:
    # dl1 = 60 mm is 20 % of link 1 (bound 10 %), dl2 = -40 mm 16 % of link 2
    (tmp_path / "um.toml").write_text("dl_mm = [60, -40, 25]\ndq_deg = [0.2, -0.1, 0.3]\n")
    (tmp_path / "ok.toml").write_text("dl_mm = [0.6, -0.4, 0.25]\ndq_deg = [0.2, -0.1, 0.3]\n")
    common = ("--robot", "robot.toml", "--plan", "plan.csv")
    for truth, expected in (("um.toml", True), ("ok.toml", False)):
        run = run_cli(tmp_path, "simulate", *common, "--truth", truth, "--trials", "20", "--json")
        assert run.returncode == 0, run.stderr
        assert ("truth-large" in _codes(run.stdout)) is expected, run.stderr
        out = f"m-{truth}.csv"
        run = run_cli(tmp_path, "synthesize", *common, "--truth", truth, "-o", out, "--json")
        assert run.returncode == 0, run.stderr
        assert ("truth-large" in _codes(run.stdout)) is expected
        assert ("armcal: warning: the virtual arm's deviations" in run.stderr) is expected


def test_a_six_axis_truth_of_another_arm_warns(tmp_path):
    """The industrial 6R's URDF with a truth whose robot is the built-in cobot's table:
    both are 6R, so the kinds check passes; their placements differ by hundreds of mm,
    far beyond a calibration's bound (1 % of the reach)."""
    six = BUILTIN_SPATIAL_ROBOTS["industrial-6r"].with_suffix(".urdf")
    (tmp_path / "arm.urdf").write_text(six.read_text())
    (tmp_path / "other.toml").write_text(BUILTIN_SPATIAL_ROBOTS["cobot-6r"].read_text())
    (tmp_path / "truth.toml").write_text('robot = "other.toml"\n')
    (tmp_path / "plan.csv").write_text(
        "q1_deg,q2_deg,q3_deg,q4_deg,q5_deg,q6_deg\n"
        + "\n".join(
            ",".join(f"{v:.3f}" for v in row)
            for row in np.random.default_rng(4).uniform(-50, 50, (8, 6))
        )
        + "\n"
    )
    options = ("--robot", "arm.urdf", "--plan", "plan.csv", "--truth", "truth.toml")
    run = run_cli(tmp_path, "synthesize", *options, "-o", "meas.csv", "--json")
    assert run.returncode == 0, run.stderr
    assert "truth-large" in _codes(run.stdout)
    assert f"{LARGE_PLACEMENT_FRACTION:.0%}" == "1%"  # the bound the docstring cites
    run = run_cli(
        tmp_path,
        "synthesize",
        "--robot",
        "industrial-6r",
        "--plan",
        "plan.csv",
        "-o",
        "clean.csv",
        "--json",
    )  # the built-in truth: calibration-sized
    assert run.returncode == 0, run.stderr
    assert "truth-large" not in _codes(run.stdout)
