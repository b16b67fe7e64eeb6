"""The files layer of every family guards its units (issue 34).

* A prismatic joint's column is ``q{j}_mm`` in every file read and written, its
  reading the slide in mm; a column in the other unit is an error.
* Unit mistakes in a spatial robot file: MDH angles or joint limits in radians, a
  slide's limits in metres, a URDF in millimetres or with limits in degrees.
* ``simulate`` and ``synthesize`` study the nominal arm of a robot file given no truth.
* The exported robot TOML keeps the arm's limits, those of a URDF under a coupled
  joint map included.

Every reference value here is computed independently of armcal (a modified DH
chain written out below, the paper's closed form), or derived in a comment.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

from armcal.export_spatial import spatial_robot_toml
from armcal.files import BUILTIN_SPATIAL_ROBOTS, load_spatial_robot
from armcal.files.joints import joint_names
from armcal.files.robot_units import MAX_REACH_MM
from armcal.files.tables import read_measurements, read_plan, read_program
from armcal.files.writers import format_measurements_csv, format_plan_csv, format_program_csv
from armcal.models import CalibratedArm
from helpers import central_differences, run_cli
from helpers_slide import (
    KINDS,
    LIMITS,
    SLIDE_TOML,
    SLIDE_TRUTH,
    slide_plan,
    slide_points,
)


def _csv(header: list[str], rows: np.ndarray) -> str:
    lines = (",".join(repr(float(v)) for v in row) for row in rows)
    return ",".join(header) + "\n" + "".join(line + "\n" for line in lines)


def _json(run) -> dict:
    assert run.returncode == 0, run.stderr
    return json.loads(run.stdout)


def _error(run) -> str:
    """The one ``armcal: error:`` line of a run that failed on bad input."""
    assert run.returncode == 2, (run.stdout, run.stderr)
    assert "Traceback" not in run.stderr
    lines = run.stderr.splitlines()
    assert len(lines) == 1 and lines[0].startswith("armcal: error:"), run.stderr
    return lines[0]


# --------------------------------------------------------------------------- 1. slides in mm


def test_joint_columns_say_each_joints_unit():
    assert joint_names(KINDS) == ["q1_deg", "q2_deg", "q3_deg", "q4_mm", "q5_deg"]
    assert joint_names(3) == ["q1_deg", "q2_deg", "q3_deg"]  # a planar arm's


def test_every_writer_writes_a_slide_in_mm_and_every_reader_reads_it_back(tmp_path):
    (tmp_path / "arm.toml").write_text(SLIDE_TOML)
    arm = load_spatial_robot(tmp_path / "arm.toml").arm
    q_file = slide_plan(7, seed=1)
    # the model takes rad for a revolute joint and mm for a slide
    q = np.where(np.array(KINDS) == "R", np.radians(q_file), q_file)
    points = slide_points(q_file)
    texts = {
        "plan.csv": format_plan_csv(q, kinds=arm.joint_kinds),
        "meas.csv": format_measurements_csv(q, points, kinds=arm.joint_kinds),
        "corrected.csv": format_program_csv(q, np.ones(7, bool), kinds=arm.joint_kinds),
    }
    for name, text in texts.items():
        header = text.splitlines()[0].split(",")
        assert header[:5] == ["q1_deg", "q2_deg", "q3_deg", "q4_mm", "q5_deg"], name
        slide = np.array([float(line.split(",")[3]) for line in text.splitlines()[1:]])
        np.testing.assert_array_equal(slide, q_file[:, 3])  # mm as they are, exactly
        (tmp_path / name).write_text(text)
    # revolute angles go through degrees and back (a few ulp), the slide exactly
    np.testing.assert_allclose(read_plan(tmp_path / "plan.csv", arm), q, rtol=0, atol=1e-13)
    # compensate's output adds a 'corrected' column to the program's
    program = "\n".join(line.rsplit(",", 1)[0] for line in texts["corrected.csv"].splitlines())
    (tmp_path / "prog.csv").write_text(program + "\n")
    np.testing.assert_allclose(read_program(tmp_path / "prog.csv", arm).q, q, atol=1e-13)
    meas = read_measurements(tmp_path / "meas.csv", arm)
    np.testing.assert_array_equal(meas.q[:, 3], q_file[:, 3])
    np.testing.assert_allclose(meas.q, q, rtol=0, atol=1e-13)


def _table(text: str) -> dict[str, np.ndarray]:
    """A CSV's numeric columns by name (the text columns left out)."""
    header = text.splitlines()[0].split(",")
    rows = [line.split(",") for line in text.splitlines()[1:]]
    out = {}
    for c, name in enumerate(header):
        try:
            out[name] = np.array([float(row[c]) for row in rows])
        except ValueError:
            continue
    return out


