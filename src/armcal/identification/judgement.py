"""Is a fit consistent with its noise?  Goodness of fit, outliers, and the warnings they give.

The judgement of a fit, for every model: the chi-square test of its residuals
against sigma, the studentized outlier test, the nested-model F test of an
effect the data may not show (:func:`nested_test`), and the warnings that say
what each verdict means.  The warnings use neutral words; advice that is an
option of the library or a flag of the command line is an
:func:`~armcal.errors.action`, which each renders in its own words.

Both tests work on *standardized* residuals ``r_i = W_i e_i / sigma_ref`` (the
noise model's whitening, :mod:`armcal.noise`): under the model they are
independent ``N(0, I_d)`` per pose (``d`` = 2 in the plane), up to the fit's
own leverage.

**Goodness of fit.**  With ``sigma`` given, ``chi2 = sum_i e_i^T Sigma_i^-1 e_i``
over the poses in the fit follows a chi-square law with ``d m - p_f`` degrees
of freedom.  The test has two tails, each at the level :data:`FIT_ALPHA`:
``P(chi2_dof >= chi2)`` (the p-value every report shows) below it says the
data and the model (or ``sigma``) disagree; ``P(chi2_dof <= chi2)`` below it
says the fit is *too good* for ``sigma`` -- sigma too large, rows repeated, or
points computed rather than measured -- and every std is too large by about
``sqrt(dof / chi2)``.  On a fit consistent with ``sigma`` either tail fails
with probability :data:`FIT_ALPHA`, both together ``2 FIT_ALPHA``.

**Outliers.**  A pose is an outlier when its residual is larger than the fit
and the noise can explain.  With ``B_i = W_i J_i G`` (``G G^T = (J_w^T J_w)^-1``
over the poses in the fit) the residual of a pose in the fit has covariance
``sigma^2 (I - B_i B_i^T)`` and the prediction error of a pose left out
``sigma^2 (I + B_i B_i^T)``, so ``t_i^2 = r_i^T V_i^-1 r_i`` is

* ``chi2(d)`` when ``sigma`` is given;
* with ``sigma`` estimated, ``d F(d, nu - d)`` for a pose in the fit with
  ``sigma`` re-estimated without it (the externally studentized residual, an
  exact law under normal noise), and ``d F(d, nu)`` for a pose left out.

Every pose is tested, so the level is corrected for multiple testing
(Bonferroni): a pose is flagged when its p-value is below
``OUTLIER_ALPHA / m``.  On clean data the chance that *any* pose is flagged is
then at most ``OUTLIER_ALPHA``.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from ..distributions import chi2_cdf, chi2_sf, f_sf
from ..errors import ArmcalWarning, action
from ..models import Effect, listing
from ..models.wording import NEGATIVE_WORDS, effect_advice

__all__ = [
    "FEW_DOF",
    "FIT_ALPHA",
    "NEGATIVE_STD",
    "NESTED_UNSEEN_P",
    "OUTLIER_ALPHA",
    "GoodnessOfFit",
    "Outlier",
    "PoseTest",
    "few_dof_warning",
    "goodness_of_fit",
    "inconsistent_fit_warning",
    "negative_effect_warning",
    "nested_test",
    "not_converged_warning",
    "outlier_warning",
    "studentized_test",
    "too_good_warning",
    "unseen_warning",
]

#: A fit whose chi-square p-value is below this is inconsistent with sigma; one whose
#: lower tail ``P(chi2_dof <= chi2)`` is below it is too good for sigma (module notes).
FIT_ALPHA = 1e-3
#: Family-wise false-alarm rate of the outlier test over all poses of a fit.
OUTLIER_ALPHA = 1e-3
#: Fewer residual degrees of freedom than this cannot judge a fit.
FEW_DOF = 4


@dataclass(frozen=True)
class GoodnessOfFit:
    """The chi-square test of a fit against its noise model, both tails (module notes).

    Attributes
    ----------
    chi2 : float or None
        ``sum_i e_i^T Sigma_i^-1 e_i`` over the poses in the fit; None when
        ``sigma`` was estimated from the same residuals (then it equals ``dof``
        by construction and tests nothing).
    dof : int
        ``2 m - p_f``: measured coordinates minus free parameters.
    p_value : float or None
        ``P(chi2_dof >= chi2)``, the upper tail; None when ``sigma`` was estimated or
        ``dof <= 0``.
    p_below : float or None
        ``P(chi2_dof <= chi2)``, the lower tail: small when the fit is too good for
        ``sigma``; None when ``p_value`` is.
    """

    chi2: float | None
    dof: int
    p_value: float | None
    p_below: float | None = None

    @property
    def too_large(self) -> bool:
        """Whether chi-square is too large for sigma: ``p_value`` below :data:`FIT_ALPHA`."""
        return self.p_value is not None and self.p_value < FIT_ALPHA

    @property
    def too_good(self) -> bool:
        """Whether chi-square is too small for sigma: ``p_below`` below :data:`FIT_ALPHA`."""
        return self.p_below is not None and self.p_below < FIT_ALPHA

    @property
    def consistent(self) -> bool:
        """Neither tail fails (or there is no test)."""
        return not (self.too_large or self.too_good)

    def to_dict(self) -> dict[str, float | int | None]:
        """JSON form ``{chi2, dof, p_value, p_value_below}``."""
        return {
            "chi2": self.chi2,
            "dof": self.dof,
            "p_value": self.p_value,
            "p_value_below": self.p_below,
        }


def goodness_of_fit(standardized: np.ndarray, dof: int, *, sigma_given: bool) -> GoodnessOfFit:
    """Chi-square test of standardized residuals ``(m_used, d)`` on ``dof`` degrees of freedom.

    Examples
    --------
    >>> fit = goodness_of_fit(np.ones((10, 2)), 16, sigma_given=True)
    >>> fit.chi2, fit.dof, round(fit.p_value, 4), round(fit.p_below, 4), fit.consistent
    (20.0, 16, 0.2202, 0.7798, True)
    >>> goodness_of_fit(np.full((10, 2), 0.1), 16, sigma_given=True).too_good
    True
    """
    if not sigma_given:
        return GoodnessOfFit(None, int(dof), None)
    chi2 = float(np.sum(standardized**2))
    if dof <= 0:
        return GoodnessOfFit(chi2, int(dof), None)
    # Each tail from its own function: 1 - P would lose the small one to round-off.
    return GoodnessOfFit(chi2, int(dof), float(chi2_sf(dof, chi2)), float(chi2_cdf(dof, chi2)))


@dataclass(frozen=True)
class Outlier:
    """A pose the studentized test flags.

    Attributes
    ----------
    index : int
        0-based index of the pose in the data.
    row : int
        1-based data row of the measurement file.
    pose : str
        Its label.
    target : str or None
        The target measured, when the data name one.
    residual_mm : float
        Euclidean residual of the pose against the final fit (mm).
    studentized : float
        ``t_i`` (see the module notes): about 1 for a typical pose.
    p_value : float
        The pose's own p-value (before the multiple-testing correction).
    removed : bool
        Whether the final fit leaves the pose out (robust fitting), or only flags it.
    unit : str
        The unit of ``residual_mm``: the readings' (mm, a camera's px), or ``deg`` for a
        row that reads a turn (partial coordinates').
    """

    index: int
    row: int
    pose: str
    target: str | None
    residual_mm: float
    studentized: float
    p_value: float
    removed: bool
    unit: str = "mm"

    def to_dict(self) -> dict[str, object]:
        """JSON form ``{row, pose, target, residual_mm, studentized, p_value, removed}``."""
        return {
            "row": self.row,
            "pose": self.pose,
            "target": self.target,
            "residual_mm": self.residual_mm,
            "studentized": self.studentized,
            "p_value": self.p_value,
            "removed": self.removed,
        }


@dataclass(frozen=True, eq=False)
class PoseTest:
    """The studentized test of every pose of one fit.

    Attributes
    ----------
    statistic : ndarray, shape (m,)
        ``t_i`` (module notes).
    p_value : ndarray, shape (m,)
        Each pose's p-value.
    flagged : ndarray of bool, shape (m,)
        ``p_value < alpha / m`` (Bonferroni).
    """

    statistic: np.ndarray
    p_value: np.ndarray
    flagged: np.ndarray


def studentized_test(
    standardized: np.ndarray,
    leverage: np.ndarray,
    used: np.ndarray,
    n_free: int,
    *,
    sigma_given: bool,
    alpha: float = OUTLIER_ALPHA,
) -> PoseTest:
    """Studentized residual test of every pose (module notes).

    Parameters
    ----------
    standardized : ndarray, shape (m, d)
        ``W_i e_i / sigma_ref`` against the fit to the poses in ``used``.
    leverage : ndarray, shape (m, d, d)
        ``B_i B_i^T`` of every pose (``W_i J_i G``, the fit's inverse information).
    used : ndarray of bool, shape (m,)
        Poses in the fit.
    n_free : int
        Free parameters of the fit.
    sigma_given : bool
        Whether ``sigma_ref`` is known (chi-square) or was estimated (F).
    alpha : float
        Family-wise level over all ``m`` poses.

    Returns
    -------
    PoseTest

    Examples
    --------
    >>> r = np.zeros((20, 2)); r[3] = [6.0, 0.0]
    >>> test = studentized_test(r, np.zeros((20, 2, 2)), np.ones(20, bool), 4, sigma_given=True)
    >>> np.flatnonzero(test.flagged).tolist(), round(float(test.statistic[3]), 6)
    ([3], 6.0)
    """
    m, dim = standardized.shape
    quad = np.maximum(_quadratic_forms(standardized, leverage, used), 0.0)
    nu = dim * int(np.count_nonzero(used)) - n_free
    if sigma_given:
        if dim == 2:
            p_value = np.exp(-quad / 2)  # the chi-square survival function for 2 dof
        else:
            p_value = chi2_sf(dim, quad)
        statistic = np.sqrt(quad)
    else:
        rss = float(np.sum(standardized[used] ** 2))  # in units of the estimated sigma
        # Leave-one-out scale for poses in the fit (d fewer equations), the fit's for others.
        dof_i = np.where(used, nu - dim, nu)
        rss_i = np.where(used, rss - quad, rss)
        with np.errstate(divide="ignore", invalid="ignore"):
            scale2 = np.where(dof_i > 0, rss_i / np.maximum(dof_i, 1), np.nan)
            f = np.where(scale2 > 0, quad / (dim * scale2), 0.0)
        valid = (dof_i > 0) & np.isfinite(scale2) & (scale2 > 0)
        p_value = np.where(valid, f_sf(dim, np.maximum(dof_i, 1), f), 1.0)
        statistic = np.where(valid, np.sqrt(dim * f), 0.0)
    flagged = p_value < alpha / max(m, 1)
    return PoseTest(statistic, p_value, flagged)


def _quadratic_forms(standardized: np.ndarray, leverage: np.ndarray, used: np.ndarray):
    """``r_i^T V_i^-1 r_i`` ``(m,)`` with ``V_i = I -+ B_i B_i^T`` (in the fit or left out).

    A pose that alone determines a direction (``V`` singular, leverage 1) has a
    residual of 0 and carries no test: its form is 0.
    """
    dim = standardized.shape[1]
    sign = np.where(used, -1.0, 1.0)[:, None, None]
    v = np.eye(dim) + sign * leverage
    if dim == 2:  # in closed form
        a, b, d = v[:, 0, 0], v[:, 0, 1], v[:, 1, 1]
        det = a * d - b * b
        x, y = standardized[:, 0], standardized[:, 1]
        with np.errstate(divide="ignore", invalid="ignore"):
            return np.where(det > 1e-12, (d * x * x - 2 * b * x * y + a * y * y) / det, 0.0)
    # V's eigenvalues lie in (0, 1] in the fit (I - B, B's in [0, 1]) and are at least 1
    # out of it, so a determinant above the threshold clears every one of them: those
    # rows are solved (LU), the few others decided by their eigenvalues.
    out = np.zeros(v.shape[0])
    clear = (np.linalg.det(v) > _SINGULAR) | ~used
    if clear.any():
        solved = np.linalg.solve(v[clear], standardized[clear][..., None])[..., 0]
        out[clear] = np.einsum("mi,mi->m", standardized[clear], solved)
    near = np.flatnonzero(~clear)
    if near.size:
        values, vectors = np.linalg.eigh(v[near])
        safe = values > _SINGULAR
        projected = np.einsum("mij,mi->mj", vectors, standardized[near])
        inverse = np.where(safe, 1.0 / np.where(safe, values, 1.0), 0.0)
        out[near] = np.where(np.all(safe, axis=1), np.sum(projected**2 * inverse, axis=1), 0.0)
    return out


#: An eigenvalue of a pose's ``V`` at or below this is 0: the pose alone determines a
#: direction, and carries no test (:func:`_quadratic_forms`).
_SINGULAR = 1e-12


# --------------------------------------------------------------------------- warnings

#: Above this p-value a model's effect lowers the residual no more than noise would.
NESTED_UNSEEN_P = 0.05


def outlier_warning(
    outliers: Sequence[Outlier],
    *,
    robust: bool,
    scatter: float | None = None,
    sigma: float | None = None,
    unit: str = "mm",
) -> ArmcalWarning:
    """``outlier``: the flagged poses, and what was done with them (or what to do); figures
    in the readings' ``unit`` (a camera's px).

    ``scatter`` (mm) is the scale they were judged against when the fit is
    inconsistent with the given ``sigma`` (:func:`~armcal.identification.robust.judge`).
    """
    shown = [
        f"row {o.row} (pose {o.pose}: residual {o.residual_mm:.3g} {o.unit}, "
        f"studentized {o.studentized:.3g})"
        for o in outliers[:5]
    ]
    more = f" and {len(outliers) - 5} more" if len(outliers) > 5 else ""
    what = "outlier" if len(outliers) == 1 else "outliers"
    if robust:
        then = "left out of the fit; check these measurements"
    else:
        then = f"{action('refit-robust')}, or check these measurements"
    against = ""
    if scatter is not None:
        given = "" if sigma is None else f" = {sigma:.3g} {unit}"
        against = (
            f", judged against the scatter of the other rows ({scatter:.3g} {unit}) since the "
            f"fit is inconsistent with sigma{given}"
        )
    return ArmcalWarning(
        "outlier",
        f"{len(outliers)} {what} at the {OUTLIER_ALPHA:g} family-wise level{against}: "
        f"{listing(shown)}{more}; {then}",
    )


def most_disagree(flagged: int, poses: int) -> bool:
    """Whether ``flagged`` poses are at least half of ``poses``: too many to be outliers
    (the model, a unit or sigma is wrong, and a robust fit cannot help)."""
    return 2 * flagged >= poses


def fixed_parameters(held: Sequence[str]) -> str:
    """``"the fixed parameter dl1"`` or ``"the fixed parameters dl3, dq3"``."""
    return f"the fixed parameter{'' if len(held) == 1 else 's'} {', '.join(held)}"


def inconsistent_fit_warning(
    fit: GoodnessOfFit,
    sigma: float,
    suggested: float,
    flagged: int,
    *,
    poses: int,
    held: Sequence[str] = (),
    freed: tuple[float, int] | None = None,
    unit: str = "mm",
    mirrored: tuple[str, float, int] | None = None,
    rows: str = "poses",
    disagreeing: int | None = None,
    scatter: float | None = None,
    robust: bool = False,
) -> ArmcalWarning:
    """``fit-inconsistent``: the chi-square test failed, and the likely causes in order.

    ``flagged`` of the ``poses`` data rows (which are ``rows``: :func:`row_noun`) fail
    the outlier test, and ``disagreeing`` (default ``flagged``) fail it against
    sigma; when those are at least half, they are no outliers and a robust fit
    cannot help, so the message says so instead of advising one -- unless the
    outliers were judged against the rows' own ``scatter`` (mm) instead, where
    ``flagged`` stand out of it (left out by a ``robust`` fit).
    ``held`` are the fixed parameters' names; ``freed`` is the chi-square and its
    degrees of freedom of the same fit with them free, given when freeing them
    explains the misfit: it is then the first cause.  ``mirrored`` is what mirrors
    the measured points, with the chi-square and dof of the fit with that undone:
    it is then the first cause.
    """
    causes = []
    if mirrored is not None:
        what, chi2, dof = mirrored
        causes.append(
            f"the measurements are mirrored: {what}; undone, chi2 = {chi2:.4g} on {dof} "
            "degrees of freedom; fix the instrument's export or its columns (x_mm, y_mm)"
        )
    if freed is not None:
        chi2, dof = freed
        one = len(held) == 1
        causes.append(
            f"{fixed_parameters(held)} {'is' if one else 'are'} not at nominal: with "
            f"{'it' if one else 'them'} free, chi2 = {chi2:.4g} on {dof} degrees of freedom; "
            f"free {'it' if one else 'them'} ({action('free-held')})"
        )
    disagreeing = flagged if disagreeing is None else disagreeing
    stand_out = ""
    if scatter is not None and flagged:
        done = "left out" if robust else action("try-robust")
        stand_out = (
            f"{flagged} of {poses} {rows} stand out of the rows' scatter, about "
            f"{scatter / sigma:.3g} times sigma ({done})"
        )
    if most_disagree(disagreeing, poses):
        shown = f"not outliers: {disagreeing} of {poses} {rows} disagree with the fit"
        causes.append(
            f"{shown}; {stand_out}" if stand_out else f"{shown}, so a robust fit cannot help"
        )
    elif scatter is not None:
        ratio = f"the rows scatter about {scatter / sigma:.3g} times sigma"
        causes.append(
            f"not outliers alone: {stand_out}" if stand_out else f"not outliers: {ratio}"
        )
    else:
        advice = action("try-robust")
        causes.append(f"outliers ({f'{flagged} flagged; ' if flagged else ''}{advice})")
    causes.append("a wrong unit (angles in radians, positions in metres)")
    model = "a model that misses an effect (base offset, a wrong robot file, compliance under load"
    if freed is None and held:
        model += f", a wrong fixed value of {', '.join(held)}"
    causes.append(model + ")")
    causes.append(f"or sigma too small (the residuals suggest about {suggested:.3g} {unit})")
    return ArmcalWarning(
        "fit-inconsistent",
        f"the fit is inconsistent with sigma = {sigma:.3g} {unit}: chi2 = {fit.chi2:.4g} on "
        f"{fit.dof} degrees of freedom (p = {fit.p_value:.2g}); likely causes, in order: "
        + "; ".join(causes),
    )


def too_good_warning(
    fit: GoodnessOfFit, sigma: float, *, repeated: int = 0, unit: str = "mm"
) -> ArmcalWarning:
    """``fit-too-good``: chi-square far below its degrees of freedom (module notes).

    The residuals suggest ``sigma sqrt(chi2 / dof)``; every std, proportional to
    sigma, is too large by the inverse ratio.  ``repeated`` rows repeat another
    exactly (:func:`~armcal.identification.experiment.repeated_rows`): they are then
    the first cause named.
    """
    chi2, dof = fit.chi2 or 0.0, fit.dof
    suggested = sigma * float(np.sqrt(chi2 / max(dof, 1)))
    ratio = f"{sigma / suggested:.3g} times" if suggested > 0 else "far"
    causes = []
    if repeated:
        causes.append(f"rows repeated ({repeated} repeat another exactly)")
    causes += [
        f"sigma too large (the residuals suggest about {suggested:.3g} {unit}; give the "
        "instrument's noise for these measurements)",
        "points computed rather than measured (noiseless virtual data)",
    ]
    return ArmcalWarning(
        "fit-too-good",
        f"the fit is better than sigma = {sigma:.3g} {unit} allows: chi2 = {chi2:.4g} on {dof} "
        f"degrees of freedom, as small by chance with probability {fit.p_below:.2g} (below "
        f"{FIT_ALPHA:g}); every std is {ratio} too large; likely causes, in order: "
        + "; ".join(causes),
    )


def row_noun(target: np.ndarray | None) -> str:
    """What a data row is: a pose, or with several targets one target's point of a pose."""
    return "poses" if target is None else "measurements"


def few_dof_warning(
    poses: int, dof: int, n_free: int, per_pose: int, rows: str = "poses"
) -> ArmcalWarning | None:
    """``few-dof`` below :data:`FEW_DOF` residual degrees of freedom: how many poses to add.

    ``poses`` counts data rows, which are ``rows`` (:func:`row_noun`); ``per_pose`` is
    the equations one more pose gives.
    """
    if dof >= FEW_DOF:
        return None
    more = -(-(FEW_DOF - dof) // per_pose)
    return ArmcalWarning(
        "few-dof",
        f"{poses} {rows} leave {dof} degrees of freedom for {n_free} parameters: too few to "
        f"judge the fit against sigma or to find outliers; measure at least {more} more "
        f"{'pose' if more == 1 else 'poses'}",
    )


def not_converged_warning(method: str, iterations: int, closed_form: bool) -> ArmcalWarning:
    """``not-converged``: the solver stopped at its iteration cap."""
    advice = action("try-closed-form") if closed_form else "check the data and the robot file"
    return ArmcalWarning(
        "not-converged", f"{method} did not converge in {iterations} iterations; {advice}"
    )


def nested_test(
    nested_whitened: np.ndarray, whitened: np.ndarray, extra: int, dof: int
) -> float | None:
    """The p-value of the nested-model F test: does an effect lower the residual beyond noise?

    With ``extra`` parameters of the effect and ``dof`` residual degrees of freedom
    of the full fit, ``F = ((RSS_nested - RSS) / extra) / (RSS / dof)`` follows
    F(extra, dof) when the effect is absent.  Both sums are of *whitened*
    residuals (``W_i e_i``), the quantity each weighted fit minimised: with
    per-row sigma or another noise model, unweighted sums would be dominated by
    the noisiest rows and say nothing about the fit.  None when there is nothing
    to test (no degrees of freedom, no extra parameter, or an exact fit).
    """
    rss, rss_nested = float(np.sum(whitened**2)), float(np.sum(nested_whitened**2))
    if dof <= 0 or extra == 0 or rss <= 0:
        return None
    f_value = max(rss_nested - rss, 0.0) / extra / (rss / dof)
    return float(f_sf(extra, dof, f_value))


def unseen_warning(
    effect: Effect,
    shown: str,
    nested_rms_mm: float,
    rms_mm: float,
    p_value: float | None,
) -> ArmcalWarning | None:
    """A ``{short}-unseen`` warning (``compliance-unseen``) above :data:`NESTED_UNSEEN_P`.

    A p-value above it means the data cannot tell the effect from noise (for
    joint compliance: loads too small, joints too stiff): its values are then
    undetermined, however finite.  ``shown`` lists them with their std.
    """
    if p_value is None or p_value <= NESTED_UNSEEN_P:
        return None
    return ArmcalWarning(
        f"{effect.short}-unseen",
        f"the data do not show the {effect.name}: it lowers the residual RMS per coordinate "
        "only from "
        f"{nested_rms_mm:.4g} to {rms_mm:.4g} mm, no more than noise would (F test p = "
        f"{p_value:.2g}), and its values are undetermined ({shown}); {effect_advice(effect)}",
    )


#: An effect's parameter that cannot be negative (:attr:`~armcal.models.Effect.positive`)
#: is warned of when it lies more than this many std below zero: by chance that
#: happens to 0.13 % of the estimates of a parameter whose true value is 0.
NEGATIVE_STD = 3.0


def negative_effect_warning(
    effect: Effect,
    names: Sequence[str],
    values: np.ndarray,
    std: np.ndarray,
    units: Sequence[str],
) -> ArmcalWarning | None:
    """A ``{short}-negative`` warning (``compliance-negative``) naming the effect's
    parameters identified more than :data:`NEGATIVE_STD` std below zero, where the effect
    says none can be negative; ``values`` and ``std`` in display units ``units``."""
    if not effect.positive:
        return None
    below = [
        f"{name} = {v:.3g} ± {s:.2g} {unit} ({-v / s:.1f} std below 0)"
        for name, v, s, unit in zip(names, values, std, units, strict=True)
        if s > 0 and v < -NEGATIVE_STD * s
    ]
    if not below:
        return None
    one = len(below) == 1
    return ArmcalWarning(
        f"{effect.short}-negative",
        f"the {effect.name} fitted {'a value' if one else 'values'} that cannot be: "
        f"{listing(below)}; {NEGATIVE_WORDS}; find the cause, or hold "
        f"{'it' if one else 'them'} at zero ({action('hold-terms')})",
    )
