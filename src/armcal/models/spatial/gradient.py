"""How a spatial arm's design information changes with its poses.

The optimizer and the certificate climb quadratic forms ``tr(A F^T F)`` of the
whitened blocks ``F = W J`` over the free parameters
(:class:`~armcal.models.information.BlockInformation`).  Their gradient in the
poses needs only a pullback, ``<G, dF/dq>`` for ``G = 2 F A``: the chain's
screws give it in closed form at the cost of the Jacobian itself
(:func:`jacobian_pose_pullback`), and a laser tracker's weights, which move with
the point, add their own term (:meth:`armcal.noise.NoiseModel.metric_pullback`).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from ...noise import NoiseModel
from ..information import Linearization
from .kinematics import ChainKinematics, SpatialLayout, cross

__all__ = ["Extra", "jacobian_pose_pullback", "linearization", "upstream_joints"]


def upstream_joints(layout: SpatialLayout) -> np.ndarray:
    """How many joints come before each parameter in the chain ``(p,)``: 0 for the base,
    ``k`` for joint ``k``'s placement (0-based), ``n`` for the targets; a zero error is
    the joint's own turn and is handled apart (:func:`jacobian_pose_pullback`)."""
    out = np.zeros(layout.n_params, dtype=int)
    for k in range(layout.n_joints):
        out[6 + 5 * k : 6 + 5 * k + 5] = k
    out[layout.zero_start : layout.target_start] = -1
    out[layout.target_start :] = layout.n_joints
    return out


def jacobian_pose_pullback(
    kin: ChainKinematics,
    layout: SpatialLayout,
    joint_map: np.ndarray,
    columns: np.ndarray,
    cotangent: np.ndarray,
) -> np.ndarray:
    """``sum_(x, k) C[x, k] d J[x, columns[k]] / d q`` ``(..., m, n)``: how a weighted sum of
    the points' parameter Jacobian (:func:`kinematics` with ``derivatives``) changes with
    each row's readings, for a cotangent ``C`` ``(..., m, 3, len(columns))``.

    Every column is the velocity ``w_k x p + m_k`` of the point ``p`` under a screw
    fixed in the chain.  A joint ``l`` before the screw moves both rigidly, so the
    column turns with it: ``a_l x J_k``; a joint after it moves only the point:
    ``w_k x V_l(p)`` (``a_l`` the joint's axis, ``V_l`` its velocity at ``p``).  A
    joint's own turn does not move its axis: both rules agree there.  A zero error's
    column is ``sum_j M_ji V_j`` (the joint map ``u = M (q + dq)``).  Contracted with
    ``C`` the rules become sums over the chain, ``C_k . (a_l x J_k) = a_l . (J_k x C_k)``
    and ``C_k . (w_k x V_l) = V_l . (C_k x w_k)``, so the cost is that of the Jacobian,
    not ``n`` times it: the gradient of any quadratic form of the blocks needs no more.
    """
    assert kin.jacobian is not None and kin.angular is not None
    assert kin.joint_axes is not None and kin.joint_velocities is not None
    a, v = kin.joint_axes, kin.joint_velocities  # (..., m, n, 3)
    n = layout.n_joints
    chain = np.arange(n)
    columns = np.asarray(columns)
    is_zero = (columns >= layout.zero_start) & (columns < layout.target_start)
    weight = np.swapaxes(cotangent, -1, -2)  # (..., m, c, 3)
    # by_axis[x, l] multiplies a_l[x], by_velocity[x, l] multiplies V_l[x]
    plain = columns[~is_zero]
    upstream = (chain[None, :] < upstream_joints(layout)[plain][:, None]).astype(float)
    c_plain = weight[..., ~is_zero, :]
    jac = np.swapaxes(kin.jacobian[..., plain], -1, -2)
    screw = np.swapaxes(kin.angular[..., plain], -1, -2)
    by_axis = np.swapaxes(cross(jac, c_plain), -1, -2) @ upstream
    by_velocity = np.swapaxes(cross(c_plain, screw), -1, -2) @ (1.0 - upstream)
    if is_zero.any():  # D_j = sum_i M_ji C_i; d V_j / d u_l = a_l x V_j (l < j), a_j x V_l
        mapped = joint_map[:, columns[is_zero] - layout.zero_start] @ weight[..., is_zero, :]
        later = (chain[:, None] > chain[None, :]).astype(float)  # [j, l]: j after l
        by_axis = by_axis + np.swapaxes(cross(v, mapped), -1, -2) @ later
        by_velocity = by_velocity + np.swapaxes(cross(mapped, a), -1, -2) @ (1.0 - later)
    by_joint = np.einsum("...lx,...xl->...l", a, by_axis) + np.einsum(
        "...lx,...xl->...l", v, by_velocity
    )
    return by_joint @ joint_map  # d/dq_i = sum_l M_li d/du_l


#: Columns a model adds to a spatial arm's (joint compliance): their unwhitened values
#: ``(..., m, 3, P)`` and the pullback of a cotangent on them ``(..., m, 3, P) -> (..., m, n)``.
Extra = tuple[np.ndarray, Callable[[np.ndarray], np.ndarray]]


def linearization(
    kin: ChainKinematics,
    layout: SpatialLayout,
    joint_map: np.ndarray,
    columns: np.ndarray,
    noise: NoiseModel,
    extra: Extra | None = None,
) -> Linearization:
    """Rows' whitened blocks ``W J[:, columns]`` and their pullback, from kinematics with
    derivatives and a noise model whose whitening depends on the rows through the points
    and the joint Jacobian (isotropic, anisotropic, a tracker's, encoder noise; not rows'
    own sigmas or orientations); ``extra`` columns follow the arm's."""
    assert kin.jacobian is not None and kin.joint_jacobian is not None
    jac = kin.jacobian[..., columns]
    g = jac.shape[-1]
    if extra is not None:
        jac = np.concatenate([jac, extra[0]], axis=-1)
    velocity = kin.joint_jacobian
    encoder = velocity if noise.joint_sigma is not None else None
    w = None
    if not noise.isotropic_iid:
        w = noise.whitening(kin.points.shape[:-1], joint_jacobian=encoder, points=kin.points)
    zeros = np.arange(layout.zero_start, layout.target_start)  # J_q's columns

    def pullback(cotangent: np.ndarray) -> np.ndarray:
        plain = cotangent if w is None else np.swapaxes(w, -1, -2) @ cotangent
        out = jacobian_pose_pullback(kin, layout, joint_map, columns, plain[..., :g])
        if extra is not None:
            out = out + extra[1](plain[..., g:])
        if w is None:
            return out
        position, joint = noise.metric_pullback(w, kin.points, velocity, jac, cotangent)
        if position is not None:
            out = out + position
        if joint is not None:
            out = out + jacobian_pose_pullback(kin, layout, joint_map, zeros, joint)
        return out

    return Linearization(jac if w is None else w @ jac, pullback)
