"""Universal Robots' kinematics: nominal DH tables, the controller's calibration.conf.

The reference forward kinematics here is the standard DH product written out
from its definition, ``prod_k Rz(q_k + theta_k) Tz(d_k) Tx(a_k) Rx(alpha_k)``,
independently of :meth:`SerialChain.from_dh`.  A UR's calibrated ``d`` of joints
2-4 reaches hundreds of metres (1e6 mm) that cancel: round-off of 1e-16 relative
on them is 1e-10 mm, so 1e-9 mm is the tolerance.
"""

from __future__ import annotations

import re

import numpy as np
import pytest

from armcal.errors import InputError
from armcal.files import load_spatial_robot
from armcal.files.ur import (
    UR_QUARTER_TURN,
    UrDh,
    format_ur_calibration,
    read_ur_calibration,
    ur_chain,
    ur_nominal,
)
from armcal.models import SerialChain

#: A UR10e's factory deltas as its controller keeps them (a public backup of a robot's
#: ``.urcontrol`` folder, calibration.conf of backup 125 of savidini/match_ur_control_backup),
#: with its other keys: d of joints 2-4 of +682, -696 and +15 metres that cancel.
UR10E_CALIBRATION = """[mounting]
delta_theta = [ -1.42409238054752585e-07, 0.673081443308028327, -0.822266214665732353, 0.14918860720820884, 1.21819269359099702e-06, 4.74135274097786663e-09]
delta_a = [ 0.000105082885035665083, 0.13393666435952839, 0.00668965589666981053, -1.03771180147864596e-05, 1.02814638390100225e-05, 0]
delta_d = [ 0.00024797136309920309, 681.73431323723787, -696.406678436933362, 14.6725337865507761, -0.000155363952597867283, -0.000962434056788766257]
delta_alpha = [ -0.000421674746571953918, 0.000559910002678443565, 0.00578643598516057414, -0.00128672498842785643, 0.000457574204941302298, 0]
joint_checksum = [ 0xb435bb63, 0xb441d7b1, 0xb5198b08, 0xb40d9f92, 0xb41b2338, 0xb42edc4e]
calibration_status = 2 # 0 == notInitialized / 1 == notLinearised / 2 == Linearised
file_save_count = 1
"""  # noqa: E501


def dh_forward(q: np.ndarray, theta, d, a, alpha) -> np.ndarray:
    """The flange positions (mm) of a standard DH table (m, rad), from the definition."""
    out = []
    for pose in q:
        frame = np.eye(4)
        for k in range(len(theta)):
            c, s = np.cos(pose[k] + theta[k]), np.sin(pose[k] + theta[k])
            ca, sa = np.cos(alpha[k]), np.sin(alpha[k])
            frame = frame @ np.array(
                [
                    [c, -s * ca, s * sa, a[k] * c],
                    [s, c * ca, -c * sa, a[k] * s],
                    [0.0, sa, ca, d[k]],
                    [0.0, 0.0, 0.0, 1.0],
                ]
            )
        out.append(1000.0 * frame[:3, 3])
    return np.array(out)


def _robot(tmp_path, text: str = UR10E_CALIBRATION, model: str = "ur10e"):
    (tmp_path / "calibration.conf").write_text(text, encoding="utf-8")
    robot = tmp_path / "ur.toml"
    robot.write_text(
        f'name = "cell-ur"\n[ur]\nmodel = "{model}"\ncalibration = "calibration.conf"\n',
        encoding="utf-8",
    )
    return load_spatial_robot(robot)


def test_a_dh_chain_is_the_dh_product_even_with_cancelling_metres():
    rng = np.random.default_rng(0)
    theta, alpha = rng.uniform(-np.pi, np.pi, (2, 6))
    a = rng.uniform(-0.6, 0.6, 6)
    d = np.array([0.2, 700.0, -700.0, 0.1, 0.1, 0.1]) + rng.uniform(-1e-3, 1e-3, 6)
    q = rng.uniform(-np.pi, np.pi, (50, 6))
    chain = SerialChain.from_dh(theta, 1000 * d, 1000 * a, alpha)
    found = chain.forward(q)[:, :3, 3]
    np.testing.assert_allclose(found, dh_forward(q, theta, d, a, alpha), rtol=0, atol=1e-9)


