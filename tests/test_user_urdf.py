"""A calibration written into the user's own URDF (issue 36): UR5's public URDF, with its
meshes, inertials, collision geometry, transmissions, Gazebo tags, comments, off-chain
joints and a tool frame beyond the tip, gets only its chain's joint origins changed.

The calibrated file is read back by a reader written here from the URDF specification
(an origin is ``T(xyz) Rz(yaw) Ry(pitch) Rx(roll)``; a revolute joint turns about its
``<axis>`` by Rodrigues' formula, a prismatic one slides along it), which shares no
code with armcal's reader or chains.
"""

from __future__ import annotations

import difflib
import json
import math
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pytest
from numpy.testing import assert_allclose

import armcal
from armcal.errors import InputError
from armcal.files import calibration_document, read_calibration
from helpers import run_cli

DATA = Path(__file__).resolve().parent / "data"
UR5 = DATA / "ur5_robot.urdf"
LABELS = ("A", "B", "C")


# -- an independent URDF reader ---------------------------------------------------------


def _rot(axis: np.ndarray, angle: float) -> np.ndarray:
    """Rodrigues: a turn by ``angle`` about the unit ``axis``."""
    k = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    return np.eye(3) + math.sin(angle) * k + (1 - math.cos(angle)) * (k @ k)


def _origin(joint: ET.Element) -> np.ndarray:
    """A joint's ``<origin>`` as a 4 x 4 transform (metres), per the URDF specification."""
    origin = joint.find("origin")
    xyz = (
        [0.0, 0.0, 0.0]
        if origin is None
        else [float(v) for v in origin.get("xyz", "0 0 0").split()]
    )
    rpy = (
        [0.0, 0.0, 0.0]
        if origin is None
        else [float(v) for v in origin.get("rpy", "0 0 0").split()]
    )
    ex, ey, ez = np.eye(3)
    out = np.eye(4)
    out[:3, :3] = _rot(ez, rpy[2]) @ _rot(ey, rpy[1]) @ _rot(ex, rpy[0])
    out[:3, 3] = xyz
    return out


def urdf_forward(text: str, base: str, tip: str, values: dict[str, float]) -> np.ndarray:
    """The frame of link ``tip`` in link ``base`` at joint ``values`` (rad, m)."""
    joints = {j.find("child").get("link"): j for j in ET.fromstring(text).findall("joint")}
    frame, link = np.eye(4), tip
    while link != base:
        joint = joints[link]
        motion = np.eye(4)
        if joint.get("type") in ("revolute", "continuous", "prismatic"):
            axis = np.array([float(v) for v in joint.find("axis").get("xyz").split()])
            axis /= np.linalg.norm(axis)
            value = values[joint.get("name")]
            if joint.get("type") == "prismatic":
                motion[:3, 3] = axis * value
            else:
                motion[:3, :3] = _rot(axis, value)
        frame = _origin(joint) @ motion @ frame
        link = joint.find("parent").get("link")
    return frame


# -- a calibrated UR5 --------------------------------------------------------------------


def _robot_toml(tmp_path: Path) -> Path:
    """The UR5 with a nest of three reflectors on its tool flange (tool0)."""
    path = tmp_path / "ur5.toml"
    path.write_text(
        f'name = "ur5"\nurdf = "{UR5.as_posix()}"\nbase_link = "base_link"\ntip_link = "tool0"\n'
        "[targets]\nA = { xyz_mm = [60, 0, 40] }\nB = { xyz_mm = [-30, 52, 40] }\n"
        "C = { xyz_mm = [-30, -52, 40] }\n",
        encoding="utf-8",
    )
    return path


@pytest.fixture(scope="module")
def calibrated(tmp_path_factory):
    """A UR5 whose joints sit 0.3 mm and 0.03 deg (1 std) off its URDF, measured without
    noise by a tracker 1.5 m away at 30 poses, and identified."""
    tmp = tmp_path_factory.mktemp("ur5")
    arm = armcal.load_robot(_robot_toml(tmp)).arm
    rng = np.random.default_rng(1)
    truth = arm.nominal.copy()
    truth[:6] = [1500.0, 200.0, -300.0, 0.01, -0.02, 1.0]
    errors = np.arange(6, arm.n_params - 9)  # every joint's placement and zero
    units = np.array(arm.param_units)
    size = np.where(units[errors] == "mm", 0.3, 0.03) / arm.display_scale[errors]
    truth[errors] += rng.normal(0.0, 1.0, errors.size) * size
    rows = arm.plan_conditions(armcal.random_plan(arm, 30, rng=2))
    labels = [LABELS[t] for t in rows.target]
    points = armcal.synthesize_measurements(arm, rows.q, truth, 0.0, target=labels)
    cal = armcal.identify(arm, rows.q, points, sigma=0.01, target=labels)
    path = tmp / "cal.json"
    path.write_text(json.dumps(calibration_document(cal)), encoding="utf-8")
    return cal, rows, points, path


