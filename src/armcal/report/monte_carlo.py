"""A Monte Carlo as text and JSON: empirical against predicted std, bias, tip errors."""

from __future__ import annotations

import math
from collections.abc import Mapping

import numpy as np

from ..errors import ACTIONS
from ..simulate import MonteCarlo
from .common import model_lines, model_to_dict, small

__all__ = [
    "format_monte_carlo",
    "monte_carlo_to_dict",
]


def format_monte_carlo(result: MonteCarlo, *, words: Mapping[str, str] = ACTIONS) -> str:
    """Human-readable table of :func:`monte_carlo`: empirical vs predicted std and bias
    (``words`` say the advice, :func:`armcal.errors.render`)."""
    arm = result.arm
    noise = arm.noise
    turned = (  # partial coordinates that read the tool's turn: its sigma too
        noise is not None and noise.orientation_sigma is not None and arm.reads_turns
    )
    turn = f", {math.degrees(noise.orientation_sigma):g} deg a turn" if turned else ""
    lines = [
        f"Monte Carlo: {result.trials} trials of {result.q.shape[0]} poses of {arm.name}, "
        f"sigma {result.sigma_mm:g} {arm.reading_unit}{turn}, {result.method} "
        f"({result.seconds:.2f} s)",
        *model_lines(arm, words=words),
        "",
        f"{'parameter':<10}{'truth':>10}{'bias':>11}{'empirical std':>15}{'predicted std':>15}"
        f"{'ratio':>8}  unit",
    ]
    truth = result.truth * result.display_scale
    model = result.model
    held = {n for n, free in zip(model.param_names, model.free, strict=True) if not free}
    for name, unit, t, b, s, ps in zip(
        result.names,
        result.units,
        truth,
        result.bias,
        result.std,
        result.predicted_std,
        strict=True,
    ):
        if name in held:  # held (by the user or a rule): no spread to compare
            lines.append(
                f"{name:<10}{t:>10.4f}{b:>11.2e}{'fixed':>15}{'fixed':>15}{'':>8}  {unit}"
            )
            continue
        lines.append(
            f"{name:<10}{t:>10.4f}{b:>11.2e}{small(s, 5):>15}{small(ps, 5):>15}"
            f"{s / ps:>8.3f}  {unit}"
        )
    flagged = result.biased
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
            f"tip error of the calibrated model at test poses: RMS {pos.rms_mm:.4g} mm per point "
            "over all "
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
        **({} if result.arm.reading_unit == "mm" else {"reading_unit": result.arm.reading_unit}),
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
            "rms_per_point": pos.rms_mm,
            "predicted_rms_per_point": pos.predicted_rms_mm,
            "quantiles": pos.quantiles_mm,
            "quantile_intervals_95": {
                key: list(bounds) for key, bounds in pos.quantile_intervals_mm.items()
            },
            "pairs": pos.pairs,
            "quantile_subsample": pos.subsample,
        }
    return document
