"""Bad input to the ``armcal`` program: exit 2, one ``armcal: error:`` line, no output.

Every case runs the program in-process (:func:`armcal.cli.main` with its streams
captured, :func:`helpers.run_cli`) in an empty folder that holds only the
case's input files -- a few run it as a real process too (exit status, one
stderr line, a signal) -- and checks the contract of
PRODUCT.md "Errors": exit status 2, exactly one stderr line that starts with
``armcal: error:`` and says what is wrong and where (file, row, column or key),
no traceback, and no output or temporary file left behind.
"""

from __future__ import annotations

import errno
import functools
import json
import math
import os
import signal
import stat
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

import pytest

from helpers import run_cli, run_program
from helpers_paper import (
    MEAS_HEADER,
    MEAS_ROWS,
    PLAN_HEADER,
    PLAN_ROWS,
    POSES,
    VALID_MEAS,
    VALID_PLAN,
    csv_file,
    exact_position,
    noisy_position,
)

# --------------------------------------------------------------------------- valid inputs
# (the valid files themselves: helpers_paper)


def _with_field(rows: list[str], row: int, column: str, value: str, header: str) -> list[str]:
    """A copy of ``rows`` with data row ``row`` (1-based), column ``column`` set to ``value``."""
    col = header.split(",").index(column)
    out = list(rows)
    fields = out[row - 1].split(",")
    fields[col] = value
    out[row - 1] = ",".join(fields)
    return out


def _meas_with(row: int, column: str, value: str) -> str:
    return csv_file(MEAS_HEADER, _with_field(MEAS_ROWS, row, column, value, MEAS_HEADER))


def _drop_column(header: str, rows: list[str], column: str) -> str:
    col = header.split(",").index(column)

    def drop(line: str) -> str:
        fields = line.split(",")
        del fields[col]
        return ",".join(fields)

    return csv_file(drop(header), [drop(r) for r in rows])


#: The valid plan in radians under the q*_deg columns (a unit mistake).
RADIANS_PLAN = csv_file(
    PLAN_HEADER, [",".join(f"{math.radians(v):.6f}" for v in p) for p in POSES]
)


def _turned(row: str) -> str:
    """A measurement row as a controller reading 0..360 writes it: negative angles + 360."""
    fields = row.split(",")
    fields[:4] = [f"{float(v) + 360:g}" if float(v) < 0 else v for v in fields[:4]]
    return ",".join(fields)


def _scaled_rows(factor: float) -> list[str]:
    """The measurement rows of an arm ``factor`` times as large (same angles)."""
    return [
        ",".join([*(f"{v:g}" for v in pose), *(repr(factor * v) for v in noisy_position(pose, k))])
        for k, pose in enumerate(POSES)
    ]


ROBOT_TOML = 'name = "my-scara"\nlink_lengths_mm = [260.0, 180.0, 120.0, 100.0]\n'
TRUTH_TOML = "dl_mm = [1.5, -0.6, -0.4, 0.7]\ndq_deg = [0.5, -0.5, 0.7, -0.3]\n"

#: Marks an input that is a folder rather than a file.
FOLDER = object()
#: Marks a valid calibration JSON of paper-4link (``identify`` on VALID_MEAS).
CALIBRATION = object()
#: Marks a FIFO (named pipe); never opened by these tests, since opening one blocks.
FIFO = object()


@dataclass(frozen=True)
class Link:
    """A symbolic link to ``target``."""

    target: str


IDENTIFY = ("identify", "--robot", "paper-4link", "--measurements", "meas.csv", "-o", "cal.json")
SYNTHESIZE = ("synthesize", "--plan", "plan.csv", "-o", "meas.csv")
SYNTHESIZE_ROBOT = (
    "synthesize",
    "--robot",
    "robot.toml",
    "--truth",
    "truth.toml",
    *SYNTHESIZE[1:],
)
IDENTIFY_ROBOT = ("identify", "--robot", "robot.toml", *IDENTIFY[3:])


# --------------------------------------------------------------------------- helpers


@functools.cache
def _calibration_json() -> str:
    """The calibration file ``identify`` writes for VALID_MEAS (made once per test process)."""
    with tempfile.TemporaryDirectory() as folder:
        root = Path(folder)
        _write(root, {"meas.csv": VALID_MEAS})
        result = run_cli(root, *IDENTIFY)
        assert result.returncode == 0, result.stderr
        return (root / "cal.json").read_text(encoding="utf-8")


def _calibration_with(**changes: object) -> str:
    """The valid calibration JSON with top-level keys replaced (None deletes one)."""
    doc = json.loads(_calibration_json())
    for key, value in changes.items():
        if value is None:
            del doc[key]
        else:
            doc[key] = value
    return json.dumps(doc)


class Derived:
    """File content made when the case runs (the calibration needs a run of identify)."""

    def __init__(self, make) -> None:
        self.make = make


def _write(root: Path, files: dict[str, object]) -> None:
    for name, content in files.items():
        path = root / name
        if isinstance(content, Derived):
            content = content.make()
        if content is CALIBRATION:
            content = _calibration_json()
        if content is FOLDER:
            path.mkdir()
        elif content is FIFO:
            os.mkfifo(path)
        elif isinstance(content, Link):
            path.symlink_to(content.target)
        elif isinstance(content, bytes):
            path.write_bytes(content)
        else:
            assert isinstance(content, str)
            path.write_text(content, encoding="utf-8")


def _entry(path: Path) -> bytes | str | None:
    """A file's bytes, a link's target, a special file's kind, or None for a folder.

    Never opens anything but a regular file (opening a FIFO would block).
    """
    mode = path.lstat().st_mode
    if stat.S_ISLNK(mode):
        return f"link to {os.readlink(path)}"
    if stat.S_ISDIR(mode):
        return None
    if stat.S_ISREG(mode):
        return path.read_bytes()
    return f"special file {stat.filemode(mode)}"


def _snapshot(root: Path) -> dict[str, bytes | str | None]:
    """Every path under ``root`` (hidden temp files included) as :func:`_entry` sees it."""
    return {p.relative_to(root).as_posix(): _entry(p) for p in sorted(root.rglob("*"))}


def _output(argv: tuple[str, ...]) -> str | None:
    return argv[argv.index("-o") + 1] if "-o" in argv else None


def case(
    id: str,
    files: dict[str, object],
    argv: tuple[str, ...],
    expected: tuple[str, ...],
):
    return pytest.param(files, argv, expected, id=id)


# --------------------------------------------------------------------------- cases

