"""Is a fit plausible for this arm?  Unit mistakes, a missing base offset, large deviations.

**Before any fit, for every family** (:func:`unit_mistake`): the spread of the
measured points (their RMS distance from their centroid) does not depend on
where the instrument stands, so it is compared with the nominal arm's points at
the same joint readings.  Points that spread 1000, 25.4 or 10 times less are in
metres, inches or centimetres; angles in radians under ``q*_deg`` barely move
the nominal arm, while taken as radians they spread its points as far as the
measured ones.  One or two evaluations of the model per row.

**Large deviations, for every family** (:func:`deviation_warning`): each model
says which of its parameters are the robot's deviations and how large one is
implausible (:attr:`~armcal.models.interface.FitModel.deviation_bounds`).

**After a fit, for the plain planar arm** (:func:`explain`):

Least squares gives the exact answer to whatever it is handed.  Handed joint
angles in radians under ``q*_deg``, positions in metres under ``x_mm``, or
instrument-frame data for an arm without a base offset, it answers with
deviations of hundreds of millimetres and says nothing.  This module asks, after
a fit that looks wrong, whether a simple alternative reading of the same data
fits far better, and says which:

* **angles in radians**: the file's angles are the true ones in radians, so the
  arm was at ``q_file * 180 / pi`` degrees;
* **positions in metres or centimetres**: the true positions are ``1000`` or
  ``10`` times the file's;
* **a missing base offset** (only when the arm has none): the same arm with
  ``x0, y0`` identified.

The model is linear in the link phasors, so a scaled copy of the positions is
fitted exactly as well by scaled phasors: a wrong length unit leaves the
residuals (in the file's unit) unchanged and shows only in the deviations,
about ``-99.9 %`` of every link for metres.  A wrong angle unit or a missing
base offset shows in the residuals instead.  Hence two tests:

* angles and base offset: the alternative's residual mean square (RSS over its
  degrees of freedom) is at least :data:`IMPROVEMENT` times smaller, it keeps at
  least :data:`MIN_DOF` degrees of freedom, and its deviations are plausible;
* lengths: the data as read give large deviations, the scaled data plausible
  ones, with residuals no worse in the file's unit.

Every fit here is the plain (unweighted) least-squares fit of the arm's model
with its fixed parameters, by the closed form when every parameter is free.

**Plausible deviations.**  PRODUCT.md expects deviations "up to a few mm / a
degree".  A deviation beyond :data:`LARGE_LENGTH_FRACTION` of its link or
:data:`LARGE_ANGLE_DEG` is several times that even on a 100 mm link (10 mm), yet
far from what a unit mistake gives (``-99.9 %`` or ``-90 %`` of every link,
tens of degrees): any bound between a few percent and 90 % separates the two,
and 10 % leaves a factor of about 3 to 10 on either side.  Such a deviation in
a calibration is reported as a ``large-deviation`` warning.  With a base
offset, the joint offsets ``A^-1 (1, ..., 1)`` (``dq1`` for the default joint
map) also take up any rotation of the instrument's axes about the base, which
may be anything: they are left out of the plausibility of the alternatives
(not of the warning, which names them).
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from .errors import ArmcalError, ArmcalWarning
from .identification import Calibration, solve
from .identification.diagnosis import IMPROVEMENT, SUSPICIOUS_RMS_FRACTION
from .models import (
    LARGE_ANGLE_DEG,
    LARGE_LENGTH_FRACTION,
    Conditions,
    FitModel,
    Loads,
    PlanarArm,
    forward_kinematics,
    rotation_vector,
    vector_rotation,
)
from .models.wording import (
    DEVIATION_CHECKS,
    absorbing_note,
    deviation_rule,
    deviation_summary,
)

__all__ = [
    "IMPROVEMENT",
    "LARGE_ANGLE_DEG",
    "LARGE_LENGTH_FRACTION",
    "LENGTH_UNITS",
    "MIN_DOF",
    "MIN_SPREAD_FRACTION",
    "MIN_TURN_DEG",
    "SLIDE_GAIN",
    "SLIDE_LIMIT_SLACK",
    "SPREAD_TOLERANCE",
    "SUSPICIOUS_RMS_FRACTION",
    "Explanation",
    "deviation_warning",
    "explain",
    "large_deviations",
    "spread",
    "suspicious",
    "truth_warning",
    "unit_mistake",
]

#: Residual degrees of freedom an alternative must keep to be compared.  For data
#: the original model fits (Gaussian noise), two extra parameters leave
#: ``RSS_alt / RSS ~ Beta(k / 2, 1)`` on ``k`` degrees of freedom, so a 100-fold drop
#: happens by chance with probability ``100^(-k/2)``: 1 % at ``k = 2``, ``1e-6`` at 6.
#: With as many parameters as equations any reading fits exactly and proves nothing.
MIN_DOF = 6

#: Position scale factors tried, with the unit they stand for.
_LENGTH_UNITS = ((1000.0, "metres"), (10.0, "centimetres"))


@dataclass(frozen=True)
class Explanation:
    """A reading of the data that fits far better than the one given.

    Attributes
    ----------
    code : str
        ``"angles-in-radians"``, ``"positions-in-metres"``,
        ``"positions-in-centimetres"`` or ``"missing-base-offset"``.
    message : str
        One line: what looks wrong, by how much the alternative fits better,
        and the fix (without the file name, which the caller adds).
    improvement : float
        Residual mean square as read over the alternative's, in the file's units
        (inf when the alternative fits to round-off or the data as read cannot be
        fitted; about 1 for a length unit, whose residuals scale with the data).
    params : ndarray, shape (p_alt,)
        The alternative's deviations (mm, rad), in its arm's parametrization.
    """

    code: str
    message: str
    improvement: float
    params: np.ndarray


@dataclass(frozen=True, eq=False)
class _Fit:
    arm: PlanarArm
    params: np.ndarray
    rss: float  # unweighted, in the squared unit of the positions fitted
    dof: int  # 2 m - p_f

    @property
    def mean_square(self) -> float:
        return self.rss / self.dof if self.dof > 0 else np.inf


def _fit(arm: PlanarArm, q: np.ndarray, xy: np.ndarray) -> _Fit | None:
    """Plain least squares of ``arm``'s model (its fixed parameters held), or None.

    None when the plan cannot identify the free parameters or the fit fails.
    """
    plain = arm.replace(noise=None)
    rows = plain.conditions(q)
    try:
        plain.check_identifiable(rows)
        params = solve(plain, rows, xy).params[0]  # the closed form, or Gauss-Newton if fixed
    except ArmcalError:  # NotIdentifiableError among them: this reading tells nothing
        return None
    if not np.all(np.isfinite(params)):
        return None
    residuals = xy - forward_kinematics(plain, q, params)
    return _Fit(plain, params, float(np.sum(residuals**2)), 2 * q.shape[0] - plain.n_free)


def large_deviations(
    model: FitModel, params: np.ndarray, *, rotation_free: bool = False
) -> list[str]:
    """The robot's deviations that are implausibly large, described one by one.

    Parameters
    ----------
    model : FitModel
        Of any family: its :attr:`~armcal.models.interface.FitModel.deviation_bounds`
        say which parameters are the robot's deviations and how large is implausible.
    params : ndarray, shape (p,)
        Identified parameters (mm, rad).
    rotation_free : bool
        Leave out the deviations that may take up something else (with a base offset,
        the offsets that take up a turn of the instrument's axes: ``dq1`` for the
        default joint map), which may be anything.

    Returns
    -------
    list of str
        ``"dl1 = 378 mm (108 % of link 1, 350 mm)"`` for every length beyond its bound
        (:data:`LARGE_LENGTH_FRACTION` of a planar link), ``"dq2 = 25.3 deg"`` for every
        angle beyond :data:`LARGE_ANGLE_DEG`; empty when none is.

    Examples
    --------
    >>> arm = PlanarArm([350.0, 200.0])
    >>> large_deviations(arm, arm.params_from_display([378.0, 1.0], [0.5, -25.3]))
    ['dl1 = 378 mm (108 % of link 1, 350 mm)', 'dq2 = -25.3 deg']
    """
    bounds = model.deviation_bounds
    params = np.asarray(params, dtype=float)
    large = np.abs(params) > bounds.bounds
    if rotation_free:
        large &= ~bounds.absorbing
    shown = params * model.display_scale
    found = []
    for i in np.flatnonzero(large):
        text = f"{model.param_names[i]} = {shown[i]:.4g} {model.param_units[i]}"
        reference = bounds.reference_mm[i]
        if np.isfinite(reference):
            text += (
                f" ({100 * abs(params[i]) / reference:.3g} % of {bounds.reference_names[i]}, "
                f"{reference:g} mm)"
            )
        found.append(text)
    return found


def deviation_warning(model: FitModel, params: np.ndarray) -> ArmcalWarning | None:
    """A ``large-deviation`` warning when identified deviations are implausibly large.

    Parameters
    ----------
    model : FitModel
        The model calibrated (any family).
    params : ndarray, shape (p,)
        Its identified parameters (mm, rad, and an effect's units).

    Returns
    -------
    ArmcalWarning or None
        Naming every large deviation (:func:`large_deviations`), the family's bounds
        and what to check.

    Examples
    --------
    >>> arm = PlanarArm([260.0, 180.0])
    >>> deviation_warning(arm, arm.params_from_display([1.5, -0.6], [0.5, -0.5])) is None
    True
    >>> deviation_warning(arm, arm.params_from_display([30.0, 0.0], [0.0, 0.0])).code
    'large-deviation'
    """
    found = large_deviations(model, params)
    if not found:
        return None
    bounds = model.deviation_bounds
    absorbing = {model.param_names[i] for i in np.flatnonzero(bounds.absorbing)}
    note = ""
    if any(item.split(" ")[0] in absorbing for item in found):
        note = f" ({absorbing_note(bounds, model.param_names)})"
    return ArmcalWarning(
        "large-deviation",
        f"identified deviations are {deviation_summary(bounds)}: {', '.join(found)}{note}; "
        f"calibration-sized deviations are a few mm and about a degree (here more than "
        f"{deviation_rule(bounds)}); {DEVIATION_CHECKS[bounds.check]}",
    )


def truth_warning(model: FitModel, truth: np.ndarray) -> ArmcalWarning | None:
    """A ``truth-large`` warning when a virtual arm's deviations (a truth file's, for
    synthesize and simulate) are implausibly large for a calibration, any family.

    A truth this far from the nominal model is another arm: a fit from nominal may not
    reach it, and a study of it says nothing of a real calibration.  The deviations that
    may take up a turn of the instrument (:func:`large_deviations`' ``rotation_free``)
    are left out: a truth may turn the arm in the instrument's frame at will.

    Examples
    --------
    >>> arm = PlanarArm([260.0, 180.0])
    >>> truth_warning(arm, arm.params_from_display([1.0, -0.5], [0.3, -0.2])) is None
    True
    >>> truth_warning(arm, arm.params_from_display([150.0, 0.0], [0.0, 0.0])).code
    'truth-large'
    """
    found = large_deviations(model, truth, rotation_free=True)
    if not found:
        return None
    return ArmcalWarning(
        "truth-large",
        f"the virtual arm's deviations are {deviation_summary(model.deviation_bounds)}: "
        f"{', '.join(found)}; "
        "an arm this far from its nominal model is another arm (a fit from nominal may not "
        "reach it, and the study says little of a real calibration): check the truth's units "
        "and the arm it describes",
    )


def suspicious(cal: Calibration) -> bool:
    """Whether a calibration looks wrong enough to try other readings of its data.

    True when the fit is inconsistent with sigma (a ``fit-inconsistent``
    warning), its residual RMS exceeds :data:`SUSPICIOUS_RMS_FRACTION` of the
    arm's reach, or a deviation is implausibly large (:func:`large_deviations`).
    """
    reach = float(np.sum(cal.arm.link_lengths))
    return (
        any(w.code == "fit-inconsistent" for w in cal.warnings)
        or cal.residual_rms > SUSPICIOUS_RMS_FRACTION * reach
        or bool(large_deviations(cal.arm, cal.model.arm_params(cal.params)))
    )


def _plausible(fit: _Fit) -> bool:
    return not large_deviations(fit.arm, fit.params, rotation_free=fit.arm.base_offset)


def _rms(fit: _Fit, m: int) -> float:
    return float(np.sqrt(fit.rss / (2 * m)))


def _fold(ratio: float) -> str:
    if not np.isfinite(ratio):
        return "to round-off"
    return f"{ratio:.2g}-fold"


def _better(original: _Fit | None, alternative: _Fit | None, m: int, reach: float) -> float:
    """Mean-square ratio of the data as read over an alternative (0: the alternative is no answer).

    The alternative must keep :data:`MIN_DOF` degrees of freedom and plausible
    deviations.  With no fit of the data as read (the plan cannot identify the
    parameters), it must fit to within :data:`SUSPICIOUS_RMS_FRACTION` of the reach.
    """
    if alternative is None or alternative.dof < MIN_DOF or not _plausible(alternative):
        return 0.0
    if original is None:
        fits = _rms(alternative, m) <= SUSPICIOUS_RMS_FRACTION * reach
        return np.inf if fits else 0.0
    if _rms(original, m) <= 1e-9 * reach:  # as read, the data fit to round-off
        return 0.0
    if alternative.rss <= 0:
        return np.inf
    return original.mean_square / alternative.mean_square


def explain(
    arm: PlanarArm,
    q: np.ndarray,
    xy: np.ndarray,
) -> Explanation | None:
    """Find a reading of measurements that fits them far better than the one given.

    Parameters
    ----------
    arm : PlanarArm
        The arm as the robot file describes it (fixed parameters held).
    q : ndarray, shape (m, n)
        Joint angles as read (rad, converted from the file's degrees).
    xy : ndarray, shape (m, 2)
        Positions as read (the file's ``x_mm``, ``y_mm``).

    Returns
    -------
    Explanation or None
        The best alternative reading (module notes) that is itself plausible;
        None when none is, or when the data as read fit to round-off.

    Notes
    -----
    Three or four least-squares fits of ``m`` poses; the data as read may be
    unidentifiable (angles in radians read as degrees put every pose within a
    few degrees of the stretched arm), in which case an alternative must fit to
    within :data:`SUSPICIOUS_RMS_FRACTION` of the reach on its own.

    Examples
    --------
    >>> arm = PlanarArm([260.0, 180.0])
    >>> q_deg = np.array([[0, 0], [0, 90], [90, 90], [45, -120], [-60, 30], [120, -45]])
    >>> truth = arm.params_from_display([1.5, -0.6], [0.5, -0.5])
    >>> xy = forward_kinematics(arm, np.radians(q_deg), truth)
    >>> explain(arm, np.radians(q_deg), xy) is None
    True
    >>> in_radians = np.radians(np.radians(q_deg))  # a file of radians, read as degrees
    >>> explain(arm, in_radians, xy).code
    'angles-in-radians'
    """
    q = np.asarray(q, dtype=float)
    xy = np.asarray(xy, dtype=float)
    m, n = q.shape
    reach = float(np.sum(arm.link_lengths))
    original = _fit(arm, q, xy)
    found: list[Explanation] = []

    radians = _fit(arm, np.degrees(q), xy)
    ratio = _better(original, radians, m, reach)
    if radians is not None and ratio >= IMPROVEMENT:
        columns = "q1_deg" if n == 1 else f"q1_deg..q{n}_deg"
        found.append(
            Explanation(
                "angles-in-radians",
                f"the joint angles in {columns} look like radians: the fit improves "
                f"{_fold(ratio)} if they are (residual RMS per coordinate "
                f"{_describe(original, m)} -> "
                f"{_rms(radians, m):.3g} mm); convert them to degrees",
                ratio,
                radians.params,
            )
        )

    if not arm.base_offset:
        based = _fit(arm.replace(base_offset=True), q, xy)
        ratio = _better(original, based, m, reach)
        if based is not None and ratio >= IMPROVEMENT:
            x0, y0 = based.params[2 * n :]
            found.append(
                Explanation(
                    "missing-base-offset",
                    f"the positions look measured in an instrument frame away from the arm's "
                    f"base: with a base offset (x0, y0 = {x0:.4g}, {y0:.4g} mm) the fit improves "
                    f"{_fold(ratio)} (residual RMS per coordinate {_describe(original, m)} -> "
                    f"{_rms(based, m):.3g} mm); set base_offset = true in the robot file",
                    ratio,
                    based.params,
                )
            )

    if original is not None and not _plausible(original):
        for scale, unit in _LENGTH_UNITS:
            scaled = _fit(arm, q, xy * scale)
            if scaled is None or not _plausible(scaled):
                continue
            if scaled.rss / scale**2 > 2.0 * original.rss:  # fits worse in the file's unit
                continue
            worst = _worst_fraction(arm, original.params)
            found.append(
                Explanation(
                    f"positions-in-{unit}",
                    f"the positions in x_mm, y_mm look like {unit}: times {scale:g} they give "
                    f"deviations of at most {_worst_fraction(arm, scaled.params):.2g} % of a "
                    f"link (as read: {worst:.3g} %); convert them to mm",
                    original.rss / (scaled.rss / scale**2) if scaled.rss > 0 else 1.0,
                    scaled.params,
                )
            )
            break
    if not found:
        return None
    return max(found, key=lambda e: e.improvement)


def _describe(fit: _Fit | None, m: int) -> str:
    return "n/a: not identifiable as read" if fit is None else f"{_rms(fit, m):.3g} mm"


def _worst_fraction(arm: PlanarArm, params: np.ndarray) -> float:
    """Largest ``|dl_k| / l_k`` in percent."""
    n = arm.n_joints
    return float(100 * np.max(np.abs(params[:n]) / arm.link_lengths))


# --------------------------------------------------------------------------- every family

#: Length units measurements are given in by mistake, with their length in mm.
LENGTH_UNITS = (("metres", 1000.0), ("inches", 25.4), ("centimetres", 10.0))

#: How far (a factor either way) the measured points' spread may be from the nominal
#: arm's at the same readings for the two to be the same arm in the same unit.  A
#: calibration changes the arm by a few mm, and targets the robot file does not place
#: (a reflector nest, a tool) change the spread by their offset from the flange, a few
#: tens of percent of a small arm's at most; the units tried are at least a factor 2.54
#: apart (inches, centimetres), which a factor 1.5 either way keeps apart.
SPREAD_TOLERANCE = 1.5

#: The nominal points' spread must be at least this fraction of the reach for their
#: size to tell a unit: a plan that hardly moves the arm spreads its points over little
#: more than the targets' offsets, which the robot file may not give.
MIN_SPREAD_FRACTION = 0.05


#: How many times less (RMS) the distances of the points from their centroid must miss
#: the measured ones with slide readings taken in another unit than as read, for that
#: unit to be named: the two readings share the nominal tool point's error (tens of mm),
#: while a slide read 1000 or 10 times too small misses by its whole travel.
SLIDE_GAIN = 2.0

#: How far (a fraction of a slide's range) its readings taken in another unit may fall
#: beyond its limits and still be that unit's: a reading a little past a limit.
SLIDE_LIMIT_SLACK = 0.01


#: A 6-DoF instrument's orientations tell a unit only when the nominal tool turns at
#: least this much (RMS, deg) from one row of a target to the next: radians read as
#: degrees turn 57 times less, 0.09 deg here, still several times a probe's noise.
MIN_TURN_DEG = 5.0


def _turns_between(turns: np.ndarray, target: np.ndarray | None) -> float:
    """The RMS angle (rad) from each row's orientation ``(m, 3)`` (rotation vectors) to the
    next row's of the same target.  A turn of the instrument, or of a target on the tool,
    leaves it unchanged (``R_i R_j^T`` is only turned), so measured and nominal compare."""
    m = turns.shape[0]
    labels = np.zeros(m, dtype=int) if target is None else np.asarray(target)
    order = np.lexsort((np.arange(m), labels))
    rotations = vector_rotation(turns[order])
    same = labels[order][1:] == labels[order][:-1]
    if not same.any():
        return 0.0
    between = rotations[1:][same] @ np.swapaxes(rotations[:-1][same], -1, -2)
    return float(np.sqrt(np.mean(np.sum(rotation_vector(between) ** 2, axis=-1))))


def spread(points: np.ndarray) -> float:
    """The RMS distance of points ``(m, d)`` from their centroid, mm.

    It does not change when the instrument stands elsewhere or turns (a rigid motion
    of every point), so measured points and the nominal arm's compare without a fit.

    Examples
    --------
    >>> spread(np.array([[0.0, 0.0], [6.0, 8.0]]))
    5.0
    """
    points = np.asarray(points, dtype=float)
    return float(np.sqrt(np.mean(np.sum((points - points.mean(axis=0)) ** 2, axis=-1))))


def _near(ratio: float) -> bool:
    return 1.0 / SPREAD_TOLERANCE <= ratio <= SPREAD_TOLERANCE


def _columns(names: list[str]) -> str:
    return names[0] if len(names) == 1 else f"{names[0]}..{names[-1]}"


def unit_mistake(
    model: FitModel,
    q: np.ndarray,
    points: np.ndarray,
    *,
    target: np.ndarray | None = None,
    loads: Loads | None = None,
    orientations: np.ndarray | None = None,
) -> str | None:
    """What looks like a unit mistake in measurements, said with the fix; None when none does.

    Two tests, without a fit and for every family, on the spread of the points
    (:func:`spread`), which does not depend on where the instrument stands:

    * **positions in metres, inches or centimetres** (:data:`LENGTH_UNITS`): the
      measured points spread as far as the nominal arm's at the same readings once
      multiplied by the unit's length in mm (within :data:`SPREAD_TOLERANCE`);
    * **angles in radians** read as degrees: every turning joint's reading is within
      a turn of "degrees" (2 pi / 180 rad), the nominal arm's points at these readings
      do not spread like the measured ones, and at the readings taken as radians
      they do.

    Both need a nominal spread of at least :data:`MIN_SPREAD_FRACTION` of the reach.
    A 6-DoF instrument's orientations in radians under ``rx_deg, ry_deg, rz_deg``
    turn 180 / pi times less from row to row than the nominal tool (at least
    :data:`MIN_TURN_DEG`), where in degrees they turn as far.

    Parameters
    ----------
    model : FitModel
        The model to fit, with its nominal targets and loads.
    q : ndarray, shape (m, n)
        Joint readings as read (rad; a slide's in mm).
    points : ndarray, shape (m, d)
        Measured positions as read (the file's ``x_mm, y_mm[, z_mm]``; 3-D points of
        a planar arm spread as their plane's).
    target, loads
        Every row's target (for a model with several) and loads.
    orientations : ndarray, shape (m, 3), optional
        A 6-DoF instrument's orientations as read (rotation vectors, rad), for a
        model whose points include them.

    Returns
    -------
    str or None
        One line naming the columns, what they look like and the fix (the file's
        name is the caller's).

    Notes
    -----
    One or two evaluations of the model at every row: ``O(m)``, far less than a fit.

    Examples
    --------
    >>> arm = PlanarArm([260.0, 180.0])
    >>> q = np.radians([[0, 0], [0, 90], [90, 90], [45, -120], [-60, 30], [120, -45]])
    >>> xy = forward_kinematics(arm, q)
    >>> unit_mistake(arm, q, xy) is None
    True
    >>> unit_mistake(arm, q, xy / 1000).split(":")[0]
    'the positions in x_mm, y_mm look like metres'
    >>> unit_mistake(arm, np.radians(q), xy).split(":")[0]
    'the joint angles in q1_deg..q2_deg look like radians'
    """
    q = np.asarray(q, dtype=float)
    measured = spread(np.asarray(points, dtype=float))
    conditions = model.conditions(q, target=target, loads=loads)
    nominal = spread(model.positions(conditions)[:, : model.position_dim])
    least = MIN_SPREAD_FRACTION * model.reach_mm
    turning = np.array(model.joint_kinds) == "R"  # the readings that turn a joint
    angles = q[:, turning]
    if angles.size and np.max(np.abs(angles)) <= np.radians(2 * np.pi) * (1 + 1e-9):
        as_radians = q.copy()
        as_radians[:, turning] = np.degrees(angles)
        turned = replace(conditions, q=as_radians)
        radians = spread(model.positions(turned)[:, : model.position_dim])
        if radians >= least and _near(measured / radians) and not _near(measured / nominal):
            names = [f"q{j + 1}_deg" for j in np.flatnonzero(turning)]
            columns = _columns(names) if turning.all() else ", ".join(names)
            return (
                f"the joint angles in {columns} look like radians: every value is within "
                f"±{np.degrees(np.max(np.abs(angles))):.3g}, and taken as radians they spread "
                f"the nominal arm's points as far as the measured ones (RMS distance from their "
                f"centroid {radians:.4g} mm, measured {measured:.4g} mm; as degrees "
                f"{nominal:.3g} mm); convert them to degrees"
            )
    if not turning.all():
        found = _slides_in_another_unit(model, conditions, q, np.asarray(points, float), turning)
        if found is not None:
            return found
    if orientations is not None and model.point_dim > model.position_dim:
        found = _orientations_in_radians(model, conditions, np.asarray(orientations, float))
        if found is not None:
            return found
    if nominal < least:
        return None
    for unit, length in LENGTH_UNITS:
        if _near(measured * length / nominal):
            columns = ", ".join(["x_mm", "y_mm", "z_mm"][: np.shape(points)[1]])
            return (
                f"the positions in {columns} look like {unit}: they spread "
                f"{nominal / measured:.3g} times less than the nominal arm's points at the "
                f"same joint readings (RMS distance from their centroid {measured:.4g} in the "
                f"file, {nominal:.4g} mm for the nominal arm), as {unit} would ({length:g} mm "
                "each); convert them to mm"
            )
    return None


def _centroid_distances(points: np.ndarray) -> np.ndarray:
    """Every point's distance from the points' centroid (mm): unchanged by where the
    instrument stands or how it is turned, so measured and nominal compare row by row."""
    return np.linalg.norm(points - points.mean(axis=0), axis=-1)


def _slides_in_another_unit(
    model: FitModel,
    conditions: Conditions,
    q: np.ndarray,
    points: np.ndarray,
    turning: np.ndarray,
) -> str | None:
    """Slide readings in metres (inches, centimetres) under ``q*_mm``, said with the fix.

    A slide read 1000 times too small hardly moves the nominal arm, while its other
    joints still spread its points: the spread alone may not tell (a 3 m track under a
    2 m arm spreads them about as far either way).  Every point's distance from the
    centroid does, row by row.  A unit is named when the readings taken in it lie
    within the slides' limits (give or take :data:`SLIDE_LIMIT_SLACK` of their range),
    the distances as read miss the measured ones by at least
    :data:`MIN_SPREAD_FRACTION` of the reach (RMS; no calibration deviation does), and
    the readings taken in the unit miss them :data:`SLIDE_GAIN` times less: the nominal
    tool point may be tens of mm off the true one, which the two share.
    """
    measured = _centroid_distances(points)
    positions = model.positions(conditions)[:, : model.position_dim]
    as_read = float(np.sqrt(np.mean((measured - _centroid_distances(positions)) ** 2)))
    if as_read < MIN_SPREAD_FRACTION * model.reach_mm:
        return None
    slides = ~turning
    low, high = model.joint_limits[slides].T
    slack = SLIDE_LIMIT_SLACK * (high - low)
    best: tuple[float, str, float] | None = None
    for unit, length in LENGTH_UNITS:
        scaled = q.copy()
        scaled[:, slides] *= length
        inside = (scaled[:, slides] >= low - slack) & (scaled[:, slides] <= high + slack)
        if not inside.all():
            continue
        moved = model.positions(replace(conditions, q=scaled))[:, : model.position_dim]
        mismatch = float(np.sqrt(np.mean((measured - _centroid_distances(moved)) ** 2)))
        if mismatch * SLIDE_GAIN <= as_read and (best is None or mismatch < best[0]):
            best = (mismatch, unit, length)
    if best is None:
        return None
    mismatch, unit, length = best
    names = [f"q{j + 1}_mm" for j in np.flatnonzero(slides)]
    span = q[:, slides]
    return (
        f"the slide readings in {', '.join(names)} look like {unit}: they span "
        f"{span.min():.4g} to {span.max():.4g}, and taken as {unit} ({length:g} mm each) "
        f"they put the nominal arm's points about as far from their centroid as the measured "
        f"ones (RMS mismatch {mismatch:.3g} mm, as read {as_read:.3g} mm); convert them to mm"
    )


def _orientations_in_radians(
    model: FitModel, conditions: Conditions, orientations: np.ndarray
) -> str | None:
    """A 6-DoF instrument's orientations that turn like radians read as degrees."""
    nominal = _turns_between(
        model.positions(conditions)[:, model.position_dim :], conditions.target
    )
    measured = _turns_between(orientations, conditions.target)
    if nominal < np.radians(MIN_TURN_DEG) or _near(measured / nominal):
        return None
    if not _near(np.degrees(measured) / nominal):
        return None
    return (
        f"the orientations in rx_deg, ry_deg, rz_deg look like radians: from row to row of a "
        f"target they turn {nominal / max(measured, 1e-300):.3g} times less than the nominal "
        f"tool at the same joint readings (RMS {np.degrees(measured):.3g} deg against "
        f"{np.degrees(nominal):.3g} deg), as radians read as degrees would; convert them to "
        "degrees"
    )
