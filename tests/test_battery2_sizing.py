"""poses-needed with a position target on a robot with joint compliance (battery 2).

A robot file with ``[elastostatic]`` had no test poses (its plans are judged by the std
of their parameters), so ``--position-rms-mm`` ended in a traceback on planar arms and
in "reaches only nan" on spatial ones.  The test poses of a position target now carry
the robot file's payload, for every family.
"""

from __future__ import annotations

import json

import numpy as np
import pytest

from armcal.doe.sizing import accuracy_metric
from armcal.errors import ArmcalError
from armcal.models import PlanarArm
from helpers import VERTICAL_3LINK, run_cli


def test_a_position_target_on_a_compliant_planar_robot_is_answered(tmp_path):
    (tmp_path / "robot.toml").write_text(VERTICAL_3LINK)
    run = run_cli(
        tmp_path, "poses-needed", "--robot", "robot.toml", "--position-rms-mm", "0.05", "--json"
    )
    assert run.returncode == 0, run.stderr
    found = json.loads(run.stdout)
    assert np.isfinite(found["achieved"]) and found["achieved"] <= 0.05
    # dl1..3, dq1..3 and k1..3 (masses known, a payload that varies): 9 parameters, two
    # equations a pose, so at least 5 poses
    assert found["poses"] >= 5


@pytest.mark.slow
def test_the_given_test_poses_are_used(tmp_path):
    """Test poses all at the stretched arm (q = 0) differ from the default 1000 random
    ones: the answers' accuracies differ, so the file was read, not ignored."""
    (tmp_path / "robot.toml").write_text(VERTICAL_3LINK)
    (tmp_path / "test.csv").write_text("q1_deg,q2_deg,q3_deg\n0,0,0\n1,0,0\n")
    common = ("poses-needed", "--robot", "robot.toml", "--position-rms-mm", "0.05", "--json")
    default = json.loads(run_cli(tmp_path, *common).stdout)["achieved"]
    run = run_cli(tmp_path, *common, "--test-poses", "test.csv")
    assert run.returncode == 0, run.stderr
    assert json.loads(run.stdout)["achieved"] != pytest.approx(default, rel=1e-3)


def test_no_test_poses_is_an_error_not_nan():
    arm = PlanarArm([300.0, 200.0], sigma=0.05)
    q = np.radians([[0, 30], [40, 60], [80, -30], [-50, 90]])
    with pytest.raises(ArmcalError, match="needs test poses"):
        accuracy_metric(arm, q, "position_rms_mm", 0.05, np.zeros((0, 2)))


@pytest.mark.parametrize("poses", [121, 1000, 100_000])
def test_a_replicated_plan_has_exactly_the_poses_asked_for(poses):
    """Above REPLICATE_ABOVE poses the plan repeats a smaller optimal plan; for 10^5
    poses of a 3-link arm the copies of 119 poses fell 635 short (834 * 119 = 99 246,
    and "its first 754 poses once more" of a 119-pose plan). The note's counts add up."""
    from armcal.doe import design
    from armcal.doe.designer import REPLICATE_ABOVE

    arm = PlanarArm([300.0, 200.0, 100.0], joint_limits=np.radians([[-170, 170]] * 3))
    made = design(arm, poses, rng=1, with_certificate=False)
    assert made.q.shape == (poses, 3)
    (note,) = [n for n in made.note_texts if "-pose plan taken" in n]
    size = int(note.split("optimal ")[1].split("-pose")[0])
    copies = int(note.split("taken ")[1].split(" times")[0])
    extra = int(note.split("first ")[1].split(" poses")[0]) if "first" in note else 0
    assert size <= REPLICATE_ABOVE and extra < size and copies * size + extra == poses
    assert not any(f"at {poses} angles" in n for n in made.note_texts)


@pytest.mark.parametrize(
    ("text", "what"),
    [
        ('urdf = "arm.urdf"\n', "a six-axis robot file"),
        ('<?xml version="1.0"?>\n<robot name="x"/>\n', "a URDF"),
    ],
)
def test_a_six_axis_robot_piped_in_is_told_to_give_its_path(tmp_path, text, what):
    """--robot - read only planar TOML: a six-axis file got "unknown key 'urdf'" and the
    planar key list, a URDF "invalid TOML" (battery 2)."""
    (tmp_path / "plan.csv").write_text("q1_deg,q2_deg\n0,10\n")
    run = run_cli(tmp_path, "evaluate", "--robot", "-", "--plan", "plan.csv", stdin=text)
    assert run.returncode == 2
    assert (
        run.stderr == f"armcal: error: <stdin>: {what} is read from a file, not piped in "
        "(only a planar robot file may be): give its path\n"
    )
