"""Forward kinematics and Jacobians of the planar arm, batched over poses and estimates.

All functions are batched on leading axes: joint angles ``q`` of shape
``(m, n)`` give positions ``(m, 2)`` and Jacobians ``(m, 2, p)``; deviations
``params`` of shape ``(..., p)`` give ``(..., m, 2)`` and ``(..., m, 2, p)``.  An
arm with several targets needs the ``target`` of every row.  The geometry and
the parametrization are :mod:`armcal.models.planar.geometry`'s.

Complex numbers carry the plane: a link vector is ``z_k u_k`` with the
deviated link phasor ``z_k`` (:func:`link_phasors`) and the unit phasor of its
nominal direction ``u_k`` (:func:`link_units`), so the tip is linear in the
``z_k``: the closed form of :mod:`armcal.models.planar.closed_form` rests on that.
"""

from __future__ import annotations

from typing import Literal

import numpy as np
from numpy.typing import ArrayLike

from ..interface import target_indices, targets_missing
from .geometry import PlanarGeometry, split_params

__all__ = [
    "Parametrization",
    "check_target",
    "forward_kinematics",
    "jacobian",
    "joint_jacobian",
    "link_jacobian",
    "link_phasors",
    "link_units",
    "link_vectors",
    "tool_angles",
]

Parametrization = Literal["user", "paper"]


def _check_q(arm: PlanarGeometry, q: np.ndarray) -> np.ndarray:
    q = np.asarray(q, dtype=float)
    if q.ndim < 1 or q.shape[-1] != arm.n_joints:
        raise ValueError(f"q must have shape (m, {arm.n_joints}) in rad, got {q.shape}")
    return q


def check_target(
    arm: PlanarGeometry, q: np.ndarray, target: ArrayLike | None
) -> np.ndarray | None:
    """The rows' target indices ``(m,)`` (None: every row measures the only target), from
    indices or the targets' labels.

    Raises ValueError (an ArmcalError) for an arm with several targets and no ``target``,
    an unknown label, or indices out of range.
    """
    if target is None:
        if arm.n_target_links > 1:
            raise targets_missing(arm.name, arm.target_labels)
        return None
    m = np.shape(q)[-2] if np.ndim(q) >= 2 else 1
    index = target_indices(target, arm.target_labels, m)
    return index if arm.n_target_links > 1 else None


def link_units(arm: PlanarGeometry, q: np.ndarray, target: ArrayLike | None = None) -> np.ndarray:
    """Unit phasors ``(..., m, K)`` of every link vector's nominal direction, 0 where unused.

    ``exp(i (theta_a(k) + alpha_k))`` for link vector ``k`` turning with link
    angle ``a(k)`` (:attr:`PlanarGeometry.link_joint`) at nominal direction
    ``alpha_k`` (:attr:`PlanarGeometry.link_angle0`); a target's last link is 0 in the
    rows of the other targets.  The tip is ``base + sum_k z_k u_k`` with the
    link phasors ``z_k`` of :func:`link_phasors`.

    Examples
    --------
    >>> from armcal.models.planar.geometry import Target
    >>> arm = PlanarGeometry([2.0, 1.0], targets=[Target("A", 1.0), Target("B", 1.0, np.pi / 2)])
    >>> link_units(arm, np.zeros((2, 2)), target=np.array([0, 1])).round(12).tolist()
    [[(1+0j), (1+0j), 0j], [(1+0j), 0j, 1j]]
    """
    q = _check_q(arm, q)
    return _tip_terms(arm, q, None, target)[1]


def link_phasors(arm: PlanarGeometry, params: np.ndarray) -> np.ndarray:
    """The deviated link vectors and base as complex numbers ``(..., K + 1)``.

    ``z_k = (L_k + dl_k) exp(i dtheta_k)`` for every link vector (nominal length
    ``L_k``, :attr:`PlanarGeometry.link_nominal`), then the base ``x0 + i y0`` (0
    without a base offset): the tip is ``base + sum_k z_k u_k`` with the unit
    phasors ``u_k`` of :func:`link_units`, linear in these numbers.

    Examples
    --------
    >>> z = link_phasors(PlanarGeometry([2.0, 1.0]), np.array([0.5, 0.0, np.pi / 2, 0.0]))
    >>> z.round(12).tolist()
    [2.5j, 1j, 0j]
    """
    dl, dtheta, base = split_params(arm, params)
    z = (arm.link_nominal + dl) * np.exp(1j * dtheta)
    return np.concatenate([z, (base[..., 0] + 1j * base[..., 1])[..., None]], axis=-1)