def test_the_nominal_ur5e_at_zero_is_where_its_table_says():
    """At q = 0 a UR's arm lies along -x: the flange at (a2 + a3, -(d4 + d6), d1 - d5),
    (-817.2, -232.9, 62.8) mm for a UR5e (UR_MODELS); the controller's twist 1.570796327
    differs from pi/2 by 2.1e-10 rad, 2.1e-7 mm at a metre."""
    flange = ur_chain(ur_nominal("ur5e")).forward(np.zeros(6))[:3, 3]
    np.testing.assert_allclose(flange, [-817.2, -232.9, 62.8], rtol=0, atol=1e-6)
    assert abs(UR_QUARTER_TURN - np.pi / 2) < 2.1e-10


def test_a_ur_robot_file_reads_the_controller_s_calibration(tmp_path):
    """The robot file's arm is the nominal UR10e plus the file's deltas, as the controller
    adds them: its flange agrees with the DH product within 1e-9 mm, although d holds
    metres; and a factory calibration moves the flange a few mm from the nominal, so
    nothing is flagged."""
    spec = _robot(tmp_path)
    assert spec.warnings == ()
    arm = spec.arm
    assert arm.n_joints == 6 and arm.chain.joint_names[0] == "shoulder_pan"
    deltas = read_ur_calibration(tmp_path / "calibration.conf")
    assert deltas.d[1] == 681.73431323723787  # the file's digits, read exactly
    table = ur_nominal("ur10e") + deltas
    q = np.random.default_rng(1).uniform(-2 * np.pi, 2 * np.pi, (200, 6))
    expected = dh_forward(q, table.theta, table.d, table.a, table.alpha)
    np.testing.assert_allclose(arm.chain.forward(q)[:, :3, 3], expected, rtol=0, atol=1e-9)
    nominal = ur_chain(ur_nominal("ur10e")).forward(q)[:, :3, 3]
    moved = np.linalg.norm(expected - nominal, axis=1)
    assert 0.1 < moved.max() < 5.0
    np.testing.assert_array_equal(np.degrees(arm.joint_limits), np.tile([-360, 360], (6, 1)))


def test_the_deltas_round_trip_through_the_controller_s_text_exactly(tmp_path):
    deltas = read_ur_calibration(_write(tmp_path, UR10E_CALIBRATION))
    again = read_ur_calibration(_write(tmp_path, format_ur_calibration(deltas), "out.conf"))
    for name in ("theta", "a", "d", "alpha"):
        np.testing.assert_array_equal(getattr(again, name), getattr(deltas, name))
    written = format_ur_calibration(deltas).splitlines()
    assert written[0] == "[mounting]"
    assert written[3].startswith("delta_d = [ 0.00024797136309920309, 681.73431323723787,")


def test_deltas_in_the_wrong_unit_are_flagged(tmp_path):
    """Millimetres where the controller writes metres move the flange by kilometres."""
    deltas = read_ur_calibration(_write(tmp_path, UR10E_CALIBRATION))
    scaled = UrDh(deltas.theta, 1000 * deltas.a, 1000 * deltas.d, deltas.alpha)
    spec = _robot(tmp_path, format_ur_calibration(scaled))
    (warning,) = spec.warnings
    assert warning.code == "ur-calibration-far" and "metres and radians" in warning.message


def _write(tmp_path, text: str, name: str = "calibration.conf"):
    path = tmp_path / name
    path.write_text(text, encoding="utf-8")
    return path


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("[other]\nx = 1\n", "has no 'delta_theta' and no [mounting] section"),
        (
            UR10E_CALIBRATION.replace("delta_alpha", "delta_beta"),
            "has no 'delta_alpha': a UR controller's calibration.conf",
        ),
        (
            UR10E_CALIBRATION.replace(", 0]\njoint", "]\njoint"),
            "line 5: key 'delta_alpha': expected six numbers",
        ),
        (
            UR10E_CALIBRATION.replace("-0.000421674746571953918", "abc"),
            "line 5: key 'delta_alpha': expected six numbers",
        ),
    ],
    ids=["no-section", "missing-key", "five-values", "not-a-number"],
)
def test_a_bad_calibration_file_is_refused_with_its_line_and_key(tmp_path, text, message):
    with pytest.raises(InputError, match=re.escape(message)):
        read_ur_calibration(_write(tmp_path, text))


@pytest.mark.parametrize(
    ("body", "message"),
    [
        ('[ur]\nmodel = "ur4"\n', "key 'ur.model': expected one of ur3, ur5"),
        ('[ur]\nmodel = "ur5e"\ncalibration = "none.conf"\n', "key 'ur.calibration': "),
        ('urdf = "x.urdf"\n[ur]\nmodel = "ur5e"\n', "keys urdf and ur all describe the arm"),
        ('[ur]\nmodel = "ur5e"\nmass = 3\n', "ur.mass"),
    ],
    ids=["unknown-model", "missing-file", "two-descriptions", "unknown-key"],
)
def test_a_bad_ur_table_is_refused(tmp_path, body, message):
    robot = tmp_path / "ur.toml"
    robot.write_text(body, encoding="utf-8")
    with pytest.raises(InputError, match=re.escape(message)):
        load_spatial_robot(robot)


