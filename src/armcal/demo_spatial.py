"""The six-axis story on a virtual arm: a laser tracker, three reflectors, a coupled J2/J3.

``armcal demo --robot industrial-6r`` (and ``make demo``) calibrates a built-in
spatial arm as a cell would: a tracker metres away in an unknown pose, a nest of
three reflectors whose positions on the flange nobody measured, a controller
that reads J3 against the horizon (the robot file's ``joint_map``).  Every step
is the library's own call; the truth is used only where a real user has none:
to draw the measurements, and to show what the corrected program really does.
Optimal designs for spatial arms are the next step; the plan here is random
within the limits.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from .choices import SPATIAL_DEMO_POSES
from .compensation import Compensation, compensate
from .demo import Demo, figure_writer, report_head
from .doe import random_plan
from .errors import ACTIONS
from .export_spatial import joint_offsets_csv, spatial_robot_toml, spatial_urdf
from .families import RobotSpec, family_of
from .files import (
    calibration_document,
    format_measurements_csv,
    format_plan_csv,
    format_program_csv,
    to_json,
)
from .identification import Calibration, identify
from .models import CalibratedArm, Conditions, SpatialArm
from .noise import NoiseModel, TrackerNoise
from .numerics import rms
from .progress import ProgressCallback, steps
from .report import format_calibration, format_cross_validation
from .synthesis import synthesize_measurements
from .validation import cross_validate, validate

__all__ = [
    "DEMO_REFLECTORS",
    "DEMO_TRACKER",
    "SPATIAL_DEMO_FILES",
    "SPATIAL_DEMO_POSES",
    "run_spatial_demo",
]

#: The story's stages, for a progress bar: measure, identify, validate, compensate, the
#: last check, the report.
DEMO_STEPS = 6

#: The three reflector nests on the flange (mm, flange frame): a plate 150 mm out, the
#: nests 100 mm apart; the fit is not told where they are.
DEMO_REFLECTORS = {
    "A": (100.0, 0.0, 150.0),
    "B": (-50.0, 86.6, 150.0),
    "C": (-50.0, -86.6, 150.0),
}

#: The virtual tracker's noise (1 std): range 8 um + 0.4 um/m, across the line of sight
#: 10 um + 2.5 um/m, of the size tracker data sheets give (half their 2-std figures).
DEMO_TRACKER = TrackerNoise(0.008, 0.0004, 0.010, 0.0025)

#: Cross-validation folds, poses of the fresh validation set and of the program.
FOLDS, VALIDATION_POSES, PROGRAM_POSES = 5, 100, 12

#: Every file the six-axis story writes.
SPATIAL_DEMO_FILES = (
    "measurements.csv",
    "calibration.json",
    "validation.csv",
    "program.csv",
    "program_corrected.csv",
    "robot_calibrated.toml",
    "arm.urdf",
    "joint_offsets.csv",
    "residuals.png",
    "report.md",
)


def _rows(arm: SpatialArm, q: np.ndarray) -> tuple[Conditions, list[str], list[str]]:
    """Every reflector of every pose: the rows, their pose labels and target labels."""
    rows = arm.plan_conditions(q)
    assert rows.target is not None
    poses = [f"P{i + 1}" for i in np.repeat(np.arange(q.shape[0]), len(arm.targets))]
    return rows, poses, [arm.targets[t] for t in rows.target]


def run_spatial_demo(
    arm: SpatialArm,
    truth_of: Callable[[SpatialArm], np.ndarray],
    *,
    poses: int = SPATIAL_DEMO_POSES,
    sigma: float | None = None,
    seed: int = 0,
    words: Mapping[str, str] = ACTIONS,
    progress: ProgressCallback | None = None,
) -> Demo:
    """Calibrate a virtual spatial arm from measurements to export; nothing is written here.

    Parameters
    ----------
    arm : SpatialArm
        The nominal arm (its joint map and limits).
    truth_of : callable
        The virtual arm's parameters for the arm with the demo's reflectors.
    poses : int
        Poses of the calibration plan (each measured at the three reflectors).
    sigma : float, optional
        Isotropic instrument noise (1 std, mm) in place of the tracker's model.
    seed : int
        Seeds every random draw.
    words : mapping, optional
        The words of the advice in the text and the calibration file's warnings
        (:func:`armcal.errors.render`; default the library's).
    """
    # One generator, drawn from in the story's order: plan, measurements, folds, fresh
    # poses and their measurements, program.
    rng = np.random.default_rng(seed)
    model = _tracked(arm, sigma)
    truth = truth_of(model.replace(target_positions=np.array(list(DEMO_REFLECTORS.values()))))
    step = steps(progress, DEMO_STEPS)
    measured = _measure(model, truth, random_plan(model, poses, rng=rng), rng)
    rows, points = measured.rows, measured.points
    step()
    cal = identify(model, rows.q, points, target=rows.target, pose_labels=measured.poses)
    step()
    calibrated = cal.calibrated()
    seen = cal.model.expressed(rows, truth)
    groups = np.repeat(np.arange(poses), len(DEMO_REFLECTORS))
    folds = cross_validate(
        model, rows.q, points, FOLDS, groups=groups, target=rows.target, rng=rng
    ).summary()
    step()
    fresh = _measure(model, truth, random_plan(model, VALIDATION_POSES, rng=rng), rng)
    check = validate(calibrated, fresh.rows.q, fresh.points, target=fresh.rows.target).summary()
    step()
    compensated = _compensate(model, calibrated, truth, seen, rng)
    step()
    story = _Story(measured, cal, seen, folds, fresh, check, compensated)
    text = "\n".join(_lines(arm, story, truth, poses=poses, seed=seed, words=words))
    document = calibration_document(cal, words=words)
    files = _files(arm, story, calibrated, to_json(document))
    report = "\n".join(
        [
            *report_head(arm.name, "A virtual six-axis arm with known errors", text),
            "![residuals](residuals.png)",
            "",
        ]
    )
    files["report.md"] = report
    step()
    return Demo(text, report, files, document, cal.warnings)


@dataclass(frozen=True, eq=False)
class _Measured:
    """Every reflector of every pose of a plan, measured on the virtual arm."""

    rows: Conditions
    points: np.ndarray
    poses: list[str]
    targets: list[str]


@dataclass(frozen=True, eq=False)
class _Compensated:
    """Step 5: a program for reflector A, its corrected commands and its true errors."""

    program: np.ndarray
    comp: Compensation
    before: np.ndarray
    after: np.ndarray


@dataclass(frozen=True, eq=False)
class _Story:
    """Every step's results, for the text and the files."""

    measured: _Measured
    cal: Calibration
    seen: np.ndarray
    folds: dict[str, Any]
    fresh: _Measured
    check: dict[str, Any]
    compensated: _Compensated


def _tracked(arm: SpatialArm, sigma: float | None) -> SpatialArm:
    """The arm with the demo's reflectors (positions unknown to the fit) and its tracker's
    noise, or an isotropic ``sigma``."""
    noise = (
        NoiseModel.laser_tracker(DEMO_TRACKER)
        if sigma is None
        else NoiseModel.isotropic(sigma, dim=3)
    )
    return arm.replace(
        targets=tuple(DEMO_REFLECTORS), target_positions=np.zeros((0, 3)), known_targets=False
    ).with_noise(noise)


def _measure(
    model: SpatialArm, truth: np.ndarray, q: np.ndarray, rng: np.random.Generator
) -> _Measured:
    """The plan ``q`` measured at every reflector on the virtual arm (``truth``)."""
    rows, poses, targets = _rows(model, q)
    points = synthesize_measurements(model, rows.q, truth, rng=rng, target=rows.target)
    return _Measured(rows, points, poses, targets)


def _compensate(
    model: SpatialArm,
    calibrated: CalibratedArm,
    truth: np.ndarray,
    seen: np.ndarray,
    rng: np.random.Generator,
) -> _Compensated:
    """Compensate a random program of :data:`PROGRAM_POSES` poses (within half the limits)
    taught for reflector A, and measure its true error before and after."""
    limits = model.limits
    program = rng.uniform(0.5 * limits[:, 0], 0.5 * limits[:, 1], (PROGRAM_POSES, model.n_joints))
    aim = np.zeros(PROGRAM_POSES, dtype=int)  # the program is taught for reflector A
    comp = compensate(calibrated, program, target=aim)
    # What really happens: the true arm at the commands, against where the nominal arm
    # would be, standing where the arm stands with the reflector it carries (the truth as
    # the fit sees it: joint 1's zero is a turn of the base, joint 6's a turn of the nest).
    meant = model.positions(
        model.conditions(program, target=aim), np.where(model.instrument_params, seen, 0.0)
    )

    def true_error(commands: np.ndarray) -> np.ndarray:
        reached = model.positions(model.conditions(commands, target=aim), truth)
        return np.linalg.norm(reached - meant, axis=1)

    return _Compensated(program, comp, true_error(program), true_error(comp.q))


def _lines(
    arm: SpatialArm,
    story: _Story,
    truth: np.ndarray,
    *,
    poses: int,
    seed: int,
    words: Mapping[str, str],
) -> list[str]:
    """The story as printed, step by step."""
    cal, check, compensated = story.cal, story.check, story.compensated
    free = cal.model.free
    error = (cal.params - story.seen)[free] / cal.std[free]
    return [
        f"armcal demo on {arm.name}: a virtual six-axis arm, a laser tracker "
        f"{np.linalg.norm(truth[:3]) / 1000:.1f} m away, three reflectors, seed {seed}",
        "",
        f"1. plan: {poses} random poses within the limits, each measured at reflectors "
        f"{', '.join(DEMO_REFLECTORS)}: {story.measured.rows.m} points",
        "2. identify, with no initial guess (the tracker's pose and the reflectors found "
        f"from the data): {cal.model.n_free} of {cal.model.n_params} parameters identifiable; "
        f"largest |estimate - truth| {np.max(np.abs(error)):.2g} std",
        "",
        format_calibration(cal, truth=story.seen, words=words),
        "",
        f"3. {format_cross_validation(story.folds)}",
        f"4. validate on {VALIDATION_POSES} fresh poses: position error RMS per point "
        f"{check['rms_before_per_point_mm']:.3g} mm nominal, "
        f"{check['rms_after_per_point_mm']:.3g} mm calibrated "
        f"(predicted {check['predicted_rms_after_per_point_mm']:.3g} mm with the noise)",
        f"5. compensate a {PROGRAM_POSES}-pose program for reflector A: "
        f"{int(compensated.comp.corrected.sum())} corrected; true error RMS "
        f"{rms(compensated.before):.3g} mm before, {rms(compensated.after):.3g} mm after",
        "6. export: arm.urdf (every zero in the joint origins), robot_calibrated.toml "
        "(modified DH table), joint_offsets.csv (the controller's zero offsets)",
    ]


def _files(
    arm: SpatialArm, story: _Story, calibrated: CalibratedArm, calibration_json: str
) -> dict[str, str | Callable[[Path], None]]:
    """Every file of :data:`SPATIAL_DEMO_FILES` but ``report.md``, by name."""
    cal, measured, fresh, compensated = story.cal, story.measured, story.fresh, story.compensated

    def plot_residual_figure():
        return family_of(cal.model).role("residual_figure")(cal)

    kinds = arm.joint_kinds
    aimed = ["A"] * PROGRAM_POSES
    return {
        "measurements.csv": format_measurements_csv(
            measured.rows.q, measured.points, measured.poses, measured.targets, kinds=kinds
        ),
        "calibration.json": calibration_json,
        "validation.csv": format_measurements_csv(
            fresh.rows.q, fresh.points, fresh.poses, fresh.targets, kinds=kinds
        ),
        "program.csv": format_plan_csv(compensated.program, targets=aimed, kinds=kinds),
        "program_corrected.csv": format_program_csv(
            compensated.comp.q, compensated.comp.corrected, targets=aimed, kinds=kinds
        ),
        "robot_calibrated.toml": spatial_robot_toml(calibrated),
        "arm.urdf": spatial_urdf(calibrated),
        "joint_offsets.csv": joint_offsets_csv(calibrated),
        "residuals.png": figure_writer(plot_residual_figure),
    }


#: What the six-axis demo writes, for the line that says so.
DEMO_KINDS = "report.md, residuals, measurements, calibration, program, URDF, DH table, offsets"


def spatial_demo(
    robot: RobotSpec[SpatialArm],
    truth_of: Callable[[Any], np.ndarray],
    *,
    poses: int | None = None,
    sigma: float | None = None,
    seed: int = 0,
    words: Mapping[str, str] = ACTIONS,
    progress: ProgressCallback | None = None,
) -> tuple[Any, str]:
    """The six-axis story (:func:`armcal.demo_spatial.run_spatial_demo`): a tracker and
    three reflectors; and what it writes."""
    result = run_spatial_demo(
        robot.arm,
        truth_of,
        poses=SPATIAL_DEMO_POSES if poses is None else poses,
        sigma=sigma,
        seed=seed,
        words=words,
        progress=progress,
    )
    return result, DEMO_KINDS
