"""A spatial calibration after identify: read back, validated, compensated and exported.

Every tolerance is the round-off of the arithmetic it checks (a few hundred
operations on millimetre values of up to 3 m: 1e-9 mm is a thousand times the
double-precision floor) or the contract's (PRODUCT.md, "Serial arms in 3-D":
export round-trips within 1e-9 mm; compensation reaches the nominal poses within
0.01 mm and 0.001 deg).
"""

from __future__ import annotations

import json

import numpy as np
import pytest

from armcal.compensation import MAX_AMPLIFICATION
from armcal.files import load_spatial_robot, read_calibration
from armcal.models import (
    SpatialArm,
    mdh_table,
    rotation_vector,
    vector_rotation,
)
from armcal.models.spatial.dh import PARALLEL_COS
from helpers import run_cli

ROBOTS = ("industrial-6r", "cobot-6r", "arm-7r")
LABELS = ("A", "B", "C")


def _truth(arm: SpatialArm, rng: np.random.Generator, scale: float = 1.0) -> np.ndarray:
    """Random errors of every joint's placement (0.3 mm, 0.05 deg) and zero, a tracker
    4 m away turned by 120 deg."""
    truth = arm.nominal.copy()
    robot = ~arm.instrument_params
    size = np.where(arm.layout.angles[robot], np.radians(0.05), 0.3) * scale
    truth[robot] += rng.normal(size=int(robot.sum())) * size
    truth[:6] = [-2000.0, 3464.1, -400.0, 0.01, -0.02, np.radians(120.0)]
    return truth


def _write(path, arm, q, points, targets, labels=None):
    head = ["pose", "target", *(f"q{k + 1}_deg" for k in range(arm.n_joints))]
    lines = [",".join([*head, "x_mm", "y_mm", "z_mm"])]
    for i in range(q.shape[0]):
        values = [
            *(repr(float(v)) for v in np.degrees(q[i])),
            *(repr(float(v)) for v in points[i]),
        ]
        pose = f"P{i // 3 + 1}" if labels is None else labels[i]
        lines.append(",".join([pose, targets[i], *values]))
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")


def _campaign(tmp_path, robot="industrial-6r", *, m=40, noise=0.0, seed=3, name="meas.csv"):
    """A virtual campaign of ``m`` poses with three reflectors: the arm and the truth."""
    rng = np.random.default_rng(seed)
    arm = load_spatial_robot(robot).arm.replace(
        targets=LABELS,
        target_positions=np.array([[100.0, 0.0, 150.0], [-50.0, 80.0, 150.0], [-50, -80, 150]]),
    )
    truth = _truth(arm, np.random.default_rng(100))
    lo, hi = arm.limits[:, 0], arm.limits[:, 1]
    q = lo + (hi - lo) * rng.uniform(0.25, 0.75, (m, arm.n_joints))
    cond = arm.plan_conditions(q)
    points = arm.positions(cond, truth) + rng.normal(scale=noise, size=(cond.m, 3)) * (noise > 0)
    _write(tmp_path / name, arm, cond.q, points, [LABELS[t] for t in cond.target])
    return arm, truth


# --------------------------------------------------------------------------- the DH table


def _calibrated_chains():
    rng = np.random.default_rng(7)
    for robot in ROBOTS:
        arm = load_spatial_robot(robot).arm
        yield robot, arm, arm.calibrated_chain(_truth(arm, rng, scale=3.0))


@pytest.mark.parametrize(("robot", "arm", "chain"), list(_calibrated_chains()))
def test_the_dh_table_of_a_calibrated_chain_is_exact(robot, arm, chain):
    table = mdh_table(chain)
    u = np.random.default_rng(1).uniform(-np.pi, np.pi, (500, chain.n_joints))
    got, want = table.chain().forward(u), chain.forward(u)
    assert np.max(np.abs(got[:, :3, 3] - want[:, :3, 3])) < 1e-9
    assert np.max(np.abs(got[:, :3, :3] - want[:, :3, :3])) < 1e-12
    # Hayati's angle only between nearly parallel axes; every row stays finite and short
    # (a plain DH table's d runs off to metres there: the built-ins reach less than 2 m).
    parallel = np.abs(chain.origins[1:, 2, 2]) >= PARALLEL_COS
    assert np.all(table.beta[1:][~parallel] == 0.0)
    assert np.max(np.abs(table.d)) < 2000.0 and np.max(np.abs(table.a)) < 2000.0


def test_the_dh_table_of_a_nominal_arm_is_its_published_one():
    """The UR5e's table as written in cobot-6r.toml (modified DH from the published one)."""
    table = mdh_table(load_spatial_robot("cobot-6r").arm.chain)
    np.testing.assert_allclose(np.degrees(table.alpha), [0, 90, 0, 0, 90, -90], atol=1e-9)
    np.testing.assert_allclose(table.a, [0, 0, -425, -392.2, 0, 0], atol=1e-9)
    np.testing.assert_allclose(table.d, [162.5, 0, 0, 133.3, 99.7, 99.6], atol=1e-9)
    np.testing.assert_allclose(table.beta, 0.0, atol=0)


