"""Every result as text and as JSON: pure functions, no numerics."""

from __future__ import annotations

import json
import math
from collections.abc import Sequence

import numpy as np

from ._version import __version__
from .compensation import Compensation
from .criteria import PlanQuality
from .doe.compliance import CompliantDesign, d_efficiency_compliant
from .doe.designer import Design
from .doe.model import unit_trace
from .doe.sizing import TARGETS, PosesNeeded
from .errors import ArmcalWarning
from .identification import Calibration
from .io import CALIBRATION_FORMAT, Measurements, Program, robot_to_dict
from .models import CalibratedArm, CompliantArm, Loads, PlanarArm, combination
from .models.information import display_std, predicted_covariance
from .paper import PAPER_DIGIT
from .reproduction.compute import TABLE_COLUMNS, Reproduction
from .simulate import MonteCarlo
from .validation import Validation

__all__ = [
    "CALIBRATION_FORMAT",
    "calibration_to_dict",
    "compensation_report",
    "cross_validation_warning",
    "design_summary",
    "format_calibration",
    "format_cross_validation",
    "format_monte_carlo",
    "format_quality",
    "format_reproduction",
    "model_lines",
    "model_to_dict",
    "monte_carlo_to_dict",
    "poses_needed_summary",
    "quality_to_dict",
    "reproduction_summary",
    "table_csv",
    "to_json",
    "validation_report",
    "validation_warnings",
]


def _noise_text(arm: PlanarArm) -> str | None:
    """The noise model in words when it is not isotropic iid (None when it is or is unknown)."""
    noise = arm.noise
    if noise is None or noise.isotropic_iid:
        return None
    cov = noise.covariance_mm2
    if noise.isotropic_instrument:
        parts = [f"instrument isotropic, sigma {math.sqrt(cov[0, 0]):.4g} mm"]
    elif cov[0, 1] == 0:
        parts = [
            f"instrument per axis, sigma_x {math.sqrt(cov[0, 0]):.4g} mm, "
            f"sigma_y {math.sqrt(cov[1, 1]):.4g} mm"
        ]
    else:
        parts = [
            f"instrument covariance [[{cov[0, 0]:.4g}, {cov[0, 1]:.4g}], "
            f"[{cov[1, 0]:.4g}, {cov[1, 1]:.4g}]] mm^2"
        ]
    if noise.joint_sigma is not None:
        joints = np.degrees(np.broadcast_to(noise.joint_sigma, (arm.n_joints,)))
        if np.all(joints == joints[0]):
            parts.append(f"encoder noise {joints[0]:.4g} deg on every joint")
        else:
            parts.append("encoder noise " + ", ".join(f"{v:.4g}" for v in joints) + " deg")
    return "; ".join(parts) + f" (reference sigma {noise.sigma_mm:.4g} mm)"


def model_lines(arm: PlanarArm, *, plan: bool = True) -> list[str]:
    """Lines naming the fixed parameters and a noise model that is not isotropic iid.

    Empty for the paper's model (every parameter free, isotropic iid noise).
    ``plan`` adds, for a noise model that is not isotropic iid, that the paper's
    D*, Table I and analytic plans assume one (what changes the answer for a plan).

    Examples
    --------
    >>> model_lines(PlanarArm([260.0, 180.0], fixed=["dl2"]))
    ['fixed (held at nominal, not identified): dl2']
    """
    lines = []
    if not np.array_equal(arm.joint_map, np.tril(np.ones((arm.n_joints, arm.n_joints)))):
        rows = "; ".join(" ".join(f"{v:g}" for v in row) for row in arm.joint_map)
        lines.append(f"joint map: link angles theta = M q with M = [{rows}]")
    if arm.targets:
        shown = ", ".join(
            f"{t.label} ({t.length:g} mm, {math.degrees(t.angle):g} deg)" for t in arm.targets
        )
        lines.append(f"targets (nominal last link from joint {arm.n_joints}): {shown}")
    if arm.fixed:
        lines.append(f"fixed (held at nominal, not identified): {', '.join(arm.fixed)}")
    if arm.base_rotation and arm.rotation_partner in arm.fixed:
        lines.append(
            f"base rotation phi0 identified, {arm.rotation_partner} held: a rotation of the base "
            f"turns every link vector like the joint offsets {_rotation_words(arm)}, so the data "
            f"cannot tell them apart (--fix phi0 identifies {arm.rotation_partner} instead)"
        )
    noise = _noise_text(arm)
    if noise is not None:
        line = f"noise model: {noise}; not isotropic iid: weighted least squares"
        if plan:
            line += (
                " and the weighted information matrix (the paper's D*, Table I and the "
                "analytic plans assume isotropic iid noise)"
            )
        lines.append(line)
    return lines


def _rotation_words(arm: PlanarArm) -> str:
    """The joint-offset direction a base rotation cannot be told from, e.g. ``dq1 - dq3@A``."""
    k = arm.n_links
    return combination(-arm.rotation_direction[k : 2 * k], arm.param_names[k : 2 * k])


def model_to_dict(arm: PlanarArm) -> dict:
    """JSON keys of the model: ``fixed`` (names), ``noise`` (or null), ``noise_isotropic_iid``."""
    return {
        "fixed": list(arm.fixed),
        "noise": None if arm.noise is None else arm.noise.to_dict(),
        "noise_isotropic_iid": arm.noise is None or arm.noise.isotropic_iid,
    }


def _identified(arm: PlanarArm) -> str:
    """``8 parameters``, or ``7 of 8 parameters identified`` when some are fixed."""
    if not arm.fixed:
        return f"{arm.n_params} parameters"
    return f"{arm.n_free} of {arm.n_params} parameters identified"


def _small(value: float, digits: int) -> str:
    """``value`` with ``digits`` decimals, or in e-notation where they would show < 2 digits.

    >>> _small(0.0224, 5), _small(2.236e-7, 5), _small(0.0, 5)
    ('0.02240', '2.24e-07', '0.00000')
    """
    if value != 0 and abs(value) < 10.0 ** (1 - digits):
        return f"{value:.2e}"
    return f"{value:.{digits}f}"


