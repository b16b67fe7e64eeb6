"""A design and a sizing as text and JSON: the method, the certificate, the order."""

from __future__ import annotations

import math
from collections.abc import Mapping

import numpy as np

from ..doe.certificate import Certificate
from ..doe.designer import Design
from ..doe.sizing import REQUIREMENTS, PosesNeeded
from ..errors import ACTIONS, render
from ..models import FitModel
from .common import model_lines, model_to_dict

__all__ = [
    "design_summary",
    "poses_needed_summary",
]


def design_summary(
    result: Design, seconds: float, *, words: Mapping[str, str] = ACTIONS
) -> tuple[dict, list[str]]:
    """JSON keys and header lines of ``armcal design`` (before the plan's quality report).

    Parameters
    ----------
    result : Design
    seconds : float
        Wall time of the design.
    words : mapping, optional
        The words of the notes' advice (:func:`armcal.errors.render`; default the
        library's).

    Returns
    -------
    document : dict
        ``criterion``, ``method``, the certificate's bounds (None without one),
        ``certificate_pool_size`` (the distinct candidate poses a plan from a pool is
        certified against, the best plan over them; None: over every feasible pose),
        ``reference_design`` (:func:`reference_design`: the weighted design behind the
        certified figure), ``d_efficiency_basis`` (what ``d_efficiency`` is relative
        to: ``unconstrained optimum`` where every design's is at most 1, else ``design
        coordinates``, the D-criterion of the information with unit-norm columns, which
        compares plans only through ``d_efficiency_vs_best_weighted_design``),
        ``notes``, ``seconds``, ``order``, ``distinct`` and the joint travel in
        the plan's order and in the order the method found
        (``joint_travel_deg``, ``joint_travel_unordered_deg``).
    lines : list of str
        The method, the notes (why the closed-form plans were not used), the
        D-efficiency against the unconstrained optimum and the certificate, the
        joint travel, and an empty line.
    """
    if result.payload_kg is not None:
        return _loaded_design_summary(result, seconds)
    cert = result.certificate
    notes = [render(note, words) for note in result.note_texts]
    document = {
        "criterion": result.criterion,
        "method": result.method,
        "certified_d_efficiency": None if cert is None else cert.certified_d_efficiency,
        "plan_only_bound": None if cert is None else cert.plan_only_bound,
        "best_weighted_design_d_efficiency": None if cert is None else cert.reference_d_efficiency,
        "d_efficiency_vs_best_weighted_design": result.reference_efficiency,
        "max_variance": None if cert is None else cert.max_variance,
        "max_variance_pose_deg": None
        if cert is None or cert.max_pose is None
        else np.degrees(cert.max_pose).tolist(),
        "certificate_pool_size": None if cert is None else cert.pool_size,
        "reference_design": None if cert is None else reference_design(cert),
        "d_efficiency_basis": "unconstrained optimum"
        if result.normalized
        else "design coordinates",
        "notes": notes,
        "seconds": seconds,
        "order": result.order,
        "distinct": result.distinct,
        "joint_travel_deg": math.degrees(result.joint_travel),
        "joint_travel_unordered_deg": math.degrees(result.joint_travel_unordered),
    }
    if result.normalized:
        efficiency = f"D-efficiency {result.d_efficiency:.4f} of the unconstrained optimum"
    elif cert is None:  # no closed-form optimum: only a certificate compares with the best
        efficiency = f"D-criterion {result.d_efficiency:.4f} on this model"
    else:
        efficiency = (
            f"D-efficiency {result.reference_efficiency:.4f} of the best weighted design found "
            f"(D-criterion {result.d_efficiency:.4f} on this model)"
        )
    if result.optimum_by_search:
        # The note ruled out only the closed-form family: say that the search met the optimum.
        efficiency += " (an orthogonal plan, found by search)"
    if cert is not None:
        over = (
            "within the constraints"
            if cert.pool_size is None
            else f"from the {cert.pool_size} candidate poses"
        )
        efficiency += (
            f"; certified >= {cert.certified_d_efficiency:.4f} of the best plan {over} "
            f"(plan-only bound {cert.plan_only_bound:.4f})"
        )
    lines = [
        f"design: {result.q.shape[0]} poses, criterion {result.criterion}, method {result.method} "
        f"({seconds:.2f} s)",
        *(f"note: {note}" for note in notes),
        efficiency,
        _travel_line(result),
        "",
    ]
    return document, lines


