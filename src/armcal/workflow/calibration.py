"""Calibrating from measurement files, and what a calibration buys, as library calls.

What ``identify``, ``validate`` and ``compensate`` do beyond reading and writing
files: the model the data need (targets, the base pose of 3-D data), the checks
that turn a unit mistake into an error instead of a calibration
(:mod:`armcal.plausibility`), the 3-D path (:func:`armcal.instrument.identify_3d`),
cross-validation, and every warning of the run, once each.  A Python user gets
the same checks and warnings as the command line.

Errors name the file they concern (``source``).
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Any, TypeVar

import numpy as np

from ..acceptance import (
    PoseCharacteristics,
    pose_characteristics,
    pose_characteristics_warnings,
)
from ..compensation import Compensation, Payload, compensate
from ..errors import (
    ArmcalError,
    ArmcalWarning,
    InputError,
    NotIdentifiableError,
    action,
    unique_warnings,
    unrendered,
)
from ..export import robot_toml, urdf, urdf_joints_are_readings
from ..export_rigid import RigidExport, rigid_export, rigid_export_warnings
from ..export_serial import joint_offsets_csv, serial_robot_toml, serial_urdf
from ..files import Measurements, Program, RobotSpec, SerialSpec
from ..files.ur import (
    FAR_FROM_NOMINAL_MM,
    UrDh,
    format_ur_calibration,
    format_ur_kinematics,
    ur_deltas,
    ur_frames,
    ur_model_of,
)
from ..identification import Calibration, identify
from ..identification.experiment import coverage, plan_degenerate_warning
from ..instrument import identify_3d
from ..models import CalibratedArm, FitModel, Loads, PlanarArm, SerialChain, SpatialArm, Target
from ..plausibility import deviation_warning, explain, suspicious, unit_mistake
from ..progress import ProgressCallback
from ..validation import (
    CrossValidation,
    Validation,
    cross_validate,
    cross_validation_warnings,
    validate,
    validation_warnings,
)
from .payloads import payload_extrapolated, payload_missing, payload_unit
from .setup import FixError, fit_model, model_spec, prefixed

__all__ = [
    "CalibrationRun",
    "CompensationRun",
    "ExportRun",
    "ValidationRun",
    "calibrate",
    "calibrate_serial",
    "compensate_program",
    "export_files",
    "measured_arm",
    "serial_arm",
    "validate_measurements",
]


@dataclass(frozen=True, eq=False)
class CalibrationRun:
    """A calibration from a measurement file, with every warning of the run.

    Attributes
    ----------
    calibration : Calibration
    warnings : tuple of ArmcalWarning
        The robot file's, the measurement file's, the plausibility checks' and
        the calibration's, once each.
    cross_validation : CrossValidation or None
        With ``folds``: every pose predicted by a calibration made without it.
    """

    calibration: Calibration
    warnings: tuple[ArmcalWarning, ...]
    cross_validation: CrossValidation | None = None


def measured_arm(arm: PlanarArm, meas: Measurements) -> PlanarArm:
    """The arm to identify from ``meas``: its targets are those measured.

    With a ``target`` column, the targets are the labels measured, in the order
    of the robot file's ``[targets]`` (nominal last link from there) or, without
    one, in the order they first appear (nominal: the last link's length, angle
    0).  With a ``z_mm`` column the base pose in the fitted plane is identified:
    base offset and base rotation (:mod:`armcal.instrument`).

    Raises
    ------
    InputError
        For an arm with targets and data without a target column.
    """
    changes: dict[str, Any] = {}
    if meas.targets is not None:
        seen = list(dict.fromkeys(meas.targets))
        if arm.targets:
            targets = tuple(t for t in arm.targets if t.label in seen)
        else:
            targets = tuple(Target(label, float(arm.link_lengths[-1])) for label in seen)
        if targets != arm.targets:
            changes["targets"] = targets
    elif arm.targets:
        raise InputError(
            f"{arm.name} has targets ({', '.join(arm.target_labels)}) but the measurements have "
            "no target column; add a column 'target' naming the target of every row"
        )
    if meas.z is not None:
        changes.update(base_offset=True, base_rotation=True)
    if not changes:
        return arm
    try:  # the fixed parameters that still exist are carried over
        return arm.replace(**changes)
    except ValueError as exc:
        raise InputError(f"{arm.name}: {unrendered(exc)}") from None


def _row_targets(arm: PlanarArm | SpatialArm, meas: Measurements) -> np.ndarray | None:
    """Every row's target index, for an arm with targets (None without)."""
    if meas.targets is None or not arm.target_labels:
        return None
    return arm.target_index(meas.targets)


