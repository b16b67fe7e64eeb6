"""The arm and the fit a measurement file asks for, family by family.

:func:`armcal.workflow.calibrate` is the same for every family; the family's part
(:mod:`armcal.families`, role ``calibrate``) is here: the arm its measurements
ask for (the targets measured, a planar arm's base pose for 3-D data), the unit
mistakes checked before the fit, and the fit.  Errors name the file (``source``).
"""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager
from typing import Any

import numpy as np

from ..errors import ArmcalError, InputError, NotIdentifiableError, unrendered
from ..files import Measurements, RobotSpec
from ..identification import Calibration, identify
from ..instrument import identify_3d
from ..models import FitModel, Loads, PlanarArm, SpatialArm, Target
from ..models.interface import Conditions, target_indices
from ..plausibility import explain, suspicious, unit_mistake
from .setup import FixError, fit_model, model_spec, prefixed

__all__ = [
    "check_meeting",
    "fit_instrumented",
    "fit_planar",
    "fit_spatial",
    "instrument_rows",
    "measured_arm",
    "row_targets",
    "spatial_measured_arm",
    "unit_mistake_of",
]


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


def row_targets(arm: FitModel, meas: Measurements) -> np.ndarray | None:
    """Every row's target index, for an arm with targets (None without)."""
    if meas.targets is None or not arm.target_labels:
        return None
    return target_indices(meas.targets, arm.target_labels, len(meas.targets))


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
        target=row_targets(arm, meas),
    )
    try:
        loads = None if elastic is None else meas.loads(elastic.payload_kg)
        model = fit_model(spec, arm, loads)
        options["loads"] = loads
        mistake = unit_mistake_of(model, meas, options["target"], loads)
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


def unit_mistake_of(
    model: FitModel, meas: Measurements, target: np.ndarray | None, loads: Loads | None
) -> str | None:
    """What in ``meas`` looks like a unit mistake for ``model`` (:func:`unit_mistake`), checked
    before the fit: positions in metres or another unit, angles in radians (joints, a
    6-DoF instrument's orientations).  A plane's, a point's or a distance's rows have
    no coordinates to misread: their rows are checked against the instrument's
    geometry instead (:func:`check_meeting`)."""
    if meas.readings is not None:
        return None
    points = meas.xy if meas.z is None else meas.xyz
    return unit_mistake(
        model, meas.q, points, target=target, loads=loads, orientations=meas.orientation
    )


def fit_planar(
    spec: RobotSpec[PlanarArm],
    meas: Measurements,
    *,
    source: str,
    fixed: tuple[str, ...] | None,
    sigma: float | None,
    method: str,
    robust: bool,
) -> tuple[Calibration, np.ndarray]:
    """The planar family's part of :func:`armcal.workflow.calibrate`: the arm its
    measurements ask for (:func:`measured_arm`), fitted (3-D data in their plane); the
    calibration and the fitted points (a 3-D file's in its plane)."""
    try:
        structure = measured_arm(spec.arm, meas)
    except InputError as exc:
        raise prefixed(source, exc) from None
    spec, arm = model_spec(spec, structure, fixed=fixed, sigma=sigma)
    cal = _identify_file(spec, arm, source, meas, method=method, robust=robust)
    points = meas.xy if cal.plane is None else cal.plane.to_plane(meas.xyz)
    return cal, points


def spatial_measured_arm(arm: SpatialArm, meas: Measurements) -> SpatialArm:
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


@contextmanager
def named(source: str) -> Iterator[None]:
    """Errors of a fit named by the measurement file ``source``: an :class:`ArmcalError`
    prefixed with it, a ``ValueError`` an :class:`InputError` of it (an ``InputError``
    or a :class:`FixError` as raised: they name their file or option already)."""
    try:
        yield
    except (InputError, FixError):
        raise
    except ArmcalError as exc:
        raise prefixed(source, exc) from None
    except ValueError as exc:
        raise InputError(f"{source}: {unrendered(exc)}") from None


def fit_spatial(
    spec: RobotSpec[SpatialArm],
    meas: Measurements,
    *,
    source: str,
    fixed: tuple[str, ...] | None,
    sigma: float | None,
    method: str,
    robust: bool,
) -> tuple[Calibration, np.ndarray]:
    """The spatial family's part of :func:`armcal.workflow.calibrate`: the base pose and
    the targets are found from the data (no start from the user); the identifiable set
    is chosen for these measurements and named.  With ``[elastostatic]`` the joints'
    compliance is fitted with the geometry, under the rows' payloads.
    """
    with named(source):
        measured = spatial_measured_arm(spec.arm, meas)
        spec, arm = model_spec(spec, measured, fixed=fixed, sigma=sigma)
        points = meas.instrument_points  # 3-D: spatial_measured_arm refuses data without z_mm
        index = None if meas.targets is None else arm.target_index(meas.targets)
        loads = None if spec.elastic is None else meas.loads(spec.elastic.payload_kg)
        model = fit_model(spec, arm, loads)
        mistake = unit_mistake_of(model, meas, index, loads)
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
    return cal, points