def test_a_slide_moves_its_reading_in_mm(tmp_path):
    # synthesize without --truth: the nominal arm, its base at the instrument's origin
    # and the target where [targets] puts it, so the points are those of the table
    # written out above
    (tmp_path / "arm.toml").write_text(SLIDE_TOML + "[targets]\nA = { xyz_mm = [10, 20, 30] }\n")
    q_file = slide_plan(12, seed=2)
    (tmp_path / "plan.csv").write_text(_csv(joint_names(KINDS), q_file))
    run = run_cli(
        tmp_path, "synthesize", "--robot", "arm.toml", "--plan", "plan.csv", "--sigma", "0",
        "-o", "meas.csv",
    )  # fmt: skip
    assert run.returncode == 0, run.stderr
    assert "truth: nominal (no --truth)" in run.stdout
    table = _table((tmp_path / "meas.csv").read_text())
    np.testing.assert_array_equal(table["q4_mm"], q_file[:, 3])
    errors = np.zeros(6 + 7 * len(KINDS) + 3)
    errors[-3:] = [10.0, 20.0, 30.0]
    points = np.column_stack([table["x_mm"], table["y_mm"], table["z_mm"]])
    # 1e-9 mm: round-off of 4 x 4 products over a 1.5 m arm (about 1e-12), far below
    # the 3.4 mm a 200 mm reading read as degrees would be off by
    np.testing.assert_allclose(points, slide_points(q_file, errors), rtol=0, atol=1e-9)


def _identifiable_rank(q_file: np.ndarray, tool_mm: np.ndarray) -> int:
    """The rank of the central-difference Jacobian of :func:`slide_points` in its
    over-complete errors, with the measured point ``tool_mm`` from the tip: how many
    parameters the poses can identify."""
    n = len(KINDS)
    at = np.zeros(6 + 7 * n + 3)
    at[-3:] = tool_mm
    jac = central_differences(lambda e: slide_points(q_file, e).ravel(), at, 1e-4)
    s = np.linalg.svd(jac, compute_uv=False)
    # Every column moves the points by about 1 mm per unit (mm, mrad at a 1 m lever, deg x
    # 17 mm at 1 m).  A combination the poses cannot see has only central differences'
    # error: h^2 |f'''| / 6 + eps |f| / h, about 1e-9 mm per unit for 1e-4 steps of a
    # 2 m arm, 1e-11 of the largest singular value (as measured); one they see keeps a
    # fair share of it over 40 random poses (the smallest here is 2e-3 of it).  1e-5 of
    # the largest lies orders of magnitude from both.
    return int(np.sum(s > 1e-5 * s[0]))


