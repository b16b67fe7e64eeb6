"""URDF and robot-description hints that point the right way (issue 34).

- ``--tip-link`` and ``--base-link`` on every command that takes ``--robot``; the
  library's messages name the robot TOML's key and its own argument, the command
  line its flag;
- a chain that ends in a gripper's joint warns and names the tip link to choose;
- a link or joint name declared twice is said to be duplicated, with both lines;
- a standard DH table under ``[mdh]`` (or a modified one under ``[dh]``) is named
  for what it looks like, and ``[dh]`` reads a standard table;
- a URDF in Latin-1 that declares it reads as XML reads it;
- a UR5 calibrated from Universal Robots' own URDF layout exports to its controller;
- the rest of what a new user gives by mistake: a xacro file, an empty file, a URDF
  with several roots, a floating joint, a mimic joint.

The reference kinematics here are written out from their definitions
(:func:`dh_product`, :func:`mdh_product`), independently of armcal's chains.
"""

from __future__ import annotations

import json
import math
import re
from pathlib import Path

import numpy as np
import pytest

from armcal.cli import build_parser
from armcal.errors import ArmcalError, InputError
from armcal.files import load_robot, load_spatial_robot, read_calibration
from armcal.files.ur import ur_frames
from armcal.files.urdf import read_urdf
from helpers import run_cli

# --------------------------------------------------------------------------- helpers


def one_error(result) -> str:
    """The single ``armcal: error:`` line of a run that must fail with exit 2."""
    assert result.returncode == 2, (result.stdout, result.stderr)
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("armcal: error: "), result.stderr
    return lines[0]


def link(name: str) -> str:
    return f'<link name="{name}"/>'


def joint(name, parent, child, kind="revolute", xyz="0.3 0 0", rpy="0 0 0", extra=""):
    """A URDF joint (metres, radians) about z."""
    axis = '<axis xyz="0 0 1"/>' if kind != "fixed" else ""
    limit = '<limit lower="-3" upper="3"/>' if kind in ("revolute", "prismatic") else ""
    return (
        f'<joint name="{name}" type="{kind}"><parent link="{parent}"/><child link="{child}"/>'
        f'<origin xyz="{xyz}" rpy="{rpy}"/>{axis}{limit}{extra}</joint>\n'
    )


def urdf(*parts: str, name: str = "arm") -> str:
    return f'<?xml version="1.0"?>\n<robot name="{name}">\n{"".join(parts)}</robot>\n'


#: A 2R arm with a hand and one prismatic finger: the URDF's single leaf is the finger.
GRIPPER_URDF = urdf(
    *(link(n) for n in ("base", "l1", "l2", "hand", "finger")),
    joint("j1", "base", "l1"),
    joint("j2", "l1", "l2"),
    joint("hand_mount", "l2", "hand", "fixed", xyz="0.1 0 0"),
    joint("finger_joint", "hand", "finger", "prismatic", xyz="0 0 0.05"),
)

#: A 2R arm with two leaves beyond l2: a flange and a camera.
TWO_LEAVES = urdf(
    *(link(n) for n in ("base", "l1", "l2", "flange", "camera")),
    joint("j1", "base", "l1"),
    joint("j2", "l1", "l2"),
    joint("l2_flange", "l2", "flange", "fixed", xyz="0.1 0 0"),
    joint("l2_camera", "l2", "camera", "fixed", xyz="0 0.05 0"),
)


def write(folder: Path, files: dict[str, str | bytes]) -> None:
    for name, content in files.items():
        path = folder / name
        if isinstance(content, bytes):
            path.write_bytes(content)
        else:
            path.write_text(content, encoding="utf-8")


def plan_csv(q_deg: np.ndarray) -> str:
    header = ",".join(f"q{j + 1}_deg" for j in range(q_deg.shape[1]))
    return header + "\n" + "\n".join(",".join(repr(float(v)) for v in row) for row in q_deg) + "\n"


def dh_product(q: np.ndarray, theta, d, a, alpha, kinds=None) -> np.ndarray:
    """Tip frames ``(m, 4, 4)`` of a standard DH table (mm, rad), from the definition:
    ``prod_k Rz(theta_k [+ q_k]) Tz(d_k [+ q_k]) Tx(a_k) Rx(alpha_k)``."""
    kinds = kinds or ["R"] * len(theta)
    out = []
    for pose in q:
        frame = np.eye(4)
        for k in range(len(theta)):
            t = theta[k] + (pose[k] if kinds[k] == "R" else 0.0)
            dd = d[k] + (pose[k] if kinds[k] == "P" else 0.0)
            c, s, ca, sa = np.cos(t), np.sin(t), np.cos(alpha[k]), np.sin(alpha[k])
            frame = frame @ np.array(
                [
                    [c, -s * ca, s * sa, a[k] * c],
                    [s, c * ca, -c * sa, a[k] * s],
                    [0.0, sa, ca, dd],
                    [0.0, 0.0, 0.0, 1.0],
                ]
            )
        out.append(frame)
    return np.array(out)


