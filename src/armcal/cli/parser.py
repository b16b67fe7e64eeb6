"""The ``armcal`` argument parser: a table of commands and a short builder that walks it.

:data:`COMMAND_TABLE` holds one :class:`Command` per sub-command: its name (its
words, summary, paragraph and examples, live in :mod:`.help` under that name),
the function of :mod:`.commands` that runs it, and its options in the order
``--help`` lists them. Options that several commands share are named once below
(``_SEED``, ``_robot_seed_json``, ...). ``inputs`` and ``outputs`` name the
options whose paths :func:`armcal.cli.main` checks before any work, and
``folder_files`` the function of :mod:`.commands` that names the files a folder
output will hold (called when the command runs: the names are its modules').

The parser imports :mod:`armcal.choices` for the values it lists, and none of the
library: ``armcal --help`` and ``armcal COMMAND --help`` import no numerics, not even
numpy (:mod:`.commands` imports what a command runs when it runs).
"""

from __future__ import annotations

import argparse
import textwrap
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from .._version import __version__
from ..choices import (
    CRITERION_NAMES,
    DEFAULT_ROBOT,
    DEFAULT_SIGMA_MM,
    DESIGN_METHODS,
    DISTINCT_TOLERANCE,
    ORDERS,
    PLANAR_DEMO_POSES,
    REQUIREMENTS,
    SPATIAL_DEMO_POSES,
    TASK_CRITERIA,
)
from ..choices import IDENTIFY_METHODS as METHODS
from ..errors import ArmcalError
from . import commands, options
from .help import COMMANDS, OUTPUTS_EPILOG
from .help import description as help_description
from .help import epilog as help_epilog

__all__ = ["COMMAND_TABLE", "Command", "OneOf", "Option", "build_parser", "option"]


class _Parser(argparse.ArgumentParser):
    """An ArgumentParser whose usage errors become one ``armcal: error:`` line."""

    def error(self, message: str) -> None:  # type: ignore[override]
        raise ArmcalError(f"{message} (see '{self.prog} --help')")


class _Joined(argparse.Action):
    """An option whose repeats add up: ``--fix dl1 --fix dq2`` is ``--fix dl1,dq2`` (a
    plain option keeps only the last, silently dropping what the user asked first)."""

    def __call__(
        self,
        parser: argparse.ArgumentParser,
        namespace: argparse.Namespace,
        values: Any,
        option_string: str | None = None,
    ) -> None:
        before = getattr(namespace, self.dest, None) or ()
        setattr(namespace, self.dest, tuple(dict.fromkeys((*before, *values))))


# --------------------------------------------------------------------------- the table's rows


@dataclass(frozen=True, eq=False)
class Option:
    """One option: its flags and the keywords of :meth:`argparse.ArgumentParser.add_argument`."""

    flags: tuple[str, ...]
    settings: dict[str, Any]


def option(*flags: str, **settings: Any) -> Option:
    """An :class:`Option` written as the ``add_argument`` call it stands for."""
    return Option(flags, settings)


@dataclass(frozen=True, eq=False)
class OneOf:
    """Options of which at most one is given (exactly one when ``required``)."""

    options: tuple[Option, ...]
    required: bool = False


@dataclass(frozen=True, eq=False)
class Command:
    """One sub-command: its name, what runs it, its options in their ``--help`` order, and
    the paths :func:`armcal.cli.main` checks first (option destinations)."""

    name: str
    run: Callable[[argparse.Namespace], None]
    options: tuple[Option | OneOf, ...] = ()
    inputs: tuple[str, ...] = ()
    outputs: tuple[str, ...] = ()
    folder_files: Callable[[], tuple[str, ...]] | None = None


# --------------------------------------------------------------------------- shared options