def test_a_slide_arm_is_identified_to_round_off_with_every_identifiable_parameter(tmp_path):
    (tmp_path / "arm.toml").write_text(SLIDE_TOML)
    (tmp_path / "truth.toml").write_text(SLIDE_TRUTH)
    q_file = slide_plan(40, seed=3)
    (tmp_path / "plan.csv").write_text(_csv(joint_names(KINDS), q_file))
    fresh = slide_plan(25, seed=4)
    (tmp_path / "fresh.csv").write_text(_csv(joint_names(KINDS), fresh))
    for plan, out in (("plan.csv", "meas.csv"), ("fresh.csv", "test.csv")):
        run = run_cli(
            tmp_path, "synthesize", "--robot", "arm.toml", "--truth", "truth.toml",
            "--plan", plan, "--sigma", "0", "-o", out,
        )  # fmt: skip
        assert run.returncode == 0, run.stderr
    identify = ("identify", "--robot", "arm.toml", "--measurements", "meas.csv")
    cal = _json(run_cli(tmp_path, *identify, "--sigma", "0.001", "--json", "-o", "cal.json"))
    free = [p for p in cal["parameters"] if not p["fixed"]]
    values = {p["name"]: p["value"] for p in cal["parameters"]}
    # The target of a robot file without [targets] (and so the true one here): 100 mm
    # beyond the tip, 50 mm off the last joint's axis (which a point on it could not see
    # turn); the fit finds it there.
    tool = np.array([values["tool.x"], values["tool.y"], values["tool.z"]])
    np.testing.assert_allclose(tool, [50.0, 0.0, 100.0], rtol=0, atol=1e-9)
    # theory (Everett): 4R + 2P + 3k for points of k targets: 4 x 4 + 2 x 1 + 3 x 1 = 21,
    # and the rank of an independent Jacobian at these poses says the same
    assert len(free) == 4 * 4 + 2 * 1 + 3 * 1 == _identifiable_rank(q_file, tool)
    # round-off: a 1.5 m arm's points to about 1e-13 mm; 1e-9 leaves room for the fit's
    # stopping rule, far below any unit mistake (the slide's zero 0.5 mm read as 0.5 deg)
    assert cal["residual_rms_mm"] < 1e-9
    assert values["dq4"] == pytest.approx(0.5, abs=1e-9)  # the slide's zero, mm
    assert values["dq2"] == pytest.approx(0.03, abs=1e-9)  # deg
    validate = ("validate", "--calibration", "cal.json", "--measurements", "test.csv")
    checked = _json(run_cli(tmp_path, *validate, "--json"))
    assert checked["rms_after_mm"] < 1e-9  # fresh poses of the true arm, to round-off
    # compensate writes the slide's corrected commands in mm: within a few mm of the
    # program's (the errors are 0.5 mm and hundredths of a degree), where degrees of
    # them would be 57 times the program's
    program = np.array([[10, 20, 30, 200, 40], [-30, 10, -20, 100, 25], [50, -40, 60, 300, -30]])
    (tmp_path / "prog.csv").write_text(_csv(joint_names(KINDS), program))
    compensate = ("compensate", "--calibration", "cal.json", "--program", "prog.csv")
    done = run_cli(tmp_path, *compensate, "-o", "corrected.csv")
    assert done.returncode == 0, done.stderr
    corrected = _table((tmp_path / "corrected.csv").read_text())
    assert corrected["corrected"].tolist() == [1, 1, 1]
    np.testing.assert_allclose(corrected["q4_mm"], program[:, 3], rtol=0, atol=5.0)


@pytest.mark.slow
def test_design_writes_a_slide_in_mm(tmp_path):
    (tmp_path / "arm.toml").write_text(SLIDE_TOML)
    run = run_cli(tmp_path, "design", "--robot", "arm.toml", "--poses", "25", "-o", "plan.csv")
    assert run.returncode == 0, run.stderr
    plan = _table((tmp_path / "plan.csv").read_text())
    assert list(plan)[:5] == joint_names(KINDS)
    # within the slide's limits in mm (degrees of them would reach 22918)
    assert plan["q4_mm"].min() >= 0.0 and plan["q4_mm"].max() <= 400.0
    assert plan["q4_mm"].max() - plan["q4_mm"].min() > 100.0  # the design moves the slide


def test_measurements_in_mm_from_elsewhere_fit_to_round_off(tmp_path):
    # data written without armcal (the nominal arm, placed and with a tool of its own, by
    # the table above) fit exactly: the slide's reading is taken as the mm it is
    (tmp_path / "arm.toml").write_text(SLIDE_TOML)
    q_file = slide_plan(40, seed=5)
    errors = np.zeros(6 + 7 * len(KINDS) + 3)
    errors[:6] = [1500.0, 300.0, -200.0, 4.0, -3.0, 500.0]  # the tracker's pose (mm, mrad)
    errors[-3:] = [10.0, 20.0, 30.0]  # a tool point off the flange
    points = slide_points(q_file, errors)
    header = [*joint_names(KINDS), "x_mm", "y_mm", "z_mm"]
    (tmp_path / "meas.csv").write_text(_csv(header, np.column_stack([q_file, points])))
    cal = _json(
        run_cli(
            tmp_path, "identify", "--robot", "arm.toml", "--measurements", "meas.csv", "--json"
        )
    )
    assert cal["residual_rms_mm"] < 1e-9
    assert sum(not p["fixed"] for p in cal["parameters"]) == 21
    joint = [p for p in cal["parameters"] if p["name"].startswith(("j", "dq"))]
    # the arm is the nominal one: every identified error of a joint is 0 to round-off
    assert max(abs(p["value"]) for p in joint) < 1e-9