#: A UR5's standard DH table (Universal Robots' published values, mm and rad):
#: d1 = 89.159, a2 = -425, a3 = -392.25, d4 = 109.15, d5 = 94.65, d6 = 82.3.
UR5_D = [89.159, 0.0, 0.0, 109.15, 94.65, 82.3]
UR5_A = [0.0, -425.0, -392.25, 0.0, 0.0, 0.0]
UR5_ALPHA_DEG = [90.0, 0.0, 0.0, 90.0, -90.0, 0.0]


def dh_toml(key: str, alpha, a, theta, d, extra: str = "") -> str:
    def listed(values):
        return "[" + ", ".join(repr(float(v)) for v in values) + "]"

    return (
        f'name = "arm"\n[{key}]\nalpha_deg = {listed(alpha)}\na_mm = {listed(a)}\n'
        f"theta_deg = {listed(theta)}\nd_mm = {listed(d)}\n{extra}"
    )


# --------------------------------------------------------------------------- 1. --tip-link


def test_every_command_that_takes_robot_takes_tip_and_base_links():
    """The flags belong to every command with --robot (PRODUCT.md's '--robot ur5.urdf:
    with several leaves, say --tip-link')."""
    parser = build_parser()
    subparsers = next(a for a in parser._actions if a.dest == "command").choices
    with_robot = [
        name
        for name, sub in subparsers.items()
        if any("--robot" in a.option_strings for a in sub._actions)
    ]
    commands = ("synthesize", "identify", "design", "evaluate", "simulate", "poses-needed", "demo")
    assert set(commands) <= set(with_robot)
    for name in with_robot:
        options = {o for a in subparsers[name]._actions for o in a.option_strings}
        assert {"--tip-link", "--base-link"} <= options, name


def test_several_leaves_name_the_flag_on_the_command_line_and_the_key_in_the_library(
    tmp_path,
):
    write(tmp_path, {"arm.urdf": TWO_LEAVES})
    with pytest.raises(InputError) as raised:
        read_urdf(tmp_path / "arm.urdf")
    library = str(raised.value)
    assert "2 links end chains beyond 'base' (camera: 2 joints, flange: 2 joints)" in library
    assert "tip_link in a robot TOML" in library and "tip_link=" in library
    assert "--" not in library  # the library names no flag
    line = one_error(run_cli(tmp_path, "design", "--robot", "arm.urdf", "--poses", "12"))
    assert "arm.urdf" in line and "--tip-link LINK" in line and "tip_link" in line


def test_tip_link_chooses_the_chain_and_overrides_the_robot_toml(tmp_path):
    """--tip-link flange: the 2R chain to the flange (two joint columns in the plan);
    over a robot TOML's tip_link it wins; --base-link l1 starts after joint 1."""
    write(
        tmp_path,
        {
            "arm.urdf": TWO_LEAVES,
            "robot.toml": 'urdf = "arm.urdf"\ntip_link = "l1"\n',
        },
    )
    assert load_spatial_robot(tmp_path / "robot.toml").arm.n_joints == 1
    over = load_spatial_robot(tmp_path / "robot.toml", tip_link="flange")
    assert over.arm.n_joints == 2
    # The flange is 300 + 300 + 100 mm out along x at zero (the URDF's origins).
    np.testing.assert_allclose(
        over.arm.chain.forward(np.zeros(2))[:3, 3], [700.0, 0.0, 0.0], rtol=0, atol=1e-9
    )
    beyond = load_spatial_robot(tmp_path / "arm.urdf", base_link="l1", tip_link="camera")
    assert beyond.arm.n_joints == 1
    rng = np.random.default_rng(6)
    write(tmp_path, {"two.csv": plan_csv(rng.uniform(-90, 90, (12, 2)))})
    write(tmp_path, {"one.csv": plan_csv(rng.uniform(-90, 90, (12, 1)))})
    for robot in ("arm.urdf", "robot.toml"):  # a plan of two joints fits the chain to flange
        chosen = ("--robot", robot, "--tip-link", "flange")
        result = run_cli(tmp_path, "evaluate", *chosen, "--plan", "two.csv", "--json")
        assert result.returncode == 0, result.stderr
        line = one_error(run_cli(tmp_path, "evaluate", *chosen, "--plan", "one.csv"))
        assert "one.csv" in line and "2 joints" in line, line
    beyond = ("--robot", "arm.urdf", "--base-link", "l1", "--tip-link", "flange")
    result = run_cli(tmp_path, "evaluate", *beyond, "--plan", "one.csv", "--json")
    assert result.returncode == 0, result.stderr


#: A truth of the same URDF, the instrument at the base and the target at the tip.
TRUTH_AT_TIP = 'robot = "arm.urdf"\n[targets]\ntool = { xyz_mm = [0, 0, 0] }\n'


