"""The ``armcal`` commands: read the files, call the library, write the files, print.

Every command is thin: what it does beyond parsing arguments and writing files
is a library call of :mod:`armcal.workflow`, and its output is a report of
:mod:`armcal.report`.  Options that name a flag in an error keep the flag's
name here.

Each command imports the library it runs in its own body, when it runs, after the
robot file (or the calibration) it starts from has loaded: the parser imports this
module, so that ``armcal --help`` imports none of the library, ``armcal design``
imports the design and its report, not the identification's, and a robot file that
cannot be read is refused before the rest is imported (a lazy import of a slow
dependency, the only kind this module has).
"""

from __future__ import annotations

import argparse
import math
import sys
from collections.abc import Callable
from dataclasses import replace
from functools import partial
from pathlib import Path
from typing import TYPE_CHECKING, Any

from ..choices import BUILTIN_ROBOTS, BUILTIN_SPATIAL_ROBOTS
from ..errors import ArmcalError
from ..files import STDIO, atomic_write, load_robot, write_folder, write_json
from ..formats import format_reference
from ..progress import ProgressBar
from .output import CLI_ACTIONS, emit, print_warnings, warning_dicts

if TYPE_CHECKING:  # annotations only: the help imports no numpy
    import numpy as np

    from ..files import RobotSpec
    from ..models import FitModel

__all__ = [
    "REQUIREMENT_OPTIONS",
    "check_compliance",
    "compensate",
    "demo",
    "demo_files",
    "design",
    "evaluate",
    "export",
    "formats",
    "identify",
    "poses_needed",
    "reproduce_files",
    "reproduce_paper",
    "simulate",
    "synthesize",
    "validate",
]

#: The option of every accuracy requirement of poses-needed.
REQUIREMENT_OPTIONS = {
    "length_std_mm": "--length-std-mm",
    "angle_std_deg": "--angle-std-deg",
    "position_rms_mm": "--position-rms-mm",
}


def _robot(args: argparse.Namespace) -> RobotSpec:
    """``--robot``, its URDF's chain from ``--base-link`` to ``--tip-link`` where given.

    What reading it warns of is kept on ``args.loaded_warnings`` too: a later error stops
    the command before its report prints them, and the program prints them then."""
    spec = load_robot(args.robot, base_link=args.base_link, tip_link=args.tip_link)
    args.loaded_warnings = tuple(spec.warnings)
    return spec


def _model(args: argparse.Namespace, spec: RobotSpec) -> tuple[RobotSpec, FitModel]:
    """The robot file and its arm with ``--fix`` (replacing the file's set, the arm's and
    the compliance's) and ``--sigma`` applied."""
    from ..workflow import model_spec  # when a command runs (module docstring)

    fixed = getattr(args, "fix", None)
    return model_spec(spec, spec.arm, fixed=fixed, sigma=getattr(args, "sigma", None))


#: What simulate and synthesize say when a robot file without a default truth is given no
#: ``--truth``: they study the nominal arm (zero deviations, no compliance).
NOMINAL_TRUTH = "truth: nominal (no --truth)"


def _truth(
    args: argparse.Namespace,
    spec: RobotSpec,
    model: FitModel,
    *,
    nominal: bool = False,
    geometry_only: bool = False,
) -> tuple[np.ndarray, str | None]:
    """The parameters of the virtual robot ``model`` (a plan's, with the plan's loads):
    ``--truth``, with compliance for a model of joint compliance, else the built-in's.

    A robot file without ``--truth`` is refused, or with ``nominal`` studied as its nominal
    arm (:data:`NOMINAL_TRUTH`, returned as the note to print): zero errors and no
    compliance, the values the model holds its fixed parameters at, for every family.
    ``geometry_only`` (the demo's rigid arm) leaves a truth's compliance out.
    """
    default = spec.default_truth
    if args.truth is None and default is None:
        if nominal:
            return model.held_values, NOMINAL_TRUTH
        raise ArmcalError(
            f"{spec.source}: a robot file has no default truth; pass --truth truth.toml "
            "(armcal formats lists its keys)"
        )
    links = (getattr(args, "base_link", None), getattr(args, "tip_link", None))
    found: np.ndarray = spec.family.role("truth")(
        spec, model, args.truth, links=links, geometry_only=geometry_only
    )
    return found, None


