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
from collections.abc import Mapping, Sequence
from dataclasses import replace
from typing import Any

import numpy as np

from .._version import __version__
from ..errors import ACTIONS, ArmcalWarning, InputError, unrendered
from ..identification import Calibration
from ..models import (
    Annulus,
    Box,
    CalibratedArm,
    CompliantArm,
    CompliantSerialArm,
    Conditions,
    Elastostatic,
    FitModel,
    Loads,
    PlanarArm,
    Plane,
    Region,
    SerialChain,
    SerialElastics,
    SpatialArm,
    Target,
    TermChoice,
)
from ..noise import NoiseModel, TrackerNoise
from .checked import BadKey, array_of, check_covariance, described, list_of, number_of
from .common import fail, read_text
from .kinds import looks_like
from .robots import parse_region

__all__ = [
    "CALIBRATION_FORMAT",
    "calibration_document",
    "read_calibration",
    "robot_to_dict",
]

# --------------------------------------------------------------------------- calibration JSON

#: The format tag of calibration files (PRODUCT.md); other formats are refused.
CALIBRATION_FORMAT = "armcal-calibration/1"


def _region_to_dict(region: Region | None) -> dict[str, Any] | None:
    if isinstance(region, Annulus):
        return {
            "kind": "annulus",
            "center_mm": list(region.center),
            "r_min_mm": region.r_min,
            "r_max_mm": region.r_max,
        }
    if isinstance(region, Box):
        return {"kind": "box", "x_mm": list(region.x), "y_mm": list(region.y)}
    return None


#: The coordinates of a standardized residual: a point's, then a 6-DoF instrument's turn.
_AXES = ("x", "y", "z", "rx", "ry", "rz")


def serial_robot_to_dict(arm: SpatialArm) -> dict[str, Any]:
    """The ``robot`` section of a spatial arm's calibration: the chain as joint origins
    (mm, rad: 4 x 4 transforms), the joint map and limits, the targets, and the
    identifiable set with why the rest is held."""
    return {
        "name": arm.name,
        "kind": "serial",
        "joint_types": list(arm.chain.kinds),
        "joint_names": list(arm.chain.joint_names),
        "origins": arm.chain.origins.tolist(),
        "tip": arm.chain.tip.tolist(),
        "joint_map": arm.joint_map.tolist(),
        "joint_limits": arm.limits.tolist(),
        "chain_limits": np.clip(arm.chain.joint_limits, -1e300, 1e300).tolist(),  # JSON: no inf
        "targets": list(arm.targets),
        "target_positions_mm": arm.target_positions.tolist(),
        "base_pose": arm.base_pose.tolist(),
        "known_targets": arm.known_targets,
        **(
            {"oriented": True, "target_turns_rad": arm.target_turns.tolist()}
            if arm.oriented
            else {}
        ),
        "held": list(arm.held),
        "merges": list(arm.merges),
    }


def _serial_from_dict(
    data: dict[str, Any], noise: NoiseModel | None, fixed: list[str]
) -> SpatialArm:
    """The spatial arm of a calibration file's ``robot`` section (:func:`serial_robot_to_dict`)."""
    kinds = tuple(str(k) for k in list_of(data, "joint_types", "'R' or 'P' per joint"))
    n = len(kinds)
    if n == 0 or any(k not in ("R", "P") for k in kinds):
        raise BadKey("robot.joint_types", f"expected 'R' or 'P' per joint, got {kinds!r}")
    pairs = f"{n} pairs [lo, hi]"
    limits = array_of(data, "chain_limits", (n, 2), f"{pairs} (the URDF's limits, rad or mm)")
    chain = SerialChain(
        array_of(data, "origins", (n, 4, 4), f"{n} joint origins, each a 4 x 4 transform (mm)"),
        kinds,
        array_of(data, "tip", (4, 4), "the tip frame, a 4 x 4 transform (mm)"),
        tuple(str(name) for name in list_of(data, "joint_names", f"{n} joint names", n)),
        np.where(np.abs(limits) >= 1e300, np.copysign(np.inf, limits), limits),
    )
    targets = tuple(str(label) for label in list_of(data, "targets", "the target labels"))
    k = len(targets)
    held = tuple(str(name) for name in list_of(data, "held", "the parameters held"))
    arm = SpatialArm(
        chain,
        str(data["name"]),
        array_of(data, "joint_map", (n, n), f"a {n} x {n} matrix (joint values from readings)"),
        array_of(data, "joint_limits", (n, 2), f"{pairs} (the readings' limits, rad or mm)"),
        targets=targets,
        target_positions=array_of(
            data, "target_positions_mm", (k, 3), f"{k} positions [x, y, z] (mm), one per target"
        ),
        base_pose=array_of(
            data, "base_pose", (6,), "6 numbers: the instrument's x, y, z (mm), rx, ry, rz (rad)"
        ),
        noise=noise,
        held=held,
        merges=tuple(str(text) for text in list_of(data, "merges", "sentences")),
        known_targets=bool(data["known_targets"]),
        oriented=bool(data.get("oriented", False)),
        target_turns=array_of(
            data, "target_turns_rad", (-1, 3), "a rotation vector (rad) per target", []
        ),
    )
    # "fixed" lists every parameter held, by the user or a rule, an effect's too
    own = set(arm.layout.names) - set(held)
    return arm.replace(user_fixed=tuple(name for name in fixed if name in own))


