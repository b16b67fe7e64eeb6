"""What measurements tell of any model: the whitened Jacobian, its covariance, predicted errors.

One place for each of these meanings, for every family of arm
(:class:`~armcal.models.interface.FitModel`):

* :func:`whitened_free_jacobian` -- ``W_i J_i`` over the free parameters, the
  rows whose Gram matrix is the information (:mod:`armcal.noise`);
* :func:`covariance_factor_from` -- ``G`` with ``(J_w^T J_w)^-1 = G G^T`` from
  those rows, by the rank policy of :mod:`armcal.numerics` (never by inverting
  ``J_w^T J_w``);
* :func:`tip_variances` -- the variance ``tr(J(x) C J(x)^T)`` of a predicted
  point at conditions ``x`` from a parameter covariance ``C``, and
  :func:`mean_tip_variance`, its mean over many test rows for a stack of
  covariances (from the test rows' Gram matrix, so many plans cost one pass);
* :class:`BlockInformation` -- what plans tell about the free parameters, for
  design and its criteria, from those rows.

A family may compute these faster where its structure allows (the planar arm's
covariance from its plan's own factorization); the numbers are the same.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, replace
from functools import cached_property
from typing import TypeVar

import numpy as np

from ..errors import NotIdentifiableError
from ..numerics import (
    COND_WARN,
    RANK_RTOL,
    RowTriangle,
    ScaledSVD,
    gram_of_factor,
    scaled_svd,
)
from .identifiability import Identifiability, combination, listing, row_echelon
from .interface import ROW_BLOCK, Conditions, FitModel, Loads, array_key

__all__ = [
    "BlockInformation",
    "Linearization",
    "column_identifiability",
    "covariance_factor_from",
    "display_std",
    "factor_from_svd",
    "identified_or_prepared",
    "identifying",
    "known_start",
    "mean_tip_variance",
    "met_rows",
    "nominal_triangle_known",
    "pose_derivative",
    "predicted_covariance",
    "refit_free",
    "start_known",
    "surely_unidentified",
    "tip_variances",
    "weighted_whitening",
    "whitened_blocks",
    "whitened_free_jacobian",
    "whitened_triangle",
]


def whitened_blocks(
    model: FitModel, conditions: Conditions, params: np.ndarray | None = None
) -> np.ndarray:
    """``W_i J_i`` over the free parameters, row by row ``(..., m, d, p_f)``, at ``params``.

    ``J`` the model's Jacobian and ``W_i`` its relative whitening
    (:meth:`~armcal.models.interface.FitModel.whitening`, the identity for isotropic
    iid noise): ``(W_i J_i)^T W_i J_i`` is row ``i``'s information.
    """
    jac = model.jacobian(conditions, params)[..., model.free]  # (..., m, d, p_f)
    w = model.whitening(conditions, params)
    return jac if w is None else w @ jac


def whitened_free_jacobian(
    model: FitModel, conditions: Conditions, params: np.ndarray | None = None
) -> np.ndarray:
    """:func:`whitened_blocks` stacked ``(..., m d, p_f)``: ``sigma_ref^2 (J_w^T J_w)^-1`` is
    the generalized least-squares covariance of the free parameters."""
    jac = whitened_blocks(model, conditions, params)
    return jac.reshape(*jac.shape[:-3], -1, model.n_free)


def whitened_triangle(
    model: FitModel,
    conditions: Conditions,
    params: np.ndarray | None = None,
    *,
    whiten: bool = True,
) -> RowTriangle:
    """:func:`whitened_free_jacobian`'s rows reduced to their triangle a block of rows at a
    time (:meth:`~armcal.models.interface.Conditions.blocks`): the covariance and the
    rank analysis need no more, and no ``(m, d, p_f)`` array is held; ``whiten=False``
    the Jacobian's own rows.  At the nominal parameters it is made once for the
    conditions (:meth:`~armcal.models.interface.Conditions.memo`): a plan's criteria
    and its covariance share it."""
    # Where the whitening is the identity the two are one triangle (the rank analysis and
    # the covariance of one plan: one pass of the model for both).
    if params is None and (whiten or model.whitening(conditions, None) is None):
        return conditions.memo(
            (model, _NOMINAL_TRIANGLE), lambda: _row_triangle(model, conditions, None, True)
        )
    if params is not None:  # what a refit left, its whitening the identity (_refit_blocks)
        kept: RowTriangle | None = conditions.latest(_TRIANGLE_AT, (model, array_key(params)))
        if kept is not None:
            return kept
    return _row_triangle(model, conditions, params, whiten)


def nominal_triangle_known(model: FitModel, conditions: Conditions, rows: RowTriangle) -> None:
    """Give :func:`whitened_triangle` at the nominal parameters, for a model whose
    whitening of these conditions is the identity: ``rows`` of its free columns there (any
    rows with their Gram matrix ``J^T J``), which a family made in another form while
    preparing the model (a spatial arm's, in the robot's own frame), sparing a pass."""
    conditions.memo((model, _NOMINAL_TRIANGLE), lambda: rows)


#: The key of the nominal triangle in :meth:`~armcal.models.interface.Conditions.memo`.
_NOMINAL_TRIANGLE = "whitened triangle"


def start_known(
    model: FitModel,
    conditions: Conditions,
    points: np.ndarray,
    params: np.ndarray,
    rows: RowTriangle,
) -> None:
    """Leave where a fit of ``model`` to ``points`` ``(m, d)`` starts, ``params`` ``(p,)``,
    and its first step there: ``rows`` of the whitened free columns with the whitened
    residuals beside them (:class:`~armcal.numerics.RowTriangle`).  A family that made
    them in another form while preparing the model for these rows (a spatial arm's
    registration, and its Jacobian in the robot's own frame) spares a registration and
    a pass (:meth:`~armcal.models.interface.FitModel.start`, Gauss-Newton)."""
    conditions.keep(_START, (model, array_key(points)), (params, rows))


def known_start(
    model: FitModel, conditions: Conditions, points: np.ndarray
) -> tuple[np.ndarray, RowTriangle] | None:
    """What :func:`start_known` left for ``model`` and these very ``points``, or None."""
    found: tuple[np.ndarray, RowTriangle] | None = conditions.latest(
        _START, (model, array_key(points))
    )
    return found


#: The slot of :func:`start_known` in :meth:`~armcal.models.interface.Conditions.keep`.
_START = "start"

#: The slot of the triangle a refit's last pass made at its result (:func:`_refit_blocks`).
_TRIANGLE_AT = "triangle at"


def _row_triangle(
    model: FitModel, conditions: Conditions, params: np.ndarray | None, whiten: bool
) -> RowTriangle:
    rows = RowTriangle(model.n_free)
    for block, _ in conditions.blocks():
        jac = (
            whitened_blocks(model, block, params)
            if whiten
            else model.jacobian(block, params)[..., model.free]
        )
        rows.add(jac.reshape(*jac.shape[:-3], -1, model.n_free))
    return rows


def weighted_whitening(
    whitening: np.ndarray | None, weights: np.ndarray | None, dim: int
) -> np.ndarray | None:
    """``sqrt(w_i) W_i`` ``(..., m, d, d)``: a whitening with extra weights per row.

    ``weights`` ``(m,)`` or ``(N, m)`` (robust fitting; 0 leaves a row out) scale
    the rows of ``whitening`` (None: the identity) of dimension ``dim``; None
    when both are None.
    """
    if weights is None:
        return whitening
    root = np.sqrt(weights)[..., None, None]
    return root * (np.eye(dim) if whitening is None else whitening)


def covariance_factor_from(
    whitened: np.ndarray, free: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """``G`` ``(..., p, p_f)`` with ``(J_w^T J_w)^-1 = G G^T``, and the full-rank mask ``(...)``.

    Parameters
    ----------
    whitened : ndarray, shape (..., r, p_f)
        Whitened rows over the free parameters (:func:`whitened_free_jacobian`).
    free : ndarray of bool, shape (p,)
        Which of the ``p`` parameters the columns are; fixed ones get zero rows.

    Returns
    -------
    factor : ndarray, shape (..., p, p_f)
        ``inf`` where the rank policy calls the rows singular.
    ok : ndarray of bool, shape (...)

    Examples
    --------
    >>> g, ok = covariance_factor_from(np.array([[2.0], [0.0]]), np.array([True, False]))
    >>> (g @ g.T).tolist(), bool(ok)
    ([[0.25, 0.0], [0.0, 0.0]], True)
    """
    return factor_from_svd(scaled_svd(whitened), free)


def factor_from_svd(svd: ScaledSVD, free: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """:func:`covariance_factor_from` given the scaled SVD of the whitened rows (of the
    whole matrix, or of its triangle, :func:`whitened_triangle`)."""
    factor, ok = svd.inverse_gram_factor()
    p_f = svd.singular_values.shape[-1]
    g = np.zeros((*factor.shape[:-2], free.size, p_f))
    g[..., free, :] = np.where(ok[..., None, None], factor, 0.0)
    ok = ok & np.all(np.isfinite(g), axis=(-2, -1))
    return np.where(ok[..., None, None], g, np.inf), ok


def column_identifiability(
    model: FitModel, conditions: Conditions, params: np.ndarray | None = None
) -> tuple[Identifiability, ScaledSVD]:
    """Rank analysis of the free columns of ``model``'s Jacobian at ``params`` (nominal when
    None).

    The one rank policy of :mod:`armcal.numerics` on unit-norm columns; the null
    and poorly determined directions in display units (mm, deg).
    """
    svd = whitened_triangle(model, conditions, params, whiten=False).svd()
    names = model.free_names
    scale = model.display_scale[model.free]
    null = svd.directions(RANK_RTOL)
    weak = svd.directions(1.0 / COND_WARN)
    bad: tuple[str, ...] = ()
    if null.shape[0]:
        basis, _ = np.linalg.qr((null * svd.column_norms).T)
        bad = tuple(
            n for n, w in zip(names, np.linalg.norm(basis, axis=1), strict=True) if w > 1e-8
        )
    null_rows = row_echelon(null * scale)
    weak_rows = row_echelon(weak * scale, tol=1e-3)
    info = Identifiability(
        rank=int(svd.rank),
        n_params=model.n_free,
        singular_values=svd.singular_values / np.sqrt(max(conditions.m, 1)),
        unidentifiable=bad,
        combinations=tuple(combination(v, names) for v in null_rows),
        poorly_determined=tuple(combination(v, names, drop=1e-3) for v in weak_rows),
    )
    return info, svd


def identifiable_or_raise(
    model: FitModel, conditions: Conditions, what: str, advice: str
) -> Identifiability:
    """The model's identifiability at these rows; when they cannot identify every free
    parameter, NotIdentifiableError naming ``what``, the combinations, and ``advice``."""
    info, _ = model.identifiability(conditions)
    if info.identifiable:
        return info
    m, p = conditions.m, model.n_free
    raise NotIdentifiableError(
        f"the {m} rows cannot identify all {p} parameters of {what} (rank {info.rank} of "
        f"{p}): not identifiable: {listing(info.unidentifiable) or '(none)'}; {advice}",
        list(info.combinations),
    )


def identifying(
    model: FitModel, conditions: Conditions, points: np.ndarray | None = None
) -> FitModel:
    """The model for these rows: as given where they identify its free parameters, else
    :meth:`~armcal.models.interface.FitModel.prepared` for them (and for the measured
    ``points``, when given).

    An over-complete family (a spatial arm straight from its robot file) then holds
    what the rows cannot separate, by its fixed rule, so that a Python user passes the
    arm as loaded, as the command line does; a model already prepared (or a minimal
    one the rows identify) is kept as it is, so a caller's choice is never redone.  A
    minimal family the rows do not identify is itself: the caller's check then says
    what the rows miss.
    """
    if not surely_unidentified(model) and model.identifiability(conditions)[0].identifiable:
        return model
    return model.prepared(conditions, points)


def met_rows(model: FitModel, q: np.ndarray) -> Conditions:
    """The rows of poses ``q`` ``(m, n)`` moved onto the instrument, of those that meet it
    (:meth:`~armcal.models.interface.FitModel.meeting_poses`; every pose for a tracker):
    what a probe of random poses judges a model's identifiable set on (a camera's random
    pose seldom sees the board)."""
    moved, met = model.meeting_poses(q)
    return model.plan_conditions(moved[met])


def identified_or_prepared(
    model: FitModel,
    conditions: Conditions,
    check: Callable[[FitModel], _Checked],
    points: Callable[[], np.ndarray] | None = None,
) -> tuple[FitModel, _Checked]:
    """The model for these rows and what ``check`` (which raises NotIdentifiableError
    where they do not identify it) finds of it: the model as given where the rows
    identify it, else :meth:`~armcal.models.interface.FitModel.prepared` for them (and
    for the measured ``points()``, when given).  A model that surely needs preparing is
    not checked as given (:func:`surely_unidentified`); a minimal family the rows do not
    identify raises its check's error, which says what they miss."""
    unseen = None
    if not surely_unidentified(model):
        try:
            return model, check(model)
        except NotIdentifiableError as error:
            unseen = error
    ready = model.prepared(conditions, None if points is None else points())
    if ready is model:
        assert unseen is not None  # (a family with a rank bound prepares)
        raise unseen
    return ready, check(ready)


