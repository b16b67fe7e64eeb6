"""The calibration file (``armcal-calibration/1``): written and read in one place.

:func:`calibration_document` is the JSON document of a calibration (the file
``identify -o`` writes and the document ``identify --json`` prints);
:func:`read_calibration` rebuilds the calibrated model from it for
``validate``, ``compensate`` and ``export``.
"""

from __future__ import annotations

import json
import math
import os
from collections.abc import Callable, Mapping, Sequence
from typing import Any, TypeVar

import numpy as np

from .._version import __version__
from ..errors import ACTIONS, ArmcalError, ArmcalWarning, InputError, unrendered
from ..families.registry import Family, family_named, family_of
from ..identification import Calibration
from ..identification.problem import sigma_parts
from ..models import CalibratedArm, Conditions, FitModel, Loads, Plane, TermChoice
from ..noise import NoiseModel, TrackerNoise
from .checked import BadKey, array_of, check_covariance, described, list_of, number_of
from .common import fail, read_text
from .kinds import looks_like

__all__ = [
    "CALIBRATION_FORMAT",
    "calibration_document",
    "read_calibration",
    "robot_to_dict",
]

# --------------------------------------------------------------------------- calibration JSON

#: The format tag of calibration files (PRODUCT.md); other formats are refused.
CALIBRATION_FORMAT = "armcal-calibration/1"


#: The coordinates of a standardized residual: a point's, then a 6-DoF instrument's turn.
_AXES = ("x", "y", "z", "rx", "ry", "rz")

T = TypeVar("T")


def robot_to_dict(arm: FitModel) -> dict[str, Any]:
    """The ``robot`` section of a calibration file: everything needed to rebuild the arm,
    as its family writes it (:mod:`armcal.families`), its ``kind`` the family's name."""
    return dict(family_of(arm).role("encode")(arm))


def read_calibration(path: str | os.PathLike) -> CalibratedArm:
    """Read a calibration file written by ``armcal identify`` (``armcal-calibration/1``).

    Returns
    -------
    CalibratedArm
        The arm rebuilt from the file's ``robot`` section, noise and fixed
        parameters; the deviations and covariance in internal units (mm, rad);
        the plane of 3-D data.

    Raises
    ------
    InputError
        For a file that is not JSON, of another format or version, or whose
        parameters do not match its robot; the message names the file and key.
    """
    doc = _document(path)
    noise = _section(path, "noise", _noise_from_dict, doc.get("noise"))
    family, arm, fixed = _section(path, "robot", _arm_from_dict, doc, noise)
    model: FitModel = arm
    if doc.get("elastostatic") is not None:
        model = _section(
            path, "elastostatic", _compliance_from_dict, family, arm, doc["elastostatic"], fixed
        )
    rows = _section(
        path,
        "training_rows",
        _rows_from_dict,
        doc.get("training_rows"),
        arm.n_joints,
        len(arm.target_labels),
    )
    names, values, stds = _section(path, "parameters", _parameters_from_dict, doc, model)
    full = _section(path, "covariance", _covariance_from_dict, doc, names, stds, model)
    sigma = _section(path, "sigma_mm", _sigma_from_dict, doc)
    plane = _section(path, "plane", _plane_from_dict, doc.get("plane"))
    baseline = _section(path, "baseline", _baseline_from_dict, arm, doc.get("baseline"))
    if rows is not None and not np.all(np.isfinite(rows.q)):
        raise fail(path, "key 'training_rows': joint readings must be finite numbers")
    return CalibratedArm(model, values, full, sigma, plane, rows, baseline)


def _document(path: str | os.PathLike) -> dict[str, Any]:
    """The JSON object of a calibration file of this format; an :class:`InputError` for a
    file of another kind, invalid JSON, a list or a scalar, or another format."""
    text = read_text(path, "calibration")
    try:
        doc = json.loads(text)
    except (ValueError, RecursionError) as exc:  # JSONDecodeError, or digits/nesting limits
        other = looks_like(text, "calibration-file")
        if other:  # a file of another kind: say which, not what JSON finds wrong in it
            raise fail(path, f"not a calibration file: {other.removesuffix('; ')}") from None
        raise fail(
            path,
            f"not a calibration file: invalid JSON ({exc}), as in a file cut short or "
            "mistyped by hand; write the calibration again with armcal identify -o",
        ) from None
    if not isinstance(doc, dict):
        raise fail(
            path,
            f"not a calibration file: {'a list' if isinstance(doc, list) else described(doc)} "
            "where an object with a 'format' key was expected; write one with armcal identify -o",
        )
    if "format" not in doc:
        raise fail(
            path, "not a calibration file: no 'format' key; write one with armcal identify -o"
        )
    if doc["format"] != CALIBRATION_FORMAT:
        raise fail(
            path,
            f"format {doc['format']!r} is not {CALIBRATION_FORMAT!r}; write the calibration with "
            "this version of armcal identify -o",
        )
    return doc


