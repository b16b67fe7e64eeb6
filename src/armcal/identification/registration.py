"""The nominal arm registered on its own, and whether the instrument moved during a campaign.

**The honest baseline.**  A calibration is worth what it buys over the arm a
user has without it: the nominal arm, placed in the instrument's frame by
fitting only where the instrument stands and where the targets sit on the tool
(the model's :attr:`~armcal.models.interface.FitModel.registration_params`), on
the same rows.  The *calibrated* instrument pose is no such baseline: it has
taken up the geometry that merges into it (joint 1's placement and zero into
the base pose, joint 6's zero and its placement along the axis into the
targets), so the nominal arm placed there misses by several times what it
misses when registered on its own.  :func:`register_nominal` fits the baseline:
Gauss-Newton over the registration alone, from the calibration's own
registration (a start within the merged geometry of the answer).

**An instrument that moved.**  A tracker nudged, a tripod that settled or a
base bolted loose during a campaign moves every later point alike, and no
geometry can take that up: the fit is inconsistent with the noise, and a
calibration may do worse on held-out poses than the nominal arm.
:func:`instrument_moved` asks whether the rows before and after a point of the
campaign (a quarter, half or three quarters of the rows, in the order
measured) are fitted far better with an instrument pose of their own, the
calibrated geometry held: an F test of the ``k`` extra registration parameters
(Bonferroni over the three splits), and a split that takes up at least half of
the residual sum of squares, so that a model's misfit spread over the poses
(which a second registration only nibbles at) is not taken for a move.  A "move"
of more than a twentieth of the reach (:data:`MOVE_MOST`) is another mistake, and a
fit that did not converge is not judged.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..distributions import f_sf
from ..models import Conditions, FitModel
from ..numerics import point_norms, rms, solve_least_squares
from .solvers import gauss_newton

__all__ = [
    "MOVE_ALPHA",
    "MOVE_MOST",
    "MOVE_SHARE",
    "MOVE_SPLITS",
    "SCREEN_SHARE",
    "Baseline",
    "Movement",
    "fit_registration",
    "instrument_moved",
    "register_nominal",
]

#: Where the campaign is split, as fractions of its rows in the order measured.
MOVE_SPLITS = (0.25, 0.5, 0.75)

#: Significance of the F test of a move, over all splits (Bonferroni).
MOVE_ALPHA = 1e-3

#: The least share of the residual sum of squares a second instrument pose must take
#: up to be called a move: a misfit spread over the poses (compliance, a wrong
#: joint map) is fitted a little better by any extra parameters, never by half.
MOVE_SHARE = 0.5

#: The largest move (RMS per point of how far the two registrations put the rows apart,
#: as a fraction of the reach) taken for an instrument that moved: a tracker knocked or a
#: tripod that settles moves the points by millimetres, not by a twentieth of the arm;
#: a larger "move" is another mistake (a mirrored frame, a wrong joint map), whose fit the
#: second registration only happens to shrink.
MOVE_MOST = 0.05

#: Gauss-Newton's step tolerance (relative to the reach) and iteration cap here.
_TOL, _MAX_ITER = 1e-10, 30


@dataclass(frozen=True, eq=False)
class Baseline:
    """The nominal arm registered on its own to measured rows.

    Attributes
    ----------
    params : ndarray, shape (p_arm,)
        The geometric arm's parameters (:attr:`~armcal.models.interface.FitModel.arm`):
        its registration fitted, every other at nominal; internal units.
    rms_per_point_mm : float
        Its residual RMS per point (positions) on the rows fitted, mm.
    rows : int
        The rows fitted.
    """

    params: np.ndarray
    rms_per_point_mm: float
    rows: int

    def __repr__(self) -> str:
        return (
            f"Baseline(nominal arm registered on {self.rows} rows: RMS per point "
            f"{self.rms_per_point_mm:.4g} mm)"
        )


def fit_registration(
    model: FitModel,
    conditions: Conditions,
    points: np.ndarray,
    start: np.ndarray,
    free: np.ndarray,
) -> np.ndarray | None:
    """``start`` with the parameters ``free`` ``(p,)`` fitted to ``points`` ``(m, d)`` by
    Gauss-Newton on the model's whitened rows, every other held (None if it fails)."""
    if not free.any():
        return start
    threshold = _TOL * model.reach_mm
    found = gauss_newton(
        model, conditions, points[None], start[None], None, threshold, _MAX_ITER, free=free
    )
    params = found.params[0]
    return params if bool(np.all(np.isfinite(params))) else None


