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

from pathlib import Path

from helpers import Run, cell_toml, run_cli


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
    from armcal.files.serial import BUILTIN_SERIAL_ROBOTS

    source = BUILTIN_SERIAL_ROBOTS["industrial-6r"]
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