_JSON = option("--json", action="store_true", help="print a JSON document on stdout")
_SEED = option("--seed", type=options.seed, default=0, help="random seed >= 0 (default 0)")
_PLAN = option("--plan", required=True, metavar="PLAN_CSV", help="plan CSV (q1_deg..)")
_TRUTH = option("--truth", metavar="TRUTH_TOML", help="deviations (default: the built-in's)")
_SIGMA = option(
    "--sigma",
    type=options.sigma,
    metavar="MM",
    help="isotropic instrument noise in mm, replacing the robot file's (its encoder noise is "
    f"kept); default: the robot file's [measurement], else {DEFAULT_SIGMA_MM}",
)
_TEST_POSES = option(
    "--test-poses",
    metavar="PLAN_CSV",
    help="plan CSV of poses where accuracy matters (default: 1000 uniform in the limits)",
)
_FIX = option(
    "--fix",
    type=options.names,
    action=_Joined,
    metavar="P,..",
    help="parameters held at nominal, not identified (e.g. dl4,dq1; repeats add up); "
    "replaces the robot file's [identify] set",
)
#: ``--calibration`` (the file identify wrote) and ``--json``: commands that start from one.
_CALIBRATION = (
    option("--calibration", required=True, metavar="JSON", help="from identify -o"),
    _JSON,
)
_LINKS = (
    option(
        "--tip-link",
        metavar="LINK",
        help="for a robot from a URDF: the link where the arm's chain ends (default: the "
        "robot TOML's tip_link, else the URDF's one leaf)",
    ),
    option(
        "--base-link",
        metavar="LINK",
        help="for a robot from a URDF: the link where the arm's chain starts (default: the "
        "robot TOML's base_link, else the URDF's root)",
    ),
)


def _output(help_: str, **settings: Any) -> Option:
    return option("-o", "--output", metavar="PATH", help=help_, **settings)


def _trials(default: int, help_: str) -> Option:
    return option("--trials", type=options.trials, default=default, metavar="N", help=help_)


def _robot_seed_json(output: str | None = None, *, required: bool = False) -> tuple[Option, ...]:
    """--robot (with --tip-link and --base-link), --seed, --json and, given its help, -o.

    ``required``: the command calibrates a real arm's data, so it has no default
    robot (fitting a user's measurements to the paper's arm would give a wrong
    calibration without a word); commands that design, simulate or explore
    default to :data:`DEFAULT_ROBOT` and name it in their report.
    """
    robot = option(
        "--robot",
        default=None if required else DEFAULT_ROBOT,
        metavar="NAME_OR_FILE",
        help="your robot's TOML file or URDF, or a built-in name (required: the measurements "
        "are of one arm; every built-in and file under reads: above)"
        if required
        else f"a built-in's name, a robot TOML file or a URDF (default {DEFAULT_ROBOT}; every "
        "built-in and file under reads: above)",
    )
    return (robot, *_LINKS, _SEED, _JSON, *(() if output is None else (_output(output),)))


def _choice(flag: str, choices: Any, default: str, help_: str) -> Option:
    return option(flag, choices=list(choices), default=default, help=help_)


_FIGURE = "(.png, .pdf, .svg or .eps)"

# --------------------------------------------------------------------------- the table