def test_a_truth_s_bare_urdf_takes_the_robot_s_links(tmp_path):
    """synthesize --robot arm.urdf --tip-link flange with a truth whose robot is the same
    URDF: its chain runs to the same tip (it needed one and could not be told); the
    measurements are the truth's arm, the nominal one here, at the flange."""
    q_deg = np.array([[0.0, 0.0], [90.0, 0.0], [0.0, 90.0]])
    write(
        tmp_path,
        {
            "arm.urdf": TWO_LEAVES,
            "truth.toml": TRUTH_AT_TIP,
            "plan.csv": plan_csv(q_deg),
        },
    )
    result = run_cli(
        tmp_path, "synthesize", "--robot", "arm.urdf", "--tip-link", "flange", "--truth",
        "truth.toml", "--plan", "plan.csv", "--sigma", "0", "-o", "meas.csv",
    )  # fmt: skip
    assert result.returncode == 0, result.stderr
    rows = (tmp_path / "meas.csv").read_text(encoding="utf-8").splitlines()
    header = rows[0].split(",")
    points = np.array([[float(v) for v in row.split(",")[2:5]] for row in rows[1:]])
    assert header[2:5] == ["x_mm", "y_mm", "z_mm"]
    # Joint 1 at x = 300 mm, joint 2 300 mm beyond, the flange 100 mm further (the URDF's
    # origins): (700, 0); joint 1 at 90 deg: (300, 400); joint 2 at 90 deg: (600, 100).
    expected = [[700.0, 0.0, 0.0], [300.0, 400.0, 0.0], [600.0, 100.0, 0.0]]
    np.testing.assert_allclose(points, expected, rtol=0, atol=1e-9)


@pytest.mark.parametrize(
    ("files", "robot", "expected"),
    [
        ({}, "paper-4link", ("paper-4link", "planar robot", "drop them")),
        (
            {"mdh.toml": dh_toml("mdh", [0, 0], [0, 300], [0, 0], [0, 0])},
            "mdh.toml",
            ("mdh.toml", "[mdh], not by a URDF"),
        ),
        (
            {"ur.toml": '[ur]\nmodel = "ur5"\n'},
            "ur.toml",
            ("ur.toml", "[ur], not by a URDF"),
        ),
        ({"arm.urdf": TWO_LEAVES}, "arm.urdf", ("arm.urdf", "tip_link 'flang'", "'flange'")),
    ],
    ids=["planar", "mdh", "ur", "unknown-link"],
)
def test_a_tip_link_for_a_robot_without_that_link_is_refused(tmp_path, files, robot, expected):
    write(tmp_path, files)
    line = one_error(
        run_cli(tmp_path, "design", "--robot", robot, "--tip-link", "flang", "--poses", "8")
    )
    for fragment in expected:
        assert fragment in line, line
    with pytest.raises(ArmcalError):
        load_robot(tmp_path / robot if files else robot, tip_link="flang")


# --------------------------------------------------------------------------- 2. grippers


def test_a_chain_that_ends_in_a_finger_warns_and_names_the_hand(tmp_path):
    """The single leaf is the finger: the 2R arm is read with 3 joints, the last the
    finger's; the warning names link 'hand' and how to choose it, on stderr and in the
    JSON; with --tip-link hand the arm has its 2 joints and no warning."""
    write(tmp_path, {"arm.urdf": GRIPPER_URDF})
    spec = load_spatial_robot(tmp_path / "arm.urdf")
    assert spec.arm.n_joints == 3
    (warning,) = spec.warnings
    assert warning.code == "gripper-joint"
    for fragment in ("'finger_joint'", "prismatic", "finger", "3 joints", "link 'hand'"):
        assert fragment in warning.message, warning.message
    assert "--" not in warning.message
    # The finger's joint slides: its column is in mm (q3_mm), the arm's in degrees.
    plan = plan_csv(np.random.default_rng(7).uniform(-90, 90, (15, 3)))
    write(tmp_path, {"plan.csv": plan.replace("q3_deg", "q3_mm", 1)})
    result = run_cli(tmp_path, "evaluate", "--robot", "arm.urdf", "--plan", "plan.csv", "--json")
    assert result.returncode == 0, result.stderr
    (shown,) = [w for w in json.loads(result.stdout)["warnings"] if w["code"] == "gripper-joint"]
    assert "--tip-link LINK" in shown["message"]
    assert f"armcal: warning: {shown['message']}" in result.stderr
    chosen = load_spatial_robot(tmp_path / "arm.urdf", tip_link="hand")
    assert chosen.arm.n_joints == 2 and chosen.warnings == ()


def test_a_joint_that_others_mimic_is_a_gripper_s_whatever_its_name(tmp_path):
    """Joint 'j3' is mimicked by 'j4' (a second jaw): named as the tip, it warns and
    names 'l2', the link before it."""
    text = urdf(
        *(link(n) for n in ("base", "l1", "l2", "a", "b")),
        joint("j1", "base", "l1"),
        joint("j2", "l1", "l2"),
        joint("j3", "l2", "a", xyz="0.1 0 0"),
        joint("j4", "l2", "b", xyz="0.1 0 0", extra='<mimic joint="j3" multiplier="-1"/>'),
    )
    write(tmp_path, {"arm.urdf": text})
    (warning,) = load_spatial_robot(tmp_path / "arm.urdf", tip_link="a").warnings
    assert "other joints mimic it" in warning.message and "link 'l2'" in warning.message