def _std_cell(arm: PlanarArm, name: str, value: float, width: int, digits: int) -> str:
    """A std column: the number, or ``fixed`` for a fixed parameter."""
    if name in arm.fixed:
        return f"{'fixed':>{width}}"
    return f"{_small(value, digits):>{width}}"


def _efficiency_label(arm: PlanarArm) -> str:
    """What the criteria are relative to: 1 at the optimum only where ``det M <= 1`` holds."""
    if unit_trace(arm):
        return "efficiency (1 = orthogonal optimum)"
    return "criteria of the weighted information (not 1 at this model's optimum; see design)"


def _table1_line(quality: PlanQuality) -> str:
    """The largest of the paper's Table I sums, or that a one-link arm has none."""
    sums = [abs(v) for v in quality.optimality_sums.values()]
    if not sums:
        return "Table I sums: none (one link, no base offset: no optimality condition)"
    return (
        f"largest Table I sum: {max(sums):.3g}"
        f" (0 for an optimal plan; {quality.n_poses} is the worst possible)"
    )


def format_quality(arm: PlanarArm, quality: PlanQuality) -> str:
    """Human-readable report of :func:`evaluate_plan`: criteria, std table, accuracy."""
    eff = quality.efficiencies
    obs = quality.observability
    det_c = f"{float(quality.dstar.det_c):.4f}".replace("-0.0000", "0.0000")
    lines = [
        f"{quality.n_poses} poses of {arm.name}, {_identified(arm)}, "
        f"sigma {quality.sigma_mm:g} mm",
        *model_lines(arm),
        f"{_efficiency_label(arm)}: D {eff['D']:.4f}  A {eff['A']:.4f}  E {eff['E']:.4f}",
        f"observability: O1 {obs['O1']:.4f}  O2 {obs['O2']:.4f}  O3 {obs['O3']:.4f}  "
        f"O4 {obs['O4']:.4f}",
        f"paper D*: det C' {det_c}  |det S'| {float(quality.dstar.abs_det_s):.3g}",
        _table1_line(quality),
    ]
    lines += ["", f"{'parameter':<10}{'predicted std':>14}  unit"]
    for name, unit, std in zip(
        arm.param_names, arm.param_units, quality.predicted_std, strict=True
    ):
        lines.append(f"{name:<10}{_std_cell(arm, name, std, 14, 5)}  {unit}")
    pos = quality.position
    lines += [
        "",
        f"predicted position error after calibration: RMS {pos.rms_mm:.4g} mm, "
        f"max {pos.max_mm:.4g} mm over {pos.per_pose_mm.size} test poses",
    ]
    return "\n".join(lines)


def quality_to_dict(arm: PlanarArm, quality: PlanQuality) -> dict:
    """JSON document of :func:`evaluate_plan` (keys of PRODUCT.md plus details).

    Only identifiable plans have a quality (:func:`~armcal.criteria.evaluate_plan`
    raises otherwise), so every value is finite.
    """
    std = {
        name: 0.0 if name in arm.fixed else float(v)
        for name, v in zip(arm.param_names, quality.predicted_std, strict=True)
    }
    pos = quality.position
    return {
        "poses": quality.n_poses,
        "sigma_mm": quality.sigma_mm,
        "identifiable": True,  # a plan that is not has no quality: evaluate_plan raises
        "d_efficiency": quality.efficiencies["D"],
        "a_efficiency": quality.efficiencies["A"],
        "e_efficiency": quality.efficiencies["E"],
        "observability": quality.observability,
        "det_c_prime": float(quality.dstar.det_c),
        "abs_det_s_prime": float(quality.dstar.abs_det_s),
        "optimality_sums": quality.optimality_sums,
        "predicted_std": std,
        "predicted_position_rms_mm": pos.rms_mm,
        "predicted_position_max_mm": pos.max_mm,
        **model_to_dict(arm),
        "warnings": [w.to_dict() for w in quality.warnings],
    }


def _fit_line(cal: Calibration) -> str:
    """The goodness of fit in words: chi-square, dof and p-value, or why there is no test."""
    fit = cal.goodness_of_fit
    dof = cal.dof if fit is None else fit.dof
    if fit is None or fit.chi2 is None:
        return f"goodness of fit: sigma estimated from the residuals, no test ({dof} dof)"
    if fit.p_value is None:
        return f"goodness of fit: chi2 = {fit.chi2:.4g} on {dof} dof: no test without dof"
    verdict = "consistent with sigma" if fit.p_value >= 1e-3 else "INCONSISTENT with sigma"
    return (
        f"goodness of fit: chi2 = {fit.chi2:.4g} on {dof} dof "
        f"(chi2/dof {fit.chi2 / max(dof, 1):.3g}), p = {fit.p_value:.3g}: {verdict}"
    )


def _outlier_lines(cal: Calibration) -> list[str]:
    if not cal.outliers:
        return []
    lines = [
        "",
        f"outliers (studentized residual test, family-wise; {len(cal.outliers)}):",
        f"{'row':>6}  {'pose':<10}{'residual mm':>12}{'studentized':>13}  status",
    ]
    for o in cal.outliers:
        status = "removed from the fit" if o.removed else "flagged, kept in the fit"
        lines.append(
            f"{o.row:>6}  {o.pose:<10}{o.residual_mm:>12.4g}{o.studentized:>13.3g}  {status}"
        )
    return lines


