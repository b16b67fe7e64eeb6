"""3-D instrument data: the plane of motion, its two sides, and identification in it.

A laser tracker or a CMM reports ``x, y, z`` in its own frame.  A planar arm
moves its targets in parallel planes (each target may sit at its own height
on the end effector), so the data are fitted with one normal and one offset
per target: the smallest right singular vector of the points, each centred on
its own target's centroid, is the least-squares normal (total least squares,
the same plane for every target up to its offset).  In-plane coordinates
``(u, v)``, with ``u`` the instrument's ``x`` axis projected onto the plane and
``v = n x u`` (:func:`armcal.models.plane.fit_plane`):

* their rotation about ``n`` against the robot's axes is where the instrument
  stood, unknown, so the base *rotation* ``phi0`` is
  identified with the base position (:attr:`armcal.models.PlanarArm.base_rotation`),
  and a joint-offset direction is held instead;
* the sign of ``n`` is not: flipping it mirrors the plane, and a mirrored
  planar arm turns the other way round.  Both sides are fitted and the one the
  arm's model explains is kept (:func:`identify_3d`); a ``mirror-ambiguous``
  warning says when the data cannot tell them apart.

How planar the data are is reported (out-of-plane RMS and largest distance)
and judged against the instrument noise (``non-planar`` warning).
"""

from __future__ import annotations

from dataclasses import replace
from typing import Any

import numpy as np

from .distributions import chi2_sf
from .errors import ArmcalError, ArmcalWarning
from .identification import Calibration, identify, solve
from .models import STANDARD_GRAVITY, Conditions, FitModel, Plane, fit_plane
from .noise import per_row_sigma

__all__ = [
    "PLANARITY_ALPHA",
    "identify_3d",
]

#: Out-of-plane distances whose chi-square against sigma has a p-value below this
#: give a ``non-planar`` warning (the level of the fit's own test).
PLANARITY_ALPHA = 1e-3

#: The mirrored plane's residual sum of squares must exceed the chosen side's by
#: this factor, else the sides are ``mirror-ambiguous``.
MIRROR_MARGIN = 4.0


def _rss(model: FitModel, conditions: Conditions, xy: np.ndarray) -> float:
    """Residual sum of squares (mm^2) of the weighted least-squares fit to in-plane data."""
    params = solve(model, conditions, xy).params[0]
    residual = xy - model.positions(conditions, params)
    return float(np.sum(residual**2))


def identify_3d(
    model: FitModel,
    q: np.ndarray,
    xyz: np.ndarray,
    *,
    target: np.ndarray | None = None,
    sigma: float | None = None,
    row_sigma: np.ndarray | None = None,
    gravity_3d: np.ndarray | None = None,
    **kwargs: Any,
) -> Calibration:
    """Identify from 3-D instrument data: fit the plane, pick its side, identify in it.

    Parameters
    ----------
    model : PlanarArm or CompliantArm
        A planar arm with ``base_offset`` and ``base_rotation`` (the base pose in
        the fitted plane is unknown; :func:`armcal.workflow.measured_arm`
        sets both), or a model of its joint compliance.
    q : ndarray, shape (m, n)
        Joint angles, rad.
    xyz : ndarray, shape (m, 3)
        Points in the instrument frame, mm.
    target : ndarray of int, shape (m,), optional
        Every row's target, for an arm with several.
    sigma, row_sigma, **kwargs
        As for :func:`armcal.identification.identify` (``sigma`` the noise of
        every coordinate, in the plane as out of it).
    gravity_3d : ndarray, shape (3,), optional
        Gravity's direction in the instrument frame (``[measurement] gravity``),
        for a model whose points depend on it (joint compliance): its component
        in the plane of motion loads the joints.

    Returns
    -------
    Calibration
        In the plane's coordinates, with :attr:`~Calibration.plane` set and the
        planarity warnings (``non-planar``, ``mirror-ambiguous``) added.
    """
    arm = model.arm
    if not (arm.base_offset and arm.base_rotation):
        raise ArmcalError(
            "3-D data need the base pose in the plane: identify with base_offset and "
            "base_rotation (armcal.workflow.measured_arm sets both)"
        )
    xyz = np.asarray(xyz, dtype=float)
    row_sigma = per_row_sigma(sigma, row_sigma)  # a given sigma replaces them, in and out of plane
    rigid = arm.conditions(q, target=target, sigma_mm=row_sigma)
    arm.check_identifiable(rigid)
    plane = fit_plane(xyz, rigid.target, arm.target_labels)
    sides = [plane, plane.mirrored()]
    rss = [_rss(arm, rigid, side.to_plane(xyz)) for side in sides]
    best = int(np.argmin(rss))
    chosen = sides[best]
    if model.uses_gravity:
        model = model.with_gravity(_gravity_in_plane(chosen, gravity_3d))
    cal = identify(
        model,
        q,
        chosen.to_plane(xyz),
        target=target,
        sigma=sigma,
        row_sigma=row_sigma,
        # The sides were fitted on these conditions: the plan's factorization is shared.
        conditions=rigid if model is arm else None,
        **kwargs,
    )
    warnings = list(cal.warnings)
    other, mine = rss[1 - best], rss[best]
    if other < MIRROR_MARGIN * max(mine, np.finfo(float).tiny):
        warnings.append(
            ArmcalWarning(
                "mirror-ambiguous",
                f"the data fit the mirror image of the plane of motion almost as well "
                f"(residual sum of squares {other:.4g} against {mine:.4g} mm^2), so which way "
                "the arm turns in the instrument frame is uncertain; measure poses that move "
                "every joint through a wide range",
            )
        )
    planarity = _planarity_warning(chosen, cal, sigma, row_sigma)
    if planarity is not None:
        warnings.append(planarity)
    return replace(cal, plane=chosen, warnings=tuple(warnings))