def _section(path: str | os.PathLike, key: str, read: Callable[..., T], *args: Any) -> T:
    """``read(*args)``: a section of a calibration file read, what is wrong with it an
    :class:`InputError` that names the file and the key (or the :class:`BadKey`'s)."""
    try:
        return read(*args)
    except (KeyError, TypeError, ValueError, AttributeError, OverflowError, InputError) as exc:
        # AttributeError: a section of the wrong JSON type ("robot": [] has no .get)
        what = unrendered(exc)
        if isinstance(exc, KeyError):
            what = "missing" if exc.args == (key,) else f"missing key {exc}"
        if isinstance(exc, AttributeError):
            what = "a section of the wrong type"
        if isinstance(exc, BadKey):
            key = exc.key
        raise fail(
            path, f"key '{key}': {what}; write the calibration again with armcal identify -o"
        ) from None


def _noise_from_dict(data: dict[str, Any] | None) -> NoiseModel | None:
    """The noise model of a calibration file's ``noise`` section (None without one)."""
    if data is None:
        return None
    sigma_q = data.get("joint_sigma_deg")
    tracker = data.get("tracker")
    turn = data.get("orientation_sigma_deg")
    return NoiseModel(
        np.array(data["covariance_mm2"], dtype=float),
        None if sigma_q is None else np.radians(np.array(sigma_q, dtype=float)),
        tracker=None if tracker is None else TrackerNoise(**tracker),
        orientation_sigma=None if turn is None else math.radians(float(turn)),
    )


def _arm_from_dict(
    doc: dict[str, Any], noise: NoiseModel | None
) -> tuple[Family, FitModel, list[str]]:
    """The family and the arm of a calibration file's ``robot`` section, as its family
    decodes it with the file's noise and ``fixed`` parameters, and those names."""
    fixed = list(doc.get("fixed", []))
    family = _family(doc["robot"])
    return family, family.role("decode")(doc["robot"], noise, fixed, doc), fixed


def _parameters_from_dict(
    doc: dict[str, Any], model: FitModel
) -> tuple[list[str], np.ndarray, list[Any]]:
    """The names, values (internal units) and stds (display units, as written) of a
    calibration file's ``parameters``, which must be the model's."""
    entries = list_of(doc, "parameters", "an entry per parameter", where="")
    names = [entry["name"] for entry in entries]
    expected = model.param_names
    if tuple(names) != expected:
        raise ValueError(
            f"parameters {', '.join(names)} do not match the robot's {', '.join(expected)}"
        )
    values = np.array(
        [number_of(e.get("value"), "parameters", f"the value of {e['name']}") for e in entries]
    )
    return names, values / model.display_scale, [entry.get("std") for entry in entries]


def _covariance_from_dict(
    doc: dict[str, Any], names: list[str], stds: list[Any], model: FitModel
) -> np.ndarray:
    """The covariance (internal units) of a calibration file's ``covariance``: a row and a
    column per parameter, symmetric, its diagonal the parameters' stds squared."""
    if list(doc["covariance"]["names"]) != names:
        raise ValueError("covariance names do not match the parameters")
    p = len(names)
    shown = array_of(
        doc["covariance"],
        "matrix",
        (p, p),
        "a row and a column per parameter (mm, deg)",
        where="covariance",
    )
    check_covariance(shown, names, stds)
    scale = model.display_scale
    return shown / np.outer(scale, scale)


def _sigma_from_dict(doc: dict[str, Any]) -> float:
    """A calibration file's ``sigma_mm``: the noise std, positive."""
    sigma = number_of(doc.get("sigma_mm"), "sigma_mm", "the noise std (mm)")
    if not sigma > 0:
        raise ValueError(f"expected a positive noise std in mm, got {sigma}")
    return sigma