def row_loads(model: FitModel, meas: Measurements) -> Loads | None:
    """The rows' loads for a model they move (payload column or the model's default)."""
    default = model.default_payload_kg
    return None if default is None else meas.loads(default)


def _explained(source: str, arm: PlanarArm, meas: Measurements) -> InputError | None:
    """The error for data that another reading fits far better (:mod:`armcal.plausibility`)."""
    found = explain(arm, meas.q, meas.xy)
    return None if found is None else InputError(f"{source}: {found.message}")


def _identify_file(
    spec: RobotSpec, arm: PlanarArm, source: str, meas: Measurements, **options: Any
) -> Calibration:
    """Identify from a measurement file; data that look like a unit mistake are an error.

    3-D data (a ``z_mm`` column) are fitted with their plane first.  Units are
    checked before the fit for every model (:func:`_unit_mistake`); the checks that
    refit the plain 2-D model (a missing base offset too) are skipped for data with
    several targets, in 3-D or with compliance.
    """
    elastic = spec.elastic
    plain = meas.z is None and arm.n_target_links == 1 and not arm.targets and elastic is None
    options.update(
        pose_labels=meas.labels,
        rows=meas.rows,
        row_sigma=meas.row_sigma,
        target=_row_targets(arm, meas),
    )
    try:
        loads = None if elastic is None else meas.loads(elastic.payload_kg)
        model = fit_model(spec, arm, loads)
        options["loads"] = loads
        mistake = _unit_mistake(model, meas, options["target"], loads)
        if mistake is not None:
            raise InputError(mistake)  # named with the file below
        if meas.z is not None:
            options["gravity_3d"] = spec.gravity_3d
            cal = identify_3d(model, meas.q, meas.xyz, **options)
        else:
            cal = identify(model, meas.q, meas.xy, **options)
    except NotIdentifiableError as exc:
        # Angles in radians read as degrees put every pose near the stretched arm.
        unit = _explained(source, arm, meas) if plain else None
        if unit is not None:
            raise unit from None
        raise prefixed(source, exc) from None
    except ArmcalError as exc:
        raise prefixed(source, exc) from None
    if plain and suspicious(cal):
        unit = _explained(source, arm, meas)
        if unit is not None:
            raise unit
    return cal


def _unit_mistake(
    model: FitModel, meas: Measurements, target: np.ndarray | None, loads: Loads | None
) -> str | None:
    """What in ``meas`` looks like a unit mistake for ``model`` (:func:`unit_mistake`), checked
    before the fit: positions in metres or another unit, angles in radians (joints, a
    6-DoF instrument's orientations)."""
    points = meas.xy if meas.z is None else meas.xyz
    return unit_mistake(
        model, meas.q, points, target=target, loads=loads, orientations=meas.orientation
    )


def _ignored_loads(
    spec: RobotSpec | SerialSpec, meas: Measurements, source: str, compliance: bool
) -> list[ArmcalWarning]:
    """A warning when the data carry loads that a rigid model cannot use."""
    if (spec.elastic is not None and compliance) or not meas.has_loads:
        return []
    if spec.elastic is not None:
        why = f"{action('geometry-only')}; leave it out to fit the joints' compliance"
    else:
        why = "the robot file has no [elastostatic] table; add one to fit the joints' compliance"
    return [_loads_ignored_warning(source, why)]


def _loads_ignored_warning(source: str, why: str) -> ArmcalWarning:
    """``loads-ignored``: the rows' payloads and tip forces are not used, and ``why``."""
    return ArmcalWarning(
        "loads-ignored", f"{source}: the payload_kg/fx_N/fy_N columns are not used: {why}"
    )


#: A robot file of either family.
_Spec = TypeVar("_Spec", RobotSpec, SerialSpec)