def _joint_values(cal, q: np.ndarray) -> dict[str, float]:
    u = cal.model.joint_map @ q
    return dict(zip(cal.model.joint_names, u, strict=True))


def test_the_users_urdf_reproduces_the_calibration_to_round_off(calibrated):
    """At 20 poses, tool0's frame in the written URDF is the calibrated arm's tip frame
    within 1e-9 mm, and the reflectors it carries land on the measured points (noiseless)
    to 1e-8 mm once placed in the tracker's frame."""
    cal, rows, points, _ = calibrated
    text = armcal.export(cal.calibrated(), "urdf", original=str(UR5))
    arm, params = cal.calibrated().arm, cal.calibrated().arm_params
    chain = arm.calibrated_chain(params)
    for q in armcal.random_plan(arm, 20, rng=5):
        frame = urdf_forward(text, "base_link", "tool0", _joint_values(cal, q))
        expected = chain.forward(arm.joint_map @ q)
        assert_allclose(frame[:3, 3] * 1000.0, expected[:3, 3], rtol=0, atol=1e-9)
        assert_allclose(frame[:3, :3], expected[:3, :3], rtol=0, atol=1e-12)
    targets = arm.layout.target_points(params)  # mm in tool0's frame
    frames = [urdf_forward(text, "base_link", "tool0", _joint_values(cal, q)) for q in rows.q]
    robot = np.array(
        [
            f[:3, :3] @ targets[t] + 1000.0 * f[:3, 3]
            for f, t in zip(frames, rows.target, strict=True)
        ]
    )
    # The tracker's frame: the rigid motion that best takes the robot-frame points onto the
    # measured ones (Kabsch), found here from the points alone.
    a, b = robot - robot.mean(0), points - points.mean(0)
    u, _, vt = np.linalg.svd(a.T @ b)
    turn = (u @ np.diag([1, 1, np.sign(np.linalg.det(u @ vt))]) @ vt).T
    placed = robot @ turn.T + (points.mean(0) - robot.mean(0) @ turn.T)
    assert_allclose(placed, points, rtol=0, atol=1e-8)


def test_only_the_chains_origins_change(calibrated):
    """Every other byte is the original's: a diff changes one origin line per calibrated
    joint, and with those origins set aside the two files are the same XML."""
    cal, *_ = calibrated
    original = UR5.read_text(encoding="utf-8")
    text = armcal.export(cal.calibrated(), "urdf", original=str(UR5))
    changed = [
        line
        for line in difflib.unified_diff(
            original.splitlines(), text.splitlines(), lineterm="", n=0
        )
        if line[:1] in "+-" and not line.startswith(("+++", "---"))
    ]
    assert changed and all("<origin " in line for line in changed)
    # Joint 1's placement and zero merge into the base pose (the tracker's): it is not moved.
    assert len(changed) == 2 * 5
    chain = set(cal.model.joint_names)

    def without_chain_origins(xml: str) -> str:
        root = ET.fromstring(xml)
        for joint in root.findall("joint"):
            if joint.get("name") in chain:
                for origin in joint.findall("origin"):
                    joint.remove(origin)
        return ET.canonicalize(ET.tostring(root, encoding="unicode"))

    assert without_chain_origins(text) == without_chain_origins(original)
    for tag in ("link", "joint", "mesh", "inertial", "collision", "limit", "transmission"):
        assert text.count(f"<{tag}") == original.count(f"<{tag}"), tag
    assert "<!-- Frame coincident with all-zeros TCP on UR controller -->" in text


def test_the_origins_yaml_holds_what_the_urdf_holds(calibrated):
    """The YAML for a xacro: every chain joint's x y z roll pitch yaw, the numbers of the
    written URDF's origins exactly."""
    cal, *_ = calibrated
    text = armcal.export(cal.calibrated(), "urdf", original=str(UR5))
    yaml = armcal.export(cal.calibrated(), "origins", original=str(UR5))
    found: dict[str, dict[str, float]] = {}
    for line in yaml.splitlines():
        if line.startswith("#") or not line.strip():
            continue
        if not line.startswith(" "):
            current = found.setdefault(line.rstrip(":"), {})
        else:
            key, value = line.strip().split(": ")
            current[key] = float(value)
    assert list(found) == list(cal.model.joint_names)
    joints = {j.get("name"): j for j in ET.fromstring(text).findall("joint")}
    for name, values in found.items():
        assert_allclose(
            _origin(joints[name]),
            _origin(
                ET.fromstring(
                    f'<joint><origin xyz="{values["x"]} {values["y"]} {values["z"]}" '
                    f'rpy="{values["roll"]} {values["pitch"]} {values["yaw"]}"/></joint>'
                )
            ),
            rtol=0,
            atol=0,
        )


