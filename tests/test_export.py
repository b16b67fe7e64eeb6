"""Export: the calibrated arm as a robot file and as URDF, both reproducing its kinematics."""

import json
import math
import sys
import xml.etree.ElementTree as ET

import numpy as np
import pytest
from numpy.testing import assert_allclose

from armcal import PlanarArm, forward_kinematics, identify, load_robot
from armcal.cli import main
from armcal.doe import random_plan
from armcal.export_planar import folded_arm, robot_toml, urdf, urdf_joint_values
from armcal.files import calibration_document, read_calibration, to_json
from armcal.models import Annulus, Box, CalibratedArm, Target, tool_angles
from armcal.noise import NoiseModel
from helpers import run_cli

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover - Python 3.10
    import tomli as tomllib

#: Position agreement (mm) the exports promise: round-off of sums of a few link vectors
#: of a few hundred mm (1e-13 mm) with a wide margin, far below any instrument's noise.
POSITION_ATOL_MM = 1e-9
#: Direction agreement (rad): round-off of sums of a few angles of order 1.
ANGLE_ATOL_RAD = 1e-12


def _cal(arm: PlanarArm, params: np.ndarray) -> CalibratedArm:
    return CalibratedArm(arm, params, np.zeros((arm.n_params, arm.n_params)), 0.1)


def _random_params(arm: PlanarArm, rng: np.random.Generator) -> np.ndarray:
    """Deviations of a few mm and about a degree (base pose: tens of mm, degrees); fixed ones 0."""
    k = arm.n_links
    params = np.concatenate(
        [
            rng.uniform(-2.0, 2.0, k),
            np.radians(rng.uniform(-1.0, 1.0, k)),
            rng.uniform(-50.0, 50.0, 2) if arm.base_offset else [],
            np.radians(rng.uniform(-20.0, 20.0, 1)) if arm.base_rotation else [],
        ]
    )
    return np.where(arm.free, params, 0.0)


def paper_cal() -> CalibratedArm:
    """The paper's 4-link arm with its deviations."""
    spec = load_robot("paper-4link")
    return _cal(spec.arm, spec.default_truth)


def coupled_cal() -> CalibratedArm:
    """3 links, joint 2 reversed, joint 3 read from the horizon, nominal offsets, 3 targets."""
    arm = PlanarArm(
        [300.0, 220.0, 120.0],
        np.radians([[-170.0, 170.0], [-135.0, 135.0], [-200.0, 200.0]]),
        name="nest-arm",
        joint_map=[[1, 0, 0], [1, -1, 0], [0, 0, 1]],
        joint_offsets=np.radians([2.0, -3.0, 5.0]),
        targets=[Target("A", 120.0, 0.3), Target("B", 90.0, -0.5), Target("C", 150.0, 1.2)],
        noise=NoiseModel.per_axis(0.05, 0.02, np.radians(0.003)),
        region=Box((-400.0, 600.0), (-500.0, 500.0)),
        fixed=["dl3@C"],
    )
    return _cal(arm, _random_params(arm, np.random.default_rng(11)))


def reversed_cal() -> CalibratedArm:
    """3 links with joint 2 counted the other way round: URDF joint values are the readings."""
    arm = PlanarArm(
        [250.0, 200.0, 80.0],
        name="reversed-arm",
        joint_map=[[1, 0, 0], [1, -1, 0], [1, -1, 1]],
        joint_offsets=np.radians([0.0, 10.0, -4.0]),
        region=Annulus((0.0, 0.0), 100.0, 500.0),
    )
    return _cal(arm, _random_params(arm, np.random.default_rng(12)))


def rotation_cal() -> CalibratedArm:
    """The 4-link arm calibrated from 3-D data: base offset and base rotation (dq1 held)."""
    arm = load_robot("paper-4link").arm.replace(
        base_offset=True, base_rotation=True, sigma=0.05, fixed=["dl4"]
    )
    return _cal(arm, _random_params(arm, np.random.default_rng(13)))


CASES = {
    "paper-4link": paper_cal,
    "coupled-targets": coupled_cal,
    "reversed": reversed_cal,
    "base-rotation": rotation_cal,
}


def _poses(arm: PlanarArm, seed: int, m: int = 200) -> tuple[np.ndarray, np.ndarray | None]:
    """Random readings within the limits, and every row's target (cycling) for several."""
    q = random_plan(arm, m, rng=seed)
    target = np.arange(m) % arm.n_target_links if arm.targets else None
    return q, target


@pytest.fixture(params=list(CASES))
def cal(request) -> CalibratedArm:
    return CASES[request.param]()