def _plane_from_dict(data: dict[str, Any] | None) -> Plane | None:
    """The plane of 3-D data of a calibration file's ``plane`` (None without one)."""
    return None if data is None else Plane.from_dict(data)


def _family(robot: dict[str, Any]) -> Family:
    """The family of a calibration file's ``robot`` section, by its ``kind`` (planar in
    files written before the key)."""
    kind = str(robot.get("kind", "planar"))
    try:
        return family_named(kind)
    except ArmcalError as exc:
        raise BadKey("robot.kind", unrendered(exc)) from None


def _compliance_from_dict(
    family: Family, arm: FitModel, data: dict[str, Any], fixed: Sequence[str]
) -> FitModel:
    """The compliance model of a calibration file's ``elastostatic`` section, as the arm's
    family reads it; of the terms ``fixed`` lists, those the rule did not hold (``held``)
    the user held."""
    rule = set(data.get("held", []))
    terms = data.get("parameters", [])  # older planar files: none held
    user = TermChoice(fixed=tuple(n for n in fixed if n in terms and n not in rule))
    model: FitModel = family.role("decode_effect")(arm, data, user)
    return model


def _finite_or_none(value: float | None) -> float | None:
    """A float for JSON: None for a missing or non-finite value (never NaN)."""
    if value is None or not math.isfinite(value):
        return None
    return float(value)


def _rows_dict(cal: Calibration) -> dict[str, Any] | None:
    """The rows the fit used, compactly: joint readings ``q`` (rad, mm for a prismatic
    joint), target indices and loads: what validation checks held-out rows against
    (:func:`armcal.validation.validate`) and a rigid export is judged on
    (:func:`armcal.export_rigid.rigid_export`)."""
    rows = cal.calibrated().training_rows
    if rows is None:
        return None
    loads = rows.loads
    return {
        "q": np.asarray(rows.q, dtype=float).tolist(),
        "target": None if rows.target is None else rows.target.tolist(),
        "payload_kg": None if loads is None else loads.payload_kg.tolist(),
        "force_n": None if loads is None or not np.any(loads.force_n) else loads.force_n.tolist(),
        **({} if rows.feature is None else {"feature": rows.feature.tolist()}),
    }


def _rows_from_dict(data: dict[str, Any] | None, n: int, targets: int) -> Conditions | None:
    """The rows of :func:`_rows_dict` of an arm of ``n`` joints and ``targets`` target
    labels (None when the file has none)."""
    if data is None:
        return None
    q = np.array(data["q"], dtype=float).reshape(-1, n)
    m = q.shape[0]
    target = None if data["target"] is None else np.array(data["target"], dtype=int).reshape(m)
    if target is not None and np.any((target < 0) | (target >= targets)):
        raise ValueError(f"rows: target indices must lie in 0..{targets - 1}")
    loads = None
    if data["payload_kg"] is not None:
        force = None if data["force_n"] is None else np.array(data["force_n"], dtype=float)
        loads = Loads.create(m, np.array(data["payload_kg"], dtype=float), force)
    feature = data.get("feature")
    if feature is not None:
        feature = np.array(feature, dtype=int).reshape(m)
        if np.any(feature < 0):
            raise ValueError("rows: feature indices must not be negative")
    return Conditions(q, target, loads, feature=feature)


def _elastostatic_dict(cal: Calibration) -> dict | None:
    """The loads model of a fit with compliance, enough to rebuild it (its family's
    section), and the RMS of the geometry alone."""
    nested = cal.nested
    if nested is None:
        return None
    section = family_of(cal.model).role("encode_effect")(cal.model)
    if section is None:
        return None
    return {**section, "geometry_only_rms_per_coordinate_mm": nested.rms_per_coordinate_mm}