def calibrate(
    spec: RobotSpec,
    meas: Measurements,
    *,
    source: str = "measurements",
    fixed: tuple[str, ...] | None = None,
    sigma: float | None = None,
    method: str = "auto",
    robust: bool = False,
    compliance: bool = True,
    folds: int | None = None,
    seed: int | np.random.Generator | None = 0,
    progress: ProgressCallback | None = None,
) -> CalibrationRun:
    """Calibrate the robot of ``spec`` from measurements, with every check and warning.

    Parameters
    ----------
    spec : RobotSpec
        The robot file (:func:`armcal.files.load_robot`).
    meas : Measurements
        The measurement file (:func:`armcal.files.read_measurements`).
    source : str
        The measurement file's name, for error messages.
    fixed : tuple of str, optional
        Parameters held at nominal, replacing the robot file's set: the arm's, and
        the joint compliance's terms held at zero.
    sigma : float, optional
        Isotropic instrument noise (mm), replacing the robot file's and any
        ``sigma_mm`` column.
    method, robust
        As for :func:`armcal.identification.identify`.
    compliance : bool
        Fit the joint compliance of a robot file with ``[elastostatic]`` (False:
        the geometry alone).
    folds : int, optional
        K-fold cross-validation.
    seed
        Shuffles the folds.
    progress : callable, optional
        ``progress(done, folds)`` as the cross-validation's folds finish
        (:mod:`armcal.progress`).

    Returns
    -------
    CalibrationRun

    Raises
    ------
    InputError
        For data the robot does not fit: a missing target column, or data that
        another reading (a unit mistake, a missing base offset) fits far better.
    NotIdentifiableError
        If the poses cannot identify every free parameter.
    """
    try:
        structure = measured_arm(spec.arm, meas)
    except InputError as exc:
        raise prefixed(source, exc) from None
    spec, meas, ignored = _as_asked(spec, meas, source, sigma, compliance)
    spec, arm = model_spec(spec, structure, fixed=fixed, sigma=sigma)
    cal = _identify_file(spec, arm, source, meas, method=method, robust=robust)
    large = deviation_warning(cal.model, cal.params)
    points = None
    if folds is not None:  # the fitted points: a 3-D file's in its plane
        points = meas.xy if cal.plane is None else cal.plane.to_plane(meas.xyz)
    return _calibration_run(
        cal, spec, meas, points, ignored, large, folds, sigma, seed, source, progress=progress
    )


def _as_asked(
    spec: _Spec, meas: Measurements, source: str, sigma: float | None, compliance: bool
) -> tuple[_Spec, Measurements, list[ArmcalWarning]]:
    """The robot file and the measurements as the options ask: a given ``sigma`` replaces
    the file's ``sigma_mm`` column too, and without ``compliance`` the arm is rigid (the
    data's loads then ``loads-ignored``)."""
    if sigma is not None:
        meas = replace(meas, row_sigma=None)
    ignored = _ignored_loads(spec, meas, source, compliance)
    return (spec if compliance else replace(spec, elastic=None)), meas, ignored


def _calibration_run(
    cal: Calibration,
    spec: RobotSpec | SerialSpec,
    meas: Measurements,
    points: np.ndarray | None,
    ignored: list[ArmcalWarning],
    large: ArmcalWarning | None,
    folds: int | None,
    sigma: float | None,
    seed: int | np.random.Generator | None,
    source: str,
    *,
    progress: ProgressCallback | None = None,
) -> CalibrationRun:
    """The run of ``cal``: what the robot file, the measurements (of ``source``; their
    payloads too: :mod:`armcal.workflow.payloads`), the options (``ignored``) and the fit
    warn of, ``large`` unless the fit warned of it, and the cross-validation of ``folds``
    on the fitted ``points`` (given with ``folds``)."""
    warnings = [*spec.warnings, *meas.warnings, *ignored, *cal.warnings]
    for found in (
        payload_unit(cal.model, meas.payload_kg, source),
        payload_missing(cal.model, meas.payload_kg, cal.warnings, source),
    ):
        if found is not None:
            warnings.append(found)
    if large is not None and all(w.code != large.code for w in warnings):
        warnings.append(large)
    checked = None
    if folds is not None:
        assert points is not None
        checked = _cross_validated(cal, meas, points, folds, sigma, seed, warnings, progress)
    return CalibrationRun(cal, tuple(unique_warnings(warnings)), checked)


