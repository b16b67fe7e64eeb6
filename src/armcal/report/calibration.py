"""A calibration as text: values with their std and units, the fit, outliers, the effect."""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from ..errors import ACTIONS
from ..identification import Calibration
from ..identification.result import STRONG_CORRELATION
from ..models.wording import effect_description, held_sentence
from .common import identified, model_lines, small

__all__ = [
    "effect_lines",
    "format_calibration",
    "format_cross_validation",
]


def _effect_held_lines(cal: Calibration) -> list[str]:
    """The effect's parameters held at zero, each sentence with why: by the user, or because
    the rows cannot identify them (joint compliance of a spatial arm: a joint gravity does
    not twist)."""
    own = set(cal.arm.held_reasons)
    notes = [held_sentence(held) for held in cal.model.held_reasons if held not in own]
    if not notes:
        return []
    effect = cal.model.effect
    name = "the effect" if effect is None else effect.name
    return [f"{name} held at zero:"] + [f"  {note}" for note in notes]


def _fit_line(cal: Calibration) -> str:
    """The goodness of fit in words: chi-square, dof and p-value, or why there is no test."""
    fit = cal.goodness_of_fit
    dof = cal.dof if fit is None else fit.dof
    if fit is None or fit.chi2 is None:
        return f"goodness of fit: sigma estimated from the residuals, no test ({dof} dof)"
    if fit.p_value is None:
        return f"goodness of fit: chi2 = {fit.chi2:.4g} on {dof} dof: no test without dof"
    verdict = "consistent with sigma"
    if fit.too_large:
        verdict = "INCONSISTENT with sigma"
    elif fit.too_good:
        verdict = f"TOO GOOD for sigma (P(chi2 below) = {fit.p_below:.3g})"
    return (
        f"goodness of fit: chi2 = {fit.chi2:.4g} on {dof} dof "
        f"(chi2/dof {fit.chi2 / max(dof, 1):.3g}), p = {fit.p_value:.3g}: {verdict}"
    )


def _turn_residual(cal: Calibration) -> str:
    """The orientation residual of a 6-DoF instrument's data, apart from the positions'."""
    turn = cal.orientation_residual_rms_deg
    return "" if turn is None else f"orientation residual RMS {turn:.4g} deg per axis; "


def _outlier_lines(cal: Calibration) -> list[str]:
    if not cal.outliers:
        return []
    lines = [
        "",
        f"outliers (studentized residual test, family-wise; {len(cal.outliers)}):",
    ]
    unit = cal.model.reading_unit
    mixed = any(o.unit != unit for o in cal.outliers)  # a turn's in deg: a unit per row
    heading = "residual" if mixed else f"residual {unit}"
    gap = "    " if mixed else ""
    lines.append(f"{'row':>6}  {'pose':<10}{heading:>12}{gap}{'studentized':>13}  status")
    for o in cal.outliers:
        status = "removed from the fit" if o.removed else "flagged, kept in the fit"
        own = f" {o.unit:<3}" if mixed else ""
        lines.append(
            f"{o.row:>6}  {o.pose:<10}{o.residual_mm:>12.4g}{own}{o.studentized:>13.3g}  {status}"
        )
    return lines


def _poses_phrase(cal: Calibration) -> str:
    """``"20 poses"``, or with targets ``"20 poses (60 measurements of 3 targets)"``, or
    where a file's line gives several readings (partial coordinates) ``"20 poses (50
    readings)"``, and the rows left out of the fit."""
    used = cal.n_used
    lines = cal.n_poses  # an instrument's poses of several readings (axes, corners) each
    if cal.model.feature_labels:
        lines = len(set(cal.pose_labels))
    if lines < cal.n_poses:  # a row is one reading of a pose's
        poses = f"{lines} poses ({cal.n_poses} readings)"
    elif cal.target is None:
        poses = f"{cal.n_poses} poses"
    else:  # a row is one target's point of a pose
        targets = max(len(cal.arm.target_labels), 1)
        poses = (
            f"{len(set(cal.pose_labels))} poses ({cal.n_poses} measurements of "
            f"{targets} target{'s' if targets > 1 else ''})"
        )
    if used < cal.n_poses:
        rows = (
            " readings" if lines < cal.n_poses else "" if cal.target is None else " measurements"
        )
        poses += f" ({cal.n_poses - used}{rows} left out of the fit)"
    return poses


