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
    robot_turn,
)
from ..compensation import Compensation, Payload, compensate
from ..errors import (
    ArmcalError,
    ArmcalWarning,
    InputError,
    action,
    unique_warnings,
)
from ..export_rigid import RigidExport, rigid_export, rigid_export_warnings
from ..export_spatial import joint_offsets_csv
from ..families.registry import family_of
from ..files import Measurements, Program, RobotSpec
from ..identification import Calibration
from ..identification.experiment import coverage, plan_degenerate_warning
from ..models import CalibratedArm, FitModel, Loads
from ..models.wording import unpredicted_loads
from ..noise import per_row_sigma
from ..plausibility import deviation_warning
from ..progress import ProgressCallback, steps
from ..validation import (
    CrossValidation,
    Validation,
    cross_validate,
    cross_validation_warnings,
    validate,
    validation_warnings,
)
from .measured import row_targets, unit_mistake_of
from .payloads import payload_extrapolated, payload_missing, payload_unit
from .setup import prefixed

__all__ = [
    "CalibrationRun",
    "CompensationRun",
    "ExportRun",
    "ValidationRun",
    "calibrate",
    "compensate_program",
    "export",
    "export_files",
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


def row_loads(model: FitModel, meas: Measurements) -> Loads | None:
    """The rows' loads for a model they move (payload column or the model's default)."""
    default = model.default_payload_kg
    return None if default is None else meas.loads(default)


def _ignored_loads(
    spec: RobotSpec, meas: Measurements, source: str, compliance: bool
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
_Spec = TypeVar("_Spec", bound=RobotSpec)


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

    The robot's family fits it (:mod:`armcal.families`: a planar arm's 3-D data in
    their plane, a spatial arm's base pose and targets found from the data); the
    run's checks, warnings and cross-validation are the same for every family.

    Parameters
    ----------
    spec : RobotSpec
        The robot, of any family (:func:`armcal.load_robot`).
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
    spec, meas, ignored = _as_asked(spec, meas, source, sigma, compliance)
    fit = family_of(spec.arm).role("calibrate")
    cal, points = fit(
        spec, meas, source=source, fixed=fixed, sigma=sigma, method=method, robust=robust
    )
    large = deviation_warning(cal.model, cal.params)
    return _calibration_run(
        cal, spec, meas, points, ignored, large, folds, sigma, seed, source, progress=progress
    )


def _as_asked(
    spec: _Spec, meas: Measurements, source: str, sigma: float | None, compliance: bool
) -> tuple[_Spec, Measurements, list[ArmcalWarning]]:
    """The robot file and the measurements as the options ask: a given ``sigma`` replaces
    the file's ``sigma_mm`` column too, and without ``compliance`` the arm is rigid (the
    data's loads then ``loads-ignored``)."""
    meas = replace(meas, row_sigma=per_row_sigma(sigma, meas.row_sigma))
    ignored = _ignored_loads(spec, meas, source, compliance)
    return (spec if compliance else replace(spec, elastic=None)), meas, ignored


def _calibration_run(
    cal: Calibration,
    spec: RobotSpec,
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
        # a pose's rows (its targets, an instrument's readings) stay in one fold
        groups=None if meas.targets is None and meas.feature is None else np.array(meas.labels),
        target=cal.target,
        sigma=sigma,
        row_sigma=meas.row_sigma,
        rng=seed,
        loads=None if conditions is None else conditions.loads,
        progress=progress,
        feature=None if conditions is None else conditions.feature,
    )
    warnings.extend(cross_validation_warnings(checked))
    return checked


@dataclass(frozen=True, eq=False)
class ValidationRun:
    """Held-out measurements against a calibration, and what they say."""

    validation: Validation
    warnings: tuple[ArmcalWarning, ...]
    acceptance: PoseCharacteristics | None = None


def validate_measurements(
    cal: CalibratedArm,
    meas: Measurements,
    *,
    source: str = "measurements",
    iso9283: bool = False,
    progress: ProgressCallback | None = None,
) -> ValidationRun:
    """:func:`armcal.validation.validate` on a measurement file, with its warnings, and with
    ``iso9283`` the pose accuracy and repeatability of its repeated poses
    (:func:`armcal.acceptance.pose_characteristics`).

    Raises InputError, naming ``source``, for a target column the calibration
    does not have or lacks, points of the other dimension, measurements that look
    like a unit mistake (:func:`armcal.plausibility.unit_mistake`), or (``iso9283``)
    poses measured once or with different joint values from cycle to cycle.
    ``progress(done, 2)`` is called after the validation and after the acceptance test
    (:mod:`armcal.progress`).
    """
    arm = cal.arm
    if meas.targets is not None and not arm.target_labels:
        raise InputError(
            f"{source}: has a target column but the calibration has no targets; remove the column"
        )
    if len(arm.target_labels) > (meas.feature is not None) and meas.targets is None:
        raise InputError(
            f"{source}: the calibration has targets ({', '.join(arm.target_labels)}); add a "
            "column 'target' naming the target of every row"
        )
    points = meas.xy if meas.z is None and meas.readings is None else meas.instrument_points
    loads = row_loads(cal.model, meas)
    target = row_targets(arm, meas)
    mistake = unit_mistake_of(cal.model, meas, target, loads)
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
            feature=meas.feature,
        )
    except ArmcalError as exc:
        raise prefixed(source, exc) from None
    step = steps(progress, 2)  # the validation, then the acceptance test
    step()
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
            sample = cal.model.plan_conditions(meas.q[: min(len(meas.q), 64)])
            turn = robot_turn(cal.model, sample, cal.params)
            acceptance = replace(acceptance, robot_turn=turn)
        except ArmcalError as exc:
            raise prefixed(source, exc) from None
        warnings += pose_characteristics_warnings(acceptance)
    step()
    return ValidationRun(result, tuple(warnings), acceptance)


def _unpredicted(cal: CalibratedArm, loads: Loads | None, source: str) -> list[ArmcalWarning]:
    """``loads-unpredicted`` when the calibration cannot predict the deflection of ``loads``."""
    found = None if loads is None else cal.model.unpredicted_loads(loads)
    if found is None:
        return []
    return [ArmcalWarning("loads-unpredicted", f"{source}: {unpredicted_loads(found)}")]


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
    cal = cal.alone()  # an instrument's parameters correct no command
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


#: The files :func:`export` writes, by kind: what each holds.
EXPORT_KINDS = {
    "robot": "a robot TOML of the calibrated arm (armcal reads it as a robot file)",
    "urdf": "a URDF of the calibrated arm (with original: the user's own, origins calibrated)",
    "origins": "the calibrated joint origins of the user's URDF (original) as YAML, for a xacro",
    "offsets": "a CSV of the joint zero offsets alone",
}


def export(cal: CalibratedArm, kind: str = "urdf", *, original: str | None = None) -> str:
    """The text of a file of the calibrated arm ``cal``, of any family.

    Parameters
    ----------
    cal : CalibratedArm
        A calibration (:meth:`armcal.identification.Calibration.calibrated`, or
        :func:`armcal.files.read_calibration`).
    kind : str
        One of :data:`EXPORT_KINDS`: ``"robot"``, ``"urdf"``, ``"origins"`` or ``"offsets"``.
    original : path, optional
        The URDF the robot was described by: ``"urdf"`` then writes it back with only
        its chain's joint origins calibrated (every link, mesh, inertial, limit and name
        kept), and ``"origins"`` (which needs it) gives those origins as YAML.

    Returns
    -------
    str
        The file's text; :func:`export_files` gives the same texts with what
        they leave out (a joint compliance, coupled axes) as warnings.

    Raises
    ------
    ArmcalError
        For another kind, or one the arm's family does not write.
    """
    if kind not in EXPORT_KINDS:
        raise ArmcalError(f"no export of kind {kind!r}; the kinds are {', '.join(EXPORT_KINDS)}")
    cal = cal.alone()  # the arm, not the instrument it was measured by
    if kind == "offsets":
        return joint_offsets_csv(cal)
    if kind == "origins" or original is not None:
        if original is None:
            raise ArmcalError("the origins export needs the robot's URDF: pass original=PATH")
        origins = _origins_of(cal, original)
        return str(origins.yaml() if kind == "origins" else origins.urdf())
    writers = family_of(cal.model).role("exports")()
    if kind not in writers:
        raise ArmcalError(f"the {cal.model.family} family writes no {kind} file")
    text: str = writers[kind](cal)
    return text


def _origins_of(cal: CalibratedArm, original: str) -> Any:
    """The calibrated joint origins of the user's URDF ``original``
    (:mod:`armcal.files.urdf_origins`), through the family's role."""
    family = family_of(cal.model)
    if not family.has("calibrated_origins"):
        raise ArmcalError(
            f"{original}: a {cal.model.family} arm is not described by a URDF chain; "
            f"{action('own-urdf')}"
        )
    return family.role("calibrated_origins")(cal, original)


def _onto_original(
    cal: CalibratedArm, original: str, urdf_path: str | None, origins_path: str | None
) -> dict[str, str]:
    """The user's own URDF ``original`` with the calibrated joint origins, and/or those
    origins as YAML, by path."""
    origins = _origins_of(cal, original)
    texts = {} if urdf_path is None else {urdf_path: origins.urdf()}
    if origins_path is not None:
        texts[origins_path] = origins.yaml()
    return texts


def export_files(
    cal: CalibratedArm,
    *,
    robot_toml_path: str | None = None,
    urdf_path: str | None = None,
    offsets_path: str | None = None,
    ur_path: str | None = None,
    ros_path: str | None = None,
    original: str | None = None,
    origins_path: str | None = None,
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
    cal = cal.alone()  # the arm, not the instrument it was measured by
    family = family_of(cal.model)  # the file formats differ by family
    texts: dict[str, str] = {}
    if ur_path is not None or ros_path is not None:
        if not family.has("controller_files"):
            first = ur_path if ur_path is not None else ros_path
            raise ArmcalError(
                f"{first}: a UR file needs a six-axis revolute arm; {cal.arm.name} is not"
            )
        texts.update(family.role("controller_files")(cal, ur_path, ros_path))
    if robot_toml_path is not None:
        texts[robot_toml_path] = export(cal, "robot")
    warnings = []
    if offsets_path is not None:
        texts[offsets_path] = export(cal, "offsets")
        warnings.append(
            ArmcalWarning(
                "offsets-only",
                f"{offsets_path}: the joint zero offsets alone leave the controller with the "
                "nominal link geometry; the URDF or robot TOML carries the whole calibration",
            )
        )
    if original is not None:
        texts.update(_onto_original(cal, original, urdf_path, origins_path))
    elif urdf_path is not None:
        texts[urdf_path] = export(cal, "urdf")
    if urdf_path is not None:
        values = family.role("coupled_urdf")(cal.arm)
        if values is not None:
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
