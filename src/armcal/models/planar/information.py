"""Which parameter combinations a plan observes: the scaled Jacobian, its SVD, identifiability.

``H`` (:func:`scaled_jacobian`) is the Jacobian of the nominal arm in the
paper's parametrization with unit-norm columns and rows divided by
``sqrt(m)``, so that ``H^T H`` is the Hadamard-normalized information matrix of
:mod:`armcal.criteria`.  At *any* deviations the paper Jacobian with unit-norm
columns is ``H`` times an orthogonal matrix (each link's two columns turn by
``dtheta_k``), so the singular values of ``H`` alone decide, through the one
policy of :mod:`armcal.numerics`, whether a plan identifies every parameter
(:func:`identifiability`, :func:`check_identifiable`) and whether results
carry an ``ill-conditioned`` warning (:func:`~armcal.models.wording.ill_conditioned_warning`).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from ...errors import NotIdentifiableError
from ...noise import complex_whitening, relative_noise
from ...numerics import COND_WARN, RANK_RTOL, ScaledSVD, scaled_svd
from ..identifiability import Identifiability, combination, listing, row_echelon
from ..information import covariance_factor_from
from .geometry import paper_from_user, split_params
from .kinematics import jacobian, link_units
from .spec import PlanarArmSpec

__all__ = [
    "check_identifiable",
    "covariance_factor",
    "every_target",
    "identifiability",
    "model_basis",
    "model_columns",
    "plan_rows",
    "plan_svd",
    "scaled_columns",
    "scaled_jacobian",
    "target_weights",
    "unit_trace",
    "user_from_scaled",
    "weighted_user_jacobian",
]


def every_target(arm: PlanarArmSpec, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Every target measured at every pose: rows ``(..., m T, n)`` and their targets ``(m T,)``.

    Pose-major: pose ``i``'s targets are rows ``i T .. i T + T - 1``.
    """
    count = arm.n_target_links
    q = np.asarray(q, dtype=float)
    rows = np.repeat(q, count, axis=-2)
    return rows, np.tile(np.arange(count), q.shape[-2])


def target_weights(arm: PlanarArmSpec) -> np.ndarray:
    """Column weights ``(p,)`` of a plan measured at every target (:func:`scaled_columns`).

    A target's last link is in ``1 / T`` of the rows of such a plan, the shared
    links in all: its two columns are weighted ``sqrt(T)`` so that every column
    has the same mean square, and the normalized information keeps its unit
    diagonal (an orthogonal plan of the arm is orthogonal for all its targets).
    """
    w = np.ones(arm.n_paper)
    k, k0 = arm.n_links, arm.n_joints - 1
    w[k0:k] = w[k + k0 : 2 * k] = np.sqrt(arm.n_target_links)
    return w


def plan_rows(
    arm: PlanarArmSpec, q: np.ndarray, target: np.ndarray | None
) -> tuple[np.ndarray, np.ndarray | None, bool]:
    """The rows a plan is measured in: ``(rows, target, every)``.

    With ``target`` given (or one target) the rows are ``q``'s own; a plan of an
    arm with several targets and no ``target`` is measured at every target of
    every pose (:func:`every_target`), ``every`` True.
    """
    if target is not None or arm.n_target_links == 1:
        return np.asarray(q, dtype=float), target, False
    rows, index = every_target(arm, q)
    return rows, index, True


def scaled_columns(
    arm: PlanarArmSpec, q: np.ndarray, target: np.ndarray | None = None
) -> np.ndarray:
    """Hadamard-scaled Jacobian columns ``(..., m, p)`` in the paper's order, as complex numbers.

    Row x of the real Jacobian is the real part, row y the imaginary part;
    column ``dtheta_k`` (``i l_k e^{i theta_k}``) is divided by ``l_k``.  With
    several targets, ``target`` ``(m,)`` says which one every row measures
    (:func:`~armcal.models.planar.kinematics.link_units`); without it every
    target is measured at every pose (``T`` rows per pose, :func:`plan_rows`) and
    the targets' columns are weighted by :func:`target_weights`.
    """
    return _plan_columns(arm, q, target)[0]


