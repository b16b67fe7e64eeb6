"""The planar arm's closed form: one linear least-squares solve gives the global optimum.

The planar model is *linear* in the complex link vectors
``z_k = (l_k + dl_k) exp(i dtheta_k)`` and the base ``x0 + i y0``::

    x + i y = (x0 + i y0) + sum_k z_k exp(i theta_k)

so one linear least-squares solve gives the global optimum, and
``z_k -> (dl_k, dtheta_k) = (|z_k| - l_k, arg z_k)`` maps it back (a bijection
for ``|z_k| > 0``).  No iterations, no starting point, and it batches over
trials: many measurement sets share one factorization.

The solve rests on one thin QR of the plan's regressor ``H``
(:func:`armcal.models.planar.information.scaled_jacobian`, ``2m x p``, memory
``O(m p)``) and the SVD of its ``p x p`` triangle, with the rank policy of
:mod:`armcal.numerics`: no normal equations, so accuracy degrades with
``cond(J)``, never ``cond(J)^2``, and a singular plan is a
:class:`~armcal.errors.NotIdentifiableError` that names the unseen combinations.

Weighted models (anisotropic, per-row or encoder noise; robust weights) solve
the same linear problem on whitened rows (:func:`weighted_closed_form`); a
model with fixed parameters has no closed form, but the closed form of the
same arm with every parameter free, projected onto its free ones, is where
Gauss-Newton starts (:func:`projected_start`).
"""

from __future__ import annotations

import numpy as np

from ...numerics import LinearLeastSquares, factor_least_squares, solve_least_squares
from ..information import weighted_whitening
from ..interface import Conditions
from .geometry import paper_from_user, wrap_angle
from .information import check_identifiable, plan_svd, scaled_columns, scaled_jacobian
from .kinematics import forward_kinematics
from .spec import PlanarArmSpec

__all__ = [
    "PlanarClosedForm",
    "as_sets",
    "link_phasors_fit",
    "params_from_phasors",
    "plan_factor",
    "projected_start",
    "shared_plan_factor",
    "solve_closed_form",
    "user_from_links",
    "weighted_closed_form",
]


def shared_plan_factor(arm: PlanarArmSpec, conditions: Conditions) -> LinearLeastSquares:
    """The factorization of the plan's regressor, computed once for these conditions.

    The closed form, the identifiability check and the covariance of the plain
    model (isotropic iid noise, every parameter free) all rest on it.
    """
    return conditions.memo(
        (arm, "plan-factor"),
        lambda: factor_least_squares(scaled_jacobian(arm, conditions.q, conditions.target)),
    )


def plan_factor(arm: PlanarArmSpec, conditions: Conditions) -> LinearLeastSquares:
    """:func:`shared_plan_factor`, raising :class:`NotIdentifiableError` for a singular plan."""
    factor = shared_plan_factor(arm, conditions)
    if not bool(factor.svd.full_rank):  # raises, naming the unseen combinations
        check_identifiable(arm, conditions.q, svd=factor.svd, target=conditions.target)
    return factor


def link_phasors_fit(factor: LinearLeastSquares, xy: np.ndarray) -> np.ndarray:
    """Least-squares ``v = (Im z_1..n, Re z_1..n, [x0, y0])`` ``(N, p)`` of sets ``xy (N, m, 2)``.

    The tip is ``sqrt(m) H v`` (:func:`~armcal.models.planar.information.scaled_jacobian`), so
    ``v = H^+ y / sqrt(m)``: one projection ``Q^T y`` and a ``p x p`` product per set.
    """
    m = xy.shape[-2]
    return factor.solve(xy.reshape(-1, 2 * m)) / np.sqrt(m)


def params_from_phasors(arm: PlanarArmSpec, v: np.ndarray) -> np.ndarray:
    k = arm.n_links
    z = v[:, k : 2 * k] + 1j * v[:, :k]
    if not arm.standard_map:
        return user_from_links(arm, np.abs(z) - arm.link_nominal, np.angle(z), v[:, 2 * k :])
    # dq_k = dtheta_k - dtheta_(k-1), wrapped into (-pi, pi], is the angle of
    # z_k conj(z_(k-1)) (z_0 = 1): one angle instead of n angles, a diff and a wrap.
    relative = z.copy()
    relative[:, 1:] *= z[:, :-1].conj()
    return np.concatenate(
        [np.abs(z) - arm.link_lengths, np.angle(relative), v[:, 2 * k :]], axis=-1
    )