CASES = [
    # ---- measurements CSV
    case(
        "meas-missing-column",
        {"meas.csv": _drop_column(MEAS_HEADER, MEAS_ROWS, "y_mm")},
        IDENTIFY,
        ("meas.csv", "line 1", "y_mm"),
    ),
    case(
        "meas-unknown-column",
        {"meas.csv": csv_file(MEAS_HEADER + ",temp_c", [r + ",0.0" for r in MEAS_ROWS])},
        IDENTIFY,
        ("meas.csv", "line 1", "temp_c"),
    ),
    case(
        "meas-duplicate-column",
        {"meas.csv": csv_file(MEAS_HEADER + ",x_mm", [r + ",0.0" for r in MEAS_ROWS])},
        IDENTIFY,
        ("meas.csv", "line 1", "x_mm", "duplicate"),
    ),
    case(
        "meas-nan",
        {"meas.csv": _meas_with(3, "x_mm", "nan")},
        IDENTIFY,
        ("meas.csv", "row 3", "x_mm", "nan"),
    ),
    case(
        "meas-inf",
        {"meas.csv": _meas_with(5, "y_mm", "inf")},
        IDENTIFY,
        ("meas.csv", "row 5", "y_mm", "inf"),
    ),
    case(
        "meas-overflowing-literal",
        {"meas.csv": _meas_with(7, "y_mm", "1e400")},
        IDENTIFY,
        ("meas.csv", "row 7", "y_mm", "1e400"),
    ),
    case(
        "meas-text",
        {"meas.csv": _meas_with(2, "q3_deg", "abc")},
        IDENTIFY,
        ("meas.csv", "row 2", "q3_deg", "abc"),
    ),
    case(
        "meas-empty-field",
        {"meas.csv": _meas_with(4, "x_mm", "")},
        IDENTIFY,
        ("meas.csv", "row 4", "x_mm"),
    ),
    case(
        "meas-short-row",
        {"meas.csv": csv_file(MEAS_HEADER, [*MEAS_ROWS[:2], MEAS_ROWS[2].rsplit(",", 1)[0]])},
        IDENTIFY,
        ("meas.csv", "row 3"),
    ),
    case(
        "meas-row-numbering-skips-blank-lines",
        {"meas.csv": csv_file(MEAS_HEADER, [*MEAS_ROWS[:2], "", "0,abc,0,0,1,2", *MEAS_ROWS[3:]])},
        IDENTIFY,
        ("meas.csv", "row 3 (line 5)", "q2_deg", "abc"),
    ),
    case("meas-empty-file", {"meas.csv": ""}, IDENTIFY, ("meas.csv", "empty")),
    case(
        "meas-commas-only",
        {"meas.csv": ",,,,,\n,,,,,\n"},
        IDENTIFY,
        ("meas.csv",),
    ),
    case(
        "meas-header-only",
        {"meas.csv": MEAS_HEADER + "\n"},
        IDENTIFY,
        ("meas.csv", "no poses"),
    ),
    case(
        "meas-3-joint-columns-for-4-joint-robot",
        {"meas.csv": _drop_column(MEAS_HEADER, MEAS_ROWS, "q4_deg")},
        IDENTIFY,
        ("meas.csv", "3 joint columns", "paper-4link", "4 joints"),
    ),
    case(
        "meas-pose-outside-default-limits",
        {"meas.csv": _meas_with(3, "q2_deg", "200")},
        IDENTIFY,
        ("meas.csv", "row 3", "q2_deg", "200"),
    ),
    case(  # a controller that reads 0..360: -162 deg (pose 12) read as 198
        "meas-readings-in-0-to-360",
        {"meas.csv": csv_file(MEAS_HEADER, [_turned(r) for r in MEAS_ROWS])},
        IDENTIFY,
        ("meas.csv", "row 12", "q2_deg", "198 is -162 + 360", "subtract or add 360"),
    ),
    case(
        "meas-pose-outside-robot-file-limits",
        {
            "robot.toml": ROBOT_TOML
            + "joint_limits_deg = [[-180, 180], [-150, 150], [-150, 150], [-150, 150]]\n",
            "meas.csv": VALID_MEAS,
        },
        IDENTIFY_ROBOT,
        ("meas.csv", "row 10", "q2_deg", "162"),
    ),
    case(
        "meas-too-few-poses",
        {"meas.csv": csv_file(MEAS_HEADER, MEAS_ROWS[1:3])},
        IDENTIFY,
        ("meas.csv", "not identifiable", "2 poses", "8 parameters"),
    ),
    case(
        "meas-identical-poses",
        {"meas.csv": csv_file(MEAS_HEADER, [MEAS_ROWS[3]] * 6)},
        IDENTIFY,
        ("meas.csv", "not identifiable", "6 poses"),
    ),
    case(
        "meas-no-residual-to-estimate-sigma",
        {"meas.csv": csv_file(MEAS_HEADER, MEAS_ROWS[0:20:5])},
        IDENTIFY,
        ("meas.csv", "4 poses", "--sigma"),
    ),
    case(
        "meas-absurd-magnitude",
        {"meas.csv": _meas_with(20, "x_mm", "1e200")},
        IDENTIFY,
        ("meas.csv",),
    ),
    case(
        "meas-sigma-column-not-positive",
        {
            "meas.csv": csv_file(
                MEAS_HEADER + ",sigma_mm", [r + ",0.1" for r in MEAS_ROWS[:-1]]
            ).rstrip("\n")
            + "\n"
            + MEAS_ROWS[-1]
            + ",-0.1\n"
        },
        IDENTIFY,
        ("meas.csv", "row 20", "sigma_mm", "-0.1"),
    ),
    case(
        "meas-value-beyond-any-reach",
        {"meas.csv": _meas_with(9, "y_mm", "5e8")},
        IDENTIFY,
        ("meas.csv", "row 9", "y_mm", "5e+08", "reach"),
    ),
    case(
        "meas-angle-far-beyond-a-limit",
        {
            "robot.toml": ROBOT_TOML
            + "joint_limits_deg = [[-180, 180], [-159, 159], [-180, 180], [-180, 180]]\n",
            "meas.csv": VALID_MEAS,
        },
        IDENTIFY_ROBOT,
        ("meas.csv", "row 10", "q2_deg", "162", "2 deg"),
    ),
    case("meas-missing-file", {}, IDENTIFY, ("meas.csv", "not found")),
    case("meas-is-a-folder", {"meas.csv": FOLDER}, IDENTIFY, ("meas.csv", "directory")),
    case(
        "meas-not-utf8",
        {"meas.csv": b"\xff\xfeq\x001\x00"},
        IDENTIFY,
        ("meas.csv", "UTF-8"),
    ),
    # ---- plan CSV
    case(
        "plan-text",
        {
            "plan.csv": csv_file(
                PLAN_HEADER, _with_field(PLAN_ROWS, 3, "q2_deg", "abc", PLAN_HEADER)
            )
        },
        SYNTHESIZE,
        ("plan.csv", "row 3", "q2_deg", "abc"),
    ),
    case(
        "plan-is-a-measurements-file",
        {"plan.csv": VALID_MEAS},
        SYNTHESIZE,
        ("plan.csv", "line 1", "x_mm"),
    ),
    case("plan-missing-file", {}, SYNTHESIZE, ("plan.csv", "not found")),
    # ---- robot TOML
    case(
        "robot-unknown-key",
        {
            "robot.toml": ROBOT_TOML.replace("link_lengths_mm", "link_length_mm"),
            "meas.csv": VALID_MEAS,
        },
        IDENTIFY_ROBOT,
        ("robot.toml", "link_length_mm", "link_lengths_mm"),
    ),
    case(
        "robot-missing-link-lengths",
        {"robot.toml": 'name = "my-scara"\n', "meas.csv": VALID_MEAS},
        IDENTIFY_ROBOT,
        ("robot.toml", "link_lengths_mm"),
    ),
    case(
        "robot-negative-link-length",
        {"robot.toml": ROBOT_TOML.replace("180.0", "-180.0"), "meas.csv": VALID_MEAS},
        IDENTIFY_ROBOT,
        ("robot.toml", "link_lengths_mm[1]", "-180"),
    ),
    case(
        "robot-invalid-toml",
        {"robot.toml": ROBOT_TOML.replace("100.0]", "100.0"), "meas.csv": VALID_MEAS},
        IDENTIFY_ROBOT,
        ("robot.toml", "invalid TOML", "at end of document", "close it"),
    ),
    case(  # issue 20: the parser's own text had no fix
        "robot-is-a-measurements-csv",
        {"meas.csv": VALID_MEAS},
        ("identify", "--robot", "meas.csv", "--measurements", "meas.csv"),
        ("meas.csv", "not a robot TOML file", "looks like a measurements file", "--measurements"),
    ),
    case(
        "robot-duplicate-key",
        {"robot.toml": ROBOT_TOML + "link_lengths_mm = [1.0]\n", "meas.csv": VALID_MEAS},
        IDENTIFY_ROBOT,
        ("robot.toml", "line 3", "'link_lengths_mm' is given twice (first on line 2)", "keep one"),
    ),
    case(
        "robot-duplicate-table",
        {
            "robot.toml": ROBOT_TOML + "[measurement]\nsigma_mm = 0.1\n[measurement]\n",
            "meas.csv": VALID_MEAS,
        },
        IDENTIFY_ROBOT,
        ("robot.toml", "line 5", "[measurement] is declared twice (first on line 3)"),
    ),
    case(
        "robot-non-ascii-bare-key",
        {"robot.toml": ROBOT_TOML + "länge = 3\n", "meas.csv": VALID_MEAS},
        IDENTIFY_ROBOT,
        ("robot.toml", "line 3", 'quoted ("länge" = ...)'),
    ),
    case(
        "robot-number-without-leading-zero",
        {"robot.toml": ROBOT_TOML.replace("100.0]", ".1]"), "meas.csv": VALID_MEAS},
        IDENTIFY_ROBOT,
        ("robot.toml", "line 2", "write 0.1"),
    ),
    case(  # link lengths in metres: blame the robot file, not the measurements
        "robot-link-lengths-in-metres",
        {
            "robot.toml": ROBOT_TOML.replace("260.0, 180.0, 120.0, 100.0", "0.26,0.18,0.12,0.1"),
            "meas.csv": VALID_MEAS,
        },
        IDENTIFY_ROBOT,
        ("meas.csv", "links add up to 0.66 mm", "link_lengths_mm are in metres, write them in mm"),
    ),
    case(
        "robot-joint-limits-wrong-count",
        {
            "robot.toml": ROBOT_TOML
            + "joint_limits_deg = [[-180, 180], [-150, 150], [-150, 150]]\n",
            "plan.csv": VALID_PLAN,
            "truth.toml": TRUTH_TOML,
        },
        SYNTHESIZE_ROBOT,
        ("robot.toml", "joint_limits_deg"),
    ),
    case(
        "robot-joint-limits-reversed",
        {
            "robot.toml": ROBOT_TOML
            + "joint_limits_deg = [[-180, 180], [150, -150], [-150, 150], [-150, 150]]\n",
            "meas.csv": VALID_MEAS,
        },
        IDENTIFY_ROBOT,
        ("robot.toml", "joint_limits_deg[1]"),
    ),
    case(
        "robot-zero-sigma",
        {"robot.toml": ROBOT_TOML + "[measurement]\nsigma_mm = 0\n", "meas.csv": VALID_MEAS},
        IDENTIFY_ROBOT,
        ("robot.toml", "measurement.sigma_mm"),
    ),
    case(
        "robot-integer-too-large-for-float",
        {"robot.toml": ROBOT_TOML.replace("180.0", "1" + "0" * 400), "meas.csv": VALID_MEAS},
        IDENTIFY_ROBOT,
        ("robot.toml", "link_lengths_mm[1]"),
    ),
    case(
        "robot-fewer-joints-than-measurements",
        {"robot.toml": ROBOT_TOML.replace(", 100.0]", "]"), "meas.csv": VALID_MEAS},
        IDENTIFY_ROBOT,
        ("meas.csv", "4 joint columns", "my-scara", "3 joints"),
    ),
    case(
        "robot-fixed-unknown-name",
        {"robot.toml": ROBOT_TOML + "[identify]\nfixed = ['dl5']\n", "meas.csv": VALID_MEAS},
        IDENTIFY_ROBOT,
        ("robot.toml", "identify.fixed", "dl5", "dl1, dl2, dl3, dl4, dq1, dq2, dq3, dq4"),
    ),
    case(
        "robot-encoder-noise-without-instrument-noise",
        {
            "robot.toml": ROBOT_TOML + "[measurement]\njoint_sigma_deg = 0.01\n",
            "meas.csv": VALID_MEAS,
        },
        IDENTIFY_ROBOT,
        ("robot.toml", "joint_sigma_deg", "sigma_mm"),
    ),
    case(
        "usage-fix-empty-name",
        {"meas.csv": VALID_MEAS},
        (*IDENTIFY, "--fix", "dl4,"),
        ("--fix", "dl4,"),
    ),
    case(
        # synthesize and simulate study the nominal arm instead (tests/test_guard_files.py);
        # the demo calibrates known errors, so it needs them
        "robot-file-without-truth",
        {"robot.toml": ROBOT_TOML},
        ("demo", "--robot", "robot.toml", "-o", "out"),
        ("robot.toml", "--truth"),
    ),
    case(
        "robot-unknown-name",
        {"meas.csv": VALID_MEAS},
        ("identify", "--robot", "paper-5link", *IDENTIFY[3:]),
        ("paper-5link", "paper-4link"),
    ),
    # ---- truth TOML
    case(
        "truth-dl-wrong-length",
        {"truth.toml": TRUTH_TOML.replace(", 0.7]", "]"), "plan.csv": VALID_PLAN},
        ("synthesize", "--truth", "truth.toml", *SYNTHESIZE[1:]),
        ("truth.toml", "dl_mm", "4"),
    ),
    case(
        "truth-missing-dq",
        {"truth.toml": TRUTH_TOML.split("\n")[0] + "\n", "plan.csv": VALID_PLAN},
        ("synthesize", "--truth", "truth.toml", *SYNTHESIZE[1:]),
        ("truth.toml", "dq_deg"),
    ),
    case(
        "truth-missing-file",
        {"plan.csv": VALID_PLAN},
        ("synthesize", "--truth", "truth.toml", *SYNTHESIZE[1:]),
        ("truth.toml", "not found"),
    ),
    # ---- output paths
    case(
        "output-folder-missing",
        {"meas.csv": VALID_MEAS},
        (
            "identify",
            "--robot",
            "paper-4link",
            "--measurements",
            "meas.csv",
            "-o",
            "nodir/cal.json",
        ),
        ("nodir",),
    ),
    case(
        "output-is-a-folder",
        {"meas.csv": VALID_MEAS, "outdir": FOLDER},
        ("identify", "--robot", "paper-4link", "--measurements", "meas.csv", "-o", "outdir"),
        ("outdir",),
    ),
    case(
        "demo-output-is-a-file",
        {"afile": "keep me\n"},
        ("demo", "-o", "afile"),
        ("afile",),
    ),
    case(
        "output-is-a-fifo",
        {"meas.csv": VALID_MEAS, "cal.json": FIFO},
        IDENTIFY,
        ("cal.json", "FIFO"),
    ),
    case(
        "output-is-the-input-by-another-name",
        {"meas.csv": VALID_MEAS},
        ("identify", "--robot", "paper-4link", "--measurements", "meas.csv", "-o", "./meas.csv"),
        ("./meas.csv", "--measurements meas.csv"),
    ),
    case(
        "output-is-a-link-to-the-input",
        {"meas.csv": VALID_MEAS, "cal.json": Link("meas.csv")},
        IDENTIFY,
        ("cal.json", "--measurements meas.csv"),
    ),
    case(
        "design-output-is-the-robot-file",
        {"robot.toml": ROBOT_TOML},
        ("design", "--robot", "robot.toml", "--poses", "12", "-o", "robot.toml"),
        ("robot.toml", "--robot robot.toml"),
    ),
    case(
        "synthesize-output-is-the-plan",
        {"plan.csv": VALID_PLAN},
        ("synthesize", "--plan", "plan.csv", "-o", "plan.csv"),
        ("plan.csv", "--plan plan.csv"),
    ),
    case(  # sigma 0.1 mm: 0.0001 mm needs ~10^6 times the poses of 0.1 mm; refused at once
        "poses-needed-target-far-beyond-reach",
        {},
        ("poses-needed", "--position-rms", "0.0001"),
        ("target of 0.0001", "needs about", "beyond the 5000 searched"),
    ),
    case(  # 10^12 poses need about 10^15 bytes: refused at once on any machine
        "design-poses-beyond-the-machine",
        {},
        ("design", "--poses", "1000000000000", "-o", "plan.csv"),
        ("--poses 1000000000000", "GB", "design fewer and repeat them"),
    ),
    case(  # the suffix names the figure's format: a .pdf holds a PDF, never PNG bytes
        "design-plot-suffix-not-a-figure-format",
        {},
        ("design", "--poses", "12", "--plot", "plan.jpg"),
        ("--plot plan.jpg", "'.jpg' is not a figure format", ".pdf"),
    ),
    case(
        "design-same-file-for-plan-and-plot",
        {},
        ("design", "--poses", "12", "--plot", "plan.png", "-o", "plan.png"),
        ("plan.png", "two outputs"),
    ),
    # Checked before any work: no plan.csv is written, and no optimizing is done first.
    case(
        "design-plot-folder-missing",
        {},
        ("design", "--poses", "12", "--plot", "nodir/plan.png", "-o", "plan.csv"),
        ("nodir/plan.png", "folder nodir"),
    ),
    case(
        "design-output-folder-missing",
        {},
        ("design", "--poses", "7", "--method", "optimize", "-o", "nodir/plan.csv"),
        ("nodir/plan.csv", "folder nodir"),
    ),
    case(
        "reproduce-output-folder-under-a-file",
        {"afile": "keep me\n"},
        ("reproduce", "-o", "afile/out"),
        ("afile/out", "afile is a file"),
    ),
    case(
        "demo-output-folder-holds-a-folder-named-like-an-output",
        {"out": FOLDER, "out/plan.csv": FOLDER},
        ("demo", "-o", "out"),
        ("out/plan.csv", "directory"),
    ),
    # identify calibrates one arm: it has no default robot to fit the data to silently
    case(
        "identify-without-robot",
        {"meas.csv": VALID_MEAS},
        ("identify", "--measurements", "meas.csv", "-o", "cal.json"),
        ("identify needs --robot", "your robot file", "paper-4link"),
    ),
    # A folder output names none of its files: only files armcal wrote there are replaced.
    case(
        "demo-output-folder-holds-the-users-calibration",
        {"out": FOLDER, "out/calibration.json": '{"mine": true}\n'},
        ("demo", "-o", "out"),
        ("out/calibration.json", "armcal did not write it", "move it away"),
    ),
    case(
        "demo-output-dot-holds-the-users-plan",
        {"plan.csv": VALID_PLAN},
        ("demo", "-o", "."),
        ("./plan.csv", "armcal did not write it", "give -o another folder"),
    ),
    case(
        "reproduce-output-folder-holds-the-users-report",
        {"out": FOLDER, "out/report.md": "# my notes\n"},
        ("reproduce", "-o", "out"),
        ("out/report.md", "armcal did not write it"),
    ),
    # ---- command-line usage (no file to name; check the option is named)
    case(
        "usage-negative-sigma",
        {"meas.csv": VALID_MEAS},
        (
            "identify",
            "--robot",
            "paper-4link",
            "--measurements",
            "meas.csv",
            "--sigma",
            "-1",
            "-o",
            "cal.json",
        ),
        ("--sigma",),
    ),
    case(
        "usage-zero-sigma",
        {"meas.csv": VALID_MEAS},
        (
            "identify",
            "--robot",
            "paper-4link",
            "--measurements",
            "meas.csv",
            "--sigma",
            "0",
            "-o",
            "cal.json",
        ),
        ("--sigma",),
    ),
    case(
        "usage-sigma-beyond-any-instrument",
        {"plan.csv": VALID_PLAN},
        ("evaluate", "--plan", "plan.csv", "--sigma", "1e160"),
        ("--sigma", "between 1e-06 and 1000 mm"),
    ),
    case(
        "synthesize-output-ends-with-a-slash",
        {"plan.csv": VALID_PLAN},
        ("synthesize", "--plan", "plan.csv", "-o", "meas.csv/"),
        ("meas.csv/", "names a folder"),
    ),
    case(
        "usage-unknown-method",
        {"meas.csv": VALID_MEAS},
        (
            "identify",
            "--robot",
            "paper-4link",
            "--measurements",
            "meas.csv",
            "--method",
            "bogus",
            "-o",
            "cal.json",
        ),
        ("--method", "bogus"),
    ),
    case(
        "usage-seed-not-a-number",
        {"plan.csv": VALID_PLAN},
        ("synthesize", "--plan", "plan.csv", "--seed", "abc", "-o", "meas.csv"),
        ("--seed",),
    ),
    case("usage-unknown-subcommand", {}, ("frobnicate", "-o", "out.csv"), ("frobnicate",)),
    case(
        "usage-missing-measurements",
        {},
        ("identify", "--robot", "paper-4link", "-o", "cal.json"),
        ("--measurements",),
    ),
    case(  # synthesize's data are CSV: --json alone once printed CSV
        "usage-synthesize-json-without-output",
        {"plan.csv": VALID_PLAN},
        ("synthesize", "--plan", "plan.csv", "--json"),
        ("synthesize --json", "give -o meas.csv"),
    ),
    case(
        "synthesize-output-named-json",
        {"plan.csv": VALID_PLAN},
        ("synthesize", "--plan", "plan.csv", "-o", "meas.json"),
        ("-o meas.json", "CSV table", "ending in .csv"),
    ),
    case(  # 2 targets: 4 equations per pose, not 2
        "design-too-few-poses-with-targets",
        {"robot.toml": ROBOT_TOML + "[targets]\nA = { length_mm = 100 }\nB = {length_mm = 60}\n"},
        ("design", "--robot", "robot.toml", "--poses", "2"),
        ("2 poses give 8 equations for the 10 parameters", "--poses 3"),
    ),
    case(
        "usage-synthesize-sigma-nan",
        {"plan.csv": VALID_PLAN},
        ("synthesize", "--plan", "plan.csv", "--sigma", "nan", "-o", "meas.csv"),
        ("--sigma", "nan"),
    ),
    case(
        "usage-synthesize-sigma-negative",
        {"plan.csv": VALID_PLAN},
        ("synthesize", "--plan", "plan.csv", "--sigma", "-0.5", "-o", "meas.csv"),
        ("--sigma", "-0.5"),
    ),
    # ---- a negative --seed, in every command that takes one (reproduce makes no folder)
    *(
        case(f"usage-negative-seed-{argv[0]}", files, (*argv, "--seed", "-1"), ("--seed", "-1"))
        for files, argv in [
            ({"plan.csv": VALID_PLAN}, ("synthesize", "--plan", "plan.csv", "-o", "meas.csv")),
            ({}, ("design", "--poses", "12", "-o", "plan.csv")),
            ({"plan.csv": VALID_PLAN}, ("evaluate", "--plan", "plan.csv")),
            ({"plan.csv": VALID_PLAN}, ("simulate", "--plan", "plan.csv")),
            ({}, ("poses-needed", "--length-std-mm", "0.01", "-o", "plan.csv")),
            ({}, ("reproduce", "-o", "out")),
            ({}, ("demo", "-o", "out")),
        ]
    ),
    # ---- simulate and poses-needed
    case(
        "simulate-unidentifiable-plan",
        {"plan.csv": csv_file(PLAN_HEADER, PLAN_ROWS[:3])},
        ("simulate", "--plan", "plan.csv"),
        ("plan.csv", "cannot identify"),
    ),
    case(
        "simulate-one-trial",
        {"plan.csv": VALID_PLAN},
        ("simulate", "--plan", "plan.csv", "--trials", "1"),
        ("--trials", "at least 2"),
    ),
    case(
        "simulate-missing-plan",
        {},
        ("simulate", "--plan", "nothere.csv"),
        ("nothere.csv",),
    ),
    case(
        "poses-needed-no-target",
        {},
        ("poses-needed", "-o", "plan.csv"),
        ("--length-std-mm", "--angle-std-deg", "--position-rms-mm"),
    ),
    case(
        "poses-needed-two-targets",
        {},
        ("poses-needed", "--length-std-mm", "0.01", "--angle-std-deg", "0.01"),
        ("--angle-std-deg", "not allowed with"),
    ),
    case(
        "poses-needed-negative-target",
        {},
        ("poses-needed", "--position-rms-mm", "-0.1"),
        ("--position-rms-mm",),
    ),
    case(
        "poses-needed-out-of-reach",
        {},
        ("poses-needed", "--length-std-mm", "1e-5", "--max-poses", "300", "-o", "plan.csv"),
        ("the 300 searched", "relax the target"),
    ),
]