def _plan_columns(
    arm: PlanarArmSpec, q: np.ndarray, target: np.ndarray | None
) -> tuple[np.ndarray, np.ndarray, np.ndarray | None]:
    """:func:`scaled_columns` with the rows and targets they were computed for."""
    q, target, every = plan_rows(arm, q, target)
    unit = link_units(arm, q, target)
    if every:
        unit = unit * target_weights(arm)[: arm.n_links]
    cols = [1j * unit, unit]
    if arm.base_offset:
        cols.append(np.broadcast_to(np.array([1.0, 1j]), (*np.shape(q)[:-1], 2)))
    return np.concatenate(cols, axis=-1), q, target


def model_basis(arm: PlanarArmSpec) -> tuple[np.ndarray, np.ndarray]:
    """The free parameters in the scaled paper coordinates: ``C`` and ``T`` ``(p, p_f)``.

    A change ``u`` ``(p_f,)`` of the model's coordinates moves the scaled paper
    coordinates of :func:`scaled_columns` by ``C u`` and the user deviations by
    ``T u`` (at nominal).  Every parameter free: ``C = I``, ``T =``
    :func:`user_from_scaled` at nominal.  A fixed ``dl_k`` or base coordinate
    drops its column.  Fixed joint offsets tie link angles together: with
    ``dq_j`` fixed for ``j > 1``, link ``j`` turns with link ``j - 1``, so links
    form groups ``G`` that share one absolute offset (``dq1`` fixed pins the
    first group to the base).  A group's column is ``sum_{k in G} l_k e_theta_k``
    divided by ``sqrt(sum_{k in G} l_k^2)``: unit mean square over random
    poses, the normalization of the columns of a single link.
    """
    p = arm.n_params
    free = arm.free
    if arm.complete:
        return np.eye(arm.n_paper), user_from_scaled(arm, None)
    if not arm.standard_map:
        return _generic_basis(arm)
    n = arm.n_joints
    columns_c: list[np.ndarray] = []
    columns_t: list[np.ndarray] = []
    free_dq = [j for j in range(n) if free[n + j]]
    for a, j in enumerate(free_dq):
        end = free_dq[a + 1] if a + 1 < len(free_dq) else n
        group = np.arange(j, end)
        scale = float(np.sqrt(np.sum(arm.link_lengths[group] ** 2)))
        c = np.zeros(p)
        c[group] = arm.link_lengths[group] / scale
        t = np.zeros(p)
        t[n + j] = 1.0 / scale  # dq_j = phi_G - phi_(previous group)
        if end < n:
            t[n + end] = -1.0 / scale
        columns_c.append(c)
        columns_t.append(t)
    for k in [k for k in range(n) if free[k]] + [k for k in range(2 * n, p) if free[k]]:
        e = np.zeros(p)
        e[n + k if k < n else k] = 1.0  # scaled paper order: (dtheta, dl, base)
        t = np.zeros(p)
        t[k] = 1.0
        columns_c.append(e)
        columns_t.append(t)
    return np.array(columns_c).T, np.array(columns_t).T


def _scaled_from_user(arm: PlanarArmSpec) -> np.ndarray:
    """``U`` ``(p_paper, p)``: scaled paper coordinates (``l_k dtheta_k``, ``dl_k``, base) of a
    change of the user parameters, at nominal."""
    scale = np.ones(arm.n_paper)
    scale[: arm.n_links] = arm.link_nominal  # u_theta_k = L_k dtheta_k, in mm
    return paper_from_user(arm) * scale[:, None]


def _generic_basis(arm: PlanarArmSpec) -> tuple[np.ndarray, np.ndarray]:
    """:func:`model_basis` of any arm: each free parameter's own column, unit norm.

    Column ``j`` of ``C`` is the change of the scaled paper coordinates per unit
    of free parameter ``j``, divided by its norm (so a column has unit mean
    square over random poses, like a single link's); ``T`` undoes the division.
    """
    u = _scaled_from_user(arm)[:, arm.free]
    norms = np.linalg.norm(u, axis=0)
    t = np.zeros((arm.n_params, arm.n_free))
    t[np.flatnonzero(arm.free), np.arange(arm.n_free)] = 1.0 / norms
    return u / norms, t