def _heading_lines(cal: Calibration, words: Mapping[str, str], header: str) -> list[str]:
    """What was calibrated and how, the model's lines, the effect's held terms, and the
    table's ``header``."""
    arm = cal.arm
    return [
        f"calibration of {arm.name}: {_poses_phrase(cal)}, {identified(arm)}"
        + (
            ""
            if cal.nested is None
            else f" and {len(cal.nested.names)} of {cal.nested.effect.name}"
        )
        + f", method {cal.method}"
        + (", robust" if cal.robust else ""),
        *model_lines(arm, plan=False, words=words, registered=True),
        *_effect_held_lines(cal),
        "",
        header,
    ]


def _parameter_lines(cal: Calibration, truth: np.ndarray | None) -> list[str]:
    """One line per parameter: value ± std (or ``fixed``) and unit, with the truth and
    the error in standard errors when ``truth`` is given; those a rule holds are left
    out (listed with why in the heading)."""
    arm = cal.arm
    truth_display = None if truth is None else np.asarray(truth) * cal.display_scale
    # held by a rule, listed with why above: the spatial arm's, and its effect's (compliance)
    merged = set(arm.rule_held)
    model, mine = cal.model, set(arm.param_names)
    merged |= {
        n
        for n, free in zip(model.param_names, model.free, strict=True)
        if not free and n not in mine
    }
    lines = []
    for i, (name, unit) in enumerate(zip(cal.names, cal.units, strict=True)):
        if name in merged:
            continue  # held by the identifiable-set rule: listed with why, above
        if name in arm.fixed:
            line = f"{name:<10}{cal.values[i]:>12.5f}  {'fixed':<10}  {unit:<4}"
        else:
            line = f"{name:<10}{cal.values[i]:>12.5f}  ± {small(cal.std[i], 5):<8}  {unit:<4}"
        if truth_display is not None:
            line += f"{truth_display[i]:>12.5f}"
            if name not in arm.fixed and cal.std[i] > 0:
                line += f"{(cal.values[i] - truth_display[i]) / cal.std[i]:>+11.2f}"
        lines.append(line.rstrip())
    return lines


def _fit_lines(cal: Calibration) -> list[str]:
    """Sigma and the residuals, the goodness of fit, the solver, strong correlations (in the
    readings' unit: mm, a camera's px)."""
    worst = cal.worst_pose
    u = cal.model.reading_unit
    lines = [
        "",
        f"sigma {cal.sigma_text} ({cal.sigma_source}); "
        f"residual RMS {cal.residual_rms:.4g} {u} per coordinate "
        f"({cal.residual_rms_per_point:.4g} {u} per point), "
        f"max {cal.residual_max:.4g} {u} at pose {cal.pose_labels[worst]}; "
        + _turn_residual(cal)
        + f"{cal.dof} degrees of freedom",
        _fit_line(cal),
        f"{cal.method}: {cal.iterations} iteration(s), "
        + ("converged" if cal.converged else "NOT converged: the estimate may be off"),
    ]
    strong = [f"{a}/{b} {r:+.2f}" for a, b, r in cal.strong_correlations()]
    if strong:
        lines.append(f"strongly correlated (|r| > {STRONG_CORRELATION:g}): " + ", ".join(strong))
    return lines


def _plane_lines(cal: Calibration) -> list[str]:
    """The plane of motion fitted to 3-D data of a planar arm, when there is one."""
    if cal.plane is None:
        return []
    plane = cal.plane
    offsets = ", ".join(
        f"{label or 'all'} {d:+.4g}"
        for label, d in zip(plane.labels or ("",), plane.offsets, strict=True)
    )
    normal = ", ".join(f"{v:.4f}" for v in plane.normal)
    return [
        "",
        f"3-D data: plane of motion fitted with normal ({normal}) in the instrument frame; "
        f"out of plane RMS {plane.rms_mm:.4g} mm per point, max {plane.max_mm:.4g} mm; target "
        f"planes at {offsets} mm; x0, y0, phi0 are the base pose in the plane's axes",
    ]


