"""Data the battery of real runs found misread or misnamed (issue 34): a truth file's
unknown target, a pose label reused for two joint readings, joint readings in the wrong
unit, payloads in the wrong unit or missing, a calibration of another arm, a slide's
wording.

Every case runs the program in-process (:func:`helpers.run_cli`) in a folder of its own
and checks the contract of PRODUCT.md "Errors" (exit 2, one ``armcal: error:`` line
naming file, key or row and the fix, no output written) or "Warnings" (the code on
stderr and in the JSON).
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from armcal.errors import InputError
from armcal.files.joints import SAME_POSE, check_pose_labels, joint_names
from helpers import Run, cell_toml, deviated_tip, planar_cell, run_cli
from helpers_paper import VALID_MEAS
from helpers_slide import KINDS, SLIDE_TOML, slide_plan, slide_points


def _one_error(run: Run) -> str:
    """The single ``armcal: error:`` line of a refused run (exit 2, nothing on stdout)."""
    assert run.returncode == 2, run.stderr
    lines = run.stderr.splitlines()
    assert len(lines) == 1, run.stderr
    assert lines[0].startswith("armcal: error: ")
    assert "Traceback" not in run.stderr
    return lines[0]


def _industrial_cell(folder: Path) -> None:
    """The virtual six-axis cell (the built-in industrial-6r's URDF, reflectors A, B, C)
    and a four-pose plan inside its limits."""
    from armcal.files.spatial import BUILTIN_SPATIAL_ROBOTS

    source = BUILTIN_SPATIAL_ROBOTS["industrial-6r"]
    (folder / "industrial-6r.urdf").write_text(source.with_suffix(".urdf").read_text())
    (folder / "cell.toml").write_text(cell_toml())
    rows = ["q1_deg,q2_deg,q3_deg,q4_deg,q5_deg,q6_deg,payload_kg"]
    rows += [f"{10 * k},{5 * k},{-10 * k},{20 * k},{30 + k},{-15 * k},0" for k in range(4)]
    (folder / "plan.csv").write_text("\n".join(rows) + "\n")


# -- 1. a truth file's target the robot does not have ------------------------------------


def test_truth_target_not_of_the_robot_is_named_with_the_robots_targets(tmp_path: Path):
    _industrial_cell(tmp_path)
    (tmp_path / "truth.toml").write_text("[targets]\nD = { xyz_mm = [0, 0, 100] }\n")
    run = run_cli(
        tmp_path,
        *("synthesize", "--robot", "cell.toml", "--truth", "truth.toml"),
        *("--plan", "plan.csv", "--seed", "1", "-o", "out.csv"),
    )
    line = _one_error(run)
    assert line.startswith("armcal: error: truth.toml: key 'targets.D': ")
    assert "'D' is not a target of cell-6r" in line
    assert "[targets] has A, B, C" in line
    assert "name one of them" in line
    assert not line.rstrip().endswith(";")  # the battery's line ended in a dangling '; '
    assert not (tmp_path / "out.csv").exists()


# -- 2. one pose label for two joint readings ----------------------------------------------


def _labelled_measurements(second_pose_q1: str) -> str:
    """Six rows of the paper's 4-link arm, labelled P1, P1, P1, P2, P2, P2; row 4's q1 is
    ``second_pose_q1`` (rows 5, 6 keep 30 deg).  The points are the nominal arm's
    (paper eq. 1 with lengths 260/180/120/100 mm), which the reader does not judge."""
    links, zero = (260.0, 180.0, 120.0, 100.0), (0.0,) * 4
    rows = ["pose,q1_deg,q2_deg,q3_deg,q4_deg,x_mm,y_mm"]
    poses = [("P1", (0.0, 40.0, 40.0, 40.0))] * 3 + [("P2", (30.0, 20.0, 20.0, 20.0))] * 3
    for k, (label, q) in enumerate(poses):
        x, y = deviated_tip(q, links, zero, zero)
        q1 = second_pose_q1 if k == 3 else f"{q[0]:g}"
        rows.append(f"{label},{q1},{q[1]:g},{q[2]:g},{q[3]:g},{x!r},{y!r}")
    return "\n".join(rows) + "\n"


def test_a_pose_label_reused_for_two_joint_readings_is_refused(tmp_path: Path):
    # row 4 (label P2) reads q1 = 0 deg, rows 5 and 6 (also P2) read 30 deg
    # (the point stays at q1 = 30 deg: only the label's two readings matter here)
    (tmp_path / "m.csv").write_text(_labelled_measurements("0"))
    run = run_cli(
        tmp_path, "identify", "--robot", "paper-4link", "--measurements", "m.csv", "-o", "cal.json"
    )
    line = _one_error(run)
    assert line.startswith("armcal: error: m.csv: rows 4 and 5 (lines 5 and 6), column pose: ")
    assert "'P2' is given to two different joint readings (q1_deg 0 and 30 deg)" in line
    assert "give the other pose a label of its own" in line
    assert not (tmp_path / "cal.json").exists()


def test_a_pose_label_over_readings_within_the_encoder_resolution_is_one_pose():
    # 0.005 deg apart, half of SAME_POSE (0.01 deg): one pose read twice
    q = np.array([[30.0, 20.0], [30.0 + SAME_POSE / 2, 20.0], [30.0 + 2 * SAME_POSE, 20.0]])
    check_pose_labels("m.csv", ["P", "P", "Q"], q, ("R", "R"), [2, 3, 4])  # no error
    with pytest.raises(InputError, match=r"rows 1 and 3 \(lines 2 and 4\)"):
        check_pose_labels("m.csv", ["P", "P", "P"], q, ("R", "R"), [2, 3, 4])
    check_pose_labels("m.csv", ["", "", ""], q, ("R", "R"), [2, 3, 4])  # empty: no label


# -- 3. joint readings in the wrong unit ---------------------------------------------------


def test_slide_readings_in_metres_are_named_before_the_fit(tmp_path: Path):
    # the five-joint arm of test_guard_files.py, whose joint 4 slides 0..400 mm; its points
    # are written out from its MDH table there, independently of armcal
    (tmp_path / "arm.toml").write_text(SLIDE_TOML)
    q_file = slide_plan(30, seed=9)
    points = slide_points(q_file)
    read = q_file.copy()
    read[:, 3] /= 1000.0  # the slide written in metres under q4_mm
    header = [*joint_names(KINDS), "x_mm", "y_mm", "z_mm"]
    rows = [",".join(repr(float(v)) for v in row) for row in np.column_stack([read, points])]
    (tmp_path / "meas.csv").write_text("\n".join([",".join(header), *rows]) + "\n")
    run = run_cli(
        tmp_path, "identify", "--robot", "arm.toml", "--measurements", "meas.csv", "-o", "c.json"
    )
    line = _one_error(run)
    assert line.startswith("armcal: error: meas.csv: the slide readings in q4_mm look like metres")
    assert f"they span {read[:, 3].min():.4g} to {read[:, 3].max():.4g}" in line
    assert line.endswith("convert them to mm")
    assert not (tmp_path / "c.json").exists()
    # the same readings in mm are no unit mistake: the fit runs (and writes its file)
    rows = [",".join(repr(float(v)) for v in row) for row in np.column_stack([q_file, points])]
    (tmp_path / "meas.csv").write_text("\n".join([",".join(header), *rows]) + "\n")
    run = run_cli(
        tmp_path, "identify", "--robot", "arm.toml", "--measurements", "meas.csv", "-o", "c.json"
    )
    assert run.returncode == 0, run.stderr
    assert (tmp_path / "c.json").exists()


#: A planar three-link arm whose joint 2 never reaches 0: -140..-5 deg (the battery's
#: kr-cell joint 2), so radians of its angles fall outside its limits.
BENT_ARM = """name = "bent-3link"
link_lengths_mm = [400.0, 300.0, 200.0]
joint_limits_deg = [[-170, 170], [-140, -5], [-150, 150]]
"""


def test_radians_that_break_a_joint_limit_are_named_as_radians(tmp_path: Path):
    (tmp_path / "arm.toml").write_text(BENT_ARM)
    q_deg = [(10.0 * k - 40.0, -5.0 - 12.0 * k, 15.0 * k - 60.0) for k in range(10)]
    lines = ["q1_deg,q2_deg,q3_deg,x_mm,y_mm"]
    zero = (0.0, 0.0, 0.0)
    for q in q_deg:
        x, y = deviated_tip(q, (400.0, 300.0, 200.0), zero, zero)  # paper eq. 1, by hand
        lines.append(",".join(f"{np.radians(v):.6f}" for v in q) + f",{x!r},{y!r}")
    (tmp_path / "meas.csv").write_text("\n".join(lines) + "\n")
    run = run_cli(
        tmp_path, "identify", "--robot", "arm.toml", "--measurements", "meas.csv", "-o", "c.json"
    )
    line = _one_error(run)
    # row 1: q2 = -5 deg = -0.0872665 rad, read as -0.087 deg, outside [-140, -5]
    assert line.startswith("armcal: error: meas.csv: row 1 (line 2), column q2_deg: ")
    assert "outside joint 2's limits [-140, -5] deg" in line
    # the largest angle, q2 = -5 - 12 * 9 = -113 deg, is 1.97 rad
    assert f"within +-{np.radians(113.0):.3g}, which looks like radians" in line
    assert "convert the angles to degrees" in line
    assert not (tmp_path / "c.json").exists()


# -- 4. payloads in another unit, beyond the calibrated range, or missing ------------------


def _vertical_cell(folder: Path) -> None:
    """test_guard_compliance.py's vertical 3-link arm (masses 20/12/6 kg, the robot file's
    payload_kg 10), its truth (k = 1.5/3/6 urad/(N m)) and 40 poses measured by
    synthesize, every other one under the 10 kg payload (meas.csv)."""
    planar_cell(folder)


def _with_payloads(folder: Path, name: str, change) -> None:
    """meas.csv with its payload_kg column changed by ``change`` (or left out: None)."""
    lines = (folder / "meas.csv").read_text().splitlines()
    header = lines[0].split(",")
    col = header.index("payload_kg")
    out = []
    for line in lines:
        fields = line.split(",")
        if change is None:
            del fields[col]
        elif line is not lines[0]:
            fields[col] = repr(change(float(fields[col])))
        out.append(",".join(fields))
    (folder / name).write_text("\n".join(out) + "\n")


def _codes(run: Run) -> dict[str, str]:
    """The warnings of a run's stderr by code: every line ``armcal: warning: ...`` and the
    JSON's ``warnings`` (when the run printed JSON) say the same."""
    codes = {w["code"]: w["message"] for w in json.loads(run.stdout)["warnings"]}
    for message in codes.values():
        assert f"armcal: warning: {message}" in run.stderr
    return codes


