"""The library's messages name no command-line flag; the command line adds its own (issue 34).

Advice that is an option goes through :func:`armcal.errors.action`: the library says
it in its words (:data:`armcal.errors.ACTIONS`: the Python argument, a robot-file
key), the command line in its flags (:data:`armcal.cli.CLI_ACTIONS`).  The first
tests guard the rule over the whole source; the others follow representative
errors, warnings and report lines both ways: the library's ``str(error)`` /
``warning.message`` / report text, and the program's stderr, JSON and text, run
in-process (:func:`helpers.run_cli`).
"""

from __future__ import annotations

import ast
import json
import re
import string
from pathlib import Path

import numpy as np
import pytest

from armcal import ArmcalError, PlanarArm, design, load_robot, monte_carlo, random_plan
from armcal.cli import CLI_ACTIONS
from armcal.errors import ACTIONS, ArmcalWarning, action, render, unrendered
from armcal.files import read_calibration, read_measurements, read_program
from armcal.report import design_summary, format_calibration, model_lines
from armcal.workflow import FixError, calibrate, compensate_program, model_spec, prefixed
from helpers import deviated_tip, run_cli

SOURCE = Path(__file__).resolve().parents[1] / "src" / "armcal"

#: A command-line flag: two dashes and a lower-case word, not inside a longer word or a
#: run of dashes (a Markdown rule ``---|``, a line style ``"--"`` and ``a--b`` are none).
#: ``-o`` is not looked for: the library may name the program's command where its advice
#: is to run another one (``write the calibration again with armcal identify -o``).
FLAG = re.compile(r"(?<![\w-])--[a-z][a-z0-9-]+")

#: Strings outside ``cli/`` that may name flags, by module and top-level name: tables
#: that document the program itself, not advice in a message.  ``FILE_KINDS`` and
#: ``COLUMNS`` (:mod:`armcal.columns`) are what ``armcal formats`` prints about each file
#: (which option reads it); the catalogue entry names the command that offers the paper's missing A
#: criterion, part of what ``armcal reproduce`` reports about the paper.
DOCUMENTS_THE_PROGRAM = {
    ("formats.py", "FILE_KINDS"),
    ("columns.py", "COLUMNS"),
    ("reproduction/catalogue.py", "DISAGREEMENTS"),
}


def _docstrings(tree: ast.AST) -> set[int]:
    """The ids of the docstring constants of a module, its classes and its functions."""
    found = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Module | ast.ClassDef | ast.FunctionDef | ast.AsyncFunctionDef):
            first = node.body[0] if node.body else None
            if (
                isinstance(first, ast.Expr)
                and isinstance(first.value, ast.Constant)
                and isinstance(first.value.value, str)
            ):
                found.add(id(first.value))
    return found


def _top_level_name(statement: ast.stmt) -> str:
    """The name a module's top-level statement defines (``""`` for none)."""
    if isinstance(statement, ast.FunctionDef | ast.AsyncFunctionDef | ast.ClassDef):
        return statement.name
    targets = statement.targets if isinstance(statement, ast.Assign) else []
    if isinstance(statement, ast.AnnAssign):
        targets = [statement.target]
    names = [t.id for t in targets if isinstance(t, ast.Name)]
    return names[0] if names else ""


def flags_in(source: str, module: str = "") -> list[tuple[int, str]]:
    """``(line, flag)`` of every flag in a string of ``source`` that is no docstring.

    The rule: every string constant of the module counts, the parts of f-strings
    among them, wherever it stands (an error's or a warning's argument, a message
    helper's return value, a module constant such as an advice phrase, a note, a
    field of a result), except the docstrings of the module, its classes and its
    functions, which document the command line freely, and the named tables of
    :data:`DOCUMENTS_THE_PROGRAM`.  Comments are not in the syntax tree.  Looking
    only at the arguments of ``ArmcalError(...)`` and ``ArmcalWarning(...)`` would
    miss the advice built elsewhere (``no_closed_form``, a module's advice
    constant, a design note); this rule is stricter and as precise.
    """
    tree = ast.parse(source)
    docstrings = _docstrings(tree)
    found = []
    for statement in tree.body:
        if (module, _top_level_name(statement)) in DOCUMENTS_THE_PROGRAM:
            continue
        for node in ast.walk(statement):
            if (
                isinstance(node, ast.Constant)
                and isinstance(node.value, str)
                and id(node) not in docstrings
            ):
                found += [(node.lineno, flag) for flag in FLAG.findall(node.value)]
    return found