def user_from_links(
    arm: PlanarArmSpec, dl: np.ndarray, dtheta: np.ndarray, base: np.ndarray
) -> np.ndarray:
    """User deviations ``(N, p)`` of link-vector deviations ``(N, K)`` and base ``(N, 2)``.

    Solves ``P_free user_free = (dtheta, dl, base)`` (``paper_from_user`` of
    :mod:`~armcal.models.planar.geometry`; fixed parameters 0).  The link angles
    are first put on one branch around the first link vector's (a base rotation
    can turn them all near +-pi), and for a
    joint map of integers the angle parameters are wrapped into (-pi, pi]: whole
    turns of them turn every link vector by whole turns.
    """
    first = dtheta[:, :1]
    dtheta = first + wrap_angle(dtheta - first)
    paper = np.concatenate([dtheta, dl, base], axis=-1)
    free = arm.free
    user = np.zeros((paper.shape[0], arm.n_params))
    user[:, free] = np.linalg.solve(paper_from_user(arm)[:, free], paper.T).T
    angles = arm.angle_params
    if np.array_equal(arm.joint_map, np.round(arm.joint_map)):
        user[:, angles] = wrap_angle(user[:, angles])
    return user


def as_sets(arm: PlanarArmSpec, q: np.ndarray, xy: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    q = np.asarray(q, dtype=float)
    xy = np.asarray(xy, dtype=float)
    if q.ndim != 2 or q.shape[1] != arm.n_joints:
        raise ValueError(f"q must have shape (m, {arm.n_joints}) in rad, got {q.shape}")
    if xy.shape[-2:] != (q.shape[0], 2) or xy.ndim not in (2, 3):
        raise ValueError(f"xy must have shape ({q.shape[0]}, 2) or (N, {q.shape[0]}, 2) in mm")
    return q, xy.reshape(-1, q.shape[0], 2)


def solve_closed_form(
    arm: PlanarArmSpec, q: np.ndarray, xy: np.ndarray, *, target: np.ndarray | None = None
) -> np.ndarray:
    """Exact least-squares deviations by one linear solve; batched over measurement sets.

    Parameters
    ----------
    arm : PlanarArmSpec
    q : ndarray, shape (m, n)
        Joint angles in rad (shared by every measurement set).
    xy : ndarray, shape (m, 2) or (N, m, 2)
        Measured positions in mm; a leading axis holds ``N`` independent sets.
    target : ndarray of int, shape (m,), optional
        Every row's target, for an arm with several.

    Returns
    -------
    ndarray, shape (p,) or (N, p)
        User deviations ``[dl (mm), dq (rad), (x0, y0) (mm), (phi0) (rad)]``.

    Raises
    ------
    NotIdentifiableError
        If the plan cannot identify every parameter (:func:`check_identifiable`).

    Notes
    -----
    Solves ``min ||A w - y||`` for the link phasors ``w`` by a thin QR of the
    plan's regressor and the SVD of its triangle (the rank policy of
    :mod:`armcal.numerics`), then ``dl_k = |z_k| - l_k``, ``dtheta_k = arg z_k``
    and ``dq_k = wrap(dtheta_k - dtheta_{k-1})``.  Round-off errs by about
    ``cond(H) eps`` of the link lengths (``H``: the plan's scaled Jacobian).

    Examples
    --------
    >>> arm = PlanarArmSpec([2.0, 1.0])
    >>> q = np.radians([[0, 0], [0, 90], [90, 90], [45, -120]])
    >>> truth = np.array([0.1, -0.05, 0.01, -0.02])
    >>> est = solve_closed_form(arm, q, forward_kinematics(arm, q, truth))
    >>> bool(np.allclose(est, truth, atol=1e-12))
    True
    """
    batched = np.ndim(xy) == 3
    q, sets = as_sets(arm, q, xy)
    params, _ = PlanarClosedForm(arm, Conditions(q, target)).solve(sets, None)
    return params if batched else params[0]


def weighted_closed_form(
    arm: PlanarArmSpec,
    q: np.ndarray,
    xy: np.ndarray,
    w: np.ndarray | None,
    target: np.ndarray | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """Closed-form deviations ``(N, p)`` of sets ``xy (N, m, 2)`` on whitened rows, and full rank.

    The regressor of the link phasors (:func:`scaled_columns` in real form),
    each pose's two rows and measurement multiplied by ``W_i``: one batched
    least-squares solve per set (one shared factorization when ``w`` does not
    depend on the set).
    """
    columns = scaled_columns(arm, q, target)  # (m, p): tip = sum_k columns_k v_k
    blocks = np.stack([columns.real, columns.imag], axis=-2)  # (m, 2, p)
    m, p = q.shape[0], arm.n_paper
    if w is None or w.ndim == 3:  # one regressor for every set
        regressor = (blocks if w is None else w @ blocks).reshape(2 * m, p)
        rhs = (xy if w is None else (w @ xy[..., None])[..., 0]).reshape(-1, 2 * m)
        factor = factor_least_squares(regressor)
        v, ok = factor.solve(rhs), np.full(rhs.shape[0], bool(factor.svd.full_rank))
    else:
        regressor = (w @ blocks).reshape(-1, 2 * m, p)
        rhs = (w @ xy[..., None])[..., 0].reshape(-1, 2 * m)
        v, ok, _ = solve_least_squares(regressor, rhs)
    return params_from_phasors(arm, v), ok


def _base_start(
    arm: PlanarArmSpec, q: np.ndarray, sets: np.ndarray, target: np.ndarray | None
) -> np.ndarray:
    """A start ``(N, p)`` that turns (and moves) the nominal arm onto each set of points.

    The rotation that best maps the nominal tips onto the measured ones, about
    their centroids when the base offset is free (the 2-D Procrustes solution),
    so that Gauss-Newton starts in the right basin however far the fitted plane's
    axes turn the base.
    """
    names = arm.param_names
    params = np.zeros((sets.shape[0], arm.n_params))
    nominal = forward_kinematics(arm, q, np.zeros(arm.n_params), target=target)
    a, b = nominal[:, 0] + 1j * nominal[:, 1], sets[..., 0] + 1j * sets[..., 1]
    if arm.base_offset:
        a, b = a - a.mean(), b - b.mean(axis=-1, keepdims=True)
    turn = np.angle(np.sum(np.conj(a) * b, axis=-1))
    if "phi0" in names and "phi0" not in arm.fixed:
        params[:, names.index("phi0")] = turn
    if arm.base_offset and "x0" not in arm.fixed and "y0" not in arm.fixed:
        shift = (sets[..., 0] + 1j * sets[..., 1]).mean(axis=-1) - np.exp(1j * turn) * (
            nominal[:, 0] + 1j * nominal[:, 1]
        ).mean()
        params[:, names.index("x0")], params[:, names.index("y0")] = shift.real, shift.imag
    return params


def _onto_free(arm: PlanarArmSpec, full: PlanarArmSpec, params: np.ndarray) -> np.ndarray:
    """Deviations ``(N, p)`` of the complete ``full`` arm as a start for ``arm``'s free ones.

    Without a base rotation the two share their parameters.  With one, the
    complete arm holds the rotation's partner, which ``arm`` may free while
    holding another parameter on the rotation's direction: the start is moved
    along that direction so that the one ``arm`` holds is 0 (the same tip).
    """
    if not arm.base_rotation:
        return params
    direction = arm.rotation_direction
    held = [i for i, name in enumerate(arm.param_names) if name in arm.fixed]
    on_direction = [i for i in held if abs(direction[i]) > 1e-12]
    if not on_direction:
        return params
    i = on_direction[0]
    return params - np.outer(params[:, i] / direction[i], direction)


def projected_start(
    arm: PlanarArmSpec, conditions: Conditions, points: np.ndarray, weights: np.ndarray | None
) -> np.ndarray:
    """Where Gauss-Newton starts ``(N, p)`` for sets ``points`` ``(N, m, 2)`` of an arm.

    Every parameter free (a closed form exists): zero deviations, the paper's
    Step 1.  Fixed parameters: the closed form of the same arm with every
    parameter free, projected onto the free ones -- from zero, a far-turned
    base (3-D data) can lead Gauss-Newton to the mirrored arm
    ``(-L, dq + 180 deg)``, which fits as well -- or, when the poses cannot
    identify that arm, the nominal arm turned onto the points
    (:func:`_base_start`).  ``weights`` ``(m,)`` or ``(N, m)`` weight the rows (0
    leaves one out).
    """
    n_sets = points.shape[0]
    if arm.complete:
        return np.zeros((n_sets, arm.n_params))
    q, target = conditions.q, conditions.target
    used = np.ones(q.shape[0], bool) if weights is None else np.any(np.atleast_2d(weights) > 0, 0)
    sub = None if target is None else target[used]
    full = arm.replace(fixed=())
    if plan_svd(full, q[used], sub).full_rank:
        w = weighted_whitening(full.relative_whitening(conditions), weights, 2)
        params, _ = weighted_closed_form(full, q, points, w, target)
        return _onto_free(arm, full, params) * arm.free
    if arm.base_rotation:
        return _base_start(arm, q[used], points[:, used], sub) * arm.free
    return np.zeros((n_sets, arm.n_params))


class PlanarClosedForm:
    """The closed form of an arm whose free parameters map onto its link vectors.

    :meth:`solve` is the weighted least-squares optimum of point sets at the
    conditions given once: unweighted, from the plan's own factorization (shared
    with the identifiability check and the covariance, :func:`shared_plan_factor`);
    weighted, from the whitened regressor (:func:`weighted_closed_form`).
    """

    def __init__(self, arm: PlanarArmSpec, conditions: Conditions) -> None:
        self.arm, self.conditions = arm, conditions

    def solve(
        self, points: np.ndarray, whitening: np.ndarray | None
    ) -> tuple[np.ndarray, np.ndarray]:
        """Deviations ``(N, p)`` of sets ``(N, m, 2)`` and whether each solve is full rank.

        Raises :class:`~armcal.errors.NotIdentifiableError` for an unweighted plan
        that cannot identify every parameter.
        """
        arm, cond = self.arm, self.conditions
        if whitening is None:
            params = params_from_phasors(arm, link_phasors_fit(plan_factor(arm, cond), points))
            return params, np.ones(points.shape[0], dtype=bool)
        return weighted_closed_form(arm, cond.q, points, whitening, cond.target)