def _exported_arm(cal: CalibratedArm, tmp_path) -> PlanarArm:
    path = tmp_path / "calibrated.toml"
    path.write_text(robot_toml(cal), encoding="utf-8")
    spec = load_robot(path)
    assert spec.warnings == ()
    return spec.arm


# --------------------------------------------------------------------------- robot TOML


def test_robot_file_reproduces_the_calibrated_kinematics(cal, tmp_path):
    exported = _exported_arm(cal, tmp_path)
    q, target = _poses(cal.arm, seed=1)
    expected = forward_kinematics(cal.arm, q, cal.robot_params(), target=target)
    assert_allclose(
        forward_kinematics(exported, q, None, target=target),
        expected,
        rtol=0,
        atol=POSITION_ATOL_MM,
    )
    assert_allclose(
        tool_angles(exported, q, None, target=target),
        tool_angles(cal.arm, q, cal.robot_params(), target=target),
        rtol=0,
        atol=ANGLE_ATOL_RAD,
    )


def test_robot_file_keeps_the_robot_and_drops_the_base_pose(cal, tmp_path):
    arm = cal.arm
    exported = _exported_arm(cal, tmp_path)
    assert exported.name == arm.name + "-calibrated"
    assert_allclose(exported.joint_limits, arm.joint_limits, rtol=1e-15, atol=0)
    assert np.array_equal(exported.joint_map, arm.joint_map)
    assert exported.base_offset == arm.base_offset and not exported.base_rotation
    assert exported.target_labels == arm.target_labels
    assert exported.region == arm.region
    if arm.noise is None:
        assert exported.noise is None
    else:
        assert exported.noise is not None
        assert_allclose(
            exported.noise.covariance_mm2, arm.noise.covariance_mm2, rtol=1e-15, atol=0
        )
        if arm.noise.joint_sigma is None:
            assert exported.noise.joint_sigma is None
        else:
            assert_allclose(exported.noise.joint_sigma, arm.noise.joint_sigma, rtol=1e-15)
    # The joint offset held only for the base rotation is not fixed in the robot's frame.
    held = {arm.rotation_partner} if arm.base_rotation else set()
    assert set(exported.fixed) == set(arm.fixed) - held - {"phi0"}


def test_robot_file_folds_deviations_into_the_nominal_values():
    cal = coupled_cal()
    arm, params = cal.arm, cal.params
    doc = tomllib.loads(robot_toml(cal))
    dl, dq = params[:5], params[5:10]  # links 1, 2, 3@A, 3@B, 3@C
    assert_allclose(
        doc["link_lengths_mm"], [300.0 + dl[0], 220.0 + dl[1], 120.0], rtol=0, atol=1e-12
    )
    # The last joint's offset is the first target's (A); joint 3 turns link 3 by +1.
    offsets = np.array([2.0, -3.0, 5.0]) + np.degrees(dq[:3])
    assert_allclose(doc["joint_offsets_deg"], offsets, rtol=0, atol=1e-12)
    angles = np.degrees([0.3, -0.5 + dq[3] - dq[2], 1.2 + dq[4] - dq[2]])
    assert_allclose([doc["targets"][t]["angle_deg"] for t in "ABC"], angles, rtol=0, atol=1e-12)
    assert_allclose(
        [doc["targets"][t]["length_mm"] for t in "ABC"],
        [120.0 + dl[2], 90.0 + dl[3], 150.0 + dl[4]],
        rtol=0,
        atol=1e-12,
    )
    assert doc["joint_map"] == arm.joint_map.tolist()
    assert doc["identify"] == {"fixed": ["dl3@C"]}


def test_robot_file_names_the_base_pose_only_in_a_comment():
    cal = rotation_cal()
    text = robot_toml(cal)
    doc = tomllib.loads(text)
    assert "phi0" not in doc.get("identify", {}).get("fixed", [])
    comments = " ".join(line.lstrip("# ") for line in text.splitlines() if line.startswith("#"))
    for name, unit in (("x0", "mm"), ("y0", "mm"), ("phi0", "deg")):
        i = cal.arm.param_names.index(name)
        shown = float(cal.params[i] * cal.arm.display_scale[i])  # mm, or rad -> deg
        assert f"{name} = {shown!r} {unit}" in comments
    assert "x0" not in "".join(line for line in text.splitlines() if not line.startswith("#"))


def test_robot_file_writes_every_number_to_full_precision():
    cal = coupled_cal()
    doc = tomllib.loads(robot_toml(cal))
    folded = folded_arm(cal)
    # repr of a float reads back as the same float: equality, no tolerance needed.
    assert doc["link_lengths_mm"] == folded.link_lengths.tolist()
    assert doc["joint_offsets_deg"] == np.degrees(folded.joint_offsets).tolist()