def _cross_validated(
    cal: Calibration,
    meas: Measurements,
    points: np.ndarray,
    folds: int,
    sigma: float | None,
    seed: int | np.random.Generator | None,
    warnings: list[ArmcalWarning],
    progress: ProgressCallback | None = None,
) -> CrossValidation:
    """K-fold cross-validation of ``cal`` on its ``points``; its warning joins ``warnings``."""
    conditions = cal.conditions
    checked = cross_validate(
        cal.model,
        meas.q,
        points,
        folds,
        groups=None if meas.targets is None else np.array(meas.labels),
        target=cal.target,
        sigma=sigma,
        row_sigma=meas.row_sigma,
        rng=seed,
        loads=None if conditions is None else conditions.loads,
        progress=progress,
    )
    warnings.extend(cross_validation_warnings(checked))
    return checked


def serial_arm(arm: SpatialArm, meas: Measurements) -> SpatialArm:
    """The spatial arm to identify from ``meas``: its targets are those measured, in the
    robot file's order (their nominal positions from there) or in the order they appear.

    Raises InputError for data without ``z_mm`` or without the targets the robot file has.
    """
    if meas.z is None:
        raise InputError(
            f"{arm.name} is a spatial arm: its measurements need x_mm, y_mm and z_mm; add the "
            "z_mm column the instrument reports"
        )
    oriented = meas.orientation is not None
    if oriented and (arm.noise is None or arm.noise.orientation_sigma is None):
        raise InputError(
            f"the measurements have orientation columns (rx_deg, ry_deg, rz_deg) but "
            f"{arm.name}'s robot file does not give their noise; add orientation_sigma_deg "
            "(and the position noise) to its [measurement] table"
        )
    arm = arm.replace(oriented=oriented, view=None)  # the view is for plans, not data
    if meas.targets is None:
        if arm.target_labels:
            raise InputError(
                f"{arm.name} has targets ({', '.join(arm.target_labels)}) but the measurements "
                "have no target column; add a column 'target' naming the target of every row"
            )
        return arm
    seen = list(dict.fromkeys(meas.targets))
    if arm.known_targets:
        keep = [i for i, label in enumerate(arm.targets) if label in seen]
        labels = tuple(arm.targets[i] for i in keep)
        return arm.replace(targets=labels, target_positions=arm.target_positions[keep])
    return arm.replace(targets=tuple(seen), target_positions=np.zeros((0, 3)))


def calibrate_serial(
    spec: SerialSpec,
    meas: Measurements,
    *,
    source: str = "measurements",
    fixed: tuple[str, ...] | None = None,
    sigma: float | None = None,
    method: str = "auto",
    robust: bool = False,
    folds: int | None = None,
    seed: int | np.random.Generator | None = 0,
    compliance: bool = True,
    progress: ProgressCallback | None = None,
) -> CalibrationRun:
    """:func:`calibrate` for a spatial arm: the same options, checks and warnings.

    The base pose and the targets are found from the data (no start from the
    user); the identifiable set is chosen for these measurements and named.
    With ``[elastostatic]`` (and ``compliance``) the joints' compliance is
    fitted with the geometry, under the rows' payloads.
    """
    spec, meas, ignored = _as_asked(spec, meas, source, sigma, compliance)
    try:
        spec, arm = model_spec(spec, serial_arm(spec.arm, meas), fixed=fixed, sigma=sigma)
        points = meas.instrument_points  # 3-D: serial_arm refuses data without z_mm
        index = None if meas.targets is None else arm.target_index(meas.targets)
        loads = None if spec.elastic is None else meas.loads(spec.elastic.payload_kg)
        model = fit_model(spec, arm, loads)
        mistake = _unit_mistake(model, meas, index, loads)
        if mistake is not None:
            raise InputError(f"{source}: {mistake}")
        cal = identify(
            model,
            meas.q,
            points,
            method=method,
            robust=robust,
            pose_labels=meas.labels,
            rows=meas.rows,
            row_sigma=meas.row_sigma,
            target=index,
            loads=loads,
        )
    except (InputError, FixError):
        raise
    except ArmcalError as exc:
        raise prefixed(source, exc) from None
    except ValueError as exc:
        raise InputError(f"{source}: {unrendered(exc)}") from None
    large = deviation_warning(cal.model, cal.params)
    return _calibration_run(
        cal, spec, meas, points, ignored, large, folds, sigma, seed, source, progress=progress
    )