def test_a_ur_robot_file_works_through_the_commands(tmp_path):
    """design on the calibrated UR10e; a broken calibration.conf stops a command with one
    line naming the file, the line and the key."""
    from helpers import run_cli

    _robot(tmp_path)
    result = run_cli(tmp_path, "design", "--robot", "ur.toml", "--poses", "20", "-o", "p.csv")
    assert result.returncode == 0, result.stderr
    assert (tmp_path / "p.csv").read_text(encoding="utf-8").startswith("q1_deg,")
    broken = UR10E_CALIBRATION.replace("delta_d = [ 0.0002", "delta_d = [ x0.0002")
    (tmp_path / "calibration.conf").write_text(broken, encoding="utf-8")
    result = run_cli(tmp_path, "design", "--robot", "ur.toml", "--poses", "20", "-o", "q.csv")
    assert result.returncode == 2 and not (tmp_path / "q.csv").exists()
    (line,) = result.stderr.strip().splitlines()
    assert line.startswith("armcal: error: ") and "line 4: key 'delta_d'" in line


def test_a_calibrated_chain_becomes_deltas_that_read_back_to_it(tmp_path):
    """Perturb every joint placement of a UR10e after joint 1 (0.3 mm, 1 mrad: axes 2-4
    no longer parallel), write the deltas in the controller's text, read them back onto
    the nominal table: the same kinematics within 1e-9 mm, although the deltas' d reach
    hundreds of metres."""
    from dataclasses import replace

    from armcal.files.ur import ur_deltas
    from armcal.models.spatial.chain import elementary, transform

    rng = np.random.default_rng(2)
    nominal = ur_chain(ur_nominal("ur10e"))
    origins = nominal.origins.copy()
    for k in range(1, 6):
        turn = elementary(0, rng.normal(0, 1e-3)) @ elementary(1, rng.normal(0, 1e-3))
        origins[k] = origins[k] @ transform(turn @ elementary(2, rng.normal(0, 1e-3)),
                                            rng.normal(0, 0.3, 3))  # fmt: skip
    calibrated = replace(nominal, origins=origins)
    deltas = ur_deltas(calibrated, "ur10e")
    assert np.max(np.abs(deltas.d)) > 10.0  # metres: the common normals of near-parallel axes
    read = read_ur_calibration(_write(tmp_path, format_ur_calibration(deltas)))
    again = ur_chain(ur_nominal("ur10e") + read)
    q = rng.uniform(-2 * np.pi, 2 * np.pi, (300, 6))
    found, expected = again.forward(q), calibrated.forward(q)
    np.testing.assert_allclose(found[:, :3, 3], expected[:, :3, 3], rtol=0, atol=1e-9)
    np.testing.assert_allclose(found[:, :3, :3], expected[:, :3, :3], rtol=0, atol=1e-12)
    # The real UR10e's own deltas come back to themselves (to round-off of their metres).
    real = read_ur_calibration(_write(tmp_path, UR10E_CALIBRATION))
    back = ur_deltas(ur_chain(ur_nominal("ur10e") + real), "ur10e")
    chain_back = ur_chain(ur_nominal("ur10e") + back).forward(q)[:, :3, 3]
    chain_real = ur_chain(ur_nominal("ur10e") + real).forward(q)[:, :3, 3]
    np.testing.assert_allclose(chain_back, chain_real, rtol=0, atol=1e-9)