def test_an_arm_whose_last_joint_is_its_own_warns_of_nothing(tmp_path):
    write(tmp_path, {"arm.urdf": TWO_LEAVES})
    assert load_spatial_robot(tmp_path / "arm.urdf", tip_link="flange").warnings == ()


def test_a_mimic_joint_on_the_chain_says_where_to_end_it(tmp_path):
    """The mimic finger as the one leaf: armcal cannot model it (no reading of its own,
    and a joint map is square); the error says so and names the link before it, not the
    joint map."""
    text = urdf(
        *(link(n) for n in ("base", "l1", "l2", "left", "right")),
        joint("j1", "base", "l1"),
        joint("j2", "l1", "l2"),
        joint("left_jaw", "l2", "left", "prismatic"),
        joint("right_jaw", "left", "right", "prismatic", extra='<mimic joint="left_jaw"/>'),
    )
    write(tmp_path, {"arm.urdf": text})
    line = one_error(run_cli(tmp_path, "design", "--robot", "arm.urdf", "--poses", "8"))
    expected = ("'right_jaw'", "mimic", "follows joint 'left_jaw'", "link 'left'", "--tip-link")
    for fragment in expected:
        assert fragment in line, line
    assert "joint_map" not in line


# --------------------------------------------------------------------------- 3. duplicates


def test_a_link_declared_twice_is_named_with_both_lines(tmp_path):
    """The second 'l1' was meant to be 'l2': said as a duplicate (lines 4 and 5 of the
    file), not as the missing 'l2'."""
    text = urdf(
        link("base") + "\n", link("l1") + "\n", link("l1") + "\n",
        joint("j1", "base", "l1"), joint("j2", "l1", "l2"),
    )  # fmt: skip
    write(tmp_path, {"arm.urdf": text})
    line = one_error(run_cli(tmp_path, "design", "--robot", "arm.urdf", "--poses", "8"))
    assert "link 'l1' is declared twice (lines 4 and 5)" in line and "arm.urdf" in line
    assert "not a <link>" not in line


def test_a_joint_declared_twice_is_named_with_both_lines(tmp_path):
    text = urdf(
        *(link(n) for n in ("base", "l1", "l2")), "\n",
        joint("j1", "base", "l1"), joint("j1", "l1", "l2"),
    )  # fmt: skip
    write(tmp_path, {"arm.urdf": text})
    with pytest.raises(
        InputError, match=re.escape("joint 'j1' is declared twice (lines 4 and 5)")
    ):
        read_urdf(tmp_path / "arm.urdf")


# --------------------------------------------------------------------------- 4. DH conventions


def test_a_standard_dh_table_under_mdh_is_named_for_what_it_is(tmp_path):
    """The UR5's standard table read as modified DH puts joints 5 and 6 on one axis (the
    last row's (alpha, a) = (0, 0) lies between them): the error says the table looks
    like standard DH and to write it under [dh], on the command line as in the library."""
    write(tmp_path, {"ur5.toml": dh_toml("mdh", UR5_ALPHA_DEG, UR5_A, [0] * 6, UR5_D)})
    line = one_error(run_cli(tmp_path, "design", "--robot", "ur5.toml", "--poses", "30"))
    for fragment in (
        "ur5.toml",
        "joints 5 and 6 turn about one axis",
        "5 independent ways, not 6",
        "looks like standard DH",
        "under [dh]",
    ):
        assert fragment in line, line


def test_a_seven_axis_standard_table_under_mdh_is_named_too(tmp_path):
    """A KUKA LBR iiwa 7's standard DH table (Sciavicco-Siciliano style: every a = 0,
    alpha = -90, 90, 90, -90, -90, 90, 0, d = 340, 0, 400, 0, 400, 0, 126 mm): read as
    modified DH its joints 6 and 7 share an axis, though the rank is 6 of 7 as for the
    real arm; the pair alone names the mistake."""
    alpha, d = [-90, 90, 90, -90, -90, 90, 0], [340, 0, 400, 0, 400, 0, 126]
    write(tmp_path, {"iiwa.toml": dh_toml("mdh", alpha, [0] * 7, [0] * 7, d)})
    with pytest.raises(InputError) as raised:
        load_spatial_robot(tmp_path / "iiwa.toml")
    message = str(raised.value)
    assert "joints 6 and 7 turn about one axis: two of its joints do the work of one" in message
    assert "write it under [dh]" in message
    write(tmp_path, {"iiwa.toml": dh_toml("dh", alpha, [0] * 7, [0] * 7, d)})
    assert load_spatial_robot(tmp_path / "iiwa.toml").arm.n_joints == 7


