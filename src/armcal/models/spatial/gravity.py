"""The static torques gravity puts on a spatial arm's joints: the load of joint compliance.

A joint twists under the weight of everything beyond it (issue 23's elastostatic
model for serial arms builds on this).  With link ``k``'s mass ``m_k`` at its
centre of mass ``c_k`` (in the instrument's levelled frame, where gravity is
``g``) and the payload at the tip, the torque about joint ``j``'s axis ``a_j``
through its origin ``p_j`` is

    tau_j = a_j . sum_(k >= j) (c_k - p_j) x m_k g = a_j . (N_j - p_j x F_j)

with ``F_j = sum_(k >= j) m_k g`` and ``N_j = sum_(k >= j) c_k x m_k g``: two
running sums from the tip, so the cost is one forward pass.  A prismatic joint
carries the force along its axis, ``a_j . F_j``.  It is the negative gradient of
the potential energy ``V = -sum_k m_k g . c_k`` in the joint values (the tests
check it so), which fixes every sign.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from .chain import SerialChain, joint_motion

__all__ = ["STANDARD_GRAVITY", "LinkMasses", "chain_frames", "gravity_torques"]

#: Standard gravity, m/s^2 (the CGPM's conventional value).
STANDARD_GRAVITY = 9.80665


@dataclass(frozen=True, eq=False)
class LinkMasses:
    """Every moving link's mass and centre of mass, and a payload at the tip.

    Attributes
    ----------
    mass_kg : ndarray, shape (n,)
        Link ``k``: what joint ``k`` moves up to joint ``k + 1`` (kg).
    com_mm : ndarray, shape (n, 3)
        Its centre of mass in joint ``k``'s frame after the joint's motion (mm).
    """

    mass_kg: np.ndarray
    com_mm: np.ndarray


def chain_frames(
    chain: SerialChain, u: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Every joint's axis and origin ``(..., n, 3)`` (mm), its frame after its motion
    ``(..., n, 4, 4)`` and the tip frame ``(..., 4, 4)``, in the chain's base frame, at
    joint values ``u`` ``(..., n)``."""
    frame = np.broadcast_to(np.eye(4), (*u.shape[:-1], 4, 4))
    axes, origins, after = [], [], []
    for k, kind in enumerate(chain.kinds):
        frame = frame @ chain.origins[k]
        axes.append(frame[..., :3, 2])
        origins.append(frame[..., :3, 3])
        frame = frame @ joint_motion(kind, u[..., k])
        after.append(frame)
    stack = np.stack
    return stack(axes, axis=-2), stack(origins, axis=-2), stack(after, axis=-3), frame @ chain.tip


def gravity_torques(
    chain: SerialChain,
    u: ArrayLike,
    links: LinkMasses,
    gravity: ArrayLike,
    *,
    payload_kg: ArrayLike = 0.0,
    payload_com_mm: ArrayLike = (0.0, 0.0, 0.0),
    frames: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray] | None = None,
) -> np.ndarray:
    """Gravity's torques ``(..., n)`` about every joint (N m; N for a prismatic joint).

    Parameters
    ----------
    chain : SerialChain
    u : ndarray, shape (..., n)
        The joint values (rad, mm).
    links : LinkMasses
    gravity : ndarray, shape (3,)
        The acceleration of gravity in the chain's base frame (m/s^2), e.g.
        ``[0, 0, -STANDARD_GRAVITY]`` for a floor-mounted arm.
    payload_kg : float or ndarray, shape (...)
        A payload at the tip, at ``payload_com_mm`` in the tip frame.
    frames : tuple, optional
        :func:`chain_frames` at ``u``, where the caller has them.

    Examples
    --------
    A horizontal 1 m link of 2 kg with its centre at 500 mm, about a vertical
    joint's perpendicular: a revolute joint about y, gravity along -z.

    >>> from armcal.models.spatial.chain import elementary, transform
    >>> chain = SerialChain(np.array([transform(elementary(0, -np.pi / 2))]), ("R",),
    ...                     np.eye(4), ("j",), np.array([[-np.inf, np.inf]]))
    >>> links = LinkMasses(np.array([2.0]), np.array([[500.0, 0.0, 0.0]]))
    >>> round(float(gravity_torques(chain, [0.0], links, [0, 0, -9.8])[0]), 9)
    9.8
    """
    u = np.asarray(u, dtype=float)
    g = np.asarray(gravity, dtype=float)
    n = chain.n_joints
    axes, origins, after, tip = chain_frames(chain, u) if frames is None else frames
    centres = np.einsum("...kij,kj->...ki", after[..., :3, :3], links.com_mm) + after[..., :3, 3]
    payload = np.asarray(payload_kg, dtype=float)
    payload_at = tip[..., :3, :3] @ np.asarray(payload_com_mm, dtype=float) + tip[..., :3, 3]
    force = payload[..., None] * g  # (..., 3), N
    moment = np.cross(payload_at, force)  # N mm about the base origin
    torques = np.empty((*u.shape[:-1], n))
    for j in range(n - 1, -1, -1):  # running sums from the tip
        weight = links.mass_kg[j] * g
        force = force + weight
        moment = moment + np.cross(centres[..., j, :], weight)
        if chain.kinds[j] == "R":
            about = moment - np.cross(origins[..., j, :], force)
            torques[..., j] = np.einsum("...i,...i->...", axes[..., j, :], about) / 1000.0
        else:
            torques[..., j] = np.einsum("...i,...i->...", axes[..., j, :], force)
    return torques