def _baseline_dict(cal: Calibration) -> dict[str, Any] | None:
    """The nominal arm registered on its own to the calibration's rows: its registration
    (instrument pose and targets, display units) and its RMS there; null without one."""
    baseline = cal.baseline
    if baseline is None:
        return None
    arm = cal.arm
    shown = baseline.params * arm.display_scale
    return {
        "what": "the nominal arm with its own instrument pose and targets, fitted on the "
        "calibration's rows (the geometry nominal)",
        "rows": baseline.rows,
        "rms_per_point_mm": baseline.rms_per_point_mm,
        "parameters": [
            {"name": name, "unit": unit, "value": float(v)}
            for name, unit, v, free in zip(
                arm.param_names, arm.param_units, shown, arm.registration_params, strict=True
            )
            if free
        ],
    }


def _baseline_from_dict(arm: FitModel, data: Any) -> np.ndarray | None:
    """The geometric arm's parameters of a calibration file's ``baseline`` (None without)."""
    if data is None:
        return None
    values = np.array(arm.held_values, dtype=float)
    names = list(arm.param_names)
    for entry in data["parameters"]:
        name = str(entry["name"])
        if name not in names:
            raise ValueError(f"{name} is not a parameter of the robot")
        i = names.index(name)
        values[i] = float(entry["value"]) / arm.display_scale[i]
    if not np.all(np.isfinite(values)):
        raise ValueError("values must be finite numbers")
    return values


def calibration_document(
    cal: Calibration,
    *,
    warnings: Sequence[ArmcalWarning] | None = None,
    words: Mapping[str, str] = ACTIONS,
) -> dict:
    """The ``armcal-calibration/1`` document of a calibration (see PRODUCT.md).

    Parameters
    ----------
    cal : Calibration
    warnings : sequence of ArmcalWarning, optional
        Every warning of the run (the robot file's, the measurement file's, the
        plausibility checks', the calibration's); default ``cal.warnings``.
    words : mapping, optional
        The words of the warnings' advice (:meth:`armcal.errors.ArmcalWarning.render`);
        default the library's.

    Returns
    -------
    dict
        The contract keys, plus ``goodness_of_fit`` ``{chi2, dof, p_value,
        p_value_below}`` (the two tails; null chi2 and p-values when sigma was
        estimated), ``standardized_residuals``
        per pose, ``outliers`` (``{row, pose, target, residual_mm, studentized,
        removed}``), ``noise`` (the noise model or null), ``fixed`` (names; their
        parameters carry ``"fixed": true`` and std 0).  No NaN anywhere.
    """
    arm = cal.arm
    turn_rms = cal.orientation_residual_rms_deg
    parts = sigma_parts(cal.model, cal.conditions, cal.sigma_mm)  # coordinates' and turns'
    sigma = (
        {"sigma_mm": cal.sigma_mm}
        if parts is None
        else {"sigma_mm": parts[0], "sigma_turn_deg": float(np.degrees(parts[1]))}
    )
    return {
        "format": CALIBRATION_FORMAT,
        "armcal_version": __version__,
        "robot": robot_to_dict(arm),
        "method": cal.method,
        "robust": bool(cal.robust),
        "poses": cal.n_poses,
        "poses_used": cal.n_used,
        **sigma,
        # a camera's sigma and residuals are pixels, under the same keys
        **({} if cal.model.reading_unit == "mm" else {"reading_unit": cal.model.reading_unit}),
        "sigma_source": cal.sigma_source,
        "noise": None if arm.noise is None else arm.noise.to_dict(),
        "elastostatic": _elastostatic_dict(cal),
        "fixed": list(cal.model.fixed),
        "parameters": _parameters_list(cal),
        "covariance": {"names": list(cal.names), "matrix": cal.covariance_display.tolist()},
        "correlation": {"names": list(cal.names), "matrix": cal.correlation.tolist()},
        "residual_rms_mm": cal.residual_rms,
        "residual_rms_per_coordinate_mm": cal.residual_rms,
        "residual_rms_per_point_mm": cal.residual_rms_per_point,
        "residual_max_mm": cal.residual_max,
        **({} if turn_rms is None else {"orientation_residual_rms_per_axis_deg": turn_rms}),
        "degrees_of_freedom": cal.dof,
        "goodness_of_fit": _goodness_dict(cal),
        "residuals": _residuals_list(cal),
        "standardized_residuals": _standardized_list(cal),
        "outliers": _outliers_list(cal),
        "iterations": cal.iterations,
        "converged": cal.converged,
        "plane": None if cal.plane is None else cal.plane.to_dict(),
        "baseline": _baseline_dict(cal),
        "training_rows": _rows_dict(cal),
        "warnings": [w.to_dict(words) for w in (cal.warnings if warnings is None else warnings)],
    }