def _tip_terms(
    arm: PlanarGeometry,
    q: np.ndarray,
    params: np.ndarray | None,
    target,
    deflection: np.ndarray | None = None,
):
    """``z_k u_k`` ``(..., m, K)``, ``exp(i dtheta_k) u_k`` ``(..., m, K)`` and the base.

    ``deflection`` ``(..., m, n)``: joint deflections (rad, relative: joint ``j``
    turns every link from ``j`` on), e.g. under load (:mod:`armcal.models.planar.compliance`).
    """
    index = check_target(arm, q, target)
    dl, dtheta, base = split_params(arm, params)
    theta = arm.link_angles(q)[..., arm.link_joint] + arm.link_angle0
    if deflection is not None:
        theta = theta + np.cumsum(deflection, axis=-1)[..., arm.link_joint]
    turn = np.exp(1j * (theta + dtheta[..., None, :]))
    if index is not None:
        turn[..., arm.n_joints - 1 :] *= index[:, None] == np.arange(arm.n_target_links)
    lengths = (arm.link_nominal + dl)[..., None, :]
    return lengths * turn, turn, base


def link_vectors(
    arm: PlanarGeometry,
    q: np.ndarray,
    params: np.ndarray | None = None,
    *,
    target: ArrayLike | None = None,
    deflection: np.ndarray | None = None,
) -> np.ndarray:
    """Every link vector of every row as a complex number ``(..., m, K)`` (mm).

    The tip is the base plus their sum (a target's last link is 0 in the rows
    of the other targets); joint ``j + 1`` sits at the base plus the sum of the
    first ``j``.  Arguments as for :func:`forward_kinematics`.

    Examples
    --------
    >>> link_vectors(PlanarGeometry([2.0, 1.0]), np.array([[0.0, np.pi / 2]])).round(12).tolist()
    [[(2+0j), 1j]]
    """
    q = _check_q(arm, q)
    return _tip_terms(arm, q, params, target, deflection)[0]


def forward_kinematics(
    arm: PlanarGeometry,
    q: np.ndarray,
    params: np.ndarray | None = None,
    *,
    target: ArrayLike | None = None,
    deflection: np.ndarray | None = None,
) -> np.ndarray:
    """End-effector positions for joint angles ``q``.

    Parameters
    ----------
    arm : PlanarGeometry
    q : ndarray, shape (m, n)
        Commanded joint angles in rad.
    params : ndarray, shape (p,) or (..., p), optional
        User deviations ``[dl (mm), dq (rad), (x0, y0) (mm), (phi0) (rad)]``;
        nominal when omitted.  Leading axes broadcast, giving positions of
        shape ``(..., m, 2)``.
    target : ndarray of int, shape (m,), optional
        Index into ``arm.targets`` of the target measured in every row; needed
        when the arm has several targets.
    deflection : ndarray, shape (m, n) or (..., m, n), optional
        Joint deflections in rad (relative angles, e.g. under gravity:
        :mod:`armcal.models.planar.compliance`), added to the real joint angles.

    Returns
    -------
    ndarray, shape (m, 2) or (..., m, 2)
        ``(x, y)`` in mm (paper eq. 1, with the arm's joint map).

    Examples
    --------
    >>> arm = PlanarGeometry([2.0, 1.0])
    >>> forward_kinematics(arm, np.array([[0.0, np.pi / 2]])).round(12).tolist()
    [[2.0, 1.0]]
    >>> horizon = PlanarGeometry([2.0, 1.0], joint_map=[[1, 0], [0, 1]])  # q2 from the horizon
    >>> forward_kinematics(horizon, np.array([[0.0, np.pi / 2]])).round(12).tolist()
    [[2.0, 1.0]]
    """
    q = _check_q(arm, q)
    terms, _, base = _tip_terms(arm, q, params, target, deflection)
    tip = np.sum(terms, axis=-1)
    return np.stack([tip.real, tip.imag], axis=-1) + base[..., None, :]


