"""Identify a model from measured poses and judge the fit: :func:`identify`.

The steps, for every family of arm (:class:`~armcal.models.interface.FitModel`):

1. check that the poses identify every free parameter (the model's own rank
   analysis, which names what they cannot separate);
2. fit by least squares (:mod:`~armcal.identification.solvers`), or robustly
   (:mod:`~armcal.identification.robust`);
3. judge the fit (:mod:`~armcal.identification.judgement`): sigma given or
   estimated, the chi-square test, the outlier test, conditioning, convergence,
   and for a model with an effect (joint compliance) whether the data show it;
4. the covariance ``sigma^2 (J_w^T J_w)^-1`` at the solution (paper eq. 16),
   with ``sigma`` given by the user or estimated as ``s^2 = RSS / (d m - p)``.

**Weighted models.**  With a noise model (:mod:`armcal.noise`) every pose's rows
and residual are whitened by ``W_i`` (``W_i^T W_i = sigma_ref^2 Sigma_i^-1``),
which turns weighted least squares into ordinary least squares; the
covariance is then the generalized-least-squares one over the free parameters.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from ..errors import ArmcalError, ArmcalWarning, action
from ..models import Conditions, FitModel, Loads, equations_per_pose
from ..models.information import display_std
from ..models.wording import ill_conditioned_warning
from ..noise import instrument_override, per_row_sigma
from ..numerics import point_norms, rms
from .diagnosis import coupled_joints, far_off, swapped_targets
from .experiment import (
    coverage,
    plan_degenerate_warning,
    refuse_registration_only,
    repeated_rows,
    repeated_rows_warning,
)
from .judgement import (
    GoodnessOfFit,
    Outlier,
    PoseTest,
    few_dof_warning,
    goodness_of_fit,
    inconsistent_fit_warning,
    most_disagree,
    negative_effect_warning,
    nested_test,
    not_converged_warning,
    outlier_warning,
    row_noun,
    too_good_warning,
    unseen_warning,
)
from .problem import Fit, Problem, reference_sigma, sigma_unit
from .registration import Movement, instrument_moved, register_nominal
from .result import Calibration, NestedFit
from .robust import Judgement, judge
from .solvers import resolve_method

__all__ = [
    "EarlyCause",
    "Verdict",
    "check_residual_freedom",
    "checked_rows",
    "covariance_of",
    "early_diagnosis",
    "experiment_warnings",
    "identify",
    "judged_fit",
    "least_squares_fit",
    "moved_warning",
    "nested_verdict",
    "outlier_list",
    "verdict_warnings",
]


#: How many times a fit with the fixed parameters freed must lower chi-square for
#: the fixed values to be named as the cause of a misfit: the planar closed form
#: and every fit here are exact least squares, so freeing k parameters lowers
#: chi-square by about k on a consistent model; a 10-fold drop of a chi-square that
#: already failed the test is no chance.
FREED_IMPROVEMENT = 10.0


def _refit_chi2(
    problem: Problem, model: FitModel, used: np.ndarray, points: np.ndarray, method: str
) -> float:
    """Chi-square (in the problem's whitened units) of ``model`` fitted to ``points``, the
    measurements of the poses ``used``."""
    refit = Problem(model, problem.rows(used), points, method, problem.tol, problem.max_iter)
    return float(np.sum(refit.fit(np.ones(len(points), dtype=bool)).whitened ** 2))


def _freed_fit(
    problem: Problem, used: np.ndarray, sigma: float, chi2: float
) -> tuple[float, int] | None:
    """Chi-square and dof of the fit with the fixed parameters free, if it explains the misfit.

    None when the model has none fixed, when the poses ``used`` cannot identify
    them, or when freeing them lowers chi-square less than
    :data:`FREED_IMPROVEMENT` times.
    """
    model = problem.model
    if not model.fixed:
        return None
    freed = model.with_fixed(())
    if not freed.identifiability(problem.rows(used))[0].identifiable:
        return None
    points = problem.points[used]
    freed_chi2 = _refit_chi2(problem, freed, used, points, resolve_method(freed, "auto"))
    freed_chi2 /= sigma**2
    if freed_chi2 * FREED_IMPROVEMENT > chi2:
        return None
    return freed_chi2, model.point_dim * len(points) - freed.n_free


#: The mirror images of measured points an instrument's set-up commonly produces,
#: as (what happened, the point columns that undo it, their signs): x and y columns
#: swapped, and the y axis flipped (a camera's image y points down).  In a frame
#: the fit registers (a rotation), the two are the same mirror.
MIRRORS = (
    ("x and y are swapped", (1, 0), (1.0, 1.0)),
    ("the y axis is flipped (a camera's image y points down)", (0, 1), (1.0, -1.0)),
)


#: How far from the noise a fit to mirrored points may stay (chi-square over its degrees
#: of freedom) for the mirror to be its cause: a wrong joint map's fit, mirrored, still
#: misses by a billion (chi-square 1e10 on 150 dof), a mirrored export's comes back to
#: the noise (1 on average), and what the model lacks besides may leave a few times more.
MIRROR_FIT = 100.0


def _mirrored_fit(
    problem: Problem, used: np.ndarray, sigma: float, chi2: float
) -> tuple[str, float, int] | None:
    """What mirrors the points, with chi-square and dof of the fit to them mirrored back.

    Tried when most poses disagree: a mirrored frame moves every point.  None
    unless undoing a mirror of :data:`MIRRORS` lowers chi-square
    :data:`FREED_IMPROVEMENT` times and leaves a fit that is not itself far off (chi-square
    below :data:`MIRROR_FIT` times its degrees of freedom: a mirror explains a misfit
    only if undoing it leaves a fit near the noise); the best one is named (both, when
    the fit's registration makes them the same, to within a factor 2).
    """
    model = problem.model
    points = problem.points[used]
    if points.shape[-1] < 2:  # one number a row (a plane's, a distance's): no mirror
        return None
    found = []
    for what, order, signs in MIRRORS:
        mirrored = points.copy()
        mirrored[:, :2] = points[:, order] * np.asarray(signs)
        refit = _refit_chi2(problem, model, used, mirrored, problem.method)
        found.append((refit / sigma**2, what))
    best, what = min(found)
    dof = model.point_dim * len(points) - model.n_free
    if best * FREED_IMPROVEMENT > chi2 or best > MIRROR_FIT * max(dof, 1):
        return None
    if all(c <= 2 * best for c, _ in found):
        what = "x and y are swapped, or one axis is flipped (a camera's image y points down)"
    return what, best, dof


def _mirror_suspect(
    problem: Problem, fit: Fit, sigma: float
) -> tuple[str | None, tuple[str, float, int] | None]:
    """What to say of a fit far off whose points, mirrored back, fit far better (the
    mirror of :func:`_mirrored_fit`): the cause named when its estimate breaks the fit,
    and :func:`_mirrored_fit`'s finding on every row (kept: the fit's verdict reuses it)."""
    used = np.ones(problem.m, dtype=bool)
    chi2 = float(np.sum(fit.whitened**2)) / sigma**2
    found = _mirrored_fit(problem, used, sigma, chi2)
    if found is None:
        return None, None
    what, mirrored_chi2, _ = found
    text = (
        f"the measurements look mirrored: {what} (undone, the fit improves "
        f"{chi2 / max(mirrored_chi2, 1e-300):.3g}-fold); fix the instrument's export or the "
        "columns"
    )
    return text, found


def identify(
    model: FitModel,
    q: ArrayLike,
    points: ArrayLike,
    *,
    method: str = "auto",
    sigma: float | None = None,
    pose_labels: Sequence[str] | None = None,
    rows: Sequence[int] | None = None,
    row_sigma: ArrayLike | None = None,
    robust: bool = False,
    tol: float = 1e-12,
    max_iter: int = 50,
    target: ArrayLike | None = None,
    loads: Loads | None = None,
    conditions: Conditions | None = None,
) -> Calibration:
    """Identify the parameters of ``model`` from measured poses, and judge the fit.

    Parameters
    ----------
    model : FitModel
        The nominal model (a :class:`~armcal.models.planar.arm.PlanarArm`, a
        :class:`~armcal.models.spatial.arm.SpatialArm` as loaded, either with joint
        compliance), with its noise model and fixed parameters; it is prepared for
        these rows (:meth:`~armcal.models.interface.FitModel.prepared`: a spatial
        arm's base pose and targets placed from the points, and what the rows cannot
        separate held).
    q : ndarray, shape (m, n)
        Commanded joint angles in rad.
    points : ndarray, shape (m, d)
        Measured points in mm, in the instrument frame (``d = 2`` in the plane, 3 for
        a spatial arm), one per row of ``q``.
    method : {"auto", "closed-form", "gauss-newton"}
        ``"auto"`` is the closed form where the model has one (exact, see
        :mod:`~armcal.models.planar.closed_form`), else Gauss-Newton
        (:func:`~armcal.identification.solvers.resolve_method`).
    sigma : float, optional
        Instrument noise (1 std, mm), replacing the noise model's instrument
        part (encoder noise stays; :func:`armcal.noise.instrument_override`) and
        any per-row sigma (``row_sigma``, or that of ``conditions``), which is then
        not used: the one rule of :func:`armcal.noise.per_row_sigma`, as the
        command line's ``--sigma``.  Without it and without a noise model or
        ``row_sigma``, sigma is estimated from the residuals, which needs
        ``d m > p_f``.
    pose_labels : sequence of str, optional
        Labels of the poses for reports; ``"1".."m"`` by default.
    rows : sequence of int, optional
        1-based data rows of the poses in their file, for reports; ``1..m`` by default.
    row_sigma : ndarray, shape (m,), optional
        Per-row instrument noise (mm), for instruments that report each point's
        uncertainty; replaces the instrument covariance row by row (unless
        ``sigma`` is given).
    robust : bool
        Fit with Huber's M-estimator from the least-squares fit, flag outliers
        by the studentized test (:mod:`~armcal.identification.judgement`), leave
        them out and refit until the set is stable.
    tol, max_iter
        Gauss-Newton step tolerance (relative to the reach) and iteration cap.
    target : ndarray of int or sequence of str, shape (m,), optional
        Every row's target, for a model with several: its label (``"A"``) or its
        index into the model's targets.  Each row is one target's point of a pose;
        ``model.plan_conditions(q)`` gives the rows of every target of every pose.
    loads : Loads, optional
        Every pose's payload and tip force (a model of joint compliance; default:
        the robot file's payload).
    conditions : Conditions, optional
        The rows' conditions, already made by ``model.conditions`` from these
        ``q``, ``target``, ``loads`` and ``row_sigma`` (whose per-row sigma a
        given ``sigma`` replaces): the factorizations
        memoized on them are shared, not computed again (3-D data have fitted
        both sides of their plane on them, :func:`armcal.instrument.identify_3d`).

    Returns
    -------
    Calibration

    Raises
    ------
    NotIdentifiableError
        If the poses cannot identify every free parameter (the rank policy of
        :mod:`armcal.numerics`); the message names the unseen combinations.
    ArmcalError
        If ``sigma`` must be estimated but ``d m = p_f`` leaves no residual freedom.

    Notes
    -----
    The steps, each a function of this module: the rows checked
    (:func:`checked_rows`), the model prepared, what the rows can support
    (:func:`experiment_warnings`, :func:`check_residual_freedom`), the
    least-squares fit (:func:`least_squares_fit`) and what a fit far off shows at
    once (:func:`early_diagnosis`), the fit judged (:func:`judged_fit`,
    :func:`outlier_list`, :func:`verdict_warnings`), its covariance
    (:func:`covariance_of`) and, for a model with an effect, whether the data show
    it (:func:`nested_verdict`).

    Without ``robust`` the fit is least squares on every pose, and the outlier
    test still runs: flagged poses are listed and warned about, not removed.
    Gross outliers pull a least-squares fit towards them and inflate every
    residual, so the poses flagged are those the robust procedure would leave
    out, judged against its fit.

    Examples
    --------
    >>> from armcal.models import PlanarArm, forward_kinematics
    >>> arm = PlanarArm([260.0, 180.0])
    >>> q = np.radians([[0, 0], [0, 90], [0, 180], [0, -90]])
    >>> truth = arm.params_from_display([1.5, -0.6], [0.5, -0.5])
    >>> cal = identify(arm, q, forward_kinematics(arm, q, truth), sigma=0.1)
    >>> cal.values.round(9).tolist(), cal.std.round(4).tolist()
    ([1.5, -0.6, 0.5, -0.5], [0.05, 0.05, 0.011, 0.0194])
    >>> cal.goodness_of_fit.dof, [w.code for w in cal.warnings]  # noiseless: too good
    (4, ['fit-too-good'])
    >>> cal["dq2"]
    dq2 = -0.5 ± 0.0194 deg
    """
    conditions, points, row_sigma = checked_rows(
        model, q, points, sigma=sigma, row_sigma=row_sigma, target=target, loads=loads,
        conditions=conditions,
    )  # fmt: skip
    method = resolve_method(model, method)
    if sigma is not None:
        model = model.with_noise(instrument_override(model.noise, sigma))
    model = model.prepared(conditions, points)
    m = conditions.m
    labels = tuple(str(i) for i in range(1, m + 1)) if pose_labels is None else tuple(pose_labels)
    row_numbers = tuple(range(1, m + 1)) if rows is None else tuple(int(r) for r in rows)
    experiment, repeated = experiment_warnings(model, conditions, points, row_numbers)
    given = model.noise is not None or row_sigma is not None
    problem = Problem(model, conditions, points, method, tol, max_iter)
    info = model.check_identifiable(conditions)
    check_residual_freedom(model, m, given=given)
    reference = reference_sigma(model, conditions.sigma_mm)  # the rows' own, a feature's
    least_squares, nested_fits = least_squares_fit(problem)
    early = early_diagnosis(problem, least_squares, reference, given=given)
    verdict = judged_fit(problem, least_squares, reference, given=given, robust=robust)
    outliers = outlier_list(model, conditions, verdict, labels, row_numbers)
    conditioning = ill_conditioned_warning(model, info)
    warnings = verdict_warnings(
        problem, verdict, outliers, early, conditioning=conditioning, experiment=experiment,
        repeated=repeated, labels=labels, row_numbers=row_numbers, reference=reference,
        given=given, robust=robust,
    )  # fmt: skip
    fit = verdict.fit
    covariance = covariance_of(model, fit.factor, verdict.sigma_value)
    nested = None
    if nested_fits is not None:
        nested, said = nested_verdict(
            model, nested_fits, verdict, covariance, conditioned=conditioning is None
        )
        warnings.extend(said)
    return Calibration(
        model=model,
        method=method,
        params=fit.params,
        covariance=covariance,
        sigma_mm=float(verdict.sigma_value),
        sigma_source="given" if given else "estimated",
        residuals=fit.residuals,
        iterations=int(fit.iterations),
        converged=bool(fit.converged),
        pose_labels=labels,
        warnings=tuple(warnings),
        goodness_of_fit=verdict.fit_test,
        standardized_residuals=verdict.standardized,
        outliers=outliers,
        used=verdict.used,
        rows=row_numbers,
        robust=bool(robust),
        conditions=conditions,
        nested=nested,
        details=model.fit_details(conditions, fit.params),
        baseline=register_nominal(model, conditions, points, fit.params, used=verdict.used),
    )


def checked_rows(
    model: FitModel,
    q: ArrayLike,
    points: ArrayLike,
    *,
    sigma: float | None,
    row_sigma: ArrayLike | None,
    target: ArrayLike | None,
    loads: Loads | None,
    conditions: Conditions | None,
) -> tuple[Conditions, np.ndarray, np.ndarray | None]:
    """The rows' conditions, the points and the per-row sigma a fit uses, checked.

    The conditions are ``conditions`` (which must be those of ``q``) or made by the
    model from ``q``, ``target``, ``loads`` and ``row_sigma``; a given ``sigma``
    replaces the per-row sigma (:func:`armcal.noise.per_row_sigma`); the rows are
    then anchored (:meth:`~armcal.models.interface.FitModel.anchor`).  ValueError for
    points of the wrong shape, ArmcalError for values that are not finite or a
    per-row sigma that is not positive, one value per row.
    """
    given_conditions = conditions
    if conditions is None:
        conditions = model.conditions(q, target=target, loads=loads)
    elif not np.array_equal(conditions.q, np.asarray(q, dtype=float)):
        raise ValueError("conditions must be those of q")
    m, dim = conditions.m, model.point_dim
    points = np.asarray(points, dtype=float)
    if points.shape != (m, dim):
        raise ValueError(
            f"points must have shape ({m}, {dim}) in mm, one per row of q, got {points.shape}"
        )
    if not (np.all(np.isfinite(conditions.q)) and np.all(np.isfinite(points))):
        raise ArmcalError("joint angles and positions must be finite")
    rows_sigma = None
    if row_sigma is not None:
        rows_sigma = np.asarray(row_sigma, dtype=float)
        if rows_sigma.shape != (m,) or not np.all(np.isfinite(rows_sigma) & (rows_sigma > 0)):
            raise ArmcalError("per-row sigma must be positive and finite, one value per pose")
    rows_sigma = per_row_sigma(sigma, rows_sigma)
    if given_conditions is None and rows_sigma is not None:
        conditions = model.conditions(
            conditions.q, target=conditions.target, loads=conditions.loads, sigma_mm=rows_sigma
        )
    elif sigma is not None and conditions.sigma_mm is not None:  # the given sigma replaces
        # the rows' own, and a feature's (an axis, a turn) is the overridden noise's
        again = model.with_noise(instrument_override(model.noise, sigma)).conditions(
            conditions.q, target=conditions.target, loads=conditions.loads,
            feature=conditions.feature,
        )  # fmt: skip
        conditions = again if conditions.frames is None else again.with_frames(conditions.frames)
    conditions, points = model.anchor(conditions, points)
    return conditions, points, rows_sigma


def experiment_warnings(
    model: FitModel, conditions: Conditions, points: np.ndarray, row_numbers: Sequence[int]
) -> tuple[list[ArmcalWarning], int]:
    """What the rows can support, before any fit, and how many rows repeat another.

    A plan that sees nothing of the arm is refused (ArmcalError); one that misses part
    of it (``plan-degenerate``) and rows repeated exactly are warned of.
    """
    noun = row_noun(conditions.target)
    found = coverage(model, conditions.q)
    refuse_registration_only(found, conditions.m, noun)
    repeats = repeated_rows(conditions.q, points, conditions.target, conditions.feature)
    said = (plan_degenerate_warning(found), repeated_rows_warning(repeats, row_numbers, noun))
    return [w for w in said if w is not None], int(np.count_nonzero(repeats >= 0))


def check_residual_freedom(model: FitModel, m: int, *, given: bool) -> None:
    """ArmcalError when sigma must be estimated (not ``given``) but ``m`` rows leave no
    residual to estimate it from (``d m <= p_f``)."""
    dim, n_free = model.point_dim, model.n_free
    if not given and dim * m - n_free <= 0:
        raise ArmcalError(
            f"{m} poses leave no residual to estimate sigma from ({dim * m} equations, "
            f"{n_free} parameters); give the instrument noise with {action('sigma')} or measure "
            "more poses"
        )


def least_squares_fit(problem: Problem) -> tuple[Fit, tuple[Problem, Fit] | None]:
    """The least-squares fit on every row, and for a model with an effect (joint
    compliance) the problem of its nested model and that model's fit, where the fit
    starts and what the F test compares it with (same noise model, per-row sigma and
    rows)."""
    model = problem.model
    everyone = np.ones(problem.m, dtype=bool)
    inner = model.nested
    if inner is None or model.effect is None:
        return problem.fit(everyone), None
    nested_problem = Problem(
        inner,
        problem.conditions,
        problem.points,
        resolve_method(inner, "auto"),
        problem.tol,
        problem.max_iter,
    )
    inner_all = nested_problem.fit(everyone)
    return problem.fit(everyone, start=model.lift(inner_all.params)), (nested_problem, inner_all)


@dataclass(frozen=True, eq=False)
class EarlyCause:
    """What a least-squares fit far off shows at once (:func:`early_diagnosis`).

    Attributes
    ----------
    cause : ArmcalWarning or None
        Coupled joints, named before anything else.
    mirror : tuple of (str, float, int) or None
        :func:`_mirrored_fit`'s finding on every row.
    mirror_tried : bool
        Whether ``mirror`` is that finding (the fit's verdict then reuses it).
    """

    cause: ArmcalWarning | None = None
    mirror: tuple[str, float, int] | None = None
    mirror_tried: bool = False


def early_diagnosis(
    problem: Problem, least_squares: Fit, reference: float, *, given: bool
) -> EarlyCause:
    """A fit far off (:func:`~armcal.identification.diagnosis.far_off`) tested at once for
    coupled joints, else for mirrored points: a step that then fails on its absurd
    estimate (a singular Jacobian) names the cause (``problem.suspect``)."""
    if not far_off(problem.model, least_squares, reference if given else None):
        return EarlyCause()
    cause = coupled_joints(problem, least_squares)
    problem.suspect = None if cause is None else cause.text
    if cause is not None:
        return EarlyCause(cause)
    # a mirrored frame moves every point: said if the fit breaks
    problem.suspect, mirror = _mirror_suspect(problem, least_squares, reference)
    return EarlyCause(None, mirror, True)


@dataclass(frozen=True, eq=False)
class Verdict:
    """The fit judged (:func:`judged_fit`).

    Attributes
    ----------
    least_squares : Fit
        The least-squares fit on every row.
    fit : Fit
        The fit reported: the robust one without its outliers, or ``least_squares``.
    used : ndarray of bool, shape (m,)
        The rows of ``fit``.
    judged : Judgement or None
        The robust judgement, where it ran.
    sigma_value : float
        Sigma given or estimated (mm).
    standardized : ndarray, shape (m, d)
        Whitened residuals over ``sigma_value``.
    test : PoseTest
        The studentized outlier test that flagged ``flagged``.
    flagged : ndarray of bool, shape (m,)
    disagreeing : int
        The rows the test against sigma flags.
    extra : tuple of ArmcalWarning
        The judgement's own warning.
    scatter : float or None
        What the rows were judged against where that was their scatter although
        sigma was given.
    dof : int
    fit_test : GoodnessOfFit
    """

    least_squares: Fit
    fit: Fit
    used: np.ndarray
    judged: Judgement | None
    sigma_value: float
    standardized: np.ndarray
    test: PoseTest
    flagged: np.ndarray
    disagreeing: int
    extra: tuple[ArmcalWarning, ...]
    scatter: float | None
    dof: int
    fit_test: GoodnessOfFit


def judged_fit(
    problem: Problem, least_squares: Fit, reference: float, *, given: bool, robust: bool
) -> Verdict:
    """The fit with sigma given (``reference``) or estimated, its outlier test and its
    chi-square test; robustly (outliers left out) with ``robust``, else judged by the
    robust procedure only where the test flags rows."""
    model = problem.model
    robust_sigma = reference if given else None
    fit, used = least_squares, np.ones(problem.m, dtype=bool)
    judged = judge(problem, robust_sigma, least_squares, robust=True) if robust else None
    if judged is not None:
        fit, used = judged.fit, judged.used
    dof = model.point_dim * int(np.count_nonzero(used)) - model.n_free
    sigma_value = reference if given else fit.scale(max(dof, 1))
    standardized = fit.whitened / sigma_value
    test = fit.test(sigma_value, given=given)
    if judged is None and np.any(test.flagged):
        # Gross outliers pull a least-squares fit towards them and inflate every
        # residual, so the poses to flag are those the robust procedure would
        # leave out, judged against its fit; this fit keeps them.
        judged = judge(problem, robust_sigma, least_squares, robust=False)
    flagged, disagreeing = test.flagged, int(np.count_nonzero(test.flagged))
    extra: tuple[ArmcalWarning, ...] = ()
    if judged is not None:
        flagged, test, disagreeing = judged.flagged, judged.test, judged.disagreeing
        extra = () if judged.warning is None else (judged.warning,)
    return Verdict(
        least_squares=least_squares,
        fit=fit,
        used=used,
        judged=judged,
        sigma_value=float(sigma_value),
        standardized=standardized,
        test=test,
        flagged=flagged,
        disagreeing=disagreeing,
        extra=extra,
        scatter=judged.scale if judged is not None and judged.scatter else None,
        dof=dof,
        fit_test=goodness_of_fit(standardized[used], dof, sigma_given=given),
    )


def outlier_list(
    model: FitModel,
    conditions: Conditions,
    verdict: Verdict,
    labels: Sequence[str],
    row_numbers: Sequence[int],
) -> tuple[Outlier, ...]:
    """Every flagged row as an :class:`Outlier`: its pose, target, residual and test."""
    distance = point_norms(verdict.fit.residuals[:, : model.position_dim])
    turn = model.turn_rows(conditions)  # a turn's residual (rad) in degrees
    turn = np.zeros(conditions.m, dtype=bool) if turn is None else turn
    distance = np.where(turn, np.degrees(distance), distance)
    target_index = conditions.target
    test = verdict.test
    return tuple(
        Outlier(
            index=int(i),
            row=row_numbers[int(i)],
            pose=labels[int(i)],
            target=None if target_index is None else model.target_labels[target_index[i]],
            residual_mm=float(distance[i]),
            studentized=float(test.statistic[i]),
            p_value=float(test.p_value[i]),
            removed=not bool(verdict.used[i]),
            unit="deg" if turn[i] else model.reading_unit,
        )
        for i in np.flatnonzero(verdict.flagged)
    )


def verdict_warnings(
    problem: Problem,
    verdict: Verdict,
    outliers: tuple[Outlier, ...],
    early: EarlyCause,
    *,
    conditioning: ArmcalWarning | None,
    experiment: Sequence[ArmcalWarning],
    repeated: int,
    labels: Sequence[str],
    row_numbers: Sequence[int],
    reference: float,
    given: bool,
    robust: bool,
) -> list[ArmcalWarning]:
    """The fit's warnings, in the order a report shows them: conditioning and the
    experiment's, convergence, outliers, too few degrees of freedom, a misfit and its
    likely cause (:func:`_misfit`), a fit too good."""
    model, fit, used = problem.model, verdict.fit, verdict.used
    scale, unit = sigma_unit(model, problem.conditions, reference)  # rows of turns: a ratio
    warnings = [w for w in (conditioning, *experiment) if w is not None]
    if not fit.converged:
        warnings.append(
            not_converged_warning(problem.method, fit.iterations, model.has_closed_form)
        )
    if outliers:
        warnings.append(
            outlier_warning(
                outliers,
                robust=robust,
                scatter=None if verdict.scatter is None else verdict.scatter * scale,
                sigma=reference * scale,
                unit=unit,
            )
        )
    warnings.extend(verdict.extra)
    n_used = int(np.count_nonzero(used))
    noun = row_noun(problem.conditions.target)
    few = (
        few_dof_warning(n_used, verdict.dof, model.n_free, equations_per_pose(model), noun)
        if given
        else None
    )
    if few is not None:
        warnings.append(few)
    inconsistent, cause = _misfit(
        problem, verdict, early, bool(outliers), labels, row_numbers, reference, given=given,
        robust=robust,
    )  # fmt: skip
    warnings.extend(w for w in (inconsistent, cause) if w is not None)
    if verdict.fit_test.too_good:
        warnings.append(
            too_good_warning(
                verdict.fit_test, verdict.sigma_value * scale, repeated=repeated, unit=unit
            )
        )
    return warnings


def _misfit(
    problem: Problem,
    verdict: Verdict,
    early: EarlyCause,
    any_outliers: bool,
    labels: Sequence[str],
    row_numbers: Sequence[int],
    reference: float,
    *,
    given: bool,
    robust: bool,
) -> tuple[ArmcalWarning | None, ArmcalWarning | None]:
    """``fit-inconsistent`` for a fit that fails the chi-square test (with what freeing the
    fixed parameters or undoing a mirror would explain), and the likely cause a cheap
    test names: coupled joints (found early), swapped target labels, an instrument that
    moved."""
    model, fit, used = problem.model, verdict.fit, verdict.used
    least_squares, sigma_value, fit_test = (
        verdict.least_squares,
        verdict.sigma_value,
        verdict.fit_test,
    )
    conditions, points = problem.conditions, problem.points
    cause, inconsistent = early.cause, None
    if fit_test.too_large:
        chi2 = fit_test.chi2 or 0.0
        suggested = sigma_value * float(np.sqrt(chi2 / max(verdict.dof, 1)))
        freed = _freed_fit(problem, used, sigma_value, chi2)
        if freed is None and cause is None:
            cause = swapped_targets(problem, least_squares, labels, row_numbers)
        if freed is None and cause is None and fit.converged:  # the instrument moved?
            moved = instrument_moved(model, conditions, points, fit.params, used=used)
            cause = None if moved is None else moved_warning(moved, row_numbers)
        mirrored = None
        if freed is None and cause is None and most_disagree(verdict.disagreeing, problem.m):
            same = early.mirror_tried and fit is least_squares and sigma_value == reference
            mirrored = early.mirror if same else _mirrored_fit(problem, used, sigma_value, chi2)
        scale, unit = sigma_unit(model, conditions, reference)  # rows of turns: a ratio
        inconsistent = inconsistent_fit_warning(
            fit_test,
            sigma_value * scale,
            suggested * scale,
            int(np.count_nonzero(verdict.flagged)),
            poses=problem.m,
            held=model.fixed,
            freed=freed,
            mirrored=mirrored,
            rows=row_noun(conditions.target),
            disagreeing=verdict.disagreeing,
            scatter=None if verdict.scatter is None else verdict.scatter * scale,
            robust=robust,
            unit=unit,
        )
    elif cause is None and (any_outliers or far_off(model, fit, None)):
        # consistent (sigma estimated, say): judged by its outliers and its size alone
        cause = swapped_targets(problem, least_squares, labels, row_numbers)
    if cause is None and not given and fit.converged:  # sigma estimated: no chi-square
        moved = instrument_moved(model, conditions, points, fit.params, used=used, screen=True)
        cause = None if moved is None else moved_warning(moved, row_numbers)
    return inconsistent, cause


def covariance_of(model: FitModel, factor: np.ndarray, sigma_value: float) -> np.ndarray:
    """``sigma^2 G G^T`` ``(p, p)`` from the free parameters' factor ``G`` ``(p_f, p_f)``
    (paper eq. 16): 0 in the rows and columns of a fixed parameter."""
    g = np.zeros((model.n_params, model.n_free))
    g[model.free] = factor
    return sigma_value**2 * (g @ g.T)


def nested_verdict(
    model: FitModel,
    nested_fits: tuple[Problem, Fit],
    verdict: Verdict,
    covariance: np.ndarray,
    *,
    conditioned: bool,
) -> tuple[NestedFit, list[ArmcalWarning]]:
    """Whether the data show the model's effect (joint compliance): the F test of the fit
    against its nested model's on the same rows, the ``compliance-unseen`` warning (for
    a fit that is ``conditioned``; else the conditioning warning says it) and the
    warning for a negative effect."""
    nested_problem, inner_all = nested_fits
    inner, effect_words = nested_problem.model, model.effect
    assert effect_words is not None  # least_squares_fit made nested fits for an effect
    fit, used = verdict.fit, verdict.used
    # On the same poses as the fit, so that the F test compares the sums of squares
    # each fit minimised (whitened residuals, in one unit).
    inner_fit = inner_all if used.all() else nested_problem.fit(used)
    # The effect's free parameters: those a rule holds (a joint gravity does not twist)
    # are neither tested nor shown.
    effect = inner.n_params + np.flatnonzero(model.free[inner.n_params :])
    p_value = nested_test(inner_fit.whitened[used], fit.whitened[used], effect.size, verdict.dof)
    nested = NestedFit(
        effect_words,
        tuple(model.param_names[i] for i in effect),
        rms(inner_fit.residuals[used]),
        p_value,
    )
    std = display_std(model, covariance)[effect]
    values = fit.params[effect] * model.display_scale[effect]
    units = [model.param_units[i] for i in effect]
    shown = ", ".join(
        f"{name} = {v:.3g} ± {s:.3g} {unit}"
        for name, unit, v, s in zip(nested.names, units, values, std, strict=True)
    )
    said = []
    unseen = unseen_warning(
        effect_words, shown, nested.rms_per_coordinate_mm, rms(fit.residuals[used]), p_value
    )
    if unseen is not None and conditioned:
        said.append(unseen)
    negative = negative_effect_warning(effect_words, nested.names, values, std, units)
    if negative is not None:
        said.append(negative)
    return nested, said


def moved_warning(moved: Movement, rows: Sequence[int]) -> ArmcalWarning:
    """``instrument-moved``: the rows from ``moved.split`` on place the instrument elsewhere."""
    first, last = rows[moved.split - 1], rows[moved.split]
    return ArmcalWarning(
        "instrument-moved",
        f"the rows up to row {first} and from row {last} on (the campaign cut at "
        f"{moved.fraction:.0%} of its rows) are fitted far better with an instrument pose of "
        f"their own (it takes up {100 * moved.explained:.0f} % of the residual; the two poses "
        f"put the points {moved.shift_mm:.3g} mm apart, RMS per point): the instrument or "
        "the arm's base moved during the campaign, and no calibration of the arm can take "
        "that up; calibrate from the rows of one setup, or measure again with the "
        "instrument fixed",
    )