def surely_unidentified(model: FitModel) -> bool:
    """Whether ``model`` has more free parameters than any rows can identify
    (:attr:`~armcal.models.interface.FitModel.rank_bound`): it needs preparing, and a
    rank analysis would only say so."""
    bound = model.rank_bound
    return bound is not None and model.n_free > bound


#: What a check of :func:`identified_or_prepared` finds.
_Checked = TypeVar("_Checked")

#: Gauss-Newton steps at most of :func:`refit_free` (it converges in a few).
_REFIT_STEPS = 30


def refit_free(model: FitModel, conditions: Conditions, params: np.ndarray) -> np.ndarray:
    """The free parameters that reproduce ``params``' points at these rows, the held ones
    at their held values: Gauss-Newton from ``params`` (a held parameter of a spatial arm
    merges by an exact symmetry of the kinematics, so the points are reproduced to
    round-off).  What :meth:`~armcal.models.interface.FitModel.expressed` does for a
    family whose held parameters are not zero."""
    goal = model.positions(conditions, params)
    free = model.free
    out = np.where(free, np.asarray(params, dtype=float), model.held_values)
    tol = 1e-12 * model.reach_mm
    if conditions.m > ROW_BLOCK:
        return _refit_blocks(model, conditions, goal, out, tol)
    for _ in range(_REFIT_STEPS):
        miss = (goal - model.positions(conditions, out)).reshape(-1)
        jac = model.jacobian(conditions, out)[..., free].reshape(miss.size, -1)
        step, *_ = np.linalg.lstsq(jac, miss, rcond=None)
        out[free] += step
        if np.max(np.abs(jac @ step), initial=0.0) <= tol:
            break
    return out