@pytest.mark.parametrize("angle", [0.0, 1e-10, 1e-3, 1.0, 2.5, np.pi - 1e-6, np.pi])
def test_rotation_vectors_round_trip_at_every_angle(angle):
    axis = np.array([0.3, -0.5, 0.8]) / np.linalg.norm([0.3, -0.5, 0.8])
    rot = vector_rotation(axis * angle)
    back = vector_rotation(rotation_vector(rot))
    np.testing.assert_allclose(back, rot, rtol=0, atol=1e-12)
    np.testing.assert_allclose(rot @ rot.T, np.eye(3), rtol=0, atol=1e-15)


# --------------------------------------------------------------------------- the command line


def _identify(tmp_path, robot, name="meas.csv", out="cal.json"):
    args = ["identify", "--robot", robot, "--measurements", name, "--sigma", "0.03"]
    result = run_cli(tmp_path, *args, "-o", out, "--json")
    assert result.returncode == 0, result.stderr
    return json.loads(result.stdout)


def _corrections_over_std(document):
    """``|value| / std`` of every robot parameter the fit frees."""
    return np.array(
        [
            abs(p["value"]) / p["std"]
            for p in document["parameters"]
            if not p["fixed"] and not p["name"].startswith(("base.", *(f"{t}." for t in LABELS)))
        ]
    )


def test_export_round_trips_and_identifying_again_finds_nothing(tmp_path):
    arm, _ = _campaign(tmp_path, noise=0.03)
    _identify(tmp_path, "industrial-6r")
    result = run_cli(
        tmp_path,
        "export",
        "--calibration",
        "cal.json",
        "--urdf",
        "cal.urdf",
        "--robot-toml",
        "cal.toml",
        "--joint-offsets",
        "offsets.csv",
    )
    assert result.returncode == 0, result.stderr
    # The coupled J2/J3 of this arm: the URDF's joint values are M q, and it says so.
    assert "urdf-joint-values" not in result.stderr  # warnings print their text, not codes
    assert "joint values are M q" in result.stderr
    cal = read_calibration(tmp_path / "cal.json")
    model, robot = cal.in_robot_frame()
    q = np.random.default_rng(2).uniform(arm.limits[:, 0], arm.limits[:, 1], (500, 6))
    want = model.positions(
        model.conditions(np.repeat(q, 3, axis=0), target=np.tile([0, 1, 2], 500)), robot
    )
    u = q @ arm.joint_map.T
    chain = cal.arm.calibrated_chain(cal.arm_params)
    for exported in ("cal.urdf", "cal.toml"):
        back = load_spatial_robot(tmp_path / exported).arm
        frames = back.chain.forward(u)
        assert np.max(np.abs(frames[:, :3, 3] - chain.forward(u)[:, :3, 3])) < 1e-9
    back = load_spatial_robot(tmp_path / "cal.toml").arm  # with its targets and joint map
    got = back.positions(back.plan_conditions(q))
    assert back.targets == LABELS
    assert np.max(np.abs(got - want)) < 1e-9
    # A robot TOML pointing at the exported URDF, with the controller's joint map.
    (tmp_path / "urdf.toml").write_text(
        'urdf = "cal.urdf"\njoint_map = [[1,0,0,0,0,0],[0,1,0,0,0,0],[0,1,1,0,0,0],'
        "[0,0,0,1,0,0],[0,0,0,0,1,0],[0,0,0,0,0,1]]\n",
        encoding="utf-8",
    )
    first = json.loads((tmp_path / "cal.json").read_text(encoding="utf-8"))
    for robot_file in ("cal.toml", "urdf.toml"):
        again = _identify(tmp_path, robot_file, out=f"again-{robot_file}.json")
        # The same identifiable set (the names read alike), and nothing left to correct.
        assert len(_corrections_over_std(again)) == len(_corrections_over_std(first))
        assert np.max(_corrections_over_std(again)) < 1e-3
        assert again["residual_rms_mm"] == pytest.approx(first["residual_rms_mm"], rel=1e-9)
    offsets = (tmp_path / "offsets.csv").read_text(encoding="utf-8").splitlines()
    assert offsets[0] == "joint,offset,unit,std,identified"
    dq = {p["name"]: p["value"] for p in first["parameters"]}
    assert [float(line.split(",")[1]) for line in offsets[1:]] == [
        dq[f"dq{k}"] for k in range(1, 7)
    ]