def _library_modules() -> list[Path]:
    return sorted(p for p in SOURCE.rglob("*.py") if p.relative_to(SOURCE).parts[0] != "cli")


def test_no_library_string_names_a_flag():
    """Every module outside ``cli/`` (:func:`flags_in`): advice goes through an action."""
    modules = _library_modules()
    assert len(modules) > 100  # the whole library is scanned, not an empty folder
    named = [
        f"{path.relative_to(SOURCE)}:{line}: {flag}"
        for path in modules
        for line, flag in flags_in(
            path.read_text(encoding="utf-8"), path.relative_to(SOURCE).as_posix()
        )
    ]
    assert named == [], "name the advice through armcal.errors.action:\n" + "\n".join(named)


def test_the_scan_finds_a_flag_in_any_message_but_not_in_a_docstring():
    """The guard can fail: flags in an error, an f-string's part, a helper's return value
    and a module constant are found; a docstring's, a line style and a rule are not."""
    source = '''
"""Module: ``armcal design --poses 10`` documents the program."""
ADVICE = "measure better (smaller --sigma)"
STYLE = dict(ls="--", rule="|---|")


def helper(n):
    """Say ``--fix NAME`` here freely."""
    return f"use --method {n} or auto"


def check(k):
    raise ArmcalError(f"{k} folds; --cross-validate needs 2")
'''
    assert [flag for _, flag in flags_in(source)] == [
        "--sigma",
        "--method",
        "--cross-validate",
    ]
    # A table that documents the program is skipped only by its name and module.
    table = 'FILE_KINDS = {"robot": "robot TOML (--robot)"}\n'
    assert flags_in(table, "formats.py") == []
    assert flags_in(table, "files/robots.py") == [(1, "--robot")]


def test_every_action_has_words_in_both_vocabularies():
    """Same keys, no flag in the library's words, and values placed by both or neither."""
    assert set(CLI_ACTIONS) == set(ACTIONS)
    fields = string.Formatter()
    for key, words in ACTIONS.items():
        assert not FLAG.search(words), key
        placed = [name for _, name, _, _ in fields.parse(words) if name is not None]
        cli_placed = [name for _, name, _, _ in fields.parse(CLI_ACTIONS[key]) if name is not None]
        assert bool(placed) == bool(cli_placed), key
        values = ("a", "b") if placed else ()
        for vocabulary in (ACTIONS, CLI_ACTIONS):
            said = render(f"x {action(key, *values)} y", vocabulary)
            assert "\u27e6" not in said and "{" not in said and said.startswith("x "), (key, said)


def test_an_action_needs_its_values_and_keeps_any_text():
    """A value may hold the separators of the reference itself; it comes back as given."""
    with pytest.raises(ValueError, match="needs its values"):
        action("method")
    with pytest.raises(KeyError):
        action("no-such-advice")
    odd = "a|b\u27e7c%7C d,\u27e6e"
    text = f"use {action('method', odd)} now"
    assert render(text) == f'use method="{odd}" now'
    assert render(text, {"method": "--method {}"}) == f"use --method {odd} now"
    assert render(action("hold", "dq1", "dq2@A"), CLI_ACTIONS) == "--fix dq1,dq2@A"
    assert render(action("hold", "dq1", "dq2@A")) == 'fixed=["dq1", "dq2@A"]'


def test_an_error_built_from_another_keeps_its_actions():
    """``prefixed`` and :func:`unrendered` carry the text as raised; ``str`` would have
    said it in the library's words for good, and the command line could not add its flag."""
    inner = FixError(f"{action('fixed')}: no; {action('hold', 'dq2')}")
    outer = prefixed("robot.toml", inner)
    assert type(outer) is FixError
    assert str(outer) == 'robot.toml: fixed: no; fixed=["dq2"]'
    assert outer.render(CLI_ACTIONS) == "robot.toml: --fix: no; --fix dq2"
    rebuilt = ArmcalError(f"file.csv: {unrendered(inner)}")
    assert rebuilt.render(CLI_ACTIONS) == "file.csv: --fix: no; --fix dq2"
    assert unrendered(ValueError("plain")) == "plain"
    assert (
        ArmcalWarning("w", f"a {action('trials', 1000)}").render(CLI_ACTIONS) == "a --trials 1000"
    )