@pytest.mark.parametrize(
    ("unit", "per_kg"),
    [("grams", 1000.0), ("pounds", 2.20462)],  # the definitions: 1 kg = 1000 g = 2.20462 lb
)
def test_a_payload_column_in_grams_or_pounds_is_warned_of(tmp_path: Path, unit, per_kg):
    _vertical_cell(tmp_path)
    _with_payloads(tmp_path, "m.csv", lambda kg: kg * per_kg)
    run = run_cli(
        tmp_path, "identify", "--robot", "robot.toml", "--measurements", "m.csv", "--json"
    )
    assert run.returncode == 0, run.stderr
    words = _codes(run)["payload-unit"]
    # the heaviest row carries 10 kg (the robot file's payload_kg): 10 * per_kg in the file
    assert words.startswith(
        f"m.csv: column payload_kg: the rows carry up to {10 * per_kg:g} kg, "
        f"{per_kg:.4g} times the robot file's payload_kg (10 kg): they look like {unit}"
    )
    assert "give payload_kg in kg" in words
    assert f"armcal: warning: {words}" in run.stderr
    # in kg: no such warning
    run = run_cli(
        tmp_path, "identify", "--robot", "robot.toml", "--measurements", "meas.csv", "--json"
    )
    assert run.returncode == 0, run.stderr
    assert "payload-unit" not in _codes(run)