# --------------------------------------------------------------------------- more cases
# The commands after identify, robot files with targets, coupled joints and compliance,
# 3-D data, the calibration file, stdin and stdout.

VALIDATE = ("validate", "--calibration", "cal.json", "--measurements", "test.csv")
COMPENSATE = ("compensate", "--calibration", "cal.json", "--program", "prog.csv", "-o", "out.csv")
EXPORT = ("export", "--calibration", "cal.json", "--robot-toml", "arm.toml")
TARGETS_TOML = ROBOT_TOML + "[targets]\nA = { length_mm = 100.0 }\nB = { length_mm = 60.0 }\n"
ELASTIC_TOML = ROBOT_TOML + "[elastostatic]\ngravity_xy = [0.0, -1.0]\n"
#: The measurements with a target column naming A on every row (valid for TARGETS_TOML).
TARGET_MEAS = csv_file(MEAS_HEADER + ",target", [r + ",A" for r in MEAS_ROWS])
#: The measurements with a z_mm column, points in the plane z = 0.
MEAS_3D = csv_file(MEAS_HEADER + ",z_mm", [r + ",0.0" for r in MEAS_ROWS])


def _robot_with(text: str) -> dict[str, object]:
    return {"robot.toml": text, "meas.csv": VALID_MEAS}


