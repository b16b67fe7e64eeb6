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
from pathlib import Path
from typing import Any

import numpy as np

from .compensation import compensate
from .demo import Demo, figure_writer, report_head
from .doe import random_plan
from .errors import ACTIONS
from .export_spatial import joint_offsets_csv, spatial_robot_toml, spatial_urdf
from .families import RobotSpec
from .files import (
    calibration_document,
    format_measurements_csv,
    format_plan_csv,
    format_program_csv,
    to_json,
)
from .identification import identify
from .models import Conditions, SpatialArm
from .noise import NoiseModel, TrackerNoise
from .numerics import rms
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

#: Poses of the demo's plan (each measured at the three reflectors).
SPATIAL_DEMO_POSES = 60

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
    rng = np.random.default_rng(seed)
    labels = tuple(DEMO_REFLECTORS)
    noise = (
        NoiseModel.laser_tracker(DEMO_TRACKER)
        if sigma is None
        else NoiseModel.isotropic(sigma, dim=3)
    )
    model = arm.replace(
        targets=labels, target_positions=np.zeros((0, 3)), known_targets=False
    ).with_noise(noise)
    truth = truth_of(model.replace(target_positions=np.array(list(DEMO_REFLECTORS.values()))))

    def measure(q: np.ndarray) -> tuple[Conditions, np.ndarray, list[str], list[str]]:
        rows, pose_labels, targets = _rows(model, q)
        points = synthesize_measurements(model, rows.q, truth, rng=rng, target=rows.target)
        return rows, points, pose_labels, targets

    q = random_plan(model, poses, rng=rng)
    rows, points, pose_labels, targets = measure(q)
    cal = identify(model, rows.q, points, target=rows.target, pose_labels=pose_labels)
    calibrated = cal.calibrated()
    seen = cal.model.expressed(rows, truth)
    groups = np.repeat(np.arange(poses), len(labels))
    folds = cross_validate(
        model, rows.q, points, FOLDS, groups=groups, target=rows.target, rng=rng
    ).summary()

    q_test = random_plan(model, VALIDATION_POSES, rng=rng)
    test_rows, test_points, test_poses, test_targets = measure(q_test)
    check = validate(calibrated, test_rows.q, test_points, target=test_rows.target).summary()

    limits = model.limits
    program = rng.uniform(0.5 * limits[:, 0], 0.5 * limits[:, 1], (PROGRAM_POSES, arm.n_joints))
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

    before, after = true_error(program), true_error(comp.q)

    free = cal.model.free
    error = (cal.params - seen)[free] / cal.std[free]
    lines = [
        f"armcal demo on {arm.name}: a virtual six-axis arm, a laser tracker "
        f"{np.linalg.norm(truth[:3]) / 1000:.1f} m away, three reflectors, seed {seed}",
        "",
        f"1. plan: {poses} random poses within the limits, each measured at reflectors "
        f"{', '.join(labels)}: {rows.m} points",
        "2. identify, with no initial guess (the tracker's pose and the reflectors found "
        f"from the data): {cal.model.n_free} of {cal.model.n_params} parameters identifiable; "
        f"largest |estimate - truth| {np.max(np.abs(error)):.2g} std",
        "",
        format_calibration(cal, truth=seen, words=words),
        "",
        f"3. {format_cross_validation(folds)}",
        f"4. validate on {VALIDATION_POSES} fresh poses: position error RMS per point "
        f"{check['rms_before_per_point_mm']:.3g} mm nominal, "
        f"{check['rms_after_per_point_mm']:.3g} mm calibrated "
        f"(predicted {check['predicted_rms_after_per_point_mm']:.3g} mm with the noise)",
        f"5. compensate a {PROGRAM_POSES}-pose program for reflector A: "
        f"{int(comp.corrected.sum())} corrected; true error RMS {rms(before):.3g} mm before, "
        f"{rms(after):.3g} mm after",
        "6. export: arm.urdf (every zero in the joint origins), robot_calibrated.toml "
        "(modified DH table), joint_offsets.csv (the controller's zero offsets)",
    ]
    text = "\n".join(lines)

    def plot_residual_figure():
        from .plotting import plot_residuals

        return plot_residuals(cal.residuals, cal.sigma_mm, used=cal.used)

    document = calibration_document(cal, words=words)
    kinds = arm.joint_kinds
    files: dict[str, str | Callable[[Path], None]] = {
        "measurements.csv": format_measurements_csv(
            rows.q, points, pose_labels, targets, kinds=kinds
        ),
        "calibration.json": to_json(document),
        "validation.csv": format_measurements_csv(
            test_rows.q, test_points, test_poses, test_targets, kinds=kinds
        ),
        "program.csv": format_plan_csv(program, targets=["A"] * PROGRAM_POSES, kinds=kinds),
        "program_corrected.csv": format_program_csv(
            comp.q, comp.corrected, targets=["A"] * PROGRAM_POSES, kinds=kinds
        ),
        "robot_calibrated.toml": spatial_robot_toml(calibrated),
        "arm.urdf": spatial_urdf(calibrated),
        "joint_offsets.csv": joint_offsets_csv(calibrated),
        "residuals.png": figure_writer(plot_residual_figure),
    }
    report = "\n".join(
        [
            *report_head(arm.name, "A virtual six-axis arm with known errors", text),
            "![residuals](residuals.png)",
            "",
        ]
    )
    files["report.md"] = report
    return Demo(text, report, files, document, cal.warnings)


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
    )
    return result, DEMO_KINDS