def _gravity_in_plane(plane: Plane, gravity_3d: np.ndarray | None) -> np.ndarray:
    """Gravity (m/s^2) in the plane's in-plane axes: the part that twists the joints."""
    if gravity_3d is None:
        raise ArmcalError(
            "3-D data with [elastostatic]: give gravity's direction in the instrument frame "
            "as [measurement] gravity = [gx, gy, gz] (e.g. [0, 0, -1] for a levelled tracker)"
        )
    g = np.asarray(gravity_3d, dtype=float)
    g = g / np.linalg.norm(g) * STANDARD_GRAVITY
    in_plane = plane.axes[:2] @ g
    if np.linalg.norm(in_plane) < 1e-3 * STANDARD_GRAVITY:
        raise ArmcalError(
            "gravity is normal to the plane of motion: a horizontal arm's joints carry no "
            "gravity torque in the plane; remove gravity or [elastostatic]"
        )
    return in_plane


def _planarity_warning(
    plane: Plane, cal: Calibration, sigma: float | None, row_sigma: np.ndarray | None
) -> ArmcalWarning | None:
    """``non-planar`` when the out-of-plane distances exceed what the noise explains.

    With the noise given, ``sum (d_i / s_i)^2`` is chi-square on ``m - 2 - T``
    degrees of freedom (the plane's normal takes 2, the offsets ``T``); without
    it, an RMS more than 3 times the in-plane residual RMS is the sign.
    """
    d = plane.out_of_plane
    assert d is not None, "a fitted plane has its points' distances"
    m, t = d.size, plane.offsets.size
    dof = m - 2 - t
    stated = ""
    if cal.sigma_source == "given" and dof > 0:
        s = row_sigma if row_sigma is not None else (sigma or cal.sigma_mm)
        chi2 = float(np.sum((d / s) ** 2))
        p_value = float(chi2_sf(dof, chi2))
        if p_value >= PLANARITY_ALPHA:
            return None
        stated = f"sigma {cal.sigma_mm:.3g} mm (chi2 = {chi2:.4g} on {dof} dof, p = {p_value:.2g})"
    else:
        if plane.rms_mm <= 3.0 * cal.residual_rms:
            return None
        stated = f"three times the in-plane residual RMS {cal.residual_rms:.3g} mm per coordinate"
    return ArmcalWarning(
        "non-planar",
        f"the points lie off their plane by {plane.rms_mm:.3g} mm RMS per point (max "
        f"{plane.max_mm:.3g} "
        f"mm), more than {stated}: the motion is not planar (a tilted joint axis, a loose "
        "target) or the noise is larger than stated; the in-plane fit ignores that part",
    )
