"""The demo of a robot with joint compliance says it calibrates the geometry alone.

``armcal demo`` tells the rigid story (a design, a measurement, a fit, a validation) on
any robot file.  A robot whose file has ``[elastostatic]`` had it left out without a
word, and a six-axis truth with ``[compliance]`` was refused with the false claim that
the robot had no ``[elastostatic]`` table (issue 34's battery).  Both families now take
such a truth and warn ``demo-rigid`` on stderr and in the JSON; a rigid robot gets no
such warning.
"""

from __future__ import annotations

import json

from armcal.files.spatial import BUILTIN_SPATIAL_ROBOTS
from helpers import VERTICAL_3LINK, cell_toml, run_cli

#: A planar truth with compliance (the keys of ``armcal formats``).
PLANAR_TRUTH = "dl_mm = [1.0, -0.5, 0.8]\ndq_deg = [0.3, -0.2, 0.4]\nk_urad_per_Nm = [1.5, 3, 6]\n"

#: A six-axis truth with a ``[compliance]`` table for the virtual cell.
SPATIAL_TRUTH = (
    'robot = "cell.toml"\n'
    "base = { xyz_mm = [2850.0, -1700.0, -650.0], rpy_deg = [0.3, -0.2, 120.0] }\n"
    '[errors]\n"j2.y" = -0.2\ndq3 = -0.03\n[compliance]\nk2 = 0.2\nk3 = 0.4\n'
)


def _codes(stdout: str) -> list[str]:
    return [w["code"] for w in json.loads(stdout)["warnings"]]


def test_a_planar_demo_of_a_compliant_robot_warns_that_it_is_rigid(tmp_path):
    (tmp_path / "robot.toml").write_text(VERTICAL_3LINK)
    (tmp_path / "truth.toml").write_text(PLANAR_TRUTH)
    run = run_cli(tmp_path, "demo", "--robot", "robot.toml", "--truth", "truth.toml", "--json")
    assert run.returncode == 0, run.stderr
    assert "demo-rigid" in _codes(run.stdout)
    assert "the demo calibrates the geometry of vertical-3link alone" in run.stderr


def test_a_planar_demo_of_a_rigid_robot_does_not(tmp_path):
    rigid = VERTICAL_3LINK.split("[elastostatic]")[0]
    (tmp_path / "robot.toml").write_text(rigid)
    (tmp_path / "truth.toml").write_text("dl_mm = [1.0, -0.5, 0.8]\ndq_deg = [0.3, -0.2, 0.4]\n")
    run = run_cli(tmp_path, "demo", "--robot", "robot.toml", "--truth", "truth.toml", "--json")
    assert run.returncode == 0, run.stderr
    assert "demo-rigid" not in _codes(run.stdout)


def test_a_six_axis_demo_takes_a_truth_with_compliance(tmp_path):
    source = BUILTIN_SPATIAL_ROBOTS["industrial-6r"].with_suffix(".urdf")
    (tmp_path / "industrial-6r.urdf").write_text(source.read_text())
    (tmp_path / "cell.toml").write_text(cell_toml())
    (tmp_path / "truth.toml").write_text(SPATIAL_TRUTH)
    options = ("--robot", "cell.toml", "--truth", "truth.toml", "--poses", "12", "--json")
    run = run_cli(tmp_path, "demo", *options)
    assert run.returncode == 0, run.stderr
    assert "demo-rigid" in _codes(run.stdout)
    assert "no [elastostatic]" not in run.stderr


def test_a_rigid_planar_robot_refuses_a_truth_with_compliance(tmp_path):
    """synthesize on a robot without [elastostatic] cannot use the truth's compliance: it
    is refused (as for six-axis arms), not dropped; nothing is written."""
    (tmp_path / "robot.toml").write_text(VERTICAL_3LINK.split("[elastostatic]")[0])
    (tmp_path / "truth.toml").write_text(PLANAR_TRUTH)
    (tmp_path / "plan.csv").write_text("q1_deg,q2_deg,q3_deg\n0,10,20\n30,-40,50\n")
    options = ("--robot", "robot.toml", "--truth", "truth.toml", "--plan", "plan.csv")
    run = run_cli(tmp_path, "synthesize", *options, "-o", "meas.csv")
    assert run.returncode == 2
    assert run.stderr.startswith("armcal: error: truth.toml: key 'k_urad_per_Nm'")
    assert "no joint compliance" in run.stderr and run.stderr.count("\n") == 1
    assert not (tmp_path / "meas.csv").exists()
