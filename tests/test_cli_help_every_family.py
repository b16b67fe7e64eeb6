"""Help that speaks to every user, and the parser that is a table (issue 35, items 6 and 7).

Every command that takes ``--robot`` says in its ``--help`` which robot
descriptions it takes (a planar robot TOML, a URDF, a robot TOML over a URDF or
an MDH/DH/UR table, the built-ins by name), names every built-in of both
families from :mod:`armcal.files`' own lists, and shows an example for a
six-axis arm that runs. The outputs paragraph is said once, in ``armcal
--help``. The parser is :data:`armcal.cli.parser.COMMAND_TABLE` walked by a short
builder: one parser per row, options in the row's order.
"""

from __future__ import annotations

import argparse
import shlex
from pathlib import Path

import numpy as np
import pytest

from armcal.cli import build_parser
from armcal.cli.help import COMMANDS, OUTPUTS_EPILOG, OUTPUTS_POINTER
from armcal.cli.parser import COMMAND_TABLE, OneOf
from armcal.doe import random_plan
from armcal.files import (
    BUILTIN_ROBOTS,
    BUILTIN_SPATIAL_ROBOTS,
    format_plan_csv,
    load_spatial_robot,
)
from armcal.files.robots import SPATIAL_ROBOT_KEYS
from helpers import run_cli

SRC = Path(__file__).resolve().parents[1] / "src" / "armcal" / "cli"
#: The commands PRODUCT.md gives a robot ("--robot NAME_OR_FILE ... where a robot is needed").
ROBOT_COMMANDS = {
    "synthesize",
    "identify",
    "design",
    "evaluate",
    "simulate",
    "poses-needed",
    "demo",
}


def _subparsers() -> dict[str, argparse.ArgumentParser]:
    parser = build_parser()
    action = next(a for a in parser._actions if a.dest == "command")
    return dict(action.choices)


def _flat(text: str) -> str:
    """The text with its line wraps undone (help is wrapped at 79 columns)."""
    return " ".join(text.split())


def _with_robot() -> dict[str, argparse.ArgumentParser]:
    return {
        name: sub
        for name, sub in _subparsers().items()
        if any("--robot" in a.option_strings for a in sub._actions)
    }


def _text_of(command: str) -> str:
    return _subparsers()[command].format_help()


def _examples(help_text: str) -> list[str]:
    """The command lines under ``example:``/``examples:`` of a rendered ``--help``."""
    lines = help_text.splitlines()
    start = next(i for i, line in enumerate(lines) if line in ("example:", "examples:"))
    found = []
    for line in lines[start + 1 :]:
        if not line.startswith("  armcal "):
            break
        found.append(line.strip())
    return found


# --------------------------------------------------------------------------- robots in help


def test_the_commands_with_a_robot_are_the_ones_product_md_names():
    assert set(_with_robot()) == ROBOT_COMMANDS


@pytest.mark.parametrize("command", sorted(ROBOT_COMMANDS))
def test_help_names_every_builtin_every_robot_description_and_a_six_axis_example(command):
    text = _flat(_with_robot()[command].format_help())
    for name in (*BUILTIN_ROBOTS, *BUILTIN_SPATIAL_ROBOTS):
        assert name in text, name
    assert "URDF" in text and "--base-link" in text and "--tip-link" in text
    assert "planar robot TOML" in text
    # every key that makes a robot TOML spatial: urdf = ..., [mdh], [dh], [ur]
    for key in SPATIAL_ROBOT_KEYS:
        assert (f"{key} =" if key == "urdf" else f"[{key}]") in text, key
    examples = _examples(_text_of(command))
    robots = {build_parser().parse_args(shlex.split(line)[1:]).robot for line in examples}
    assert robots & set(BUILTIN_SPATIAL_ROBOTS), f"{command}: no example for a six-axis arm"


def test_the_builtins_in_help_come_from_the_files_lists_not_literals():
    """A built-in's name is written in the help's words and the parser only in example
    command lines: the lists printed under reads: are armcal.files' own, so a new
    built-in shows up by itself."""
    in_examples = " ".join(line for help_ in COMMANDS.values() for line in help_.examples)
    for path in (SRC / "help.py", SRC / "parser.py"):
        source = path.read_text(encoding="utf-8")
        for name in (*BUILTIN_ROBOTS, *BUILTIN_SPATIAL_ROBOTS):
            expected = in_examples.count(name) if path.name == "help.py" else 0
            assert source.count(name) == expected, f"{path.name}: {name}"


# --------------------------------------------------------------------------- examples