def format_calibration(cal: Calibration, *, truth: np.ndarray | None = None) -> str:
    """Human-readable table of a calibration: value ± std with units, and a fit summary.

    Parameters
    ----------
    cal : Calibration
    truth : ndarray, shape (p,), optional
        Known deviations (internal units) of a virtual robot; adds columns with the
        truth and the error in standard errors.

    Returns
    -------
    str
        Lines without a trailing newline: the model (fixed parameters, a noise
        model that is not isotropic iid), the parameters (fixed ones marked
        ``fixed``), sigma and residuals, the goodness of fit, the outliers.
    """
    arm = cal.arm
    header = f"{'parameter':<10}{'value':>12}  {'± std':>10}  unit"
    if truth is not None:
        header += f"{'truth':>12}{'error/std':>11}"
    used = cal.n_used
    poses = f"{cal.n_poses} poses" + (
        f" ({cal.n_poses - used} left out of the fit)" if used < cal.n_poses else ""
    )
    lines = [
        f"calibration of {arm.name}: {poses}, {_identified(arm)}"
        + (
            ""
            if cal.nested is None
            else f" and {len(cal.nested.names)} of {cal.nested.effect.name}"
        )
        + f", method {cal.method}"
        + (", robust" if cal.robust else ""),
        *model_lines(arm, plan=False),
        "",
        header,
    ]
    truth_display = None if truth is None else np.asarray(truth) * cal.display_scale
    for i, (name, unit) in enumerate(zip(cal.names, cal.units, strict=True)):
        if name in arm.fixed:
            line = f"{name:<10}{cal.values[i]:>12.5f}  {'fixed':<10}  {unit:<4}"
        else:
            line = f"{name:<10}{cal.values[i]:>12.5f}  ± {_small(cal.std[i], 5):<8}  {unit:<4}"
        if truth_display is not None:
            line += f"{truth_display[i]:>12.5f}"
            if name not in arm.fixed and cal.std[i] > 0:
                line += f"{(cal.values[i] - truth_display[i]) / cal.std[i]:>+11.2f}"
        lines.append(line.rstrip())
    kept = cal.pose_residuals if cal.used is None else np.where(cal.used, cal.pose_residuals, -1)
    worst = int(np.argmax(kept))
    lines += [
        "",
        f"sigma {cal.sigma_mm:.4g} mm ({cal.sigma_source}); "
        f"residual RMS {cal.residual_rms:.4g} mm per coordinate, "
        f"max {cal.residual_max:.4g} mm at pose {cal.pose_labels[worst]}; "
        f"{cal.dof} degrees of freedom",
        _fit_line(cal),
        f"{cal.method}: {cal.iterations} iteration(s), "
        + ("converged" if cal.converged else "NOT converged: the estimate may be off"),
    ]
    corr = np.abs(cal.correlation - np.eye(len(cal.names)))
    strong = [
        f"{cal.names[i]}/{cal.names[j]} {cal.correlation[i, j]:+.2f}"
        for i, j in zip(*np.nonzero(np.triu(corr > 0.9)), strict=True)
    ]
    if strong:
        lines.append("strongly correlated (|r| > 0.9): " + ", ".join(strong))
    lines += _outlier_lines(cal)
    if cal.plane is not None:
        plane = cal.plane
        offsets = ", ".join(
            f"{label or 'all'} {d:+.4g}"
            for label, d in zip(plane.labels or ("",), plane.offsets, strict=True)
        )
        normal = ", ".join(f"{v:.4f}" for v in plane.normal)
        lines += [
            "",
            f"3-D data: plane of motion fitted with normal ({normal}) in the instrument frame; "
            f"out of plane RMS {plane.rms_mm:.4g} mm, max {plane.max_mm:.4g} mm; target "
            f"planes at {offsets} mm; x0, y0, phi0 are the base pose in the plane's axes",
        ]
    lines += compliance_lines(cal)
    return "\n".join(lines)


def compliance_lines(cal: Calibration) -> list[str]:
    """What the model's effect explains: residuals without it and the deflections fitted."""
    nested = cal.nested
    if nested is None:
        return []
    effect = nested.effect
    out = [
        "",
        f"{effect.name}, {effect.description}; {effect.nested} alone leaves "
        f"{nested.rms_per_coordinate_mm:.4g} mm residual RMS, with {effect.short} "
        f"{cal.residual_rms:.4g} mm",
    ]
    deflection = cal.details.get("max_deflection_rad")
    if deflection is not None:
        worst = np.degrees(deflection) * 1e3
        out.append(
            "largest fitted deflection per joint: "
            + ", ".join(f"joint {j + 1} {v:.4g} mdeg" for j, v in enumerate(worst))
        )
    return out


def _finite_or_none(value: float | None) -> float | None:
    """A float for JSON: None for a missing or non-finite value (never NaN)."""
    if value is None or not math.isfinite(value):
        return None
    return float(value)


def _elastostatic_dict(cal: Calibration) -> dict | None:
    """The loads model of a fit with compliance, enough to rebuild it (gravity in m/s^2)."""
    model, nested = cal.model, cal.nested
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
        "geometry_only_rms_mm": nested.rms_per_coordinate_mm,
    }


