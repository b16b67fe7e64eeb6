"""Help that teaches, and the file oddities a newcomer's files have that armcal accepts.

Every command's ``--help`` says what it does, names the files it reads with
their columns, and shows an example that the parser accepts; ``armcal
formats`` lists every robot-file key.  Files from spreadsheets and instruments
(byte-order mark, CRLF, semicolons with decimal commas, tabs, ``#`` comments)
read the same as the plain file, and ``-`` pipes files through stdin and stdout.
"""

from __future__ import annotations

import json
import shlex
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from armcal.cli import build_parser
from armcal.cli.help import COMMANDS
from armcal.files import COMPLIANCE_TRUTH_KEYS, load_robot, read_measurements
from armcal.formats import COLUMNS, ROBOT_KEYS, TRUTH_KEYS, columns_line, format_reference
from helpers import run_cli

PAPER = load_robot("paper-4link").arm


def _subparsers() -> dict:
    parser = build_parser()
    action = next(a for a in parser._actions if a.dest == "command")
    return dict(action.choices)


def test_every_command_has_help() -> None:
    assert set(_subparsers()) == set(COMMANDS)


@pytest.mark.parametrize("command", sorted(COMMANDS))
def test_help_has_a_paragraph_an_example_and_the_files_read(command: str) -> None:
    text = _subparsers()[command].format_help()
    help_ = COMMANDS[command]
    assert len(help_.text.split()) >= 25, "one paragraph, not a line"
    assert help_.text.split()[0] in text
    assert "example" in text
    for example in help_.examples:
        assert example in text
    for kind, columns in COLUMNS.items():
        if any(line.startswith(f"{kind} CSV") for line in help_.reads):
            assert all(c.name in text for c in columns if c.required), kind
    if command in {"identify", "validate"}:
        assert columns_line("measurements") in " ".join(text.split())


@pytest.mark.parametrize(
    ("command", "example"),
    [(name, line) for name, h in sorted(COMMANDS.items()) for line in h.examples],
)
def test_every_example_is_accepted_by_the_parser(command: str, example: str) -> None:
    argv = shlex.split(example)
    assert argv[:2] == ["armcal", command]
    args = build_parser().parse_args(argv[1:])
    assert args.command == command


def test_formats_lists_every_key_and_column() -> None:
    text = format_reference()
    for key in (*ROBOT_KEYS, *TRUTH_KEYS):
        assert key.name in text and key.default in " ".join(text.split())
    for columns in COLUMNS.values():
        for column in columns:
            assert column.name in text
    assert set(COMPLIANCE_TRUTH_KEYS.values()) <= {k.name for k in TRUTH_KEYS}
    for table in {k.table for k in ROBOT_KEYS if k.table}:
        assert f"[{table}]" in text


def test_formats_command_prints_the_reference(tmp_path: Path) -> None:
    result = run_cli(tmp_path, "formats")
    assert result.returncode == 0, result.stderr
    assert result.stdout == format_reference() + "\n"


# --------------------------------------------------------------------------- accepted oddities

PLAIN = (
    "q1_deg,q2_deg,q3_deg,q4_deg,x_mm,y_mm\n"
    "0,10.5,-20,30,512.25,88.125\n"
    "15,-40,60,-80,430.5,210.75\n"
    "-30,90,-45,20.25,120,355.5\n"
)


def _semicolon_decimal_comma(text: str) -> str:
    return text.replace(",", ";").replace(".", ",")


@pytest.mark.parametrize(
    "variant",
    [
        pytest.param(lambda t: "\ufeff" + t, id="byte-order-mark"),
        pytest.param(lambda t: t.replace("\n", "\r\n"), id="crlf"),
        pytest.param(lambda t: t.replace(",", ";"), id="semicolons"),
        pytest.param(_semicolon_decimal_comma, id="semicolons-decimal-comma"),
        pytest.param(lambda t: t.replace(",", "\t"), id="tabs"),
        pytest.param(lambda t: "# Leica AT960 export\n#\n" + t + "# end\n", id="comments"),
        pytest.param(lambda t: t.replace(",", ", "), id="spaces-after-commas"),
        pytest.param(lambda t: t.replace("\n", "\n\n"), id="blank-lines"),
    ],
)
def test_spreadsheet_and_instrument_files_read_like_the_plain_one(tmp_path: Path, variant) -> None:
    plain = tmp_path / "plain.csv"
    plain.write_text(PLAIN, encoding="utf-8")
    odd = tmp_path / "odd.csv"
    odd.write_bytes(variant(PLAIN).encode("utf-8"))
    want, got = read_measurements(plain, PAPER), read_measurements(odd, PAPER)
    np.testing.assert_array_equal(got.q, want.q)
    np.testing.assert_array_equal(got.xy, want.xy)
    assert got.rows == want.rows


def test_semicolon_file_row_errors_name_the_file_line(tmp_path: Path) -> None:
    """Line numbers count comment lines, so the message points at the line in an editor."""
    path = tmp_path / "m.csv"
    text = _semicolon_decimal_comma(PLAIN).replace("430,5", "430,5,1")
    path.write_text("# export\n" + text, encoding="utf-8")
    with pytest.raises(Exception, match=r"row 2 \(line 4\), column x_mm: '430,5,1'"):
        read_measurements(path, PAPER)


# --------------------------------------------------------------------------- stdin and stdout


def _armcal(cwd: Path, *args: str, stdin: str = "") -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, "-m", "armcal", *args],
        cwd=cwd,
        input=stdin,
        capture_output=True,
        text=True,
        check=False,
        timeout=120,
    )


def test_a_pipeline_through_stdin_and_stdout(tmp_path: Path) -> None:
    """design | synthesize | identify, with each file given as '-', as a shell pipe runs them."""
    plan = _armcal(tmp_path, "design", "--poses", "12", "-o", "-")
    assert plan.returncode == 0, plan.stderr
    assert plan.stdout.startswith("q1_deg,q2_deg,q3_deg,q4_deg\n")
    meas = _armcal(tmp_path, "synthesize", "--plan", "-", "--sigma", "0", stdin=plan.stdout)
    assert meas.returncode == 0, meas.stderr
    piped = _armcal(
        tmp_path,
        "identify",
        "--robot",
        "paper-4link",
        "--measurements",
        "-",
        "-o",
        "-",
        stdin=meas.stdout,
    )
    assert piped.returncode == 0, piped.stderr
    (tmp_path / "meas.csv").write_text(meas.stdout, encoding="utf-8")
    filed = _armcal(
        tmp_path, "identify", "--robot", "paper-4link", "--measurements", "meas.csv", "--json"
    )
    assert filed.returncode == 0, filed.stderr
    from_pipe, from_file = json.loads(piped.stdout), json.loads(filed.stdout)
    assert from_pipe["parameters"] == from_file["parameters"]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["meas.csv"]