def test_a_forgotten_payload_column_is_named_as_the_likely_cause(tmp_path: Path):
    # half the rows were measured without the payload; read without the column, every row
    # carries the robot file's 10 kg, and 10 kg at up to 1.25 m on k3 = 6 urad/(N m) alone
    # turns the last link by ~0.7 mrad: tenths of a mm, far above sigma = 0.02 mm
    _vertical_cell(tmp_path)
    _with_payloads(tmp_path, "m.csv", None)
    run = run_cli(
        tmp_path, "identify", "--robot", "robot.toml", "--measurements", "m.csv", "--json"
    )
    assert run.returncode == 0, run.stderr
    codes = _codes(run)
    assert "fit-inconsistent" in codes
    assert codes["payload-missing"].startswith(
        "m.csv: has no payload_kg column, so every row was taken to carry the robot file's "
        "payload_kg (10 kg), and the fit is inconsistent with the noise"
    )
    assert "add the column payload_kg" in codes["payload-missing"]
    # with the column the fit is consistent, and nothing is said of it
    run = run_cli(
        tmp_path, "identify", "--robot", "robot.toml", "--measurements", "meas.csv", "--json"
    )
    assert not {"payload-missing", "fit-inconsistent"} & set(_codes(run))


def test_payloads_beyond_the_calibrated_range_are_an_extrapolation(tmp_path: Path):
    _vertical_cell(tmp_path)
    made = run_cli(
        tmp_path, "identify", "--robot", "robot.toml", "--measurements", "meas.csv",
        "-o", "cal.json",
    )  # fmt: skip
    assert made.returncode == 0, made.stderr
    (tmp_path / "prog.csv").write_text("q1_deg,q2_deg,q3_deg\n10,20,30\n-40,50,-60\n")

    def compensate(kg: str) -> Run:
        return run_cli(
            tmp_path, "compensate", "--calibration", "cal.json", "--program", "prog.csv",
            "--payload-kg", kg, "-o", "out.csv",
        )  # fmt: skip

    # the calibration saw 0 and 10 kg: 100 kg is 10 times its largest
    run = compensate("100")
    assert run.returncode == 0, run.stderr
    assert (
        "armcal: warning: prog.csv: payloads up to 100 kg, 10 times the largest the "
        "calibration was fitted under (0 to 10 kg)" in run.stderr
    )
    # twice its largest (PAYLOAD_EXTRAPOLATION) is not warned of
    run = compensate("20")
    assert run.returncode == 0 and "payload" not in run.stderr, run.stderr
    # validation on rows whose payloads are in grams: 1000 times, and the unit named
    _with_payloads(tmp_path, "grams.csv", lambda kg: kg * 1000.0)
    run = run_cli(
        tmp_path, "validate", "--calibration", "cal.json", "--measurements", "grams.csv",
        "--json",
    )  # fmt: skip
    assert run.returncode == 0, run.stderr
    words = _codes(run)["payload-extrapolated"]
    assert words.startswith("grams.csv: payloads up to 10000 kg, 1000 times the largest")
    assert words.endswith("if the payloads are not in kg, they look like grams (1000 per kg)")