# ---------------------------------------------------------------- both ways, in-process


def _plan_csv(q_deg: np.ndarray, joints: int) -> str:
    header = ",".join(f"q{j + 1}_deg" for j in range(joints))
    return "\n".join([header, *(",".join(repr(float(v)) for v in q) for q in q_deg)]) + "\n"


def _measurements_csv(q_deg: np.ndarray, links: tuple[float, ...], z_mm: float | None = None):
    """Rows of the nominal arm's tip (paper eq. 1, :func:`helpers.deviated_tip` with no
    deviation), with a constant ``z_mm`` column for 3-D data."""
    n = len(links)
    header = [*(f"q{j + 1}_deg" for j in range(n)), "x_mm", "y_mm"]
    header += [] if z_mm is None else ["z_mm"]
    lines = [",".join(header)]
    for q in q_deg:
        x, y = deviated_tip(tuple(q), links, (0.0,) * n, (0.0,) * n)
        fields = [*(repr(float(v)) for v in q), repr(x), repr(y)]
        lines.append(",".join(fields + ([] if z_mm is None else [repr(z_mm)])))
    return "\n".join(lines) + "\n"


def _one_error(run) -> str:
    assert run.returncode == 2, run.stderr
    lines = run.stderr.splitlines()
    assert len(lines) == 1 and lines[0].startswith("armcal: error: "), run.stderr
    return lines[0]


TWO_TARGETS = (
    'name = "two-tools"\nlink_lengths_mm = [260.0, 180.0]\n'
    "[targets]\nA = { length_mm = 100.0 }\nB = { length_mm = 60.0 }\n"
)


def test_holding_the_last_link_of_an_arm_with_targets(tmp_path):
    """FixError: the library names ``fixed`` and its list, the program ``--fix`` (the
    prefix it always printed) and the names comma-joined as the flag takes them."""
    (tmp_path / "robot.toml").write_text(TWO_TARGETS)
    spec = load_robot(tmp_path / "robot.toml")
    with pytest.raises(FixError) as info:
        model_spec(spec, spec.arm, fixed=["dl2"])
    said = str(info.value)
    assert said.startswith("fixed: unknown parameter 'dl2'; with targets it is one per target")
    assert 'hold them all with fixed=["dl2@A", "dl2@B"];' in said and "--" not in said

    argv = ("design", "--robot", "robot.toml", "--poses", "8", "--fix", "dl2")
    line = _one_error(run_cli(tmp_path, *argv))
    assert line.startswith("armcal: error: --fix: unknown parameter 'dl2'; with targets")
    assert "hold them all with --fix dl2@A,dl2@B;" in line and "fixed=" not in line


def test_closed_form_with_a_held_parameter_through_the_measurement_file(tmp_path):
    """An error the workflow prefixes with the file's name keeps its action: the library
    says ``method="gauss-newton"``, the program ``--method gauss-newton``."""
    spec = load_robot("paper-2link")
    links = tuple(float(v) for v in spec.arm.link_lengths)
    q_deg = np.random.default_rng(3).uniform(-150.0, 150.0, (8, 2))
    (tmp_path / "meas.csv").write_text(_measurements_csv(q_deg, links))
    meas = read_measurements(tmp_path / "meas.csv", spec.arm)
    with pytest.raises(ArmcalError) as info:
        calibrate(spec, meas, source="meas.csv", method="closed-form", fixed=("dl2",))
    assert str(info.value) == (
        "meas.csv: the closed form needs every parameter free, but dl2 is fixed; use "
        'method="gauss-newton" or auto'
    )

    argv = ("identify", "--robot", "paper-2link", "--measurements", "meas.csv")
    line = _one_error(run_cli(tmp_path, *argv, "--method", "closed-form", "--fix", "dl2"))
    assert line == (
        "armcal: error: meas.csv: the closed form needs every parameter free, but dl2 is "
        "fixed; use --method gauss-newton or auto"
    )