def register_nominal(
    model: FitModel,
    conditions: Conditions,
    points: np.ndarray,
    params: np.ndarray,
    *,
    used: np.ndarray | None = None,
) -> Baseline | None:
    """The nominal arm of ``model`` registered on its own to the rows ``used``.

    Parameters
    ----------
    model : FitModel
        The model calibrated (prepared for these rows); its geometric arm
        (:attr:`~armcal.models.interface.FitModel.arm`) is registered.
    conditions : Conditions
        The rows, anchored as the fit saw them.
    points : ndarray, shape (m, d)
        The measured points, anchored as the fit saw them, mm.
    params : ndarray, shape (p,)
        The calibration's parameters: its registration is where the fit starts.
    used : ndarray of bool, shape (m,), optional
        The rows the calibration kept (default: all).

    Returns
    -------
    Baseline or None
        None when the rows cannot place the nominal arm (the fit fails).

    Examples
    --------
    >>> from armcal.models import PlanarArm, forward_kinematics
    >>> arm = PlanarArm([260.0, 180.0], base_offset=True)
    >>> q = np.radians([[0, 0], [0, 90], [90, 90], [45, -120], [-60, 30]])
    >>> truth = np.array([1.5, -0.6, 0.01, -0.01, 100.0, 50.0])
    >>> rows = arm.conditions(q)
    >>> found = register_nominal(arm, rows, forward_kinematics(arm, q, truth), truth)
    >>> found.params[:4].tolist(), bool(found.rms_per_point_mm > 1.0)
    ([0.0, 0.0, 0.0, 0.0], True)
    """
    arm = model.arm
    free = np.asarray(arm.registration_params, dtype=bool)
    start = np.where(free, model.arm_params(np.asarray(params, dtype=float)), arm.held_values)
    used = np.ones(conditions.m, dtype=bool) if used is None else np.asarray(used, dtype=bool)
    rows = conditions if used.all() else conditions.take(used)
    kept = np.asarray(points, dtype=float)[used]
    fitted = fit_registration(arm, rows, kept, start, free)
    if fitted is None:
        return None
    d = arm.position_dim
    miss = point_norms((kept - arm.positions(rows, fitted))[:, :d])
    return Baseline(fitted, rms(miss), int(np.count_nonzero(used)))


@dataclass(frozen=True)
class Movement:
    """The instrument (or the arm's base) moved between two parts of a campaign.

    Attributes
    ----------
    split : int
        The index of the first row (in the order measured) after the split tried (a
        quarter, half or three quarters of the rows), the nearest to the move.
    fraction : float
        That split as a fraction of the rows.
    shift_mm : float
        RMS per point of how far the two parts' instrument poses put the rows apart, mm.
    explained : float
        The share of the residual sum of squares a pose of each part takes up.
    p_value : float
        The F test's, Bonferroni-corrected over the splits tried.
    """

    split: int
    fraction: float
    shift_mm: float
    explained: float
    p_value: float


def _whitened_residual(
    model: FitModel, conditions: Conditions, points: np.ndarray, params: np.ndarray
) -> np.ndarray:
    """Whitened residuals ``(r,)`` of ``params`` on the rows (no Jacobian)."""
    residual = points - model.positions(conditions, params)
    w = model.whitening(conditions, params)
    if w is not None:
        residual = (w @ residual[..., None])[..., 0]
    return residual.reshape(-1)