@pytest.mark.parametrize(
    ("column", "kind", "fix"),
    [
        ("q4_deg", "prismatic", "name the column q4_mm and give millimetres"),
        ("q4_rad", "prismatic", "name the column q4_mm and give millimetres"),
        ("q4_m", "prismatic", "name the column q4_mm and give millimetres"),
    ],
)
def test_a_slide_read_as_an_angle_is_an_error(tmp_path, column, kind, fix):
    (tmp_path / "arm.toml").write_text(SLIDE_TOML)
    header = joint_names(KINDS)
    header[3] = column
    (tmp_path / "plan.csv").write_text(_csv(header, slide_plan(5, seed=6)))
    line = _error(run_cli(tmp_path, "evaluate", "--robot", "arm.toml", "--plan", "plan.csv"))
    for text in ("plan.csv", "line 1", column, kind, fix):
        assert text in line, line


def test_a_revolute_joint_in_mm_is_an_error(tmp_path):
    (tmp_path / "arm.toml").write_text(SLIDE_TOML)
    header = [*joint_names(KINDS), "x_mm", "y_mm", "z_mm"]
    header[1] = "q2_mm"
    rows = np.column_stack([slide_plan(5, seed=7), np.zeros((5, 3))])
    (tmp_path / "meas.csv").write_text(_csv(header, rows))
    line = _error(
        run_cli(tmp_path, "identify", "--robot", "arm.toml", "--measurements", "meas.csv")
    )
    for text in ("meas.csv", "q2_mm", "revolute", "name the column q2_deg and give degrees"):
        assert text in line, line


def test_a_slide_beyond_its_limit_is_judged_in_mm(tmp_path):
    (tmp_path / "arm.toml").write_text(SLIDE_TOML)
    arm = load_spatial_robot(tmp_path / "arm.toml").arm
    q_file = slide_plan(6, seed=8)
    points = slide_points(q_file)
    header = [*joint_names(KINDS), "x_mm", "y_mm", "z_mm"]
    # 1 mm past the 400 mm limit: within the 2 mm a measured slide is allowed, a warning
    q_file[2, 3] = 401.0
    (tmp_path / "meas.csv").write_text(_csv(header, np.column_stack([q_file, points])))
    meas = read_measurements(tmp_path / "meas.csv", arm)
    (warning,) = meas.warnings
    assert warning.code == "beyond-limits"
    assert "q4_mm = 401 ([0, 400], 1 mm beyond)" in warning.message
    # 3 mm past it: an error that says mm
    q_file[2, 3] = 403.0
    (tmp_path / "meas.csv").write_text(_csv(header, np.column_stack([q_file, points])))
    line = _error(
        run_cli(tmp_path, "identify", "--robot", "arm.toml", "--measurements", "meas.csv")
    )
    assert "row 3 (line 4), column q4_mm: 403 mm is outside joint 4's limits [0, 400] mm" in line


def test_a_joint_map_cannot_mix_a_slide_and_an_angle(tmp_path):
    rows = np.eye(5, dtype=int).tolist()
    rows[4][3] = 1  # joint 5 (revolute) would turn by reading 4 (a slide, mm)
    (tmp_path / "arm.toml").write_text(SLIDE_TOML.replace("[mdh]", f"joint_map = {rows}\n[mdh]"))
    (tmp_path / "plan.csv").write_text(_csv(joint_names(KINDS), slide_plan(5, seed=9)))
    line = _error(run_cli(tmp_path, "evaluate", "--robot", "arm.toml", "--plan", "plan.csv"))
    for text in ("arm.toml", "joint_map", "row 5, column 4", "set it to 0"):
        assert text in line, line


# --------------------------------------------------------------------------- 2. robot units

#: A six-axis table in degrees (the PRODUCT.md example), and its angles in radians.
SIX_DEG = """name = "my-6r"
[mdh]
alpha_deg = [0, -90, 180, -90, 90, -90]
a_mm = [0, 312, 1075, 225, 0, 0]
theta_deg = [0, -90, 0, 0, 0, 0]
d_mm = [0, 0, 0, -1280, 0, -215]
"""