CASES += [
    # ---- columns: wrong unit, misspelled, long rows
    case(
        "meas-angles-in-radians-column",
        {"meas.csv": VALID_MEAS.replace("q1_deg", "q1_rad", 1)},
        IDENTIFY,
        ("meas.csv", "line 1", "q1_rad", "degrees", "q1_deg"),
    ),
    case(
        "meas-positions-in-metres-column",
        {"meas.csv": VALID_MEAS.replace("x_mm", "x_m", 1)},
        IDENTIFY,
        ("meas.csv", "line 1", "x_m", "x_mm", "millimetres"),
    ),
    case(
        "meas-misspelled-joint-column",
        {"meas.csv": VALID_MEAS.replace("q2_deg", "q2_dge", 1)},
        IDENTIFY,
        ("meas.csv", "line 1", "q2_dge", "did you mean 'q2_deg'"),
    ),
    case(
        "meas-long-row",
        {"meas.csv": csv_file(MEAS_HEADER, [*MEAS_ROWS[:4], MEAS_ROWS[4] + ",7", *MEAS_ROWS[5:]])},
        IDENTIFY,
        ("meas.csv", "row 5 (line 6)", "7 fields", "6"),
    ),
    case(
        "meas-semicolon-file-with-text",
        {"meas.csv": VALID_MEAS.replace(",", ";").replace("\n0;", "\nzero;", 1)},
        IDENTIFY,
        ("meas.csv", "row 1", "q1_deg", "zero"),
    ),
    case(
        "meas-comment-lines-count-in-line-numbers",
        {"meas.csv": "# tracker export\n# units mm\n" + _meas_with(2, "y_mm", "oops")},
        IDENTIFY,
        ("meas.csv", "row 2 (line 5)", "y_mm", "oops"),
    ),
    # ---- 3-D data, targets, loads
    case(
        "meas-3d-z-not-a-number",
        {"meas.csv": MEAS_3D.replace(",0.0\n", ",n/a\n", 1)},
        IDENTIFY,
        ("meas.csv", "row 1", "z_mm", "n/a"),
    ),
    case(
        "meas-empty-target-label",
        {"robot.toml": TARGETS_TOML, "meas.csv": TARGET_MEAS.replace(",A\n", ",\n", 1)},
        IDENTIFY_ROBOT,
        ("meas.csv", "row 1", "target"),
    ),
    case(
        "meas-unknown-target-label",
        {"robot.toml": TARGETS_TOML, "meas.csv": TARGET_MEAS.replace(",A\n", ",C\n", 1)},
        IDENTIFY_ROBOT,
        ("meas.csv", "row 1", "target", "C"),
    ),
    case(
        "meas-payload-text",
        {
            "robot.toml": ELASTIC_TOML,
            "meas.csv": csv_file(MEAS_HEADER + ",payload_kg", [r + ",ten" for r in MEAS_ROWS]),
        },
        IDENTIFY_ROBOT,
        ("meas.csv", "row 1", "payload_kg", "ten"),
    ),
    case(
        "meas-negative-payload",
        {
            "robot.toml": ELASTIC_TOML,
            "meas.csv": csv_file(MEAS_HEADER + ",payload_kg", [r + ",-5" for r in MEAS_ROWS]),
        },
        IDENTIFY_ROBOT,
        ("meas.csv", "payload_kg", "-5"),
    ),
    # ---- robot files: misplaced keys, values, tables
    case(
        "robot-sigma-at-top-level",
        _robot_with(ROBOT_TOML + "sigma_mm = 0.05\n"),
        IDENTIFY_ROBOT,
        ("robot.toml", "sigma_mm", "[measurement]"),
    ),
    case(
        "robot-top-level-key-after-a-table",
        _robot_with('name = "x"\n[measurement]\nsigma_mm = 0.05\nlink_lengths_mm = [1.0]\n'),
        IDENTIFY_ROBOT,
        ("robot.toml", "measurement.link_lengths_mm", "above the first [table]"),
    ),
    case(
        "robot-misspelled-key",
        _robot_with(ROBOT_TOML + "joint_limit_deg = [[-90, 90]]\n"),
        IDENTIFY_ROBOT,
        ("robot.toml", "joint_limit_deg", "did you mean 'joint_limits_deg'"),
    ),
    case(
        "robot-zero-link-length",
        _robot_with("link_lengths_mm = [260.0, 0.0, 120.0, 100.0]\n"),
        IDENTIFY_ROBOT,
        ("robot.toml", "link_lengths_mm[1]", "0"),
    ),
    case(
        "robot-length-as-text",
        _robot_with('link_lengths_mm = [260.0, "180", 120.0, 100.0]\n'),
        IDENTIFY_ROBOT,
        ("robot.toml", "link_lengths_mm[1]", "number"),
    ),
    case(
        "robot-duplicate-key",
        _robot_with(ROBOT_TOML + "link_lengths_mm = [1.0, 2.0, 3.0, 4.0]\n"),
        IDENTIFY_ROBOT,
        ("robot.toml", "invalid TOML"),
    ),
    case(
        "robot-negative-sigma",
        _robot_with(ROBOT_TOML + "[measurement]\nsigma_mm = -0.05\n"),
        IDENTIFY_ROBOT,
        ("robot.toml", "measurement.sigma_mm", "-0.05"),
    ),
    case(
        "robot-covariance-not-symmetric",
        _robot_with(ROBOT_TOML + "[measurement]\ncovariance_mm2 = [[1e-3, 1e-4], [0, 1e-3]]\n"),
        IDENTIFY_ROBOT,
        ("robot.toml", "covariance_mm2", "symmetric"),
    ),
    case(
        "robot-region-unknown-kind",
        _robot_with(ROBOT_TOML + '[measurement]\nregion = { kind = "circle" }\n'),
        IDENTIFY_ROBOT,
        ("robot.toml", "region.kind", "annulus"),
    ),
    case(
        "robot-identify-fixed-and-free",
        _robot_with(ROBOT_TOML + '[identify]\nfixed = ["dl1"]\nfree = ["dq1"]\n'),
        IDENTIFY_ROBOT,
        ("robot.toml", "identify.fixed", "identify.free", "keep one"),
    ),
    case(
        "robot-joint-map-wrong-shape",
        _robot_with(ROBOT_TOML + "joint_map = [[1, 0], [0, 1]]\n"),
        IDENTIFY_ROBOT,
        ("robot.toml", "joint_map", "4 rows"),
    ),
    case(
        "robot-joint-map-singular",
        _robot_with(
            ROBOT_TOML + "joint_map = [[1, 0, 0, 0], [1, 0, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]]\n"
        ),
        IDENTIFY_ROBOT,
        ("robot.toml", "joint_map", "invertible"),
    ),
    case(
        "robot-target-negative-length",
        _robot_with(ROBOT_TOML + "[targets]\nA = { length_mm = -10.0 }\n"),
        IDENTIFY_ROBOT,
        ("robot.toml", "targets.A.length_mm", "-10"),
    ),
    case(
        "robot-target-unknown-key",
        _robot_with(ROBOT_TOML + "[targets]\nA = { length_mm = 90.0, angle = 5.0 }\n"),
        IDENTIFY_ROBOT,
        ("robot.toml", "targets.A.angle", "did you mean 'angle_deg'"),
    ),
    case(
        "robot-elastostatic-unknown-key",
        _robot_with(ELASTIC_TOML + "masses_kg = [1, 1, 1, 1]\n"),
        IDENTIFY_ROBOT,
        ("robot.toml", "elastostatic.masses_kg", "link_masses_kg"),
    ),
    case(
        "robot-elastostatic-negative-mass",
        _robot_with(ELASTIC_TOML + "link_masses_kg = [5, -1, 1, 1]\n"),
        IDENTIFY_ROBOT,
        ("robot.toml", "elastostatic", "-1"),
    ),
    case(
        "robot-elastostatic-com-beyond-link",
        _robot_with(ELASTIC_TOML + "link_masses_kg = [5, 3, 1, 1]\ncom_fraction = 1.5\n"),
        IDENTIFY_ROBOT,
        ("robot.toml", "com_fraction", "1.5"),
    ),
    case(
        "robot-measurement-gravity-zero",
        _robot_with(ROBOT_TOML + "[measurement]\ngravity = [0, 0, 0]\n"),
        IDENTIFY_ROBOT,
        ("robot.toml", "measurement.gravity", "non-zero"),
    ),
    case(
        "robot-builtin-name-typo",
        {"meas.csv": VALID_MEAS},
        ("identify", "--robot", "paper-4lnk", *IDENTIFY[3:]),
        ("paper-4lnk", "did you mean 'paper-4link'"),
    ),
    case(
        "truth-key-of-a-robot-file",
        {"plan.csv": VALID_PLAN, "truth.toml": TRUTH_TOML + "sigma_mm = 0.1\n"},
        ("synthesize", "--truth", "truth.toml", *SYNTHESIZE[1:]),
        ("truth.toml", "sigma_mm", "dl_mm"),
    ),
    case(
        "plan-payload-without-elastostatic",
        {"plan.csv": csv_file(PLAN_HEADER + ",payload_kg", [r + ",2" for r in PLAN_ROWS])},
        SYNTHESIZE,
        ("plan.csv", "payload_kg", "[elastostatic]"),
    ),
    case(
        "plan-too-few-poses-to-evaluate",
        {"plan.csv": csv_file(PLAN_HEADER, PLAN_ROWS[:2])},
        ("evaluate", "--plan", "plan.csv"),
        ("plan.csv", "2 poses"),
    ),
    case(
        "plan-identical-poses-to-simulate",
        {"plan.csv": csv_file(PLAN_HEADER, [PLAN_ROWS[5]] * 12)},
        ("simulate", "--plan", "plan.csv", "--trials", "50"),
        ("plan.csv", "cannot identify"),
    ),
    case(
        "design-too-few-poses",
        {},
        ("design", "--poses", "3", "-o", "plan.csv"),
        ("3 poses", "8 parameters", "--poses 4"),
    ),
    case(
        "design-candidates-of-another-robot",
        {"cand.csv": _drop_column(PLAN_HEADER, PLAN_ROWS, "q4_deg")},
        ("design", "--poses", "8", "--candidates", "cand.csv", "-o", "plan.csv"),
        ("cand.csv", "3 joint columns", "4 joints"),
    ),
    case(
        "identify-fix-unknown-parameter",
        {"meas.csv": VALID_MEAS},
        (*IDENTIFY, "--fix", "dl9"),
        ("dl9",),
    ),
    case(
        "check-compliance-one-trial",
        {},
        ("check-compliance", "--trials", "1"),
        ("--trials",),
    ),
    # ---- the calibration file
    case(
        "calibration-missing",
        {"test.csv": VALID_MEAS},
        VALIDATE,
        ("cal.json", "not found"),
    ),
    case(
        "calibration-is-a-csv",
        {"cal.json": VALID_MEAS, "test.csv": VALID_MEAS},
        VALIDATE,
        ("cal.json", "not a calibration file", "looks like a measurements file", "--measurements"),
    ),
    case(
        "calibration-truncated",
        {"cal.json": Derived(lambda: _calibration_json()[:200]), "test.csv": VALID_MEAS},
        VALIDATE,
        ("cal.json", "not a calibration file"),
    ),
    case(
        "calibration-of-another-format",
        {"cal.json": '{"format": "lmfit-result/2"}\n', "test.csv": VALID_MEAS},
        VALIDATE,
        ("cal.json", "lmfit-result/2", "armcal-calibration/1"),
    ),
    case(
        "calibration-of-a-later-version",
        {
            "cal.json": Derived(lambda: _calibration_with(format="armcal-calibration/2")),
            "test.csv": VALID_MEAS,
        },
        VALIDATE,
        ("cal.json", "armcal-calibration/2", "armcal-calibration/1"),
    ),
    case(
        "calibration-without-parameters",
        {"cal.json": Derived(lambda: _calibration_with(parameters=None)), "prog.csv": VALID_PLAN},
        COMPENSATE,
        ("cal.json", "parameters"),
    ),
    case(
        "calibration-is-a-robot-file",
        {"cal.json": ROBOT_TOML},
        EXPORT,
        ("cal.json", "not a calibration file"),
    ),
    # ---- validate, compensate, export
    case(
        "validate-measurements-of-another-robot",
        {"cal.json": CALIBRATION, "test.csv": _drop_column(MEAS_HEADER, MEAS_ROWS, "q4_deg")},
        VALIDATE,
        (
            "test.csv",
            "3 joint columns",
            "the calibration cal.json belongs to paper-4link, an arm of 4 joints",
            "are of different arms; pass the calibration of the same arm",
        ),
    ),
    case(  # a 3x larger arm: its points lie beyond paper-4link's reach (issue 20)
        "validate-measurements-of-a-larger-robot",
        {"cal.json": CALIBRATION, "test.csv": csv_file(MEAS_HEADER, _scaled_rows(3.0))},
        VALIDATE,
        (
            "test.csv",
            "beyond the reach of paper-4link (",
            "the calibration cal.json belongs to paper-4link: if the measurements are of "
            "another arm, pass that arm's calibration",
        ),
    ),
    case(  # the last link's parameter splits into one per target: name them, not dl3
        "fix-last-link-with-targets",
        {"robot.toml": TARGETS_TOML, "meas.csv": TARGET_MEAS},
        (*IDENTIFY_ROBOT, "--fix", "dl4"),
        ("with targets it is one per target (dl4@A)", "--fix dl4@A;"),  # only A is measured
    ),
    case(
        "compensate-program-of-another-robot",
        {"cal.json": CALIBRATION, "prog.csv": _drop_column(PLAN_HEADER, PLAN_ROWS, "q4_deg")},
        COMPENSATE,
        (
            "prog.csv",
            "the calibration cal.json belongs to paper-4link",
            "the program and the calibration cal.json are of different arms",
        ),
    ),
    case(
        "validate-plan-instead-of-measurements",
        {"cal.json": CALIBRATION, "test.csv": VALID_PLAN},
        VALIDATE,
        ("test.csv", "missing column 'x_mm'"),
    ),
    case(
        "validate-plot-folder-missing",
        {"cal.json": CALIBRATION, "test.csv": VALID_MEAS},
        (*VALIDATE, "--plot", "figs/errors.png"),
        ("figs/errors.png", "does not exist"),
    ),
    case(
        "compensate-measurements-instead-of-program",
        {"cal.json": CALIBRATION, "prog.csv": VALID_MEAS},
        COMPENSATE,
        ("prog.csv", "line 1", "x_mm"),
    ),
    case(
        "compensate-command-outside-limits",
        {"cal.json": CALIBRATION, "prog.csv": csv_file(PLAN_HEADER, ["0,0,0,0", "10,190,0,0"])},
        COMPENSATE,
        ("prog.csv", "row 2", "q2_deg", "190"),
    ),
    # Radians under q*_deg: the plan's or program's range is the evidence (2 pi)
    case(
        "compensate-program-in-radians",
        {"cal.json": CALIBRATION, "prog.csv": RADIANS_PLAN},
        COMPENSATE,
        ("prog.csv", "looks like radians", "convert the angles to degrees"),
    ),
    case(
        "evaluate-plan-in-radians",
        {"plan.csv": RADIANS_PLAN},
        ("evaluate", "--plan", "plan.csv"),
        ("plan.csv", "20 plan rows", "looks like radians"),
    ),
    case(
        "compensate-output-is-the-program",
        {"cal.json": CALIBRATION, "prog.csv": VALID_PLAN},
        (*COMPENSATE[:-1], "prog.csv"),
        ("prog.csv", "input --program"),
    ),
    case(
        "compensate-target-without-targets",
        {"cal.json": CALIBRATION, "prog.csv": VALID_PLAN},
        (*COMPENSATE, "--target", "A"),
        ("A",),
    ),
    case(
        "compensate-payload-without-compliance",
        {"cal.json": CALIBRATION, "prog.csv": VALID_PLAN},
        (*COMPENSATE, "--payload-kg", "5"),
        ("--payload-kg",),
    ),
    case(
        "compensate-negative-payload",
        {"cal.json": CALIBRATION, "prog.csv": VALID_PLAN},
        (*COMPENSATE, "--payload-kg", "-5"),
        ("--payload-kg", "-5"),
    ),
    case(
        "export-without-an-output",
        {"cal.json": CALIBRATION},
        ("export", "--calibration", "cal.json"),
        ("--robot-toml", "--urdf"),
    ),
    case(
        "export-same-file-twice",
        {"cal.json": CALIBRATION},
        (*EXPORT, "--urdf", "arm.toml"),
        ("arm.toml", "two outputs"),
    ),
    case(
        "export-over-the-calibration",
        {"cal.json": CALIBRATION},
        ("export", "--calibration", "cal.json", "--urdf", "./cal.json"),
        ("cal.json", "input --calibration"),
    ),
    case(
        "export-folder-missing",
        {"cal.json": CALIBRATION},
        ("export", "--calibration", "cal.json", "--urdf", "ros/arm.urdf"),
        ("ros/arm.urdf", "does not exist", "create it first"),
    ),
    # ---- stdin and stdout
    case(
        "stdin-empty",
        {},
        ("identify", "--robot", "paper-4link", "--measurements", "-"),
        ("<stdin>",),
    ),
    case(
        "stdin-for-two-inputs",
        {},
        ("synthesize", "--plan", "-", "--truth", "-"),
        ("--plan", "--truth", "stdin"),
    ),
    case(
        "stdout-with-json",
        {"meas.csv": VALID_MEAS},
        ("identify", "--robot", "paper-4link", "--measurements", "meas.csv", "-o", "-", "--json"),
        ("--json", "-o -", "stdout"),
    ),
    case(
        "stdout-for-a-figure",
        {},
        ("design", "--poses", "12", "--plot", "-"),
        ("--plot -", ".png, .pdf"),
    ),
    case(
        "stdout-for-a-folder",
        {},
        ("demo", "-o", "-"),
        ("-o -", "folder"),
    ),
    case(
        "stdout-for-two-outputs",
        {"cal.json": CALIBRATION},
        ("export", "--calibration", "cal.json", "--robot-toml", "-", "--urdf", "-"),
        ("--robot-toml", "--urdf", "stdout"),
    ),
]