def test_a_dh_table_is_the_dh_product(tmp_path):
    """[dh] reads the UR5's table: its tip frames are the DH product written out, within
    1e-9 mm and 1e-12 rad, at 50 random readings; with a base and a tip frame too."""
    theta = [0.0, -90.0, 0.0, -90.0, 0.0, 0.0]
    extra = "base_xyz_mm = [10, 20, 30]\nbase_rpy_deg = [0, 0, 180]\ntip_xyz_mm = [0, 0, 50]\n"
    write(tmp_path, {"ur5.toml": dh_toml("dh", UR5_ALPHA_DEG, UR5_A, theta, UR5_D, extra)})
    chain = load_spatial_robot(tmp_path / "ur5.toml").arm.chain
    q = np.random.default_rng(0).uniform(-np.pi, np.pi, (50, 6))
    reference = dh_product(q, np.radians(theta), UR5_D, UR5_A, np.radians(UR5_ALPHA_DEG))
    base = np.array([[-1.0, 0, 0, 10], [0, -1.0, 0, 20], [0, 0, 1.0, 30], [0, 0, 0, 1]])
    tip = np.eye(4)
    tip[2, 3] = 50.0
    expected = base @ reference @ tip
    found = chain.forward(q)
    np.testing.assert_allclose(found[:, :3, 3], expected[:, :3, 3], rtol=0, atol=1e-9)
    np.testing.assert_allclose(found[:, :3, :3], expected[:, :3, :3], rtol=0, atol=1e-12)


def test_a_dh_table_with_a_prismatic_joint_is_the_dh_product(tmp_path):
    """A cylindrical RPR arm under [dh]: the prismatic reading adds to d (mm)."""
    alpha, a, theta, d = (
        [0.0, -90.0, 0.0],
        [100.0, 0.0, 0.0],
        [0.0, 0.0, 30.0],
        [400.0, 50.0, 80.0],
    )
    extra = 'joint_types = ["R", "P", "R"]\n'
    write(tmp_path, {"arm.toml": dh_toml("dh", alpha, a, theta, d, extra)})
    chain = load_spatial_robot(tmp_path / "arm.toml").arm.chain
    rng = np.random.default_rng(1)
    q = np.column_stack([rng.uniform(-3, 3, 20), rng.uniform(0, 500, 20), rng.uniform(-3, 3, 20)])
    expected = dh_product(q, np.radians(theta), d, a, np.radians(alpha), ["R", "P", "R"])
    np.testing.assert_allclose(chain.forward(q), expected, rtol=0, atol=1e-9)


def test_a_modified_dh_table_under_dh_is_named_for_what_it_is(tmp_path):
    """PRODUCT.md's modified DH example read as standard DH: its first row's (0, 0) puts
    joints 1 and 2 on one axis; the table looks like modified DH."""
    alpha, a = [0, -90, 180, -90, 90, -90], [0, 312, 1075, 225, 0, 0]
    theta, d = [0, -90, 0, 0, 0, 0], [0, 0, 0, -1280, 0, -215]
    write(tmp_path, {"arm.toml": dh_toml("dh", alpha, a, theta, d)})
    with pytest.raises(InputError) as raised:
        load_spatial_robot(tmp_path / "arm.toml")
    message = str(raised.value)
    assert "joints 1 and 2 turn about one axis" in message
    assert "looks like modified DH; write it under [mdh]" in message
    write(tmp_path, {"arm.toml": dh_toml("mdh", alpha, a, theta, d)})
    assert load_spatial_robot(tmp_path / "arm.toml").arm.n_joints == 6


def test_a_degenerate_table_that_is_degenerate_both_ways_is_not_blamed_on_the_convention(
    tmp_path,
):
    """A planar 4R arm (every alpha 0) moves its tip in 3 independent ways under either
    convention: a redundant planar arm, not a convention mistake, so it loads."""
    write(tmp_path, {"arm.toml": dh_toml("mdh", [0] * 4, [0, 300, 200, 100], [0] * 4, [0] * 4)})
    assert load_spatial_robot(tmp_path / "arm.toml").arm.n_joints == 4


# --------------------------------------------------------------------------- 5. encodings


def test_a_latin_1_urdf_that_declares_it_reads(tmp_path):
    """A comment and a link name in Latin-1 bytes (e-acute is 0xE9), with the encoding
    declared: the chain reads, its link names as the file means them, and an error's
    line is counted in the file's own lines."""
    text = TWO_LEAVES.replace(
        '<?xml version="1.0"?>', '<?xml version="1.0" encoding="ISO-8859-1"?>'
    )
    text = text.replace('"camera"', '"caméra"').replace("<robot", "<!-- bras articulé -->\n<robot")
    data = text.encode("latin-1")
    assert b"\xe9" in data
    with pytest.raises(UnicodeDecodeError):  # the bytes are not UTF-8: the declaration counts
        data.decode("utf-8")
    write(tmp_path, {"arm.urdf": data})
    found = read_urdf(tmp_path / "arm.urdf", tip_link="caméra")
    assert found.tip_link == "caméra" and found.chain.n_joints == 2
    bad = text.replace('<origin xyz="0.1 0 0"', '<origin xyz="0.1 0"')
    write(tmp_path, {"arm.urdf": bad.encode("latin-1")})
    line = bad.splitlines().index(next(s for s in bad.splitlines() if "l2_flange" in s)) + 1
    assert line == 6  # the declaration, the comment, <robot>, the links and j1, j2
    with pytest.raises(InputError, match=rf"line {line}, joint 'l2_flange'"):
        read_urdf(tmp_path / "arm.urdf", tip_link="flange")