def model_columns(
    arm: PlanarArmSpec, q: np.ndarray, target: np.ndarray | None = None
) -> np.ndarray:
    """The model's scaled Jacobian ``(..., m, p_f)`` as complex columns, at nominal.

    :func:`scaled_columns` in the coordinates of :func:`model_basis` (the free
    parameters), each pose whitened by the noise model
    (:meth:`armcal.noise.NoiseModel.whitening`, as ``alpha c + beta conj(c)``):
    the information matrix of any model is ``sum_i Re(c_i^H c_i)`` over these
    columns.  For the paper's model (:attr:`PlanarArmSpec.standard`) it is
    :func:`scaled_columns` itself.
    """
    columns, q, target = _plan_columns(arm, q, target)
    if arm.standard:
        return columns
    if not arm.complete:
        columns = columns @ model_basis(arm)[0]
    if arm.noise is not None and not arm.noise.isotropic_iid:
        w = arm.whitening_at(np.asarray(q, dtype=float), target=target)
        alpha, beta = complex_whitening(w)
        columns = alpha[..., None] * columns + beta[..., None] * columns.conj()
    return columns


def scaled_jacobian(
    arm: PlanarArmSpec, q: np.ndarray, target: np.ndarray | None = None
) -> np.ndarray:
    """The policy's matrix ``H`` ``(..., 2m, p_f)``: the Hadamard-normalized nominal Jacobian.

    The real form of :func:`model_columns` divided by ``sqrt(m)``: rows alternate
    x, y per pose.  For the paper's model (every parameter free, isotropic iid
    noise) columns are the paper's ``(dtheta, dl, [x0, y0])``, every column has
    unit norm and ``H^T H = Fs``; its singular values are 1 for an orthogonal
    plan.  Otherwise columns are the free parameters of :func:`model_basis` and
    rows are whitened: ``sigma_ref^2 (H^T H)^-1 / m`` is the weighted
    (generalized) least-squares covariance in the model's coordinates.

    For the paper's model it is also the plan's regressor of the model that is
    linear in the links: the tip is ``sqrt(m) H v`` with
    ``v = (Im z_1..n, Re z_1..n, [x0, y0])`` and ``z_k = (l_k + dl_k) exp(i dtheta_k)``
    (see :mod:`armcal.identification`).
    """
    q = np.asarray(q, dtype=float)
    columns = model_columns(arm, q, target)
    rows = columns.shape[-2]
    columns = columns / np.sqrt(rows)
    real = np.stack([columns.real, columns.imag], axis=-2)  # (..., m, 2, p_f)
    return real.reshape(*q.shape[:-2], 2 * rows, columns.shape[-1])


def plan_svd(arm: PlanarArmSpec, q: np.ndarray, target: np.ndarray | None = None) -> ScaledSVD:
    """Singular values and right singular vectors of :func:`scaled_jacobian` (batched).

    Thin factorizations only (:func:`armcal.numerics.scaled_svd`): memory
    ``O(m p)`` per plan.
    """
    return scaled_svd(scaled_jacobian(arm, q, target))


def user_from_scaled(arm: PlanarArmSpec, params: np.ndarray | None) -> np.ndarray:
    """``T`` ``(..., p, p)``: user deviations ``= T u`` for a change ``u`` in ``H``'s coordinates.

    At deviations ``params`` the user Jacobian is ``sqrt(m) H T^-1``: with
    ``phi_k = dtheta_k`` and ``L_k = l_k + dl_k``, a change ``u`` of link ``k``'s
    two coordinates gives ``dtheta_k = (cos phi u_theta - sin phi u_l) / L_k``,
    ``dl_k = sin phi u_theta + cos phi u_l`` (a rotation, then a division by the
    length), and ``dq_k = dtheta_k - dtheta_(k-1)``.  Explicit, so nothing is
    inverted; ``inf`` entries for a link of length 0.
    """
    k, p = arm.n_links, arm.n_params
    values = np.zeros(p) if params is None else np.asarray(params, dtype=float)
    if values.shape[-1] != p:
        raise ValueError(
            f"params must have shape (..., {p}) for {arm.param_names}, got {values.shape}"
        )
    dl, phi, _ = split_params(arm, values)
    length = arm.link_nominal + dl
    cos, sin = np.cos(phi), np.sin(phi)
    with np.errstate(divide="ignore", invalid="ignore"):
        inverse_length = 1.0 / length
    q = arm.n_paper
    paper = np.zeros((*values.shape[:-1], q, q))
    i = np.arange(k)
    paper[..., i, i] = cos * inverse_length
    paper[..., i, k + i] = -sin * inverse_length
    paper[..., k + i, i] = sin
    paper[..., k + i, k + i] = cos
    if arm.base_offset:
        paper[..., 2 * k :, 2 * k :] = np.eye(2)
    if not arm.standard_map:
        # user = P_free^-1 paper over the free parameters (the arm is complete).
        to_user = np.zeros((p, q))
        to_user[arm.free] = np.linalg.inv(paper_from_user(arm)[:, arm.free])
        with np.errstate(invalid="ignore"):
            return to_user @ paper
    n = k
    user = np.empty_like(paper)
    user[..., :n, :] = paper[..., n : 2 * n, :]
    with np.errstate(invalid="ignore"):
        user[..., n : 2 * n, :] = np.diff(paper[..., :n, :], axis=-2, prepend=0.0)
    user[..., 2 * n :, :] = paper[..., 2 * n :, :]
    return user


