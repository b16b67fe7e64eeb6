"""The ``armcal`` command line: parse arguments, call the library, write files.

Exit status: 0 on success, 2 for bad input (one ``armcal: error: ...`` line on
stderr, no traceback, no output file), 130 when interrupted (Ctrl-C; one
``armcal: interrupted`` line), 1 for bugs.  Output paths are checked before any
work (:func:`armcal.io.check_outputs`).
"""

from __future__ import annotations

import argparse
import dataclasses
import math
import sys
import textwrap
import time
from collections.abc import Callable, Sequence
from functools import partial
from pathlib import Path
from typing import Any

import numpy as np

from ._version import __version__
from .cli_help import COMMANDS, OUTPUTS_EPILOG
from .cli_help import description as help_description
from .cli_help import epilog as help_epilog
from .compensation import compensate
from .criteria import CRITERIA, evaluate_plan
from .demo import DEMO_FILES, run_demo
from .doe import DISTINCT_TOLERANCE, ORDERS, TARGETS, design, feasible, poses_needed, random_plan
from .doe import METHODS as DESIGN_METHODS
from .doe.compliance import design_compliant
from .errors import ArmcalError, ArmcalWarning, InputError, NotIdentifiableError
from .export import robot_toml, urdf, urdf_joints_are_readings
from .formats import format_reference
from .identification import METHODS, Calibration, Method, identify
from .instrument import identify_3d
from .io import (
    BUILTIN_ROBOTS,
    COMPLIANCE_TRUTH_KEYS,
    DEFAULT_ROBOT,
    SIGMA_RANGE_MM,
    STDIO,
    Measurements,
    OutputFolder,
    RobotSpec,
    arm_for_measurements,
    atomic_write,
    check_outputs,
    format_measurements_csv,
    format_plan_csv,
    format_program_csv,
    load_compliance_truth,
    load_robot,
    load_truth,
    read_calibration,
    read_loaded_plan,
    read_measurements,
    read_plan,
    read_program,
    unknown_parameter,
    write_folder,
)
from .models import CompliantArm, FitModel, Loads, PlanarArm, every_target
from .noise import NoiseModel
from .plausibility import deviation_warning, explain, suspicious
from .progress import ProgressBar
from .report import (
    calibration_to_dict,
    compensation_report,
    compliant_design_summary,
    compliant_quality,
    design_summary,
    format_calibration,
    format_cross_validation,
    format_monte_carlo,
    format_quality,
    format_reproduction,
    monte_carlo_to_dict,
    poses_needed_summary,
    quality_to_dict,
    reproduction_summary,
    table_csv,
    to_json,
    validation_report,
    validation_warnings,
)
from .reproduction import TABLE_COLUMNS, reproduce
from .simulate import monte_carlo
from .synthesis import synthesize_measurements
from .validation import cross_validate, cross_validation_warning, validate

__all__ = ["main"]

#: The command line's words for the advice of warnings (:data:`armcal.errors.ACTIONS`).
CLI_ACTIONS = {
    "refit-robust": "rerun with --robust to fit without them",
    "try-robust": "try --robust",
    "try-closed-form": "try --method closed-form",
    "geometry-alone": "fit the geometry alone (--no-compliance)",
    "design": "(armcal design)",
}

#: Noise assumed for design and simulation when neither --sigma nor the robot file gives it.
DEFAULT_SIGMA_MM = 0.1


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


def _finite(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number, got {text!r}") from None
    if not math.isfinite(value):
        raise argparse.ArgumentTypeError(f"expected a finite number, got {text!r}")
    return value


def _above_zero(text: str, *, strict: bool) -> float:
    value = _finite(text)
    if value < 0 or (strict and value == 0):
        bound = "> 0" if strict else ">= 0"
        raise argparse.ArgumentTypeError(f"expected a number {bound}, got {text!r}")
    return value


def _positive(text: str) -> float:
    return _above_zero(text, strict=True)


def _not_negative(text: str) -> float:
    return _above_zero(text, strict=False)


def _payloads(text: str) -> tuple[float, ...]:
    values = tuple(_not_negative(part) for part in text.split(",") if part.strip())
    if not values:
        raise argparse.ArgumentTypeError(f"expected payloads in kg like 0,10, got {text!r}")
    return values


def _sigma(text: str) -> float:
    """Instrument noise in mm, within the range any instrument has (io.SIGMA_RANGE_MM)."""
    value = _finite(text)
    low, high = SIGMA_RANGE_MM
    if not low <= value <= high:
        raise argparse.ArgumentTypeError(
            f"expected a noise std between {low:g} and {high:g} mm, got {text!r}"
        )
    return value


def _sigma_or_zero(text: str) -> float:
    """Like :func:`_sigma`, or 0 for noiseless synthetic data."""
    return 0.0 if _finite(text) == 0 else _sigma(text)


def _seed(text: str) -> int:
    try:
        value = int(text)
    except ValueError:
        value = -1
    if value < 0:
        raise argparse.ArgumentTypeError(f"expected a whole number >= 0, got {text!r}")
    return value


def _poses(text: str) -> int:
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a whole number, got {text!r}") from None
    if value < 1:
        raise argparse.ArgumentTypeError(f"expected at least 1 pose, got {value}")
    return value


def _folds(text: str) -> int:
    """``--cross-validate K``: a whole number of folds >= 2."""
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"expected a whole number of folds, got {text!r}"
        ) from None
    if value < 2:
        raise argparse.ArgumentTypeError(f"needs at least 2 folds, got {value}")
    return value


def _trials(text: str) -> int:
    value = _poses(text)
    if value < 2:
        raise argparse.ArgumentTypeError(f"expected at least 2 trials, got {value}")
    return value