def test_latin_1_bytes_without_a_declaration_say_so(tmp_path):
    write(tmp_path, {"arm.urdf": TWO_LEAVES.replace('"camera"', '"caméra"').encode("latin-1")})
    line = one_error(run_cli(tmp_path, "design", "--robot", "arm.urdf", "--poses", "8"))
    assert "not UTF-8 and it declares no encoding" in line and 'encoding="ISO-8859-1"' in line


# --------------------------------------------------------------------------- 6. UR's own URDF

#: The controller's quarter turn, as ur_description's default_kinematics.yaml writes it.
QUARTER = 1.570796327


def ur_description_urdf(d, a, calibration: np.ndarray | None = None) -> str:
    """A UR's URDF in the layout of Universal Robots' ROS description (ur_macro.xacro,
    expanded with a model's default_kinematics.yaml), written from the DH facts ``d``
    and ``a`` (m): base_link, then base_link_inertia turned by pi about z; each joint
    frame at the foot of its DH row's Rz(theta) Tz(d), placed by the previous row's
    Rx(alpha) Tx(a) (so wrist_2's origin is (0, -d5 sin q, d5 cos q), q the controller's
    quarter turn, and wrist_3's (0, d6 sin q, d6 cos q) with rpy (pi - q, pi, pi), as the
    YAML has it); wrist_3_link carries the flange frame (rpy 0, -pi/2, -pi/2) and tool0
    beyond it (pi/2, 0, pi/2), and 'base' (pi about z of base_link) and 'ft_frame' are
    leaves too.  ``calibration`` ``(6, 6)`` adds to every joint's xyz (m) and rpy, as the
    description does with a robot's calibration YAML."""
    pi = math.pi
    sq, cq = math.sin(QUARTER), math.cos(QUARTER)
    moving = [
        ("shoulder_pan_joint", "base_link_inertia", "shoulder_link", (0, 0, d[0]), (0, 0, 0)),
        ("shoulder_lift_joint", "shoulder_link", "upper_arm_link", (0, 0, 0), (QUARTER, 0, 0)),
        ("elbow_joint", "upper_arm_link", "forearm_link", (a[1], 0, 0), (0, 0, 0)),
        ("wrist_1_joint", "forearm_link", "wrist_1_link", (a[2], 0, d[3]), (0, 0, 0)),
        (
            "wrist_2_joint",
            "wrist_1_link",
            "wrist_2_link",
            (0, -d[4] * sq, d[4] * cq),
            (QUARTER, 0, 0),
        ),
        (
            "wrist_3_joint",
            "wrist_2_link",
            "wrist_3_link",
            (0, d[5] * sq, d[5] * cq),
            (pi - QUARTER, pi, pi),
        ),
    ]
    if calibration is not None:
        moving = [
            (n, p, c, np.add(xyz, extra[:3]), np.add(rpy, extra[3:]))
            for (n, p, c, xyz, rpy), extra in zip(moving, calibration, strict=True)
        ]
    fixed = [
        ("base_link-base_link_inertia", "base_link", "base_link_inertia", (0, 0, pi)),
        ("wrist_3-flange", "wrist_3_link", "flange", (0, -pi / 2, -pi / 2)),
        ("flange-tool0", "flange", "tool0", (pi / 2, 0, pi / 2)),
        ("base_link-base_fixed_joint", "base_link", "base", (0, 0, pi)),
        ("wrist_3_link-ft_frame", "wrist_3_link", "ft_frame", (pi, 0, 0)),
    ]
    names = ["base_link", "base_link_inertia", *(m[2] for m in moving)]
    names += ["flange", "tool0", "base", "ft_frame"]

    def numbers(values) -> str:
        return " ".join(repr(float(v)) for v in values)

    parts = [link(n) + "\n" for n in names]
    parts += [joint(n, p, c, "fixed", xyz="0 0 0", rpy=numbers(rpy)) for n, p, c, rpy in fixed]
    parts += [
        joint(n, p, c, xyz=numbers(xyz), rpy=numbers(rpy)).replace(
            '<limit lower="-3" upper="3"/>', f'<limit lower="{-2 * pi!r}" upper="{2 * pi!r}"/>'
        )
        for n, p, c, xyz, rpy in moving
    ]
    return urdf(*parts, name="ur5")


UR5_URDF = ur_description_urdf([v / 1000 for v in UR5_D], [v / 1000 for v in UR5_A])


