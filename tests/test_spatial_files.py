"""Spatial robot files: the built-in arms, URDF against DH, and identify from the command line."""

from __future__ import annotations

import json

import numpy as np
import pytest

from armcal.files import BUILTIN_SPATIAL_ROBOTS, load_spatial_robot, read_measurements
from armcal.models import SerialChain
from armcal.workflow import calibrate
from helpers import run_cli


def test_the_built_in_arms_load_with_their_published_joint_counts():
    counts = {"industrial-6r": 6, "cobot-6r": 6, "arm-7r": 7}
    for name in BUILTIN_SPATIAL_ROBOTS:
        assert load_spatial_robot(name).arm.n_joints == counts[name]


def test_the_industrial_urdf_is_its_dh_table():
    """The table of the URDF's opening comment (FANUC R-2000iC/165F dimensions)."""
    arm = load_spatial_robot("industrial-6r").arm
    table = SerialChain.from_mdh(
        np.radians([0, -90, 180, -90, 90, -90]),
        [0, 312, 1075, 225, 0, 0],
        np.radians([0, -90, 0, 0, 0, 0]),
        [0, 0, 0, -1280, 0, -215],
    )
    u = np.random.default_rng(0).uniform(-2, 2, (20, 6))
    np.testing.assert_allclose(
        arm.chain.forward(u)[:, :3, 3], table.forward(u)[:, :3, 3], rtol=0, atol=1e-9
    )
    # The controller reads J3 from the horizon: the URDF's elbow is J2 + J3.
    assert arm.joint_map[2].tolist() == [0, 1, 1, 0, 0, 0]


def test_the_seven_axis_arm_ignores_the_fingers_and_ends_at_the_flange():
    arm = load_spatial_robot("arm-7r").arm
    assert arm.chain.joint_names == tuple(f"panda_joint{k}" for k in range(1, 8))
    assert arm.chain.tip[:3, 3].tolist() == pytest.approx([0.0, 0.0, 107.0])


def _measurements(path, rng, noise=0.03):
    arm = load_spatial_robot("industrial-6r").arm.replace(
        targets=("A", "B", "C"), target_positions=np.zeros((0, 3))
    )
    truth = arm.nominal.copy()
    lay = arm.layout
    truth[6 : lay.target_start] = rng.normal(size=lay.target_start - 6) * 0.003
    truth[:6] = [-2000.0, 3464.1, -400.0, 0.0, 0.0, np.radians(120.0)]  # 4 m away, 120 deg
    truth[lay.target_start :] = [100, 0, 150, -50, 80, 150, -50, -80, 150]
    lo, hi = arm.limits[:, 0], arm.limits[:, 1]
    q = lo + (hi - lo) * rng.uniform(0.25, 0.75, (40, 6))
    cond = arm.plan_conditions(q)
    points = arm.positions(cond, truth) + rng.normal(scale=noise, size=(cond.m, 3))
    lines = ["pose,target,q1_deg,q2_deg,q3_deg,q4_deg,q5_deg,q6_deg,x_mm,y_mm,z_mm"]
    for i in range(cond.m):
        angles = ",".join(f"{v:.10f}" for v in np.degrees(cond.q[i]))
        xyz = ",".join(f"{v:.6f}" for v in points[i])
        lines.append(f"P{i // 3 + 1},{'ABC'[cond.target[i]]},{angles},{xyz}")
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    return arm, truth


def test_identify_a_six_axis_arm_with_three_reflectors_from_the_command_line(tmp_path):
    _measurements(tmp_path / "meas.csv", np.random.default_rng(1))
    result = run_cli(
        tmp_path,
        "identify",
        "--robot",
        "industrial-6r",
        "--measurements",
        "meas.csv",
        "--sigma",
        "0.03",
        "--cross-validate",
        "5",
        "--json",
    )
    assert result.returncode == 0, result.stderr
    document = json.loads(result.stdout)
    assert document["robot"]["kind"] == "spatial"
    free = [p for p in document["parameters"] if not p["fixed"]]
    assert len(free) == 33  # 4R + 3k for 6 revolute joints and 3 reflectors
    assert any("joints 2 and 3 are parallel" in s for s in document["robot"]["merges"])
    assert document["converged"]
    assert "cross_validation" in document


def test_noiseless_measurements_from_a_file_are_recovered(tmp_path):
    arm, truth = _measurements(tmp_path / "meas.csv", np.random.default_rng(2), noise=0.0)
    spec = load_spatial_robot("industrial-6r")
    run = calibrate(spec, read_measurements(tmp_path / "meas.csv", spec.arm))
    cal = run.calibration
    rows = arm.plan_conditions(np.random.default_rng(3).uniform(-1, 1, (50, 6)))
    # 1e-6 mm: the file holds the points to 1e-6 mm and the angles to 1e-10 deg.
    error = cal.model.positions(rows, cal.params) - arm.positions(rows, truth)
    assert np.max(np.abs(error)) < 1e-5
