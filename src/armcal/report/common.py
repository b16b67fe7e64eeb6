"""What every report shares: the model in words, numbers in their columns, tables.

Reports are pure: every function turns a result into text or a JSON-ready dict,
with no numerics and no decisions (those are the library's; the warnings come
with the results).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

import numpy as np

from ..errors import ACTIONS, action, render
from ..families.registry import family_of
from ..models import FitModel, PlanarArm, SpatialArm, combination
from ..models.wording import held_sentence

__all__ = [
    "identified",
    "markdown",
    "model_lines",
    "model_to_dict",
    "planar_model_lines",
    "small",
    "spatial_model_lines",
    "std_cell",
    "table_csv",
]


def _noise_text(arm: FitModel) -> str | None:
    """The noise model in words when it is not isotropic iid (None when it is or is unknown)."""
    noise = arm.noise
    if noise is None or noise.isotropic_iid:
        return None
    cov = noise.covariance_mm2
    if noise.tracker is not None:
        t = noise.tracker
        parts = [
            f"laser tracker, range {t.range_mm:.4g} mm + {t.range_mm_per_m:.4g} mm/m, "
            f"transverse {t.transverse_mm:.4g} mm + {t.transverse_mm_per_m:.4g} mm/m of "
            "distance"
        ]
    elif noise.isotropic_instrument:
        parts = [f"instrument isotropic, sigma {math.sqrt(cov[0, 0]):.4g} mm"]
    elif np.count_nonzero(cov - np.diag(np.diagonal(cov))) == 0 and cov.shape[0] == 3:
        parts = [
            "instrument per axis, sigma_x, _y, _z "
            + ", ".join(f"{math.sqrt(v):.4g}" for v in np.diagonal(cov))
            + " mm"
        ]
    elif cov.shape[0] == 3:
        parts = ["instrument covariance (3 x 3) " + str(np.round(cov, 6).tolist()) + " mm^2"]
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
    if noise.orientation_sigma is not None:
        parts.append(f"orientation {np.degrees(noise.orientation_sigma):.4g} deg about each axis")
    return "; ".join(parts) + f" (reference sigma {noise.sigma_mm:.4g} mm)"


def spatial_model_lines(
    arm: SpatialArm,
    *,
    plan: bool = True,
    words: Mapping[str, str] = ACTIONS,
    registered: bool = False,
) -> list[str]:
    """A spatial arm's model: joint map, targets, the identifiable set and what merges.

    ``registered``: the arm was placed on measured points (a calibration), so a fixed
    parameter of the instrument (the base pose, a target found from the data) is held
    where that registration put it, not at a nominal value."""
    lines = []
    if not np.array_equal(arm.joint_map, np.eye(arm.n_joints)):
        rows = "; ".join(" ".join(f"{v:g}" for v in row) for row in arm.joint_map)
        lines.append(f"joint map: the arm's joint values u = M q with M = [{rows}]")
    where = "from the robot file" if arm.known_targets else "found from the data"
    what = "positions" if not arm.oriented else "positions and orientations, measured by a 6-DoF"
    lines.append(f"targets ({where}, {what} in the tip frame): {', '.join(arm.targets)}")
    revolute = int(np.sum(arm.chain.revolute))
    prismatic = arm.n_joints - revolute
    k = len(arm.targets)
    kind, per = ("full-pose", 6) if arm.oriented else ("point", 3)
    lines.append(
        f"identifiable set: {arm.n_free} of {arm.n_params} parameters (theory for "
        f"{revolute} revolute and {prismatic} prismatic joints and {k} {kind} "
        f"target{'s' if k > 1 else ''}: 4R + 2P + {per}k = "
        f"{4 * revolute + 2 * prismatic + per * k})"
    )
    instrument = {n for n, i in zip(arm.param_names, arm.instrument_params, strict=True) if i}
    placed = [n for n in arm.user_fixed if registered and n in instrument]
    nominal = [n for n in arm.user_fixed if n not in placed]
    if nominal:
        lines.append(f"fixed (held at nominal, not identified): {', '.join(nominal)}")
    if placed:
        lines.append(
            "fixed (held at the value registered from the data, where the nominal arm placed "
            f"on the measured points puts it; not identified): {', '.join(placed)}"
        )
    if arm.merges:
        lines.append("held at nominal, because the measurements cannot separate them:")
        lines += [f"  {held_sentence(held)}" for held in arm.merges]
    noise = _noise_text(arm)
    if noise is not None:
        lines.append(f"noise model: {noise}; not isotropic iid: weighted least squares")
    return lines


def instrumented_model_lines(
    model: Any,
    *,
    plan: bool = True,
    words: Mapping[str, str] = ACTIONS,
    registered: bool = False,
) -> list[str]:
    """An arm measured by a plane, fixed points or a distance: the instrument, what it
    cannot see, the identifiable set and what the rows cannot separate."""
    instrument = model.instrument
    inner = model.inner
    labels = instrument.labels
    shown = (
        ", ".join(labels) if len(labels) <= 8 else f"{len(labels)}: {labels[0]} to {labels[-1]}"
    )
    lines = [
        f"instrument: {instrument.kind} ({shown}), identified with the "
        f"arm: {', '.join(np.array(model.param_names)[model.instrument_params & model.free])}",
        f"what it cannot see: {instrument.unseen}",
        f"identifiable set: {model.n_free} of {model.n_params} parameters (the arm's "
        f"{inner.n_free}, the instrument's {model.n_free - inner.n_free}); the arm's base is "
        "the frame the instrument is placed in",
    ]
    base = set(model.base_names)
    held = set(inner.rule_held) | base  # the rule's, and the base the instrument sits in
    user = [n for n in inner.fixed if n not in held]
    user += list(model.instrument_fixed)
    if user:
        lines.append(f"fixed (held at nominal, not identified): {', '.join(user)}")
    merges = tuple(inner.held_reasons)
    if merges:
        lines.append("held at nominal, because the measurements cannot separate them:")
        lines += [f"  {held_sentence(held)}" for held in merges]
    noise = _noise_text(model)
    if noise is not None:
        lines.append(f"noise model: {noise}; not isotropic iid: weighted least squares")
    return lines


def model_lines(
    arm: FitModel,
    *,
    plan: bool = True,
    words: Mapping[str, str] = ACTIONS,
    registered: bool = False,
) -> list[str]:
    """Lines naming the fixed parameters and a noise model that is not isotropic iid.

    Empty for the paper's model (every parameter free, isotropic iid noise).
    ``plan`` adds, for a noise model that is not isotropic iid, that the paper's
    D*, Table I and analytic plans assume one (what changes the answer for a plan).
    ``words`` say the advice (:func:`armcal.errors.render`; the library's by default).
    ``registered``: the arm was placed on measured points (a calibration), so a spatial
    arm's fixed instrument parameters are named as held at their registered value.

    Examples
    --------
    >>> model_lines(PlanarArm([260.0, 180.0], fixed=["dl2"]))
    ['fixed (held at nominal, not identified): dl2']
    """
    describe = family_of(arm).role("describe")
    lines: list[str] = describe(arm, plan=plan, words=words, registered=registered)
    return lines


def planar_model_lines(
    arm: PlanarArm,
    *,
    plan: bool = True,
    words: Mapping[str, str] = ACTIONS,
    registered: bool = False,
) -> list[str]:
    """A planar arm's model: joint map, targets, fixed parameters, the base rotation and
    a noise model that is not isotropic iid (:func:`model_lines`)."""
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
            f"cannot tell them apart; keep phi0 free, as it also holds the turn of the "
            f"instrument's axes{render(_other_zero(arm), words)}"
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


def _other_zero(arm: PlanarArm) -> str:
    """How to take another joint offset's zero as the arm's frame, where the map has one."""
    others = [n for n in arm.rotation_names() if n not in (arm.rotation_partner, "phi0")]
    if not others:
        return ""
    return f" (to take {others[0]}'s zero as the arm's instead, {action('hold', others[0])})"


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


def identified(arm: PlanarArm) -> str:
    """``8 parameters``, or ``7 of 8 parameters identified`` when some are fixed."""
    if not arm.fixed:
        return f"{arm.n_params} parameters"
    return f"{arm.n_free} of {arm.n_params} parameters identified"


def small(value: float, digits: int) -> str:
    """``value`` with ``digits`` decimals, or in e-notation where they would show < 2 digits.

    >>> small(0.0224, 5), small(2.236e-7, 5), small(0.0, 5)
    ('0.02240', '2.24e-07', '0.00000')
    """
    if value != 0 and abs(value) < 10.0 ** (1 - digits):
        return f"{value:.2e}"
    return f"{value:.{digits}f}"


def std_cell(arm: PlanarArm, name: str, value: float, width: int, digits: int) -> str:
    """A std column: the number, or ``fixed`` for a fixed parameter."""
    if name in arm.fixed:
        return f"{'fixed':>{width}}"
    return f"{small(value, digits):>{width}}"


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


def markdown(rows: list[dict], columns: tuple[str, ...]) -> list[str]:
    out = ["| " + " | ".join(columns) + " |", "|" + "---|" * len(columns)]
    for row in rows:
        out.append("| " + " | ".join(_cell(row[c]).strip('"') for c in columns) + " |")
    return out