def robot_to_dict(arm: PlanarArm | SpatialArm) -> dict[str, Any]:
    """The ``robot`` section of a calibration file: everything needed to rebuild the arm.

    ``name``, ``link_lengths_mm``, ``joint_limits_deg``, ``base_offset``,
    ``base_rotation``, ``joint_map``, ``joint_offsets_deg``, ``targets``
    (label to ``{length_mm, angle_deg}``) and ``region`` (or null); the noise
    model and the fixed parameters are top-level keys of the document.
    """
    if isinstance(arm, SpatialArm):
        return serial_robot_to_dict(arm)
    return {
        "name": arm.name,
        "link_lengths_mm": arm.link_lengths.tolist(),
        "joint_limits_deg": arm.joint_limits_deg.tolist(),
        "base_offset": arm.base_offset,
        "base_rotation": arm.base_rotation,
        "joint_map": arm.joint_map.tolist(),
        "joint_offsets_deg": np.degrees(arm.joint_offsets).tolist(),
        "targets": {
            t.label: {"length_mm": t.length, "angle_deg": math.degrees(t.angle)}
            for t in arm.targets
        },
        "region": _region_to_dict(arm.region),
    }


def _arm_from_dict(data: dict[str, Any], noise: NoiseModel | None, fixed: list[str]) -> PlanarArm:
    region = None
    if data.get("region") is not None:
        region = parse_region("", data["region"])
    targets = tuple(
        Target(label, float(entry["length_mm"]), math.radians(float(entry["angle_deg"])))
        for label, entry in data.get("targets", {}).items()
    )
    lengths = array_of(data, "link_lengths_mm", (-1,), "the nominal link lengths (mm)")
    n = lengths.size
    if n == 0:
        raise BadKey("robot.link_lengths_mm", "expected the nominal link lengths (mm); got none")
    each = f"for each of the {n} links in robot.link_lengths_mm"  # the count the rest follow
    offsets = data.get("joint_offsets_deg")
    joint_map = None
    if data.get("joint_map") is not None:
        joint_map = array_of(
            data, "joint_map", (n, n), f"the matrix theta = M q, a row and column {each}"
        )
    return PlanarArm(
        lengths,
        np.radians(array_of(data, "joint_limits_deg", (n, 2), f"a pair [lo, hi] (deg) {each}")),
        base_offset=bool(data["base_offset"]),
        name=str(data["name"]),
        noise=noise,
        region=region,
        fixed=fixed,
        joint_map=joint_map,
        targets=targets,
        base_rotation=bool(data.get("base_rotation", False)),
        joint_offsets=None
        if offsets is None
        else np.radians(array_of(data, "joint_offsets_deg", (n,), f"a joint offset (deg) {each}")),
    )


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
    key = "robot"
    try:
        noise = None
        if doc.get("noise") is not None:
            key = "noise"
            sigma_q = doc["noise"].get("joint_sigma_deg")
            tracker = doc["noise"].get("tracker")
            turn = doc["noise"].get("orientation_sigma_deg")
            noise = NoiseModel(
                np.array(doc["noise"]["covariance_mm2"], dtype=float),
                None if sigma_q is None else np.radians(np.array(sigma_q, dtype=float)),
                tracker=None if tracker is None else TrackerNoise(**tracker),
                orientation_sigma=None if turn is None else math.radians(float(turn)),
            )
        key = "robot"
        fixed = list(doc.get("fixed", []))
        serial = doc["robot"].get("kind") == "serial"
        arm: PlanarArm | SpatialArm = (
            _serial_from_dict(doc["robot"], noise, fixed)
            if serial
            else _arm_from_dict(doc["robot"], noise, [n for n in fixed if n not in _terms(doc)])
        )
        model: FitModel = arm
        if doc.get("elastostatic") is not None:
            key = "elastostatic"
            model = _compliance_from_dict(arm, doc["elastostatic"], fixed)
        key = "training_rows"
        rows = _rows_from_dict(doc.get("training_rows"), arm.n_joints, len(arm.target_labels))
        key = "parameters"
        entries = list_of(doc, "parameters", "an entry per parameter", where="")
        names = [entry["name"] for entry in entries]
        expected = model.param_names
        if tuple(names) != expected:
            raise ValueError(
                f"parameters {', '.join(names)} do not match the robot's {', '.join(expected)}"
            )
        scale = model.display_scale
        values = np.array(
            [number_of(e.get("value"), "parameters", f"the value of {e['name']}") for e in entries]
        )
        values = values / scale
        stds = [entry.get("std") for entry in entries]
        key = "covariance"
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
        full = shown / np.outer(scale, scale)
        key = "sigma_mm"
        sigma = number_of(doc.get("sigma_mm"), key, "the noise std (mm)")
        if not sigma > 0:
            raise ValueError(f"expected a positive noise std in mm, got {sigma}")
        key = "plane"
        plane = None if doc.get("plane") is None else Plane.from_dict(doc["plane"])
        key = "baseline"
        baseline = _baseline_from_dict(arm, doc.get("baseline"))
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
    if plane is None and isinstance(arm, PlanarArm) and arm.base_rotation:
        raise fail(path, "key 'plane': a calibration from 3-D data must record its plane")
    if rows is not None and not np.all(np.isfinite(rows.q)):
        raise fail(path, "key 'training_rows': joint readings must be finite numbers")
    return CalibratedArm(model, values, full, sigma, plane, rows, baseline)


