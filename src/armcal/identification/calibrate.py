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
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike

from ..errors import ArmcalError, ArmcalWarning, action
from ..models import Conditions, FitModel, Loads, equations_per_pose
from ..models.information import display_std
from ..noise import instrument_override
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
    Outlier,
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
from .problem import Fit, Problem, reference_sigma
from .registration import Movement, instrument_moved, register_nominal
from .result import Calibration, NestedFit
from .robust import judge
from .solvers import resolve_method

__all__ = [
    "identify",
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
        :class:`~armcal.models.planar.compliance.CompliantArm`), with its noise model and
        fixed parameters.
    q : ndarray, shape (m, n)
        Commanded joint angles in rad.
    points : ndarray, shape (m, d)
        Measured points in mm, in the instrument frame (``d = 2`` in the plane).
    method : {"auto", "closed-form", "gauss-newton"}
        ``"auto"`` is the closed form where the model has one (exact, see
        :mod:`~armcal.models.planar.closed_form`), else Gauss-Newton
        (:func:`~armcal.identification.solvers.resolve_method`).
    sigma : float, optional
        Instrument noise (1 std, mm), replacing the noise model's instrument
        part (encoder noise stays; :func:`armcal.noise.instrument_override`).
        Without it and without a noise model or ``row_sigma``, sigma is
        estimated from the residuals, which needs ``d m > p_f``.
    pose_labels : sequence of str, optional
        Labels of the poses for reports; ``"1".."m"`` by default.
    rows : sequence of int, optional
        1-based data rows of the poses in their file, for reports; ``1..m`` by default.
    row_sigma : ndarray, shape (m,), optional
        Per-row instrument noise (mm), for instruments that report each point's
        uncertainty; replaces the instrument covariance row by row.
    robust : bool
        Fit with Huber's M-estimator from the least-squares fit, flag outliers
        by the studentized test (:mod:`~armcal.identification.judgement`), leave
        them out and refit until the set is stable.
    tol, max_iter
        Gauss-Newton step tolerance (relative to the reach) and iteration cap.
    target : ndarray of int, shape (m,), optional
        Every pose's target (index into the model's targets), for a model with several.
    loads : Loads, optional
        Every pose's payload and tip force (a model of joint compliance; default:
        the robot file's payload).
    conditions : Conditions, optional
        The rows' conditions, already made by ``model.conditions`` from these
        ``q``, ``target``, ``loads`` and ``row_sigma``: the factorizations
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
    dim = model.point_dim
    given_conditions = conditions
    if conditions is None:
        conditions = model.conditions(q, target=target, loads=loads)
    elif not np.array_equal(conditions.q, np.asarray(q, dtype=float)):
        raise ValueError("conditions must be those of q")
    q = conditions.q
    m = conditions.m
    points = np.asarray(points, dtype=float)
    if points.shape != (m, dim):
        raise ValueError(f"points must have shape ({m}, {dim}) in mm, got {points.shape}")
    if not (np.all(np.isfinite(q)) and np.all(np.isfinite(points))):
        raise ArmcalError("joint angles and positions must be finite")
    if row_sigma is not None:
        row_sigma = np.asarray(row_sigma, dtype=float)
        if row_sigma.shape != (m,) or not np.all(np.isfinite(row_sigma) & (row_sigma > 0)):
            raise ArmcalError("per-row sigma must be positive and finite, one value per pose")
        if given_conditions is None:
            conditions = model.conditions(
                q, target=conditions.target, loads=conditions.loads, sigma_mm=row_sigma
            )
    conditions, points = model.anchor(conditions, points)
    method = resolve_method(model, method)
    if sigma is not None:
        model = model.with_noise(instrument_override(model.noise, sigma))
    model = model.prepared(conditions, points)
    noun = row_noun(conditions.target)
    # What the rows can support, before any fit: a plan that sees nothing of the arm is
    # refused, one that misses part of it and rows repeated exactly are warned of.
    found = coverage(model, conditions.q)
    refuse_registration_only(found, m, noun)
    labels = tuple(str(i) for i in range(1, m + 1)) if pose_labels is None else tuple(pose_labels)
    row_numbers = tuple(range(1, m + 1)) if rows is None else tuple(int(r) for r in rows)
    repeats = repeated_rows(conditions.q, points, conditions.target)
    repeated_count = int(np.count_nonzero(repeats >= 0))
    repeated = repeated_rows_warning(repeats, row_numbers, noun)
    experiment = [plan_degenerate_warning(found), repeated]
    given = model.noise is not None or row_sigma is not None
    problem = Problem(model, conditions, points, method, tol, max_iter)
    info = model.check_identifiable(conditions)
    n_free = model.n_free
    if not given and dim * m - n_free <= 0:
        raise ArmcalError(
            f"{m} poses leave no residual to estimate sigma from ({dim * m} equations, "
            f"{n_free} parameters); give the instrument noise with {action('sigma')} or measure "
            "more poses"
        )
    reference = reference_sigma(model, row_sigma)
    everyone = np.ones(m, dtype=bool)
    extra: list[ArmcalWarning] = []
    robust_sigma = reference if given else None
    inner, effect_words = model.nested, model.effect
    nested_problem = inner_all = None
    start = None
    if inner is not None and effect_words is not None:
        # The model without its effect, fitted as the model is (same noise model, per-row
        # sigma and poses): where the fit starts, and what the F test compares it with.
        nested_problem = Problem(
            inner, conditions, points, resolve_method(inner, "auto"), tol, max_iter
        )
        inner_all = nested_problem.fit(everyone)
        start = model.lift(inner_all.params)
    least_squares = problem.fit(everyone, start=start)
    # A fit far off is tested at once for coupled joints: a step that fails on its absurd
    # estimate (a singular Jacobian) then names the cause too (Problem.suspect).
    cause = None  # a likely cause a cheap test names (diagnosis), before the mirror's
    early_mirror: tuple[str, float, int] | None = None
    mirror_tried = False  # whether early_mirror is _mirrored_fit's finding on every row
    if far_off(model, least_squares, reference if given else None):
        cause = coupled_joints(problem, least_squares)
        problem.suspect = None if cause is None else cause.text
        if cause is None:  # a mirrored frame moves every point: said if the fit breaks
            problem.suspect, early_mirror = _mirror_suspect(problem, least_squares, reference)
            mirror_tried = True
    fit, used = least_squares, everyone
    judged = judge(problem, robust_sigma, least_squares, robust=True) if robust else None
    if judged is not None:
        fit, used = judged.fit, judged.used
    dof = dim * int(np.count_nonzero(used)) - n_free
    source: Literal["given", "estimated"]
    if given:
        sigma_value, source = reference, "given"
    else:
        sigma_value, source = fit.scale(max(dof, 1)), "estimated"
    standardized = fit.whitened / sigma_value
    test = fit.test(sigma_value, given=given)
    if judged is None and np.any(test.flagged):
        # Gross outliers pull a least-squares fit towards them and inflate every
        # residual, so the poses to flag are those the robust procedure would
        # leave out, judged against its fit; this fit keeps them.
        judged = judge(problem, robust_sigma, least_squares, robust=False)
    flagged, disagreeing = test.flagged, int(np.count_nonzero(test.flagged))
    if judged is not None:
        flagged, test, disagreeing = judged.flagged, judged.test, judged.disagreeing
        if judged.warning is not None:
            extra.append(judged.warning)
    distance = point_norms(fit.residuals[:, : model.position_dim])
    target_index = conditions.target
    outliers = tuple(
        Outlier(
            index=int(i),
            row=row_numbers[i],
            pose=labels[i],
            target=None if target_index is None else model.target_labels[target_index[i]],
            residual_mm=float(distance[i]),
            studentized=float(test.statistic[i]),
            p_value=float(test.p_value[i]),
            removed=not bool(used[i]),
        )
        for i in np.flatnonzero(flagged)
    )
    fit_test = goodness_of_fit(standardized[used], dof, sigma_given=given)
    conditioning = model.conditioning_warning(info)
    warnings = [w for w in (conditioning, *experiment) if w is not None]
    if not fit.converged:
        warnings.append(not_converged_warning(method, fit.iterations, model.has_closed_form))
    scatter = judged.scale if judged is not None and judged.scatter else None
    if outliers:
        warnings.append(outlier_warning(outliers, robust=robust, scatter=scatter, sigma=reference))
    warnings.extend(extra)
    few = (
        few_dof_warning(int(np.count_nonzero(used)), dof, n_free, equations_per_pose(model), noun)
        if given
        else None
    )
    if few is not None:
        warnings.append(few)
    if fit_test.too_large:
        suggested = sigma_value * float(np.sqrt((fit_test.chi2 or 0.0) / max(dof, 1)))
        chi2 = fit_test.chi2 or 0.0
        freed = _freed_fit(problem, used, sigma_value, chi2)
        if freed is None and cause is None:
            cause = swapped_targets(problem, least_squares, labels, row_numbers)
        if freed is None and cause is None and fit.converged:  # the instrument moved?
            moved = instrument_moved(model, conditions, points, fit.params, used=used)
            cause = None if moved is None else moved_warning(moved, row_numbers)
        mirrored = None
        if freed is None and cause is None and most_disagree(disagreeing, m):
            same = mirror_tried and fit is least_squares and sigma_value == reference
            mirrored = early_mirror if same else _mirrored_fit(problem, used, sigma_value, chi2)
        warnings.append(
            inconsistent_fit_warning(
                fit_test,
                sigma_value,
                suggested,
                int(np.count_nonzero(flagged)),
                poses=m,
                held=model.fixed,
                freed=freed,
                mirrored=mirrored,
                rows=noun,
                disagreeing=disagreeing,
                scatter=scatter,
                robust=robust,
            )
        )
    elif cause is None and (outliers or far_off(model, fit, None)):
        # consistent (sigma estimated, say): judged by its outliers and its size alone
        cause = swapped_targets(problem, least_squares, labels, row_numbers)
    if cause is None and not given and fit.converged:  # sigma estimated: no chi-square
        moved = instrument_moved(model, conditions, points, fit.params, used=used, screen=True)
        cause = None if moved is None else moved_warning(moved, row_numbers)
    if cause is not None:
        warnings.append(cause)
    if fit_test.too_good:
        warnings.append(too_good_warning(fit_test, sigma_value, repeated=repeated_count))
    g = np.zeros((model.n_params, n_free))
    g[model.free] = fit.factor
    covariance = sigma_value**2 * (g @ g.T)
    nested = None
    if nested_problem is not None and inner is not None and effect_words is not None:
        # On the same poses as the fit, so that the F test compares the sums of squares
        # each fit minimised (whitened residuals, in one unit).
        inner_fit = inner_all if used.all() else nested_problem.fit(used)
        assert inner_fit is not None
        # The effect's free parameters: those a rule holds (a joint gravity does not twist)
        # are neither tested nor shown.
        effect = inner.n_params + np.flatnonzero(model.free[inner.n_params :])
        p_value = nested_test(inner_fit.whitened[used], fit.whitened[used], effect.size, dof)
        nested = NestedFit(
            effect_words,
            tuple(model.param_names[i] for i in effect),
            rms(inner_fit.residuals[used]),
            p_value,
        )
        std = display_std(model, covariance)[effect]
        shown = ", ".join(
            f"{name} = {v:.3g} ± {s:.3g} {unit}"
            for name, unit, v, s in zip(
                nested.names,
                [model.param_units[i] for i in effect],
                fit.params[effect] * model.display_scale[effect],
                std,
                strict=True,
            )
        )
        unseen = unseen_warning(
            effect_words, shown, nested.rms_per_coordinate_mm, rms(fit.residuals[used]), p_value
        )
        if unseen is not None and conditioning is None:
            warnings.append(unseen)
        negative = negative_effect_warning(
            effect_words,
            nested.names,
            fit.params[effect] * model.display_scale[effect],
            std,
            [model.param_units[i] for i in effect],
        )
        if negative is not None:
            warnings.append(negative)
    return Calibration(
        model=model,
        method=method,
        params=fit.params,
        covariance=covariance,
        sigma_mm=float(sigma_value),
        sigma_source=source,
        residuals=fit.residuals,
        iterations=int(fit.iterations),
        converged=bool(fit.converged),
        pose_labels=labels,
        warnings=tuple(warnings),
        goodness_of_fit=fit_test,
        standardized_residuals=standardized,
        outliers=outliers,
        used=used,
        rows=row_numbers,
        robust=bool(robust),
        conditions=conditions,
        nested=nested,
        details=model.fit_details(conditions, fit.params),
        baseline=register_nominal(model, conditions, points, fit.params, used=used),
    )


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