def calibration_to_dict(
    cal: Calibration, *, warnings: Sequence[ArmcalWarning] | None = None
) -> dict:
    """The ``armcal-calibration/1`` document of a calibration (see PRODUCT.md).

    Parameters
    ----------
    cal : Calibration
    warnings : sequence of ArmcalWarning, optional
        Every warning of the run (the robot file's, the measurement file's, the
        plausibility checks', the calibration's); default ``cal.warnings``.

    Returns
    -------
    dict
        The contract keys, plus ``goodness_of_fit`` ``{chi2, dof, p_value}``
        (null chi2 and p-value when sigma was estimated), ``standardized_residuals``
        per pose, ``outliers`` (``{row, pose, target, residual_mm, studentized,
        removed}``), ``noise`` (the noise model or null), ``fixed`` (names; their
        parameters carry ``"fixed": true`` and std 0).  No NaN anywhere.
    """
    arm = cal.arm
    corr = cal.correlation
    fit = cal.goodness_of_fit
    rows = cal.rows or tuple(range(1, cal.n_poses + 1))
    used = np.ones(cal.n_poses, dtype=bool) if cal.used is None else cal.used
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
        "fixed": list(arm.fixed),
        "parameters": [
            {
                "name": name,
                "unit": unit,
                "value": float(v),
                "std": 0.0 if name in arm.fixed else float(s),
                "fixed": name in arm.fixed,
            }
            for name, unit, v, s in zip(cal.names, cal.units, cal.values, cal.std, strict=True)
        ],
        "covariance": {"names": list(cal.names), "matrix": cal.covariance_display.tolist()},
        "correlation": {"names": list(cal.names), "matrix": corr.tolist()},
        "residual_rms_mm": cal.residual_rms,
        "residual_max_mm": cal.residual_max,
        "degrees_of_freedom": cal.dof,
        "goodness_of_fit": {
            "chi2": None if fit is None else _finite_or_none(fit.chi2),
            "dof": cal.dof if fit is None else int(fit.dof),
            "p_value": None if fit is None else _finite_or_none(fit.p_value),
        },
        "residuals": [
            {
                "row": int(row),
                "pose": label,
                "target": None if cal.target is None else arm.targets[cal.target[i]].label,
                "dx_mm": float(r[0]),
                "dy_mm": float(r[1]),
                "used": bool(u),
            }
            for i, (row, label, r, u) in enumerate(
                zip(rows, cal.pose_labels, cal.residuals, used, strict=True)
            )
        ],
        "standardized_residuals": []
        if standardized is None
        else [
            {"row": int(row), "pose": label, "x": float(z[0]), "y": float(z[1])}
            for row, label, z in zip(rows, cal.pose_labels, standardized, strict=True)
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
        "warnings": [w.to_dict() for w in (cal.warnings if warnings is None else warnings)],
    }


def to_json(document: dict) -> str:
    """Serialize a result document; refuses NaN and infinity rather than writing them."""
    return json.dumps(document, indent=2, allow_nan=False) + "\n"


def format_monte_carlo(result: MonteCarlo) -> str:
    """Human-readable table of :func:`monte_carlo`: empirical vs predicted std and bias."""
    arm = result.arm
    lines = [
        f"Monte Carlo: {result.trials} trials of {result.q.shape[0]} poses of {arm.name}, "
        f"sigma {result.sigma_mm:g} mm, {result.method} ({result.seconds:.2f} s)",
        *model_lines(arm),
        "",
        f"{'parameter':<10}{'truth':>10}{'bias':>11}{'empirical std':>15}{'predicted std':>15}"
        f"{'ratio':>8}  unit",
    ]
    truth = result.truth * result.display_scale
    for name, unit, t, b, s, ps in zip(
        result.names,
        result.units,
        truth,
        result.bias,
        result.std,
        result.predicted_std,
        strict=True,
    ):
        if name in arm.fixed:  # held at nominal: no spread to compare
            lines.append(
                f"{name:<10}{t:>10.4f}{b:>11.2e}{'fixed':>15}{'fixed':>15}{'':>8}  {unit}"
            )
            continue
        lines.append(
            f"{name:<10}{t:>10.4f}{b:>11.2e}{_small(s, 5):>15}{_small(ps, 5):>15}"
            f"{s / ps:>8.3f}  {unit}"
        )
    flagged = [
        name
        for name, b, limit in zip(result.names, result.bias, result.bias_limit, strict=True)
        if abs(b) > limit
    ]
    lines += [
        "",
        "bias within 4 std/sqrt(N) for every parameter"
        if not flagged
        else f"bias beyond 4 std/sqrt(N): {', '.join(flagged)}",
    ]
    if result.position is not None:
        pos = result.position
        if pos.exact_quantiles:
            quantiles = ", ".join(
                f"{key} % {value:.4g}" for key, value in pos.quantiles_mm.items()
            )
            source = f"all {pos.pairs} (trial, test pose) pairs"
        else:
            quantiles = ", ".join(
                f"{key} % {value:.4g} [{low:.4g}, {high:.4g}]"
                for (key, value), (low, high) in zip(
                    pos.quantiles_mm.items(), pos.quantile_intervals_mm.values(), strict=True
                )
            )
            source = (
                f"a random subsample of {pos.subsample} of the {pos.pairs} (trial, test pose) "
                "pairs, with 95 % intervals"
            )
        lines += [
            f"tip error of the calibrated model at test poses: RMS {pos.rms_mm:.4g} mm over all "
            f"{pos.pairs} (trial, test pose) pairs (predicted {pos.predicted_rms_mm:.4g} mm)",
            f"quantiles (mm) from {source}: {quantiles}",
        ]
    if result.not_converged:
        lines.append(f"warning: Gauss-Newton did not converge in {result.not_converged} trials")
    return "\n".join(lines)


def monte_carlo_to_dict(result: MonteCarlo) -> dict:
    """JSON document of :func:`monte_carlo` (the keys of PRODUCT.md plus details)."""
    names = result.names

    def by_name(values: np.ndarray) -> dict[str, float]:
        return {name: float(v) for name, v in zip(names, values, strict=True)}

    document: dict = {
        "trials": result.trials,
        "poses": int(result.q.shape[0]),
        "sigma_mm": result.sigma_mm,
        "method": result.method,
        "units": dict(zip(names, result.units, strict=True)),
        "truth": by_name(result.truth * result.display_scale),
        "empirical_mean": by_name(result.mean * result.display_scale),
        "empirical_std": by_name(result.std),
        "predicted_std": by_name(result.predicted_std),
        "bias": by_name(result.bias),
        "bias_limit": by_name(result.bias_limit),
        "not_converged": result.not_converged,
        "seconds": result.seconds,
        **model_to_dict(result.arm),
    }
    if result.position is not None:
        pos = result.position
        document["position_error_mm"] = {
            "rms": pos.rms_mm,
            "predicted_rms": pos.predicted_rms_mm,
            "quantiles": pos.quantiles_mm,
            "quantile_intervals_95": {
                key: list(bounds) for key, bounds in pos.quantile_intervals_mm.items()
            },
            "pairs": pos.pairs,
            "quantile_subsample": pos.subsample,
        }
    return document


