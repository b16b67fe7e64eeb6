"""Calibration plans: the analytic optimal (orthogonal) plan and random plans.

A plan is an array of joint angles ``q`` of shape ``(m, n)`` in rad.
"""

from __future__ import annotations

import numpy as np

from .arm import PlanarArm, wrap_angle
from .errors import ArmcalError

__all__ = ["orthogonal_plan", "random_plan"]


def orthogonal_plan(arm: PlanarArm, m: int, *, q1: float = 0.0) -> np.ndarray:
    """A plan that meets the paper's optimality conditions (21) / Table I exactly.

    Parameters
    ----------
    arm : PlanarArm
    m : int
        Number of poses; at least ``n`` (``n + 1`` with a base offset).
    q1 : float
        Angle of joint 1 (rad) for every pose when the base is not identified.

    Returns
    -------
    ndarray, shape (m, n)
        Joint angles in rad, wrapped into ``(-pi, pi]``.

    Notes
    -----
    Pose ``k = 0..m-1`` sets ``q_j = 2 pi k / m`` for ``j >= 2``, so
    ``theta_j - theta_i = (j - i) 2 pi k / m`` and
    ``sum_k exp(i (theta_j - theta_i)) = 0`` whenever ``0 < j - i < m``: the
    off-diagonal sums ``c_ij, s_ij`` of eq. (18) vanish and the information
    matrix is ``diag(m l_i^2, m)`` (Table II).  With a base offset the sums
    ``sum_k exp(i theta_j)`` must vanish too, so joint 1 also steps by
    ``2 pi k / m`` (then ``theta_j = 2 pi j k / m``, which needs ``m > n``).
    Joint limits and the measurement region are not considered here.

    Examples
    --------
    >>> np.degrees(orthogonal_plan(PlanarArm([2.0, 1.0]), 4)).round(9).tolist()
    [[0.0, 0.0], [0.0, 90.0], [0.0, 180.0], [0.0, -90.0]]
    """
    n = arm.n_joints
    min_poses = n + 1 if arm.base_offset else n
    if m < min_poses:
        raise ArmcalError(
            f"an orthogonal plan for {arm.name} needs at least {min_poses} poses, got {m}"
        )
    step = 2 * np.pi * np.arange(m) / m
    q = np.tile(step[:, None], (1, n))
    if not arm.base_offset:
        q[:, 0] = q1
    return wrap_angle(q)


def random_plan(
    arm: PlanarArm, m: int, rng: np.random.Generator | int | None = None
) -> np.ndarray:
    """``m`` poses drawn uniformly within the joint limits.

    Parameters
    ----------
    arm : PlanarArm
    m : int
        Number of poses.
    rng : numpy.random.Generator or int or None
        Random source or seed.

    Returns
    -------
    ndarray, shape (m, n)
        Joint angles in rad.

    Examples
    --------
    >>> random_plan(PlanarArm([1.0, 1.0, 1.0]), 5, rng=0).shape
    (5, 3)
    """
    rng = np.random.default_rng(rng)
    lo, hi = arm.joint_limits[:, 0], arm.joint_limits[:, 1]
    return rng.uniform(lo, hi, size=(m, arm.n_joints))