COMMAND_TABLE: tuple[Command, ...] = (
    Command(
        "synthesize",
        commands.synthesize,
        (
            _PLAN,
            _TRUTH,
            option(
                "--sigma",
                type=options.sigma_or_zero,
                metavar="MM",
                help=f"noise std in mm (default: robot file's sigma_mm, else {DEFAULT_SIGMA_MM})",
            ),
            *_robot_seed_json("measurements CSV to write (default: stdout)"),
        ),
        inputs=("robot", "plan", "truth"),
        outputs=("output",),
    ),
    Command(
        "identify",
        commands.identify,
        (
            option("--measurements", required=True, metavar="CSV", help="measurements CSV"),
            _choice(
                "--method",
                ["auto", *METHODS],
                "auto",
                "solver; auto = closed-form, the exact least-squares optimum (default auto)",
            ),
            option(
                "--sigma",
                type=options.sigma,
                metavar="MM",
                help="isotropic instrument noise in mm, replacing the robot file's (its encoder "
                "noise is kept) and any sigma_mm column; default: the sigma_mm column, the "
                "robot file's [measurement], else estimated",
            ),
            option(
                "--robust",
                action="store_true",
                help="robust fit: Huber M-estimator from the least-squares fit, then the "
                "studentized outlier test and a refit without the outliers",
            ),
            option(
                "--cross-validate",
                type=options.folds,
                metavar="K",
                help="K-fold cross-validation: every pose predicted by a calibration without it "
                "(poses with the same pose label stay together); --seed shuffles the folds",
            ),
            option(
                "--no-compliance",
                action="store_true",
                help="fit the geometry only, even when the robot file has [elastostatic] (to see "
                "what the joints' compliance explains)",
            ),
            option(
                "--plot",
                metavar="FIGURE",
                help="draw every pose's residual (one bar per target, in the arm's 2 or 3 "
                f"dimensions) and every row's residual against each joint {_FIGURE}",
            ),
            option(
                "--report",
                metavar="HTML",
                help="write the calibration as one self-contained HTML page to hand over: the "
                "verdict, the data, what they identify, parameters, warnings and figures",
            ),
            _FIX,
            *_robot_seed_json("calibration JSON to write", required=True),
        ),
        inputs=("robot", "measurements"),
        outputs=("output", "plot", "report"),
    ),
    Command(
        "validate",
        commands.validate,
        (
            *_CALIBRATION,
            option(
                "--measurements",
                required=True,
                metavar="CSV",
                help="held-out measurements CSV (columns under reads: above)",
            ),
            option("--per-pose", action="store_true", help="a table of every pose's errors"),
            option(
                "--iso9283",
                action="store_true",
                help="an acceptance test in the spirit of ISO 9283: pose accuracy (AP, before "
                "and after calibration) and repeatability (RP) of every pose the 'pose' column "
                "repeats over cycles",
            ),
            option(
                "--plot",
                metavar="FIGURE",
                help="draw the error vectors on the workspace, or with --iso9283 every pose's AP "
                f"and RP {_FIGURE}",
            ),
            option(
                "--report",
                metavar="HTML",
                help="write the validation as one self-contained HTML page to hand over: the "
                "verdict on the held-out poses, errors before and after, warnings, figures "
                "and, with --iso9283, the acceptance test",
            ),
        ),
        inputs=("calibration", "measurements"),
        outputs=("plot", "report"),
    ),
    Command(
        "compensate",
        commands.compensate,
        (
            *_CALIBRATION,
            option(
                "--program",
                required=True,
                metavar="CSV",
                help="program CSV of joint commands (columns under reads: above)",
            ),
            option("--target", metavar="LABEL", help="the target the program is for"),
            option(
                "--payload-kg",
                type=options.not_negative,
                metavar="KG",
                help="the program's payload, for a calibration with joint compliance (default: "
                "the robot file's payload_kg; a payload_kg column gives it per row)",
            ),
            option(
                "-o", "--output", required=True, metavar="CSV", help="corrected program to write"
            ),
        ),
        inputs=("calibration", "program"),
        outputs=("output",),
    ),
    Command(
        "design",
        commands.design,
        (
            option(
                "--poses", type=options.poses, required=True, metavar="M", help="number of poses"
            ),
            _choice(
                "--criterion",
                [*CRITERION_NAMES, *TASK_CRITERIA],
                "D",
                "criterion (default D); I and G: the mean and the largest predicted position "
                "error after calibration over the test poses (--test-poses)",
            ),
            _choice(
                "--method",
                DESIGN_METHODS,
                "auto",
                "auto = analytic if it fits the constraints, else optimize + exchange",
            ),
            option(
                "--candidates",
                metavar="PLAN_CSV",
                help="reachable poses: every pose of the plan is one of them",
            ),
            option(
                "--payloads",
                type=options.payloads,
                metavar="KG,KG",
                help="payloads a pose may carry, for a robot with [elastostatic]: the design "
                "picks which poses to load and with what (default: 0 and the robot file's "
                "payload_kg)",
            ),
            _choice(
                "--order",
                ORDERS,
                "travel",
                "order of the poses in the plan file, which the robot visits in turn: travel = "
                "short joint travel (the sum of every joint's moves), none = as the method made "
                "them (default travel; the plan's quality is the same)",
            ),
            option(
                "--distinct",
                action="store_true",
                help="no pose twice (poses count as one within "
                f"{DISTINCT_TOLERANCE:g} rad on every joint): exchange takes each candidate pose "
                "once and the optimizer's repeated poses are replaced; a note says what that "
                "cost",
            ),
            option(
                "--plot",
                metavar="FIGURE",
                help=f"draw the plan's poses as stick arms {_FIGURE}",
            ),
            _SIGMA,
            _TEST_POSES,
            _FIX,
            *_robot_seed_json("plan CSV to write"),
        ),
        inputs=("robot", "candidates", "test_poses"),
        outputs=("output", "plot"),
    ),
    Command(
        "evaluate",
        commands.evaluate,
        (_PLAN, _SIGMA, _TEST_POSES, _FIX, *_robot_seed_json()),
        inputs=("robot", "plan", "test_poses"),
    ),
    Command(
        "simulate",
        commands.simulate,
        (
            _PLAN,
            _TRUTH,
            _SIGMA,
            _trials(10_000, "trials (default 10000)"),
            _choice(
                "--method",
                ["auto", *METHODS],
                "auto",
                "solver applied to every trial; auto = closed-form when every parameter is "
                "free, else gauss-newton (default auto)",
            ),
            _TEST_POSES,
            _FIX,
            *_robot_seed_json(),
        ),
        inputs=("robot", "plan", "truth", "test_poses"),
    ),
    Command(
        "poses-needed",
        commands.poses_needed,
        (
            OneOf(
                tuple(
                    option(
                        flag,
                        dest=key,
                        type=options.positive,
                        metavar="A",
                        help=REQUIREMENTS[key] + " to reach",
                    )
                    for key, flag in commands.REQUIREMENT_OPTIONS.items()
                ),
                required=True,
            ),
            _SIGMA,
            _TEST_POSES,
            option(
                "--max-poses",
                type=options.poses,
                default=5000,
                metavar="M",
                help="give up beyond (default 5000)",
            ),
            _FIX,
            *_robot_seed_json("plan CSV of the plan that reaches the target"),
        ),
        inputs=("robot", "test_poses"),
        outputs=("output",),
    ),
    Command(
        "reproduce",
        commands.reproduce_paper,
        (
            _trials(
                10_000, "Monte Carlo trials per configuration (default 10000, as in the paper)"
            ),
            option(
                "--random-plans",
                type=options.random_plans,
                default=10_000,
                metavar="N",
                help="random plans per study (default 10000, as in the paper)",
            ),
            _SEED,
            _JSON,
            option("-o", "--output", required=True, metavar="DIR", help="folder to write"),
        ),
        outputs=("output",),
        folder_files=commands.reproduce_files,
    ),
    Command(
        "check-compliance",
        commands.check_compliance,
        (_trials(4000, "Monte Carlo trials (default 4000)"), _SEED, _JSON),
    ),
    Command(
        "demo",
        commands.demo,
        (
            option(
                "--poses",
                type=options.poses,
                help=f"number of poses (default {PLANAR_DEMO_POSES}; {SPATIAL_DEMO_POSES} for a "
                "spatial arm)",
            ),
            _TRUTH,
            option("--sigma", type=options.sigma, metavar="MM", help="noise std in mm"),
            *_robot_seed_json("folder for the report, figures and files"),
        ),
        inputs=("robot", "truth"),
        outputs=("output",),
        folder_files=commands.demo_files,
    ),
    Command(
        "export",
        commands.export,
        (
            *_CALIBRATION,
            option("--robot-toml", metavar="PATH", help="robot TOML file to write"),
            option(
                "--urdf",
                metavar="PATH",
                help="URDF file to write: with --from, the user's own URDF with only its chain's "
                "joint origins calibrated",
            ),
            option(
                "--from",
                dest="original",
                metavar="URDF",
                help="the URDF the calibrated robot was described by (a spatial arm): --urdf "
                "writes it back with the calibrated joint origins, every link, mesh, inertial, "
                "limit and name kept",
            ),
            option(
                "--origins-yaml",
                metavar="PATH",
                help="with --from: the calibrated joint origins as YAML (m, rad per joint), for "
                "a xacro that takes its origins as properties (docs/six-axis.md)",
            ),
            option(
                "--joint-offsets",
                metavar="PATH",
                help="CSV of every joint's zero offset (deg) for the controller",
            ),
            option(
                "--ur-calibration",
                metavar="PATH",
                help="a Universal Robots arm's [mounting] deltas, as the controller's "
                "calibration.conf holds them (docs/controllers.md)",
            ),
            option(
                "--ros-calibration",
                metavar="PATH",
                help="a Universal Robots arm's calibration YAML for the ROS driver (kinematics: "
                "x, y, z, roll, pitch, yaw per joint; docs/controllers.md)",
            ),
        ),
        inputs=("calibration", "original"),
        outputs=(
            "robot_toml",
            "urdf",
            "origins_yaml",
            "joint_offsets",
            "ur_calibration",
            "ros_calibration",
        ),
    ),
    Command("formats", commands.formats),
)

