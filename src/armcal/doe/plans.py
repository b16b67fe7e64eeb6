"""Calibration plans that need no search: orthogonal, analytic (placed), random; feasibility."""

from __future__ import annotations

import numpy as np

from ..arm import PlanarArm, forward_kinematics, wrap_angle
from ..errors import ArmcalError

__all__ = [
    "analytic_plan",
    "feasible",
    "feasible_poses",
    "orthogonal_plan",
    "random_plan",
]


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


def feasible(arm: PlanarArm, q: np.ndarray, *, tol: float = 1e-9) -> np.ndarray:
    """Mask ``(..., m)`` of poses inside the joint limits and (if any) the measurement region."""
    ok = np.all(arm.within_limits(q, tol=tol), axis=-1)
    if arm.region is not None:
        ok &= arm.region.contains(forward_kinematics(arm, q), tol=tol)
    return ok


def feasible_poses(
    arm: PlanarArm, k: int, rng: np.random.Generator | int | None = None
) -> np.ndarray:
    """``k`` poses ``(k, n)`` uniform in the joint limits, restricted to the region.

    Raises
    ------
    ArmcalError
        If fewer than 1 in 10 000 random poses reach the measurement region.
    """
    rng = np.random.default_rng(rng)
    found: list[np.ndarray] = []
    count, drawn = 0, 0
    while count < k:
        batch = random_plan(arm, max(4 * k, 1000), rng)
        drawn += batch.shape[0]
        batch = batch[feasible(arm, batch)]
        found.append(batch)
        count += batch.shape[0]
        if count == 0 and drawn >= 10_000:
            raise ArmcalError(
                f"{arm.name}: no random pose within the joint limits puts the tip inside the "
                "measurement region; check the region and the limits"
            )
    return np.concatenate(found)[:k]


def analytic_plan(arm: PlanarArm, m: int) -> np.ndarray:
    """An orthogonal plan (Table I) placed inside the joint limits and region, if one fits.

    The conditions are invariant to a common shift ``alpha`` of joints 2..n and,
    without a base offset, to the angle of joint 1 in each pose; with a base
    offset, to a common rotation of joint 1.  These freedoms are searched on a
    fine grid for the placement with the largest margin to the limits and region.

    Raises
    ------
    ArmcalError
        If no such placement keeps every pose within the limits and region (use
        :func:`optimize_plan` then).
    """
    base = orthogonal_plan(arm, m)
    n = arm.n_joints
    grid = np.linspace(-np.pi, np.pi, 721)[:-1]
    lo, hi = arm.joint_limits[:, 0], arm.joint_limits[:, 1]
    # Common shift of joints 2..n: margin of every candidate shift (grid, m, n-1).
    shifted = wrap_angle(base[None, :, 1:] + grid[:, None, None])
    margin = np.minimum(shifted - lo[1:], hi[1:] - shifted).min(axis=(1, 2), initial=np.inf)
    if margin.max() < 0:
        raise ArmcalError(
            f"no orthogonal {m}-pose plan fits the joint limits of {arm.name}: joints 2..{n} "
            f"would each need {m} angles spaced {360 / m:g} deg apart"
        )
    q = base.copy()
    q[:, 1:] = shifted[int(np.argmax(margin))]
    if arm.base_offset:
        rotated = wrap_angle(base[None, :, 0] + grid[:, None])  # (grid, m)
        candidates = np.repeat(q[None], grid.size, axis=0)
        candidates[:, :, 0] = rotated
        score = _placement_margin(arm, candidates).min(axis=1)
        if score.max() < 0:
            raise ArmcalError(
                f"no rotation of the orthogonal {m}-pose plan keeps every pose of {arm.name} "
                "inside the joint limits and measurement region"
            )
        return candidates[int(np.argmax(score))]
    # Joint 1 is free pose by pose: choose the angle with the largest margin.
    candidates = np.repeat(q[None], grid.size, axis=0)
    candidates[:, :, 0] = grid[:, None]
    score = _placement_margin(arm, candidates)  # (grid, m)
    best = np.argmax(score, axis=0)
    if np.any(score[best, np.arange(m)] < 0):
        raise ArmcalError(
            f"no angle of joint 1 puts every pose of the orthogonal {m}-pose plan of {arm.name} "
            "inside the measurement region"
        )
    q[:, 0] = grid[best]
    return q


def _placement_margin(arm: PlanarArm, q: np.ndarray) -> np.ndarray:
    """Smallest margin (rad for limits, mm for the region) of each pose ``(..., m)``."""
    lo, hi = arm.joint_limits[:, 0], arm.joint_limits[:, 1]
    margin = np.minimum(q - lo, hi - q).min(axis=-1)
    if arm.region is not None:
        g, _ = arm.region.constraints(forward_kinematics(arm, q))
        margin = np.minimum(margin, g.min(axis=-1))
    return margin