def test_a_ur_cell_calibrated_and_exported_for_its_controller(tmp_path):
    """The UR10e of the robot file (its factory deltas) is measured as a virtual arm whose
    truth moves joints 2-5 (0.2 mm, 0.02 deg); identify, export --ur-calibration, and a
    robot file on the exported deltas is the calibrated arm: its flange agrees with the
    calibration's chain within 1e-9 mm."""
    import json

    from armcal.files import read_calibration
    from helpers import run_cli

    _robot(tmp_path)
    truth = tmp_path / "truth.toml"
    truth.write_text(
        'robot = "ur.toml"\nbase = { xyz_mm = [2500, -800, -400], rpy_deg = [0, 0, 30] }\n'
        "[errors]\n"
        + "".join(f"j{k}.x = 0.2\nj{k}.rx = 0.02\n" for k in (2, 3, 4, 5))
        + "[targets]\ntool = { xyz_mm = [0, 0, 60] }\n",
        encoding="utf-8",
    )
    steps = [
        ("design", "--robot", "ur.toml", "--poses", "40", "-o", "plan.csv"),
        ("synthesize", "--robot", "ur.toml", "--truth", "truth.toml", "--plan", "plan.csv",
         "--sigma", "0", "-o", "meas.csv"),
        ("identify", "--robot", "ur.toml", "--measurements", "meas.csv", "-o", "cal.json"),
        ("export", "--calibration", "cal.json", "--ur-calibration", "out.conf",
         "--ros-calibration", "out.yaml", "--json"),
    ]  # fmt: skip
    for step in steps:
        result = run_cli(tmp_path, *step)
        assert result.returncode == 0, (step[0], result.stderr)
    assert json.loads(result.stdout)["ur_calibration"] == "out.conf"
    robot = tmp_path / "exported.toml"
    robot.write_text('[ur]\nmodel = "ur10e"\ncalibration = "out.conf"\n', encoding="utf-8")
    exported = load_spatial_robot(robot)
    assert exported.warnings == ()
    cal = read_calibration(tmp_path / "cal.json")
    chain = cal.arm.calibrated_chain(cal.arm_params)
    q = np.random.default_rng(3).uniform(-np.pi, np.pi, (100, 6))
    np.testing.assert_allclose(
        exported.arm.chain.forward(q)[:, :3, 3], chain.forward(q)[:, :3, 3], rtol=0, atol=1e-9
    )
    robot.write_text('[ur]\nmodel = "ur10e"\ncalibration = "out.yaml"\n', encoding="utf-8")
    ros = load_spatial_robot(robot)  # the ROS driver's YAML: the joint frames themselves
    assert ros.warnings == ()
    np.testing.assert_allclose(
        ros.arm.chain.forward(q)[:, :3, 3], chain.forward(q)[:, :3, 3], rtol=0, atol=1e-9
    )


def test_what_the_robot_file_warns_of_reaches_the_calibration(tmp_path):
    """The calibration.conf in millimetres warns ``ur-calibration-far`` when read; the
    calibration made with that robot file carries the warning on (identify reported
    nothing of it before)."""
    from dataclasses import replace

    from armcal.files import read_measurements
    from armcal.workflow import calibrate
    from helpers import run_cli

    spec = _robot(tmp_path)
    (tmp_path / "truth.toml").write_text(
        'robot = "ur.toml"\nbase = { xyz_mm = [2500, -800, -400], rpy_deg = [0, 0, 30] }\n',
        encoding="utf-8",
    )
    for step in (
        ("design", "--robot", "ur.toml", "--poses", "30", "-o", "plan.csv"),
        ("synthesize", "--robot", "ur.toml", "--truth", "truth.toml", "--plan", "plan.csv",
         "--sigma", "0.01", "-o", "meas.csv"),
    ):  # fmt: skip
        assert run_cli(tmp_path, *step).returncode == 0, step
    deltas = read_ur_calibration(_write(tmp_path, UR10E_CALIBRATION))
    scaled = UrDh(deltas.theta, 1000 * deltas.a, 1000 * deltas.d, deltas.alpha)
    (far,) = _robot(tmp_path, format_ur_calibration(scaled)).warnings
    run = calibrate(
        replace(spec, warnings=(far,)), read_measurements(tmp_path / "meas.csv", spec.arm)
    )
    assert far in run.warnings


#: The ROS description's nominal UR5e (Universal_Robots_ROS2_Description,
#: config/ur5e/default_kinematics.yaml): the controller's DH table with its twist
#: 1.570796327 as the driver's calibration tool writes it, R = Rx(roll) Ry(pitch) Rz(yaw).
UR5E_DEFAULT_KINEMATICS = """kinematics:
  shoulder:
    x: 0
    y: 0
    z: 0.1625
    roll: 0
    pitch: 0
    yaw: 0
  upper_arm: {x: 0, y: 0, z: 0, roll: 1.570796327, pitch: 0, yaw: 0}
  forearm:
    x: -0.425
    y: 0
    z: 0
    roll: 0
    pitch: 0
    yaw: 0
  wrist_1:
    x: -0.3922
    y: 0
    z: 0.1333
    roll: 0
    pitch: 0
    yaw: 0
  wrist_2:
    x: 0
    y: -0.0997
    z: -2.044881182297852e-11
    roll: 1.570796327
    pitch: 0
    yaw: 0
  wrist_3:
    x: 0
    y: 0.09959999999999999
    z: -2.042830148012698e-11
    roll: 1.570796326589793
    pitch: 3.141592653589793
    yaw: 3.141592653589793
  hash: calib_12788084448423163542
"""


