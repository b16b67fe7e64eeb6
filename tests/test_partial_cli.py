"""Partial coordinates through the front door (issue 38): dial indicators, a displacement
sensor or a CMM that reads some of the tool point's coordinates in its own frame.

Two virtual labs on each of two built-in six-axis arms (``helpers_instruments``):

* ``partial``: a frame that reads x, y and z, where the user says it is 10 mm and 1-2
  degrees from where it really is; the measurement files have a third of their cells
  emptied (a row reads any subset of the axes);
* ``dial``: one dial indicator reading z, its axis along the base's x, as rough.

Tolerances as in ``test_instrument_cli``: a held-out RMS below 1e-9 mm is round-off.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np
import pytest

from helpers import run_cli
from helpers_instruments import met_plan, refused_measurements, refused_table, write_lab

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover - Python 3.10
    import tomli as tomllib


def ok(folder: Path, *args: str) -> str:
    run = run_cli(folder, *args)
    assert run.returncode == 0, run.stderr
    return run.stdout


def synthesized(folder: Path, robot: Path, truth: Path, plan: str, out: str, *more: str) -> str:
    return ok(
        folder,
        "synthesize",
        "--robot",
        robot.name,
        "--plan",
        plan,
        "--truth",
        truth.name,
        *more,
        "-o",
        out,
    )


#: The columns of partial coordinates' readings: the coordinates, and the tool's turn.
READINGS = ("x_mm", "y_mm", "z_mm", "rx_deg", "ry_deg", "rz_deg")


def holes(path: Path, seed: int) -> int:
    """Empty a third of the reading cells of ``path`` (never every cell of a line); the
    readings left."""
    lines = path.read_text(encoding="utf-8").splitlines()
    head = lines[0].split(",")
    axes = [k for k, name in enumerate(head) if name in READINGS]
    rng = np.random.default_rng(seed)
    left = 0
    out = [lines[0]]
    for line in lines[1:]:
        cells = line.split(",")
        drop = [k for k in axes if rng.random() < 1 / 3][: len(axes) - 1]
        for k in drop:
            cells[k] = ""
        left += len(axes) - len(drop)
        out.append(",".join(cells))
    path.write_text("\n".join(out) + "\n", encoding="utf-8")
    return left


@pytest.mark.parametrize("robot", ["industrial-6r", "cobot-6r"])
@pytest.mark.parametrize("kind", ["partial", "dial"])
def test_noiseless_partial_coordinates_are_recovered_on_held_out_poses(tmp_path, robot, kind):
    """synthesize (noiseless, one line a pose, a column an axis) -> empty some cells ->
    identify -> validate on other poses: every held-out reading to round-off."""
    robot_file, truth = write_lab(tmp_path, robot, kind)
    met_plan(tmp_path, robot_file, 100, 1, "train.csv")
    met_plan(tmp_path, robot_file, 30, 2, "test.csv")
    synthesized(tmp_path, robot_file, truth, "train.csv", "meas.csv", "--sigma", "0")
    synthesized(tmp_path, robot_file, truth, "test.csv", "held.csv", "--sigma", "0")
    text = (tmp_path / "meas.csv").read_text(encoding="utf-8").splitlines()
    columns = ["x_mm", "y_mm", "z_mm"] if kind == "partial" else ["z_mm"]
    assert text[0].split(",")[-len(columns) :] == columns
    assert len(text) == 101  # one line a pose
    readings = holes(tmp_path / "meas.csv", 3) if kind == "partial" else 100
    held = holes(tmp_path / "held.csv", 4) if kind == "partial" else 30
    report = ok(
        tmp_path,
        "identify",
        "--robot",
        robot_file.name,
        "--measurements",
        "meas.csv",
        "-o",
        "cal.json",
    )
    assert f"100 poses ({readings} readings)" in report or kind == "dial"
    document = json.loads((tmp_path / "cal.json").read_text(encoding="utf-8"))
    assert document["robot"]["instrument"]["kind"] == "partial"
    summary = json.loads(
        ok(
            tmp_path,
            "validate",
            "--calibration",
            "cal.json",
            "--measurements",
            "held.csv",
            "--json",
        )
    )
    assert summary["rms_after_mm"] < 1e-9
    assert summary["rms_before_mm"] > 1e-3
    assert (
        len(
            json.loads(
                ok(
                    tmp_path,
                    "validate",
                    "--calibration",
                    "cal.json",
                    "--measurements",
                    "held.csv",
                    "--json",
                    "--per-pose",
                )
            )["per_pose"]
        )
        == held
    )


@pytest.mark.parametrize("robot", ["industrial-6r", "cobot-6r"])
def test_noiseless_turns_are_recovered_on_held_out_poses(tmp_path, robot):
    """Partial coordinates with the tool's turn (``turned``: x, z, rx and rz, the tool's
    axes 1-2 degrees from where the user says): synthesize noiseless, empty a third of
    the cells, identify, validate on other poses: every held-out coordinate and turn
    to round-off (1e-9 mm; 1e-9 deg, a turn of 2e-11 rad); the calibration file gives
    the tool's turns, both sigmas, and each residual's unit; the tool's turns are
    written in degrees in the measurement file (a few degrees here, not radians)."""
    robot_file, truth = write_lab(tmp_path, robot, "turned")
    met_plan(tmp_path, robot_file, 100, 1, "train.csv")
    met_plan(tmp_path, robot_file, 30, 2, "test.csv")
    said = synthesized(tmp_path, robot_file, truth, "train.csv", "meas.csv", "--sigma", "0")
    assert "(sigma 0 mm, orientation 0 deg," in said  # --sigma 0: no noise at all
    synthesized(tmp_path, robot_file, truth, "test.csv", "held.csv", "--sigma", "0")
    text = (tmp_path / "meas.csv").read_text(encoding="utf-8").splitlines()
    assert text[0].split(",")[-4:] == ["x_mm", "z_mm", "rx_deg", "rz_deg"]
    turns = np.array([[float(c) for c in line.split(",")[-2:]] for line in text[1:]])
    assert np.all(np.abs(turns) <= 150.0) and np.abs(turns).max() > 10.0  # degrees
    readings = holes(tmp_path / "meas.csv", 3)
    holes(tmp_path / "held.csv", 4)
    report = ok(
        tmp_path, "identify", "--robot", robot_file.name, "--measurements", "meas.csv",
        "-o", "cal.json",
    )  # fmt: skip
    assert f"100 poses ({readings} readings)" in report
    assert "sigma 0.01 mm a coordinate, 0.001 deg a turn (given)" in report
    assert "tool.rx" in report and "it reads the tool's turn (rx, rz) too" in report
    document = json.loads((tmp_path / "cal.json").read_text(encoding="utf-8"))
    assert document["robot"]["instrument"]["reads"] == ["x", "z", "rx", "rz"]
    assert document["sigma_mm"] == pytest.approx(0.01) and document[
        "sigma_turn_deg"
    ] == pytest.approx(0.001)
    units = {row["unit"] for row in document["residuals"]}
    assert units == {"mm", "deg"}
    names = [p["name"] for p in document["parameters"]]
    assert names[-3:] == ["tool.rx", "tool.ry", "tool.rz"]
    summary = json.loads(
        ok(tmp_path, "validate", "--calibration", "cal.json", "--measurements", "held.csv",
           "--json")
    )  # fmt: skip
    assert summary["rms_after_mm"] < 1e-9
    assert summary["orientation_rms_after_deg"] < 1e-9
    assert summary["rms_before_mm"] > 1e-3 and summary["orientation_rms_before_deg"] > 1e-3
    run = run_cli(
        tmp_path,
        "validate",
        "--calibration",
        "cal.json",
        "--measurements",
        "meas.csv",
        "--plot",
        "fig.png",
    )  # its own rows, the turns' too, are not held out; the figure of its coordinates'
    assert run.returncode == 0 and (tmp_path / "fig.png").stat().st_size > 0, run.stderr
    assert f"({readings} readings, all of them the calibration's own rows" in run.stdout
    assert f"{readings} of {readings} rows are rows the calibration was fitted to" in run.stderr


@pytest.mark.parametrize("kind", ["partial", "turned"])
def test_cross_validation_keeps_a_poses_readings_together(tmp_path, kind):
    """identify --cross-validate of partial coordinates (it once stopped on a traceback:
    the folds' rows lost their features): a pose's readings stay in one fold, every fold
    holds 1/5 of the poses, and noiseless data are predicted to round-off (1e-9 mm;
    1e-9 deg a turn)."""
    robot_file, truth = write_lab(tmp_path, "industrial-6r", kind)
    met_plan(tmp_path, robot_file, 50, 1, "train.csv")
    synthesized(tmp_path, robot_file, truth, "train.csv", "meas.csv", "--sigma", "0")
    document = json.loads(
        ok(
            tmp_path, "identify", "--robot", robot_file.name, "--measurements", "meas.csv",
            "--cross-validate", "5", "--json",
        )
    )  # fmt: skip
    checked = document["cross_validation"]
    coordinates = 3 if kind == "partial" else 2  # x, y, z; x, z (and rx, rz apart)
    assert [fold["points"] for fold in checked["per_fold"]] == [10 * coordinates] * 5
    assert checked["rms_per_point_mm"] < 1e-9
    assert kind == "partial" or checked["orientation_rms_deg"] < 1e-9


def test_bad_turns_are_one_line(tmp_path):
    """A turn beyond a half turn, a line's sigma in mm beside turns, and turns in radians
    under a degrees column: exit 2, the file, the row or line and the column named."""
    robot_file, truth = write_lab(tmp_path, "industrial-6r", "turned")
    met_plan(tmp_path, robot_file, 40, 6, "plan.csv")
    synthesized(tmp_path, robot_file, truth, "plan.csv", "meas.csv")
    good = (tmp_path / "meas.csv").read_text(encoding="utf-8").splitlines()
    head, rows = good[0], good[1:]

    def cell(line: str, k: int, value: str) -> str:
        cells = line.split(",")
        cells[k] = value
        return ",".join(cells)

    def radians(line: str) -> str:
        cells = line.split(",")
        cells[-1] = repr(float(np.radians(float(cells[-1]))))
        return ",".join(cells)

    cases = {
        "beyond a half turn": (
            [head, cell(rows[0], -1, "250"), *rows[1:]],
            "row 1 (line 2), column rz_deg",
            "no component of a rotation vector",
        ),
        "a line's sigma": (
            [head + ",sigma_mm", *(r + ",0.01" for r in rows)],
            "column sigma_mm",
            "orientation_sigma_deg",
        ),
        "radians": ([head, *(radians(r) for r in rows)], "row ", "deg from where the other"),
    }
    for name, (lines, where, words) in cases.items():
        refused_measurements(tmp_path, robot_file.name, lines, where, words, name=name)


def test_what_one_dial_cannot_see_is_held_and_said(tmp_path):
    """One axis read: the instrument's shift along its other two axes and its turn about
    its own are held, and the report says what the dial cannot see."""
    robot_file, truth = write_lab(tmp_path, "industrial-6r", "dial")
    met_plan(tmp_path, robot_file, 60, 1, "plan.csv")
    synthesized(tmp_path, robot_file, truth, "plan.csv", "meas.csv")
    report = ok(tmp_path, "identify", "--robot", robot_file.name, "--measurements", "meas.csv")
    assert (
        "cannot see the arm move along the instrument's x or y axes, nor turn about its z"
        in report
    )
    assert (
        "fixed (held at nominal, not identified): instrument.x, instrument.y, "
        "instrument.rz" in report
    )
    assert "identified with the arm: instrument.z, instrument.rx, instrument.ry\n" in report


def test_sigma_per_axis_weighs_every_reading(tmp_path):
    """``sigma_mm = [sx, sy, sz]``: every reading has its axis's sigma, so the fit is
    consistent with it (chi2 on its dof), the calibration keeps the noise per axis, and
    validation predicts the held-out error it finds (90 readings: the RMS is known to
    about 1 / sqrt(180) = 7.5 %; 30 % is four of those)."""
    robot_file, truth = write_lab(tmp_path, "cobot-6r", "partial", sigma="[0.01, 0.02, 0.04]")
    met_plan(tmp_path, robot_file, 100, 1, "plan.csv")
    met_plan(tmp_path, robot_file, 30, 2, "test.csv")
    synthesized(tmp_path, robot_file, truth, "plan.csv", "meas.csv", "--seed", "5")
    synthesized(tmp_path, robot_file, truth, "test.csv", "held.csv", "--seed", "6")
    fit = json.loads(
        ok(
            tmp_path,
            "identify",
            "--robot",
            robot_file.name,
            "--measurements",
            "meas.csv",
            "--json",
            "-o",
            "cal.json",
        )
    )
    assert 0.001 < fit["goodness_of_fit"]["p_value"] < 0.999
    assert np.allclose(np.diag(fit["noise"]["covariance_mm2"]), [1e-4, 4e-4, 16e-4])
    summary = json.loads(
        ok(
            tmp_path,
            "validate",
            "--calibration",
            "cal.json",
            "--measurements",
            "held.csv",
            "--json",
        )
    )
    assert abs(summary["rms_after_mm"] / summary["predicted_rms_after_per_point_mm"] - 1) < 0.3


def test_evaluate_simulate_and_export_take_partial_coordinates(tmp_path):
    """evaluate, simulate and export work through partial coordinates and name the
    instrument's parameters."""
    robot_file, truth = write_lab(tmp_path, "cobot-6r", "partial")
    met_plan(tmp_path, robot_file, 40, 5, "plan.csv")
    quality = json.loads(
        ok(tmp_path, "evaluate", "--robot", robot_file.name, "--plan", "plan.csv", "--json")
    )
    assert "instrument.rz" in quality["predicted_std"]
    result = json.loads(
        ok(
            tmp_path,
            "simulate",
            "--robot",
            robot_file.name,
            "--plan",
            "plan.csv",
            "--truth",
            truth.name,
            "--trials",
            "40",
            "--json",
        )
    )
    assert result["trials"] == 40
    synthesized(tmp_path, robot_file, truth, "plan.csv", "meas.csv", "--sigma", "0")
    ok(
        tmp_path,
        "identify",
        "--robot",
        robot_file.name,
        "--measurements",
        "meas.csv",
        "-o",
        "cal.json",
    )
    ok(tmp_path, "export", "--calibration", "cal.json", "--robot-toml", "out.toml")
    exported = tomllib.loads((tmp_path / "out.toml").read_text(encoding="utf-8"))
    assert "instrument" not in exported and "mdh" in exported  # the arm alone


def _table(reads: str = '["z"]', rpy: str = "[0, 90, 0]", xyz: str = "[900, 0, 100]") -> str:
    return f'kind = "partial"\nreads = {reads}\nxyz_mm = {xyz}\nrpy_deg = {rpy}\n'


BAD_ROBOTS = {
    "an unknown axis": (_table(reads='["w"]'), "", "key 'instrument.reads'"),
    "no axis": (_table(reads="[]"), "", "some of"),
    "an axis twice": (_table(reads='["z", "z"]'), "", "each once"),
    "no origin": ('kind = "partial"\nreads = ["z"]\nrpy_deg = [0, 0, 0]\n', "", "need xyz_mm"),
    "two angles": (_table(rpy="[0, 90]"), "", "key 'instrument.rpy_deg'"),
    "a covariance": (
        _table(),
        "[measurement]\ncovariance_mm2 = [[1e-4, 1e-5, 0], [1e-5, 1e-4, 0], [0, 0, 1e-4]]\n",
        "not a covariance",
    ),
    "orientation noise": (
        _table(),
        "[measurement]\nsigma_mm = 0.01\norientation_sigma_deg = 0.01\n",
        'the instrument reads no turn; add "rx", "ry" or "rz"',
    ),
    "turns alone": (_table(reads='["rx", "ry"]'), "", 'read a coordinate too (add "x"'),
    "a turn twice": (_table(reads='["z", "rz", "rz"]'), "", "each once"),
    "tool axes without turns": (
        _table() + "tool_rpy_deg = [0, 0, 30]\n",
        "",
        "key 'instrument.tool_rpy_deg': the instrument reads no turn",
    ),
    "a half turn's range": (
        _table(reads='["z", "rz"]') + "max_turn_deg = 180\n",
        "[measurement]\nsigma_mm = 0.01\norientation_sigma_deg = 0.001\n",
        "key 'instrument.max_turn_deg': expected the largest turn",
    ),
    "turns without any noise": (_table(reads='["z", "rz"]'), "", "give sigma_mm and orientation"),
    "turns without their noise": (
        _table(reads='["z", "rz"]'),
        "[measurement]\nsigma_mm = 0.01\n",
        "give orientation_sigma_deg",
    ),
}


@pytest.mark.parametrize("case", sorted(BAD_ROBOTS))
def test_bad_partial_tables_are_one_line(tmp_path, case):
    table, measurement, words = BAD_ROBOTS[case]
    assert words in refused_table(tmp_path, table, measurement)


def test_bad_partial_measurements_are_one_line(tmp_path):
    """An axis the instrument does not read, an orientation column, a line without a
    reading, a cell that is no number, no reading column, and a reading far from the
    others' (a metre's worth): exit 2, the file, the row or line and the column named."""
    robot_file, truth = write_lab(tmp_path, "industrial-6r", "partial")
    met_plan(tmp_path, robot_file, 40, 6, "plan.csv")
    synthesized(tmp_path, robot_file, truth, "plan.csv", "meas.csv")
    good = (tmp_path / "meas.csv").read_text(encoding="utf-8").splitlines()
    head, rows = good[0], good[1:]
    dial = robot_file.read_text(encoding="utf-8").replace('["x", "y", "z"]', '["z"]')
    (tmp_path / "dial.toml").write_text(dial, encoding="utf-8")

    def cell(line: str, k: int, value: str) -> str:
        cells = line.split(",")
        cells[k] = value
        return ",".join(cells)

    cases = {
        "unread axis": ("dial.toml", good, "column x_mm", 'add "x" to [instrument] reads'),
        "orientation": (
            robot_file.name,
            [head + ",rx_deg", *(r + ",1" for r in rows)],
            "column rx_deg",
            'add "rx" to [instrument] reads',
        ),
        "empty line": (
            robot_file.name,
            [head, cell(cell(cell(rows[0], -1, ""), -2, ""), -3, ""), *rows[1:]],
            "row 1 (line 2): no reading",
            "x_mm or y_mm or z_mm",
        ),
        "not a number": (
            robot_file.name,
            [head, cell(rows[0], -1, "abc"), *rows[1:]],
            "row 1 (line 2), column z_mm",
            "leave the cell empty",
        ),
        "no reading column": (
            robot_file.name,
            [",".join(head.split(",")[:-3]), *(",".join(r.split(",")[:-3]) for r in rows)],
            "no column of a reading",
            "add a column x_mm or y_mm or z_mm",
        ),
        "far reading": (
            robot_file.name,
            [head, cell(rows[0], -1, "9000"), *rows[1:]],
            "row 1:",
            "feature 'z'",
        ),
    }
    for name, (robot, lines, where, words) in cases.items():
        refused_measurements(tmp_path, robot, lines, where, words, name=name)


def test_the_rows_a_pose_gives_size_the_plan(tmp_path):
    """A pose read in x, y and z gives three equations: 8 poses give 24 for 27 free
    parameters, so 9 are needed (not 27, as one equation a pose would say)."""
    robot_file, _ = write_lab(tmp_path, "industrial-6r", "partial")
    run = run_cli(tmp_path, "design", "--robot", robot_file.name, "--poses", "8")
    assert run.returncode == 2
    assert "8 poses give 24 equations for the 27 free parameters" in run.stderr
    assert "use --poses 9 or more" in run.stderr


def test_a_target_column_names_the_tool_point(tmp_path):
    """A measurement file of partial coordinates with a target column (the one tool
    point's name) is read and fitted."""
    robot_file, truth = write_lab(tmp_path, "industrial-6r", "partial")
    met_plan(tmp_path, robot_file, 40, 1, "plan.csv")
    synthesized(tmp_path, robot_file, truth, "plan.csv", "meas.csv")
    lines = (tmp_path / "meas.csv").read_text(encoding="utf-8").splitlines()
    lines = [lines[0] + ",target", *(line + ",tool" for line in lines[1:])]
    (tmp_path / "tmeas.csv").write_text("\n".join(lines) + "\n", encoding="utf-8")
    ok(tmp_path, "identify", "--robot", robot_file.name, "--measurements", "tmeas.csv", "--json")


def test_a_given_sigma_is_the_coordinates_and_turns_keep_their_own(tmp_path):
    """synthesize --sigma 0.02 on partial coordinates with turns (the robot file's 0.01 mm
    and 0.001 deg): the same seed draws the same normals, so every turn reads exactly what
    it reads without --sigma, and every coordinate's noise is exactly twice the file's
    (it once gave the turns 0.02 rad, 1.1 deg, while saying 0.001 deg)."""
    robot_file, truth = write_lab(tmp_path, "industrial-6r", "turned")
    met_plan(tmp_path, robot_file, 20, 1, "plan.csv")
    said = synthesized(tmp_path, robot_file, truth, "plan.csv", "given.csv", "--sigma", "0.02")
    assert "(sigma 0.02 mm, orientation 0.001 deg," in said
    synthesized(tmp_path, robot_file, truth, "plan.csv", "file.csv")
    synthesized(tmp_path, robot_file, truth, "plan.csv", "none.csv", "--sigma", "0")

    def read(name: str) -> tuple[list[str], np.ndarray]:
        lines = (tmp_path / name).read_text(encoding="utf-8").splitlines()
        return lines[0].split(","), np.array(
            [[float(c) for c in x.split(",")[-4:]] for x in lines[1:]]
        )

    header, given = read("given.csv")
    _, file = read("file.csv")
    _, none = read("none.csv")
    assert header[-4:] == ["x_mm", "z_mm", "rx_deg", "rz_deg"]
    np.testing.assert_allclose(given[:, 2:], file[:, 2:], rtol=0, atol=1e-12)
    assert np.abs(file[:, 2:] - none[:, 2:]).max() > 1e-4  # the turns are noisy
    np.testing.assert_allclose(
        given[:, :2] - none[:, :2], 2 * (file[:, :2] - none[:, :2]), atol=1e-9
    )