@pytest.mark.parametrize(
    ("old", "new", "key", "value"),
    [
        ("alpha_deg = [0, -90, 180, -90, 90, -90]",
         "alpha_deg = [0, -1.5708, 3.1416, -1.5708, 1.5708, -1.5708]", "mdh.alpha_deg", "-1.5708"),
        # two decimals, as people write radians; the twists are all 0 (parallel axes)
        ("alpha_deg = [0, -90, 180, -90, 90, -90]\n", "alpha_deg = [0, 0, 0, 0, 0, 0]\n"
         "theta_deg = [0, -1.57, 0, 3.14, 0, 0]\n", "mdh.theta_deg", "-1.57"),
        ("d_mm = [0, 0, 0, -1280, 0, -215]",
         "d_mm = [0, 0, 0, -1280, 0, -215]\nbase_rpy_deg = [0, 0, 3.14159]",
         "mdh.base_rpy_deg", "3.14159"),
    ],
)  # fmt: skip
def test_mdh_angles_in_radians_are_an_error(tmp_path, old, new, key, value):
    text = SIX_DEG.replace(old, new)
    if "theta_deg = [0, -1.57" in text:
        text = text.replace("theta_deg = [0, -90, 0, 0, 0, 0]\n", "")
    (tmp_path / "arm.toml").write_text(text)
    line = _error(run_cli(tmp_path, "design", "--robot", "arm.toml", "--poses", "30"))
    for part in ("arm.toml", f"key '{key}'", value, "looks like radians", "give degrees"):
        assert part in line, line


def test_the_built_in_spatial_robots_and_a_degree_table_load_without_a_unit_warning(tmp_path):
    (tmp_path / "arm.toml").write_text(SIX_DEG)
    (tmp_path / "slide.toml").write_text(SLIDE_TOML)
    for robot in ("industrial-6r", "cobot-6r", "arm-7r", tmp_path / "arm.toml",
                  tmp_path / "slide.toml"):  # fmt: skip
        assert load_spatial_robot(robot).warnings == (), robot


def _warnings(tmp_path: Path, robot: str, plan_rows: np.ndarray, header: list[str]) -> list:
    """The warnings of ``synthesize --json`` on the robot file ``robot`` (stderr and JSON)."""
    (tmp_path / "plan.csv").write_text(_csv(header, plan_rows))
    run = run_cli(
        tmp_path, "synthesize", "--robot", robot, "--plan", "plan.csv", "-o", "meas.csv", "--json"
    )
    document = _json(run)
    for warning in document["warnings"]:
        assert f"armcal: warning: {warning['message']}" in run.stderr
    return document["warnings"]


def test_spatial_limits_in_radians_warn(tmp_path):
    limits = "[[-2.97, 2.97], [-1.57, 1.57], [-2.09, 2.09], [0, 400], [-2.09, 2.09]]"
    (tmp_path / "arm.toml").write_text(SLIDE_TOML.replace(str(LIMITS), limits))
    plan = np.array([[1.0, -1.0, 2.0, 100.0, 0.5], [-2.0, 1.5, -1.0, 300.0, -1.0]])
    warnings = _warnings(tmp_path, "arm.toml", plan, joint_names(KINDS))
    (warning,) = [w for w in warnings if w["code"] == "limits-radians"]
    assert "every revolute joint's limit is within +-6.3" in warning["message"]
    assert "[-170.2, 170.2] for [-2.97, 2.97] rad" in warning["message"]


def test_a_slides_limits_in_metres_warn(tmp_path):
    limits = str(LIMITS).replace("[0, 400]", "[0, 0.4]")
    (tmp_path / "arm.toml").write_text(SLIDE_TOML.replace(str(LIMITS), limits))
    plan = np.array([[10.0, 20.0, 30.0, 0.1, 40.0], [-10.0, -20.0, -30.0, 0.3, -40.0]])
    warnings = _warnings(tmp_path, "arm.toml", plan, joint_names(KINDS))
    (warning,) = [w for w in warnings if w["code"] == "limits-metres"]
    assert "prismatic joint 4 travels 0.4 mm ([0, 0.4])" in warning["message"]
    assert "[0, 400]" in warning["message"]