def test_the_ros_description_s_nominal_ur5e_is_the_dh_table(tmp_path):
    """Its YAML (block and flow entries) read in the driver's angle order is the nominal
    UR5e table's kinematics within 1e-9 mm, flange frame included; written again and
    read back, the same."""
    from armcal.files.ur import format_ur_kinematics, read_ur_kinematics

    chain = read_ur_kinematics(_write(tmp_path, UR5E_DEFAULT_KINEMATICS, "ur5e.yaml"))
    nominal = ur_chain(ur_nominal("ur5e"))
    q = np.random.default_rng(4).uniform(-np.pi, np.pi, (100, 6))
    np.testing.assert_allclose(chain.forward(q), nominal.forward(q), rtol=0, atol=1e-9)
    written = format_ur_kinematics(nominal, "ur5e", "x")
    again = read_ur_kinematics(_write(tmp_path, written, "o.yaml"))
    np.testing.assert_allclose(again.forward(q), nominal.forward(q), rtol=0, atol=1e-9)
    # Every joint frame where the ROS description has it (its links' meshes hang there).
    np.testing.assert_allclose(again.origins, chain.origins, rtol=0, atol=1e-9)


def test_a_ros_yaml_without_a_frame_is_refused(tmp_path):
    from armcal.files.ur import read_ur_kinematics

    text = UR5E_DEFAULT_KINEMATICS.replace("    yaw: 3.141592653589793\n", "")
    with pytest.raises(InputError, match=re.escape("kinematics.wrist_3.yaw is missing")):
        read_ur_kinematics(_write(tmp_path, text, "bad.yaml"))
    for bad in ("0.13x", "nan", "inf"):
        text = UR5E_DEFAULT_KINEMATICS.replace("z: 0.1333", f"z: {bad}")
        with pytest.raises(InputError, match=re.escape("line 20: 'z': expected a number")):
            read_ur_kinematics(_write(tmp_path, text, "bad.yaml"))


def test_a_zero_offset_is_the_controller_s_theta_delta_with_its_sign(tmp_path):
    """armcal's dq_k is added to the reading (u = q + dq); a UR's joint angle is q + theta:
    a calibration that only moves joint 3's zero by +0.01 deg writes delta_theta[2] larger
    by 0.01 deg (in rad) and every other delta as it was (docs/controllers.md)."""
    from armcal.files.ur import ur_deltas

    arm = _robot(tmp_path).arm
    params = arm.nominal.copy()
    params[arm.param_names.index("dq3")] = np.radians(0.01)
    found = ur_deltas(arm.calibrated_chain(params), "ur10e")
    factory = read_ur_calibration(tmp_path / "calibration.conf")
    change = found.theta - factory.theta
    np.testing.assert_allclose(change, [0, 0, np.radians(0.01), 0, 0, 0], rtol=0, atol=1e-12)
    for name, scale in (("a", 1e-12), ("d", 1e-9), ("alpha", 1e-12)):  # m, rad; d in metres
        np.testing.assert_allclose(getattr(found, name), getattr(factory, name), atol=scale)


def test_what_a_ur_table_cannot_hold_is_refused_with_the_file(tmp_path):
    """A tip off the last axis (delta_a[5]) still has a DH row; a joint 1 tilted from the
    base's z has none, and export says why in one line instead of a traceback."""
    from dataclasses import replace

    from armcal.files.ur import ur_deltas
    from armcal.models.spatial.chain import elementary, transform

    deltas = read_ur_calibration(_write(tmp_path, UR10E_CALIBRATION))
    offset = UrDh(deltas.theta, deltas.a + np.array([0, 0, 0, 0, 0, 1e-4]), deltas.d, deltas.alpha)
    chain = ur_chain(ur_nominal("ur10e") + offset)
    back = ur_deltas(chain, "ur10e")
    q = np.random.default_rng(5).uniform(-np.pi, np.pi, (50, 6))
    again = ur_chain(ur_nominal("ur10e") + back).forward(q)[:, :3, 3]
    np.testing.assert_allclose(again, chain.forward(q)[:, :3, 3], rtol=0, atol=1e-9)
    tilted = chain.origins.copy()
    tilted[0] = transform(elementary(0, 1e-3), [0.2, 0.0, 0.0])
    with pytest.raises(ValueError, match="joint 1's axis is not the base frame's z"):
        ur_deltas(replace(chain, origins=tilted), "ur10e")