def _truth_source(args: argparse.Namespace, note: str | None) -> str:
    """Where the truth came from, for the JSON: ``given`` (--truth), ``built-in`` or
    ``nominal`` (:data:`NOMINAL_TRUTH`)."""
    if note is not None:
        return "nominal"
    return "given" if args.truth is not None else "built-in"


def _plan(path: str, spec: RobotSpec) -> tuple[np.ndarray, np.ndarray | None]:
    """A plan file's poses (rad) and, for a robot with [elastostatic], its payload column."""
    q, payload, _ = _labelled_plan(path, spec)
    return q, payload


def _labelled_plan(
    path: str, spec: RobotSpec
) -> tuple[np.ndarray, np.ndarray | None, tuple[str, ...] | None]:
    """:func:`_plan` and the plan's ``pose`` labels (None without the column)."""
    from ..files import read_labelled_plan, read_loaded_plan  # when a command runs

    if spec.elastic is None:
        q, labels = read_labelled_plan(path, spec.arm)
        return q, None, labels
    return read_loaded_plan(path, spec.arm)


def _test_poses(args: argparse.Namespace, spec: RobotSpec, *, loaded: bool = False) -> np.ndarray:
    """``--test-poses``, else 1000 uniform poses within the limits
    (:func:`armcal.workflow.test_poses`)."""
    from ..workflow import test_poses  # when a command runs (module docstring)

    return test_poses(spec, args.seed, args.test_poses, loaded=loaded)


def _written(*paths: str | None) -> list[str]:
    return [f"wrote {path}" for path in paths if path is not None]


def reproduce_files() -> tuple[str, ...]:
    """The files ``reproduce -o DIR`` writes, checked before any work."""
    from ..reproduction import TABLE_COLUMNS  # when the command runs (module docstring)

    return (*(f"{name}.csv" for name in TABLE_COLUMNS), "figure1.png", "figure2.png", "report.md")


def demo_files() -> tuple[str, ...]:
    """The files ``demo -o DIR`` may write, either family's, checked before any work."""
    from ..demo import DEMO_FILES  # when the command runs (module docstring)
    from ..demo_spatial import SPATIAL_DEMO_FILES

    return tuple(dict.fromkeys(DEMO_FILES + SPATIAL_DEMO_FILES))


# --------------------------------------------------------------------------- commands


def synthesize(args: argparse.Namespace) -> None:
    """``armcal synthesize``: measurements of a virtual robot."""
    if args.json and args.output in (None, STDIO):
        raise ArmcalError(
            "synthesize --json: without -o the measurements (a CSV table) are the output on "
            "stdout; give -o meas.csv, and --json prints the summary as JSON"
        )
    if args.output is not None and args.output.lower().endswith(".json"):
        raise ArmcalError(
            f"-o {args.output}: synthesize writes measurements as a CSV table (--json changes "
            "only the summary on stdout); give a name ending in .csv"
        )
    spec = _robot(args)
    from ..files import format_measurements_csv  # the library it runs (module docstring)
    from ..workflow import plan_model, simulation_sigma, synthesize_plan

    q, payload, labels = _labelled_plan(args.plan, spec)
    model, loads = plan_model(spec, spec.arm, q.shape[0], payload, virtual=True)
    truth, note = _truth(args, spec, model, nominal=True)
    made = synthesize_plan(
        model,
        q,
        truth,
        sigma=simulation_sigma(spec, args.sigma),
        seed=args.seed,
        loads=loads,
        pose_labels=labels,
    )
    text = format_measurements_csv(
        made.q,
        made.points,
        made.labels,
        made.targets,
        made.payload_kg,
        kinds=spec.arm.joint_kinds,
        instrument=getattr(spec.arm, "instrument", None),
        feature=made.feature,
    )
    if args.output is None or args.output == STDIO:
        print_warnings([*spec.warnings, *made.warnings])
        args.loaded_warnings = ()  # printed
        if note is not None:  # stdout holds the measurements: the note goes beside the warnings
            print(f"armcal: {note}", file=sys.stderr)
        sys.stdout.write(text)
        return
    atomic_write(args.output, text)
    what = f" with {made.effect}" if made.effect else ""
    document = {
        "poses": int(made.q.shape[0]),
        "sigma_mm": made.sigma_mm,
        "truth_source": _truth_source(args, note),
        "output": args.output,
    }
    noise = spec.arm.noise
    tracker = args.sigma is None and noise is not None and noise.tracker is not None
    turn_sigma = None if noise is None else noise.orientation_sigma
    turn = ""
    # a 6-DoF instrument, or partial coordinates that read the tool's turn
    if (made.points.shape[1] == 6 or spec.arm.reads_turns) and turn_sigma is not None:
        turn_sigma = 0.0 if args.sigma == 0 else turn_sigma  # --sigma 0: no noise at all
        turn = f", orientation {math.degrees(turn_sigma):g} deg"
    emit(
        args,
        document,
        f"wrote {made.q.shape[0]} measurements of {spec.arm.name}{what} ("
        f"{'laser tracker noise, reference sigma' if tracker else 'sigma'} "
        f"{made.sigma_mm:g} {spec.arm.reading_unit}{turn}, seed {args.seed}) to {args.output}"
        + ("" if note is None else f"\n{note}"),
        [*spec.warnings, *made.warnings],
    )