def test_fit_inconsistent_names_the_held_parameter_to_free(tmp_path):
    """``fit-inconsistent`` with dl2 held 2 mm off: the library's advice names
    ``calibrate(..., fixed=...)``, the program's ``--fix`` on stderr, in the JSON and in
    the calibration file ``identify -o`` writes (the same text each)."""
    links, dl, dq = (260.0, 180.0), (0.0, 2.0), (0.0, 0.0)
    q_deg = np.random.default_rng(8).uniform(-150.0, 150.0, (12, 2))
    noise = np.random.default_rng(9).normal(0.0, 0.02, (12, 2))
    lines = ["q1_deg,q2_deg,x_mm,y_mm"]
    for q, e in zip(q_deg, noise, strict=True):
        x, y = deviated_tip(tuple(q), links, dl, dq)
        lines.append(",".join(repr(float(v)) for v in (*q, x + e[0], y + e[1])))
    (tmp_path / "meas.csv").write_text("\n".join(lines) + "\n")
    (tmp_path / "robot.toml").write_text(
        f"link_lengths_mm = {list(links)}\n[measurement]\nsigma_mm = 0.02\n"
    )
    advice = "the fixed parameter dl2 is not at nominal: with it free, chi2 = "
    spec = load_robot(tmp_path / "robot.toml")
    run = calibrate(spec, read_measurements(tmp_path / "meas.csv", spec.arm), fixed=("dl2",))
    (library,) = [w.message for w in run.warnings if w.code == "fit-inconsistent"]
    assert advice in library
    assert "; free it (calibrate(..., fixed=...) or the robot file's [identify])" in library
    assert "--" not in library

    argv = ("identify", "--robot", "robot.toml", "--measurements", "meas.csv", "--fix", "dl2")
    result = run_cli(tmp_path, *argv, "-o", "cal.json", "--json")
    assert result.returncode == 0, result.stderr
    cli = "; free it (--fix or the robot file's [identify])"
    (said,) = [line for line in result.stderr.splitlines() if advice in line]
    assert said.startswith("armcal: warning: the fit is inconsistent") and cli in said
    for document in (json.loads(result.stdout), json.loads((tmp_path / "cal.json").read_text())):
        (listed,) = [w["message"] for w in document["warnings"] if w["code"] == "fit-inconsistent"]
        assert listed == said.removeprefix("armcal: warning: ")


def test_few_trials_warning_in_both_vocabularies(tmp_path):
    """A warning: ``trials=1000`` from the library, ``--trials 1000`` on stderr and in the
    JSON, once each; 1000 trials know a std to 100 / sqrt(2 x 999) = 2.2 %."""
    spec = load_robot("paper-2link")
    q = random_plan(spec.arm, 6, rng=np.random.default_rng(4))
    result = monte_carlo(spec.arm, q, spec.default_truth, 0.1, 20, rng=5)
    (few,) = [w for w in result.warnings if w.code == "few-trials"]
    assert "use trials=1000 or more (+-2.2 %)" in few.message and "--" not in few.message

    (tmp_path / "plan.csv").write_text(_plan_csv(np.degrees(q), 2))
    argv = ("simulate", "--robot", "paper-2link", "--plan", "plan.csv", "--trials", "20")
    run = run_cli(tmp_path, *argv, "--json")
    assert run.returncode == 0, run.stderr
    said = [line for line in run.stderr.splitlines() if "1000 or more" in line]
    assert said[0].startswith("armcal: warning: with 20 trials"), run.stderr
    assert len(said) == 1 and "use --trials 1000 or more (+-2.2 %)" in said[0], run.stderr
    (listed,) = [w for w in json.loads(run.stdout)["warnings"] if w["code"] == "few-trials"]
    assert "use --trials 1000 or more" in listed["message"]