def _scaled_from_user_nominal(arm: PlanarArmSpec) -> np.ndarray:
    """``T0^-1`` ``(p_f, p_f)``: model coordinates of a change of the free user parameters.

    Every parameter free: ``u = diag(l, 1, [1, 1]) P user`` (explicit).  Otherwise
    the inverse of the free rows of :func:`model_basis`'s ``T``, a small matrix
    that is nonsingular by construction (triangular per joint group).
    """
    if not arm.free.all() or not arm.standard_map:
        return np.linalg.inv(model_basis(arm)[1][arm.free])
    return _scaled_from_user(arm)


def _link_of(arm: PlanarArmSpec) -> np.ndarray:
    """The link (1..n; 0 for the base) each user parameter belongs to."""
    links = arm.link_joint + 1
    base = [0, 0] if arm.base_offset else []
    return np.concatenate([links, links, base, [0] if arm.base_rotation else []]).astype(int)


def _joints_to_vary(arm: PlanarArmSpec, rows: np.ndarray, drop: float) -> tuple[int, ...]:
    joints: set[int] = set()
    link_of = _link_of(arm)
    for row in rows:
        involved = link_of[np.abs(row) > drop * np.max(np.abs(row))]
        lo, hi = int(involved.min()), int(involved.max())
        joints.update(range(lo + 1, hi + 1) if hi > lo else [max(hi, 1)])
    return tuple(sorted(joints))