def _options(args: argparse.Namespace) -> dict[str, Any]:
    """The calibration options of ``identify``, the same for every family of arm."""
    return {
        "source": args.measurements,
        "fixed": args.fix,
        "sigma": args.sigma,
        "method": args.method,
        "robust": args.robust,
        "folds": args.cross_validate,
        "seed": args.seed,
        "progress": None if args.cross_validate is None else ProgressBar("cross-validation"),
    }


def identify(args: argparse.Namespace) -> None:
    """``armcal identify``: the calibration of a measurement file."""
    if args.robot is None:
        builtins = ", ".join([*BUILTIN_ROBOTS, *BUILTIN_SPATIAL_ROBOTS])
        raise ArmcalError(
            "identify needs --robot: the measurements are of one arm, and a fit to another "
            "arm's model is a wrong calibration; give your robot file (armcal formats lists "
            f"its keys) or a built-in name ({builtins})"
        )
    spec = _robot(args)
    from ..files import calibration_document, read_measurements  # the library it runs
    from ..models.wording import held_sentence
    from ..report import format_calibration, format_cross_validation
    from ..workflow import calibrate

    meas = read_measurements(args.measurements, spec.arm)
    run = calibrate(spec, meas, compliance=not args.no_compliance, **_options(args))
    cal = run.calibration
    text = format_calibration(cal, words=CLI_ACTIONS)
    document = calibration_document(cal, warnings=run.warnings, words=CLI_ACTIONS)
    if run.cross_validation is not None:
        summary = run.cross_validation.summary()
        folds = run.cross_validation.per_fold()
        unit = run.cross_validation.unit  # a camera's pixels, under the same keys
        document["cross_validation"] = {
            **summary,
            "per_fold": folds,
            **({} if unit == "mm" else {"reading_unit": unit}),
        }
        text += "\n" + format_cross_validation(summary, folds, unit)
    if args.output is not None:
        atomic_write(args.output, partial(write_json, document))
    if args.plot is not None or args.report is not None:
        from ..plotting import figure_png, save_figure  # matplotlib only when asked for

        figure = spec.family.role("residual_figure")(cal)
        if args.plot is not None:
            save_figure(figure, args.plot)
        if args.report is not None:
            from ..report.html import calibration_html

            page = calibration_html(
                {**document, "warnings": warning_dicts(run.warnings)},
                text,
                {"Every pose's residual, and every row's against each joint": figure_png(figure)},
                source=args.measurements,
                held=[held_sentence(held) for held in cal.model.held_reasons],
            )
            atomic_write(args.report, page)
    emit(args, document, text, run.warnings)