def _refit_blocks(
    model: FitModel, conditions: Conditions, goal: np.ndarray, out: np.ndarray, tol: float
) -> np.ndarray:
    """:func:`refit_free` of more rows than a block: one pass of the model per step, a
    block of rows at a time (the points from the Jacobian's pass), the step from the
    rows' triangle.  Whether a step moved any point by more than ``tol`` is read from
    the next pass's Jacobian (the same to first order in the step): a last pass then
    only confirms it."""
    free, n_free = model.free, model.n_free
    first = next(iter(conditions.blocks()))[0]
    plain = model.whitening(first, out) is None  # then the rows are the covariance's
    step = None
    for _ in range(_REFIT_STEPS + 1):
        rows, moved = RowTriangle(n_free), 0.0
        for block, part in conditions.blocks():
            jac = model.jacobian(block, out)[..., free].reshape(-1, n_free)
            miss = (goal[part] - model.positions(block, out)).reshape(-1)
            if step is not None:
                moved = max(moved, float(np.max(np.abs(jac @ step), initial=0.0)))
            rows.add(jac, miss)
        if step is not None and moved <= tol:
            if plain:  # the last pass was at the result: its triangle is the covariance's
                conditions.keep(_TRIANGLE_AT, (model, array_key(out)), rows)
            break
        step = rows.solve()[0]
        out[free] += step
    return out