def reference_design(cert: Certificate) -> dict[str, object]:
    """The weighted design a certificate divides by, so that anyone can check its claim:
    its poses (deg) and weights, and where its variance function peaks.

    With ``M = sum_k w_k I(x_k)`` the model's per-pose information at the poses, and
    ``d(x) = tr(M^-1 I(x))``, the certified figure is ``min(1, max(kw, plan_only, ...))``
    with ``kw = (det M_plan / det M)^(1/p) exp(1 - max_x d(x) / p)``: ``max_variance``
    is ``d`` at ``max_variance_pose_deg``, the largest the search found.
    """
    return {
        "poses_deg": np.degrees(cert.support).tolist(),
        "weights": np.asarray(cert.weights, dtype=float).tolist(),
    }


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


def _loaded_design_summary(result: Design, seconds: float) -> tuple[dict, list[str]]:
    """JSON keys and header lines of ``armcal design`` for poses chosen with their payloads."""
    cert = result.certificate
    assert cert is not None  # a design with loads is always certified
    effect = result.model.effect
    what = "geometry" if effect is None else f"geometry and {effect.name}"
    document = {
        "criterion": result.criterion,
        "method": result.method,
        "certified_d_efficiency": cert.certified_d_efficiency,
        "plan_only_bound": cert.plan_only_bound,
        "max_variance": cert.max_variance,
        "payloads_allowed": list(result.payloads),
        "seconds": seconds,
        "order": result.order,
        "joint_travel_deg": float(np.degrees(result.joint_travel)),
    }
    lines = [
        f"design: D-optimal for {what}, poses and payloads "
        f"(from {', '.join(f'{v:g}' for v in result.payloads)} kg) chosen together "
        f"({seconds:.1f} s)",
        f"certified D-efficiency >= {cert.certified_d_efficiency:.4f} of the best plan "
        f"within the limits and region (max d = {cert.max_variance:.3f} for "
        f"p = {result.model.n_free})",
        "",
    ]
    return document, lines


#: Parameter names a poses-needed report lists before "and k more".
_NAMES_SHOWN = 6


def _measured(names: tuple[str, ...]) -> str:
    """``": dl1, dl2"``: the parameters a length or angle target bounds, or ``""``."""
    if not names:
        return ""
    shown = ", ".join(names[:_NAMES_SHOWN])
    rest = len(names) - _NAMES_SHOWN
    return f": {shown}" + (f" and {rest} more" if rest > 0 else "")


def poses_needed_summary(
    found: PosesNeeded, model: FitModel, seconds: float, *, words: Mapping[str, str] = ACTIONS
) -> tuple[dict, list[str]]:
    """The JSON document and the text lines of ``armcal poses-needed``.

    Parameters
    ----------
    found : PosesNeeded
    model : FitModel
        The model the plans were designed for (its name is printed).
    seconds : float
        Wall time of the search.
    words : mapping, optional
        The words of the advice (:func:`armcal.errors.render`; default the library's).

    Returns
    -------
    document : dict
        ``poses`` (PRODUCT.md), ``requirement``, ``goal``, ``achieved``,
        ``with_one_pose_less`` (null when fewer poses cannot identify every
        parameter), ``sigma_mm``, ``method``, ``evaluated`` (m -> accuracy of the
        best m-pose plan, identifiable ones only), ``measured`` (the parameters a
        length or angle target bounds; empty for the position RMS) and ``seconds``.
    lines : list of str
        The answer and how it was found; the caller adds the file it wrote.
    """
    unit = "deg" if found.requirement == "angle_std_deg" else "mm"
    arm = model.arm
    finite_previous = math.isfinite(found.previous)
    document = {
        "poses": found.poses,
        "requirement": found.requirement,
        "goal": found.goal,
        "achieved": found.achieved,
        "with_one_pose_less": found.previous if finite_previous else None,
        "sigma_mm": found.sigma_mm,
        "method": found.method,
        "evaluated": {str(m): v for m, v in found.evaluated.items() if math.isfinite(v)},
        "measured": list(found.measured),
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
        f"({REQUIREMENTS[found.requirement]}{_measured(found.measured)}; "
        f"sigma {found.sigma_mm:g} mm; "
        f"{len(found.evaluated)} plan sizes tried in {seconds:.2f} s)",
        *model_lines(arm, words=words),
    ]
    return document, lines