def design_summary(result: Design, seconds: float) -> tuple[dict, list[str]]:
    """JSON keys and header lines of ``armcal design`` (before the plan's quality report).

    Parameters
    ----------
    result : Design
    seconds : float
        Wall time of the design.

    Returns
    -------
    document : dict
        ``criterion``, ``method``, the certificate's bounds (None without one),
        ``notes``, ``seconds``, ``order``, ``distinct`` and the joint travel in
        the plan's order and in the order the method found
        (``joint_travel_deg``, ``joint_travel_unordered_deg``).
    lines : list of str
        The method, the notes (why the closed-form plans were not used), the
        D-efficiency against the unconstrained optimum and the certificate, the
        joint travel, and an empty line.
    """
    cert = result.certificate
    document = {
        "criterion": result.criterion,
        "method": result.method,
        "certified_d_efficiency": None if cert is None else cert.certified_d_efficiency,
        "plan_only_bound": None if cert is None else cert.plan_only_bound,
        "best_weighted_design_d_efficiency": None if cert is None else cert.reference_d_efficiency,
        "notes": list(result.notes),
        "seconds": seconds,
        "order": result.order,
        "distinct": result.distinct,
        "joint_travel_deg": math.degrees(result.joint_travel),
        "joint_travel_unordered_deg": math.degrees(result.joint_travel_unordered),
    }
    if unit_trace(result.arm):
        efficiency = f"D-efficiency {result.d_efficiency:.4f} of the unconstrained optimum"
    else:  # no closed-form optimum: only the certificate compares with the best plan
        efficiency = f"D-criterion {result.d_efficiency:.4f} on this model"
    if unit_trace(result.arm) and result.method != "analytic" and result.d_efficiency >= 1 - 1e-9:
        # The note ruled out only the closed-form family: say that the search met the optimum.
        efficiency += " (an orthogonal plan, found by search)"
    if cert is not None:
        efficiency += (
            f"; certified >= {cert.certified_d_efficiency:.4f} of the best plan within the "
            f"constraints (plan-only bound {cert.plan_only_bound:.4f})"
        )
    lines = [
        f"design: {result.q.shape[0]} poses, criterion {result.criterion}, method {result.method} "
        f"({seconds:.2f} s)",
        *(f"note: {note}" for note in result.notes),
        efficiency,
        _travel_line(result),
        "",
    ]
    return document, lines


def _travel_line(result: Design) -> str:
    """``order: joint travel 1234 deg after ordering (5678 deg in the order found, 22 %)``."""
    after = math.degrees(result.joint_travel)
    found = math.degrees(result.joint_travel_unordered)
    if result.order == "none":
        return f"order: joint travel {after:.0f} deg in the order found (not reordered)"
    share = f", {100 * after / found:.0f} %" if found > 0 else ""
    return (
        f"order: joint travel {after:.0f} deg after ordering "
        f"({found:.0f} deg in the order found{share})"
    )


def _cell(value) -> str:
    if value is None:
        return ""
    if isinstance(value, float):
        return f"{value:.6g}"
    text = str(value)
    return f'"{text}"' if any(c in text for c in ',"\n') else text


def table_csv(rows: list[dict], columns: tuple[str, ...]) -> str:
    """CSV text of ``rows`` (header ``columns``; empty cell for None, 6 significant digits)."""
    lines = [",".join(columns)]
    lines += [",".join(_cell(row[c]) for c in columns) for row in rows]
    return "\n".join(lines) + "\n"


def _markdown(rows: list[dict], columns: tuple[str, ...]) -> list[str]:
    out = ["| " + " | ".join(columns) + " |", "|" + "---|" * len(columns)]
    for row in rows:
        out.append("| " + " | ".join(_cell(row[c]).strip('"') for c in columns) + " |")
    return out


def _not_computable(result: Reproduction) -> str:
    """``"4 links with 3 poses"``: the Table III configurations no plan can calibrate."""
    configurations = sorted(
        {(r["links"], r["poses"]) for r in result.tables["table3"] if r["computable"] == "no"}
    )
    return ", ".join(f"{n} links with {m} poses" for n, m in configurations) or "none"


def _counts_line(result: Reproduction) -> str:
    counts = result.printed_values()
    return (
        f"{counts['agree']} of the paper's {counts['printed']} printed values agree, "
        f"{counts['differ']} differ, {counts['not_computable']} cannot be computed "
        f"({_not_computable(result)}: no plan identifies the parameters)"
    )


def _equations_line(result: Reproduction) -> str:
    differing = [c for c in result.equations if not c.agrees]
    return (
        f"{len(result.equations)} printed equations checked by computing them: "
        f"{len(result.equations) - len(differing)} agree, {len(differing)} differ"
    )