# ---- spatial serial arms (URDF and robot TOML)


def _urdf(joints: str, links: str = "base,l1,l2") -> str:
    """A URDF of the given joints between links (metres, radians)."""
    declared = "".join(f'<link name="{name}"/>' for name in links.split(","))
    return f'<?xml version="1.0"?>\n<robot name="two">\n{declared}\n{joints}</robot>\n'


def _joint(name: str, parent: str, child: str, extra: str = "") -> str:
    return (
        f'<joint name="{name}" type="revolute"><parent link="{parent}"/>'
        f'<child link="{child}"/><origin xyz="0.3 0 0" rpy="0 0 0"/><axis xyz="0 0 1"/>'
        f'<limit lower="-3" upper="3"/>{extra}</joint>\n'
    )


#: A valid 2R arm: two parallel joints 300 mm apart.
URDF_2R = _urdf(_joint("j1", "base", "l1") + _joint("j2", "l1", "l2"))
#: Its measurements: 6 poses of the point at the end of link 2, with z.
SPATIAL_HEADER = "q1_deg,q2_deg,x_mm,y_mm,z_mm"
SPATIAL_ROWS = [
    f"{a},{b},{300 * (1 + math.cos(math.radians(a)) + math.cos(math.radians(a + b))):.6f},"
    f"{300 * (math.sin(math.radians(a)) + math.sin(math.radians(a + b))):.6f},0.0"
    for a, b in ((0, 10), (30, 40), (60, -20), (-45, 90), (90, 30), (120, -60))
]
SPATIAL_MEAS = csv_file(SPATIAL_HEADER, SPATIAL_ROWS)
IDENTIFY_URDF = ("identify", "--robot", "arm.urdf", "--measurements", "meas.csv", "-o", "cal.json")

