"""The robust fit: Huber's M-estimator, then the outlier test, leaving out and refitting.

Why Huber: for the planar arm the model is linear in the link phasors, so
Huber's objective is convex there -- one optimum, reached from the least-squares
fit whatever the outliers -- and a pose's influence is bounded by its weight
``min(1, k sigma / |r_i|)``, so gross outliers barely move the fit the test
then judges; clean poses keep weight 1 (``k`` is the 95 % point of a clean
pose's radial residual, :func:`huber_constant`).  The final estimate is
ordinary (weighted) least squares on the poses kept, so its covariance is the
usual one.
"""

from __future__ import annotations

import math

import numpy as np

from ..errors import ArmcalWarning
from ..numerics import point_norms
from .judgement import fixed_parameters, most_disagree, row_noun
from .problem import Fit, Problem

__all__ = [
    "HUBER_K",
    "MISFIT_ROUNDS",
    "MISFIT_SHARE",
    "huber_constant",
    "misfit_warning",
    "robust_fit",
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
    from scipy import special  # on use, and not scipy.stats (3x slower to import)

    return float(np.sqrt(special.chdtri(dim, 0.05)))


#: Huber's constant for a point in the plane (:func:`huber_constant` of 2).
HUBER_K = huber_constant(2)

#: A model misfit, not outliers: when Huber leaves this share of the poses below full
#: weight for :data:`MISFIT_ROUNDS` reweightings in a row, the reweighting stops.  Its
#: end would still leave most poses out of the core, so the fit falls back to every
#: pose (``model-misfit``) whatever the last weights; iterating them to 1e-9 on a model
#: that fits nothing took 50 fits (435 s at 10^5 rows of a sagging arm fitted rigid).
MISFIT_SHARE = 0.99
MISFIT_ROUNDS = 5


def _median_chi2(dim: int) -> float:
    """The median of chi-square with ``dim`` dof: ``2 ln 2`` for 2."""
    if dim == 2:
        return 2 * math.log(2)
    from scipy import special  # on use, and not scipy.stats (3x slower to import)

    return float(special.chdtri(dim, 0.5))


def misfit_warning(problem: Problem, disagreeing: int) -> ArmcalWarning:
    """``model-misfit``: most poses disagree with any fit, so none is an outlier."""
    held = problem.model.fixed
    first = f"{fixed_parameters(held)}, " if held else ""
    return ArmcalWarning(
        "model-misfit",
        f"{disagreeing} of {problem.m} {row_noun(problem.conditions.target)} disagree with the "
        "fit: that is a model problem, "
        f"not outliers, so the robust fit leaves none out; check, in order: {first}a unit, the "
        "robot file (base offset, link lengths, targets), compliance under load",
    )


def robust_fit(
    problem: Problem, sigma: float | None, fit: Fit
) -> tuple[Fit, np.ndarray, np.ndarray, ArmcalWarning | None]:
    """Huber IRLS from the least-squares ``fit`` to every pose, then test, leave out, refit.

    Returns the final fit, the poses in it, the poses flagged as outliers, and a
    warning when nothing was left out though the test flagged poses:
    ``outliers-kept`` when leaving them out would lose identifiability or every
    residual degree of freedom, ``model-misfit`` when at least half of the
    poses disagree with the fit -- then nothing is an outlier: the model, the
    units or sigma are wrong, and a fit to the few poses left would be a fit to
    a handful of points, not a calibration.  ``sigma`` is the reference noise
    when given, None when it is estimated.
    """
    m = problem.m
    dim = problem.model.point_dim
    n_free = problem.model.n_free
    huber = huber_constant(dim)
    everyone = np.ones(m, dtype=bool)
    weights = np.ones(m)
    misfit_rounds = 0
    for _ in range(100):
        distance = point_norms(fit.whitened)
        if sigma is None:  # a robust scale: the median squared distance of a clean point
            scale = float(np.sqrt(np.median(distance**2) / _median_chi2(dim)))
            scale = max(scale, np.finfo(float).tiny)
        else:
            scale = sigma
        new = np.minimum(1.0, huber * scale / np.maximum(distance, np.finfo(float).tiny))
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
    fit = problem.fit(used, start=fit.params)

    def everything(flagged: np.ndarray, warning: ArmcalWarning) -> tuple:
        return problem.fit(everyone, start=fit.params), everyone, flagged, warning

    for _ in range(20):
        dof = dim * int(np.count_nonzero(used)) - n_free
        scale = sigma if sigma is not None else fit.scale(max(dof, 1))
        test = fit.test(scale, given=sigma is not None)
        keep = ~test.flagged
        if most_disagree(int(np.count_nonzero(~keep)), m):
            return everything(~everyone, misfit_warning(problem, int(np.count_nonzero(~keep))))
        if np.array_equal(keep, used):
            return fit, used, ~used, None
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
    return fit, used, ~used, None