#: The built-in industrial 6R's URDF (a FANUC R-2000iC's nominal geometry).
INDUSTRIAL_URDF = BUILTIN_SPATIAL_ROBOTS["industrial-6r"].with_suffix(".urdf").read_text()


def _urdf_offsets_mm(text: str) -> float:
    """The sum of a URDF's joint origins' lengths (mm): an upper bound of its reach."""
    total = 0.0
    for line in text.splitlines():
        if "<origin" in line:
            start = line.index('xyz="') + 5
            xyz = [float(v) for v in line[start : line.index('"', start)].split()]
            total += 1000 * math.hypot(*xyz)
    return total


def _urdf_scaled(length: float, limit: float) -> str:
    """The built-in industrial 6R's URDF with every xyz times ``length`` and every limit
    times ``limit``."""
    text = INDUSTRIAL_URDF
    out = []
    for line in text.splitlines():
        for key, factor in (("xyz", length), ("lower", limit), ("upper", limit)):
            marker = f'{key}="'
            if marker in line and "axis" not in line:
                start = line.index(marker) + len(marker)
                end = line.index('"', start)
                values = " ".join(repr(float(v) * factor) for v in line[start:end].split())
                line = line[:start] + values + line[end:]
        out.append(line)
    return "\n".join(out) + "\n"


def test_a_urdf_in_millimetres_is_an_error(tmp_path):
    # the arm's offsets add up to about 2.9 m; written in mm, 2.9 km
    (tmp_path / "arm.urdf").write_text(_urdf_scaled(1000.0, 1.0))
    (tmp_path / "arm.toml").write_text('urdf = "arm.urdf"\n')
    for robot in ("arm.urdf", "arm.toml"):
        line = _error(run_cli(tmp_path, "design", "--robot", robot, "--poses", "30"))
        for part in ("arm.urdf", "km", "millimetres", "divide its xyz"):
            assert part in line, line


def test_the_reach_bound_lies_between_the_largest_arm_and_a_urdf_in_mm(tmp_path):
    # the built-in URDF's offsets add up to about 2.9 m: times 5.6 an arm of 16 m (under
    # Canadarm2's 17.6 m) loads, times 7.5 (22 m) does not
    reach = _urdf_offsets_mm(INDUSTRIAL_URDF)
    assert 5.6 * reach < 17_600 and 7.5 * reach > MAX_REACH_MM
    (tmp_path / "big.urdf").write_text(_urdf_scaled(5.6, 1.0))
    assert load_spatial_robot(tmp_path / "big.urdf").warnings == ()
    (tmp_path / "huge.urdf").write_text(_urdf_scaled(7.5, 1.0))
    line = _error(run_cli(tmp_path, "design", "--robot", "huge.urdf", "--poses", "30"))
    assert "beyond any arm's reach (20 m)" in line


def test_mdh_lengths_in_metres_warn(tmp_path):
    text = SIX_DEG.replace("[0, 312, 1075, 225, 0, 0]", "[0, 0.312, 1.075, 0.225, 0, 0]")
    (tmp_path / "arm.toml").write_text(text.replace("-1280, 0, -215", "-1.28, 0, -0.215"))
    (warning,) = load_spatial_robot(tmp_path / "arm.toml").warnings
    assert warning.code == "lengths-in-metres"
    # every row's offset is Tx(a) Tz(d), of length hypot(a, d)
    reach = 0.312 + 1.075 + math.hypot(0.225, 1.28) + 0.215
    assert f"add up to {reach:g} mm" in warning.message


def test_urdf_limits_in_degrees_warn(tmp_path):
    # limits in degrees read as radians: J1's +-185 deg as +-185 rad, 29 turns
    (tmp_path / "arm.urdf").write_text(_urdf_scaled(1.0, 180 / math.pi))
    (warning,) = load_spatial_robot(tmp_path / "arm.urdf").warnings
    assert warning.code == "urdf-limits-degrees"
    assert "joint_1 [-185, 185]" in warning.message
    assert "look" in warning.message and "radians" in warning.message


# --------------------------------------------------------------------------- 3. no truth

