"""Is a fit plausible for this arm?  Unit mistakes, a missing base offset, large deviations.

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

from dataclasses import dataclass

import numpy as np

from .errors import ArmcalError, ArmcalWarning
from .identification import Calibration, solve
from .models import PlanarArm, combination, forward_kinematics

__all__ = [
    "IMPROVEMENT",
    "LARGE_ANGLE_DEG",
    "LARGE_LENGTH_FRACTION",
    "MIN_DOF",
    "SUSPICIOUS_RMS_FRACTION",
    "Explanation",
    "deviation_warning",
    "explain",
    "large_deviations",
    "suspicious",
]

#: A link-length deviation beyond this fraction of its nominal length is implausible.
LARGE_LENGTH_FRACTION = 0.10

#: A joint-offset deviation beyond this many degrees is implausible.
LARGE_ANGLE_DEG = 10.0

#: How many times smaller an alternative's residual sum of squares must be (two
#: orders of magnitude: far beyond what two extra parameters or chance give).
IMPROVEMENT = 100.0

#: Residual degrees of freedom an alternative must keep to be compared.  For data
#: the original model fits (Gaussian noise), two extra parameters leave
#: ``RSS_alt / RSS ~ Beta(k / 2, 1)`` on ``k`` degrees of freedom, so a 100-fold drop
#: happens by chance with probability ``100^(-k/2)``: 1 % at ``k = 2``, ``1e-6`` at 6.
#: With as many parameters as equations any reading fits exactly and proves nothing.
MIN_DOF = 6

#: A residual RMS above this fraction of the arm's reach (0.66 mm for the paper's
#: 660 mm arm) is more than an instrument good enough to calibrate the arm leaves:
#: calibration corrects deviations of about 1/200 of the reach (a few mm), so a
#: useful instrument is several times better than 1/1000 of it.
SUSPICIOUS_RMS_FRACTION = 1e-3

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
    arm: PlanarArm, params: np.ndarray, *, rotation_free: bool = False
) -> list[str]:
    """The deviations that are a large fraction of a link, described one by one.

    Parameters
    ----------
    arm : PlanarArm
    params : ndarray, shape (p,)
        User deviations (mm, rad).
    rotation_free : bool
        Leave out the offsets that take up a turn of the instrument's axes
        (with a base offset; ``dq1`` for the default joint map), which may be anything.

    Returns
    -------
    list of str
        ``"dl1 = 378 mm (108 % of link 1, 350 mm)"`` for every ``|dl_k|`` above
        :data:`LARGE_LENGTH_FRACTION` of ``l_k`` and ``"dq2 = 25.3 deg"`` for
        every ``|dq_k|`` above :data:`LARGE_ANGLE_DEG`; empty when none is.

    Examples
    --------
    >>> arm = PlanarArm([350.0, 200.0])
    >>> large_deviations(arm, arm.params_from_display([378.0, 1.0], [0.5, -25.3]))
    ['dl1 = 378 mm (108 % of link 1, 350 mm)', 'dq2 = -25.3 deg']
    """
    k = arm.n_links
    names = arm.param_names
    nominal = arm.link_nominal
    dl = params[:k]
    dq = np.degrees(params[k : 2 * k])
    found = [
        f"{names[i]} = {dl[i]:.4g} mm ({100 * abs(dl[i]) / nominal[i]:.3g} % of link "
        f"{arm.link_names[i]}, {nominal[i]:g} mm)"
        for i in range(k)
        if abs(dl[i]) > LARGE_LENGTH_FRACTION * nominal[i]
    ]
    turned = arm.turn_offsets != 0 if rotation_free else np.zeros(k, dtype=bool)
    found += [
        f"{names[k + i]} = {dq[i]:.4g} deg"
        for i in range(k)
        if abs(dq[i]) > LARGE_ANGLE_DEG and not turned[i]
    ]
    return found


def deviation_warning(arm: PlanarArm, params: np.ndarray) -> ArmcalWarning | None:
    """A ``large-deviation`` warning when identified deviations are implausibly large.

    Parameters
    ----------
    arm : PlanarArm
        The arm calibrated.
    params : ndarray, shape (p,)
        Identified user deviations (mm, rad).

    Returns
    -------
    ArmcalWarning or None
        Naming every large deviation (:func:`large_deviations`) and what to check.

    Examples
    --------
    >>> arm = PlanarArm([260.0, 180.0])
    >>> deviation_warning(arm, arm.params_from_display([1.5, -0.6], [0.5, -0.5])) is None
    True
    >>> deviation_warning(arm, arm.params_from_display([30.0, 0.0], [0.0, 0.0])).code
    'large-deviation'
    """
    found = large_deviations(arm, params)
    if not found:
        return None
    rotation = ""
    k = arm.n_links
    turn = arm.turn_offsets
    turned = [arm.param_names[k + i] for i in np.flatnonzero(turn)]
    if arm.base_offset and any(item.split(" ")[0] in turned for item in found):
        offsets = combination(turn, arm.param_names[k : 2 * k])
        rotation = (
            f" (with a base offset, {offsets} also take{'s' if len(turned) == 1 else ''} up "
            "any rotation of the instrument's axes)"
        )
    return ArmcalWarning(
        "large-deviation",
        f"identified deviations are a large part of a link: {', '.join(found)}{rotation}; "
        f"calibration-sized deviations are a few mm and about a degree (here more than "
        f"{100 * LARGE_LENGTH_FRACTION:g} % of a link or {LARGE_ANGLE_DEG:g} deg); check the "
        "robot file's link lengths, the units of the measurements (mm, deg), "
        "and base_offset",
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