@dataclass(frozen=True, eq=False)
class ValidationRun:
    """Held-out measurements against a calibration, and what they say."""

    validation: Validation
    warnings: tuple[ArmcalWarning, ...]
    acceptance: PoseCharacteristics | None = None


def validate_measurements(
    cal: CalibratedArm, meas: Measurements, *, source: str = "measurements", iso9283: bool = False
) -> ValidationRun:
    """:func:`armcal.validation.validate` on a measurement file, with its warnings, and with
    ``iso9283`` the pose accuracy and repeatability of its repeated poses
    (:func:`armcal.acceptance.pose_characteristics`).

    Raises InputError, naming ``source``, for a target column the calibration
    does not have or lacks, points of the other dimension, measurements that look
    like a unit mistake (:func:`armcal.plausibility.unit_mistake`), or (``iso9283``)
    poses measured once or with different joint values from cycle to cycle.
    """
    arm = cal.arm
    if meas.targets is not None and not arm.target_labels:
        raise InputError(
            f"{source}: has a target column but the calibration has no targets; remove the column"
        )
    if arm.target_labels and meas.targets is None:
        raise InputError(
            f"{source}: the calibration has targets ({', '.join(arm.target_labels)}); add a "
            "column 'target' naming the target of every row"
        )
    points = meas.xy if meas.z is None else meas.instrument_points
    loads = row_loads(cal.model, meas)
    target = _row_targets(arm, meas)
    mistake = _unit_mistake(cal.model, meas, target, loads)
    if mistake is not None:
        raise InputError(f"{source}: {mistake}")
    try:
        result = validate(
            cal,
            meas.q,
            points,
            target=target,
            row_sigma=meas.row_sigma,
            loads=loads,
        )
    except ArmcalError as exc:
        raise prefixed(source, exc) from None
    poses = None if meas.targets is None else np.array(meas.labels)  # a pose's points together
    warnings = [
        *meas.warnings,
        *_unpredicted(cal, loads, source),
        *_extrapolated(cal, loads, source),
        *validation_warnings(result, poses),
    ]
    degenerate = plan_degenerate_warning(  # the calibration holds part of the arm nominal
        coverage(cal.model),
        "the calibration's measurements",
        holds="its predicted error holds",
        like="those it was calibrated on",
    )
    if degenerate is not None:
        warnings.append(degenerate)
    if loads is None and meas.has_loads:  # the rows sag by their loads; the model cannot say
        warnings.append(
            _loads_ignored_warning(
                source,
                "the calibration has no joint compliance, so the sag under them is in the "
                "errors after calibration; calibrate with the robot file's [elastostatic] "
                "table to predict it",
            )
        )
    acceptance = None
    if iso9283:
        try:
            turns = None if result.turns is None else (result.turns.before, result.turns.after)
            acceptance = pose_characteristics(
                meas.q, result.positions, result.before, result.after, meas.labels,
                meas.targets, meas.rows, turns,
            )  # fmt: skip
        except ArmcalError as exc:
            raise prefixed(source, exc) from None
        warnings += pose_characteristics_warnings(acceptance)
    return ValidationRun(result, tuple(warnings), acceptance)


def _unpredicted(cal: CalibratedArm, loads: Loads | None, source: str) -> list[ArmcalWarning]:
    """``loads-unpredicted`` when the calibration cannot predict the deflection of ``loads``."""
    words = None if loads is None else cal.model.unpredicted_loads(loads)
    return [] if words is None else [ArmcalWarning("loads-unpredicted", f"{source}: {words}")]


def _extrapolated(cal: CalibratedArm, loads: Loads | None, source: str) -> list[ArmcalWarning]:
    """``payload-extrapolated`` when ``loads`` go far beyond the calibration's payloads."""
    found = payload_extrapolated(cal, loads, source)
    return [] if found is None else [found]