# -- 5. a calibration of another arm -------------------------------------------------------


def test_a_calibration_of_another_arm_is_named_as_such(tmp_path: Path):
    # a calibration of paper-4link (4 joints) from test_cli_errors.py's valid measurements
    (tmp_path / "meas.csv").write_text(VALID_MEAS)
    made = run_cli(
        tmp_path, "identify", "--robot", "paper-4link", "--measurements", "meas.csv",
        "-o", "cal.json",
    )  # fmt: skip
    assert made.returncode == 0, made.stderr
    # a 3-joint arm's program (its joints well within any limits)
    (tmp_path / "prog.csv").write_text("q1_deg,q2_deg,q3_deg\n10,20,30\n-10,40,-20\n")
    run = run_cli(
        tmp_path, "compensate", "--calibration", "cal.json", "--program", "prog.csv",
        "-o", "out.csv",
    )  # fmt: skip
    line = _one_error(run)
    assert line == (
        "armcal: error: prog.csv: has 3 joint columns (q1_deg..q3_deg), but the calibration "
        "cal.json belongs to paper-4link, an arm of 4 joints: the program and the calibration "
        "cal.json are of different arms; pass the calibration of the same arm (or fix the "
        "header, if the file is of paper-4link)"
    )
    assert not (tmp_path / "out.csv").exists()
    # held-out measurements of that arm: the same words, for the measurements
    (tmp_path / "test.csv").write_text(
        "q1_deg,q2_deg,q3_deg,x_mm,y_mm\n10,20,30,100,200\n-10,40,-20,150,100\n"
    )
    run = run_cli(
        tmp_path, "validate", "--calibration", "cal.json", "--measurements", "test.csv",
        "--plot", "v.png",
    )  # fmt: skip
    line = _one_error(run)
    assert "the calibration cal.json belongs to paper-4link, an arm of 4 joints" in line
    assert "the measurements and the calibration cal.json are of different arms" in line
    assert not (tmp_path / "v.png").exists()