def identifiability(
    arm: PlanarArmSpec,
    q: np.ndarray,
    *,
    svd: ScaledSVD | None = None,
    target: np.ndarray | None = None,
) -> Identifiability:
    """Rank of the Jacobian of a plan, on scaled columns, by the one rank policy.

    Parameters
    ----------
    arm : PlanarArmSpec
    q : ndarray, shape (m, n)
        Joint angles of the plan in rad.
    svd : ScaledSVD, optional
        ``plan_svd(arm, q)`` when the caller has it already.
    target : ndarray of int, shape (m,), optional
        Every row's target, for an arm with several.

    Returns
    -------
    Identifiability

    Notes
    -----
    The singular values are those of :func:`scaled_jacobian` (thin QR, then SVD
    of the ``p x p`` triangle: memory ``O(m p)``).  They do not depend on the
    deviations: at any deviations the paper Jacobian with unit-norm columns is
    that matrix times an orthogonal one, so the nominal model suffices.  Null
    and poorly determined directions are mapped to the user parameters and
    shown in display units (mm, deg).

    Examples
    --------
    >>> arm = PlanarArmSpec([2.0, 1.0])
    >>> info = identifiability(arm, np.zeros((3, 2)))   # three identical poses
    >>> info.rank, info.unidentifiable
    (2, ('dl1', 'dl2', 'dq1', 'dq2'))
    """
    if svd is None:
        svd = plan_svd(arm, q, target)
    rank = int(svd.rank)
    to_user = model_basis(arm)[1]
    if target is None and arm.n_target_links > 1 and arm.complete:
        to_user = to_user * target_weights(arm)  # a plan measured at every target
    names = arm.param_names
    free = arm.free
    null = svd.directions(RANK_RTOL) @ to_user.T  # rows: unseen directions (mm, rad)
    weak = svd.directions(1.0 / COND_WARN) @ to_user.T
    bad: tuple[str, ...] = ()
    if null.shape[0]:
        # Which parameters the null space touches, judged on the user Jacobian with
        # unit-norm columns: |J_user e_j| = sqrt(m) |S V^T (c * T0^-1 e_j)|.
        user_columns = svd.column_norms[:, None] * _scaled_from_user_nominal(arm)
        user_norms = np.linalg.norm(svd.singular_values[:, None] * (svd.vt @ user_columns), axis=0)
        basis, _ = np.linalg.qr((null[:, free] * user_norms).T)  # orthonormal, (p_f, k)
        weights = np.linalg.norm(basis, axis=1)
        bad = tuple(n for n, w in zip(arm.free_names, weights, strict=True) if w > 1e-8)
    display = arm.display_scale  # a direction in mm, rad shown in mm, deg
    null_rows = row_echelon(null * display)
    # A poorly determined direction is only near the null space of a nearby plan:
    # terms below the 3 significant digits shown of the leading one are left out.
    weak_drop = 1e-3
    weak_rows = row_echelon(weak * display, tol=weak_drop)
    if null.shape[0]:
        joints = _joints_to_vary(arm, null_rows, 1e-6)
    else:
        joints = _joints_to_vary(arm, weak_rows, weak_drop)
    return Identifiability(
        rank=rank,
        n_params=arm.n_free,
        singular_values=svd.singular_values,
        unidentifiable=bad,
        combinations=tuple(combination(v, names) for v in null_rows),
        poorly_determined=tuple(combination(v, names, drop=weak_drop) for v in weak_rows),
        joints_to_vary=joints,
    )


def _joints_phrase(joints: Sequence[int]) -> str:
    return ("joint " if len(joints) == 1 else "joints ") + listing(joints)


