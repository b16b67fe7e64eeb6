"""The ``armcal`` argument parser: every command, its options and its help.

Each command's ``run`` is a function of :mod:`.commands`; ``inputs`` and
``outputs`` name the options whose paths :func:`armcal.cli.main` checks before
any work, and ``folder_files`` the files a folder output will hold.
"""

from __future__ import annotations

import argparse
import textwrap
from typing import Any

from .._version import __version__
from ..criteria import CRITERIA
from ..demo import DEMO_FILES, PLANAR_DEMO_POSES
from ..demo_spatial import SPATIAL_DEMO_FILES, SPATIAL_DEMO_POSES
from ..doe import DISTINCT_TOLERANCE, ORDERS, REQUIREMENTS, TASK_CRITERIA
from ..doe import METHODS as DESIGN_METHODS
from ..errors import ArmcalError
from ..files import DEFAULT_ROBOT
from ..identification import METHODS
from ..reproduction import TABLE_COLUMNS
from ..workflow import DEFAULT_SIGMA_MM
from . import commands, options
from .help import COMMANDS, OUTPUTS_EPILOG
from .help import description as help_description
from .help import epilog as help_epilog

__all__ = ["build_parser"]


class _Parser(argparse.ArgumentParser):
    """An ArgumentParser whose usage errors become one ``armcal: error:`` line."""

    def error(self, message: str) -> None:  # type: ignore[override]
        raise ArmcalError(f"{message} (see '{self.prog} --help')")


#: Files written by ``reproduce -o DIR``, checked before any work.
_REPRODUCE_FILES = (
    *(f"{name}.csv" for name in TABLE_COLUMNS),
    "figure1.png",
    "figure2.png",
    "report.md",
)


def _add_common(
    sub: argparse.ArgumentParser,
    *,
    seed: bool = False,
    output: str | None = None,
    robot_required: bool = False,
) -> None:
    """--robot (with --tip-link and --base-link), --seed, --json and -o.

    ``robot_required``: the command calibrates a real arm's data, so it has no
    default robot (fitting a user's measurements to the paper's arm would give a
    wrong calibration without a word); commands that design, simulate or
    explore default to :data:`DEFAULT_ROBOT` and name it in their report.
    """
    sub.add_argument(
        "--robot",
        default=None if robot_required else DEFAULT_ROBOT,
        metavar="NAME_OR_FILE",
        help="your robot's TOML file, or a built-in name (required: the measurements are of "
        "one arm)"
        if robot_required
        else f"built-in robot name or robot TOML file (default {DEFAULT_ROBOT})",
    )
    sub.add_argument(
        "--tip-link",
        metavar="LINK",
        help="for a robot from a URDF: the link where the arm's chain ends (default: the "
        "robot TOML's tip_link, else the URDF's one leaf)",
    )
    sub.add_argument(
        "--base-link",
        metavar="LINK",
        help="for a robot from a URDF: the link where the arm's chain starts (default: the "
        "robot TOML's base_link, else the URDF's root)",
    )
    if seed:
        sub.add_argument(
            "--seed", type=options.seed, default=0, help="random seed >= 0 (default 0)"
        )
    sub.add_argument("--json", action="store_true", help="print a JSON document on stdout")
    if output is not None:
        sub.add_argument("-o", "--output", metavar="PATH", help=output)


def _add_calibration(sub: argparse.ArgumentParser) -> None:
    """``--calibration`` (the file identify wrote) and ``--json``: commands that start from one."""
    sub.add_argument("--calibration", required=True, metavar="JSON", help="from identify -o")
    sub.add_argument("--json", action="store_true", help="print a JSON document on stdout")


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


def _add_fix(sub: argparse.ArgumentParser) -> None:
    sub.add_argument(
        "--fix",
        type=options.names,
        action=_Joined,
        metavar="P,..",
        help="parameters held at nominal, not identified (e.g. dl4,dq1; repeats add up); "
        "replaces the robot file's [identify] set",
    )


