"""A plan's quality as text and JSON: criteria, predicted std, predicted accuracy."""

from __future__ import annotations

from collections.abc import Mapping

from ..criteria import PlanQuality
from ..errors import ACTIONS
from .common import identified, model_lines, model_to_dict, std_cell

__all__ = [
    "format_quality",
    "quality_report",
    "quality_to_dict",
]


def _efficiency_label(quality: PlanQuality) -> str:
    """What the criteria are relative to: 1 at the optimum only where ``det M <= 1`` holds."""
    if quality.normalized:
        return "efficiency (1 = orthogonal optimum)"
    return "criteria of the weighted information (not 1 at this model's optimum; see design)"


def _table1_line(quality: PlanQuality) -> str:
    """The largest of the paper's Table I sums, or that a one-link arm has none."""
    assert quality.paper is not None
    sums = [abs(v) for v in quality.paper.optimality_sums.values()]
    if not sums:
        return "Table I sums: none (one link, no base offset: no optimality condition)"
    return (
        f"largest Table I sum: {max(sums):.3g}"
        f" (0 for an optimal plan; {quality.n_poses} is the worst possible)"
    )


def quality_report(
    quality: PlanQuality, *, words: Mapping[str, str] = ACTIONS
) -> tuple[dict, str]:
    """The JSON document and the text of :func:`~armcal.criteria.evaluate_plan` (``words``
    say the advice, :func:`armcal.errors.render`)."""
    if quality.payload_counts is not None:
        return _loaded_quality(quality)
    return _document(quality), _text(quality, words)


def format_quality(quality: PlanQuality) -> str:
    """Human-readable report of :func:`evaluate_plan`: criteria, std table, accuracy."""
    return quality_report(quality)[1]


def quality_to_dict(quality: PlanQuality) -> dict:
    """JSON document of :func:`evaluate_plan` (keys of PRODUCT.md plus details)."""
    return quality_report(quality)[0]


def _text(quality: PlanQuality, words: Mapping[str, str]) -> str:
    arm = quality.model.arm  # the geometric model, described in words
    eff = quality.efficiencies
    obs = quality.observability
    lines = [
        f"{quality.n_poses} poses of {arm.name}, {identified(arm)}, sigma {quality.sigma_mm:g} "
        f"{arm.reading_unit}",
        *model_lines(arm, words=words),
        f"{_efficiency_label(quality)}: D {eff['D']:.4f}  A {eff['A']:.4f}  E {eff['E']:.4f}",
        f"observability: O1 {obs['O1']:.4f}  O2 {obs['O2']:.4f}  O3 {obs['O3']:.4f}  "
        f"O4 {obs['O4']:.4f}",
    ]
    if quality.paper is not None:
        det_c = f"{quality.paper.det_c:.4f}".replace("-0.0000", "0.0000")
        lines += [
            f"paper D*: det C' {det_c}  |det S'| {quality.paper.abs_det_s:.3g}",
            _table1_line(quality),
        ]
    lines += ["", f"{'parameter':<10}{'predicted std':>14}  unit"]
    for name, unit, std in zip(
        arm.param_names, arm.param_units, quality.predicted_std, strict=True
    ):
        lines.append(f"{name:<10}{std_cell(arm, name, std, 14, 5)}  {unit}")
    pos = quality.position
    if pos is not None:
        lines += [
            "",
            f"predicted position error after calibration: RMS {pos.rms_mm:.4g} mm per point, "
            f"max {pos.max_mm:.4g} mm over {pos.per_pose_mm.size} test poses",
        ]
        if arm.feature_labels:  # an instrument's readings are not where the tool is
            lines.append(
                "  (of the arm's tool point in 3-D, in the frame the instrument is placed in; "
                "what the instrument cannot see is held, not counted)"
            )
    return "\n".join(lines)


def _document(quality: PlanQuality) -> dict:
    """Only identifiable plans have a quality (:func:`~armcal.criteria.evaluate_plan`
    raises otherwise), so every value is finite."""
    arm = quality.model.arm
    std = {
        name: 0.0 if name in arm.fixed else float(v)
        for name, v in zip(arm.param_names, quality.predicted_std, strict=True)
    }
    pos = quality.position
    paper = quality.paper
    return {
        "poses": quality.n_poses,
        "sigma_mm": quality.sigma_mm,
        "identifiable": True,  # a plan that is not has no quality: evaluate_plan raises
        "d_efficiency": quality.efficiencies["D"],
        "a_efficiency": quality.efficiencies["A"],
        "e_efficiency": quality.efficiencies["E"],
        "observability": quality.observability,
        **(
            {}
            if paper is None
            else {
                "det_c_prime": paper.det_c,
                "abs_det_s_prime": paper.abs_det_s,
                "optimality_sums": paper.optimality_sums,
            }
        ),
        "predicted_std": std,
        "predicted_position_rms_mm": None if pos is None else pos.rms_mm,
        "predicted_position_rms_per_point_mm": None if pos is None else pos.rms_mm,
        "predicted_position_max_mm": None if pos is None else pos.max_mm,
        **model_to_dict(arm),
        "warnings": [w.to_dict() for w in quality.warnings],
    }


def _loaded_quality(quality: PlanQuality) -> tuple[dict, str]:
    """JSON keys and text of the quality of a plan whose poses carry payloads (compliance).

    The predicted std of every parameter (display units), the D-efficiency of
    the normalized information on unit-norm columns (compares plans of this
    model) and how many poses carry each payload.
    """
    model = quality.model
    assert quality.payload_counts is not None
    payloads = {f"{v:g}": c for v, c in quality.payload_counts.items()}
    free = dict(zip(model.param_names, model.free, strict=True))
    std = quality.predicted_std
    effect = model.effect
    extra = [] if effect is None else list(model.param_names[model.arm.n_params :])
    document = {
        "poses": quality.n_poses,
        "sigma_mm": quality.sigma_mm,
        "identifiable": True,
        "d_efficiency": quality.efficiencies["D"],
        "predicted_std": {
            name: float(v) if free[name] else 0.0
            for name, v in zip(model.param_names, std, strict=True)
        },
        "units": dict(zip(model.param_names, model.param_units, strict=True)),
        "payload_counts": payloads,
        "compliance": extra,
        "warnings": [w.to_dict() for w in quality.warnings],
    }
    what = "" if effect is None else f" with {effect.name} ({', '.join(extra)})"
    lines = [
        f"{quality.n_poses} poses of {model.arm.name}{what}, sigma {quality.sigma_mm:g} mm",
        "payloads: " + ", ".join(f"{c} poses at {v} kg" for v, c in payloads.items()),
        f"D-efficiency (unit-norm columns, compares plans of this model): "
        f"{quality.efficiencies['D']:.4f}",
        "",
        f"{'parameter':<10}{'predicted std':>14}  unit",
    ]
    for name, unit, value in zip(model.param_names, model.param_units, std, strict=True):
        cell = f"{'fixed':>14}" if not free[name] else f"{value:>14.5g}"
        lines.append(f"{name:<10}{cell}  {unit}")
    return document, "\n".join(lines)