def test_base_rotation_note_of_the_report(tmp_path):
    """A report line: 3-D data of a 3-link arm whose joints read absolute angles (joint map
    I) hold dq1 against phi0 and name dq2 as the other zero to take: ``fixed=["dq2"]`` in
    the library's report, ``--fix dq2`` in the program's, as docs/model.md prints it."""
    arm = PlanarArm(
        [260.0, 180.0, 120.0], base_offset=True, base_rotation=True, joint_map=np.eye(3)
    )
    note = "(to take dq2's zero as the arm's instead, "
    (library,) = [line for line in model_lines(arm) if note in line]
    assert library.endswith(note + 'fixed=["dq2"])')
    (cli,) = [line for line in model_lines(arm, words=CLI_ACTIONS) if note in line]
    assert cli.endswith(note + "--fix dq2)")

    links = np.array([260.0, 180.0, 120.0])
    (tmp_path / "robot.toml").write_text(
        f'name = "coupled"\nlink_lengths_mm = {links.tolist()}\n'
        "joint_map = [[1, 0, 0], [0, 1, 0], [0, 0, 1]]\n"
    )
    q = np.radians(np.random.default_rng(6).uniform(-150.0, 150.0, (12, 3)))
    # With the joint map I each joint reads its link's absolute angle: tip = sum l_k e^(i q_k).
    tip = np.stack([np.cos(q) @ links, np.sin(q) @ links], axis=1)
    rows = [
        ",".join(repr(float(v)) for v in (*np.degrees(qi), *p, 250.0))
        for qi, p in zip(q, tip, strict=True)
    ]
    header = "q1_deg,q2_deg,q3_deg,x_mm,y_mm,z_mm"
    (tmp_path / "meas.csv").write_text("\n".join([header, *rows]) + "\n")
    run = run_cli(tmp_path, "identify", "--robot", "robot.toml", "--measurements", "meas.csv")
    assert run.returncode == 0, run.stderr
    assert note + "--fix dq2)" in run.stdout and "fixed=[" not in run.stdout
    spec = load_robot(tmp_path / "robot.toml")
    cal = calibrate(spec, read_measurements(tmp_path / "meas.csv", spec.arm)).calibration
    assert note + 'fixed=["dq2"])' in format_calibration(cal)


def test_design_note_names_the_method_in_each_vocabulary(tmp_path):
    """A design's note (``method="auto"`` / ``--method auto``): the closed-form plan of the
    3-link arm is not D-optimal under noise of 0.05 mm along x and 0.3 mm along y."""
    robot = (
        'name = "skewed"\nlink_lengths_mm = [260.0, 180.0, 120.0]\n'
        "[measurement]\nsigma_mm = [0.05, 0.3]\n"
    )
    (tmp_path / "robot.toml").write_text(robot)
    arm = load_robot(tmp_path / "robot.toml").arm
    made = design(arm, 6, method="analytic", rng=1, with_certificate=False)
    (note,) = [n for n in made.notes if "not D-optimal for this model" in n]
    assert note.endswith('; method="auto" optimizes for it')
    _, lines = design_summary(made, 0.0, words=CLI_ACTIONS)
    (line,) = [line for line in lines if "not D-optimal" in line]
    assert line.startswith("note: ") and line.endswith("; --method auto optimizes for it")

    argv = ("design", "--robot", "robot.toml", "--poses", "6", "--method", "analytic", "--json")
    run = run_cli(tmp_path, *argv)
    assert run.returncode == 0, run.stderr
    (listed,) = [n for n in json.loads(run.stdout)["notes"] if "not D-optimal" in n]
    assert listed.endswith("; --method auto optimizes for it")


def test_compensate_options_in_each_vocabulary(tmp_path):
    """A rigid calibration refuses a payload and a target it does not have: the library
    names its arguments ``payload_kg`` and ``target``, the program its flags."""
    spec = load_robot("paper-2link")
    links = tuple(float(v) for v in spec.arm.link_lengths)
    q_deg = np.random.default_rng(7).uniform(-150.0, 150.0, (8, 2))
    (tmp_path / "meas.csv").write_text(_measurements_csv(q_deg, links))
    (tmp_path / "prog.csv").write_text(_plan_csv(q_deg[:3], 2))
    argv = ("identify", "--robot", "paper-2link", "--measurements", "meas.csv", "-o", "cal.json")
    assert run_cli(tmp_path, *argv).returncode == 0
    cal = read_calibration(tmp_path / "cal.json")
    program = read_program(tmp_path / "prog.csv", cal.arm)
    compensate = ("compensate", "--calibration", "cal.json", "--program", "prog.csv")

    with pytest.raises(ArmcalError) as info:
        compensate_program(cal, program, payload_kg=5.0)
    assert str(info.value).startswith(
        "payload_kg (given or the program's column): the calibration has no joint compliance"
    )
    line = _one_error(run_cli(tmp_path, *compensate, "--payload-kg", "5", "-o", "out.csv"))
    assert line.startswith(
        "armcal: error: --payload-kg/payload_kg: the calibration has no joint compliance"
    )

    with pytest.raises(ArmcalError) as info:
        compensate_program(cal, program, target="T")
    assert str(info.value) == "target: 'T' is not a target of the calibration (none)"
    line = _one_error(run_cli(tmp_path, *compensate, "--target", "T", "-o", "out.csv"))
    assert line == "armcal: error: --target: 'T' is not a target of the calibration (none)"