def test_ur_s_own_urdf_is_the_dh_table_turned_by_half_a_turn(tmp_path):
    """The URDF written from the facts is the UR5's DH table (the DH product, twists of
    the controller's quarter turn) from a base turned by pi about z, to tool0 = the DH
    flange: within 1e-9 mm; and ur_frames finds the UR5 and those frames for every tip
    the description offers."""
    write(tmp_path, {"ur5.urdf": UR5_URDF})
    alpha = [QUARTER, 0, 0, QUARTER, -QUARTER, 0]
    q = np.random.default_rng(2).uniform(-np.pi, np.pi, (100, 6))
    reference = dh_product(q, [0] * 6, UR5_D, UR5_A, alpha)
    turned = np.diag([-1.0, -1.0, 1.0, 1.0])  # Rz(pi): base_link from the DH base frame
    chain = read_urdf(tmp_path / "ur5.urdf", tip_link="tool0").chain
    np.testing.assert_allclose(chain.forward(q), turned @ reference, rtol=0, atol=1e-9)
    for tip in ("tool0", "flange", "wrist_3_link", "ft_frame"):
        found = ur_frames(read_urdf(tmp_path / "ur5.urdf", tip_link=tip).chain)
        assert found.model == "ur5" and found.distance_mm < 1e-9, tip
        np.testing.assert_allclose(found.base, turned.T, rtol=0, atol=1e-12)
    # The description with a robot's calibration (joints 2-6 moved by 0.3 mm and 1 mrad,
    # joint 1 turned about its axis and raised, as a DH row's theta and d): the same
    # frames, exactly, and the calibration stays in the chain (its flange moves mm).
    rng = np.random.default_rng(8)
    moved = np.hstack([rng.normal(0, 3e-4, (6, 3)), rng.normal(0, 1e-3, (6, 3))])
    moved[0] = [0, 0, 2e-4, 0, 0, 1e-3]
    write(tmp_path, {"cal.urdf": ur_description_urdf(
        [v / 1000 for v in UR5_D], [v / 1000 for v in UR5_A], moved)})  # fmt: skip
    found = ur_frames(read_urdf(tmp_path / "cal.urdf", tip_link="tool0").chain)
    assert found.model == "ur5" and 0.5 < found.distance_mm < 20
    np.testing.assert_array_equal(found.base, turned.T)
    np.testing.assert_array_equal(found.tip, np.eye(4))


def test_a_ur5_calibrated_from_ur_s_own_urdf_exports_to_its_controller(tmp_path):
    """A virtual UR5 described by UR's own URDF (--tip-link tool0): synthesize with a
    truth that moves joints 2-5 (0.2 mm, 0.02 deg) and joint 3's zero, identify, export
    --ur-calibration and --ros-calibration.  A [ur] robot file on the exported deltas
    (and on the YAML) is the calibrated arm: its flange, in the DH base frame, is the
    calibration's tool0 turned back by pi about z, within 1e-9 mm and 1e-12 rad (the
    tolerance of tests/test_ur.py: metres of d that cancel)."""
    truth = (
        "base = { xyz_mm = [2500, -800, -400], rpy_deg = [0, 0, 30] }\n[errors]\n"
        + "".join(f"j{k}.x = 0.2\nj{k}.rx = 0.02\n" for k in (2, 3, 4, 5))
        + "dq3 = 0.03\n[targets]\ntool = { xyz_mm = [0, 0, 60] }\n"
    )
    q_deg = np.random.default_rng(3).uniform(-170, 170, (40, 6))
    write(tmp_path, {"ur5.urdf": UR5_URDF, "truth.toml": truth, "plan.csv": plan_csv(q_deg)})
    robot = ("--robot", "ur5.urdf", "--tip-link", "tool0")
    steps = [
        ("synthesize", *robot, "--truth", "truth.toml", "--plan", "plan.csv", "--sigma", "0",
         "-o", "meas.csv"),
        ("identify", *robot, "--measurements", "meas.csv", "-o", "cal.json"),
        ("export", "--calibration", "cal.json", "--ur-calibration", "out.conf",
         "--ros-calibration", "out.yaml"),
    ]  # fmt: skip
    for step in steps:
        result = run_cli(tmp_path, *step)
        assert result.returncode == 0, (step[0], result.stderr)
    cal = read_calibration(tmp_path / "cal.json")
    calibrated = cal.arm.calibrated_chain(cal.arm_params)  # base_link to tool0
    q = np.random.default_rng(4).uniform(-np.pi, np.pi, (200, 6))
    expected = np.diag([-1.0, -1.0, 1.0, 1.0]) @ calibrated.forward(q)  # in the DH base
    nominal = read_urdf(tmp_path / "ur5.urdf", tip_link="tool0").chain
    moved = calibrated.forward(q)[:, :3, 3] - nominal.forward(q)[:, :3, 3]
    assert np.max(np.linalg.norm(moved, axis=1)) > 0.1  # the calibration is no nominal arm
    for written in ("out.conf", "out.yaml"):
        (tmp_path / "cell.toml").write_text(
            f'[ur]\nmodel = "ur5"\ncalibration = "{written}"\n', encoding="utf-8"
        )
        exported = load_spatial_robot(tmp_path / "cell.toml")
        assert exported.warnings == ()
        found = exported.arm.chain.forward(q)
        np.testing.assert_allclose(found[:, :3, 3], expected[:, :3, 3], rtol=0, atol=1e-9)
        np.testing.assert_allclose(found[:, :3, :3], expected[:, :3, :3], rtol=0, atol=1e-12)