@dataclass(frozen=True, eq=False)
class CompensationRun:
    """A compensated program, the target label of every row, and the warnings."""

    compensation: Compensation
    targets: tuple[str, ...] | None
    warnings: tuple[ArmcalWarning, ...]
    payload: Payload | None = None


def compensate_program(
    cal: CalibratedArm,
    program: Program,
    *,
    target: str | None = None,
    payload_kg: float | None = None,
    source: str = "program",
) -> CompensationRun:
    """:func:`armcal.compensation.compensate` a program file.

    ``target`` is the target every row is for when the program has no target
    column; ``payload_kg`` its payload when it has no payload column (default:
    the robot file's).

    Raises
    ------
    ArmcalError
        For a target or payload the calibration cannot use, or a program of an
        arm with several targets that says none.
    """
    arm = cal.arm
    labels = program.targets
    if labels is None and target is not None:
        labels = (target,) * program.q.shape[0]
    if labels is not None:
        if target is not None and program.targets is not None:
            raise ArmcalError(
                f"{action('target')}: the program has a target column already; give one"
            )
        if target is not None and target not in arm.target_labels:
            raise ArmcalError(
                f"{action('target')}: {target!r} is not a target of the calibration "
                f"({', '.join(arm.target_labels) or 'none'})"
            )
    elif len(arm.target_labels) > 1:
        raise ArmcalError(
            f"{source}: the calibration has targets {', '.join(arm.target_labels)}; "
            f"add a column 'target' or pass {action('target-label')} for the tool point of the "
            "program"
        )
    index = None if labels is None or not arm.target_labels else arm.target_index(labels)
    default = cal.model.default_payload_kg
    loads = None
    used = None
    if default is not None:
        payload: float | np.ndarray = default
        origin = "the calibration's default"
        if payload_kg is not None:
            if program.payload_kg is not None:
                raise ArmcalError(
                    f"{action('payload-kg')}: the program has a payload_kg column already"
                )
            payload, origin = payload_kg, "the payload_kg argument"
        if program.payload_kg is not None:
            payload, origin = program.payload_kg, "the program's payload_kg column"
        loads = Loads.create(program.q.shape[0], payload, program.force_n)
        kg = loads.payload_kg
        used = Payload(float(kg.min()), float(kg.max()), origin)
    elif payload_kg is not None or program.payload_kg is not None:
        raise ArmcalError(
            f"{action('payload-given')}: the calibration has no joint compliance, so a payload "
            "changes nothing; calibrate with [elastostatic] in the robot file"
        )
    result = compensate(cal, program.q, target=index, loads=loads)
    bad = result.uncorrectable
    warnings = [*_unpredicted(cal, loads, source), *_extrapolated(cal, loads, source)]
    if bad.size:
        m = program.q.shape[0]
        shown = "; ".join(f"row {int(i) + 1}: {result.reasons[i]}" for i in bad[:5])
        more = f" and {bad.size - 5} more" if bad.size > 5 else ""
        warnings.append(
            ArmcalWarning(
                "uncorrectable",
                f"{bad.size} of {m} poses cannot be corrected and keep their commands "
                f"(corrected = 0 in the output): {shown}{more}",
            )
        )
    return CompensationRun(result, labels, tuple(warnings), used)


@dataclass(frozen=True, eq=False)
class ExportRun:
    """The texts of the files to write (made before any is written), and the warnings."""

    texts: dict[str, str]
    warnings: tuple[ArmcalWarning, ...]
    rigid: RigidExport | None = None