def validate(args: argparse.Namespace) -> None:
    """``armcal validate``: a calibration against held-out measurements."""
    from ..files import read_calibration  # first, as the robot (module docstring)

    cal = read_calibration(args.calibration)
    from ..files import read_measurements  # the library it runs (module docstring)
    from ..report import acceptance_report, validation_report
    from ..workflow import validate_measurements

    meas = read_measurements(
        args.measurements, cal.arm, arm_from=f"the calibration {args.calibration}"
    )
    run = validate_measurements(
        cal,
        meas,
        source=args.measurements,
        iso9283=args.iso9283,
        progress=ProgressBar("validate"),
    )
    figures = {}
    if args.plot is not None or args.report is not None:
        from ..plotting import figure_png, plot_validation, save_figure  # only when asked for

        kept = run.validation.kept  # the rows of its position errors (a turn's apart)
        rows = list(range(len(meas.labels))) if kept is None else kept.tolist()
        several = meas.targets is not None or meas.feature is not None  # a pose's rows
        pose = [meas.labels[i] for i in rows] if several else None  # share its label
        figures["Errors before and after calibration"] = plot_validation(
            cal.arm, meas.q[rows], run.validation, pose=pose
        )
        if run.acceptance is not None:
            from ..plotting_acceptance import plot_acceptance

            figures["ISO 9283 pose accuracy and repeatability"] = plot_acceptance(run.acceptance)
        if args.plot is not None:
            save_figure(list(figures.values())[-1], args.plot)
    document, text = validation_report(cal, run.validation, meas, per_pose=args.per_pose)
    if run.acceptance is not None:
        document["iso9283"], lines = acceptance_report(run.acceptance)
        text += "\n" + "\n".join(lines)
    if args.report is not None:
        from ..report.html import validation_html

        page = validation_html(
            {**document, "warnings": warning_dicts(run.warnings)},
            text,
            {caption: figure_png(figure) for caption, figure in figures.items()},
            source=args.measurements,
            calibration=args.calibration,
        )
        atomic_write(args.report, page)
    if args.plot is not None:
        text += f"\nwrote {args.plot}"
    emit(args, document, text, run.warnings)


def compensate(args: argparse.Namespace) -> None:
    """``armcal compensate``: a program's corrected commands."""
    from ..files import read_calibration  # first, as the robot (module docstring)

    cal = read_calibration(args.calibration)
    from ..files import format_program_csv, read_program  # the library it runs
    from ..report import compensation_report
    from ..workflow import compensate_program

    program = read_program(args.program, cal.arm, arm_from=f"the calibration {args.calibration}")
    run = compensate_program(
        cal, program, target=args.target, payload_kg=args.payload_kg, source=args.program
    )
    result = run.compensation
    atomic_write(
        args.output,
        format_program_csv(
            result.q,
            result.corrected,
            program.labels,
            run.targets,
            kinds=cal.arm.joint_kinds,
            payload_kg=program.payload_kg,
            force_n=program.force_n,
        ),
    )
    payload = run.payload
    if payload is not None and args.payload_kg is not None:  # the library names its argument
        payload = replace(payload, source="--payload-kg")
    document, text = compensation_report(cal, result, program, payload)
    text += f"\nwrote {args.output}"
    emit(args, document, text, run.warnings)


def design(args: argparse.Namespace) -> None:
    """``armcal design``: an optimal plan, its quality and its picture."""
    spec = _robot(args)
    from ..files import format_plan_csv  # the library it runs (module docstring)
    from ..report import design_summary, quality_report
    from ..workflow import design_plan

    spec, arm = _model(args, spec)
    if args.plot is not None:  # a family without the figure says so before the work
        spec.family.role("plan_figure")
    # with [elastostatic] a candidates file may carry payload_kg: read it, so that the
    # refusal the user sees is design_plan's (candidates with loads), not a column's
    candidates = None if args.candidates is None else _plan(args.candidates, spec)[0]
    run = design_plan(
        spec,
        arm,
        args.poses,
        criterion=args.criterion,
        method=args.method,
        seed=args.seed,
        candidates=candidates,
        candidates_source=args.candidates,
        order=args.order,
        distinct=args.distinct,
        payloads=args.payloads,
        test_q=_test_poses(args, spec),
        progress=ProgressBar("design"),
    )
    document, report = quality_report(run.quality, words=CLI_ACTIONS)
    extra, header = design_summary(run.design, run.seconds, words=CLI_ACTIONS)
    document.update(extra)
    if args.plot is not None:  # first: drawing is what can fail, the plan CSV is text
        from ..plotting import save_figure  # matplotlib only when a plot is asked for

        figure = spec.family.role("plan_figure")(spec, run, seed=args.seed)
        save_figure(figure, args.plot)
    if args.output is not None:
        plan = format_plan_csv(run.q, run.payload_kg, kinds=spec.arm.joint_kinds)
        atomic_write(args.output, plan)
    written = _written(args.output, args.plot)
    text = "\n".join([*header, report, *([""] if written else []), *written])
    emit(args, document, text, run.warnings)


