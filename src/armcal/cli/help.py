"""What each ``armcal`` command's ``--help`` says: what it does, examples, the files it reads.

The words live here, apart from the parser in :mod:`armcal.cli`, so that every
command is described the same way: a one-line summary for ``armcal --help``;
a paragraph; examples, one of them for a six-axis arm where the command takes
a robot; and the layout of every file it reads, taken from :mod:`armcal.formats`
and :mod:`armcal.files` so that help and reader cannot disagree. The outputs
paragraph is said once, in ``armcal --help``; a command that writes files points
to it in one line.
"""

from __future__ import annotations

import textwrap
from dataclasses import dataclass

from ..choices import BUILTIN_ROBOTS, BUILTIN_SPATIAL_ROBOTS
from ..formats import columns_line

__all__ = ["COMMANDS", "OUTPUTS_EPILOG", "OUTPUTS_POINTER", "CommandHelp", "description", "epilog"]

OUTPUTS_EPILOG = (
    "Outputs: every output path is checked before any work. A file is written to a "
    "temporary file and renamed into place, so a failed or interrupted run leaves no "
    "half-written file; an output folder appears only once all its files are complete. An "
    "existing output file is replaced (reruns are the rule in scripts), keeping its "
    "permissions; a symbolic link is written through, the link kept. An output that is an "
    "input of the same command, a directory where a file is expected, or a special file "
    "(FIFO, device, socket) is refused. '-' as an output file writes it to stdout instead "
    "of the report; '-' as an input file reads stdin. Exit status: 0 done, 2 bad input "
    "(one 'armcal: error:' line), 130 interrupted, 1 a bug."
)
#: The line a command that writes files has where :data:`OUTPUTS_EPILOG` would be.
OUTPUTS_POINTER = "Outputs, '-' for stdin/stdout and exit status: see 'armcal --help'."

_ROBOT = (
    f"robot (--robot): a built-in name, planar: {', '.join(BUILTIN_ROBOTS)}; spatial: "
    f"{', '.join(BUILTIN_SPATIAL_ROBOTS)}; or a file: a planar robot TOML (link_lengths_mm, "
    "joint_limits_deg, [measurement] sigma_mm, ...), a URDF (the chain from --base-link to "
    '--tip-link), or a robot TOML over a URDF (urdf = "arm.urdf") or with an MDH, DH or UR '
    "table ([mdh], [dh], [ur]); every key: armcal formats"
)
_TRUTH = (
    "truth TOML: planar: dl_mm = [...], dq_deg = [...] (base_mm, k_urad_per_Nm, c_mdeg_per_m); "
    "spatial: robot (the true arm's file), base = { xyz_mm, rpy_deg }, [errors] (j2.x, dq3, "
    "...), [targets], [compliance]"
)
_CALIBRATION = (
    "calibration JSON: written by armcal identify -o (format armcal-calibration/1), of a "
    "planar or a spatial arm"
)


def _csv(kind: str) -> str:
    return f"{kind} CSV: {columns_line(kind)}"


@dataclass(frozen=True)
class CommandHelp:
    """The help of one command.

    Attributes
    ----------
    summary : str
        One line for ``armcal --help``.
    text : str
        One paragraph: what the command does and prints.
    examples : tuple of str
        Command lines.
    reads : tuple of str
        The files it reads, one line each.
    writes : bool
        Whether it writes files (the outputs paragraph of ``armcal --help`` applies).
    """

    summary: str
    text: str
    examples: tuple[str, ...]
    reads: tuple[str, ...] = ()
    writes: bool = True