def fit_instrumented(
    spec: RobotSpec,
    meas: Measurements,
    *,
    source: str,
    fixed: tuple[str, ...] | None,
    sigma: float | None,
    method: str,
    robust: bool,
) -> tuple[Calibration, np.ndarray]:
    """The part of :func:`armcal.workflow.calibrate` for an arm measured by a plane, fixed
    points or a distance: every row's feature and reading, its rows checked against the
    instrument's geometry where the robot file places it (:func:`instrument_rows`), and
    the fit from where the arm meets the readings."""
    with named(source):
        spec, model = model_spec(spec, spec.arm, fixed=fixed, sigma=sigma)
        rows = instrument_rows(model, meas)
        points = meas.instrument_points
        check_meeting(source, model, rows, points, meas)
        cal = identify(
            model,
            meas.q,
            points,
            method=method,
            robust=robust,
            pose_labels=meas.labels,
            rows=meas.rows,
            conditions=rows,
        )
    return cal, points


def instrument_rows(model: FitModel, meas: Measurements) -> Conditions:
    """The rows of ``meas`` for an arm measured by an instrument: joints, targets (the
    target column, else the arm's one tool point), features and per-row sigma."""
    if meas.targets is None and len(model.target_labels) > 1:
        raise InputError(
            f"{model.name} has targets ({', '.join(model.target_labels)}) but the measurements "
            "have no target column; add a column 'target' naming the tool point of every row"
        )
    return model.conditions(
        meas.q, target=meas.targets, sigma_mm=meas.row_sigma, feature=meas.feature
    )


#: A row whose reading differs from the others' by more than this fraction of the arm's reach,
#: at the nominal arm and the instrument where the robot file places it, is not of this
#: instrument (a wrong label, a pose that touched nothing): no error of a few mm and a degree
#: in the arm, nor the user's rough placement of the instrument, moves a reading that far.
_FAR_FROM_FEATURE = 0.1


#: A turn's reading (partial coordinates' rx_deg...) that differs from the others' by more
#: than this (deg) is not of this tool or instrument (a column in radians, another
#: convention): the arm's errors and the user's rough axes turn the tool by a few degrees.
_FAR_TURN_DEG = 10.0


#: A camera's reading that differs from the others' by more than this fraction of the
#: image's diagonal is not of this board (a wrong corner, another camera's file): the
#: user's rough placement of the camera and the board moves a corner by tens of pixels.
_FAR_IN_IMAGE = 0.5


def _image(model: FitModel) -> np.ndarray:
    """The instrument's reading bounds ``(dim, 2)`` (a camera's image)."""
    return np.asarray(model.instrument.reading_bounds, dtype=float)  # type: ignore[attr-defined]


def check_meeting(
    source: str, model: FitModel, rows: Conditions, points: np.ndarray, meas: Measurements
) -> None:
    """InputError for a row that violates the instrument's geometry: its reading, against
    what the nominal arm and the robot file's instrument predict, differs from the median
    difference of the rows of its feature by more than :data:`_FAR_FROM_FEATURE` of the
    reach (module notes of :data:`_FAR_FROM_FEATURE`)."""
    found = np.asarray(points, dtype=float) - np.asarray(model.positions(rows))
    centre = np.empty_like(found)
    index = np.zeros(len(found), dtype=int) if rows.feature is None else rows.feature
    for k in np.unique(index):  # a feature's own: an axis's rough offset is its own
        centre[index == k] = np.median(found[index == k], axis=0)
    spread = np.linalg.norm(found - centre, axis=-1)
    limit = _FAR_FROM_FEATURE * model.reach_mm
    unit = model.reading_unit
    if unit != "mm":  # a camera's pixels: the image's size, not the reach
        limit = _FAR_IN_IMAGE * float(np.linalg.norm(np.ptp(_image(model), axis=1)))
    turn = model.turn_rows(rows)  # a turn's component (rad): degrees, against its own bound
    turn = np.zeros(spread.shape, dtype=bool) if turn is None else turn
    spread = np.where(turn, np.degrees(spread), spread)
    limits = np.where(turn, _FAR_TURN_DEG, limit)
    if not spread.size or np.all(spread <= limits):
        return
    r = int(np.argmax(spread / limits))
    feature = "" if meas.feature is None else f" {meas.feature[r]!r}"
    if turn[r]:
        what, unit, limit = "the nominal arm's tool is turned", "deg", _FAR_TURN_DEG
        bound = "no error of the arm or of where the tool's axes are"
        where = "its turn"
    elif unit == "mm":
        what = "the nominal arm's tool point is"
        bound = "a tenth of the reach"
        where = "the instrument's feature"
    else:  # the reading the arm and the camera predict, in the image
        what = "the nominal arm and the robot file's camera put the reading"
        bound = "half the image's diagonal"
        where = "the instrument's feature"
    raise InputError(
        f"{source}: row {meas.rows[r]}: at its joint readings {what} {spread[r]:.4g} {unit} "
        f"from where the other rows put {where}{feature} (at most {limit:.4g} {unit}, "
        f"{bound}, is an error of the arm or of where the robot file places the instrument); "
        "check the row's joint readings and its label, and where [instrument] places the "
        "feature"
    )