# -- 6. a slide's words ----------------------------------------------------------------------

#: A lift (joint 1 slides 0..800 mm along the base's z) under a three-joint arm.
LIFT_TOML = """name = "lift-arm"
joint_limits_deg = [[0, 800], [-170, 170], [-120, 120], [-170, 170]]
[mdh]
alpha_deg = [0, 0, -90, 0]
a_mm = [0, 0, 0, 400]
theta_deg = [0, 0, 0, 0]
d_mm = [0, 0, 0, 0]
joint_types = ["P", "R", "R", "R"]
tip_xyz_mm = [300, 0, 50]
[measurement]
sigma_mm = 0.02
"""


def test_a_slide_at_joint_1_slides_the_arm_in_the_identifiability_report(tmp_path: Path):
    (tmp_path / "lift.toml").write_text(LIFT_TOML)
    (tmp_path / "truth.toml").write_text(
        "base = { xyz_mm = [2000.0, -500.0, -300.0], rpy_deg = [0.2, -0.1, 30.0] }\n"
    )
    rng = np.random.default_rng(12)
    low, high = np.array([[0, 800], [-170, 170], [-120, 120], [-170, 170]], float).T
    q = rng.uniform(low, high, (30, 4))
    rows = ["q1_mm,q2_deg,q3_deg,q4_deg", *(",".join(f"{v:.6f}" for v in row) for row in q)]
    (tmp_path / "plan.csv").write_text("\n".join(rows) + "\n")
    made = run_cli(
        tmp_path, "synthesize", "--robot", "lift.toml", "--truth", "truth.toml",
        "--plan", "plan.csv", "--seed", "1", "-o", "meas.csv",
    )  # fmt: skip
    assert made.returncode == 0, made.stderr
    run = run_cli(tmp_path, "identify", "--robot", "lift.toml", "--measurements", "meas.csv")
    assert run.returncode == 0, run.stderr
    # the slide's zero is a shift of the whole arm along its axis: the base's position
    assert (
        "the zero of joint 1 (dq1) merges into the base position: joint 1 slides the whole "
        "arm along its axis, as the base position does" in run.stdout
    )
    assert "joint 1 turns" not in run.stdout
