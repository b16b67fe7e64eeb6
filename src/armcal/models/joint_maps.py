"""The one check of a joint map, for every family: square, finite and invertible.

A joint map ``M`` turns the controller's joint readings ``q`` into the angles
the kinematics use (a planar arm's link angles ``theta = M q``, a spatial arm's
URDF joint values ``u = M q``).  Coupled axes make it other than the identity
(a FANUC-style J3 read against the horizon: ``u3 = q2 + q3``).  Every family
checks its map here, and the robot files' one parser
(:func:`armcal.files.robots.read_joint_map`) calls this check too, so a singular
or nearly singular map is refused with the same words from Python and from
either family's robot file.

Why the test is relative.  ``det M`` scales with ``c^n`` when ``M`` is scaled by
``c``: an absolute threshold on it refuses a well-conditioned map whose entries
are small (``1e-5 I`` has ``det = 1e-15``) and accepts a nearly singular one
whose entries are large.  The ratio ``s_n / s_1`` of the smallest to the largest
singular value is scale-free: it is ``1 / cond(M)``, the relative distance of
``M`` to the nearest singular matrix (Eckart-Young).

Why the threshold is :data:`~armcal.numerics.RANK_RTOL` (``1e-10``).  It is
armcal's one rank policy, the line at which a direction of a column-scaled
Jacobian is not identifiable, and a joint map is judged by it for the same two
reasons.  The joint-offset columns of the Jacobian are the angle columns times
``M``, so a direction of readings that ``M`` shrinks to ``1e-10`` of the others
moves no angle the fit can see; and readings recovered from angles,
``q = M^-1 u`` (limits, exports, a controller's zero offsets), err by about
``cond(M) eps``, over ``1e10 * 2.2e-16 ~ 2e-6`` of their scale past it.  No
real map comes near it: the paper's lower-triangular ones have ``cond`` 4 for
3 joints and 16 for 12, the FANUC J2/J3 coupling 2.6, and a coupling of ratio
``r`` (``[[1, 0], [r, 1]]``) about ``r^2``, so even a motor-side ratio of 1000
stays four orders of magnitude clear; a row written twice or a row of zeros
gives ``s_n / s_1`` of round-off, ``1e-16`` or 0.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from ..numerics import RANK_RTOL

__all__ = ["checked_joint_map"]


def checked_joint_map(mapping: ArrayLike, n: int) -> np.ndarray:
    """The joint map ``mapping`` of an arm of ``n`` joints as a float array, checked.

    Parameters
    ----------
    mapping : array_like, shape (n, n)
        The joint map ``M``: the angles the kinematics use are ``M q`` of the
        readings ``q``.
    n : int
        The arm's joints.

    Returns
    -------
    ndarray, shape (n, n)
        ``mapping`` as a new float array.

    Raises
    ------
    ValueError
        For another shape, a value that is not finite, or a map whose smallest
        singular value is at most :data:`~armcal.numerics.RANK_RTOL` times its
        largest (singular or nearly so, see the module's notes).

    Examples
    --------
    >>> checked_joint_map([[1, 0], [1, 1]], 2).tolist()
    [[1.0, 0.0], [1.0, 1.0]]
    >>> checked_joint_map([[1, 0], [1, 0]], 2)  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    ValueError: joint_map must be invertible: every joint angle needs a reading of its own, ...
    """
    matrix = np.array(mapping, dtype=float)
    if matrix.shape != (n, n):
        raise ValueError(f"joint_map must have shape ({n}, {n}), got {matrix.shape}")
    if not np.all(np.isfinite(matrix)):
        raise ValueError("joint_map must be finite")
    s = np.linalg.svd(matrix, compute_uv=False)
    ratio = s[-1] / s[0] if s[0] > 0 else 0.0
    if not ratio > RANK_RTOL:
        raise ValueError(
            "joint_map must be invertible: every joint angle needs a reading of its own, "
            f"but its smallest singular value is {ratio:.2g} times its largest (at most "
            f"{RANK_RTOL:g} is singular); look for a row written twice, a row of zeros or "
            "a row that is the sum of others"
        )
    return matrix
