"""Is a fit consistent with its noise?  Goodness of fit and the studentized outlier test.

Both work on *standardized* residuals ``r_i = W_i e_i / sigma_ref`` (the noise
model's whitening, :mod:`armcal.noise`): under the model they are independent
``N(0, I_2)`` per pose, up to the fit's own leverage.

**Goodness of fit.**  With ``sigma`` given, ``chi2 = sum_i e_i^T Sigma_i^-1 e_i``
over the poses in the fit follows a chi-square law with ``2m - p_f`` degrees
of freedom; a p-value below :data:`FIT_ALPHA` says the data and the model (or
``sigma``) disagree.

**Outliers.**  A pose is an outlier when its residual is larger than the fit
and the noise can explain.  With ``B_i = W_i J_i G`` (``G G^T = (J_w^T J_w)^-1``
over the poses in the fit) the residual of a pose in the fit has covariance
``sigma^2 (I - B_i B_i^T)`` and the prediction error of a pose left out
``sigma^2 (I + B_i B_i^T)``, so ``t_i^2 = r_i^T V_i^-1 r_i`` is

* ``chi2(2)`` when ``sigma`` is given;
* with ``sigma`` estimated, ``2 F(2, nu - 2)`` for a pose in the fit with
  ``sigma`` re-estimated without it (the externally studentized residual, an
  exact law under normal noise), and ``2 F(2, nu)`` for a pose left out.

Every pose is tested, so the level is corrected for multiple testing
(Bonferroni): a pose is flagged when its p-value is below
``OUTLIER_ALPHA / m``.  On clean data the chance that *any* pose is flagged is
then at most ``OUTLIER_ALPHA``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = [
    "FEW_DOF",
    "FIT_ALPHA",
    "OUTLIER_ALPHA",
    "GoodnessOfFit",
    "Outlier",
    "PoseTest",
    "goodness_of_fit",
    "studentized_test",
]

#: A fit whose chi-square p-value is below this is inconsistent with sigma.
FIT_ALPHA = 1e-3
#: Family-wise false-alarm rate of the outlier test over all poses of a fit.
OUTLIER_ALPHA = 1e-3
#: Fewer residual degrees of freedom than this cannot judge a fit.
FEW_DOF = 4


@dataclass(frozen=True)
class GoodnessOfFit:
    """The chi-square test of a fit against its noise model.

    Attributes
    ----------
    chi2 : float or None
        ``sum_i e_i^T Sigma_i^-1 e_i`` over the poses in the fit; None when
        ``sigma`` was estimated from the same residuals (then it equals ``dof``
        by construction and tests nothing).
    dof : int
        ``2 m - p_f``: measured coordinates minus free parameters.
    p_value : float or None
        ``P(chi2_dof >= chi2)``; None when ``sigma`` was estimated or ``dof <= 0``.
    """

    chi2: float | None
    dof: int
    p_value: float | None

    @property
    def consistent(self) -> bool:
        """False when the p-value is below :data:`FIT_ALPHA`."""
        return self.p_value is None or self.p_value >= FIT_ALPHA

    def to_dict(self) -> dict[str, float | int | None]:
        """JSON form ``{chi2, dof, p_value}``."""
        return {"chi2": self.chi2, "dof": self.dof, "p_value": self.p_value}


def goodness_of_fit(standardized: np.ndarray, dof: int, *, sigma_given: bool) -> GoodnessOfFit:
    """Chi-square test of standardized residuals ``(m_used, 2)`` on ``dof`` degrees of freedom.

    Examples
    --------
    >>> fit = goodness_of_fit(np.ones((10, 2)), 16, sigma_given=True)
    >>> fit.chi2, fit.dof, round(fit.p_value, 4)
    (20.0, 16, 0.2202)
    """
    if not sigma_given:
        return GoodnessOfFit(None, int(dof), None)
    from scipy import stats  # imported on use: `import armcal` stays light

    chi2 = float(np.sum(standardized**2))
    p_value = float(stats.chi2.sf(chi2, dof)) if dof > 0 else None
    return GoodnessOfFit(chi2, int(dof), p_value)


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
    """

    index: int
    row: int
    pose: str
    target: str | None
    residual_mm: float
    studentized: float
    p_value: float
    removed: bool

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
    standardized : ndarray, shape (m, 2)
        ``W_i e_i / sigma_ref`` against the fit to the poses in ``used``.
    leverage : ndarray, shape (m, 2, 2)
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
    m = standardized.shape[0]
    sign = np.where(used, -1.0, 1.0)[:, None, None]
    v = np.eye(2) + sign * leverage
    a, b, d = v[:, 0, 0], v[:, 0, 1], v[:, 1, 1]
    det = a * d - b * b
    x, y = standardized[:, 0], standardized[:, 1]
    with np.errstate(divide="ignore", invalid="ignore"):
        # r^T V^-1 r in closed form; a pose that alone determines a direction (V
        # singular, leverage 1) has a residual of 0 and carries no test.
        quad = np.where(det > 1e-12, (d * x * x - 2 * b * x * y + a * y * y) / det, 0.0)
    quad = np.maximum(quad, 0.0)
    nu = 2 * int(np.count_nonzero(used)) - n_free
    if sigma_given:
        p_value = np.exp(-quad / 2)  # the chi-square survival function for 2 dof
        statistic = np.sqrt(quad)
    else:
        from scipy import stats  # imported on use: `import armcal` stays light

        rss = float(np.sum(standardized[used] ** 2))  # in units of the estimated sigma
        # Leave-one-out scale for poses in the fit (2 fewer equations), the fit's for others.
        dof_i = np.where(used, nu - 2, nu)
        rss_i = np.where(used, rss - quad, rss)
        with np.errstate(divide="ignore", invalid="ignore"):
            scale2 = np.where(dof_i > 0, rss_i / np.maximum(dof_i, 1), np.nan)
            f = np.where(scale2 > 0, quad / (2 * scale2), 0.0)
        valid = (dof_i > 0) & np.isfinite(scale2) & (scale2 > 0)
        p_value = np.where(valid, stats.f.sf(f, 2, np.maximum(dof_i, 1)), 1.0)
        statistic = np.where(valid, np.sqrt(2 * f), 0.0)
    flagged = p_value < alpha / max(m, 1)
    return PoseTest(statistic, p_value, flagged)