def format_calibration(
    cal: Calibration, *, truth: np.ndarray | None = None, words: Mapping[str, str] = ACTIONS
) -> str:
    """Human-readable table of a calibration: value ± std with units, and a fit summary.

    Parameters
    ----------
    cal : Calibration
    truth : ndarray, shape (p,), optional
        Known deviations (internal units) of a virtual robot; adds columns with the
        truth and the error in standard errors.
    words : mapping, optional
        The words of the advice in the text (:func:`armcal.errors.render`; default
        the library's).

    Returns
    -------
    str
        Lines without a trailing newline: the model (fixed parameters, a noise
        model that is not isotropic iid), the parameters (fixed ones marked
        ``fixed``), sigma and residuals, the goodness of fit, the outliers.
    """
    header = f"{'parameter':<10}{'value':>12}  {'± std':>10}  unit"
    if truth is not None:
        header += f"{'truth':>12}{'error/std':>11}"
    lines = [
        *_heading_lines(cal, words, header),
        *_parameter_lines(cal, truth),
        *_fit_lines(cal),
        *_outlier_lines(cal),
        *_plane_lines(cal),
        *effect_lines(cal),
    ]
    return "\n".join(lines)


def effect_lines(cal: Calibration) -> list[str]:
    """What the model's effect explains: residuals without it and the deflections fitted."""
    nested = cal.nested
    if nested is None:
        return []
    effect = nested.effect
    out = [
        "",
        f"{effect.name}, {effect_description(effect)}; {effect.nested} alone leaves "
        f"{nested.rms_per_coordinate_mm:.4g} mm residual RMS per coordinate, with "
        f"{effect.short} {cal.residual_rms:.4g} mm per coordinate",
    ]
    deflection = cal.details.get("max_deflection_rad")
    if deflection is not None:
        worst = np.degrees(deflection) * 1e3
        out.append(
            "largest fitted deflection per joint: "
            + ", ".join(f"joint {j + 1} {v:.4g} mdeg" for j, v in enumerate(worst))
        )
    return out


def format_cross_validation(
    summary: dict, per_fold: list[dict] | None = None, unit: str = "mm"
) -> str:
    """The K-fold prediction error against what the calibrations predict and against the
    nominal arm registered on the same training rows; with ``per_fold`` a line a fold;
    in the readings' ``unit`` (a camera's px, under the same keys)."""
    nominal = summary.get("nominal_rms_per_point_mm")
    u = unit
    text = (
        f"cross-validation ({summary['folds']} folds): prediction error RMS per point "
        f"{summary['rms_per_point_mm']:.4g} {u} (max {summary['max_mm']:.4g} {u}); predicted "
        f"{summary['predicted_rms_per_point_mm']:.4g} {u}"
        + (
            f"; orientation RMS {summary['orientation_rms_deg']:.4g} deg (predicted "
            f"{summary['predicted_orientation_rms_deg']:.4g} deg)"
            if "orientation_rms_deg" in summary
            else ""
        )
        + (
            ""
            if nominal is None
            else f"; the nominal arm, registered on its own to the same training rows, "
            f"{nominal:.4g} {u}"
        )
    )
    if not per_fold:
        return text
    lines = [
        text,
        f"{'fold':>6}{'points':>8}{'nominal':>11}{'calibrated':>12}{'predicted':>11}"
        f"   (RMS per point, {u})",
    ]
    for entry in per_fold:
        before = entry["nominal_rms_per_point_mm"]
        lines.append(
            f"{entry['fold']:>6}{entry['points']:>8}"
            + (f"{'-':>11}" if before is None else f"{before:>11.4g}")
            + f"{entry['rms_per_point_mm']:>12.4g}{entry['predicted_rms_per_point_mm']:>11.4g}"
        )
    return "\n".join(lines)