def test_identify_against_the_exported_robot_finds_no_deviation(cal, tmp_path):
    """The exported robot is a fixed point: its own nominal data identify deviations 0."""
    exported = _exported_arm(cal, tmp_path)
    q, target = _poses(exported, seed=2, m=40)
    xy = forward_kinematics(exported, q, target=target)
    found = identify(exported, q, xy, sigma=0.1, target=target)
    k = exported.n_links
    assert_allclose(found.params[:k], 0.0, rtol=0, atol=1e-9)  # mm
    assert_allclose(found.params[k : 2 * k], 0.0, rtol=0, atol=1e-12)  # rad
    assert_allclose(found.params[2 * k :], 0.0, rtol=0, atol=1e-9)  # base, mm


# --------------------------------------------------------------------------- URDF


def _relative_map(arm: PlanarArm) -> np.ndarray:
    """D M, written out: relative link angles r_i = theta_i - theta_(i-1) from the readings."""
    n = arm.n_joints
    difference = np.eye(n) - np.eye(n, k=-1)
    return difference @ arm.joint_map


def _joint_values(arm: PlanarArm, q: np.ndarray) -> np.ndarray:
    """The documented convention: the readings when D M is diagonal +-1, else D M q."""
    relative = _relative_map(arm)
    signs = np.diag(relative)
    if np.array_equal(relative, np.diag(signs)) and np.all(np.abs(signs) == 1):
        return q
    return q @ relative.T


def _floats(text: str) -> list[float]:
    return [float(v) for v in text.split()]


def _planar(x: float, y: float, yaw: float) -> np.ndarray:
    c, s = math.cos(yaw), math.sin(yaw)
    return np.array([[c, -s, x], [s, c, y], [0.0, 0.0, 1.0]])


def _urdf_frames(text: str, values: dict[str, float]) -> dict[str, np.ndarray]:
    """Every link's planar pose (3 x 3, metres) for the given joint values, from the XML alone."""
    root = ET.fromstring(text)
    assert root.tag == "robot"
    links = {link.get("name") for link in root.findall("link")}
    joints = {j.find("child").get("link"): j for j in root.findall("joint")}
    roots = links - set(joints)
    assert roots == {"base_link"}
    frames: dict[str, np.ndarray] = {}

    def pose(link: str) -> np.ndarray:
        if link == "base_link":
            return np.eye(3)
        if link not in frames:
            joint = joints[link]
            origin = joint.find("origin")
            x, y, z = _floats(origin.get("xyz"))
            roll, pitch, yaw = _floats(origin.get("rpy"))
            assert z == 0.0 and roll == 0.0 and pitch == 0.0  # a planar arm
            transform = pose(joint.find("parent").get("link")) @ _planar(x, y, yaw)
            if joint.get("type") == "revolute":
                axis = _floats(joint.find("axis").get("xyz"))
                assert axis[:2] == [0.0, 0.0] and abs(axis[2]) == 1.0
                transform = transform @ _planar(0.0, 0.0, axis[2] * values[joint.get("name")])
            else:
                assert joint.get("type") == "fixed"
            frames[link] = transform
        return frames[link]

    for link in links:
        pose(link)
    return frames


def test_urdf_reproduces_the_calibrated_kinematics(cal):
    arm = cal.arm
    text = urdf(cal)
    q, target = _poses(arm, seed=3, m=60)
    values = _joint_values(arm, q)
    labels = [f"target_{t}" for t in arm.target_labels] or ["tool0"]
    worst_mm = worst_rad = 0.0
    for row in range(q.shape[0]):
        frames = _urdf_frames(text, {f"joint{j + 1}": v for j, v in enumerate(values[row])})
        for index, label in enumerate(labels):
            qi = q[row : row + 1]
            ti = None if target is None else np.array([index])
            tip = forward_kinematics(arm, qi, cal.robot_params(), target=ti)[0]
            yaw = tool_angles(arm, qi, cal.robot_params(), target=ti)[0]
            frame = frames[label]
            worst_mm = max(worst_mm, np.max(np.abs(frame[:2, 2] * 1000.0 - tip)))
            turn = math.atan2(frame[1, 0], frame[0, 0]) - yaw
            worst_rad = max(worst_rad, abs(math.remainder(turn, 2 * math.pi)))
    assert worst_mm <= POSITION_ATOL_MM
    assert worst_rad <= ANGLE_ATOL_RAD