def test_a_six_axis_arm_that_is_no_ur_is_still_refused_for_ur_export(tmp_path):
    """The built-in industrial 6R is no UR in any frames: refused, naming the nearest."""
    q_deg = np.random.default_rng(5).uniform(-60, 60, (30, 6))
    write(tmp_path, {"plan.csv": plan_csv(q_deg)})
    for step in (
        ("synthesize", "--robot", "industrial-6r", "--plan", "plan.csv", "-o", "meas.csv"),
        ("identify", "--robot", "industrial-6r", "--measurements", "meas.csv", "-o", "c.json"),
    ):
        assert run_cli(tmp_path, *step).returncode == 0, step
    line = one_error(
        run_cli(tmp_path, "export", "--calibration", "c.json", "--ur-calibration", "o.conf")
    )
    assert "o.conf" in line and "no UR model in any base and tip frames (nearest" in line
    assert not (tmp_path / "o.conf").exists()


# --------------------------------------------------------------------------- beyond the list


@pytest.mark.parametrize(
    ("name", "content", "expected"),
    [
        (
            "arm.urdf.xacro",
            urdf(
                '<xacro:property name="l" value="0.3"/>',
                *(link(n) for n in ("base", "l1")),
                joint("j1", "base", "l1", xyz="${l} 0 0"),
            ).replace("<robot ", '<robot xmlns:xacro="http://www.ros.org/wiki/xacro" '),
            ("arm.urdf.xacro", "a xacro file", "xacro robot.urdf.xacro > robot.urdf"),
        ),
        (
            "arm.urdf",
            urdf(*(link(n) for n in ("base", "l1")), '<xacro:include filename="x"/>'),
            ("arm.urdf", "not well-formed XML", "xacro file, not a URDF"),
        ),
        ("arm.urdf", "", ("arm.urdf", "the file is empty")),
        (
            "arm.urdf",
            urdf(link("base")).replace('"1.0"?>', '"1.0" encoding="klingon"?>'),
            ("arm.urdf", "unknown encoding: klingon", "save the file as UTF-8"),
        ),
        (
            "arm.urdf",
            urdf(link("base"), link("tool"), joint("mount", "base", "tool", "fixed")),
            ("arm.urdf", "no moving joint", "'base'", "'tool'"),
        ),
        ("arm.urdf", "name = 'x'\n", ("arm.urdf", "a URDF is XML")),
        (
            "arm.urdf",
            urdf(*(link(n) for n in ("base", "l1", "l2", "stray")), joint("j1", "base", "l1"),
                 joint("j2", "l1", "l2")),
            ("arm.urdf", "2 root links (base, stray)", "no joint connects"),
        ),
        (
            "arm.urdf",
            urdf(*(link(n) for n in ("world", "base", "l1")),
                 joint("float", "world", "base", "floating"), joint("j1", "base", "l1")),
            ("arm.urdf", "'float'", "floating joint on the chain", "link 'base'", "--base-link"),
        ),
    ],
    ids=[
        "xacro", "xacro-unbound-prefix", "empty", "unknown-encoding", "no-moving-joint",
        "not-xml", "two-roots", "floating-on-chain",
    ],
)  # fmt: skip
def test_what_a_new_user_gives_by_mistake_is_named(tmp_path, name, content, expected):
    write(tmp_path, {name: content})
    line = one_error(run_cli(tmp_path, "design", "--robot", name, "--poses", "8"))
    for fragment in expected:
        assert fragment in line, line


def test_a_floating_or_planar_joint_off_the_chain_is_ignored(tmp_path):
    """A camera on a planar joint and a marker on a floating one beside the arm: joints
    off the chain are ignored, whatever their kind (they were refused)."""
    text = urdf(
        *(link(n) for n in ("base", "l1", "l2", "camera", "marker")),
        joint("j1", "base", "l1"),
        joint("j2", "l1", "l2"),
        joint("cam", "base", "camera", "planar"),
        joint("mark", "l1", "marker", "floating"),
    )
    write(tmp_path, {"arm.urdf": text})
    assert read_urdf(tmp_path / "arm.urdf", tip_link="l2").chain.n_joints == 2
    with pytest.raises(InputError, match="type 'ball' is not a URDF joint's"):
        write(tmp_path, {"arm.urdf": text.replace('"planar"', '"ball"')})
        read_urdf(tmp_path / "arm.urdf", tip_link="l2")