def _names(text: str) -> tuple[str, ...]:
    """``--fix dl4,dq1``: parameter names, checked against the robot once it is loaded."""
    names = tuple(name.strip() for name in text.split(","))
    if not all(names):
        raise argparse.ArgumentTypeError(
            f"expected parameter names separated by commas (e.g. dl4,dq1), got {text!r}"
        )
    return names


def _model_arm(args: argparse.Namespace, spec: RobotSpec) -> PlanarArm:
    """The robot's arm with ``--fix`` and ``--sigma`` applied.

    ``--fix`` replaces the robot file's ``[identify]`` set; ``--sigma`` replaces
    the instrument noise by isotropic noise and keeps the encoder noise.
    """
    arm = spec.arm
    fix = getattr(args, "fix", None)
    if fix is not None:
        for name in fix:
            if name not in arm.param_names:
                raise ArmcalError(f"--fix: {unknown_parameter(name, arm.param_names, arm.name)}")
        if len(set(fix)) == arm.n_params:
            raise ArmcalError("--fix: every parameter would be fixed; leave at least one free")
        arm = arm.replace(fixed=fix)
    sigma = getattr(args, "sigma", None)
    if sigma:  # 0 (noiseless synthesis) is no noise model
        noise = NoiseModel.isotropic(sigma) if arm.noise is None else arm.noise
        arm = arm.replace(noise=noise.with_instrument_sigma(sigma))
    return arm


def _sigma_for_simulation(args: argparse.Namespace, spec: RobotSpec) -> float | None:
    """``--sigma``, else None: the robot file's whole noise model (shape and encoders)."""
    if args.sigma is not None:
        return args.sigma
    return None if spec.arm.noise is not None else DEFAULT_SIGMA_MM


def _design_sigma(arm: PlanarArm) -> float:
    """The reference noise of a model arm (:func:`_model_arm`), else the default."""
    return arm.sigma if arm.sigma is not None else DEFAULT_SIGMA_MM


def _truth(args: argparse.Namespace, spec: RobotSpec) -> np.ndarray:
    if args.truth is not None:
        return load_truth(args.truth, spec.arm)
    if spec.default_truth is None:
        raise ArmcalError(
            f"{spec.source}: a robot file has no default truth; pass --truth truth.toml "
            "(dl_mm, dq_deg and, with a base offset, base_mm)"
        )
    return spec.default_truth


def _unique(warnings: Sequence[ArmcalWarning]) -> list[ArmcalWarning]:
    """Each warning once, in order."""
    seen: set[tuple[str, str]] = set()
    kept = []
    for warning in warnings:
        if (warning.code, warning.message) not in seen:
            seen.add((warning.code, warning.message))
            kept.append(warning)
    return kept


def _emit(
    args: argparse.Namespace,
    document: dict,
    text: str,
    warnings: Sequence[ArmcalWarning] = (),
) -> None:
    """Print the result, after every warning of the run (once each) on stderr.

    The warnings also replace the document's ``warnings`` list, so the JSON and
    stderr say the same.
    """
    warnings = _unique(warnings)
    document["warnings"] = [w.to_dict(CLI_ACTIONS) for w in warnings]
    _print_warnings(warnings)
    if getattr(args, "stdout_taken", False):  # `-o -`: the file is the command's output
        return
    print(to_json(document) if args.json else text, end="" if args.json else "\n")


# --------------------------------------------------------------------------- commands