def check_identifiable(
    arm: PlanarArmSpec,
    q: np.ndarray,
    *,
    svd: ScaledSVD | None = None,
    target: np.ndarray | None = None,
) -> Identifiability:
    """Raise :class:`NotIdentifiableError` unless the plan ``q`` identifies every parameter.

    The message counts poses and parameters, names the parameters that cannot be
    identified and up to three unseen combinations, and says how to fix the plan.
    ``svd`` is ``plan_svd(arm, q)`` when the caller has it already.
    """
    q = np.asarray(q, dtype=float)
    m = q.shape[0]
    p = arm.n_free
    # Rows with a target each are one point; plain poses are measured at every target.
    per_pose = 2 * (len(arm.targets) if target is None and arm.targets else 1)
    min_poses = -(-p // per_pose)
    info = identifiability(arm, q, svd=svd, target=target)
    if info.identifiable:
        return info
    shown = "; ".join(info.combinations[:3])
    more = f" (and {len(info.combinations) - 3} more)" if len(info.combinations) > 3 else ""
    if m < min_poses:
        why = (
            f"{m} {'poses' if target is None else 'measurements'} give {per_pose * m} "
            f"equations for {p} parameters; measure at least {min_poses} "
            f"{'poses' if target is None else 'measurements'}"
        )
    else:
        joints = info.joints_to_vary
        why = (
            f"add poses in which {_joints_phrase(joints)} "
            f"{'takes' if len(joints) == 1 else 'take'} several different angles (armcal design)"
        )
    raise NotIdentifiableError(
        f"the {m} poses cannot identify all {p} parameters of {arm.name} "
        f"(Jacobian rank {info.rank} of {p}): not identifiable: {', '.join(info.unidentifiable)}; "
        f"unseen combinations: {shown}{more}; {why}",
        list(info.combinations),
    )


def covariance_factor(
    arm: PlanarArmSpec,
    q: np.ndarray,
    params: np.ndarray | None,
    svd: ScaledSVD | None = None,
    target: np.ndarray | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """``G`` ``(..., p, p)`` with ``(J^T J)^-1 = G G^T`` (user parametrization) and the ok mask.

    ``target`` ``(m,)``: the rows' targets (measurements); without it a plan of
    an arm with several targets is measured at every target of every pose.
    """
    q = np.asarray(q, dtype=float)
    every = target is None and arm.n_target_links > 1  # measured at every target
    rows = q.shape[-2] * (arm.n_target_links if every else 1)
    if not arm.standard and (params is not None or every):
        at = np.zeros(arm.n_params) if params is None else params
        return _covariance_factor_at(arm, q, at, target)
    factor, ok = (plan_svd(arm, q) if svd is None else svd).inverse_gram_factor()
    to_user = user_from_scaled(arm, params) if arm.standard else model_basis(arm)[1]
    if every:  # the targets' columns were weighted (observability.target_weights)
        to_user = to_user * target_weights(arm)[: to_user.shape[-1]]
    with np.errstate(invalid="ignore", over="ignore"):
        g = to_user @ np.where(ok[..., None, None], factor, 0.0) / np.sqrt(rows)
    ok = ok & np.all(np.isfinite(g), axis=(-2, -1))
    return np.where(ok[..., None, None], g, np.inf), ok


def _covariance_factor_at(
    arm: PlanarArmSpec, q: np.ndarray, params: np.ndarray, target: np.ndarray | None = None
) -> tuple[np.ndarray, np.ndarray]:
    """:func:`covariance_factor` of a weighted or reduced model at deviations ``params``.

    The free columns of the user Jacobian at ``params``, each pose whitened at
    ``params`` (:meth:`armcal.noise.NoiseModel.whitening`), through the rank
    policy's SVD: ``G`` ``(..., p, p_f)`` with zero rows for fixed parameters.
    """
    return covariance_factor_from(weighted_user_jacobian(arm, q, params, target=target), arm.free)


def weighted_user_jacobian(
    arm: PlanarArmSpec,
    q: np.ndarray,
    params: np.ndarray | None = None,
    row_sigma: np.ndarray | None = None,
    *,
    target: np.ndarray | None = None,
) -> np.ndarray:
    """Whitened free columns of the user Jacobian ``(..., 2m, p_f)`` at ``params``.

    Rows are ``W_i J_i`` (:meth:`armcal.noise.NoiseModel.whitening` at ``params``,
    the identity for isotropic iid noise), so ``sigma_ref^2 (J_w^T J_w)^-1`` is
    the generalized-least-squares covariance of the free parameters.
    """
    q, target, _ = plan_rows(arm, q, target)
    jac = jacobian(arm, q, params, target=target)  # (..., m, 2, p)
    noise = arm.noise
    if row_sigma is not None or (noise is not None and not noise.isotropic_iid):
        weights = relative_noise(noise)
        jac = arm.whitening_at(q, params, row_sigma, target=target, noise=weights) @ jac
    jac = jac[..., arm.free]
    return jac.reshape(*jac.shape[:-3], -1, arm.n_free)


def unit_trace(arm: PlanarArmSpec) -> bool:
    """Whether every pose's information over the free parameters has trace ``p_f``.

    Then ``det M <= 1`` for the normalized information of every plan and
    design, with equality iff ``M = I`` (AM-GM on its eigenvalues, the paper's
    Hadamard bound where the diagonal is 1): isotropic iid noise
    with only ``dl``, base or leading ``dq`` parameters fixed, or every
    parameter free without encoder noise.

    Examples
    --------
    >>> from armcal.noise import NoiseModel
    >>> arm = PlanarArmSpec([260.0, 180.0, 120.0, 100.0], sigma=0.02)
    >>> unit_trace(arm), unit_trace(arm.replace(fixed=("dl4",)))
    (True, True)
    >>> unit_trace(arm.replace(fixed=("dq2",)))
    False
    >>> anisotropic = arm.replace(noise=NoiseModel.per_axis(0.08, 0.02))
    >>> unit_trace(anisotropic), unit_trace(anisotropic.replace(fixed=("dl4",)))
    (True, False)
    """
    noise = arm.noise
    if noise is not None and noise.joint_sigma is not None:
        return False
    if arm.free.all():
        return True
    if noise is not None and not noise.isotropic_instrument:
        return False
    basis = model_basis(arm)[0]
    return bool(np.all(np.count_nonzero(basis, axis=0) == 1))