def evaluate(args: argparse.Namespace) -> None:
    """``armcal evaluate``: a plan's quality."""
    spec = _robot(args)
    from ..report import quality_report  # the library it runs (module docstring)
    from ..workflow import evaluate_file

    spec, arm = _model(args, spec)
    q, payload = _plan(args.plan, spec)
    run = evaluate_file(
        spec, arm, q, test_q=_test_poses(args, spec), payload=payload, source=args.plan
    )
    emit(args, *quality_report(run.quality, words=CLI_ACTIONS), run.warnings)


def simulate(args: argparse.Namespace) -> None:
    """``armcal simulate``: a Monte Carlo of a plan."""
    spec = _robot(args)
    from ..report import format_monte_carlo, monte_carlo_to_dict  # the library it runs
    from ..workflow import plan_model, simulate_plan

    spec, arm = _model(args, spec)
    q, payload = _plan(args.plan, spec)
    model, loads = plan_model(spec, arm, q.shape[0], payload)
    truth, note = _truth(args, spec, model, nominal=True)
    result = simulate_plan(
        model,
        q,
        truth,
        trials=args.trials,
        method=args.method,
        seed=args.seed,
        test_q=_test_poses(args, spec),
        loads=loads,
        progress=ProgressBar("simulate"),
        source=args.plan,
    )
    document = monte_carlo_to_dict(result)
    document["truth_source"] = _truth_source(args, note)
    text = format_monte_carlo(result, words=CLI_ACTIONS)
    if note is not None:  # under the heading line
        head, _, rest = text.partition("\n")
        text = f"{head}\n{note}\n{rest}"
    emit(args, document, text, [*spec.warnings, *result.warnings])


def poses_needed(args: argparse.Namespace) -> None:
    """``armcal poses-needed``: the smallest plan that reaches an accuracy."""
    spec = _robot(args)
    from ..files import format_plan_csv  # the library it runs (module docstring)
    from ..report import poses_needed_summary
    from ..workflow import size_plan

    arm = _model(args, spec)[1] if spec.elastic is None else spec.arm
    requirement = next(key for key in REQUIREMENT_OPTIONS if getattr(args, key) is not None)
    positions = requirement == "position_rms_mm"  # test poses with the robot's payload
    found, seconds = size_plan(
        spec,
        arm,
        requirement,
        getattr(args, requirement),
        seed=args.seed,
        test_q=_test_poses(args, spec, loaded=positions),
        max_poses=args.max_poses,
        progress=ProgressBar("poses-needed"),
    )
    document, lines = poses_needed_summary(found, found.model or arm, seconds, words=CLI_ACTIONS)
    if args.output is not None:
        plan = format_plan_csv(found.plan, found.payload_kg, kinds=spec.arm.joint_kinds)
        atomic_write(args.output, plan)
        lines.append(f"wrote {args.output}")
    emit(args, document, "\n".join(lines), spec.warnings)


def reproduce_paper(args: argparse.Namespace) -> None:
    """``armcal reproduce``: the paper's tables and figures, recomputed."""
    from ..plotting import plot_accuracy_curves, plot_random_plans, save_figure
    from ..report import format_reproduction, reproduction_summary, table_csv
    from ..reproduction import TABLE_COLUMNS, reproduce

    result = reproduce(
        trials=args.trials,
        random_plans=args.random_plans,
        seed=args.seed,
        progress=ProgressBar("reproduce"),
    )
    study = result.figure1
    title = f"paper-4link, sigma {result.sigma_mm:g} mm: accuracy against the number of poses"
    tables = result.tables
    figure1 = plot_random_plans(study.det_d, study.det_c, study.abs_det_s, poses=study.n_poses)
    figure2 = plot_accuracy_curves(result.figure2, title=title)
    outputs: dict[str, str | Callable[[Path], None]] = {
        **{f"{name}.csv": table_csv(tables[name], cols) for name, cols in TABLE_COLUMNS.items()},
        "figure1.png": partial(save_figure, figure1),
        "figure2.png": partial(save_figure, figure2),
        "report.md": format_reproduction(result),
    }
    folder = write_folder(args.output, outputs)
    document, lines = reproduction_summary(result)
    document["files"] = [str(folder / name) for name in outputs]
    lines.append(f"wrote {', '.join(outputs)} to {folder}/")
    emit(args, document, "\n".join(lines))