#: A 6-DoF instrument's data of the 2R arm: its orientation about z is q1 + q2.
ORIENTED_HEADER = SPATIAL_HEADER + ",rx_deg,ry_deg,rz_deg"
ORIENTED_ROWS = [
    f"{row},0.0,0.0,{float(row.split(',')[0]) + float(row.split(',')[1])}" for row in SPATIAL_ROWS
]
ORIENTED_TOML = 'urdf = "arm.urdf"\n[measurement]\nsigma_mm = 0.02\norientation_sigma_deg = 0.01\n'

CASES += [
    case(
        "urdf-missing-file",
        {"meas.csv": SPATIAL_MEAS},
        IDENTIFY_URDF,
        ("arm.urdf", "no such URDF file"),
    ),
    case(
        "urdf-loop",
        {
            "arm.urdf": _urdf(
                _joint("j1", "base", "l1") + _joint("j2", "l1", "l2") + _joint("j3", "base", "l2")
            ),
            "meas.csv": SPATIAL_MEAS,
        },
        IDENTIFY_URDF,
        ("arm.urdf", "line", "'j3'", "loop"),
    ),
    case(
        "urdf-mimic-on-the-chain",
        {
            "arm.urdf": _urdf(
                _joint("j1", "base", "l1")
                + _joint("j2", "l1", "l2", '<mimic joint="j1" multiplier="1"/>')
            ),
            "meas.csv": SPATIAL_MEAS,
        },
        IDENTIFY_URDF,
        ("arm.urdf", "'j2'", "mimic", "follows joint 'j1'", "--tip-link"),
    ),
    case(
        "urdf-unknown-link",
        {
            "arm.urdf": _urdf(_joint("j1", "base", "l1") + _joint("j2", "l1", "elbow")),
            "meas.csv": SPATIAL_MEAS,
        },
        IDENTIFY_URDF,
        ("arm.urdf", "'j2'", "'elbow'", "not a <link>"),
    ),
    case(
        "urdf-not-xml",
        {"arm.urdf": URDF_2R.replace("</robot>", ""), "meas.csv": SPATIAL_MEAS},
        IDENTIFY_URDF,
        ("arm.urdf", "line", "not well-formed"),
    ),
    case(
        "robot-toml-urdf-missing",
        {"robot.toml": 'urdf = "arm.urdf"\n', "meas.csv": SPATIAL_MEAS},
        IDENTIFY_ROBOT,
        ("robot.toml", "'urdf'", "arm.urdf", "does not exist"),
    ),
    case(
        "robot-toml-tip-link-unknown",
        {
            "robot.toml": 'urdf = "arm.urdf"\ntip_link = "flange"\n',
            "arm.urdf": URDF_2R,
            "meas.csv": SPATIAL_MEAS,
        },
        IDENTIFY_ROBOT,
        ("arm.urdf", "tip_link 'flange'", "not a link"),
    ),
    case(
        "spatial-wrong-joint-count",
        {"arm.urdf": URDF_2R, "meas.csv": csv_file("q1_deg,x_mm,y_mm,z_mm", ["0,1,2,3"] * 6)},
        IDENTIFY_URDF,
        ("meas.csv", "2 joints"),
    ),
    case(
        "spatial-without-z",
        {
            "arm.urdf": URDF_2R,
            "meas.csv": csv_file(
                "q1_deg,q2_deg,x_mm,y_mm", [r.rsplit(",", 1)[0] for r in SPATIAL_ROWS]
            ),
        },
        IDENTIFY_URDF,
        ("z_mm",),
    ),
    case(
        "orientation-not-a-number",
        {
            "robot.toml": ORIENTED_TOML,
            "arm.urdf": URDF_2R,
            "meas.csv": csv_file(
                ORIENTED_HEADER, _with_field(ORIENTED_ROWS, 3, "ry_deg", "12.5°", ORIENTED_HEADER)
            ),
        },
        IDENTIFY_ROBOT,
        ("meas.csv", "row 3", "ry_deg", "12.5°"),
    ),
    case(
        "orientation-empty-field",
        {
            "robot.toml": ORIENTED_TOML,
            "arm.urdf": URDF_2R,
            "meas.csv": csv_file(
                ORIENTED_HEADER, _with_field(ORIENTED_ROWS, 2, "rz_deg", "", ORIENTED_HEADER)
            ),
        },
        IDENTIFY_ROBOT,
        ("meas.csv", "row 2", "rz_deg"),
    ),
    case(
        "orientation-partial-columns",
        {
            "robot.toml": ORIENTED_TOML,
            "arm.urdf": URDF_2R,
            "meas.csv": csv_file(
                ORIENTED_HEADER.rsplit(",", 1)[0], [r.rsplit(",", 1)[0] for r in ORIENTED_ROWS]
            ),
        },
        IDENTIFY_ROBOT,
        ("meas.csv", "line 1", "rx_deg, ry_deg", "not rz_deg"),
    ),
    case(
        "orientation-beyond-a-turn",
        {
            "robot.toml": ORIENTED_TOML,
            "arm.urdf": URDF_2R,
            "meas.csv": csv_file(
                ORIENTED_HEADER, _with_field(ORIENTED_ROWS, 4, "rx_deg", "400", ORIENTED_HEADER)
            ),
        },
        IDENTIFY_ROBOT,
        ("meas.csv", "row 4", "rx_deg", "more than 360", "rotation vector"),
    ),
    case(
        "orientation-without-its-noise",
        {"arm.urdf": URDF_2R, "meas.csv": csv_file(ORIENTED_HEADER, ORIENTED_ROWS)},
        IDENTIFY_URDF,
        ("orientation_sigma_deg", "[measurement]"),
    ),
    case(
        "orientation-of-a-planar-arm",
        {
            "meas.csv": csv_file(
                MEAS_HEADER + ",rx_deg,ry_deg,rz_deg", [r + ",0,0,0" for r in MEAS_ROWS]
            )
        },
        IDENTIFY,
        ("meas.csv", "planar arm", "remove them"),
    ),
    case(
        "orientation-sigma-wrong-unit",
        {
            "robot.toml": ORIENTED_TOML.replace("0.01", "20"),
            "arm.urdf": URDF_2R,
            "meas.csv": csv_file(ORIENTED_HEADER, ORIENTED_ROWS),
        },
        IDENTIFY_ROBOT,
        ("robot.toml", "orientation_sigma_deg", "check the unit (deg)"),
    ),
    case(
        "instrument-acceptance-without-normals",
        {
            "robot.toml": 'urdf = "arm.urdf"\n[instrument]\nposition_mm = [2000, 0, 0]\n'
            "acceptance_deg = 30\n[targets]\nA = { xyz_mm = [0, 0, 50] }\n",
            "arm.urdf": URDF_2R,
        },
        ("design", "--robot", "robot.toml", "--poses", "10", "-o", "plan.csv"),
        ("robot.toml", "instrument.acceptance_deg", "normal", "A"),
    ),
    case(
        "instrument-range-without-position",
        {
            "robot.toml": 'urdf = "arm.urdf"\n[instrument]\nrange_mm = [1000, 5000]\n',
            "arm.urdf": URDF_2R,
        },
        ("design", "--robot", "robot.toml", "--poses", "10", "-o", "plan.csv"),
        ("robot.toml", "instrument.range_mm", "position_mm"),
    ),
    case(
        "instrument-range-reversed",
        {
            "robot.toml": 'urdf = "arm.urdf"\n[instrument]\nposition_mm = [2000, 0, 0]\n'
            "range_mm = [5000, 1000]\n",
            "arm.urdf": URDF_2R,
        },
        ("design", "--robot", "robot.toml", "--poses", "10", "-o", "plan.csv"),
        ("robot.toml", "instrument.range_mm", "least < greatest"),
    ),
    case(
        "mdh-wrong-length",
        {
            "robot.toml": "[mdh]\nalpha_deg = [0, 0]\na_mm = [0, 300]\ntheta_deg = [0]\n"
            "d_mm = [0, 0]\n",
            "meas.csv": SPATIAL_MEAS,
        },
        IDENTIFY_ROBOT,
        ("robot.toml", "mdh.theta_deg", "expected 2"),
    ),
]