def format_reproduction(result: Reproduction) -> str:
    """``report.md``: set-up, Tables I-III, Figures 1-2, equations checked, disagreements."""
    t3 = result.tables["table3"]
    judged = [r for r in t3 if r["analytic_std"] is not None and r["simulated_std"] is not None]
    worst = max(abs(r["simulated_std"] / r["analytic_std"] - 1) for r in judged)
    lines = [
        "# The paper's Sections II-VI, recomputed by armcal",
        "",
        "Klimchik et al., *Design of Experiments for Calibration of Planar Anthropomorphic "
        "Manipulators*. Every number below is computed; the paper's values appear only "
        "in the `paper_value` column and in the comparison.",
        "",
        "## Set-up",
        "",
        "- Arms: the paper's 2-, 3- and 4-link arms, l = 260, 180, 120, 100 mm, true "
        "deviations dl = 1.5, -0.6, -0.4, 0.7 mm and dq = 0.5, -0.5, 0.7, -0.3 deg "
        "(built-in robots `paper-2link`, `paper-3link`, `paper-4link`), no joint limits.",
        f"- Noise: sigma = {result.sigma_mm:g} mm per coordinate, iid normal.",
        f"- Plans: orthogonal plans meeting Table I exactly (`armcal.doe.orthogonal_plan`: "
        f"q1 = 0, q2 = ... = qn = 360 k / m deg); Monte Carlo with {result.trials} trials per "
        f"configuration (closed-form solver); {result.random_plans} random plans (uniform "
        "joint angles) per random study.",
        f"- Seed {result.seed}; the whole reproduction took {result.seconds:.1f} s.",
        "- Table III has one row per printed value, each compared once: a printed dL_k with "
        "the std of dl_k, a printed 'dq_k' with the std of the cumulative link angle "
        "dtheta_k = dq_1 + ... + dq_k, the paper's parameter (the std of the joint offset "
        "dq_k is shown beside it, `joint_offset_std`). `analytic_std`: "
        "sqrt(diag(sigma^2 (J^T J)^-1)) at the nominal geometry; `simulated_std`: the std "
        "over the trials. `agrees` is yes when the printed value is within "
        f"{PAPER_DIGIT} (one unit of its last digit) of `analytic_std`; `computable` is no "
        "when no plan of that many poses identifies the parameters.",
        f"- Table III: {_counts_line(result)}.",
        f"- Simulated and analytic std agree to within {100 * worst:.1f} % in every "
        f"identifiable configuration (sampling error of a std from {result.trials} trials: "
        f"{100 / math.sqrt(2 * result.trials):.1f} %).",
        f"- Equations: {_equations_line(result)} (section 'Equations checked').",
        "",
        "## Table I: optimality conditions on the generated plans (`table1.csv`)",
        "",
        *_markdown(result.tables["table1"], TABLE_COLUMNS["table1"]),
        "",
        "## Table II: information matrix and analytic accuracy (`table2.csv`)",
        "",
        *_markdown(result.tables["table2"], TABLE_COLUMNS["table2"]),
        "",
        "## Table III: identification accuracy, analytic and simulated (`table3.csv`)",
        "",
        *_markdown(t3, TABLE_COLUMNS["table3"]),
        "",
        "## Figure 1: random 10-pose plans of the 4-link arm (`figure1.png`)",
        "",
        "![Figure 1](figure1.png)",
        "",
        f"det(D') = D-efficiency^p over {result.random_plans} random plans: median "
        f"{np.median(result.figure1.det_d):.3g}, max {result.figure1.det_d.max():.3g} "
        f"(orthogonal plan: 1); {100 * np.mean(result.figure1.det_d < 0.5):.1f} % of the "
        "plans are below 0.5. det(C') median "
        f"{np.median(result.figure1.det_c):.3g} (optimum 1), |det(S')| median "
        f"{np.median(result.figure1.abs_det_s):.3g} (optimum 0). This confirms the paper's "
        "qualitative claim that random plans are poor.",
        "",
        "## Figure 2: accuracy against the number of poses, 4-link arm (`figure2.png`)",
        "",
        "![Figure 2](figure2.png)",
        "",
        "Curve 1: analytic, orthogonal plans; x: simulated orthogonal plans; curve 2: "
        f"random plans, mean and median over {result.random_plans} plans of the predicted "
        "accuracy (the mean is dominated by nearly singular plans at small m).",
        "",
        "## Equations checked",
        "",
        "Each printed equation of Sections II-V, computed: model (1) from its printed double "
        "sum, Jacobians and gradients by central differences of it, information matrices "
        "from those Jacobians, the algorithm with "
        "`armcal.reproduction.algorithm.solve_gauss_newton`.",
        "",
    ]
    for i, check in enumerate(result.equations, start=1):
        lines += [
            f"{i}. **{check.where}: {check.verdict}.** Paper: {check.paper}. "
            f"Computed: {check.evidence}.",
            "",
        ]
    lines += ["## Where this differs from the paper", ""]
    for i, d in enumerate(result.disagreements, start=1):
        lines += [
            f"{i}. **{d.where}.** Paper: {d.paper}. Computed: {d.computed}. Cause: {d.cause}.",
            "",
        ]
    return "\n".join(lines)


def reproduction_summary(result: Reproduction) -> tuple[dict, list[str]]:
    """The JSON document and the text lines of ``armcal reproduce``.

    Parameters
    ----------
    result : Reproduction

    Returns
    -------
    document : dict
        ``trials``, ``random_plans``, ``seed``, ``seconds``; Table III's printed
        values counted once each: ``printed_values``, ``printed_values_agreeing``,
        ``printed_values_differing``, ``printed_values_not_computable`` (and
        ``table3_rows``, one per printed value); ``equations`` (each printed
        equation with its verdict), ``equations_differing``; ``disagreements``
        (where the paper differs).  The caller adds ``files``.
    lines : list of str
        What was reproduced, the counts, and every disagreement; the caller
        adds the line naming the files written.
    """
    counts = result.printed_values()
    document = {
        "trials": result.trials,
        "random_plans": result.random_plans,
        "seed": result.seed,
        "seconds": result.seconds,
        "table3_rows": len(result.tables["table3"]),
        "printed_values": counts["printed"],
        "printed_values_agreeing": counts["agree"],
        "printed_values_differing": counts["differ"],
        "printed_values_not_computable": counts["not_computable"],
        "equations": [{"equation": c.where, "verdict": c.verdict} for c in result.equations],
        "equations_differing": sum(not c.agrees for c in result.equations),
        "disagreements": [d.where for d in result.disagreements],
    }
    lines = [
        f"reproduced the paper's Tables I-III and Figures 1-2 with {result.trials} trials "
        f"per configuration (seed {result.seed}) in {result.seconds:.1f} s",
        f"Table III: {_counts_line(result)}",
        _equations_line(result),
        f"{len(result.disagreements)} places where the paper differs (causes in report.md):",
        *(f"  - {d.where}" for d in result.disagreements),
    ]
    return document, lines