def test_another_robots_urdf_is_refused(calibrated, tmp_path):
    """A URDF whose elbow sits 1 mm elsewhere is another variant: refused, naming the joint."""
    cal, *_ = calibrated
    other = tmp_path / "other.urdf"
    text = UR5.read_text(encoding="utf-8")
    other.write_text(text.replace('xyz="0.0 -0.1197 0.425"', 'xyz="0.0 -0.1197 0.426"'))
    with pytest.raises(InputError, match=r"'elbow_joint' .*another robot or variant"):
        armcal.export(cal.calibrated(), "urdf", original=str(other))


def test_the_command_line_writes_the_users_urdf_and_refuses_to_replace_it(calibrated, tmp_path):
    *_, path = calibrated
    out, yaml = tmp_path / "ur5-calibrated.urdf", tmp_path / "origins.yaml"
    result = run_cli(
        tmp_path, "export", "--calibration", str(path), "--from", str(UR5), "--urdf", str(out),
        "--origins-yaml", str(yaml),
    )  # fmt: skip
    assert result.returncode == 0, result.stderr
    assert out.read_text(encoding="utf-8") == armcal.export(
        read_calibration(path), "urdf", original=str(UR5)
    )
    assert yaml.read_text(encoding="utf-8").startswith("# Calibrated joint origins")
    copy = tmp_path / "mine.urdf"
    copy.write_bytes(UR5.read_bytes())
    result = run_cli(
        tmp_path, "export", "--calibration", str(path), "--from", str(copy), "--urdf", str(copy)
    )
    assert result.returncode == 2
    assert result.stderr.startswith("armcal: error: ") and "--from" in result.stderr
    assert copy.read_bytes() == UR5.read_bytes()
    result = run_cli(tmp_path, "export", "--calibration", str(path), "--origins-yaml", str(yaml))
    assert result.returncode == 2 and "--from URDF" in result.stderr


# -- joint data as the robot publishes it ------------------------------------------------


def _files(tmp_path: Path, calibrated) -> tuple[str, str]:
    """The calibration's rows as a measurement file in q{j}_deg, and the same rows with the
    joints named by the URDF in radians, as ROS's /joint_states gives them (each reading
    converted from the degrees written, so both files hold the same angles to round-off)."""
    from armcal.files.writers import format_measurements_csv

    cal, rows, points, _ = calibrated
    labels = [LABELS[t] for t in rows.target]
    text = format_measurements_csv(rows.q, points, targets=labels, kinds=cal.model.joint_kinds)
    (tmp_path / "deg.csv").write_text(text, encoding="utf-8")
    lines = text.splitlines()
    n = len(cal.model.joint_names)
    head = lines[0].split(",")
    named = [",".join([*cal.model.joint_names, *head[n:]])]
    for line in lines[1:]:
        cells = line.split(",")
        named.append(",".join([*(repr(math.radians(float(c))) for c in cells[:n]), *cells[n:]]))
    (tmp_path / "named.csv").write_text("\n".join(named) + "\n", encoding="utf-8")
    (tmp_path / "ur5.toml").write_text(_robot_toml(tmp_path).read_text(), encoding="utf-8")
    return "deg.csv", "named.csv"


def _identified(tmp_path: Path, measurements: str) -> dict:
    result = run_cli(
        tmp_path, "identify", "--robot", "ur5.toml", "--measurements", measurements,
        "--sigma", "0.01", "--json",
    )  # fmt: skip
    assert result.returncode == 0, result.stderr
    return json.loads(result.stdout)


def test_urdf_joint_names_in_radians_give_the_same_calibration(calibrated, tmp_path):
    """Mapped by name: the columns in the URDF's order or any other give the calibration
    of the q{j}_deg file, every value within 1e-9 of its std (the readings differ by the
    round-off of a degree printed and turned into radians, 1e-16 rad)."""
    deg, named = _files(tmp_path, calibrated)
    reference = _identified(tmp_path, deg)
    shuffled = tmp_path / "shuffled.csv"
    rows = [line.split(",") for line in (tmp_path / named).read_text().splitlines()]
    order = [5, 2, 0, 4, 1, 3, *range(6, len(rows[0]))]  # joints out of order
    shuffled.write_text("\n".join(",".join(r[i] for i in order) for r in rows) + "\n")
    for measurements in (named, shuffled.name):
        found = _identified(tmp_path, measurements)
        for a, b in zip(reference["parameters"], found["parameters"], strict=True):
            assert a["name"] == b["name"]
            assert abs(a["value"] - b["value"]) <= 1e-9 * max(a["std"], 1e-12), a["name"]