def _synthesize(args: argparse.Namespace) -> None:
    spec = load_robot(args.robot)
    sigma = _sigma_for_simulation(args, spec)
    labels = targets = target = None
    what = ""
    if spec.elastic is not None:  # a robot whose joints deflect under load
        q, loads, model = _loaded_plan(args.plan, spec, spec.arm)
        truth = _compliance_truth(args, spec, model)
        xy = synthesize_measurements(model, q, truth, sigma, rng=args.seed, loads=loads)
        text = format_measurements_csv(q, xy, payload_kg=loads.payload_kg)
        what = " with joint compliance"
    else:
        q = read_plan(args.plan, spec.arm)
        truth = _truth(args, spec)
        if spec.arm.targets:  # every target measured at every pose, one row each
            count = len(spec.arm.targets)
            labels = [str(i // count + 1) for i in range(q.shape[0] * count)]
            q, target = every_target(spec.arm, q)
            targets = [spec.arm.targets[t].label for t in target]
        xy = synthesize_measurements(spec.arm, q, truth, sigma, rng=args.seed, target=target)
        text = format_measurements_csv(q, xy, labels, targets)
    if args.output is None or args.output == STDIO:
        _print_warnings(_unique(spec.warnings))
        sys.stdout.write(text)
        return
    atomic_write(args.output, text)
    shown = sigma if sigma is not None else float(spec.arm.sigma or 0.0)
    document = {"poses": int(q.shape[0]), "sigma_mm": shown, "output": str(args.output)}
    _emit(
        args,
        document,
        f"wrote {q.shape[0]} measurements of {spec.arm.name}{what} (sigma {shown:g} mm, "
        f"seed {args.seed}) to {args.output}",
        spec.warnings,
    )


def _explained(path: str, arm: PlanarArm, meas: Measurements) -> InputError | None:
    """The error for data that another reading fits far better (:mod:`armcal.plausibility`)."""
    found = explain(arm, meas.q, meas.xy)
    return None if found is None else InputError(f"{path}: {found.message}")


def _row_targets(arm: PlanarArm, meas: Measurements) -> np.ndarray | None:
    """Every row's target index, for an arm with targets (None without)."""
    if meas.targets is None or not arm.targets:
        return None
    return arm.target_index(meas.targets)


def _identify_file(
    arm: PlanarArm,
    path: str,
    meas: Measurements,
    *,
    method: Method,
    robust: bool,
    spec: RobotSpec | None = None,
) -> Calibration:
    """Identify from a measurement file; data that look like a unit mistake are an error.

    3-D data (a ``z_mm`` column) are fitted with their plane first
    (:func:`armcal.instrument.identify_3d`).  The unit checks of
    :mod:`armcal.plausibility` refit the plain 2-D model; they are skipped for
    data with several targets or in 3-D, whose reach check stays.  With the
    robot's ``[elastostatic]`` (``spec``) the joint compliance is fitted too.
    """
    elastic = None if spec is None else spec.elastic
    plain = meas.z is None and arm.n_target_links == 1 and not arm.targets and elastic is None
    kwargs: dict[str, Any] = {
        "method": method,
        "pose_labels": meas.labels,
        "rows": meas.rows,
        "row_sigma": meas.row_sigma,
        "robust": robust,
        "target": _row_targets(arm, meas),
    }
    model: FitModel = arm
    try:
        if elastic is not None:
            kwargs["loads"] = meas.loads(elastic.payload_kg)
            model = CompliantArm.for_loads(arm, elastic, kwargs["loads"])
        if meas.z is not None:
            if elastic is not None:
                kwargs["gravity_3d"] = None if spec is None else spec.gravity_3d
            cal = identify_3d(model, meas.q, meas.xyz, **kwargs)
        else:
            cal = identify(model, meas.q, meas.xy, **kwargs)
    except NotIdentifiableError as exc:
        # Angles in radians read as degrees put every pose near the stretched arm.
        unit = _explained(path, arm, meas) if plain else None
        if unit is not None:
            raise unit from None
        raise NotIdentifiableError(f"{path}: {exc}", exc.combinations) from None
    except ArmcalError as exc:
        raise ArmcalError(f"{path}: {exc}") from None
    if plain and suspicious(cal):
        unit = _explained(path, arm, meas)
        if unit is not None:
            raise unit
    return cal


def _print_warnings(warnings: Sequence[ArmcalWarning]) -> None:
    """Each warning as one ``armcal: warning: ...`` line on stderr."""
    for warning in warnings:
        print(f"armcal: warning: {warning.render(CLI_ACTIONS)}", file=sys.stderr)


def _measured_arm(args: argparse.Namespace, spec: RobotSpec, meas: Measurements) -> PlanarArm:
    """The robot's arm as the data need it (targets, 3-D base pose), with --fix and --sigma."""
    try:
        structure = arm_for_measurements(spec.arm, meas)
    except InputError as exc:
        raise InputError(f"{args.measurements}: {exc}") from None
    return _model_arm(args, dataclasses.replace(spec, arm=structure))


def _identify(args: argparse.Namespace) -> None:
    spec = load_robot(args.robot)
    meas = read_measurements(args.measurements, spec.arm)
    arm = _measured_arm(args, spec, meas)
    if args.sigma is not None:  # the command line's noise replaces the file's sigma_mm column too
        meas = dataclasses.replace(meas, row_sigma=None)
    if args.no_compliance:
        spec = dataclasses.replace(spec, elastic=None)
    cal = _identify_file(
        arm, args.measurements, meas, method=args.method, robust=args.robust, spec=spec
    )
    warnings = [*spec.warnings, *meas.warnings, *_ignored_loads(args, spec, meas), *cal.warnings]
    large = deviation_warning(cal.arm, cal.model.arm_params(cal.params))
    if large is not None and all(w.code != large.code for w in warnings):
        warnings.append(large)
    text = format_calibration(cal)
    extra: dict = {}
    if args.cross_validate is not None:
        xy = meas.xy if cal.plane is None else cal.plane.to_plane(meas.xyz)
        groups = None if meas.targets is None else np.array(meas.labels)
        conditions = cal.conditions
        result = cross_validate(
            cal.model,
            meas.q,
            xy,
            args.cross_validate,
            groups=groups,
            target=cal.target,
            sigma=args.sigma,
            row_sigma=meas.row_sigma,
            rng=args.seed,
            loads=None if conditions is None else conditions.loads,
        )
        summary = result.summary()
        extra["cross_validation"] = summary
        text += "\n" + format_cross_validation(summary)
        warning = cross_validation_warning(result)
        if warning is not None:
            warnings.append(warning)
    warnings = _unique(warnings)
    document = calibration_to_dict(cal, warnings=warnings)
    document["warnings"] = [w.to_dict(CLI_ACTIONS) for w in warnings]
    document.update(extra)
    if args.output is not None:
        atomic_write(args.output, to_json(document))
    _emit(args, document, text, warnings)


def _ignored_loads(
    args: argparse.Namespace, spec: RobotSpec, meas: Measurements
) -> list[ArmcalWarning]:
    """A warning when the data carry loads that a rigid model cannot use."""
    if spec.elastic is not None or not meas.has_loads:
        return []
    why = (
        "--no-compliance fits the geometry only"
        if getattr(args, "no_compliance", False)
        else "the robot file has no [elastostatic] table"
    )
    return [
        ArmcalWarning(
            "loads-ignored",
            f"{args.measurements}: the payload_kg/fx_N/fy_N columns are not used: {why}; "
            "add [elastostatic] to the robot file to fit the joints' compliance",
        )
    ]


def _validate(args: argparse.Namespace) -> None:
    cal = read_calibration(args.calibration)
    meas = read_measurements(args.measurements, cal.arm)
    if meas.targets is not None and not cal.arm.targets:
        raise InputError(
            f"{args.measurements}: has a target column but the calibration has no targets; "
            "remove the column"
        )
    if cal.arm.targets and meas.targets is None:
        raise InputError(
            f"{args.measurements}: the calibration has targets "
            f"({', '.join(cal.arm.target_labels)}); add a column 'target' naming the target "
            "of every row"
        )
    points = meas.xy if meas.z is None else meas.xyz
    model = cal.model
    loads = meas.loads(model.elastic.payload_kg) if isinstance(model, CompliantArm) else None
    try:
        result = validate(
            cal,
            meas.q,
            points,
            target=_row_targets(cal.arm, meas),
            row_sigma=meas.row_sigma,
            loads=loads,
        )
    except ArmcalError as exc:
        raise ArmcalError(f"{args.measurements}: {exc}") from None
    if args.plot is not None:
        from .plotting import plot_validation, save_figure  # matplotlib only when asked for

        save_figure(plot_validation(cal.arm, meas.q, result), args.plot)
    document, text = validation_report(cal, result, meas, per_pose=args.per_pose)
    warnings = [*meas.warnings, *validation_warnings(result)]
    if args.plot is not None:
        text += f"\nwrote {args.plot}"
    _emit(args, document, text, warnings)


def _compensate(args: argparse.Namespace) -> None:
    cal = read_calibration(args.calibration)
    program = read_program(args.program, cal.arm)
    arm = cal.arm
    labels = program.targets
    if labels is None and args.target is not None:
        labels = (args.target,) * program.q.shape[0]
    if labels is not None:
        if args.target is not None and program.targets is not None:
            raise ArmcalError("--target: the program has a target column already; give one")
        if args.target is not None and args.target not in arm.target_labels:
            raise ArmcalError(
                f"--target: {args.target!r} is not a target of the calibration "
                f"({', '.join(arm.target_labels) or 'none'})"
            )
    elif arm.n_target_links > 1:
        raise ArmcalError(
            f"{args.program}: the calibration has targets {', '.join(arm.target_labels)}; "
            "add a column 'target' or pass --target LABEL for the tool point of the program"
        )
    target = None if labels is None or not arm.targets else arm.target_index(labels)
    loads = None
    if isinstance(cal.model, CompliantArm):
        payload: float | np.ndarray = cal.model.elastic.payload_kg
        if args.payload_kg is not None:
            if program.payload_kg is not None:
                raise ArmcalError("--payload-kg: the program has a payload_kg column already")
            payload = args.payload_kg
        if program.payload_kg is not None:
            payload = program.payload_kg
        loads = Loads.create(program.q.shape[0], payload, program.force_n)
    elif args.payload_kg is not None or program.payload_kg is not None:
        raise ArmcalError(
            "--payload-kg/payload_kg: the calibration has no joint compliance, so a payload "
            "changes nothing; calibrate with [elastostatic] in the robot file"
        )
    result = compensate(cal, program.q, target=target, loads=loads)
    atomic_write(
        args.output, format_program_csv(result.q, result.corrected, program.labels, labels)
    )
    document, text, warnings = compensation_report(cal, result, program)
    text += f"\nwrote {args.output}"
    _emit(args, document, text, warnings)


def _demo(args: argparse.Namespace) -> None:
    spec = load_robot(args.robot)
    truth = _truth(args, spec)
    sigma = _design_sigma(spec.arm) if args.sigma is None else args.sigma
    result = run_demo(spec.arm, truth, poses=args.poses, sigma=sigma, seed=args.seed)
    lines = [result.text]
    if args.output is not None:
        folder = write_folder(args.output, result.files)
        lines += [
            "",
            f"wrote {len(result.files)} files to {folder}/: report.md, figures, "
            "plan, measurements, calibration, program, robot file, URDF",
        ]
    warnings = _unique([*spec.warnings, *result.warnings])
    document = dict(result.document)
    _emit(args, document, "\n".join(lines), warnings)


def _test_poses(args: argparse.Namespace, spec: RobotSpec) -> np.ndarray:
    """Poses where positioning accuracy matters: --test-poses, else 1000 uniform in the limits."""
    if args.test_poses is not None:
        return read_plan(args.test_poses, spec.arm)
    return random_plan(spec.arm, 1000, rng=np.random.default_rng(args.seed))


def _quality_report(args: argparse.Namespace, spec: RobotSpec, arm: PlanarArm, q: np.ndarray):
    quality = evaluate_plan(arm, q, sigma=_design_sigma(arm), test_q=_test_poses(args, spec))
    return quality, quality_to_dict(arm, quality), format_quality(arm, quality)


def _loaded_plan(
    path: str, spec: RobotSpec, arm: PlanarArm
) -> tuple[np.ndarray, Loads, CompliantArm]:
    """A plan of a robot with ``[elastostatic]``: poses, payloads and the compliance model."""
    assert spec.elastic is not None
    q, payload = read_loaded_plan(path, spec.arm)
    loads = Loads.create(q.shape[0], spec.elastic.payload_kg if payload is None else payload)
    try:
        model = CompliantArm.for_loads(arm, spec.elastic, loads)
    except ArmcalError as exc:
        raise ArmcalError(f"{spec.source}: {exc}") from None
    return q, loads, model


def _compliance_truth(
    args: argparse.Namespace, spec: RobotSpec, model: CompliantArm
) -> np.ndarray:
    """The deviations and the compliance of the virtual robot (``--truth`` is required)."""
    if args.truth is None:
        keys = ", ".join(COMPLIANCE_TRUTH_KEYS[k] for k in dict.fromkeys(model.kinds))
        raise ArmcalError(
            f"{spec.source}: a robot with [elastostatic] needs --truth truth.toml with the "
            f"deviations and {keys}"
        )
    geometry = load_truth(args.truth, spec.arm)
    return np.concatenate([geometry, load_compliance_truth(args.truth, model)])


def _design_compliant(args: argparse.Namespace, spec: RobotSpec, arm: PlanarArm) -> None:
    assert spec.elastic is not None
    if args.criterion != "D" or args.method not in ("auto", "exchange"):
        raise ArmcalError(
            "a robot with [elastostatic] is designed D-optimal by exchange and polish; "
            "leave --criterion and --method at their defaults"
        )
    if args.candidates is not None or args.distinct:
        raise ArmcalError("--candidates and --distinct are not supported with [elastostatic] yet")
    start = time.perf_counter()
    result = design_compliant(
        arm,
        spec.elastic,
        args.poses,
        payloads=args.payloads,
        sigma=_design_sigma(arm),
        rng=np.random.default_rng(args.seed),
        order=args.order,
    )
    seconds = time.perf_counter() - start
    document, report = compliant_quality(result.model, result.q, result.loads, result.sigma_mm)
    extra, header = compliant_design_summary(result, seconds)
    document.update(extra)
    written = []
    if args.plot is not None:
        from .plotting import plot_plan, save_figure  # matplotlib only when a plot is asked for

        save_figure(plot_plan(spec.arm, result.q), args.plot)
    if args.output is not None:
        atomic_write(args.output, format_plan_csv(result.q, result.payload_kg))
        written.append(f"wrote {args.output}")
    if args.plot is not None:
        written.append(f"wrote {args.plot}")
    text = "\n".join([*header, report, *([""] if written else []), *written])
    _emit(args, document, text, spec.warnings)


def _design(args: argparse.Namespace) -> None:
    spec = load_robot(args.robot)
    arm = _model_arm(args, spec)
    if spec.elastic is not None:
        _design_compliant(args, spec, arm)
        return
    if args.payloads is not None:
        raise ArmcalError(
            f"--payloads: robot {spec.arm.name} has no [elastostatic] table, so a payload "
            "changes nothing; add the table to the robot file"
        )
    candidates = None if args.candidates is None else read_plan(args.candidates, spec.arm)
    if candidates is not None and not np.all(feasible(spec.arm, candidates)):
        row = int(np.flatnonzero(~feasible(spec.arm, candidates))[0]) + 1
        raise ArmcalError(
            f"{args.candidates}: row {row}: the tip is outside the measurement region; "
            "remove the pose or widen the region"
        )
    start = time.perf_counter()
    result = design(
        arm,
        args.poses,
        criterion=args.criterion,
        method=args.method,
        rng=np.random.default_rng(args.seed),
        candidates=candidates,
        order=args.order,
        distinct=args.distinct,
    )
    seconds = time.perf_counter() - start
    quality, document, report = _quality_report(args, spec, arm, result.q)
    extra, header = design_summary(result, seconds)
    document.update(extra)
    written = []
    if args.plot is not None:  # first: drawing is what can fail, the plan CSV is text
        from .plotting import plot_plan, save_figure  # matplotlib only when a plot is asked for

        save_figure(plot_plan(spec.arm, result.q), args.plot)
    if args.output is not None:
        atomic_write(args.output, format_plan_csv(result.q))
        written.append(f"wrote {args.output}")
    if args.plot is not None:
        written.append(f"wrote {args.plot}")
    text = "\n".join([*header, report, *([""] if written else []), *written])
    _emit(args, document, text, [*spec.warnings, *quality.warnings])


def _evaluate(args: argparse.Namespace) -> None:
    spec = load_robot(args.robot)
    arm = _model_arm(args, spec)
    if spec.elastic is not None:
        q, loads, model = _loaded_plan(args.plan, spec, arm)
        try:
            model.check_identifiable(model.conditions(q, loads=loads))
        except NotIdentifiableError as exc:
            raise NotIdentifiableError(f"{args.plan}: {exc}", exc.combinations) from None
        document, report = compliant_quality(model, q, loads, _design_sigma(arm))
        _emit(args, document, report, spec.warnings)
        return
    q = read_plan(args.plan, arm)
    try:
        quality, document, report = _quality_report(args, spec, arm, q)
    except NotIdentifiableError as exc:  # PRODUCT.md: an error, exit 2, one line
        raise NotIdentifiableError(f"{args.plan}: {exc}", exc.combinations) from None
    warnings = [*spec.warnings, *quality.warnings]
    outside = np.flatnonzero(~feasible(spec.arm, q))
    if outside.size:
        poses = ", ".join(map(str, outside + 1))
        warnings.append(
            ArmcalWarning(
                "outside-region",
                f"{args.plan}: the tip of pose(s) {poses} is outside the measurement region",
            )
        )
    _emit(args, document, report, warnings)


def _simulate_compliant(args: argparse.Namespace, spec: RobotSpec, arm: PlanarArm) -> None:
    q, loads, model = _loaded_plan(args.plan, spec, arm)
    truth = _compliance_truth(args, spec, model)
    try:
        result = monte_carlo(
            model,
            q,
            truth,
            None if arm.noise is not None else DEFAULT_SIGMA_MM,
            args.trials,
            rng=np.random.default_rng(args.seed),
            progress=ProgressBar("simulate"),
            loads=loads,
        )
    except NotIdentifiableError as exc:
        raise NotIdentifiableError(f"{args.plan}: {exc}", exc.combinations) from None
    _emit(
        args,
        monte_carlo_to_dict(result),
        format_monte_carlo(result),
        [*spec.warnings, *result.warnings],
    )


def _simulate(args: argparse.Namespace) -> None:
    spec = load_robot(args.robot)
    arm = _model_arm(args, spec)
    if spec.elastic is not None:
        _simulate_compliant(args, spec, arm)
        return
    q = read_plan(args.plan, arm)
    truth = _truth(args, spec)
    method = args.method
    if method == "auto":
        method = "closed-form" if arm.free.all() else "gauss-newton"
    try:
        result = monte_carlo(
            arm,
            q,
            truth,
            None if arm.noise is not None else DEFAULT_SIGMA_MM,  # the model as it is
            args.trials,
            method=method,
            rng=np.random.default_rng(args.seed),
            test_q=_test_poses(args, spec),
            progress=ProgressBar("simulate"),
        )
    except NotIdentifiableError as exc:
        raise NotIdentifiableError(f"{args.plan}: {exc}", exc.combinations) from None
    warnings = [*spec.warnings, *result.warnings]
    if result.not_converged:
        warnings.append(
            ArmcalWarning(
                "not-converged",
                f"gauss-newton did not converge in {result.not_converged} of "
                f"{result.trials} trials; their last iterates are included",
            )
        )
    _emit(args, monte_carlo_to_dict(result), format_monte_carlo(result), warnings)


_TARGET_OPTIONS = {
    "length_std_mm": "--length-std-mm",
    "angle_std_deg": "--angle-std-deg",
    "position_rms_mm": "--position-rms-mm",
}


def _poses_needed(args: argparse.Namespace) -> None:
    spec = load_robot(args.robot)
    if spec.elastic is not None:
        raise ArmcalError(
            f"{spec.source}: poses-needed sizes plans of the geometric model only, and this "
            "robot has [elastostatic]; compare the predicted std of armcal design --poses M at "
            "a few sizes M (std falls like 1/sqrt(M))"
        )
    arm = _model_arm(args, spec)
    target = next(key for key in TARGETS if getattr(args, key) is not None)
    sigma = _design_sigma(arm)
    start = time.perf_counter()
    found = poses_needed(
        arm,
        target,
        getattr(args, target),
        sigma=sigma,
        rng=np.random.default_rng(args.seed),
        test_q=_test_poses(args, spec),
        max_poses=args.max_poses,
    )
    seconds = time.perf_counter() - start
    document, lines = poses_needed_summary(found, arm, seconds)
    if args.output is not None:
        atomic_write(args.output, format_plan_csv(found.plan))
        lines.append(f"wrote {args.output}")
    _emit(args, document, "\n".join(lines), spec.warnings)


def _reproduce(args: argparse.Namespace) -> None:
    from .plotting import plot_accuracy_curves, plot_random_plans, save_figure

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
    _emit(args, document, "\n".join(lines))


def _check_compliance(args: argparse.Namespace) -> None:
    from .compliance_check import check_compliance, format_check

    result = check_compliance(seed=args.seed, trials=args.trials)
    _emit(args, result.to_dict(), format_check(result))


def _export(args: argparse.Namespace) -> None:
    if args.robot_toml is None and args.urdf is None:
        raise ArmcalError(
            "export needs an output: give --robot-toml FILE, --urdf FILE or both "
            "(see 'armcal export --help')"
        )
    cal = read_calibration(args.calibration)
    texts = {}  # every text made before any file is written
    if args.robot_toml is not None:
        texts[args.robot_toml] = robot_toml(cal)
    warnings = []
    if args.urdf is not None:
        texts[args.urdf] = urdf(cal)
        if not urdf_joints_are_readings(cal.arm):
            warnings.append(
                ArmcalWarning(
                    "urdf-joint-values",
                    f"{args.urdf}: {cal.arm.name} has coupled axes (joint_map): the URDF's joint "
                    "values are the relative link angles D M q, not the controller's readings; "
                    "convert them before publishing joint_states (see the file's comment)",
                )
            )
    if isinstance(cal.model, CompliantArm):
        model = cal.model
        p = model.arm.n_params
        values = ", ".join(
            f"{name} = {v:.4g} {unit}"
            for name, unit, v in zip(
                model.compliance_names,
                model.compliance_units,
                cal.params[p:] * model.compliance_scale,
                strict=True,
            )
        )
        warnings.append(
            ArmcalWarning(
                "compliance-not-exported",
                f"the exported geometry is rigid: the joint compliance ({values}) is not part "
                "of a robot file or URDF; compensate programs with armcal compensate, which "
                "uses it",
            )
        )
    for path, text in texts.items():
        atomic_write(path, text)
    document = {"robot_toml": args.robot_toml, "urdf": args.urdf}
    _emit(args, document, "\n".join(f"wrote {path}" for path in texts), warnings)


def _formats(args: argparse.Namespace) -> None:
    print(format_reference())


# --------------------------------------------------------------------------- parser


def _add_common(
    sub: argparse.ArgumentParser, *, seed: bool = False, output: str | None = None
) -> None:
    sub.add_argument(
        "--robot",
        default=DEFAULT_ROBOT,
        metavar="NAME_OR_FILE",
        help=f"built-in robot name or robot TOML file (default {DEFAULT_ROBOT})",
    )
    if seed:
        sub.add_argument("--seed", type=_seed, default=0, help="random seed >= 0 (default 0)")
    sub.add_argument("--json", action="store_true", help="print a JSON document on stdout")
    if output is not None:
        sub.add_argument("-o", "--output", metavar="PATH", help=output)


def _add_calibration(sub: argparse.ArgumentParser) -> None:
    """``--calibration`` (the file identify wrote) and ``--json``: commands that start from one."""
    sub.add_argument("--calibration", required=True, metavar="JSON", help="from identify -o")
    sub.add_argument("--json", action="store_true", help="print a JSON document on stdout")


def _add_fix(sub: argparse.ArgumentParser) -> None:
    sub.add_argument(
        "--fix",
        type=_names,
        metavar="P,..",
        help="parameters held at nominal, not identified (e.g. dl4,dq1); replaces the robot "
        "file's [identify] set",
    )


def build_parser() -> argparse.ArgumentParser:
    """The argument parser of the ``armcal`` program."""
    parser = _Parser(
        prog="armcal",
        description="Design, run and evaluate calibration experiments for planar serial arms.",
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
        type=_sigma_or_zero,
        metavar="MM",
        help=f"noise std in mm (default: robot file's sigma_mm, else {DEFAULT_SIGMA_MM})",
    )
    _add_common(sub, seed=True, output="measurements CSV to write (default: stdout)")
    sub.set_defaults(run=_synthesize, inputs=("robot", "plan", "truth"), outputs=("output",))

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
        type=_sigma,
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
        type=_folds,
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
    _add_common(sub, seed=True, output="calibration JSON to write")
    sub.set_defaults(run=_identify, inputs=("robot", "measurements"), outputs=("output",))

    sub = _command(subs, "validate")
    _add_calibration(sub)
    sub.add_argument(
        "--measurements",
        required=True,
        metavar="CSV",
        help="held-out measurements CSV (columns under reads: above)",
    )
    sub.add_argument("--per-pose", action="store_true", help="a table of every pose's errors")
    sub.add_argument("--plot", metavar="PNG", help="draw the error vectors on the workspace")
    sub.set_defaults(run=_validate, inputs=("calibration", "measurements"), outputs=("plot",))

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
        type=_not_negative,
        metavar="KG",
        help="the program's payload, for a calibration with joint compliance (default: the "
        "robot file's payload_kg; a payload_kg column gives it per row)",
    )
    sub.add_argument(
        "-o", "--output", required=True, metavar="CSV", help="corrected program to write"
    )
    sub.set_defaults(run=_compensate, inputs=("calibration", "program"), outputs=("output",))

    sigma_help = (
        "isotropic instrument noise in mm, replacing the robot file's (its encoder noise is "
        f"kept); default: the robot file's [measurement], else {DEFAULT_SIGMA_MM}"
    )
    test_help = "plan CSV of poses where accuracy matters (default: 1000 uniform in the limits)"
    sub = _command(subs, "design")
    sub.add_argument("--poses", type=_poses, required=True, metavar="M", help="number of poses")
    sub.add_argument(
        "--criterion", choices=list(CRITERIA), default="D", help="criterion (default D)"
    )
    sub.add_argument(
        "--method",
        choices=list(DESIGN_METHODS),
        default="auto",
        help="auto = analytic if it fits the constraints, else optimize + exchange",
    )
    sub.add_argument("--candidates", metavar="PLAN_CSV", help="reachable poses for exchange")
    sub.add_argument(
        "--payloads",
        type=_payloads,
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
    sub.add_argument("--plot", metavar="PNG", help="draw the plan's poses as stick arms")
    sub.add_argument("--sigma", type=_sigma, metavar="MM", help=sigma_help)
    sub.add_argument("--test-poses", metavar="PLAN_CSV", help=test_help)
    _add_fix(sub)
    _add_common(sub, seed=True, output="plan CSV to write")
    sub.set_defaults(
        run=_design, inputs=("robot", "candidates", "test_poses"), outputs=("output", "plot")
    )

    sub = _command(subs, "evaluate")
    sub.add_argument("--plan", required=True, metavar="PLAN_CSV", help="plan CSV (q1_deg..)")
    sub.add_argument("--sigma", type=_sigma, metavar="MM", help=sigma_help)
    sub.add_argument("--test-poses", metavar="PLAN_CSV", help=test_help)
    _add_fix(sub)
    _add_common(sub, seed=True)
    sub.set_defaults(run=_evaluate, inputs=("robot", "plan", "test_poses"))

    sub = _command(subs, "simulate")
    sub.add_argument("--plan", required=True, metavar="PLAN_CSV", help="plan CSV (q1_deg..)")
    sub.add_argument("--truth", metavar="TRUTH_TOML", help="deviations (default: the built-in's)")
    sub.add_argument("--sigma", type=_sigma, metavar="MM", help=sigma_help)
    sub.add_argument(
        "--trials", type=_trials, default=10_000, metavar="N", help="trials (default 10000)"
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
    sub.set_defaults(run=_simulate, inputs=("robot", "plan", "truth", "test_poses"))

    sub = _command(subs, "poses-needed")
    group = sub.add_mutually_exclusive_group(required=True)
    for key, option in _TARGET_OPTIONS.items():
        group.add_argument(
            option, dest=key, type=_positive, metavar="A", help=TARGETS[key] + " to reach"
        )
    sub.add_argument("--sigma", type=_sigma, metavar="MM", help=sigma_help)
    sub.add_argument("--test-poses", metavar="PLAN_CSV", help=test_help)
    sub.add_argument(
        "--max-poses", type=_poses, default=5000, metavar="M", help="give up beyond (default 5000)"
    )
    _add_fix(sub)
    _add_common(sub, seed=True, output="plan CSV of the plan that reaches the target")
    sub.set_defaults(run=_poses_needed, inputs=("robot", "test_poses"), outputs=("output",))

    sub = _command(subs, "reproduce")
    sub.add_argument(
        "--trials",
        type=_trials,
        default=10_000,
        metavar="N",
        help="Monte Carlo trials per configuration (default 10000, as in the paper)",
    )
    sub.add_argument(
        "--random-plans",
        type=_trials,
        default=10_000,
        metavar="N",
        help="random plans per study (default 10000, as in the paper)",
    )
    sub.add_argument("--seed", type=_seed, default=0, help="random seed >= 0 (default 0)")
    sub.add_argument("--json", action="store_true", help="print a JSON document on stdout")
    sub.add_argument("-o", "--output", required=True, metavar="DIR", help="folder to write")
    sub.set_defaults(run=_reproduce, outputs=("output",), folder_files=_REPRODUCE_FILES)

    sub = _command(subs, "check-compliance")
    sub.add_argument(
        "--trials",
        type=_trials,
        default=4000,
        metavar="N",
        help="Monte Carlo trials (default 4000)",
    )
    sub.add_argument("--seed", type=_seed, default=0, help="random seed >= 0 (default 0)")
    sub.add_argument("--json", action="store_true", help="print a JSON document on stdout")
    sub.set_defaults(run=_check_compliance)

    sub = _command(subs, "demo")
    sub.add_argument("--poses", type=_poses, default=20, help="number of poses (default 20)")
    sub.add_argument("--truth", metavar="TRUTH_TOML", help="deviations (default: the built-in's)")
    sub.add_argument("--sigma", type=_sigma, metavar="MM", help="noise std in mm")
    _add_common(sub, seed=True, output="folder for the report, figures and files")
    sub.set_defaults(
        run=_demo, inputs=("robot", "truth"), outputs=("output",), folder_files=DEMO_FILES
    )

    sub = _command(subs, "export")
    _add_calibration(sub)
    sub.add_argument("--robot-toml", metavar="PATH", help="robot TOML file to write")
    sub.add_argument("--urdf", metavar="PATH", help="URDF file to write")
    sub.set_defaults(run=_export, inputs=("calibration",), outputs=("robot_toml", "urdf"))

    sub = _command(subs, "formats")
    sub.set_defaults(run=_formats)
    return parser


_WORKFLOW = (
    "The workflow: write a robot file (armcal formats lists every key), design a plan "
    "(design; evaluate, simulate and poses-needed judge and size it), measure it, identify "
    "the deviations, validate them on held-out poses, then compensate programs or export the "
    "calibrated arm. 'armcal COMMAND --help' shows a command's files and an example; "
    "docs/guide.md walks through a whole calibration."
)


def _command(subs: Any, name: str) -> argparse.ArgumentParser:
    """The parser of command ``name``, with its help from :mod:`armcal.cli_help`."""
    parser: argparse.ArgumentParser = subs.add_parser(
        name,
        help=COMMANDS[name].summary,
        description=help_description(name),
        epilog=help_epilog(name),
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    return parser


def _option(dest: str) -> str:
    return "-o" if dest == "output" else "--" + dest.replace("_", "-")


def _check_stdio(args: argparse.Namespace, inputs: dict, outputs: dict) -> None:
    """``-`` reads stdin (one input) and writes stdout (one file output, instead of the report)."""
    piped = [option for option, path in inputs.items() if path == STDIO]
    if len(piped) > 1:
        raise ArmcalError(
            f"{' and '.join(piped)} both read '-' (stdin); pipe in one of them and give the "
            "other a file name"
        )
    to_stdout = [option for option, path in outputs.items() if path == STDIO]
    if not to_stdout:
        return
    if getattr(args, "folder_files", ()):
        raise ArmcalError(f"{to_stdout[0]} -: a folder cannot go to stdout; give a folder name")
    if "--plot" in to_stdout:
        raise ArmcalError("--plot -: a figure cannot go to stdout; give a PNG file name")
    if len(to_stdout) > 1:
        raise ArmcalError(
            f"{' and '.join(to_stdout)} both write '-' (stdout); give all but one a file name"
        )
    if getattr(args, "json", False):
        raise ArmcalError(
            f"--json and {to_stdout[0]} - both write stdout; drop --json (the file is the "
            "output) or give a file name"
        )
    args.stdout_taken = True


def _check_paths(args: argparse.Namespace) -> None:
    """Refuse the command's unusable output paths before it does any work."""
    inputs = {_option(dest): getattr(args, dest) for dest in getattr(args, "inputs", ())}
    if inputs.get("--robot") in BUILTIN_ROBOTS:
        del inputs["--robot"]  # a name, not a file
    folder_files = getattr(args, "folder_files", ())
    outputs: dict[str, str | OutputFolder | None] = {}
    for dest in getattr(args, "outputs", ()):
        path = getattr(args, dest)
        outputs[_option(dest)] = (
            OutputFolder(path, folder_files)
            if folder_files and path is not None and path != STDIO
            else path
        )
    _check_stdio(args, inputs, outputs)
    check_outputs(outputs, inputs)


def main(argv: Sequence[str] | None = None) -> int:
    """Run the ``armcal`` program; returns the exit status."""
    try:
        args = build_parser().parse_args(argv)
        _check_paths(args)
        run: Callable[[argparse.Namespace], None] = args.run
        run(args)
    except ArmcalError as exc:
        print(f"armcal: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:  # Ctrl-C: writers have removed their temporary files
        if sys.stderr.isatty():
            sys.stderr.write("\n")  # after a progress bar or the terminal's ^C
        print("armcal: interrupted", file=sys.stderr)
        return 130
    except BrokenPipeError:  # e.g. `armcal synthesize ... | head`
        sys.stderr.close()
        return 0
    return 0


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