def poses_needed_summary(
    found: PosesNeeded, arm: PlanarArm, seconds: float
) -> tuple[dict, list[str]]:
    """The JSON document and the text lines of ``armcal poses-needed``.

    Parameters
    ----------
    found : PosesNeeded
    arm : PlanarArm
        The arm the plans were designed for (its name is printed).
    seconds : float
        Wall time of the search.

    Returns
    -------
    document : dict
        ``poses`` (PRODUCT.md), ``target``, ``goal``, ``achieved``,
        ``with_one_pose_less`` (null when fewer poses cannot identify every
        parameter), ``sigma_mm``, ``method``, ``evaluated`` (m -> accuracy of the
        best m-pose plan, identifiable ones only) and ``seconds``.
    lines : list of str
        The answer and how it was found; the caller adds the file it wrote.
    """
    unit = "deg" if found.target == "angle_std_deg" else "mm"
    finite_previous = math.isfinite(found.previous)
    document = {
        "poses": found.poses,
        "target": found.target,
        "goal": found.goal,
        "achieved": found.achieved,
        "with_one_pose_less": found.previous if finite_previous else None,
        "sigma_mm": found.sigma_mm,
        "method": found.method,
        "evaluated": {str(m): v for m, v in found.evaluated.items() if math.isfinite(v)},
        "seconds": seconds,
        **model_to_dict(arm),
    }
    less = (
        f"{found.poses - 1} poses give {found.previous:.6g} {unit}"
        if finite_previous
        else f"{found.poses - 1} poses cannot identify every parameter"
    )
    lines = [
        f"{found.poses} poses: the best {found.poses}-pose plan of {arm.name} "
        f"({found.method}) reaches {found.achieved:.6g} {unit} against a target of "
        f"{found.goal:g} {unit}; {less}",
        f"({TARGETS[found.target]}; sigma {found.sigma_mm:g} mm; {len(found.evaluated)} plan "
        f"sizes tried in {seconds:.2f} s)",
        *model_lines(arm),
    ]
    return document, lines


# --------------------------------------------------------------------------- validation


def format_cross_validation(summary: dict) -> str:
    """One line: the K-fold prediction error against what the calibrations predict."""
    return (
        f"cross-validation ({summary['folds']} folds): prediction error RMS "
        f"{summary['rms_mm']:.4g} mm (max {summary['max_mm']:.4g} mm); predicted "
        f"{summary['predicted_rms_mm']:.4g} mm"
    )


def _too_large(measured: float, predicted: float, count: int) -> bool:
    """Whether an RMS over ``count`` points is above its prediction beyond chance.

    The mean square of ``2 count`` coordinates has relative std ``1/sqrt(count)``
    (chi-square), so the RMS about ``1/(2 sqrt(count))``: 6 of them, and at least 20 %.
    """
    return measured > predicted * (1.0 + max(0.2, 3.0 / np.sqrt(max(count, 1))))


def cross_validation_warning(summary: dict, count: int) -> ArmcalWarning | None:
    """``cross-validation`` when poses are predicted worse than the calibration says."""
    if not _too_large(summary["rms_mm"], summary["predicted_rms_mm"], count):
        return None
    return ArmcalWarning(
        "cross-validation",
        f"held-out poses are predicted with RMS {summary['rms_mm']:.3g} mm, more than the "
        f"{summary['predicted_rms_mm']:.3g} mm the calibrations predict: the model misses an "
        "effect (compliance, a wrong joint map) or some poses are outliers (try --robust)",
    )


def validation_warnings(result: Validation) -> list[ArmcalWarning]:
    """``validation-error`` when the calibrated error exceeds its prediction beyond chance."""
    s = result.summary()
    warnings = []
    count = result.after.shape[0]
    if _too_large(s["rms_after_mm"], s["predicted_rms_after_mm"], count):
        warnings.append(
            ArmcalWarning(
                "validation-error",
                f"the calibrated model misses the held-out poses by RMS {s['rms_after_mm']:.3g} "
                f"mm, more than the {s['predicted_rms_after_mm']:.3g} mm it predicts (noise and "
                "its uncertainty): the model misses an effect, the poses lie outside the "
                "calibrated range, the arm changed, or the measurements belong to another setup",
            )
        )
    if s["rms_after_mm"] > s["rms_before_mm"]:
        warnings.append(
            ArmcalWarning(
                "calibration-worse",
                f"the calibrated model is worse than the nominal one on these poses "
                f"({s['rms_after_mm']:.3g} against {s['rms_before_mm']:.3g} mm RMS): check that "
                "the calibration and the measurements are of the same robot and instrument setup",
            )
        )
    return warnings


def validation_report(
    cal: CalibratedArm, result: Validation, meas: Measurements, *, per_pose: bool = False
) -> tuple[dict, str]:
    """The ``validate`` document and text: errors before and after, predicted, per pose."""
    s = result.summary()
    m = result.after.shape[0]
    lines = [
        f"validation of {cal.arm.name} on {m} held-out poses"
        + (" (3-D, projected into the calibration's plane)" if cal.plane is not None else ""),
        "",
        f"{'position error (mm)':<24}{'RMS':>10}{'95 %':>10}{'max':>10}",
        f"{'nominal model':<24}{s['rms_before_mm']:>10.4g}{s['p95_before_mm']:>10.4g}"
        f"{s['max_before_mm']:>10.4g}",
        f"{'calibrated model':<24}{s['rms_after_mm']:>10.4g}{s['p95_after_mm']:>10.4g}"
        f"{s['max_after_mm']:>10.4g}",
        f"{'predicted (calibrated)':<24}{s['predicted_rms_after_mm']:>10.4g}",
        "",
        f"predicted = the noise of a measurement and the calibration's own uncertainty "
        f"({s['model_rms_mm']:.3g} mm RMS at these poses)",
    ]
    document: dict = {"poses": m, **s}
    if result.out_of_plane_mm is not None:
        oop = result.out_of_plane_mm
        document["out_of_plane_rms_mm"] = float(np.sqrt(np.mean(oop**2)))
        document["out_of_plane_max_mm"] = float(np.max(np.abs(oop)))
        lines.append(
            f"out of the calibration's plane: RMS {document['out_of_plane_rms_mm']:.3g} mm, "
            f"max {document['out_of_plane_max_mm']:.3g} mm"
        )
    if per_pose:
        targets = meas.targets
        lines += [
            "",
            f"{'row':>5}  {'pose':<8}{'target':<8}{'before mm':>11}{'after mm':>10}"
            f"{'predicted':>11}",
        ]
        rows = []
        for i in range(m):
            target = "" if targets is None else targets[i]
            rows.append(
                {
                    "row": int(meas.rows[i]),
                    "pose": meas.labels[i],
                    "target": None if targets is None else target,
                    "before_mm": float(result.before_mm[i]),
                    "after_mm": float(result.after_mm[i]),
                    "predicted_mm": float(result.predicted_mm[i]),
                }
            )
            lines.append(
                f"{meas.rows[i]:>5}  {meas.labels[i]:<8}{target:<8}"
                f"{result.before_mm[i]:>11.4g}{result.after_mm[i]:>10.4g}"
                f"{result.predicted_mm[i]:>11.4g}"
            )
        document["per_pose"] = rows
    return document, "\n".join(lines)