def predicted_covariance(
    model: FitModel, conditions: Conditions, sigma_mm: float, params: np.ndarray | None = None
) -> tuple[np.ndarray, bool]:
    """``sigma^2 G G^T`` ``(p, p)``: the predicted covariance of the parameters, and whether
    the rows identify them (:meth:`~armcal.models.interface.FitModel.covariance_factor`;
    ``inf`` where not)."""
    factor, ok = model.covariance_factor(conditions, params)
    return sigma_mm**2 * gram_of_factor(factor, ok), bool(ok)


def display_std(model: FitModel, covariance: np.ndarray) -> np.ndarray:
    """Standard deviations ``(..., p)`` in display units of a covariance ``(..., p, p)``."""
    return np.sqrt(np.diagonal(covariance, axis1=-2, axis2=-1)) * model.display_scale


def tip_variances(jacobian: np.ndarray, covariance: np.ndarray) -> np.ndarray:
    """``tr(J_i C J_i^T)`` ``(..., k)``: the variance of every predicted point, mm^2.

    ``jacobian`` ``(..., k, d, p)`` of the points at ``k`` rows, ``covariance``
    ``(..., p, p)`` of the parameters (internal units); clipped at 0 against
    round-off.

    Examples
    --------
    >>> tip_variances(np.array([[[1.0, 0.0], [0.0, 1.0]]]), np.eye(2) * 0.01).tolist()
    [0.02]
    """
    jacobian, covariance = np.asarray(jacobian), np.asarray(covariance)
    if covariance.ndim == 2:  # one covariance: one BLAS product of every row's rows
        weighted = (jacobian.reshape(-1, jacobian.shape[-1]) @ covariance).reshape(jacobian.shape)
    else:
        weighted = jacobian @ covariance[..., None, :, :]
    return np.clip(np.einsum("...kia,...kia->...k", weighted, jacobian), 0.0, None)