PLANAR = (
    'name = "bench"\nlink_lengths_mm = [260.0, 180.0, 120.0]\n[measurement]\nsigma_mm = 0.05\n'
)
PLANAR_ELASTIC = PLANAR.replace('"bench"', '"vertical"') + (
    "[elastostatic]\ngravity_xy = [0, -1]\nlink_masses_kg = [10, 6, 3]\npayload_kg = 5\n"
)
SLIDE_ELASTIC = (
    SLIDE_TOML
    + "[measurement]\nsigma_mm = 0.02\n"
    + "[elastostatic]\nlink_masses_kg = [30, 20, 10, 5, 2]\npayload_kg = 10\n"
)
PLANAR_PLAN = np.array(
    [[0, 10, 20], [30, -40, 50], [-60, 70, -80], [90, -100, 110], [-120, 130, -140],
     [150, -160, 170], [45, 45, 45], [-30, -60, 90]], dtype=float,
)  # fmt: skip


@pytest.mark.parametrize(
    ("robot", "header", "plan"),
    [
        pytest.param(PLANAR, joint_names(3), PLANAR_PLAN, id="planar"),
        pytest.param(PLANAR_ELASTIC, joint_names(3), PLANAR_PLAN, id="planar-compliance"),
        pytest.param(
            SLIDE_TOML + "[measurement]\nsigma_mm = 0.02\n", joint_names(KINDS),
            slide_plan(30, seed=10), id="spatial",
        ),
        pytest.param(SLIDE_ELASTIC, joint_names(KINDS), slide_plan(30, seed=10),
                     id="spatial-compliance"),
    ],
)  # fmt: skip
def test_simulate_without_a_truth_studies_the_nominal_arm(tmp_path, robot, header, plan):
    (tmp_path / "arm.toml").write_text(robot)
    (tmp_path / "plan.csv").write_text(_csv(header, plan))
    argv = ("simulate", "--robot", "arm.toml", "--plan", "plan.csv", "--trials", "20")
    text = run_cli(tmp_path, *argv)
    assert text.returncode == 0, text.stderr
    assert text.stdout.splitlines()[1] == "truth: nominal (no --truth)"
    document = _json(run_cli(tmp_path, *argv, "--json"))
    assert document["truth_source"] == "nominal"
    # the nominal arm: no deviation of a joint and no compliance (the base pose and the
    # targets of a spatial arm are where its nominal puts them)
    joint = {k: v for k, v in document["truth"].items() if not k.startswith(("base", "tool"))}
    assert joint and all(v == 0.0 for v in joint.values()), joint


def test_synthesize_without_a_truth_measures_the_nominal_arm(tmp_path):
    (tmp_path / "arm.toml").write_text(PLANAR)
    (tmp_path / "plan.csv").write_text(_csv(joint_names(3), PLANAR_PLAN))
    argv = ("synthesize", "--robot", "arm.toml", "--plan", "plan.csv", "--sigma", "0")
    run = run_cli(tmp_path, *argv, "-o", "meas.csv", "--json")
    assert _json(run)["truth_source"] == "nominal"
    table = np.loadtxt((tmp_path / "meas.csv").read_text().splitlines()[1:], delimiter=",")
    # paper eq. (1) with no deviation: x = sum l_i cos(q_1 + ... + q_i), y the same in sin
    angles = np.radians(np.cumsum(PLANAR_PLAN, axis=1))
    links = np.array([260.0, 180.0, 120.0])
    np.testing.assert_allclose(table[:, 3], np.cos(angles) @ links, rtol=0, atol=1e-9)
    np.testing.assert_allclose(table[:, 4], np.sin(angles) @ links, rtol=0, atol=1e-9)
    # to stdout, the measurements are the output and the note goes to stderr
    piped = run_cli(tmp_path, *argv)
    assert piped.returncode == 0 and piped.stdout.startswith("q1_deg")
    assert "armcal: truth: nominal (no --truth)" in piped.stderr
    # a built-in robot keeps its own truth
    plan4 = np.array([[0, 0, 0, 0], [90, 0, 0, 0], [0, 90, 0, 0], [0, 0, 90, 0]], float)
    (tmp_path / "plan4.csv").write_text(_csv(joint_names(4), plan4))
    builtin = run_cli(tmp_path, "synthesize", "--plan", "plan4.csv", "-o", "b.csv", "--json")
    assert _json(builtin)["truth_source"] == "built-in"


# --------------------------------------------------------------------------- 4. export