def build_parser() -> argparse.ArgumentParser:
    """The argument parser of the ``armcal`` program."""
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

    sub = _command(subs, "synthesize")
    sub.add_argument("--plan", required=True, metavar="PLAN_CSV", help="plan CSV (q1_deg..)")
    sub.add_argument("--truth", metavar="TRUTH_TOML", help="deviations (default: the built-in's)")
    sub.add_argument(
        "--sigma",
        type=options.sigma_or_zero,
        metavar="MM",
        help=f"noise std in mm (default: robot file's sigma_mm, else {DEFAULT_SIGMA_MM})",
    )
    _add_common(sub, seed=True, output="measurements CSV to write (default: stdout)")
    sub.set_defaults(
        run=commands.synthesize, inputs=("robot", "plan", "truth"), outputs=("output",)
    )

    sub = _command(subs, "identify")
    sub.add_argument("--measurements", required=True, metavar="CSV", help="measurements CSV")
    sub.add_argument(
        "--method",
        choices=["auto", *METHODS],
        default="auto",
        help="solver; auto = closed-form, the exact least-squares optimum (default auto)",
    )
    sub.add_argument(
        "--sigma",
        type=options.sigma,
        metavar="MM",
        help="isotropic instrument noise in mm, replacing the robot file's (its encoder noise "
        "is kept) and any sigma_mm column; default: the sigma_mm column, the robot file's "
        "[measurement], else estimated",
    )
    sub.add_argument(
        "--robust",
        action="store_true",
        help="robust fit: Huber M-estimator from the least-squares fit, then the studentized "
        "outlier test and a refit without the outliers",
    )
    sub.add_argument(
        "--cross-validate",
        type=options.folds,
        metavar="K",
        help="K-fold cross-validation: every pose predicted by a calibration without it "
        "(poses with the same pose label stay together); --seed shuffles the folds",
    )
    sub.add_argument(
        "--no-compliance",
        action="store_true",
        help="fit the geometry only, even when the robot file has [elastostatic] (to see what "
        "the joints' compliance explains)",
    )
    _add_fix(sub)
    _add_common(sub, seed=True, output="calibration JSON to write", robot_required=True)
    sub.set_defaults(run=commands.identify, inputs=("robot", "measurements"), outputs=("output",))

    sub = _command(subs, "validate")
    _add_calibration(sub)
    sub.add_argument(
        "--measurements",
        required=True,
        metavar="CSV",
        help="held-out measurements CSV (columns under reads: above)",
    )
    sub.add_argument("--per-pose", action="store_true", help="a table of every pose's errors")
    sub.add_argument(
        "--iso9283",
        action="store_true",
        help="an acceptance test in the spirit of ISO 9283: pose accuracy (AP, before and "
        "after calibration) and repeatability (RP) of every pose the 'pose' column repeats "
        "over cycles",
    )
    sub.add_argument(
        "--plot",
        metavar="FIGURE",
        help="draw the error vectors on the workspace, or with --iso9283 every pose's AP and "
        "RP (.png, .pdf, .svg or .eps)",
    )
    sub.set_defaults(
        run=commands.validate, inputs=("calibration", "measurements"), outputs=("plot",)
    )

    sub = _command(subs, "compensate")
    _add_calibration(sub)
    sub.add_argument(
        "--program",
        required=True,
        metavar="CSV",
        help="program CSV of joint commands (columns under reads: above)",
    )
    sub.add_argument("--target", metavar="LABEL", help="the target the program is for")
    sub.add_argument(
        "--payload-kg",
        type=options.not_negative,
        metavar="KG",
        help="the program's payload, for a calibration with joint compliance (default: the "
        "robot file's payload_kg; a payload_kg column gives it per row)",
    )
    sub.add_argument(
        "-o", "--output", required=True, metavar="CSV", help="corrected program to write"
    )
    sub.set_defaults(
        run=commands.compensate, inputs=("calibration", "program"), outputs=("output",)
    )

    sigma_help = (
        "isotropic instrument noise in mm, replacing the robot file's (its encoder noise is "
        f"kept); default: the robot file's [measurement], else {DEFAULT_SIGMA_MM}"
    )
    test_help = "plan CSV of poses where accuracy matters (default: 1000 uniform in the limits)"
    sub = _command(subs, "design")
    sub.add_argument(
        "--poses", type=options.poses, required=True, metavar="M", help="number of poses"
    )
    sub.add_argument(
        "--criterion",
        choices=[*CRITERIA, *TASK_CRITERIA],
        default="D",
        help="criterion (default D); I and G: the mean and the largest predicted position "
        "error after calibration over the test poses (--test-poses)",
    )
    sub.add_argument(
        "--method",
        choices=list(DESIGN_METHODS),
        default="auto",
        help="auto = analytic if it fits the constraints, else optimize + exchange",
    )
    sub.add_argument(
        "--candidates",
        metavar="PLAN_CSV",
        help="reachable poses: every pose of the plan is one of them",
    )
    sub.add_argument(
        "--payloads",
        type=options.payloads,
        metavar="KG,KG",
        help="payloads a pose may carry, for a robot with [elastostatic]: the design picks "
        "which poses to load and with what (default: 0 and the robot file's payload_kg)",
    )
    sub.add_argument(
        "--order",
        choices=list(ORDERS),
        default="travel",
        help="order of the poses in the plan file, which the robot visits in turn: travel = "
        "short joint travel (the sum of every joint's moves), none = as the method made them "
        "(default travel; the plan's quality is the same)",
    )
    sub.add_argument(
        "--distinct",
        action="store_true",
        help="no pose twice (poses count as one within "
        f"{DISTINCT_TOLERANCE:g} rad on every joint): exchange takes each candidate pose once "
        "and the optimizer's repeated poses are replaced; a note says what that cost",
    )
    sub.add_argument(
        "--plot",
        metavar="FIGURE",
        help="draw the plan's poses as stick arms (.png, .pdf, .svg or .eps)",
    )
    sub.add_argument("--sigma", type=options.sigma, metavar="MM", help=sigma_help)
    sub.add_argument("--test-poses", metavar="PLAN_CSV", help=test_help)
    _add_fix(sub)
    _add_common(sub, seed=True, output="plan CSV to write")
    sub.set_defaults(
        run=commands.design,
        inputs=("robot", "candidates", "test_poses"),
        outputs=("output", "plot"),
    )

    sub = _command(subs, "evaluate")
    sub.add_argument("--plan", required=True, metavar="PLAN_CSV", help="plan CSV (q1_deg..)")
    sub.add_argument("--sigma", type=options.sigma, metavar="MM", help=sigma_help)
    sub.add_argument("--test-poses", metavar="PLAN_CSV", help=test_help)
    _add_fix(sub)
    _add_common(sub, seed=True)
    sub.set_defaults(run=commands.evaluate, inputs=("robot", "plan", "test_poses"))

    sub = _command(subs, "simulate")
    sub.add_argument("--plan", required=True, metavar="PLAN_CSV", help="plan CSV (q1_deg..)")
    sub.add_argument("--truth", metavar="TRUTH_TOML", help="deviations (default: the built-in's)")
    sub.add_argument("--sigma", type=options.sigma, metavar="MM", help=sigma_help)
    sub.add_argument(
        "--trials", type=options.trials, default=10_000, metavar="N", help="trials (default 10000)"
    )
    sub.add_argument(
        "--method",
        choices=["auto", *METHODS],
        default="auto",
        help="solver applied to every trial; auto = closed-form when every parameter is free, "
        "else gauss-newton (default auto)",
    )
    sub.add_argument("--test-poses", metavar="PLAN_CSV", help=test_help)
    _add_fix(sub)
    _add_common(sub, seed=True)
    sub.set_defaults(run=commands.simulate, inputs=("robot", "plan", "truth", "test_poses"))

    sub = _command(subs, "poses-needed")
    group = sub.add_mutually_exclusive_group(required=True)
    for key, option in commands.REQUIREMENT_OPTIONS.items():
        group.add_argument(
            option,
            dest=key,
            type=options.positive,
            metavar="A",
            help=REQUIREMENTS[key] + " to reach",
        )
    sub.add_argument("--sigma", type=options.sigma, metavar="MM", help=sigma_help)
    sub.add_argument("--test-poses", metavar="PLAN_CSV", help=test_help)
    sub.add_argument(
        "--max-poses",
        type=options.poses,
        default=5000,
        metavar="M",
        help="give up beyond (default 5000)",
    )
    _add_fix(sub)
    _add_common(sub, seed=True, output="plan CSV of the plan that reaches the target")
    sub.set_defaults(
        run=commands.poses_needed, inputs=("robot", "test_poses"), outputs=("output",)
    )

    sub = _command(subs, "reproduce")
    sub.add_argument(
        "--trials",
        type=options.trials,
        default=10_000,
        metavar="N",
        help="Monte Carlo trials per configuration (default 10000, as in the paper)",
    )
    sub.add_argument(
        "--random-plans",
        type=options.random_plans,
        default=10_000,
        metavar="N",
        help="random plans per study (default 10000, as in the paper)",
    )
    sub.add_argument("--seed", type=options.seed, default=0, help="random seed >= 0 (default 0)")
    sub.add_argument("--json", action="store_true", help="print a JSON document on stdout")
    sub.add_argument("-o", "--output", required=True, metavar="DIR", help="folder to write")
    sub.set_defaults(
        run=commands.reproduce_paper, outputs=("output",), folder_files=_REPRODUCE_FILES
    )

    sub = _command(subs, "check-compliance")
    sub.add_argument(
        "--trials",
        type=options.trials,
        default=4000,
        metavar="N",
        help="Monte Carlo trials (default 4000)",
    )
    sub.add_argument("--seed", type=options.seed, default=0, help="random seed >= 0 (default 0)")
    sub.add_argument("--json", action="store_true", help="print a JSON document on stdout")
    sub.set_defaults(run=commands.check_compliance)

    sub = _command(subs, "demo")
    sub.add_argument(
        "--poses",
        type=options.poses,
        help=f"number of poses (default {PLANAR_DEMO_POSES}; {SPATIAL_DEMO_POSES} for a "
        "spatial arm)",
    )
    sub.add_argument("--truth", metavar="TRUTH_TOML", help="deviations (default: the built-in's)")
    sub.add_argument("--sigma", type=options.sigma, metavar="MM", help="noise std in mm")
    _add_common(sub, seed=True, output="folder for the report, figures and files")
    sub.set_defaults(
        run=commands.demo,
        inputs=("robot", "truth"),
        outputs=("output",),
        folder_files=tuple(dict.fromkeys(DEMO_FILES + SPATIAL_DEMO_FILES)),
    )

    sub = _command(subs, "export")
    _add_calibration(sub)
    sub.add_argument("--robot-toml", metavar="PATH", help="robot TOML file to write")
    sub.add_argument("--urdf", metavar="PATH", help="URDF file to write")
    sub.add_argument(
        "--joint-offsets",
        metavar="PATH",
        help="CSV of every joint's zero offset (deg) for the controller",
    )
    sub.add_argument(
        "--ur-calibration",
        metavar="PATH",
        help="a Universal Robots arm's [mounting] deltas, as the controller's calibration.conf "
        "holds them (docs/controllers.md)",
    )
    sub.add_argument(
        "--ros-calibration",
        metavar="PATH",
        help="a Universal Robots arm's calibration YAML for the ROS driver (kinematics: x, y, "
        "z, roll, pitch, yaw per joint; docs/controllers.md)",
    )
    sub.set_defaults(
        run=commands.export,
        inputs=("calibration",),
        outputs=("robot_toml", "urdf", "joint_offsets", "ur_calibration", "ros_calibration"),
    )

    sub = _command(subs, "formats")
    sub.set_defaults(run=commands.formats)
    return parser


_WORKFLOW = (
    "The workflow: write a robot file (armcal formats lists every key), design a plan "
    "(design; evaluate, simulate and poses-needed judge and size it), measure it, identify "
    "the deviations, validate them on held-out poses, then compensate programs or export the "
    "calibrated arm. 'armcal COMMAND --help' shows a command's files and an example; "
    "docs/guide.md walks through a whole calibration."
)


def _command(subs: Any, name: str) -> argparse.ArgumentParser:
    """The parser of command ``name``, with its help from :mod:`.help`."""
    parser: argparse.ArgumentParser = subs.add_parser(
        name,
        help=COMMANDS[name].summary,
        description=help_description(name),
        epilog=help_epilog(name),
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    return parser