def _ur_arm(cal: CalibratedArm, path: str) -> tuple[SerialChain, str, UrDh]:
    """The calibrated chain of a UR arm (DH base frame to flange, whatever frames its
    description used: :func:`armcal.files.ur.ur_frames`), its model
    (:func:`armcal.files.ur.ur_model_of`) and its deltas from that model's table, for a
    controller's file at ``path``."""
    arm = cal.arm
    if not isinstance(arm, SpatialArm) or arm.n_joints != 6 or set(arm.chain.kinds) != {"R"}:
        raise ArmcalError(f"{path}: a UR file needs a six-axis revolute arm; {arm.name} is not")
    frames = ur_frames(arm.chain)  # of the nominal: they hold for its calibration
    if frames.distance_mm > FAR_FROM_NOMINAL_MM:
        raise ArmcalError(
            f"{path}: {arm.name} is no UR model in any base and tip frames (nearest "
            f"{frames.model}, {frames.distance_mm:.4g} mm away); describe the arm with a robot "
            "file's [ur] table or Universal Robots' own URDF"
        )
    chain = frames.apply(arm.calibrated_chain(cal.arm_params))
    model, distance = ur_model_of(chain)
    if distance > FAR_FROM_NOMINAL_MM:
        raise ArmcalError(
            f"{path}: the calibrated {arm.name} moves the flange {distance:.4g} mm from the "
            f"nominal {model}'s (a calibration moves it a few mm); check the calibration"
        )
    try:
        deltas = ur_deltas(chain, model)
    except ValueError as exc:  # what a UR's DH table cannot hold, e.g. a tilted joint 1
        raise ArmcalError(
            f"{path}: the calibrated {arm.name} has no UR DH table: {unrendered(exc)}; a UR's "
            "table starts "
            "at joint 1's axis, so leave the base pose free (the joint's placement merges "
            "into it) rather than fixing base.* and identifying j1.*"
        ) from None
    return chain, model, deltas


def _ur_texts(cal: CalibratedArm, ur_path: str | None, ros_path: str | None) -> dict[str, str]:
    """A UR controller's calibration.conf deltas and the ROS driver's calibration YAML."""
    texts: dict[str, str] = {}
    first = ur_path if ur_path is not None else ros_path
    if first is None:
        return texts
    chain, model, deltas = _ur_arm(cal, first)
    if ur_path is not None:
        texts[ur_path] = format_ur_calibration(deltas)
    if ros_path is not None:
        try:
            texts[ros_path] = format_ur_kinematics(chain, model, f"armcal_{cal.arm.name}_{model}")
        except ValueError as exc:
            raise ArmcalError(
                f"{ros_path}: the calibrated {cal.arm.name}: {unrendered(exc)}"
            ) from None
    return texts


def export_files(
    cal: CalibratedArm,
    *,
    robot_toml_path: str | None = None,
    urdf_path: str | None = None,
    offsets_path: str | None = None,
    ur_path: str | None = None,
    ros_path: str | None = None,
) -> ExportRun:
    """The calibrated arm as a robot TOML, a URDF and/or the joint offsets, with what they
    leave out.

    ``urdf-joint-values`` when the URDF's joint values are not the controller's
    readings (coupled axes), ``offsets-only`` for the offsets (the geometry is not
    in them), and a warning that a model's effect (joint compliance) is in no file,
    with what the rigid geometry loses on the calibration's rows (``rigid``,
    :func:`armcal.export_rigid.rigid_export`; ``rigid-export-worse`` when it fits
    them worse than the nominal arm).
    """
    serial = isinstance(cal.arm, SpatialArm)  # the file formats differ by family
    texts: dict[str, str] = {}
    texts.update(_ur_texts(cal, ur_path, ros_path))
    if robot_toml_path is not None:
        texts[robot_toml_path] = serial_robot_toml(cal) if serial else robot_toml(cal)
    warnings = []
    if offsets_path is not None:
        texts[offsets_path] = joint_offsets_csv(cal)
        warnings.append(
            ArmcalWarning(
                "offsets-only",
                f"{offsets_path}: the joint zero offsets alone leave the controller with the "
                "nominal link geometry; the URDF or robot TOML carries the whole calibration",
            )
        )
    if urdf_path is not None:
        texts[urdf_path] = serial_urdf(cal) if serial else urdf(cal)
        coupled = (
            not np.array_equal(cal.arm.joint_map, np.eye(cal.arm.n_joints))
            if serial
            else not urdf_joints_are_readings(cal.arm)
        )
        if coupled:
            values = "M q" if serial else "the relative link angles D M q"
            warnings.append(
                ArmcalWarning(
                    "urdf-joint-values",
                    f"{urdf_path}: {cal.arm.name} has coupled axes (joint_map): the URDF's joint "
                    f"values are {values}, not the controller's readings; convert them before "
                    "publishing joint_states (see the file's comment)",
                )
            )
    loss = rigid_export(cal)
    warnings += rigid_export_warnings(cal, loss)
    return ExportRun(texts, tuple(warnings), loss)
