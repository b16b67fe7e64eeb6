"""Least squares for any fit model: the closed form where the family has one, else Gauss-Newton.

Every solver here works through :class:`~armcal.models.interface.FitModel` and is
batched over measurement sets: points ``(N, m, d)`` share the conditions of
their rows and are solved together, so a Monte Carlo is one call per chunk of
trials.

* ``"closed-form"`` -- the model's own exact solver
  (:meth:`~armcal.models.interface.FitModel.closed_form`; for the planar arm, one
  linear least-squares solve in the link phasors).  With encoder noise the
  weights depend on the estimate (errors in variables): the whitening is
  re-evaluated at the estimate and the solve repeated until it no longer moves.
* ``"gauss-newton"`` -- one Gauss-Newton loop for every model: whitened rows of
  the Jacobian over the free parameters, the minimum-norm step of the rank
  policy (:class:`armcal.numerics.RowTriangle`, never the normal equations),
  every active set at once, the rows a block at a time (memory ``O(m)``, not
  ``O(m p)``).  It starts from the nested model's fit
  (the geometry, for a model of joint compliance), or from the model's own
  start (:meth:`~armcal.models.interface.FitModel.start`).

``method="auto"`` is the closed form where the model has one
(:attr:`~armcal.models.interface.FitModel.has_closed_form`), else Gauss-Newton
(:func:`resolve_method`: the one place this rule is made).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

import numpy as np

from ..choices import IDENTIFY_METHODS
from ..errors import ArmcalError
from ..models import ROW_BLOCK, Conditions, FitModel, wrap_angle
from ..models.information import known_start, weighted_whitening
from ..models.interface import columns_jacobian
from ..models.wording import no_closed_form
from ..numerics import RowTriangle, steps_settled

__all__ = [
    "METHODS",
    "LastStep",
    "Method",
    "Solution",
    "gauss_newton",
    "resolve_method",
    "solve",
]

Method = Literal["auto", "closed-form", "gauss-newton"]

#: The solvers by name (``"auto"`` chooses one, :func:`resolve_method`).
METHODS = IDENTIFY_METHODS

#: A Gauss-Newton step smaller than this times ``cond(J_w)`` times the reach is within
#: the round-off of its own solve (``cond eps``, eps = 2.2e-16, with a margin of 10).
ROUND_OFF = 10 * float(np.finfo(float).eps)


@dataclass(frozen=True, eq=False)
class Solution:
    """Least-squares parameters of ``N`` measurement sets.

    Attributes
    ----------
    params : ndarray, shape (N, p)
        Internal units (mm, rad, ...); fixed parameters 0.
    iterations : ndarray of int, shape (N,)
        Linearized solves (1 for the closed form).
    converged : ndarray of bool, shape (N,)
        Whether each set met the tolerance (for the closed form: full rank).
    method : str
        ``"closed-form"`` or ``"gauss-newton"``.
    """

    params: np.ndarray
    iterations: np.ndarray
    converged: np.ndarray
    method: str
    last: LastStep | None = None

    def __repr__(self) -> str:
        sets = self.params.shape[0]
        done = int(np.count_nonzero(self.converged))
        return (
            f"Solution({self.method}: {sets} set(s) of {self.params.shape[-1]} parameters, "
            f"{done} converged, at most {int(np.max(self.iterations, initial=0))} iteration(s))"
        )


@dataclass(frozen=True, eq=False)
class LastStep:
    """The whitened rows of one set's last Gauss-Newton step, where that step was within
    the tolerance (so its parameters are the estimate's to a part in ``1/tol``, the
    tolerance's ``1e-12`` of the reach by default): the covariance and the leverage at the
    estimate, without a pass of their own.

    Attributes
    ----------
    blocks : ndarray, shape (m, d, p_f)
        ``W J`` over the free parameters, row by row.
    rows : RowTriangle
        Their triangle (:class:`~armcal.numerics.RowTriangle`).
    """

    blocks: np.ndarray
    rows: RowTriangle


def resolve_method(model: FitModel, method: str) -> str:
    """The solver ``method`` means for ``model``: the rule behind ``"auto"``, in one place.

    ``"auto"`` is the closed form where the model has one, else Gauss-Newton.

    Raises
    ------
    ArmcalError
        For an unknown method, or the closed form asked of a model without one.

    Examples
    --------
    >>> from armcal.models import PlanarArm
    >>> arm = PlanarArm([2.0, 1.0])
    >>> resolve_method(arm, "auto"), resolve_method(arm.with_fixed(["dl2"]), "auto")
    ('closed-form', 'gauss-newton')
    """
    if method == "auto":
        return "closed-form" if model.has_closed_form else "gauss-newton"
    if method not in METHODS:
        raise ArmcalError(f"unknown method {method!r}; choose one of auto, {', '.join(METHODS)}")
    if method == "closed-form" and not model.has_closed_form:
        raise ArmcalError(no_closed_form(model))
    return method


def _sets(conditions: Conditions, points: np.ndarray, dim: int) -> np.ndarray:
    points = np.asarray(points, dtype=float)
    m = conditions.m
    if points.ndim not in (2, 3) or points.shape[-2:] != (m, dim):
        raise ValueError(f"points must have shape ({m}, {dim}) or (N, {m}, {dim}) in mm")
    return points.reshape(-1, m, dim)


def _shared(weights: np.ndarray | None, n_sets: int, m: int) -> np.ndarray | None:
    """Weights as ``(m,)`` when every set has the same, else ``(N, m)``."""
    if weights is None:
        return None
    weights = np.broadcast_to(np.asarray(weights, dtype=float), (n_sets, m))
    if n_sets == 1 or np.all(weights == weights[:1]):
        return weights[0]
    return weights


def _for_sets(weights: np.ndarray | None, active: np.ndarray) -> np.ndarray | None:
    """The weights of the sets ``active``: shared ``(m,)`` weights serve every set."""
    if weights is None or weights.ndim == 1:
        return weights
    return weights[active]


def solve(
    model: FitModel,
    conditions: Conditions,
    points: np.ndarray,
    *,
    method: str = "auto",
    weights: np.ndarray | None = None,
    start: np.ndarray | None = None,
    tol: float = 1e-12,
    max_iter: int = 50,
    keep: bool = False,
    settle: bool = False,
) -> Solution:
    """Weighted least squares over the free parameters of ``model``; batched over sets.

    Parameters
    ----------
    model : FitModel
        Its noise model weights the rows; its fixed parameters stay at 0.
    conditions : Conditions
        The rows' joint readings, targets, loads and per-row noise, shared by
        every set (:meth:`~armcal.models.interface.FitModel.conditions`).
    points : ndarray, shape (m, d) or (N, m, d)
        Measured points in mm.
    method : {"auto", "closed-form", "gauss-newton"}
        See :func:`resolve_method`; the closed form ignores ``start``.
    weights : ndarray, shape (m,) or (N, m), optional
        Extra weights per row (robust fitting, leaving rows out with 0).
    start : ndarray, shape (p,) or (N, p), optional
        Where Gauss-Newton starts; by default the nested model's fit, or the
        model's own start.
    tol, max_iter
        A set has converged when its largest step moves the points by less
        than ``tol`` times the arm's reach (mm); iteration cap.
    keep : bool
        Gauss-Newton on one set keeps its last step's rows (:class:`LastStep`) in
        :attr:`Solution.last` where that step was within the tolerance.
    settle : bool
        Gauss-Newton also stops a set whose steps shrank so fast that the ones after
        its last add up to less than the tolerance
        (:func:`~armcal.numerics.steps_settled`), without a pass of the model only to
        confirm it: for estimates needed to a small part of their spread (a Monte
        Carlo's), not to round-off.

    Returns
    -------
    Solution
        Always batched: one row per set.

    Raises
    ------
    NotIdentifiableError
        From the closed form of rows that cannot identify the parameters (other
        callers check identifiability first).
    ArmcalError
        For an unknown method, or the closed form of a model without one.

    Examples
    --------
    >>> from armcal.models import PlanarArm, forward_kinematics
    >>> arm = PlanarArm([2.0, 1.0], sigma=0.01, fixed=("dl2",))
    >>> q = np.radians([[0, 0], [0, 90], [90, 90], [45, -120]])
    >>> truth = np.array([0.1, 0.0, 0.01, -0.02])
    >>> found = solve(arm, arm.conditions(q), forward_kinematics(arm, q, truth))
    >>> bool(np.allclose(found.params[0], truth, atol=1e-12)), found.method
    (True, 'gauss-newton')
    """
    method = resolve_method(model, method)
    sets = _sets(conditions, points, model.point_dim)
    weights = _shared(weights, sets.shape[0], conditions.m)
    threshold = tol * model.reach_mm
    if method == "closed-form":
        return _closed_form(model, conditions, sets, weights, threshold, max_iter)
    if start is None:
        params = _initial(model, conditions, sets, weights, tol, max_iter)
    else:
        params = np.broadcast_to(np.asarray(start, dtype=float), (sets.shape[0], model.n_params))
    params = np.where(model.free, params, model.held_values)  # held ones where they are held
    return gauss_newton(
        model, conditions, sets, params, weights, threshold, max_iter, keep=keep, settle=settle
    )


def _initial(
    model: FitModel,
    conditions: Conditions,
    sets: np.ndarray,
    weights: np.ndarray | None,
    tol: float,
    max_iter: int,
) -> np.ndarray:
    """Where Gauss-Newton starts: the nested model's fit lifted, else the model's start."""
    inner = model.nested
    if inner is not None:
        fitted = solve(inner, conditions, sets, weights=weights, tol=tol, max_iter=max_iter)
        return model.lift(fitted.params)
    return model.start(conditions, sets, weights)


def _closed_form(
    model: FitModel,
    conditions: Conditions,
    sets: np.ndarray,
    weights: np.ndarray | None,
    threshold: float,
    max_iter: int,
) -> Solution:
    """The model's closed form on whitened rows; re-whitened at the estimate with encoder noise."""
    closed = model.closed_form(conditions)
    assert closed is not None, "resolve_method checked that the model has a closed form"
    dim = model.point_dim
    w = weighted_whitening(model.whitening(conditions, None), weights, dim)
    params, ok = closed.solve(sets, w)
    n_sets = sets.shape[0]
    iterations = np.ones(n_sets, dtype=int)
    converged = ok.copy()
    noise = model.noise
    if noise is not None and noise.joint_sigma is not None:
        scale = model.step_scale(conditions)
        active = np.arange(n_sets)
        for _ in range(max_iter):
            # (N, p) estimates: per-set whitening (N, m, d, d)
            at = weighted_whitening(
                model.whitening(conditions, params[active]), _for_sets(weights, active), dim
            )
            new, ok = closed.solve(sets[active], at)
            moved = np.max(np.abs(wrap_angle(new - params[active]) * scale), axis=-1, initial=0)
            params[active] = new
            iterations[active] += 1
            active = active[ok & (moved > threshold)]
            if active.size == 0:
                break
        converged[active] = False
    return Solution(params, iterations, converged, "closed-form")


def _whitened_rows(
    model: FitModel,
    conditions: Conditions,
    points: np.ndarray,
    params: np.ndarray,
    free: np.ndarray,
    weights: np.ndarray | None,
) -> tuple[np.ndarray, np.ndarray]:
    """``W J`` over the columns ``free`` ``(N, m, d, p_f)`` and the whitened residuals
    ``W (points - positions)`` ``(N, m, d)`` of sets ``points`` ``(N, m, d)`` at ``params``
    ``(N, p)``, ``W`` with the rows' extra ``weights``: the Jacobian first, whose pass
    gives the points the residuals and the whitening need (a model keeps them,
    :meth:`~armcal.models.interface.Conditions.latest`)."""
    jac = columns_jacobian(model, conditions, params, free)
    w = weighted_whitening(model.whitening(conditions, params), weights, model.point_dim)
    residual = points - model.positions(conditions, params)
    if w is None:
        return jac, residual
    return w @ jac, (w @ residual[..., None])[..., 0]


def _step_rows(
    model: FitModel,
    chunks: list[tuple[Conditions, slice]],
    measured: np.ndarray,
    current: np.ndarray,
    free: np.ndarray,
    weights: np.ndarray | None,
    blocks: list[np.ndarray],
    keep: bool,
) -> RowTriangle:
    """The rows of a Gauss-Newton step of the sets ``measured`` ``(N, m, d)`` at ``current``
    ``(N, p)``, a block of rows at a time; with ``keep`` (one set) each block's Jacobian
    also goes to ``blocks`` (for :class:`LastStep`).  Sets at one point (a Monte Carlo's first
    step, from the truth) share their rows' Jacobian: one pass of the model and one
    factorization for them all."""
    n_sets, n_free = current.shape[0], int(np.count_nonzero(free))
    shared = n_sets > 1 and weights is None and bool(np.all(current == current[0]))
    rows = RowTriangle(n_free, sides=n_sets) if shared else RowTriangle(n_free)
    for sub, part in chunks:
        w = None if weights is None else weights[..., part]
        at = current[:1] if shared else current
        jac, weighted = _whitened_rows(model, sub, measured[:, part], at, free, w)
        if shared:
            rows.add(jac.reshape(-1, n_free), weighted.reshape(n_sets, -1).T)
        else:
            rows.add(jac.reshape(n_sets, -1, n_free), weighted.reshape(n_sets, -1))
        if keep:
            blocks.append(jac[0])
    return rows


def gauss_newton(
    model: FitModel,
    conditions: Conditions,
    sets: np.ndarray,
    params: np.ndarray,
    weights: np.ndarray | None,
    threshold: float,
    max_iter: int,
    *,
    free: np.ndarray | None = None,
    keep: bool = False,
    settle: bool = False,
) -> Solution:
    """Gauss-Newton over the free parameters, on whitened rows, every active set at once.

    ``sets`` ``(N, m, d)``, starting parameters ``(N, p)``.  A set stops when
    its largest step moves the points by at most ``threshold`` mm
    (:meth:`~armcal.models.interface.FitModel.step_scale`), or when a step below
    the round-off floor no longer halves: ``1e-9`` of the reach, or for an
    ill-conditioned problem the ``cond(J_w) eps`` of the reach a backward-stable
    solve is accurate to (:data:`ROUND_OFF`).  The result is
    in the model's canonical form (angles in ``(-pi, pi]``).

    ``free`` ``(p,)`` boolean fits only those parameters, every other held where
    ``params`` has it (default: the model's free ones).  ``keep`` (one set) keeps the
    last step's rows where it was within the threshold (:class:`LastStep`).
    """
    free = model.free if free is None else np.asarray(free, dtype=bool)
    params = np.array(params, dtype=float)
    scale = model.step_scale(conditions)
    n_sets = sets.shape[0]
    iterations = np.zeros(n_sets, dtype=int)
    failed = np.zeros(n_sets, dtype=bool)
    previous = np.full(n_sets, np.inf)
    active = np.arange(n_sets)
    floor = 1e-9 * model.reach_mm  # round-off floor of a stalled step, well conditioned
    last = None
    # The rows a block at a time (the blocks made once: what a model memoizes on them serves
    # every iteration), about ROW_BLOCK rows of all the sets together.
    chunks = list(conditions.blocks(max(64, ROW_BLOCK // n_sets)))
    # A first step the model made while preparing for these rows (information.start_known).
    known = None
    if n_sets == 1 and weights is None and np.array_equal(free, model.free):
        found = known_start(model, conditions, sets[0])
        if found is not None and np.array_equal(found[0], params[0]):
            known = found[1]
    for _ in range(max_iter):
        current = params[active]
        measured, set_weights = sets[active], _for_sets(weights, active)
        blocks: list[np.ndarray] = []
        if known is not None:  # the first step's rows, made already
            rows, known = known, None
        else:
            one = keep and n_sets == 1  # its last step's rows serve the covariance
            rows = _step_rows(model, chunks, measured, current, free, set_weights, blocks, one)
        step, _, svd = rows.solve()
        full_step = np.zeros((active.size, free.size))
        full_step[:, free] = step
        params[active] = current + full_step
        iterations[active] += 1
        finite = np.all(np.isfinite(full_step), axis=1)
        failed[active[~finite]] = True
        size = np.max(np.abs(full_step * scale), axis=-1, initial=0.0)
        # A step no longer halving below what round-off resolves (cond(J) eps of the
        # reach, a backward-stable solve's error) has converged as far as it can.
        with np.errstate(over="ignore"):
            resolved = np.maximum(floor, ROUND_OFF * svd.condition_number * model.reach_mm)
        stalled = (size >= 0.5 * previous[active]) & (size < resolved)
        if settle:
            stalled |= steps_settled(size, previous[active], threshold)
        previous[active] = size
        if blocks and bool(finite[0]) and size[0] <= threshold:
            last = LastStep(np.concatenate(blocks), rows)
        active = active[finite & (size > threshold) & ~stalled]
        if active.size == 0:
            break
    converged = ~failed
    converged[active] = False
    return Solution(model.canonical(params), iterations, converged, "gauss-newton", last)