def test_urdf_structure_limits_and_convention():
    cal = coupled_cal()
    root = ET.fromstring(urdf(cal))
    assert root.get("name") == "nest-arm-calibrated"
    names = [j.get("name") for j in root.findall("joint")]
    assert names == [
        "joint1",
        "joint2",
        "joint3",
        "target_A_joint",
        "target_B_joint",
        "target_C_joint",
    ]
    assert root.find("joint/calibration") is None  # offsets are in the origins
    # Coupled axes: every axis +z, limits the range of r = D M q over the readings' box.
    relative = _relative_map(cal.arm)
    corners = np.array(np.meshgrid(*cal.arm.joint_limits, indexing="ij")).reshape(3, -1).T
    r = corners @ relative.T
    for j, joint in enumerate(root.findall("joint")[:3]):
        assert joint.find("axis").get("xyz") == "0 0 1"
        limit = joint.find("limit")
        assert_allclose(
            [float(limit.get("lower")), float(limit.get("upper"))],
            [r[:, j].min(), r[:, j].max()],
            rtol=0,
            atol=1e-12,
        )
    assert "NOT the controller's readings" in " ".join(urdf(cal).split())


def test_urdf_reversed_joint_turns_about_minus_z_with_the_readings_limits():
    cal = reversed_cal()
    root = ET.fromstring(urdf(cal))
    axes = [j.find("axis").get("xyz") for j in root.findall("joint")[:3]]
    assert axes == ["0 0 1", "0 0 -1", "0 0 1"]
    limits = [
        [float(j.find("limit").get(key)) for key in ("lower", "upper")]
        for j in root.findall("joint")[:3]
    ]
    assert_allclose(limits, cal.arm.joint_limits, rtol=0, atol=0)
    assert [link.get("name") for link in root.findall("link")][-1] == "tool0"


def test_urdf_joint_values_follow_the_documented_convention():
    for make in CASES.values():
        arm = make().arm
        q = random_plan(arm, 5, rng=4)
        assert_allclose(urdf_joint_values(arm, q), _joint_values(arm, q), rtol=0, atol=1e-15)


def test_urdf_comment_gives_the_base_pose_in_the_instrument_frame():
    cal = rotation_cal()
    text = urdf(cal)
    assert "generated by armcal" in text
    phi0_deg = math.degrees(cal.params[cal.arm.param_names.index("phi0")])
    assert f"phi0 = {phi0_deg!r} deg" in " ".join(text.split())
    ET.fromstring(text)  # the comment keeps the document well formed


# --------------------------------------------------------------------------- command line


@pytest.fixture(scope="module")
def calibration_file(tmp_path_factory):
    """A calibration of paper-4link from noiseless data, by the commands a user runs."""
    folder = tmp_path_factory.mktemp("export-cli")
    plan, meas, cal = folder / "plan.csv", folder / "meas.csv", folder / "cal.json"
    assert main(["design", "--poses", "12", "-o", str(plan)]) == 0
    assert main(["synthesize", "--plan", str(plan), "--sigma", "0", "-o", str(meas)]) == 0
    assert (
        main(
            [
                "identify",
                "--robot",
                "paper-4link",
                "--measurements",
                str(meas),
                "--sigma",
                "0.1",
                "-o",
                str(cal),
            ]
        )
        == 0
    )
    return cal


def test_cli_writes_both_files(calibration_file, tmp_path, capsys):
    capsys.readouterr()
    robot, model = tmp_path / "calibrated.toml", tmp_path / "arm.urdf"
    args = ["export", "--calibration", str(calibration_file)]
    assert main([*args, "--robot-toml", str(robot), "--urdf", str(model)]) == 0
    assert capsys.readouterr().out.splitlines() == [f"wrote {robot}", f"wrote {model}"]
    cal = read_calibration(calibration_file)
    assert robot.read_text() == robot_toml(cal) and model.read_text() == urdf(cal)
    q, _ = _poses(cal.arm, seed=5)
    assert_allclose(
        forward_kinematics(load_robot(robot).arm, q),
        forward_kinematics(cal.arm, q, cal.robot_params()),
        rtol=0,
        atol=POSITION_ATOL_MM,
    )
    ET.parse(model)


def test_cli_json_names_the_files_written(calibration_file, tmp_path, capsys):
    capsys.readouterr()
    model = tmp_path / "arm.urdf"
    args = ["export", "--calibration", str(calibration_file), "--urdf", str(model), "--json"]
    assert main(args) == 0
    document = json.loads(capsys.readouterr().out)
    assert document["robot_toml"] is None and document["urdf"] == str(model)


