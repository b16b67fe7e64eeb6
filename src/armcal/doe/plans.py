"""Plans that need no search, and the poses a plan may hold: random, feasible, distinct.

The family's closed-form plans (the planar arm's orthogonal plans of the
paper) are the family's own (:meth:`~armcal.models.interface.FitModel.closed_form_plans`).
"""

from __future__ import annotations

import numpy as np

from ..choices import DISTINCT_TOLERANCE
from ..errors import ArmcalError
from ..models import FitModel

__all__ = [
    "DISTINCT_TOLERANCE",
    "feasible",
    "feasible_poses",
    "random_plan",
    "repeated_poses",
]


def random_plan(
    model: FitModel, m: int, *, rng: np.random.Generator | int | None = None
) -> np.ndarray:
    """``m`` poses drawn uniformly within the joint limits.

    Parameters
    ----------
    model : FitModel
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
    >>> from armcal.models import PlanarArm
    >>> random_plan(PlanarArm([1.0, 1.0, 1.0]), 5, rng=0).shape
    (5, 3)
    """
    rng = np.random.default_rng(rng)
    lo, hi = model.joint_limits[:, 0], model.joint_limits[:, 1]
    return rng.uniform(lo, hi, size=(m, model.n_joints))


def feasible(model: FitModel, q: np.ndarray, *, tol: float = 1e-9) -> np.ndarray:
    """Mask ``(..., m)`` of poses within the joint limits and the instrument's view.

    (:meth:`~armcal.models.interface.FitModel.feasible`; for a planar arm every
    target's point in the measurement region.)
    """
    return model.feasible(q, tol=tol)


def repeated_poses(q: np.ndarray, *, tol: float = DISTINCT_TOLERANCE) -> np.ndarray:
    """Mask ``(m,)`` of poses that repeat an earlier pose of ``q`` ``(m, n)``.

    Pose ``j`` repeats pose ``i < j`` when ``|q_j - q_i| <= tol`` (rad) on every
    joint.  Every pose within ``tol`` of an earlier one is marked, so the poses
    not marked are pairwise distinct.

    Examples
    --------
    >>> repeated_poses(np.array([[0.0, 1.0], [0.5, 1.0], [0.0, 1.0 + 1e-9]])).tolist()
    [False, False, True]
    """
    from scipy.spatial import cKDTree  # ~0.3 s to import: keep scipy off `import armcal`

    q = np.asarray(q, dtype=float)
    marked = np.zeros(q.shape[0], dtype=bool)
    if q.shape[0] > 1:
        pairs = cKDTree(q).query_pairs(tol, p=np.inf, output_type="ndarray")  # i < j
        marked[pairs[:, 1]] = True
    return marked


#: Poses moved onto the instrument at once by :func:`feasible_poses`: its memory stays
#: that of a few thousand poses however many are drawn (a camera's 80 000 poses of 48
#: corners each took 4.5 GB at once).
MEET_CHUNK = 2048


def feasible_poses(
    model: FitModel, k: int, *, rng: np.random.Generator | int | None = None
) -> np.ndarray:
    """``k`` poses ``(k, n)`` uniform in the joint limits, restricted to the region, each
    moved to meet the instrument where one must (a touch of a plane: the model's
    :meth:`~armcal.models.interface.FitModel.meeting_poses`; those that cannot are
    left out).

    Raises
    ------
    ArmcalError
        If none of 10 000 random poses reaches the measurement region or meets the
        instrument.
    """
    rng = np.random.default_rng(rng)
    found: list[np.ndarray] = []
    count, drawn = 0, 0
    while count < k:
        batch = random_plan(model, max(4 * k, 1000), rng=rng)
        drawn += batch.shape[0]
        batch = batch[model.feasible(batch)]
        for i in range(0, batch.shape[0], MEET_CHUNK):  # a camera's pose is 48 rows
            moved, met = model.meeting_poses(batch[i : i + MEET_CHUNK])
            moved = moved[met]
            if model.constrained and moved.shape[0]:  # moved: within what a plan keeps to
                moved = moved[model.feasible(moved)]
            found.append(moved)
            count += moved.shape[0]
            if count >= k:  # the rest of the batch would be cut off below: not moved
                break
        if count == 0 and drawn >= 10_000:
            raise ArmcalError(
                f"{model.name}: no random pose within the joint limits "
                + (
                    "meets the instrument where the robot file places it (a plane or a point "
                    "out of reach, a distance's range no pose reaches); check [instrument]"
                    if model.constrained
                    else "puts the tip inside the measurement region; check the region and "
                    "the limits"
                )
            )
    return np.concatenate(found)[:k]
