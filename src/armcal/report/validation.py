"""Validation and compensation as text and JSON: errors before and after, per pose."""

from __future__ import annotations

from typing import Any

import numpy as np

from ..acceptance import ISO_CYCLES, PoseCharacteristics
from ..compensation import Compensation, Payload
from ..files import Measurements, Program
from ..models import CalibratedArm
from ..validation import Validation

__all__ = [
    "acceptance_report",
    "compensation_report",
    "validation_report",
]


def _rows_words(m: int, poses: int | None, result: Validation, unit: str = "points") -> str:
    """What validation ran on: ``m`` rows (``unit``: points of targets, readings of
    partial coordinates) of ``poses`` poses (None: a row is a pose), held out, or not
    all (the calibration's own rows are not called held-out)."""
    reused = 0 if result.reused is None else int(np.count_nonzero(result.reused))
    if not reused:
        return f"{m} held-out poses" if poses is None else f"{poses} held-out poses ({m} {unit})"
    own = f"{'all' if reused == m else reused} of them the calibration's own rows, not held out"
    return f"{m} poses ({own})" if poses is None else f"{poses} poses ({m} {unit}, {own})"


def _error_header(model: Any) -> str:
    """The table's heading: a position's error in mm, a camera's reading's in pixels."""
    unit = model.reading_unit
    return "position error (mm)" if unit == "mm" else f"reading error ({unit})"


def validation_report(
    cal: CalibratedArm, result: Validation, meas: Measurements, *, per_pose: bool = False
) -> tuple[dict, str]:
    """The ``validate`` document and text: errors before and after, predicted, per pose."""
    s = result.summary()
    m = len(meas.labels)  # every row validated (a turn's rows' errors apart, result.turns)
    index = np.arange(m) if result.kept is None else result.kept  # the rows of result's arrays
    poses = len(set(meas.labels))
    if meas.targets is not None:
        held = _rows_words(m, poses, result)
    else:  # an instrument's poses of several readings each (axes, a photo's corners)
        several = bool(cal.arm.feature_labels) and poses < m
        held = _rows_words(m, poses if several else None, result, "readings")
    lines = [
        f"validation of {cal.arm.name} on {held}"
        + (" (3-D, projected into the calibration's plane)" if cal.plane is not None else ""),
        "",
        f"{_error_header(cal.arm):<24}{'RMS':>10}{'95 %':>10}{'max':>10}   (per point)",
        f"{'nominal arm':<24}{s['rms_before_per_point_mm']:>10.4g}"
        f"{s['p95_before_mm']:>10.4g}{s['max_before_mm']:>10.4g}",
        f"{'calibrated model':<24}{s['rms_after_per_point_mm']:>10.4g}"
        f"{s['p95_after_mm']:>10.4g}{s['max_after_mm']:>10.4g}",
        f"{'predicted (calibrated)':<24}{s['predicted_rms_after_per_point_mm']:>10.4g}",
        "",
        f"predicted = the noise of a measurement and the calibration's own uncertainty "
        f"({s['model_rms_per_point_mm']:.3g} {cal.arm.reading_unit} RMS per point at these "
        "poses)",
        _baseline_line(result.baseline_rows),
    ]
    document: dict = {"poses": m, **s, "baseline": result.baseline_rows}
    if cal.arm.reading_unit != "mm":  # a camera's errors are pixels, under the same keys
        document["reading_unit"] = cal.arm.reading_unit
    if result.turns is not None:
        lines[6:6] = [
            "",
            f"{'orientation error (deg)':<24}{'RMS':>10}{'':>10}{'max':>10}   "
            + (
                "(angle of the turn)"
                if result.turns.after.shape[1] == 3
                else "(a turn's component)"
            ),
            f"{'nominal arm':<24}{s['orientation_rms_before_deg']:>10.4g}",
            f"{'calibrated model':<24}{s['orientation_rms_after_deg']:>10.4g}{'':>10}"
            f"{s['orientation_max_after_deg']:>10.4g}",
            f"{'predicted (calibrated)':<24}{s['predicted_orientation_rms_after_deg']:>10.4g}",
        ]
    if "out_of_plane_rms_per_point_mm" in s:
        lines.append(
            f"out of the calibration's plane: RMS {s['out_of_plane_rms_per_point_mm']:.3g} mm "
            f"per point, max {s['out_of_plane_max_mm']:.3g} mm"
        )
    if per_pose:
        targets = meas.targets
        lines += [
            "",
            f"{'row':>5}  {'pose':<8}{'target':<8}{'before mm':>11}{'after mm':>10}"
            f"{'predicted':>11}",
        ]
        rows = []
        for k, i in enumerate(index.tolist()):
            target = "" if targets is None else targets[i]
            rows.append(
                {
                    "row": int(meas.rows[i]),
                    "pose": meas.labels[i],
                    "target": None if targets is None else target,
                    "before_mm": float(result.before_mm[k]),
                    "after_mm": float(result.after_mm[k]),
                    "predicted_mm": float(result.predicted_mm[k]),
                }
            )
            lines.append(
                f"{meas.rows[i]:>5}  {meas.labels[i]:<8}{target:<8}"
                f"{result.before_mm[k]:>11.4g}{result.after_mm[k]:>10.4g}"
                f"{result.predicted_mm[k]:>11.4g}"
            )
        document["per_pose"] = rows
    return document, "\n".join(lines)