def _terms(doc: dict[str, Any]) -> list[str]:
    """The compliance terms of a calibration file (none without an ``elastostatic`` section)."""
    section = doc.get("elastostatic")
    return [] if not isinstance(section, dict) else list(section.get("parameters", []))


def _compliance_from_dict(
    arm: PlanarArm | SpatialArm, data: dict[str, Any], fixed: Sequence[str]
) -> CompliantArm | CompliantSerialArm:
    """The compliance model of a calibration file's ``elastostatic`` section; of the terms
    ``fixed`` lists, those the rule did not hold (``held``) the user held."""
    rule = set(data.get("held", []))
    terms = data.get("parameters", [])  # older planar files: none held
    user = TermChoice(fixed=tuple(n for n in fixed if n in terms and n not in rule))
    if isinstance(arm, SpatialArm):
        serial = CompliantSerialArm(
            arm,
            replace(SerialElastics.from_dict(data, arm.n_joints), terms=user),
            bool(data["known_loads"]),
            tuple(str(name) for name in data["held"]),
            tuple(str(text) for text in data["merges"]),
        )
        if list(data["parameters"]) != list(serial.compliance_names):
            raise ValueError(
                f"compliance parameters do not match {', '.join(serial.compliance_names)}"
            )
        return serial
    gravity = data["gravity_mps2"]
    masses = data["link_masses_kg"]
    elastic = Elastostatic(
        None if gravity is None else np.array(gravity, dtype=float).reshape(2),
        None if masses is None else np.array(masses, dtype=float).reshape(arm.n_joints),
        np.array(data["com_fraction"], dtype=float).reshape(arm.n_joints),
        float(data["payload_kg"]),
        user,
    )
    model = CompliantArm(arm, elastic, bool(data["known_loads"]))
    if list(data.get("parameters", model.compliance_names)) != list(model.compliance_names):
        raise ValueError(f"compliance parameters do not match {', '.join(model.compliance_names)}")
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
    return Conditions(q, target, loads)