@pytest.mark.parametrize("command", sorted(COMMANDS))
def test_every_example_the_help_shows_parses(command):
    """The examples as the user reads them in --help, not as the table holds them."""
    shown = _examples(_text_of(command))
    assert shown == list(COMMANDS[command].examples)
    for line in shown:
        argv = shlex.split(line)
        assert argv[:2] == ["armcal", command]
        assert build_parser().parse_args(argv[1:]).command == command


#: Commands whose six-axis example designs a plan (tens of seconds on a 6R arm): run only
#: by the slow test; the fast one starts from a random plan of the design's size instead.
DESIGNING = {"design", "poses-needed", "demo"}
#: The order the examples run in, each reading what an earlier one wrote.
WORKFLOW = (
    "design",
    "evaluate",
    "simulate",
    "poses-needed",
    "synthesize",
    "identify",
    "validate",
    "compensate",
    "export",
    "demo",
)


def test_the_workflow_order_has_every_command_that_reads_a_file():
    reads = {c.name for c in COMMAND_TABLE if c.inputs}
    assert reads <= set(WORKFLOW)


def _run_six_axis_examples(folder: Path, skip: set[str]) -> list[str]:
    """Run, in :data:`WORKFLOW` order, every example for a spatial built-in and every
    example that reads only files the examples run before it wrote; return those run."""
    ran = []
    for command in WORKFLOW:
        for line in COMMANDS[command].examples:
            argv = shlex.split(line)[1:]
            args = build_parser().parse_args(argv)
            robot = getattr(args, "robot", None)
            files = [
                getattr(args, dest) for dest in getattr(args, "inputs", ()) if dest != "robot"
            ]
            written = bool(files) and all(f is None or (folder / f).is_file() for f in files)
            if command in skip or not (robot in BUILTIN_SPATIAL_ROBOTS or (written and not robot)):
                continue
            result = run_cli(folder, *argv)
            assert result.returncode == 0, f"{line}\n{result.stderr}"
            for dest in getattr(args, "outputs", ()):
                path = getattr(args, dest)
                assert path is None or (folder / path).exists(), f"{line}: no {path}"
            ran.append(line)
    return ran


def _six_axis_examples() -> list[str]:
    return [
        line
        for help_ in COMMANDS.values()
        for line in help_.examples
        if getattr(build_parser().parse_args(shlex.split(line)[1:]), "robot", None)
        in BUILTIN_SPATIAL_ROBOTS
    ]


def test_the_six_axis_examples_that_read_a_plan_run(tmp_path):
    """synthesize, identify, evaluate, simulate and export as their help shows them, on a
    random plan of the size the design example asks for (seeded)."""
    design = next(e for e in COMMANDS["design"].examples if e in _six_axis_examples())
    args = build_parser().parse_args(shlex.split(design)[1:])
    arm = load_spatial_robot(args.robot).arm
    q = random_plan(arm, args.poses, rng=np.random.default_rng(35))
    (tmp_path / args.output).write_text(format_plan_csv(q), encoding="utf-8")
    ran = _run_six_axis_examples(tmp_path, DESIGNING)
    commands = [shlex.split(line)[1] for line in ran]
    assert commands == ["evaluate", "simulate", "synthesize", "identify", "export"]


@pytest.mark.slow
def test_every_six_axis_example_runs(tmp_path):
    """The whole chain, the design included: every six-axis example runs, none is skipped
    for a file that no example before it wrote."""
    ran = _run_six_axis_examples(tmp_path, set())
    assert set(_six_axis_examples()) <= set(ran)
    assert any(shlex.split(line)[1] == "export" for line in ran)


# --------------------------------------------------------------------------- outputs once


def test_the_outputs_paragraph_is_said_once_and_pointed_to():
    top = _flat(build_parser().format_help())
    assert _flat(OUTPUTS_EPILOG) in top
    assert "armcal --help" in OUTPUTS_POINTER
    for name, sub in _subparsers().items():
        text = _flat(sub.format_help())
        assert "renamed into place" not in text, name  # a sentence of the paragraph
        assert (OUTPUTS_POINTER in text) == COMMANDS[name].writes, name


# --------------------------------------------------------------------------- the table


def test_the_parser_has_one_command_per_row_with_the_rows_options_in_order():
    subs = _subparsers()
    assert list(subs) == [c.name for c in COMMAND_TABLE]
    for command in COMMAND_TABLE:
        flags = [
            one.flags[0]
            for entry in command.options
            for one in (entry.options if isinstance(entry, OneOf) else (entry,))
        ]
        shown = [a.option_strings[0] for a in subs[command.name]._actions if a.option_strings]
        assert shown == ["-h", *flags], command.name
        defaults = subs[command.name]._defaults
        assert defaults["run"] is command.run
        assert defaults.get("inputs", ()) == command.inputs
        assert defaults.get("outputs", ()) == command.outputs