COMMANDS: dict[str, CommandHelp] = {
    "synthesize": CommandHelp(
        "measurements of a virtual robot (truth + noise)",
        "Make the measurements a real instrument would give on a virtual robot: the positions "
        "of the robot with the truth's deviations at every pose of the plan, plus Gaussian "
        "noise of --sigma (0 for noiseless data). Use it to rehearse an experiment, test a "
        "pipeline, or stand in for the instrument in examples. A robot with [targets] gets one "
        "row per pose and target; one with [elastostatic] deflects under the plan's payload_kg.",
        (
            "armcal synthesize --plan plan.csv --sigma 0.02 -o meas.csv",
            "armcal synthesize --robot my-arm.toml --truth truth.toml --plan plan.csv -o meas.csv",
            "armcal synthesize --robot industrial-6r --plan plan6.csv --sigma 0.02 -o meas6.csv",
        ),
        (_ROBOT, _csv("plan"), _TRUTH),
    ),
    "identify": CommandHelp(
        "parameter deviations ± std from measurements",
        "Identify the arm's deviations from nominal (a planar arm: dl1..dln in mm, dq1..dqn in "
        "deg, the base pose with base_offset, the targets' offsets; a spatial arm: every "
        "joint's placement and zero (j2.x, dq3, ...), the base pose and the targets' positions, "
        "reduced to the set the data can identify, the report saying which merge and why; the "
        "joint compliance with [elastostatic]) by least squares, with the standard error of "
        "every parameter, the goodness of fit against the instrument noise, studentized "
        "outliers and warnings for what the data cannot support. 3-D data (a z_mm column) of a "
        "planar arm are fitted in its plane of motion. -o writes the calibration JSON that "
        "validate, compensate and export read.",
        (
            "armcal identify --robot my-arm.toml --measurements meas.csv -o cal.json",
            "armcal identify --measurements meas.csv --robust --cross-validate 5",
            "armcal identify --robot industrial-6r --measurements meas6.csv -o cal6.json",
        ),
        (_ROBOT, _csv("measurements")),
    ),
    "validate": CommandHelp(
        "positioning error before and after calibration on held-out poses",
        "Compare held-out measurements (poses not used to calibrate) with the nominal arm and "
        "with the calibrated one, both at the calibrated base pose, and with the error the "
        "calibration predicts (its uncertainty plus the instrument noise). 3-D data of a planar "
        "arm are projected into the calibration's plane.",
        (
            "armcal validate --calibration cal.json --measurements test.csv --per-pose "
            "--plot errors.png",
        ),
        (_CALIBRATION, _csv("measurements")),
    ),
    "compensate": CommandHelp(
        "corrected joint commands of a robot program",
        "Correct a program's joint commands so that the calibrated arm puts the tool where the "
        "nominal program meant, in the robot's own frame (the instrument's pose is never "
        "corrected); where the arm has the joints (3 in the plane, 6 in space) the tool's "
        "orientation too, the remaining redundancy going to the smallest joint change. Commands "
        "that cannot be corrected within the joint limits are kept and listed, never clipped.",
        ("armcal compensate --calibration cal.json --program prog.csv -o corrected.csv",),
        (_CALIBRATION, _csv("program")),
    ),
    "design": CommandHelp(
        "an optimal plan within the limits and region",
        "Choose M poses that make the identification as precise as possible by a criterion "
        "(D: the volume of the confidence ellipsoid; A: the mean variance; E: the worst "
        "direction), within the joint limits and the instrument's "
        "region: the paper's analytic orthogonal plans where they fit, else optimization and "
        "exchange, with a certificate of how close to the optimum the plan is. Prints the "
        "plan's quality; -o writes the plan, ordered for short joint travel.",
        (
            "armcal design --robot my-arm.toml --poses 20 -o plan.csv --plot plan.png",
            "armcal design --poses 30 --criterion A --candidates reachable.csv -o plan.csv",
            "armcal design --robot industrial-6r --poses 30 -o plan6.csv",
            "armcal design --robot ur5.urdf --tip-link tool0 --poses 30 -o plan-ur5.csv",
        ),
        (_ROBOT, _csv("plan") + " (--candidates, --test-poses)"),
    ),
    "evaluate": CommandHelp(
        "quality of a plan: criteria, predicted std",
        "Judge any plan before measuring it: its D-efficiency and criteria, the predicted std "
        "of every parameter at the instrument noise, and the predicted positioning error after "
        "calibration over the test poses. Compare a hand-made plan with a designed one.",
        (
            "armcal evaluate --robot my-arm.toml --plan plan.csv --sigma 0.05",
            "armcal evaluate --robot industrial-6r --plan plan6.csv",
        ),
        (_ROBOT, _csv("plan") + " (--plan, --test-poses)"),
        writes=False,
    ),
    "simulate": CommandHelp(
        "Monte Carlo: empirical vs predicted std and bias",
        "Repeat the experiment of a plan on a virtual robot --trials times with fresh noise "
        "and identify each (batched), then compare the empirical std and bias of every "
        "parameter with the predicted std: a check that the uncertainty armcal reports is "
        "right for this plan, solver and noise.",
        (
            "armcal simulate --plan plan.csv --trials 2000 --sigma 0.02",
            "armcal simulate --robot industrial-6r --plan plan6.csv --trials 500",
        ),
        (_ROBOT, _csv("plan") + " (--plan, --test-poses)", _TRUTH),
        writes=False,
    ),
    "poses-needed": CommandHelp(
        "the smallest m whose best plan reaches a target",
        "Size the experiment: the smallest number of poses whose optimal plan reaches a target "
        "std of the lengths, of the angles, or a target positioning error after calibration, "
        "at the instrument noise. -o writes that plan.",
        (
            "armcal poses-needed --robot my-arm.toml --position-rms-mm 0.05 -o plan.csv",
            "armcal poses-needed --robot industrial-6r --position-rms-mm 0.1",
        ),
        (_ROBOT, _csv("plan") + " (--test-poses)"),
    ),
    "reproduce": CommandHelp(
        "the paper's Tables I-III and Figures 1-2, recomputed",
        "Recompute the source paper's tables and figures (Design of Experiments for "
        "Calibration of Planar Anthropomorphic Manipulators) from first principles, with a "
        "report that explains every disagreement with the printed numbers.",
        ("armcal reproduce -o paper-out --trials 2000",),
    ),
    "check-compliance": CommandHelp(
        "self-check of elastostatic calibration on a virtual vertical arm",
        "Calibrate a virtual vertical 3-link arm whose joints twist under the weight of its "
        "links and a 10 kg payload (sigma 0.02 mm, 40 poses): the geometry-only fit and its "
        "warning, the fit with joint compliance against the truth, held-out validation, a "
        "Monte Carlo of the predicted std, and a certified design of poses and payloads.",
        ("armcal check-compliance --trials 4000",),
        writes=False,
    ),
    "demo": CommandHelp(
        "the whole workflow on a virtual robot",
        "Design a certified plan, measure a virtual arm with noise and one bumped measurement, "
        "identify robustly, validate on fresh poses, compensate a program and export the "
        "calibrated arm, then write report.md with its figures into the folder. A spatial arm "
        "tells a cell's story instead: a laser tracker in an unknown pose, three reflectors "
        "found from the data, a random plan within the limits.",
        (
            "armcal demo -o demo-out",
            "armcal demo --robot my-arm.toml --truth truth.toml -o out",
            "armcal demo --robot industrial-6r -o demo-6r",
        ),
        (_ROBOT, _TRUTH),
    ),
    "export": CommandHelp(
        "the calibrated arm as a robot file every command accepts, or as URDF",
        "Write the arm of a calibration file with its deviations folded into the nominal "
        "values, in the robot's own frame: as a robot TOML file that every armcal command "
        "accepts (a planar arm: link lengths l + dl, joint_offsets_deg, targets' lengths and "
        "angles; a spatial arm: the calibrated chain as a modified DH table), as a URDF for ROS "
        "(each joint's zero folded into its origin, lengths in m), as every joint's zero "
        "offset for the controller, or as a Universal Robots arm's calibration. The base pose "
        "in the instrument frame is the instrument's and appears only as a comment. Give one "
        "or more of the outputs below.",
        (
            "armcal export --calibration cal.json --robot-toml my-arm-cal.toml --urdf my-arm.urdf",
            "armcal export --calibration cal6.json --urdf cal6.urdf --robot-toml cal6.toml",
        ),
        (_CALIBRATION,),
    ),
    "formats": CommandHelp(
        "every file armcal reads: keys and columns with unit and default",
        "Print every key of the robot and truth TOML files and every column of the plan, "
        "measurement and program CSV files, with its unit, its default and what it sets, and "
        "the CSV conventions armcal accepts.",
        ("armcal formats",),
        writes=False,
    ),
}


def description(command: str) -> str:
    """The ``--help`` text above the options: the paragraph and the files read."""
    help_ = COMMANDS[command]
    text = textwrap.fill(help_.text, 79)
    if help_.reads:
        text += "\n\nreads:\n" + "\n".join(
            # a hyphenated name (a built-in's, the calibration format's) stays on one line
            textwrap.fill(
                line, 79, initial_indent="  ", subsequent_indent="    ", break_on_hyphens=False
            )
            for line in help_.reads
        )
    return text


def epilog(command: str) -> str:
    """The ``--help`` text below the options: the examples, and where the outputs are told."""
    help_ = COMMANDS[command]
    text = "example" + ("s" if len(help_.examples) > 1 else "") + ":\n"
    text += "\n".join(f"  {line}" for line in help_.examples)
    if help_.writes:
        text += "\n\n" + OUTPUTS_POINTER
    return text