# --------------------------------------------------------------------------- the builder

_WORKFLOW = (
    "The workflow: describe the robot (a robot TOML file, a URDF or a built-in, planar or "
    "spatial; armcal formats lists every key), design a plan "
    "(design; evaluate, simulate and poses-needed judge and size it), measure it, identify "
    "the deviations, validate them on held-out poses, then compensate programs or export the "
    "calibrated arm. 'armcal COMMAND --help' shows a command's files and an example; "
    "docs/guide.md walks through a whole calibration."
)


def build_parser() -> argparse.ArgumentParser:
    """The argument parser of the ``armcal`` program: every command of :data:`COMMAND_TABLE`."""
    parser = _Parser(
        prog="armcal",
        description=(
            "Design, run and evaluate calibration experiments for serial arms, planar and spatial."
        ),
        epilog=textwrap.fill(_WORKFLOW, 79) + "\n\n" + textwrap.fill(OUTPUTS_EPILOG, 79),
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    parser.add_argument("--version", action="version", version=f"armcal {__version__}")
    subs = parser.add_subparsers(dest="command", metavar="COMMAND", parser_class=_Parser)
    subs.required = True
    for command in COMMAND_TABLE:
        _add_command(subs, command)
    return parser


def _add_command(subs: Any, command: Command) -> None:
    """Add ``command``'s parser to ``subs``: its help from :mod:`.help`, its options in order."""
    sub: argparse.ArgumentParser = subs.add_parser(
        command.name,
        help=COMMANDS[command.name].summary,
        description=help_description(command.name),
        epilog=help_epilog(command.name),
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    for entry in command.options:
        if isinstance(entry, OneOf):
            group = sub.add_mutually_exclusive_group(required=entry.required)
            for one in entry.options:
                group.add_argument(*one.flags, **one.settings)
        else:
            sub.add_argument(*entry.flags, **entry.settings)
    paths: dict[str, Any] = {"inputs": command.inputs, "outputs": command.outputs}
    paths["folder_files"] = command.folder_files
    sub.set_defaults(run=command.run, **{key: value for key, value in paths.items() if value})