def mean_tip_variance(jacobian: np.ndarray, covariance: np.ndarray) -> np.ndarray:
    """The mean of :func:`tip_variances` over the ``k`` test rows, for stacks of covariances.

    ``jacobian`` ``(k, d, p)`` (one set of test rows), ``covariance`` ``(..., p, p)``:
    ``mean_k tr(J_k C J_k^T) = tr(C G)`` with ``G = mean_k J_k^T J_k``, one
    ``p x p`` product per covariance however many test rows.

    Examples
    --------
    >>> j = np.array([[[1.0, 0.0], [0.0, 1.0]], [[2.0, 0.0], [0.0, 0.0]]])
    >>> float(mean_tip_variance(j, np.eye(2)))   # (2 + 4) / 2
    3.0
    """
    gram = np.einsum("kia,kib->ab", jacobian, jacobian) / jacobian.shape[0]
    return np.clip(np.einsum("...ab,ba->...", covariance, gram), 0.0, None)


def pose_derivative(
    value_at: Callable[[np.ndarray], np.ndarray], q: np.ndarray, step: float = 1e-6
) -> np.ndarray:
    """``d value_i / d q_i`` ``(..., m, n)`` by central differences of step ``step`` (rad).

    ``value_at`` maps poses ``(..., m, n)`` to one value per pose ``(..., m)`` that
    depends on that pose only, so one pair of evaluations per joint moves every pose
    at once; values of several numbers a pose ``(..., m, c)`` give ``(..., m, c, n)``.
    """
    n = q.shape[-1]
    return np.stack(
        [(value_at(q + step * e) - value_at(q - step * e)) / (2 * step) for e in np.eye(n)],
        axis=-1,
    )


@dataclass(frozen=True, eq=False)
class Linearization:
    """Rows' whitened blocks and, where the family has it in closed form, their pullback.

    Attributes
    ----------
    blocks : ndarray, shape (rows, d, p_f)
        ``W J[:, free]`` (:func:`whitened_blocks`).
    pullback : callable or None
        ``G -> <G, d blocks / d q>`` ``(rows, d, p_f) -> (rows, n)``, every row in
        its own readings: the gradient of a weighted sum of the blocks, all the
        design's criteria need; None where the family has no closed form for these
        rows (central differences then).
    """

    blocks: np.ndarray
    pullback: Callable[[np.ndarray], np.ndarray] | None