def _elastostatic_dict(cal: Calibration) -> dict | None:
    """The loads model of a fit with compliance, enough to rebuild it (gravity in m/s^2),
    and the rows it used."""
    model, nested = cal.model, cal.nested
    if isinstance(model, CompliantSerialArm) and nested is not None:
        return {
            **model.elastic.to_dict(),
            "known_loads": model.known_loads,
            "parameters": list(model.compliance_names),
            "held": list(model.held),
            "merges": list(model.merges),
            "geometry_only_rms_per_coordinate_mm": nested.rms_per_coordinate_mm,
        }
    if not isinstance(model, CompliantArm) or nested is None:
        return None
    elastic = model.elastic
    return {
        "gravity_mps2": None if elastic.gravity is None else elastic.gravity.tolist(),
        "link_masses_kg": None
        if elastic.link_masses_kg is None
        else elastic.link_masses_kg.tolist(),
        "com_fraction": elastic.com_fraction.tolist(),
        "payload_kg": elastic.payload_kg,
        "known_loads": model.known_loads,
        "parameters": list(model.compliance_names),
        "geometry_only_rms_per_coordinate_mm": nested.rms_per_coordinate_mm,
    }


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
    corr = cal.correlation
    fit = cal.goodness_of_fit
    # Python numbers, column by column (a 10^5-row table indexed row by row in numpy is slow).
    rows = [int(r) for r in cal.rows] if cal.rows else list(range(1, cal.n_poses + 1))
    used = [True] * cal.n_poses if cal.used is None else np.asarray(cal.used, bool).tolist()
    labels = list(arm.target_labels)
    targets = (
        [None] * cal.n_poses if cal.target is None else [labels[t] for t in cal.target.tolist()]
    )
    axes = ("dx_mm", "dy_mm", "dz_mm", "drx_deg", "dry_deg", "drz_deg")[: cal.residuals.shape[1]]
    shown = np.array(cal.residuals, dtype=float)
    shown[:, 3:] = np.degrees(shown[:, 3:])  # a 6-DoF instrument's turns, in degrees
    turn_rms = cal.orientation_residual_rms_deg
    standardized = cal.standardized_residuals
    return {
        "format": CALIBRATION_FORMAT,
        "armcal_version": __version__,
        "robot": robot_to_dict(arm),
        "method": cal.method,
        "robust": bool(cal.robust),
        "poses": cal.n_poses,
        "poses_used": cal.n_used,
        "sigma_mm": cal.sigma_mm,
        "sigma_source": cal.sigma_source,
        "noise": None if arm.noise is None else arm.noise.to_dict(),
        "elastostatic": _elastostatic_dict(cal),
        "fixed": list(cal.model.fixed),
        "parameters": [
            {
                "name": name,
                "unit": unit,
                "value": float(v),
                "std": 0.0 if name in cal.model.fixed else float(s),
                "fixed": name in cal.model.fixed,
            }
            for name, unit, v, s in zip(cal.names, cal.units, cal.values, cal.std, strict=True)
        ],
        "covariance": {"names": list(cal.names), "matrix": cal.covariance_display.tolist()},
        "correlation": {"names": list(cal.names), "matrix": corr.tolist()},
        "residual_rms_mm": cal.residual_rms,
        "residual_rms_per_coordinate_mm": cal.residual_rms,
        "residual_rms_per_point_mm": cal.residual_rms_per_point,
        "residual_max_mm": cal.residual_max,
        **({} if turn_rms is None else {"orientation_residual_rms_per_axis_deg": turn_rms}),
        "degrees_of_freedom": cal.dof,
        "goodness_of_fit": {
            "chi2": None if fit is None else _finite_or_none(fit.chi2),
            "dof": cal.dof if fit is None else int(fit.dof),
            "p_value": None if fit is None else _finite_or_none(fit.p_value),
            "p_value_below": None if fit is None else _finite_or_none(fit.p_below),
        },
        "residuals": [
            {"row": row, "pose": label, "target": t, **dict(zip(axes, d, strict=True)), "used": u}
            for row, label, t, d, u in zip(
                rows, cal.pose_labels, targets, shown.tolist(), used, strict=True
            )
        ],
        "standardized_residuals": []
        if standardized is None
        else [
            {"row": row, "pose": label, **dict(zip(_AXES, d, strict=False))}
            for row, label, d in zip(rows, cal.pose_labels, standardized.tolist(), strict=True)
        ],
        "outliers": [
            {
                "row": int(o.row),
                "pose": o.pose,
                "target": o.target,
                "residual_mm": float(o.residual_mm),
                "studentized": float(o.studentized),
                "removed": bool(o.removed),
            }
            for o in cal.outliers
        ],
        "iterations": cal.iterations,
        "converged": cal.converged,
        "plane": None if cal.plane is None else cal.plane.to_dict(),
        "baseline": _baseline_dict(cal),
        "training_rows": _rows_dict(cal),
        "warnings": [w.to_dict(words) for w in (cal.warnings if warnings is None else warnings)],
    }