# --------------------------------------------------------------------------- tests


@pytest.mark.parametrize(("files", "argv", "expected"), CASES)
def test_bad_input_exits_2_with_one_error_line(
    tmp_path: Path, files: dict[str, object], argv: tuple[str, ...], expected: tuple[str, ...]
) -> None:
    _write(tmp_path, files)
    before = _snapshot(tmp_path)

    result = run_cli(tmp_path, *argv)

    assert "Traceback" not in result.stderr, result.stderr
    assert result.returncode == 2, result.stderr
    # The robot file's warnings, if any, come first (issue 34: they often explain the error)
    *warned, message = result.stderr.removesuffix("\n").split("\n")
    assert all(line.startswith("armcal: warning: ") for line in warned), result.stderr
    assert message.startswith("armcal: error:"), result.stderr
    for text in expected:
        assert text in message, f"{text!r} not in {message!r}"
    assert result.stdout == "", result.stdout
    out = _output(argv)
    if out is not None and os.path.normpath(out) not in {*files, "."}:
        assert not (tmp_path / out).exists(), f"{out} was written"
    assert _snapshot(tmp_path) == before, "files were written, changed or left behind"


@pytest.mark.parametrize(
    ("files", "argv", "output"),
    [
        pytest.param({"meas.csv": VALID_MEAS}, IDENTIFY, "cal.json", id="identify"),
        pytest.param(
            {"meas.csv": VALID_MEAS, "robot.toml": ROBOT_TOML},
            IDENTIFY_ROBOT,
            "cal.json",
            id="identify-robot-file",
        ),
        pytest.param(
            {"arm.urdf": URDF_2R, "meas.csv": SPATIAL_MEAS},
            IDENTIFY_URDF,
            "cal.json",
            id="identify-urdf",
        ),
        pytest.param({"plan.csv": VALID_PLAN}, SYNTHESIZE, "meas.csv", id="synthesize"),
        pytest.param(
            {"plan.csv": VALID_PLAN, "robot.toml": ROBOT_TOML, "truth.toml": TRUTH_TOML},
            SYNTHESIZE_ROBOT,
            "meas.csv",
            id="synthesize-robot-and-truth-files",
        ),
    ],
)
def test_valid_inputs_succeed(
    tmp_path: Path, files: dict[str, object], argv: tuple[str, ...], output: str
) -> None:
    """Control: the valid files the bad cases are derived from are accepted."""
    _write(tmp_path, files)
    result = run_cli(tmp_path, *argv)
    assert result.returncode == 0, result.stderr
    assert result.stderr == ""
    assert (tmp_path / output).is_file()
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted({*files, output})