def check_compliance(args: argparse.Namespace) -> None:
    """``armcal check-compliance``: the elastostatic self-check."""
    from ..compliance_check import check_compliance as run_check
    from ..compliance_check import format_check

    result = run_check(seed=args.seed, trials=args.trials)
    emit(args, result.to_dict(), format_check(result), result.monte_carlo.warnings)


def demo(args: argparse.Namespace) -> None:
    """``armcal demo``: the whole workflow on a built-in robot."""
    spec = _robot(args)
    from ..demo import demo_rigid_warning  # the library it runs (module docstring)

    result, kinds = spec.family.role("demo")(
        spec,
        lambda arm: _truth(args, spec, arm, geometry_only=True)[0],
        poses=args.poses,
        sigma=args.sigma,
        seed=args.seed,
        words=CLI_ACTIONS,
        progress=ProgressBar("demo"),
    )
    lines = [result.text]
    if args.output is not None:
        folder = write_folder(args.output, result.files)
        lines += ["", f"wrote {len(result.files)} files to {folder}/: {kinds}"]
    rigid = () if spec.elastic is None else (demo_rigid_warning(spec.arm.name),)
    emit(args, dict(result.document), "\n".join(lines), [*spec.warnings, *rigid, *result.warnings])


def export(args: argparse.Namespace) -> None:
    """``armcal export``: the calibrated arm as a robot file or URDF."""
    outputs = (
        args.robot_toml, args.urdf, args.origins_yaml, args.joint_offsets, args.ur_calibration,
        args.ros_calibration,
    )  # fmt: skip
    if all(path is None for path in outputs):
        raise ArmcalError(
            "export needs an output: give --robot-toml FILE, --urdf FILE, --joint-offsets FILE, "
            "--ur-calibration FILE, --ros-calibration FILE or several (see 'armcal export "
            "--help')"
        )
    if args.origins_yaml is not None and args.original is None:
        raise ArmcalError(
            f"{args.origins_yaml}: --origins-yaml writes the origins of a URDF's joints: give "
            "the URDF the robot was described by with --from URDF"
        )
    if args.original is not None and args.urdf is None and args.origins_yaml is None:
        raise ArmcalError(
            f"{args.original}: --from is the URDF to calibrate: give --urdf FILE to write it "
            "with the calibrated origins (or --origins-yaml FILE)"
        )
    from ..files import read_calibration  # first, as the robot (module docstring)

    cal = read_calibration(args.calibration)
    from ..workflow import export_files  # the library it runs (module docstring)

    run = export_files(
        cal,
        robot_toml_path=args.robot_toml,
        urdf_path=args.urdf,
        offsets_path=args.joint_offsets,
        ur_path=args.ur_calibration,
        ros_path=args.ros_calibration,
        original=args.original,
        origins_path=args.origins_yaml,
    )
    for path, text in run.texts.items():
        atomic_write(path, text)
    document = {
        "robot_toml": args.robot_toml,
        "urdf": args.urdf,
        "from": args.original,
        "origins_yaml": args.origins_yaml,
        "joint_offsets": args.joint_offsets,
        "ur_calibration": args.ur_calibration,
        "ros_calibration": args.ros_calibration,
    }
    if run.rigid is not None:
        document["rigid_export"] = run.rigid.to_dict()
    emit(args, document, "\n".join(f"wrote {path}" for path in run.texts), run.warnings)


def formats(args: argparse.Namespace) -> None:
    """``armcal formats``: every key of the robot file and column of the CSV files."""
    print(format_reference())