class BlockInformation:
    """The :class:`~armcal.models.interface.PlanInformation` of any model, from its Jacobian.

    A pose's information is the Gram matrix of its whitened free rows
    (:func:`whitened_blocks`, every target of the pose) with the columns divided
    by ``scale`` ``(p_f,)``: the design coordinates (default: the free parameters
    in internal units).  Gradients in the poses come from ``linearize`` where the
    family gives a pullback, else central differences (:func:`pose_derivative`).

    Parameters
    ----------
    model : FitModel
    q : ndarray, shape (..., m, n)
        Plans (rad); leading axes batch over plans.
    loads : Loads, optional
        Every pose's loads ``(m,)`` (default: the model's).
    scale : ndarray, shape (p_f,), optional
        The design coordinates' column scale.
    unit_columns : bool
        The criteria's singular values with unit-norm columns per plan (how
        orthogonal the columns are), not those of the design coordinates.
    linearize : callable, optional
        The family's :class:`Linearization` of rows: their blocks (the same as
        :func:`whitened_blocks`) and the gradient's pullback, from one pass of
        its kinematics.
    rows : Conditions, optional
        One plan's rows, made already by ``model.plan_conditions(q, loads)``: what is
        memoized on them (:meth:`~armcal.models.interface.Conditions.memo`) is shared.
    """

    def __init__(
        self,
        model: FitModel,
        q: np.ndarray,
        loads: Loads | None = None,
        *,
        scale: np.ndarray | None = None,
        unit_columns: bool = False,
        linearize: Callable[[Conditions], Linearization] | None = None,
        rows: Conditions | None = None,
    ) -> None:
        self.model = model
        if rows is not None:  # the cached property, given
            self.__dict__["_rows"] = rows
        self.q = np.asarray(q, dtype=float)
        self.loads = loads
        self.scale = np.ones(model.n_free) if scale is None else np.asarray(scale, dtype=float)
        self.unit_columns = unit_columns
        self.linearize = linearize

    @property
    def rows_per_pose(self) -> int:
        return max(1, len(self.model.target_labels))

    def _conditions(self, q: np.ndarray) -> Conditions:
        """Every target of every pose of ``q`` ``(..., m, n)``, plan after plan."""
        flat = q.reshape(-1, q.shape[-1])
        loads = self.loads
        if loads is not None and loads.n_rows != q.shape[-2]:
            raise ValueError(
                f"loads must have one row per pose ({q.shape[-2]}), got {loads.n_rows}"
            )
        if loads is not None and flat.shape[0] != loads.n_rows:  # the same loads in every plan
            plans = flat.shape[0] // loads.n_rows
            loads = Loads(np.tile(loads.payload_kg, plans), np.tile(loads.force_n, (plans, 1)))
        return self.model.plan_conditions(flat, loads)

    def _blocks_at(self, q: np.ndarray, rows: Conditions | None = None) -> np.ndarray:
        rows = self._conditions(q) if rows is None else rows
        blocks = whitened_blocks(self.model, rows) / self.scale
        return blocks.reshape(*q.shape[:-1], -1, self.model.n_free)

    @cached_property
    def _rows(self) -> Conditions:
        """The rows of the plans themselves (every target of every pose)."""
        return self._conditions(self.q)

    @cached_property
    def _linear(self) -> Linearization | None:
        return None if self.linearize is None else self.linearize(self._rows)

    @cached_property
    def _blocks(self) -> np.ndarray:
        if self._linear is None:
            return self._blocks_at(self.q, self._rows)
        blocks = self._linear.blocks / self.scale
        return blocks.reshape(*self.q.shape[:-1], -1, self.model.n_free)

    def blocks(self) -> np.ndarray:
        return self._blocks

    @cached_property
    def _triangle(self) -> np.ndarray | None:
        """For one large plan (more than :data:`~armcal.models.interface.ROW_BLOCK` rows)
        the triangle of its design rows ``W J / scale / sqrt(rows)``
        (:func:`whitened_triangle`, which its covariance shares): what its criteria
        need, without its ``(m, d, p_f)`` blocks; None for plans whose blocks are
        made (a stack of plans, a small one, or one whose gradient was asked for)."""
        if self.q.ndim != 2 or "_blocks" in self.__dict__ or self._rows.m <= ROW_BLOCK:
            return None
        count = self.q.shape[0] * self.rows_per_pose
        return whitened_triangle(self.model, self._rows).triangle() / (self.scale * np.sqrt(count))

    def information(self) -> np.ndarray:
        if self._triangle is not None:
            return self._triangle.T @ self._triangle
        f = self._blocks
        rows = f.shape[-3] * self.rows_per_pose
        return np.einsum("...mrp,...mrq->...pq", f, f) / rows

    def _central_difference(self, value) -> np.ndarray:
        """``d value(F_i) / d q_i`` ``(..., m, n)`` of a per-pose function of the blocks.

        Every pose moves by the same joint shift, so the plans' rows, shifted, are the
        shifted plans' rows where they carry nothing else that depends on the poses
        (no reference orientations): what the model chose for them (an instrument's
        feature) is chosen once."""
        rows = self._rows
        if rows.frames is not None:
            return pose_derivative(lambda q: value(self._blocks_at(q)), self.q)
        base = np.asarray(rows.q)

        def shifted(q: np.ndarray) -> np.ndarray:
            shift = (q - self.q).reshape(-1, q.shape[-1])[0]
            return value(self._blocks_at(q, replace(rows, q=base + shift)))

        return pose_derivative(shifted, self.q)

    def _quadratic_derivative(
        self, weight: np.ndarray, weighted: np.ndarray | None = None
    ) -> np.ndarray:
        """``d (sum_r f_r^T A f_r) / d q_i`` ``(..., m, n)`` of every pose's blocks ``f``,
        ``A`` = ``weight`` (broadcast over the plans' poses): ``<2 f A, d f / d q>``;
        ``weighted`` is ``f A`` where the caller has it."""
        linear = self._linear
        if linear is None or linear.pullback is None:
            return self._central_difference(
                lambda f: np.einsum("...rp,...pq,...rq->...", f, weight, f)
            )
        f = self._blocks  # (..., m, r d, p_f)
        cotangent = 2.0 * (f @ weight if weighted is None else weighted) / self.scale
        rows = linear.pullback(cotangent.reshape(linear.blocks.shape))
        return rows.reshape(*self.q.shape[:-1], -1, self.q.shape[-1]).sum(axis=-2)

    def gradient(self, phi: np.ndarray) -> np.ndarray:
        phi = np.asarray(phi, dtype=float)
        return self._quadratic_derivative(phi if phi.ndim == 2 else phi[..., None, :, :])

    def pose_variance(self, m_inv: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        count = self.rows_per_pose
        weighted = self._blocks @ m_inv
        value = np.sum(weighted * self._blocks, axis=(-2, -1)) / count
        return value, self._quadratic_derivative(m_inv, weighted) / count

    @cached_property
    def _svd(self) -> ScaledSVD:
        if self._triangle is not None:
            return scaled_svd(self._triangle)
        f = self._blocks
        rows = f.shape[-3] * self.rows_per_pose
        stacked = f.reshape(*f.shape[:-3], -1, f.shape[-1]) / np.sqrt(rows)
        return scaled_svd(stacked)

    def svd(self) -> ScaledSVD:
        return self._svd

    def singular_values(self) -> np.ndarray:
        if self.unit_columns:
            return self._svd.truncated
        if self._triangle is not None:
            s = np.linalg.svd(self._triangle, compute_uv=False)
            return np.where(self._svd.kept, _padded_values(s, self.model.n_free), 0.0)
        f = self._blocks
        rows = f.shape[-3] * self.rows_per_pose
        stacked = f.reshape(*f.shape[:-3], -1, f.shape[-1]) / np.sqrt(rows)
        return np.where(self._svd.kept, np.linalg.svd(stacked, compute_uv=False), 0.0)

    @cached_property
    def _identified(self) -> Identifiability:
        return self.model.check_identifiable(self._rows)  # raises: nothing cached

    def check_identifiable(self) -> Identifiability:
        return self._identified

    @cached_property
    def _nominal_factor(self) -> tuple[np.ndarray, np.ndarray]:
        return self._factor(None)

    def covariance_factor(self, params: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
        return self._nominal_factor if params is None else self._factor(params)

    def _factor(self, params: np.ndarray | None) -> tuple[np.ndarray, np.ndarray]:
        if self.q.ndim == 2:  # one plan: the model's own (its rank policy and weights)
            return self.model.covariance_factor(self._rows, params)
        rows = whitened_blocks(self.model, self._rows, params)  # plan after plan
        stacked = rows.reshape(*self.q.shape[:-2], -1, self.model.n_free)
        return covariance_factor_from(stacked, self.model.free)


def _padded_values(values: np.ndarray, p: int) -> np.ndarray:
    """Singular values ``(k,)`` padded with zeros to ``(p,)``."""
    return np.concatenate([values, np.zeros(p - values.shape[-1])])