def _whitened(
    model: FitModel, conditions: Conditions, points: np.ndarray, params: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Whitened residuals ``(r,)`` of ``params`` on the rows, and their Jacobian ``(r, p)``."""
    residual = points - model.positions(conditions, params)
    jac = model.jacobian(conditions, params)
    w = model.whitening(conditions, params)
    if w is not None:
        residual = (w @ residual[..., None])[..., 0]
        jac = w @ jac
    return residual.reshape(-1), jac.reshape(-1, jac.shape[-1])


def _split_rss(
    model: FitModel,
    parts: tuple[Conditions, Conditions],
    points: tuple[np.ndarray, np.ndarray],
    params: np.ndarray,
    moved: np.ndarray,
) -> tuple[float, np.ndarray, np.ndarray]:
    """The whitened residual sum of squares of the model refitted with a registration of
    its own for the second part (Gauss-Newton over the free parameters and the second
    part's copy of the registration ``moved`` ``(p,)``, from ``params``), and the two
    parts' parameters."""
    free = np.asarray(model.free, dtype=bool)
    first, second = np.array(params, dtype=float), np.array(params, dtype=float)
    k = int(np.count_nonzero(moved))
    scale = model.step_scale(parts[0])
    for _ in range(_MAX_ITER):
        r1, j1 = _whitened(model, parts[0], points[0], first)
        r2, j2 = _whitened(model, parts[1], points[1], second)
        # Columns: the shared free parameters, then the second part's registration.  The
        # second part's rows see their own registration, not the shared one.
        top = np.hstack([j1[:, free], np.zeros((j1.shape[0], k))])
        shared = j2[:, free] * ~moved[free]
        bottom = np.hstack([shared, j2[:, moved]])
        step, _, _ = solve_least_squares(
            np.vstack([top, bottom])[None], np.concatenate([r1, r2])[None]
        )
        step = step[0]
        if not np.all(np.isfinite(step)):
            break
        shift = np.zeros_like(first)
        shift[free] = step[: int(np.count_nonzero(free))]
        own = step[-k:]
        first, second = first + shift, second + shift
        second[moved] = second[moved] - shift[moved] + own
        size = max(np.max(np.abs(shift * scale)), np.max(np.abs(own * scale[moved])))
        if size <= _TOL * model.reach_mm:
            break
    r1 = _whitened_residual(model, parts[0], points[0], first)
    r2 = _whitened_residual(model, parts[1], points[1], second)
    return float(r1 @ r1 + r2 @ r2), first, second


#: The share of the residual one linear step must take up at some split for a screened
#: test (:func:`instrument_moved`'s ``screen``) to refit: half of :data:`MOVE_SHARE`,
#: room for the curvature a refit follows beyond one step.
SCREEN_SHARE = MOVE_SHARE / 2


def _linear_shares(
    model: FitModel, residual: np.ndarray, jac: np.ndarray, rows: int, moved: np.ndarray
) -> list[float]:
    """The share of the whitened residual ``(r,)`` one Gauss-Newton step takes up at each
    split of :data:`MOVE_SPLITS`, with the free parameters' Jacobian ``jac`` ``(r, p)``
    and a copy of the registration ``moved`` for the rows after the split."""
    d = residual.size // rows
    free = np.asarray(model.free, dtype=bool)
    total = float(residual @ residual)
    shares = []
    for fraction in MOVE_SPLITS:
        after = np.arange(residual.size) >= d * round(fraction * rows)
        columns = np.hstack([jac[:, free], jac[:, moved] * after[:, None]])
        step, _, _ = solve_least_squares(columns[None], residual[None])
        left = residual - columns @ step[0]
        shares.append(1.0 - float(left @ left) / total if np.all(np.isfinite(step)) else 0.0)
    return shares


def instrument_moved(
    model: FitModel,
    conditions: Conditions,
    points: np.ndarray,
    params: np.ndarray,
    *,
    used: np.ndarray | None = None,
    screen: bool = False,
) -> Movement | None:
    """Whether the rows before and after some point were measured from another instrument pose.

    Parameters
    ----------
    model, conditions, points, params
        The calibrated (prepared) model, its anchored rows and points, and the
        fitted parameters (where the refits start).
    used : ndarray of bool, shape (m,), optional
        The rows in the fit.
    screen : bool
        Refit only where one linear step, at the fit, takes up
        :data:`SCREEN_SHARE` of the residual or more at some split: one Jacobian of
        the rows and three small least-squares solves instead of three refits, for a
        fit that no chi-square flags (sigma estimated), so every calibration can be
        asked.

    Returns
    -------
    Movement or None
        The split that explains the most, when it passes both tests (module
        notes); None otherwise, or when the parts are too small to tell.

    Notes
    -----
    At each split the whole model is refitted with a second copy of its registration
    for the rows after it (Gauss-Newton from the calibration): the nested F test of
    those ``k`` parameters.  Holding the calibrated geometry instead would not do: a
    calibration of a campaign whose instrument moved has bent its geometry towards
    the move, and a second registration alone then takes up only part of it.
    """
    points = np.asarray(points, dtype=float)
    m = conditions.m
    used = np.ones(m, dtype=bool) if used is None else np.asarray(used, dtype=bool)
    moved = np.asarray(model.registration_params, dtype=bool) & np.asarray(model.free)
    k = int(np.count_nonzero(moved))
    d = model.point_dim
    rows = np.flatnonzero(used)
    residual_dof = d * rows.size - model.n_free - k
    if k == 0 or residual_dof <= 0:
        return None
    whole = conditions.take(rows)
    if screen:
        residual, jac = _whitened(model, whole, points[rows], params)
    else:
        residual = _whitened_residual(model, whole, points[rows], params)
    total = float(residual @ residual)
    if total <= 0:
        return None
    if screen and max(_linear_shares(model, residual, jac, rows.size, moved)) < SCREEN_SHARE:
        return None
    best: Movement | None = None
    for fraction in MOVE_SPLITS:
        split = round(fraction * rows.size)
        parts = (rows[:split], rows[split:])
        if min(d * part.size for part in parts) <= 2 * k:  # a part too small to place
            continue
        conditions_of = (conditions.take(parts[0]), conditions.take(parts[1]))
        split_rss, first, second = _split_rss(
            model, conditions_of, (points[parts[0]], points[parts[1]]), params, moved
        )
        explained = 1.0 - split_rss / total
        if split_rss <= 0:
            p_value = 0.0
        else:
            statistic = max(total - split_rss, 0.0) / k / (split_rss / residual_dof)
            p_value = float(f_sf(k, residual_dof, statistic)) * len(MOVE_SPLITS)
        if p_value >= MOVE_ALPHA or explained < MOVE_SHARE:
            continue
        apart = model.positions(whole, first) - model.positions(whole, second)
        shift = rms(point_norms(apart[:, : model.position_dim]))
        if not shift <= MOVE_MOST * model.reach_mm:  # (a NaN too)
            continue
        found = Movement(int(rows[split]), fraction, shift, float(explained), min(p_value, 1.0))
        if best is None or found.explained > best.explained:
            best = found
    return best