def jacobian(
    arm: PlanarGeometry,
    q: np.ndarray,
    params: np.ndarray | None = None,
    *,
    parametrization: Parametrization = "user",
    target: ArrayLike | None = None,
    deflection: np.ndarray | None = None,
) -> np.ndarray:
    """Jacobian of the end-effector position with respect to the deviations.

    Parameters
    ----------
    arm : PlanarGeometry
    q : ndarray, shape (m, n)
        Commanded joint angles in rad.
    params : ndarray, shape (p,) or (..., p), optional
        User deviations (mm, rad) at which to linearize; nominal when omitted.
        Leading axes broadcast against those of ``q`` (one Jacobian per estimate).
    parametrization : {"user", "paper"}
        Columns ``[dl, dq, (x0, y0), (phi0)]`` or the paper's ``[dtheta, dl, (x0, y0)]``.
    target : ndarray of int, shape (m,), optional
        Every row's target (see :func:`forward_kinematics`).
    deflection : ndarray, shape (m, n) or (..., m, n), optional
        Joint deflections in rad at which to linearize (see :func:`forward_kinematics`).

    Returns
    -------
    ndarray, shape (m, 2, p) or (..., m, 2, p)
        ``d(x, y) / d(params)``: mm per mm for lengths and base, mm per rad for angles.

    Notes
    -----
    With ``L_k = l_k + dl_k`` and ``phi_k = theta_k + dtheta_k`` (paper eq. 7-8,
    evaluated at the current deviations)::

        dp/ddtheta_k = L_k (-sin phi_k, cos phi_k),  dp/ddl_k = (cos phi_k, sin phi_k)

    and ``dp/ddq_j = sum_k A_kj dp/ddtheta_k`` (``A`` the angle map; for the
    default joint map the sum over ``k >= j``), ``dp/dphi0 = sum_k dp/ddtheta_k``.

    Examples
    --------
    >>> arm = PlanarGeometry([2.0, 1.0])
    >>> (jacobian(arm, np.zeros((1, 2)), parametrization="paper")[0] + 0.0).tolist()
    [[0.0, 0.0, 1.0, 1.0], [2.0, 1.0, 0.0, 0.0]]
    """
    q = _check_q(arm, q)
    terms, turn, _ = _tip_terms(arm, q, params, target, deflection)
    d_theta = 1j * terms  # complex d(tip)/d(dtheta_k), shape (..., m, K)
    if parametrization == "user":
        if arm.standard_map:
            # d/d dq_j = sum over k >= j of d/d dtheta_k: reverse cumulative sum.
            d_q = np.cumsum(d_theta[..., ::-1], axis=-1)[..., ::-1]
        else:
            d_q = d_theta @ arm.angle_map
        cols = [turn, d_q]
    elif parametrization == "paper":
        cols = [d_theta, turn]
    else:
        raise ValueError(f"parametrization must be 'user' or 'paper', got {parametrization!r}")
    if arm.base_offset:
        cols.append(np.broadcast_to(np.array([1.0, 1j]), (*turn.shape[:-1], 2)))
    if arm.base_rotation and parametrization == "user":
        cols.append(np.sum(d_theta, axis=-1, keepdims=True))
    jc = np.concatenate(cols, axis=-1)
    return np.stack([jc.real, jc.imag], axis=-2)


def joint_jacobian(
    arm: PlanarGeometry,
    q: np.ndarray,
    params: np.ndarray | None = None,
    *,
    target: ArrayLike | None = None,
    deflection: np.ndarray | None = None,
) -> np.ndarray:
    """``d(x, y) / dq`` ``(..., m, 2, n)``: how the tip moves with the joint readings (mm/rad).

    ``theta = M q`` turns link vector ``k`` by ``M[a(k), j]`` per unit of ``q_j``.

    Examples
    --------
    >>> arm = PlanarGeometry([2.0, 1.0])
    >>> (joint_jacobian(arm, np.zeros((1, 2)))[0] + 0.0).tolist()
    [[0.0, 0.0], [3.0, 1.0]]
    """
    jc = link_jacobian(arm, q, params, target=target, deflection=deflection)
    jc = jc @ arm.joint_map[arm.link_joint]
    return np.stack([jc.real, jc.imag], axis=-2)


def link_jacobian(
    arm: PlanarGeometry,
    q: np.ndarray,
    params: np.ndarray | None = None,
    *,
    target: ArrayLike | None = None,
    deflection: np.ndarray | None = None,
) -> np.ndarray:
    """``d tip / d theta_k`` ``(..., m, K)`` as complex numbers: the tip's motion as link
    vector ``k`` turns (mm/rad), ``i z_k u_k``; :func:`joint_jacobian` is it through the
    joint map.

    Examples
    --------
    >>> arm = PlanarGeometry([2.0, 1.0])
    >>> (link_jacobian(arm, np.zeros((1, 2)))[0] + 0.0).tolist()
    [2j, 1j]
    """
    q = _check_q(arm, q)
    terms, _, _ = _tip_terms(arm, q, params, target, deflection)
    return 1j * terms


def tool_angles(
    arm: PlanarGeometry,
    q: np.ndarray,
    params: np.ndarray | None = None,
    *,
    target: ArrayLike | None = None,
) -> np.ndarray:
    """Direction ``(..., m)`` of every row's last link vector (the tool's orientation), rad.

    ``theta_n + alpha_t + dtheta_(n, t)``: the angle of the last link vector of
    the row's target, with the deviations ``params`` (nominal when omitted).
    """
    q = _check_q(arm, q)
    index = check_target(arm, q, target)
    _, dtheta, _ = split_params(arm, params)
    k0 = arm.n_joints - 1
    last = k0 + (0 if index is None else index)
    theta_n = arm.link_angles(q)[..., -1]
    return theta_n + arm.link_angle0[last] + np.take(dtheta, last, axis=-1)