def compensation_report(
    cal: CalibratedArm, result: Compensation, program: Program
) -> tuple[dict, str, list[ArmcalWarning]]:
    """The ``compensate`` document, text and warnings (one for the uncorrectable poses)."""
    s = result.summary()
    m = result.q.shape[0]
    bad = result.uncorrectable
    lines = [
        f"compensated {m - bad.size} of {m} poses for {cal.arm.name} (robot frame; the "
        "instrument's pose is not corrected)",
        f"predicted position error: RMS {s['rms_before_mm']:.4g} mm before, "
        f"{s['rms_after_mm']:.4g} mm after (the calibration's uncertainty)",
    ]
    if s["orientation_rms_before_deg"] is not None:
        lines.append(
            f"predicted tool orientation error: RMS {s['orientation_rms_before_deg']:.4g} deg "
            f"before, {s['orientation_rms_after_deg']:.4g} deg after"
        )
    change = np.degrees(np.abs(result.q - program.q))
    lines.append(f"largest joint change: {float(np.max(change, initial=0.0)):.4g} deg")
    labels = program.labels or tuple(str(i + 1) for i in range(m))
    uncorrectable = [
        {"row": int(i) + 1, "pose": labels[i], "reason": result.reasons[i]} for i in bad
    ]
    warnings = []
    if bad.size:
        shown = "; ".join(f"row {u['row']}: {u['reason']}" for u in uncorrectable[:5])
        more = f" and {bad.size - 5} more" if bad.size > 5 else ""
        warnings.append(
            ArmcalWarning(
                "uncorrectable",
                f"{bad.size} of {m} poses cannot be corrected and keep their commands "
                f"(corrected = 0 in the output): {shown}{more}",
            )
        )
    document = {
        "poses": m,
        **s,
        "corrected": int(m - bad.size),
        "uncorrectable": uncorrectable,
        "largest_joint_change_deg": float(np.max(change, initial=0.0)),
    }
    return document, "\n".join(lines), warnings


def compliant_quality(
    model: CompliantArm, q: np.ndarray, loads: Loads, sigma: float
) -> tuple[dict, str]:
    """JSON keys and text of a plan's quality for geometry plus joint compliance.

    The predicted std of every parameter (display units) at ``sigma``, the
    D-efficiency of the normalized information on unit-norm columns
    (:func:`armcal.doe.compliance.d_efficiency_compliant`; compares plans of
    this model) and how many poses carry each payload.
    """
    covariance, _ = predicted_covariance(model, model.conditions(q, loads=loads), sigma)
    std = display_std(model, covariance)
    d_eff = d_efficiency_compliant(model, q, loads)
    values, counts = np.unique(loads.payload_kg, return_counts=True)
    payloads = {f"{v:g}": int(c) for v, c in zip(values, counts, strict=True)}
    free = dict(zip(model.param_names, model.free, strict=True))
    document = {
        "poses": int(q.shape[0]),
        "sigma_mm": sigma,
        "identifiable": True,
        "d_efficiency": d_eff,
        "predicted_std": {
            name: float(v) if free[name] else 0.0
            for name, v in zip(model.param_names, std, strict=True)
        },
        "units": dict(zip(model.param_names, model.param_units, strict=True)),
        "payload_counts": payloads,
        "compliance": list(model.compliance_names),
    }
    lines = [
        f"{q.shape[0]} poses of {model.arm.name} with joint compliance "
        f"({', '.join(model.compliance_names)}), sigma {sigma:g} mm",
        "payloads: " + ", ".join(f"{c} poses at {v} kg" for v, c in payloads.items()),
        f"D-efficiency (unit-norm columns, compares plans of this model): {d_eff:.4f}",
        "",
        f"{'parameter':<10}{'predicted std':>14}  unit",
    ]
    for name, unit, value in zip(model.param_names, model.param_units, std, strict=True):
        cell = f"{'fixed':>14}" if not free[name] else f"{value:>14.5g}"
        lines.append(f"{name:<10}{cell}  {unit}")
    return document, "\n".join(lines)


def compliant_design_summary(result: CompliantDesign, seconds: float) -> tuple[dict, list[str]]:
    """JSON keys and header lines of ``armcal design`` for a model with joint compliance."""
    document = {
        "criterion": "D",
        "method": "exchange+polish",
        "certified_d_efficiency": result.certified_d_efficiency,
        "plan_only_bound": result.plan_only_bound,
        "max_variance": result.max_variance,
        "payloads_allowed": list(result.payloads),
        "seconds": seconds,
        "order": result.order,
        "joint_travel_deg": float(np.degrees(result.joint_travel)),
    }
    lines = [
        f"design: D-optimal for geometry and joint compliance, poses and payloads "
        f"(from {', '.join(f'{v:g}' for v in result.payloads)} kg) chosen together "
        f"({seconds:.1f} s)",
        f"certified D-efficiency >= {result.certified_d_efficiency:.4f} of the best plan "
        f"within the limits and region (max d = {result.max_variance:.3f} for "
        f"p = {result.model.n_free})",
        "",
    ]
    return document, lines