def test_a_spatial_calibration_validates_and_compensates(tmp_path):
    arm, truth = _campaign(tmp_path)  # noiseless: the calibration is the truth
    _campaign(tmp_path, m=20, seed=11, name="test.csv")
    _identify(tmp_path, "industrial-6r")
    result = run_cli(
        tmp_path, "validate", "--calibration", "cal.json", "--measurements", "test.csv", "--json"
    )
    assert result.returncode == 0, result.stderr
    summary = json.loads(result.stdout)
    assert summary["rms_after_mm"] < 1e-6 < 0.1 < summary["rms_before_mm"]

    rng = np.random.default_rng(4)
    q0 = rng.uniform(arm.limits[:, 0] * 0.5, arm.limits[:, 1] * 0.5, (25, 6))
    lines = ["q1_deg,q2_deg,q3_deg,q4_deg,q5_deg,q6_deg,target"]
    lines += [",".join(repr(float(v)) for v in np.degrees(row)) + ",A" for row in q0]
    (tmp_path / "program.csv").write_text("\n".join(lines) + "\n", encoding="utf-8")
    result = run_cli(
        tmp_path,
        "compensate",
        "--calibration",
        "cal.json",
        "--program",
        "program.csv",
        "-o",
        "corrected.csv",
        "--json",
    )
    assert result.returncode == 0, result.stderr
    rows = (tmp_path / "corrected.csv").read_text(encoding="utf-8").splitlines()[1:]
    # A wrist within asin(1 / MAX_AMPLIFICATION) (2.9 deg) of J5 = 0 would turn J4 and J6 by
    # about 1 / sin(J5) times the tool's error to correct it (the compensation's bound):
    # here one row, 0.22 deg from it; every other J5 is 13 deg or more from 0.
    near = np.abs(np.sin(q0[:, 4])) < 1 / MAX_AMPLIFICATION
    assert np.count_nonzero(near) == 1
    assert [row.endswith(",0") for row in rows] == near.tolist()
    refused = json.loads(result.stdout)["uncorrectable"]
    assert [r["row"] - 1 for r in refused] == np.flatnonzero(near).tolist()
    assert all(r["reason"].startswith("near a singularity") for r in refused)
    q0 = q0[~near]
    q1 = np.radians([[float(v) for v in row.split(",")[:6]] for row in rows])[~near]
    # The true arm at the corrected commands puts the reflector body (all three) where the
    # nominal arm, standing where the calibration found it, puts it at the program's commands.
    cal = read_calibration(tmp_path / "cal.json")
    every = np.tile(np.arange(3), len(q0))
    reached = arm.positions(arm.conditions(np.repeat(q1, 3, axis=0), target=every), truth)
    meant = cal.positions(
        cal.model.conditions(np.repeat(q0, 3, axis=0), target=every), cal.instrument_pose_params()
    )
    assert np.max(np.linalg.norm(reached - meant, axis=1)) < 0.01
    turn = _triad(reached.reshape(-1, 3, 3)) @ np.swapaxes(_triad(meant.reshape(-1, 3, 3)), 1, 2)
    assert np.degrees(np.max(np.linalg.norm(rotation_vector(turn), axis=1))) < 0.001


def _triad(points):
    """The frame ``(m, 3, 3)`` of three points per row: x along A->B, z normal to the plane."""
    x = points[:, 1] - points[:, 0]
    x /= np.linalg.norm(x, axis=1, keepdims=True)
    z = np.cross(x, points[:, 2] - points[:, 0])
    z /= np.linalg.norm(z, axis=1, keepdims=True)
    return np.stack([x, np.cross(z, x), z], axis=2)


def test_validation_warns_when_the_calibration_is_worse_than_nominal(tmp_path):
    arm, _ = _campaign(tmp_path, noise=0.03)
    _identify(tmp_path, "industrial-6r")
    # Held-out points of an arm without the errors, seen from where the tracker stood: the
    # nominal arm registered on its own to the calibration's rows (its baseline).
    rng = np.random.default_rng(9)
    q = rng.uniform(arm.limits[:, 0] * 0.5, arm.limits[:, 1] * 0.5, (20, 6))
    cal = read_calibration(tmp_path / "cal.json")
    cond = arm.plan_conditions(q)
    points = cal.baseline_positions(cal.model.conditions(cond.q, target=cond.target))
    _write(tmp_path / "other.csv", arm, cond.q, points, [LABELS[t] for t in cond.target])
    result = run_cli(
        tmp_path, "validate", "--calibration", "cal.json", "--measurements", "other.csv"
    )
    assert result.returncode == 0, result.stderr
    assert "worse than the nominal arm" in result.stderr
    assert "misses the held-out poses" in result.stderr
    document = json.loads(
        run_cli(
            tmp_path, "validate", "--calibration", "cal.json", "--measurements", "other.csv",
            "--json",
        ).stdout
    )  # fmt: skip
    # The nominal arm is the held-out points' own arm: it misses them by round-off only.
    assert document["rms_before_mm"] < 1e-9
    assert "calibration-worse" in [w["code"] for w in document["warnings"]]