def _exported(tmp_path: Path, robot_text: str, urdf: str | None = None):
    """The arm of ``robot_text`` and the arm its exported robot TOML loads as."""
    if urdf is not None:
        (tmp_path / "arm.urdf").write_text(urdf)
    (tmp_path / "arm.toml").write_text(robot_text)
    arm = load_spatial_robot(tmp_path / "arm.toml").arm
    p = arm.n_params
    exported = spatial_robot_toml(CalibratedArm(arm, arm.nominal, np.zeros((p, p)), 0.1))
    (tmp_path / "exported.toml").write_text(exported)
    return arm, load_spatial_robot(tmp_path / "exported.toml").arm, exported


COUPLED = """urdf = "arm.urdf"
joint_map = [[1, 0, 0, 0, 0, 0], [0, 1, 0, 0, 0, 0], [0, 1, 1, 0, 0, 0],
             [0, 0, 0, 1, 0, 0], [0, 0, 0, 0, 1, 0], [0, 0, 0, 0, 0, 1]]
"""


def test_the_exported_robot_file_keeps_a_urdfs_limits_under_a_coupled_joint_map(tmp_path):
    arm, back, text = _exported(tmp_path, COUPLED, _urdf_scaled(1.0, 1.0))
    # the URDF's limits hold for the joint values u = M q: J3's elbow angle u3 = q2 + q3
    # within +-200 deg (the URDF's +-3.4906585 rad)
    assert "joint_limits_deg = [[-185.0, 185.0], [-60.0, 76.0], [-200.0, 200.0]" in text.replace(
        "-59.99999999999999", "-60.0"
    )
    np.testing.assert_array_equal(back.limits, arm.limits)
    np.testing.assert_array_equal(back.chain.joint_limits, arm.chain.joint_limits)
    # the same readings are within the limits: q2 = 70, q3 = 150 has u3 = 220 > 200
    q = np.radians([[0, 70, 150, 0, 0, 0], [0, 70, 120, 0, 0, 0]])
    np.testing.assert_array_equal(back.within_limits(q), arm.within_limits(q))
    assert arm.within_limits(q).all(axis=1).tolist() == [False, True]
    rng = np.random.default_rng(11)
    samples = rng.uniform(arm.limits[:, 0], arm.limits[:, 1], (2000, 6))
    np.testing.assert_array_equal(back.within_limits(samples), arm.within_limits(samples))


def test_the_exported_robot_file_keeps_the_readings_limits(tmp_path):
    # limits on the readings (the robot file's), and a URDF's under an identity map
    industrial = COUPLED + (
        "joint_limits_deg = [[-185, 185], [-60, 76], [-132, 150], [-360, 360], [-125, 125], "
        "[-360, 360]]\n"
    )
    for robot in (industrial, 'urdf = "arm.urdf"\n', SLIDE_TOML):
        arm, back, text = _exported(tmp_path, robot, _urdf_scaled(1.0, 1.0))
        np.testing.assert_array_equal(back.limits, arm.limits)
        rng = np.random.default_rng(12)
        low, high = arm.limits.T
        span = high - low
        samples = rng.uniform(low - 0.1 * span, high + 0.1 * span, (2000, arm.n_joints))
        np.testing.assert_array_equal(back.within_limits(samples), arm.within_limits(samples))
        assert "joint_limits_deg = [[-185.0, 185.0]" in text or robot == SLIDE_TOML


def test_a_plan_beyond_a_urdfs_limits_under_a_coupled_joint_map_is_an_error(tmp_path):
    (tmp_path / "arm.urdf").write_text(INDUSTRIAL_URDF)
    (tmp_path / "arm.toml").write_text(COUPLED)
    # every reading within its limits (a turn each way: no joint_limits_deg), but the elbow
    # angle u3 = q2 + q3 = 70 + 150 = 220 deg is beyond the URDF's +-200 deg
    plan = np.array([[0, 10, 20, 0, 30, 0], [0, 70, 150, 0, 30, 0], [0, -20, 40, 0, 30, 0]])
    (tmp_path / "plan.csv").write_text(_csv(joint_names(6), plan))
    line = _error(run_cli(tmp_path, "evaluate", "--robot", "arm.toml", "--plan", "plan.csv"))
    for text in ("plan.csv", "row 2 (line 3)", "joint 3", "joint_3", "220 deg", "[-200, 200]"):
        assert text in line, line
