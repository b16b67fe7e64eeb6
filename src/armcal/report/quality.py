"""A plan's quality as text and JSON: criteria, predicted std, predicted accuracy."""

from __future__ import annotations

from ..criteria import PlanQuality
from ..doe.compliance import CompliantQuality
from ..models import PlanarArm
from .common import identified, model_lines, model_to_dict, std_cell

__all__ = [
    "compliant_quality",
    "format_quality",
    "quality_to_dict",
]


def _efficiency_label(quality: PlanQuality) -> str:
    """What the criteria are relative to: 1 at the optimum only where ``det M <= 1`` holds."""
    if quality.normalized:
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
        f"{quality.n_poses} poses of {arm.name}, {identified(arm)}, sigma {quality.sigma_mm:g} mm",
        *model_lines(arm),
        f"{_efficiency_label(quality)}: D {eff['D']:.4f}  A {eff['A']:.4f}  E {eff['E']:.4f}",
        f"observability: O1 {obs['O1']:.4f}  O2 {obs['O2']:.4f}  O3 {obs['O3']:.4f}  "
        f"O4 {obs['O4']:.4f}",
        f"paper D*: det C' {det_c}  |det S'| {float(quality.dstar.abs_det_s):.3g}",
        _table1_line(quality),
    ]
    lines += ["", f"{'parameter':<10}{'predicted std':>14}  unit"]
    for name, unit, std in zip(
        arm.param_names, arm.param_units, quality.predicted_std, strict=True
    ):
        lines.append(f"{name:<10}{std_cell(arm, name, std, 14, 5)}  {unit}")
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


def compliant_quality(quality: CompliantQuality) -> tuple[dict, str]:
    """JSON keys and text of a plan's quality for geometry plus joint compliance.

    The predicted std of every parameter (display units), the D-efficiency of
    the normalized information on unit-norm columns
    (:func:`armcal.doe.compliance.d_efficiency_compliant`; compares plans of
    this model) and how many poses carry each payload.
    """
    model = quality.model
    payloads = {f"{v:g}": c for v, c in quality.payload_counts.items()}
    free = dict(zip(model.param_names, model.free, strict=True))
    std = quality.predicted_std
    document = {
        "poses": quality.n_poses,
        "sigma_mm": quality.sigma_mm,
        "identifiable": True,
        "d_efficiency": quality.d_efficiency,
        "predicted_std": {
            name: float(v) if free[name] else 0.0
            for name, v in zip(model.param_names, std, strict=True)
        },
        "units": dict(zip(model.param_names, model.param_units, strict=True)),
        "payload_counts": payloads,
        "compliance": list(model.compliance_names),
    }
    lines = [
        f"{quality.n_poses} poses of {model.arm.name} with joint compliance "
        f"({', '.join(model.compliance_names)}), sigma {quality.sigma_mm:g} mm",
        "payloads: " + ", ".join(f"{c} poses at {v} kg" for v, c in payloads.items()),
        f"D-efficiency (unit-norm columns, compares plans of this model): "
        f"{quality.d_efficiency:.4f}",
        "",
        f"{'parameter':<10}{'predicted std':>14}  unit",
    ]
    for name, unit, value in zip(model.param_names, model.param_units, std, strict=True):
        cell = f"{'fixed':>14}" if not free[name] else f"{value:>14.5g}"
        lines.append(f"{name:<10}{cell}  {unit}")
    return document, "\n".join(lines)
