"""The robust fit: Huber's M-estimator, then the outlier test, leaving out and refitting.

Why Huber: for the planar arm the model is linear in the link phasors, so
Huber's objective is convex there -- one optimum, reached from the least-squares
fit whatever the outliers -- and a pose's influence is bounded by its weight
``min(1, k sigma / |r_i|)``, so gross outliers barely move the fit the test
then judges; clean poses keep weight 1 (``k`` is the 95 % point of a clean
pose's radial residual, :func:`huber_constant`).  The final estimate is
ordinary (weighted) least squares on the poses kept, so its covariance is the
usual one.

**Too many to be outliers.**  A blunder -- a broken beam, a knocked reflector, a
mistyped row -- is an accident of one row.  When the test would leave out more
than :data:`OUTLIER_SHARE` of the rows and more than :data:`OUTLIER_FEW` of them,
the rows flagged are a pattern the model misses (compliance, a wrong fixed
value, a unit, the noise model), not accidents: the fit keeps them all and
says so (``model-misfit``); dropping them would fit the model to the rows it
happens to explain.  Even at a blunder rate of 1 in 100 rows, more than
``max(3, 0.05 m)`` blunders in ``m`` rows happen with probability below 1 %
(binomial; at most 0.83 %, at 79 rows).

**Outliers when the fit is inconsistent with sigma.**  With sigma given, a fit
whose rows, outliers left out, still fail the chi-square test (a missing
effect, or sigma too small) makes every row "disagree" with sigma, and the
test against sigma can tell no blunder from the rest.  :func:`judge` then
judges the rows against their own scatter instead: the test of an estimated
sigma -- every row against the root-mean-square of the others (externally
studentized) -- on the least-squares fit to every row, leaving the flagged out
and refitting until the set is stable.  Not from Huber's core: a missing
effect gives the residuals heavier tails than normal noise, and the core (the
rows Huber keeps at full weight) would leave the tails out and shrink the
scale until the tails themselves failed the test (at 10^4 rows of a six-axis
arm sagging 4 sigma, more than 5 % of them); against the scatter of every
other row, a 5 mm blunder stands 60 times out and the sag's tail below the
test's bound.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..distributions import chi2_isf
from ..errors import ArmcalWarning
from ..numerics import point_norms
from .judgement import (
    PoseTest,
    fixed_parameters,
    goodness_of_fit,
    most_disagree,
    row_noun,
)
from .problem import Fit, Problem

__all__ = [
    "HUBER_K",
    "MISFIT_ROUNDS",
    "MISFIT_SHARE",
    "OUTLIER_FEW",
    "OUTLIER_SHARE",
    "Judgement",
    "huber_constant",
    "judge",
    "misfit_warning",
    "robust_fit",
    "too_many",
]


def huber_constant(dim: int) -> float:
    """Huber's tuning constant for the radial residual of a point with ``dim`` coordinates.

    A clean point's standardized residual is below it with probability 0.95
    (chi-square, ``dim`` dof), so clean data keep weight 1 almost everywhere and
    the fit stays efficient.  In the plane, ``sqrt(-2 ln 0.05)``: the chi-square
    law with 2 dof has survival function ``exp(-x / 2)``.
    """
    if dim == 2:
        return float(np.sqrt(-2.0 * np.log(0.05)))
    return float(np.sqrt(chi2_isf(dim, 0.05)))


#: Huber's constant for a point in the plane (:func:`huber_constant` of 2).
HUBER_K = huber_constant(2)

#: A model misfit, not outliers: when Huber leaves this share of the poses below full
#: weight for :data:`MISFIT_ROUNDS` reweightings in a row, the reweighting stops.  Its
#: end would still leave most poses out of the core, so the fit falls back to every
#: pose (``model-misfit``) whatever the last weights; iterating them to 1e-9 on a model
#: that fits nothing took 50 fits (435 s at 10^5 rows of a sagging arm fitted rigid).
MISFIT_SHARE = 0.99
MISFIT_ROUNDS = 5

#: More than this share of the rows (and more than :data:`OUTLIER_FEW`) flagged is a
#: model problem, not outliers (module notes).
OUTLIER_SHARE = 0.05
#: So many flagged rows are outliers however few the rows: a small campaign's blunders.
OUTLIER_FEW = 3


def too_many(flagged: int, rows: int) -> bool:
    """Whether ``flagged`` of ``rows`` are too many to be outliers (module notes).

    Examples
    --------
    >>> too_many(3, 12), too_many(4, 12), too_many(5, 100), too_many(6, 100)
    (False, True, False, True)
    """
    return flagged > max(OUTLIER_FEW, OUTLIER_SHARE * rows)


def _median_chi2(dim: int) -> float:
    """The median of chi-square with ``dim`` dof: ``2 ln 2`` for 2."""
    if dim == 2:
        return 2 * math.log(2)
    return float(chi2_isf(dim, 0.5))


def misfit_warning(problem: Problem, disagreeing: int, *, left_out: int = 0) -> ArmcalWarning:
    """``model-misfit``: too many rows disagree with the fit for any to be outliers.

    ``left_out`` rows were still left out as outliers of the rows' own scatter
    (:func:`judge`, when the rows disagree with sigma).
    """
    held = problem.model.fixed
    first = f"{fixed_parameters(held)}, " if held else ""
    share = 100.0 * disagreeing / max(problem.m, 1)
    if most_disagree(disagreeing, problem.m):
        why = ""
    else:
        why = (
            f" (more than {100 * OUTLIER_SHARE:g} % of the rows and more than {OUTLIER_FEW}: "
            "blunders are accidents of single rows)"
        )
    if left_out:
        done = f"only the {left_out} that stand far off the scatter of the others are outliers"
    else:
        done = "the robust fit leaves none out and none should be dropped"
    return ArmcalWarning(
        "model-misfit",
        f"{disagreeing} of {problem.m} {row_noun(problem.conditions.target)} disagree with "
        f"the fit ({share:.3g} %): that is a model problem, not outliers{why}, "
        f"so {done}; check, in order: {first}a unit, the robot file (base offset, link "
        "lengths, targets), compliance under load, the noise model (sigma per axis)",
    )


def robust_fit(
    problem: Problem, sigma: float | None, fit: Fit, *, huber: bool = True
) -> tuple[Fit, np.ndarray, np.ndarray, ArmcalWarning | None]:
    """Huber IRLS from the least-squares ``fit`` to every pose, then test, leave out, refit.

    Without ``huber`` the test starts from ``fit`` itself on every pose (the rows'
    own scatter, :func:`judge`).

    Returns the final fit, the poses in it, the poses flagged as outliers, and a
    warning when nothing was left out though the test flagged poses:
    ``outliers-kept`` when leaving them out would lose identifiability or every
    residual degree of freedom, ``model-misfit`` when too many poses disagree
    with the fit (:func:`too_many`) -- then nothing is an outlier: the model, the
    units or sigma are wrong, and a fit to the poses left would fit the model to
    the rows it happens to explain, not calibrate it.  ``sigma`` is the reference noise
    when given, None when it is estimated.
    """
    return _robust(problem, sigma, fit, huber=huber)[:4]


#: What :func:`_robust` returns: :func:`robust_fit`'s four, and how many rows the test
#: flagged when they were too many (0 otherwise).
_Robust = tuple[Fit, np.ndarray, np.ndarray, ArmcalWarning | None, int]


def _robust(problem: Problem, sigma: float | None, fit: Fit, *, huber: bool) -> _Robust:
    """:func:`robust_fit`, and the count of a misfit."""
    m = problem.m
    dim = problem.model.point_dim
    everyone = np.ones(m, dtype=bool)
    if not huber:
        return _tested(problem, sigma, fit, everyone)
    constant = huber_constant(dim)
    weights = np.ones(m)
    misfit_rounds = 0
    for _ in range(100):
        distance = point_norms(fit.whitened)
        if sigma is None:  # a robust scale: the median squared distance of a clean point
            scale = float(np.sqrt(np.median(distance**2) / _median_chi2(dim)))
            scale = max(scale, np.finfo(float).tiny)
        else:
            scale = sigma
        new = np.minimum(1.0, constant * scale / np.maximum(distance, np.finfo(float).tiny))
        fit = problem.fit(everyone, weights=new, start=fit.params)
        if np.max(np.abs(new - weights)) < 1e-9:
            break
        weights = new
        misfit_rounds = misfit_rounds + 1 if np.mean(new < 1.0) >= MISFIT_SHARE else 0
        if misfit_rounds >= MISFIT_ROUNDS:
            break
    # The core: poses Huber left at full weight, if they identify the model.
    used = weights >= 1.0
    if not problem.identifiable(used) or most_disagree(m - int(np.count_nonzero(used)), m):
        used = everyone
    return _tested(problem, sigma, problem.fit(used, start=fit.params), used)


def _tested(problem: Problem, sigma: float | None, fit: Fit, used: np.ndarray) -> _Robust:
    """From ``fit`` to the rows ``used``: test every row, leave the flagged out, refit,
    until the set is stable (:func:`robust_fit`)."""
    m = problem.m
    dim = problem.model.point_dim
    n_free = problem.model.n_free
    everyone = np.ones(m, dtype=bool)

    def everything(flagged: np.ndarray, warning: ArmcalWarning, count: int = 0) -> _Robust:
        return problem.fit(everyone, start=fit.params), everyone, flagged, warning, count

    for _ in range(20):
        dof = dim * int(np.count_nonzero(used)) - n_free
        scale = sigma if sigma is not None else fit.scale(max(dof, 1))
        test = fit.test(scale, given=sigma is not None)
        keep = ~test.flagged
        count = int(np.count_nonzero(~keep))
        # Too many on the way (at least half: a fit to the rest would fit a handful), or
        # where the set settles (a round may flag more than it finally leaves out).
        settled = np.array_equal(keep, used)
        if most_disagree(count, m) or (settled and too_many(count, m)):
            return everything(~everyone, misfit_warning(problem, count), count)
        if settled:
            return fit, used, ~used, None, 0
        if not problem.identifiable(keep) or dim * int(np.count_nonzero(keep)) <= n_free:
            warning = ArmcalWarning(
                "outliers-kept",
                f"leaving out the {int(np.count_nonzero(~keep))} flagged poses would leave too "
                "few poses to identify every parameter and judge the fit, so they stay in the "
                "fit; measure more poses",
            )
            return everything(~keep, warning)
        used = keep
        fit = problem.fit(used, start=fit.params)
    count = int(np.count_nonzero(~used))
    if too_many(count, m):
        return everything(~everyone, misfit_warning(problem, count), count)
    return fit, used, ~used, None, 0


@dataclass(frozen=True, eq=False)
class Judgement:
    """The outliers of a fit, and the fit without them (:func:`judge`).

    Attributes
    ----------
    fit : Fit
        The fit to the rows kept (every row when none is left out).
    used : ndarray of bool, shape (m,)
        The rows kept.
    flagged : ndarray of bool, shape (m,)
        The rows flagged as outliers.
    test : PoseTest
        The studentized test that flagged them, against ``fit``.
    scale : float
        What the test judged against (mm of the reference noise): sigma, or the
        scatter of the rows kept when sigma was estimated or the rows disagree with it.
    scatter : bool
        Whether the rows were judged against their own scatter although sigma was given
        (the fit is inconsistent with sigma beyond its outliers).
    disagreeing : int
        The rows the test against sigma flags (sigma given), else those of ``test``:
        at least half means the model or sigma is wrong everywhere.
    warning : ArmcalWarning or None
        ``outliers-kept`` or ``model-misfit`` (:func:`robust_fit`) to show, when the fit
        left none out though the test flagged some (:func:`judge`).
    """

    fit: Fit
    used: np.ndarray
    flagged: np.ndarray
    test: PoseTest
    scale: float
    scatter: bool
    disagreeing: int
    warning: ArmcalWarning | None


def _judged(problem: Problem, sigma: float | None, fit: Fit, *, huber: bool = True) -> tuple:
    """:func:`robust_fit` against ``sigma`` (None: the rows' scatter), its test, the scale,
    and the count of a misfit."""
    found, used, flagged, warning, count = _robust(problem, sigma, fit, huber=huber)
    dof = problem.model.point_dim * int(np.count_nonzero(used)) - problem.model.n_free
    scale = sigma if sigma is not None else found.scale(max(dof, 1))
    test = found.test(scale, given=sigma is not None)
    return found, used, flagged, warning, test, scale, dof, count


def judge(problem: Problem, sigma: float | None, fit: Fit, *, robust: bool) -> Judgement:
    """The outliers of the least-squares ``fit``, found robustly (module notes).

    Against ``sigma`` when given (None: sigma estimated), from Huber's fit.  When the
    rows kept still fail the chi-square test against the given sigma, or too many rows
    fail the test for outliers (:func:`too_many`), against the scatter of every other
    row instead, so that a blunder far off the others is found whatever the misfit.
    The warning is the one to show for a ``robust`` fit or not: without it only a
    misfit is news, and a misfit against a given sigma the ``fit-inconsistent``
    warning says.
    """
    found, used, flagged, warning, test, scale, dof, count = _judged(problem, sigma, fit)
    disagreeing = int(np.count_nonzero(test.flagged))
    switched = count > 0
    if sigma is not None and not switched:
        kept = goodness_of_fit(found.whitened[used] / sigma, dof, sigma_given=True)
        switched = kept.too_large
    if switched:
        first = warning
        found, used, flagged, warning, test, scale, _, _ = _judged(problem, None, fit, huber=False)
        misfit = first is not None and first.code == "model-misfit"
        if warning is None and misfit and (robust or sigma is None):
            # Too many rows disagreed: still a model problem, said with what the judgement
            # against the scatter left out.
            warning = misfit_warning(
                problem, max(count, disagreeing), left_out=int(np.count_nonzero(~used))
            )
    if not robust and (warning is None or warning.code != "model-misfit"):
        warning = None
    scatter = switched and sigma is not None
    return Judgement(found, used, flagged, test, scale, scatter, disagreeing, warning)
