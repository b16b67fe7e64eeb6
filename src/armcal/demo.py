"""The whole story on a virtual robot: design, measure, identify, validate, compensate, export.

``armcal demo`` (and ``make demo``) runs it on the default robot with the
paper's deviations as the truth.  Every step is the library's own call, and the
truth is used only where a real user has none: to draw the measurements, and
to show, next to what the calibration predicts, what really happened.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from .choices import PLANAR_DEMO_POSES
from .compensation import Compensation, compensate
from .doe import Design, design, random_plan
from .errors import ACTIONS, ArmcalWarning
from .export_planar import robot_toml, urdf
from .families import RobotSpec, family_of
from .files import (
    calibration_document,
    format_measurements_csv,
    format_plan_csv,
    format_program_csv,
    to_json,
)
from .identification import Calibration, identify
from .models import CalibratedArm, PlanarArm, forward_kinematics
from .numerics import rms
from .progress import ProgressCallback, steps
from .report import format_calibration
from .synthesis import synthesize_measurements
from .validation import Validation, validate
from .workflow.setup import design_sigma

__all__ = [
    "DEMO_FILES",
    "OUTLIER_MM",
    "PLANAR_DEMO_POSES",
    "Demo",
    "demo_rigid_warning",
    "figure_writer",
    "report_head",
    "run_demo",
]

#: The story's stages, for a progress bar: measure, identify, validate, compensate, the
#: last check, the report.
DEMO_STEPS = 6

#: The gross error put on one measurement (a bumped reflector), mm in x and y.
OUTLIER_MM = (1.2, -0.9)

#: Poses of the fresh validation set, of the program compensated, of the error map.
VALIDATION_POSES, PROGRAM_POSES, MAP_POSES = 100, 12, 2000

#: Every file ``demo -o DIR`` writes.
DEMO_FILES = (
    "plan.csv",
    "measurements.csv",
    "calibration.json",
    "validation.csv",
    "program.csv",
    "program_corrected.csv",
    "robot_calibrated.toml",
    "arm.urdf",
    "plan.png",
    "residuals.png",
    "validation.png",
    "error_map.png",
    "report.md",
)


@dataclass(frozen=True, eq=False)
class Demo:
    """What the demo did: the text it prints, its files, its warnings.

    Attributes
    ----------
    text : str
        The story, step by step, as printed.
    report : str
        ``report.md``: the same with the figures and the parameter table.
    files : dict of str to str or callable
        File name to its text, or to a function writing the figure to a path.
    document : dict
        The calibration document (JSON) of the identification.
    warnings : tuple of ArmcalWarning
        The calibration's warnings (the outlier among them).
    """

    text: str
    report: str
    files: dict[str, str | Callable[[Path], None]]
    document: dict
    warnings: tuple[ArmcalWarning, ...]


def demo_rigid_warning(name: str) -> ArmcalWarning:
    """``demo-rigid``: the demo of robot ``name``, whose file has ``[elastostatic]``,
    calibrates its geometry alone (every family: the demo's arm is rigid)."""
    return ArmcalWarning(
        "demo-rigid",
        f"the demo calibrates the geometry of {name} alone: its joint compliance "
        "([elastostatic], and a truth's compliance) is left out of the virtual arm and of "
        "the fit; synthesize, identify and validate take it",
    )


def figure_writer(make: Callable[[], object]) -> Callable[[Path], None]:
    """A writer that draws the figure only when the file is written (matplotlib is lazy)."""

    def write(path: Path) -> None:
        from .plotting import save_figure

        save_figure(make(), path)  # type: ignore[arg-type]

    return write


def run_demo(
    arm: PlanarArm,
    truth: np.ndarray,
    *,
    poses: int = PLANAR_DEMO_POSES,
    sigma: float = 0.1,
    seed: int = 0,
    words: Mapping[str, str] = ACTIONS,
    progress: ProgressCallback | None = None,
) -> Demo:
    """Calibrate a virtual robot from design to export; nothing is written here.

    Parameters
    ----------
    arm : PlanarArm
        The nominal arm (its joint limits and region constrain the plan).
    truth : ndarray, shape (p,)
        The virtual robot's deviations (mm, rad).
    poses : int
        Poses of the calibration plan.
    sigma : float
        Instrument noise (1 std, mm) of the virtual measurements, known to the fit.
    seed : int
        Seeds every random draw.
    words : mapping, optional
        The words of the advice in the text and the calibration file's warnings
        (:func:`armcal.errors.render`; default the library's).

    Returns
    -------
    Demo
    """
    # One generator, drawn from in the story's order: plan, measurements, validation,
    # program, error map.
    rng = np.random.default_rng(seed)
    model = arm.replace(sigma=sigma)
    step = steps(progress, DEMO_STEPS)
    measured = _measure(arm, model, truth, poses, sigma, rng)
    step()
    cal = identify(model, measured.plan.q, measured.xy, robust=True, pose_labels=measured.labels)
    step()
    calibrated = cal.calibrated()
    document = calibration_document(cal, words=words)
    validated = _validate(arm, calibrated, truth, sigma, rng)
    step()
    compensated = _compensate(arm, calibrated, truth, rng)
    step()
    error_map = _error_map(arm, cal.params, truth, rng)
    step()
    story = _Story(measured, cal, calibrated, validated, compensated, error_map)
    text = "\n".join(_lines(arm, story, truth, sigma=sigma, seed=seed, words=words))
    files = _files(arm, story, to_json(document))
    report = _report(arm, text, error_map.before, error_map.after)
    files["report.md"] = report
    step()
    return Demo(text, report, files, document, cal.warnings)


@dataclass(frozen=True, eq=False)
class _Measured:
    """Step 1 and 2: the designed plan and its virtual measurements, one of them bumped."""

    plan: Design
    xy: np.ndarray
    labels: list[str]
    bumped: int


@dataclass(frozen=True, eq=False)
class _Validated:
    """Step 4: fresh poses, their measurements and the calibrated arm's errors there."""

    q: np.ndarray
    xy: np.ndarray
    validation: Validation


@dataclass(frozen=True, eq=False)
class _Compensated:
    """Step 5: a program, its corrected commands and its true errors before and after."""

    program: np.ndarray
    comp: Compensation
    true_before: np.ndarray
    true_after: np.ndarray


@dataclass(frozen=True, eq=False)
class _ErrorMap:
    """The true position error over the workspace, nominal and calibrated."""

    q: np.ndarray
    real: np.ndarray
    before: np.ndarray
    after: np.ndarray


@dataclass(frozen=True, eq=False)
class _Story:
    """Every step's results, for the text and the files."""

    measured: _Measured
    cal: Calibration
    calibrated: CalibratedArm
    validated: _Validated
    compensated: _Compensated
    error_map: _ErrorMap


def _measure(
    arm: PlanarArm,
    model: PlanarArm,
    truth: np.ndarray,
    poses: int,
    sigma: float,
    rng: np.random.Generator,
) -> _Measured:
    """Design the plan of ``poses`` poses and measure it on the virtual arm, one
    measurement moved by :data:`OUTLIER_MM` (a reflector knocked)."""
    plan = design(model, poses, rng=rng)
    xy = synthesize_measurements(arm, plan.q, truth, sigma, rng=rng)
    bumped = poses // 3
    xy[bumped] += OUTLIER_MM
    return _Measured(plan, xy, [str(i + 1) for i in range(poses)], bumped)


def _validate(
    arm: PlanarArm,
    calibrated: CalibratedArm,
    truth: np.ndarray,
    sigma: float,
    rng: np.random.Generator,
) -> _Validated:
    """Measure :data:`VALIDATION_POSES` fresh random poses and validate the calibration there."""
    q_test = random_plan(arm, VALIDATION_POSES, rng=rng)
    xy_test = synthesize_measurements(arm, q_test, truth, sigma, rng=rng)
    return _Validated(q_test, xy_test, validate(calibrated, q_test, xy_test))


def _compensate(
    arm: PlanarArm, calibrated: CalibratedArm, truth: np.ndarray, rng: np.random.Generator
) -> _Compensated:
    """Compensate a random program of :data:`PROGRAM_POSES` poses (within 80 % of the
    limits) and measure its true error, the nominal arm's point the goal."""
    limits = arm.joint_limits
    program = rng.uniform(0.8 * limits[:, 0], 0.8 * limits[:, 1], (PROGRAM_POSES, arm.n_joints))
    comp = compensate(calibrated, program)
    goal = forward_kinematics(arm, program)
    true_before = np.linalg.norm(forward_kinematics(arm, program, truth) - goal, axis=1)
    true_after = np.linalg.norm(forward_kinematics(arm, comp.q, truth) - goal, axis=1)
    return _Compensated(program, comp, true_before, true_after)


def _error_map(
    arm: PlanarArm, params: np.ndarray, truth: np.ndarray, rng: np.random.Generator
) -> _ErrorMap:
    """The true position error at :data:`MAP_POSES` random poses, of the nominal arm and
    of the one with the identified ``params``."""
    q_map = random_plan(arm, MAP_POSES, rng=rng)
    real = forward_kinematics(arm, q_map, truth)
    before = np.linalg.norm(real - forward_kinematics(arm, q_map), axis=1)
    after = np.linalg.norm(real - forward_kinematics(arm, q_map, params), axis=1)
    return _ErrorMap(q_map, real, before, after)


def _lines(
    arm: PlanarArm,
    story: _Story,
    truth: np.ndarray,
    *,
    sigma: float,
    seed: int,
    words: Mapping[str, str],
) -> list[str]:
    """The story as printed, step by step."""
    plan, cal = story.measured.plan, story.cal
    poses = plan.q.shape[0]
    check = story.validated.validation.summary()
    comp = story.compensated.comp
    predicted = comp.summary()
    cert = plan.certificate
    certified = "" if cert is None else f", certified >= {cert.certified_d_efficiency:.4f}"
    travel = (
        f"; ordered for joint travel {np.degrees(plan.joint_travel):.0f} deg "
        f"({np.degrees(plan.joint_travel_unordered):.0f} deg as designed)"
    )
    outliers = [o for o in cal.outliers if o.removed]
    found = ", ".join(f"pose {o.pose} ({o.residual_mm:.3g} mm)" for o in outliers) or "none found"
    return [
        f"armcal demo on {arm.name}: a virtual arm with the paper's deviations, noise "
        f"sigma {sigma:g} mm, seed {seed}",
        "",
        f"1. design: {poses} poses, method {plan.method}, D-efficiency "
        f"{plan.d_efficiency:.4f}{certified}{travel}",
        f"2. measure: {poses} poses with noise; pose {story.measured.bumped + 1} moved by "
        f"{np.hypot(*OUTLIER_MM):.2g} mm (a bumped reflector)",
        f"3. identify (robust): outliers left out: {found}",
        "",
        format_calibration(cal, truth=truth, words=words),
        "",
        f"4. validate on {VALIDATION_POSES} fresh poses: position error RMS per point "
        f"{check['rms_before_per_point_mm']:.3g} mm nominal, "
        f"{check['rms_after_per_point_mm']:.3g} mm calibrated "
        f"(predicted {check['predicted_rms_after_per_point_mm']:.3g} mm with the noise)",
        f"5. compensate a {PROGRAM_POSES}-pose program: {int(comp.corrected.sum())} corrected; "
        f"true error RMS per point {rms(story.compensated.true_before):.3g} mm before, "
        f"{rms(story.compensated.true_after):.3g} mm after (predicted "
        f"{predicted['rms_before_per_point_mm']:.3g} "
        f"and {predicted['rms_after_per_point_mm']:.3g} mm)",
        "6. export: robot_calibrated.toml (a robot file with the deviations folded in), "
        "arm.urdf (ROS)",
    ]


def _figures(arm: PlanarArm, story: _Story) -> dict[str, str | Callable[[Path], None]]:
    """The story's four figures, each drawn only when its file is written."""
    q, cal = story.measured.plan.q, story.cal
    validated, error_map = story.validated, story.error_map

    def plot_plan_figure():
        from .plotting import plot_plan

        return plot_plan(arm, q, numbers=True, title=f"{arm.name}: the {q.shape[0]}-pose plan")

    def plot_residual_figure():
        return family_of(cal.model).role("residual_figure")(cal)

    def plot_validation_figure():
        from .plotting import plot_validation

        return plot_validation(arm, validated.q, validated.validation)

    def plot_map_figure():
        from .plotting import plot_error_map

        return plot_error_map(arm, error_map.q, error_map.before, error_map.after, error_map.real)

    return {
        "plan.png": figure_writer(plot_plan_figure),
        "residuals.png": figure_writer(plot_residual_figure),
        "validation.png": figure_writer(plot_validation_figure),
        "error_map.png": figure_writer(plot_map_figure),
    }


def _files(
    arm: PlanarArm, story: _Story, calibration_json: str
) -> dict[str, str | Callable[[Path], None]]:
    """Every file of :data:`DEMO_FILES` but ``report.md``, by name."""
    q, measured = story.measured.plan.q, story.measured
    compensated, calibrated = story.compensated, story.calibrated
    return {
        "plan.csv": format_plan_csv(q),
        "measurements.csv": format_measurements_csv(q, measured.xy, measured.labels),
        "calibration.json": calibration_json,
        "validation.csv": format_measurements_csv(story.validated.q, story.validated.xy),
        "program.csv": format_plan_csv(compensated.program),
        "program_corrected.csv": format_program_csv(
            compensated.comp.q, compensated.comp.corrected
        ),
        "robot_calibrated.toml": robot_toml(calibrated),
        "arm.urdf": urdf(calibrated),
        **_figures(arm, story),
    }


def report_head(name: str, what: str, text: str) -> list[str]:
    """The opening lines of a demo's ``report.md``: its title and the story as printed."""
    return [
        f"# armcal demo: calibrating {name}",
        "",
        f"{what} is calibrated as a real one would be. "
        "Every number below was computed by this run (`armcal demo`).",
        "",
        "```text",
        text,
        "```",
        "",
    ]


def _report(arm: PlanarArm, text: str, before: np.ndarray, after: np.ndarray) -> str:
    """``report.md``: the story, its figures and what every file is."""
    return "\n".join(
        [
            *report_head(arm.name, "A virtual arm with known deviations", text),
            "## The plan",
            "",
            "Every pose drawn as the nominal arm, numbered in the order the file lists them.",
            "",
            "![plan](plan.png)",
            "",
            "## Residuals of the fit",
            "",
            "Every pose's residual after the robust fit; the bumped measurement stands out "
            "and is left out.",
            "",
            "![residuals](residuals.png)",
            "",
            "## Validation on fresh poses",
            "",
            "![validation](validation.png)",
            "",
            "## Error over the workspace",
            "",
            f"The true position error of the nominal model (RMS {rms(before):.3g} mm per point) "
            f"and of the calibrated one (RMS {rms(after):.3g} mm per point) at {before.size} "
            "random poses.",
            "",
            "![error map](error_map.png)",
            "",
            "## Files",
            "",
            "| file | what |",
            "| --- | --- |",
            "| plan.csv | the designed plan |",
            "| measurements.csv | the virtual measurements (one bumped) |",
            "| calibration.json | the calibration (armcal-calibration/1) |",
            "| validation.csv | fresh measurements for `armcal validate` |",
            "| program.csv, program_corrected.csv | a program and its corrected commands |",
            "| robot_calibrated.toml | the calibrated arm as a robot file |",
            "| arm.urdf | the calibrated arm for ROS |",
            "",
        ]
    )


#: What the planar demo writes, for the line that says so.
DEMO_KINDS = "report.md, figures, plan, measurements, calibration, program, robot file, URDF"


def planar_demo(
    robot: RobotSpec[PlanarArm],
    truth_of: Callable[[Any], np.ndarray],
    *,
    poses: int | None = None,
    sigma: float | None = None,
    seed: int = 0,
    words: Mapping[str, str] = ACTIONS,
    progress: ProgressCallback | None = None,
) -> tuple[Any, str]:
    """The planar story (:func:`armcal.demo.run_demo`) and what it writes."""
    truth_ = truth_of(robot.arm)
    sigma = design_sigma(robot.arm) if sigma is None else sigma
    poses = PLANAR_DEMO_POSES if poses is None else poses
    result = run_demo(
        robot.arm, truth_, poses=poses, sigma=sigma, seed=seed, words=words, progress=progress
    )
    return result, DEMO_KINDS