def test_exported_robot_file_serves_identify(calibration_file, tmp_path, capsys):
    """identify with the exported robot on the calibration's own noiseless data finds ~0."""
    robot = tmp_path / "calibrated.toml"
    args = ["export", "--calibration", str(calibration_file), "--robot-toml", str(robot)]
    assert main(args) == 0
    capsys.readouterr()
    meas = calibration_file.parent / "meas.csv"
    args = ["identify", "--robot", str(robot), "--measurements", str(meas), "--sigma", "0.1"]
    assert main([*args, "--json"]) == 0
    document = json.loads(capsys.readouterr().out)
    assert document["robot"]["name"] == "paper-4link-calibrated"
    # The calibration recovered the truth to ~1e-11 from noiseless data; so close to 0 here.
    assert_allclose([p["value"] for p in document["parameters"]], 0.0, rtol=0, atol=1e-8)


def test_cli_coupled_arm_round_trips_through_the_file_and_warns(tmp_path, capsys):
    """A joint map, offsets and targets survive calibration JSON -> export; URDF values warned."""
    truth = coupled_cal()
    q, target = _poses(truth.arm, seed=6, m=30)
    xy = forward_kinematics(truth.arm, q, truth.params, target=target)
    found = identify(truth.arm, q, xy, target=target)
    path, robot, model = tmp_path / "cal.json", tmp_path / "r.toml", tmp_path / "a.urdf"
    path.write_text(to_json(calibration_document(found)))
    args = ["export", "--calibration", str(path), "--robot-toml", str(robot), "--urdf", str(model)]
    assert main([*args, "--json"]) == 0
    out, err = capsys.readouterr()
    assert json.loads(out)["warnings"][0]["code"] == "urdf-joint-values"
    assert err.startswith("armcal: warning: ") and "joint_states" in err
    cal = read_calibration(path)
    assert_allclose(cal.params, truth.params, rtol=0, atol=1e-9)  # noiseless: the truth
    q, target = _poses(truth.arm, seed=7)
    assert_allclose(
        forward_kinematics(load_robot(robot).arm, q, target=target),
        forward_kinematics(truth.arm, q, truth.robot_params(), target=target),
        rtol=0,
        atol=1e-8,  # the identified deviations differ from the truth by round-off (1e-11)
    )


def test_cli_without_an_output_is_an_error(calibration_file, capsys):
    assert main(["export", "--calibration", str(calibration_file)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("armcal: error:")
    assert "--robot-toml" in err and "--urdf" in err


def test_cli_refuses_to_overwrite_the_calibration(calibration_file, capsys):
    before = calibration_file.read_bytes()
    args = ["export", "--calibration", str(calibration_file), "--urdf", str(calibration_file)]
    assert main(args) == 2
    assert capsys.readouterr().err.startswith("armcal: error:")
    assert calibration_file.read_bytes() == before


def test_bad_calibration_file_exits_2_with_one_line(tmp_path):
    (tmp_path / "cal.json").write_text('{"format": "something-else/9"}\n')
    done = run_cli(tmp_path, "export", "--calibration", "cal.json", "--robot-toml", "out.toml")
    assert done.returncode == 2
    assert done.stderr.count("\n") == 1 and done.stderr.startswith("armcal: error: cal.json")
    assert "Traceback" not in done.stderr and not (tmp_path / "out.toml").exists()


def test_robot_file_quotes_names_and_labels_that_need_it(tmp_path):
    arm = PlanarArm(
        [200.0, 100.0],
        name='shop "A"\\arm\x7f',
        targets=[Target("nest.1", 100.0), Target("ü-2", 80.0, 0.2)],
    )
    exported = _exported_arm(_cal(arm, np.zeros(arm.n_params)), tmp_path)
    assert exported.name == arm.name + "-calibrated"
    assert exported.target_labels == ("nest.1", "ü-2")
    root = ET.fromstring(urdf(_cal(arm, np.zeros(arm.n_params))))
    assert root.get("name") == 'shop "A"\\arm_-calibrated'  # control characters become _
    assert [link.get("name") for link in root.findall("link")][-2:] == [
        "target_nest.1",
        "target_ü-2",
    ]


def test_joint_limits_in_degrees_survive_a_round_trip() -> None:
    """120 deg read as radians is written back as 120, not 119.99999999999999."""
    from armcal.files import robot_to_dict

    arm = PlanarArm([300.0, 250.0], joint_limits=np.radians([[-90.0, 90.0], [-120.0, 120.0]]))
    assert np.degrees(arm.joint_limits)[1, 1] != 120.0  # the round-off this guards against
    assert robot_to_dict(arm)["joint_limits_deg"] == [[-90.0, 90.0], [-120.0, 120.0]]