#: Catalogue cases also run as a real process: the exit status and stderr the shell sees.
REAL_PROCESS_CASES = ("meas-nan", "stdout-for-a-folder", "usage-unknown-subcommand")


@pytest.mark.parametrize(
    ("files", "argv", "expected"), [c for c in CASES if c.id in REAL_PROCESS_CASES]
)
def test_bad_input_in_a_real_process(
    tmp_path: Path, files: dict[str, object], argv: tuple[str, ...], expected: tuple[str, ...]
) -> None:
    """The in-process catalogue's contract holds for ``python -m armcal`` itself."""
    _write(tmp_path, files)
    before = _snapshot(tmp_path)
    result = run_program(tmp_path, *argv)
    assert result.returncode == 2, result.stderr
    assert len(result.stderr.splitlines()) == 1 and result.stderr.startswith("armcal: error:")
    assert all(text in result.stderr for text in expected), result.stderr
    assert result.stdout == ""
    assert _snapshot(tmp_path) == before


# --------------------------------------------------------------------------- outputs


def test_output_link_is_written_through(tmp_path: Path) -> None:
    """A symbolic link as -o: the file it points to is replaced (mode kept), the link kept."""
    _write(tmp_path, {"meas.csv": VALID_MEAS, "data": FOLDER, "data/cal.json": "old\n"})
    (tmp_path / "cal.json").symlink_to("data/cal.json")
    (tmp_path / "data" / "cal.json").chmod(0o640)

    result = run_cli(tmp_path, *IDENTIFY)

    assert result.returncode == 0, result.stderr
    assert os.readlink(tmp_path / "cal.json") == "data/cal.json"
    target = tmp_path / "data" / "cal.json"
    assert json.loads(target.read_text(encoding="utf-8"))["format"] == "armcal-calibration/1"
    assert stat.S_IMODE(target.stat().st_mode) == 0o640
    assert set(_snapshot(tmp_path)) == {"meas.csv", "cal.json", "data", "data/cal.json"}


def test_synthesize_sigma_zero_gives_noiseless_data(tmp_path: Path) -> None:
    _write(tmp_path, {"plan.csv": VALID_PLAN})

    result = run_cli(tmp_path, "synthesize", "--plan", "plan.csv", "--sigma", "0.00")

    assert result.returncode == 0, result.stderr
    lines = result.stdout.splitlines()
    assert lines[0] == MEAS_HEADER and len(lines) == 1 + len(POSES)
    for line, pose in zip(lines[1:], POSES, strict=True):
        fields = [float(v) for v in line.split(",")]
        assert fields[:4] == list(pose)
        # Exact positions of the paper's deviated arm; both sides round off at ~1e-13 mm.
        for got, want in zip(fields[4:], exact_position(pose), strict=True):
            assert math.isclose(got, want, rel_tol=0, abs_tol=1e-9), (line, want)


#: armcal as a terminal's foreground job starts it: Python's own SIGINT handler.  A job a
#: script starts in the background (``cmd &``, as a CI runner or ``nohup`` may) inherits
#: SIGINT ignored (POSIX), Python then keeps it ignored, and armcal rightly runs on: this
#: test, run that way, waited 60 s on a simulate that ignored every Ctrl-C.
FOREGROUND = (
    "import runpy, signal, sys; signal.signal(signal.SIGINT, signal.default_int_handler); "
    "sys.argv[0] = 'armcal'; runpy.run_module('armcal', run_name='__main__', alter_sys=True)"
)


@pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="needs a FIFO to know the run has started")
def test_ctrl_c_exits_130_with_one_line(tmp_path: Path) -> None:
    """SIGINT during a long simulate: status 130, one stderr line, nothing written.

    The plan is a FIFO: opening it for writing succeeds only once the program
    opens it to read the plan, so the signal surely arrives while ``main`` runs.
    """
    _write(tmp_path, {"plan.csv": FIFO})
    before = _snapshot(tmp_path)
    argv = ["simulate", "--plan", "plan.csv", "--trials", "100000000"]
    with subprocess.Popen(
        [sys.executable, "-c", FOREGROUND, *argv],
        cwd=tmp_path,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        encoding="utf-8",
    ) as proc:
        try:
            deadline = time.monotonic() + 60.0
            while True:
                try:
                    fd = os.open(tmp_path / "plan.csv", os.O_WRONLY | os.O_NONBLOCK)
                    break
                except OSError as exc:  # ENXIO: no reader yet
                    assert exc.errno == errno.ENXIO, exc
                assert proc.poll() is None, proc.communicate()
                assert time.monotonic() < deadline, "armcal never opened its plan"
                time.sleep(0.02)
            os.set_blocking(fd, True)
            with os.fdopen(fd, "w", encoding="utf-8") as plan:
                plan.write(VALID_PLAN)
            proc.send_signal(signal.SIGINT)
            stdout, stderr = proc.communicate(timeout=60)
        finally:
            proc.kill()

    assert proc.returncode == 130, stderr
    assert stderr == "armcal: interrupted\n"
    assert stdout == ""
    assert _snapshot(tmp_path) == before


def test_an_existing_output_file_is_replaced(tmp_path: Path) -> None:
    """Scripts rerun commands: -o over an old file replaces it (no --force needed)."""
    _write(tmp_path, {"meas.csv": VALID_MEAS, "cal.json": "an old calibration\n"})

    result = run_cli(tmp_path, *IDENTIFY)

    assert result.returncode == 0, result.stderr
    doc = json.loads((tmp_path / "cal.json").read_text(encoding="utf-8"))
    assert doc["format"] == "armcal-calibration/1"
    assert sorted(_snapshot(tmp_path)) == ["cal.json", "meas.csv"]


@pytest.mark.skipif(
    not hasattr(os, "geteuid") or os.geteuid() == 0, reason="root can read any file"
)
def test_unreadable_input_exits_2(tmp_path: Path) -> None:
    _write(tmp_path, {"meas.csv": VALID_MEAS})
    (tmp_path / "meas.csv").chmod(0)

    result = run_cli(tmp_path, *IDENTIFY)

    assert result.returncode == 2, result.stderr
    assert result.stderr.startswith("armcal: error: meas.csv: cannot read: Permission denied")
    assert not (tmp_path / "cal.json").exists()