@pytest.mark.parametrize(
    ("change", "message"),
    [
        (lambda h: h.replace("elbow_joint,", ""), "elbow_joint has no column"),
        (lambda h: h.replace("target", "target,finger_joint"), "column finger_joint: not a joint"),
        (lambda h: h.replace("elbow_joint", "elbow_joint_mm"), "elbow_joint is a revolute joint"),
        (lambda h: h.replace("wrist_1_joint", "elbow_joint_deg"), "elbow_joint has two columns"),
    ],
)
def test_a_missing_extra_or_misnamed_joint_is_an_error(calibrated, tmp_path, change, message):
    _, named = _files(tmp_path, calibrated)
    path = tmp_path / named
    lines = path.read_text().splitlines()
    header = change(lines[0])
    width = len(header.split(","))
    body = [",".join([*line.split(","), "0"][:width]) for line in lines[1:]]
    path.write_text("\n".join([header, *body]) + "\n")
    result = run_cli(
        tmp_path, "identify", "--robot", "ur5.toml", "--measurements", named, "--sigma", "0.01"
    )
    assert result.returncode == 2
    (line,) = result.stderr.strip().splitlines()
    assert line.startswith("armcal: error: named.csv: line 1") and message in line, line


def test_named_columns_are_the_urdfs_joint_values_under_a_coupled_joint_map(tmp_path):
    """ROS publishes the URDF's joint values u = M q; with a coupled joint map (a FANUC's
    J3 against the horizon: u3 = q2 + q3) the file's named columns are read as u and turned
    into the controller's readings q."""
    from armcal.files import read_measurements

    robots = Path(armcal.__file__).parent / "robots"
    robot = tmp_path / "cell.toml"
    robot.write_text(
        f'name = "cell"\nurdf = "{(robots / "industrial-6r.urdf").as_posix()}"\n'
        'base_link = "base_link"\ntip_link = "flange"\n'
        "joint_map = [[1, 0, 0, 0, 0, 0], [0, 1, 0, 0, 0, 0], [0, 1, 1, 0, 0, 0],\n"
        "             [0, 0, 0, 1, 0, 0], [0, 0, 0, 0, 1, 0], [0, 0, 0, 0, 0, 1]]\n",
        encoding="utf-8",
    )
    arm = armcal.load_robot(robot).arm
    q = armcal.random_plan(arm, 6, rng=3)
    u = q @ arm.joint_map.T
    points = arm.positions(arm.conditions(q), arm.nominal)
    lines = [",".join([*arm.joint_names, "x_mm", "y_mm", "z_mm"])]
    lines += [",".join(repr(float(v)) for v in [*a, *p]) for a, p in zip(u, points, strict=True)]
    path = tmp_path / "meas.csv"
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    assert_allclose(read_measurements(path, arm).q, q, rtol=0, atol=1e-13)


def test_identify_plot_draws_the_residual_figure(calibrated, tmp_path):
    """identify --plot writes the family's residual figure as a PNG (what it plots is
    checked in test_api_every_family, through the same role)."""
    deg, _ = _files(tmp_path, calibrated)
    result = run_cli(
        tmp_path, "identify", "--robot", "ur5.toml", "--measurements", deg, "--sigma", "0.01",
        "--plot", "residuals.png",
    )  # fmt: skip
    assert result.returncode == 0, result.stderr
    assert (tmp_path / "residuals.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_a_gantry_whose_joints_are_named_x_y_z_keeps_its_measured_columns(tmp_path):
    """A Cartesian robot's joints are often named x, y and z: the measurement's own x_mm,
    y_mm and z_mm stay the measured point, never the joint "x" in mm."""
    from armcal.files.joints import named_joint_columns

    urdf = tmp_path / "gantry.urdf"
    axes = ("1 0 0", "0 1 0", "0 0 1")
    joints = "".join(
        f'<link name="l{k + 1}"/><joint name="{name}" type="prismatic"><parent link="l{k}"/>'
        f'<child link="l{k + 1}"/><axis xyz="{axes[k]}"/><limit lower="-1" upper="1"/></joint>'
        for k, name in enumerate("xyz")
    )
    urdf.write_text(f'<robot name="gantry"><link name="l0"/>{joints}</robot>', encoding="utf-8")
    arm = armcal.load_robot(urdf).arm
    assert arm.joint_names == ("x", "y", "z")
    header = ["x", "y", "z", "x_mm", "y_mm", "z_mm"]
    renamed, factors, named = named_joint_columns(
        "m.csv", header, 1, arm, ["x_mm", "y_mm", "z_mm", "pose", "target"]
    )
    assert named and renamed == ["q1_mm", "q2_mm", "q3_mm", "x_mm", "y_mm", "z_mm"]
    assert factors.tolist() == [1000.0, 1000.0, 1000.0]  # metres, as ROS publishes a slide