def _parameters_list(cal: Calibration) -> list[dict[str, Any]]:
    """``parameters``: every parameter's name, unit, value and std (display units); a
    fixed one has std 0."""
    fixed = cal.model.fixed
    return [
        {
            "name": name,
            "unit": unit,
            "value": float(v),
            "std": 0.0 if name in fixed else float(s),
            "fixed": name in fixed,
        }
        for name, unit, v, s in zip(cal.names, cal.units, cal.values, cal.std, strict=True)
    ]


def _goodness_dict(cal: Calibration) -> dict[str, Any]:
    """``goodness_of_fit``: chi-square, its degrees of freedom and both tails' p-values
    (null where sigma was estimated)."""
    fit = cal.goodness_of_fit
    return {
        "chi2": None if fit is None else _finite_or_none(fit.chi2),
        "dof": cal.dof if fit is None else int(fit.dof),
        "p_value": None if fit is None else _finite_or_none(fit.p_value),
        "p_value_below": None if fit is None else _finite_or_none(fit.p_below),
    }


def _row_numbers(cal: Calibration) -> list[int]:
    """The measurement file's row of every residual (1, 2, ... where the rows are not known)."""
    return [int(r) for r in cal.rows] if cal.rows else list(range(1, cal.n_poses + 1))


def _residuals_list(cal: Calibration) -> list[dict[str, Any]]:
    """``residuals``: every row's residual (mm; a 6-DoF instrument's turns in degrees), its
    pose and target, and whether the fit used it."""
    # Python numbers, column by column (a 10^5-row table indexed row by row in numpy is slow).
    used = [True] * cal.n_poses if cal.used is None else np.asarray(cal.used, bool).tolist()
    labels = list(cal.arm.target_labels)
    targets = (  # one target of the default name has no label of its own
        [None] * cal.n_poses
        if cal.target is None or not labels
        else [labels[t] for t in cal.target.tolist()]
    )
    axes = ("dx_mm", "dy_mm", "dz_mm", "drx_deg", "dry_deg", "drz_deg")[: cal.residuals.shape[1]]
    shown = np.array(cal.residuals, dtype=float)
    shown[:, 3:] = np.degrees(shown[:, 3:])  # a 6-DoF instrument's turns, in degrees
    turn = cal.turn_rows
    if not np.any(turn):
        return _records(
            ("row", "pose", "target", *axes, "used"),
            _row_numbers(cal), cal.pose_labels, targets, *shown.T.tolist(), used,
        )  # fmt: skip
    shown[turn] = np.degrees(shown[turn])  # partial coordinates' turns, in degrees
    units = np.where(turn, "deg", cal.model.reading_unit).tolist()
    return _records(
        ("row", "pose", "target", "residual", "unit", "used"),
        _row_numbers(cal), cal.pose_labels, targets, shown[:, 0].tolist(), units, used,
    )  # fmt: skip


def _standardized_list(cal: Calibration) -> list[dict[str, Any]]:
    """``standardized_residuals``: every row's whitened residual (none where the fit has none)."""
    standardized = cal.standardized_residuals
    if standardized is None:
        return []
    axes = _AXES[: standardized.shape[1]]
    return _records(
        ("row", "pose", *axes), _row_numbers(cal), cal.pose_labels, *standardized.T.tolist()
    )


def _records(keys: tuple[str, ...], *columns: Sequence[Any]) -> list[dict[str, Any]]:
    """One object per row of ``columns`` (one per key, of equal length), keys in order."""
    return [dict(zip(keys, values, strict=True)) for values in zip(*columns, strict=True)]


def _outliers_list(cal: Calibration) -> list[dict[str, Any]]:
    """``outliers``: every row the robust fit flagged, and whether it was left out."""
    return [
        {
            "row": int(o.row),
            "pose": o.pose,
            "target": o.target,
            "residual_mm": float(o.residual_mm),
            **({} if o.unit == "mm" else {"unit": o.unit}),  # a turn's in deg, a camera's px
            "studentized": float(o.studentized),
            "removed": bool(o.removed),
        }
        for o in cal.outliers
    ]