def _baseline_line(rows: str) -> str:
    """What the nominal arm's row is: the arm a user has without calibrating."""
    if rows == "calibration":
        return (
            "nominal arm = the nominal geometry with its own instrument pose and targets, "
            "fitted on the calibration's rows (what the arm does without calibration)"
        )
    return (
        "nominal arm = the nominal geometry with its own instrument pose and targets, fitted "
        "on these held-out rows: the calibration file records no baseline of its own rows, so "
        "this flatters the nominal arm (identify again to record one)"
    )


def acceptance_report(found: PoseCharacteristics) -> tuple[dict, list[str]]:
    """The ISO 9283 section of ``validate --iso9283``: every pose's cycles, pose accuracy
    against the nominal and the calibrated model, and repeatability, and the worst pose."""
    s = found.summary()
    targets = found.targets
    lines = [
        "",
        f"ISO 9283 pose characteristics (clause 7.2; {ISO_CYCLES} cycles per pose asked, 6.9)",
        f"{'pose':<10}{'target':<8}{'cycles':>7}{'AP before':>11}{'AP after':>10}{'RP':>9}   (mm)",
    ]
    poses = []
    for g, pose in enumerate(found.poses):
        target = "" if targets is None else targets[g]
        before, after = found.accuracy_before_mm[g], found.accuracy_after_mm[g]
        rp = found.repeatability_mm[g]
        lines.append(
            f"{pose:<10}{target:<8}{found.cycles[g]:>7}{before:>11.4g}{after:>10.4g}{rp:>9.4g}"
        )
        poses.append(
            {
                "pose": pose,
                "target": None if targets is None else target,
                "cycles": int(found.cycles[g]),
                "ap_before_mm": float(before),
                "ap_after_mm": float(after),
                "ap_before_xyz_mm": found.accuracy_before[g].tolist(),
                "ap_after_xyz_mm": found.accuracy_after[g].tolist(),
                "rp_mm": float(rp),
                "barycentre_mm": found.barycentres[g].tolist(),
            }
        )
    if found.orientation_after is not None:
        lines += _orientation_lines(found, poses)
    lines += [
        f"{'worst pose':<25}{s['ap_before_mm']:>11.4g}{s['ap_after_mm']:>10.4g}{s['rp_mm']:>9.4g}",
        "AP: from the command position (where the nominal arm, registered on its own, or the "
        "calibrated model puts the commanded joints) to the mean attained position (7.2.1); "
        "RP = lbar + 3 S_l of the attained positions about their mean (7.2.2)",
    ]
    return {**s, "per_pose": poses}, lines


def _orientation_lines(found: PoseCharacteristics, poses: list[dict]) -> list[str]:
    """A 6-DoF instrument's orientation AP_a..c (after calibration) and RP_a..c per pose, in
    degrees; adds them to every pose's JSON."""
    turns = (found.orientation_before, found.orientation_after, found.orientation_repeatability)
    before, after, spread = (np.degrees(v) for v in turns if v is not None)
    lines = [
        f"{'orientation (deg)':<18}{'AP_a':>9}{'AP_b':>9}{'AP_c':>9}{'RP_a':>9}{'RP_b':>9}"
        f"{'RP_c':>9}   (after calibration; RP a +- band)",
    ]
    for g, (entry, name) in enumerate(zip(poses, found.names, strict=True)):
        lines.append(f"{name:<18}" + "".join(f"{v:>9.3g}" for v in (*after[g], *spread[g])))
        entry["ap_before_abc_deg"] = before[g].tolist()
        entry["ap_after_abc_deg"] = after[g].tolist()
        entry["rp_abc_deg"] = spread[g].tolist()
    return lines


def compensation_report(
    cal: CalibratedArm,
    result: Compensation,
    program: Program,
    payload: Payload | None = None,
) -> tuple[dict, str]:
    """The ``compensate`` document and text, with the ``payload`` the sag was corrected
    under for a calibration with joint compliance."""
    s = result.summary()
    m = result.q.shape[0]
    bad = result.uncorrectable
    lines = [
        f"compensated {m - bad.size} of {m} poses for {cal.arm.name} (robot frame; the "
        "instrument's pose is not corrected)",
        f"predicted position error: RMS per point {s['rms_before_per_point_mm']:.4g} mm "
        f"before, {s['rms_after_per_point_mm']:.4g} mm after (the calibration's uncertainty)",
    ]
    before, after = (
        s["orientation_rms_before_per_pose_deg"],
        s["orientation_rms_after_per_pose_deg"],
    )
    if before is not None and after is not None:
        # Below 1e-9 deg is round-off: a planar arm's registered tool frame takes up every
        # joint zero, so its orientation is the calibrated one's exactly.
        shown = "0" if before < 1e-9 else f"{before:.4g}"
        lines.append(
            f"predicted tool orientation error: RMS per pose {shown} deg before, "
            f"{after:.4g} deg after"
        )
    lines.append(f"largest joint change: {result.largest_change_deg:.4g} deg")
    labels = program.labels or tuple(str(i + 1) for i in range(m))
    uncorrectable = [
        {"row": int(i) + 1, "pose": labels[i], "reason": result.reasons[i]} for i in bad
    ]
    document = {
        "poses": m,
        **s,
        "corrected": int(m - bad.size),
        "uncorrectable": uncorrectable,
        "largest_joint_change_deg": result.largest_change_deg,
    }
    if payload is not None:  # the last line of the text, too
        low, high = payload.low_kg, payload.high_kg
        kg = f"{low:g} kg" if low == high else f"{low:g} to {high:g} kg"
        lines.append(f"sag corrected under a payload of {kg} ({payload.source})")
        document["payload_kg"] = {"min": low, "max": high, "from": payload.source}
    return document, "\n".join(lines)
