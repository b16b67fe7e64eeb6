"""The paper's closed-form plans for planar arms: orthogonal (Table I), placed in the limits.

:func:`orthogonal_plan` meets the paper's optimality conditions (21) exactly;
:func:`analytic_plan` places such a plan inside the joint limits and the
measurement region when one fits.  :class:`PaperPlans` is the planar family's
:class:`~armcal.models.interface.ClosedFormPlans`: the plans the designer takes
where they are optimal for the arm's model, and the notes that say why (or why
not).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from functools import cached_property
from typing import cast

import numpy as np

from ...errors import ArmcalError, action
from ..interface import ClosedFormPlan, FitModel, Note
from .design import feasible, model_differences, rotation_invariant
from .geometry import wrap_angle
from .information import plan_rows
from .kinematics import forward_kinematics
from .spec import PlanarArmSpec

__all__ = [
    "BYTES_PER_CANDIDATE_POSE",
    "JOINT1_STEPPING",
    "PAPER",
    "PLACEMENT_CANDIDATES",
    "PLACEMENT_CHUNK_BYTES",
    "PaperPlans",
    "analytic_plan",
    "orthogonal_plan",
]


def _wrap_readings(arm: PlanarArmSpec, q: np.ndarray) -> np.ndarray:
    """Joint readings wrapped into ``(-pi, pi]`` where that keeps every link angle.

    A whole turn of reading ``j`` turns the link angles by ``2 pi M[:, j]``: whole
    turns too when the joint map is integer, otherwise (a gear ratio) not, and then
    the readings are left as solved.
    """
    if np.array_equal(arm.joint_map, np.round(arm.joint_map)):
        return wrap_angle(q)
    return q


def orthogonal_plan(arm: PlanarArmSpec, m: int, *, q1: float = 0.0) -> np.ndarray:
    """A plan that meets the paper's optimality conditions (21) / Table I exactly.

    Parameters
    ----------
    arm : PlanarArmSpec
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
    >>> np.degrees(orthogonal_plan(PlanarArmSpec([2.0, 1.0]), 4)).round(9).tolist()
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
    if not arm.paper_structure:  # the same link angles, read through the arm's joint map
        q = np.linalg.solve(arm.joint_map, np.cumsum(q, axis=1).T).T - arm.joint_offsets
    return _wrap_readings(arm, q)


#: Candidate angles tried for joint 1 in every pose (or, with a base offset, for
#: the plan's common rotation of joint 1) when a measurement region constrains it.
PLACEMENT_CANDIDATES = 720

#: Bytes of working arrays per chunk of poses while joint 1 is placed in a
#: measurement region (see :func:`analytic_plan`).
PLACEMENT_CHUNK_BYTES = 16 * 2**20

#: Upper bound on the bytes of working arrays per (candidate angle, pose) pair
#: while joint 1 is placed in a region: the tip (complex and as x, y), the
#: region's constraint values and gradients (at most 4 of each, 2 doubles per
#: gradient), the score -- fewer than 32 doubles.
BYTES_PER_CANDIDATE_POSE = 256


def _placement_limits(arm: PlanarArmSpec) -> tuple[np.ndarray, np.ndarray]:
    """Where a placed plan's angles lie ``(n,)``: the joint limits, at most one turn wide.

    Limits wider than a turn are narrowed to the turn centred in them (every
    angle has a representative there, and the margins only grow).
    """
    lo, hi = arm.joint_limits[:, 0], arm.joint_limits[:, 1]
    centre = (lo + hi) / 2
    wide = hi - lo > 2 * np.pi
    return np.where(wide, centre - np.pi, lo), np.where(wide, centre + np.pi, hi)


def _shift_margin(shift: np.ndarray, lo: float, hi: float, m: int) -> np.ndarray:
    """Margin (rad) of the ``m`` angles ``shift + 2 pi k / m`` within ``[lo, hi]``; any shape.

    Needs ``0 < hi - lo <= 2 pi``.  Each angle counts at its representative in
    ``[lo, lo + 2 pi)``: the lowest is ``t = lo + mod(shift - lo, h)`` with
    ``h = 2 pi / m`` and the highest ``t + (m - 1) h``, so the margin is
    ``min(t - lo, hi - t - (m - 1) h)``, negative when an angle is outside.
    """
    step = 2 * np.pi / m
    lowest = lo + np.mod(np.asarray(shift, dtype=float) - lo, step)
    return np.minimum(lowest - lo, hi - lowest - (m - 1) * step)


def _best_common_shift(lo: np.ndarray, hi: np.ndarray, m: int) -> tuple[float, float]:
    """The shift ``alpha`` whose angles ``alpha + 2 pi k / m`` lie deepest inside every interval.

    Parameters
    ----------
    lo, hi : ndarray, shape (J,)
        Feasible intervals of ``J`` joints (rad), ``0 < hi - lo <= 2 pi``.
    m : int
        Number of angles, spaced ``h = 2 pi / m`` apart.

    Returns
    -------
    shift : float
        The best ``alpha`` (rad), in ``[0, h)``.
    margin : float
        The smallest distance (rad) from an angle to a limit of its joint at that
        shift (``inf`` without joints); negative when no shift fits every joint.

    Notes
    -----
    Shifting by ``h`` only relabels the angles, so ``alpha`` lives on the circle
    ``R / hZ``.  An angle breaks joint ``j`` when it lies in the forbidden arc
    ``(hi_j, lo_j + 2 pi)`` of length ``gap_j = 2 pi - (hi_j - lo_j)``, so the
    shifts that break joint ``j`` form one arc of that circle, ``(hi_j, hi_j +
    gap_j)`` mod ``h`` (the whole circle when ``gap_j > h``).  Moving ``alpha``
    by ``d`` moves the lowest angle away from ``lo_j`` by ``d`` and the highest
    towards ``hi_j`` by ``d``, so at an allowed shift the margin of joint ``j``
    is the distance along the circle to its blocked arc, and the margin of the
    plan is the distance to the union of the blocked arcs.  It is largest at the
    midpoint of the longest free arc, which starts where a blocked arc ends
    and runs to the next start: those midpoints (and the ends, for free arcs of
    length 0) are the candidates, each evaluated by :func:`_shift_margin`.

    For one joint the free arc has length ``h - gap``: the ``m`` angles fit iff
    ``gap <= 2 pi / m``, and the largest margin is ``(2 pi / m - gap) / 2``, at
    ``alpha = (lo + hi - (m - 1) h) / 2`` (the angles centred in ``[lo, hi]``).
    """
    lo, hi = np.asarray(lo, dtype=float), np.asarray(hi, dtype=float)
    if lo.size == 0:
        return 0.0, math.inf
    step = 2 * np.pi / m
    gap = np.clip(2 * np.pi - (hi - lo), 0.0, None)
    start = np.mod(hi, step)
    end = start + gap
    # Forward distance from the end of arc j to the start of arc i; a start at the
    # very end point (a full-turn joint's point arc, or arc j itself when gap = h)
    # does not close the free arc.
    ahead = np.mod(start[None, :] - end[:, None], step)
    ahead = np.where(ahead == 0, step, ahead)
    np.fill_diagonal(ahead, step - np.minimum(gap, step))
    free = ahead.min(axis=1)
    candidates = np.mod(np.concatenate([end + free / 2, end]), step)
    margins = np.min(
        [_shift_margin(candidates, a, b, m) for a, b in zip(lo, hi, strict=True)], axis=0
    )
    best = int(np.argmax(margins))
    return float(candidates[best]), float(margins[best])


def _placed_angles(shift: float, lo: float, hi: float, m: int) -> np.ndarray:
    """The angles ``shift + 2 pi k / m`` (``k < m``), each at its representative in ``[lo, hi]``.

    When an angle lies outside (by round-off at a margin of 0) it is given the
    representative nearest to the interval.
    """
    offset = np.mod(shift + 2 * np.pi * np.arange(m) / m - lo, 2 * np.pi)  # in [0, 2 pi)
    width = hi - lo
    # Angles past `hi` by more than half the forbidden arc are closer to `lo` from below.
    offset = np.where(offset > width + (2 * np.pi - width) / 2, offset - 2 * np.pi, offset)
    return lo + offset


def analytic_plan(arm: PlanarArmSpec, m: int, *, turn_joint1: bool = False) -> np.ndarray:
    """An orthogonal plan (Table I) placed inside the joint limits and region, if one fits.

    Parameters
    ----------
    arm : PlanarArmSpec
    m : int
        Number of poses; at least ``n`` (``n + 1`` with a base offset).
    turn_joint1 : bool
        Step joint 1 with the others, as with a base offset, even without one:
        for ``m > 2 n`` the plan is then D-optimal under anisotropic or
        correlated instrument noise too (see Notes).

    Returns
    -------
    ndarray, shape (m, n)
        Joint angles in rad, within the joint limits (and within ``[-pi, pi]``
        when the limits allow a full turn about 0); pose ``k`` sets joints 2..n
        to ``alpha + 2 pi k / m``.

    Raises
    ------
    ArmcalError
        If no placement keeps every pose within the limits and region (use
        :func:`optimize_plan` then).  With a region the common shift ``alpha`` is
        the one with the largest joint-limit margin, and only joint 1 is then
        searched against the region: a shift with a smaller margin that also fits
        the region can be missed (the optimizer still finds such plans).

    Notes
    -----
    The optimality conditions (21) hold for the poses of :func:`orthogonal_plan`
    shifted by a common ``alpha`` in joints 2..n (the relative link angles
    ``theta_j - theta_i = (j - i)(alpha + 2 pi k / m)`` still sum to zero), with
    joint 1 free in every pose -- or, with a base offset (or ``turn_joint1``),
    for joint 1 at ``beta + 2 pi k / m`` with any common ``beta``.  The
    placement uses these freedoms:

    * ``alpha`` in closed form (see ``_best_common_shift``): the largest
      smallest distance of joints 2..n to their limits, ``(2 pi / m - gap) / 2``
      for joints sharing one interval of ``2 pi - gap`` rad;
    * joint 1 without a region: the middle of its limits, or ``beta`` by the
      same closed form for its own limits (base offset or ``turn_joint1``);
    * joint 1 with a region: the best of :data:`PLACEMENT_CANDIDATES` angles
      (per pose; when it steps, common rotations ``beta`` over a full turn,
      starting at the closed-form one), scored by the smaller of the joint-1
      limit margin (rad) and the region margin (mm) divided by the arm's reach
      (a turn of joint 1 by ``d`` rad moves the tip by at most ``reach d`` mm).

    **Anisotropic noise.**  With instrument precision ``P`` (relative, ``tr P = 2``,
    :mod:`armcal.noise`) and every parameter free, each pose's information
    ``A^T P A`` has trace ``p`` (``A A^T = (p / 2) I``: each link's two columns,
    and the base's, are orthonormal in the plane), so ``det M <= 1`` for the
    normalized information, with equality iff ``M = I``.  ``P`` adds
    ``Re(b sum_i conj(c_ia c_ib))`` to ``M``, which vanishes when
    ``sum_i exp(i (theta_a + theta_b)) = 0`` for all links ``a, b``: with joint 1
    stepping (``turn_joint1``, or a base offset) ``theta_a + theta_b`` advances
    by ``(a + b) 2 pi / m`` per pose, so ``m > 2 n`` gives ``M = I`` (without a
    base offset; with one the base block stays ``P`` whatever the plan).

    Time and memory are O(m n) without a region.  With one, candidates are
    scored for chunks of poses: the working arrays hold at most
    ``PLACEMENT_CHUNK_BYTES`` bytes (16 MiB: ``PLACEMENT_CANDIDATES`` candidates
    times the chunk's poses times :data:`BYTES_PER_CANDIDATE_POSE`) besides
    the O(m n) plan, and the time is O(m (n + PLACEMENT_CANDIDATES)).

    With a joint map (:attr:`armcal.models.PlanarArm.joint_map`) the plan is the
    same in relative link angles ``r = D M q`` (``D`` the differences of
    consecutive link angles).  When ``D M`` is diagonal (joints that count the
    other way round: ``r_j = -q_j``) the limits are placed through it exactly;
    otherwise (coupled axes) the plan for the relative angles is mapped to
    joint readings and returned only if it keeps within the limits.

    Examples
    --------
    >>> np.degrees(analytic_plan(PlanarArmSpec([2.0, 1.0]), 4)).round(9).tolist()
    [[0.0, 45.0], [0.0, 135.0], [0.0, -135.0], [0.0, -45.0]]
    """
    if not arm.paper_structure:
        return _mapped_analytic_plan(arm, m, turn_joint1=turn_joint1)
    n = arm.n_joints
    min_poses = n + 1 if arm.base_offset else n
    if m < min_poses:
        raise ArmcalError(
            f"an orthogonal plan for {arm.name} needs at least {min_poses} poses, got {m}"
        )
    lo, hi = _placement_limits(arm)
    alpha, margin = _best_common_shift(lo[1:], hi[1:], m)
    if margin < 0:
        raise ArmcalError(
            f"the closed-form orthogonal {m}-pose plan (the paper's Table I family) does not fit "
            f"the joint limits of {arm.name}: joints 2..{n} would each need {m} angles spaced "
            f"{360 / m:g} deg apart; other plans may still be optimal "
            f"({action('method', 'optimize')})"
        )
    q = np.empty((m, n))
    for j in range(1, n):
        q[:, j] = _placed_angles(alpha, lo[j], hi[j], m)
    if arm.base_offset or turn_joint1:
        beta, margin1 = _best_common_shift(lo[:1], hi[:1], m)
        if margin1 < 0:
            raise ArmcalError(
                f"no rotation of the orthogonal {m}-pose plan keeps joint 1 of {arm.name} "
                f"within its limits: it would need {m} angles spaced {360 / m:g} deg apart"
            )
        if arm.region is not None:
            beta = _best_rotation_in_region(arm, q, beta, lo[0], hi[0])
        q[:, 0] = _placed_angles(beta, lo[0], hi[0], m)
    elif arm.region is not None:
        q[:, 0] = _joint1_in_region(arm, q, lo[0], hi[0])
    else:
        q[:, 0] = (lo[0] + hi[0]) / 2
    return q


def _mapped_analytic_plan(arm: PlanarArmSpec, m: int, *, turn_joint1: bool) -> np.ndarray:
    """:func:`analytic_plan` of an arm with a joint map, through the relative link angles."""
    offsets = arm.joint_offsets
    if np.any(offsets):  # plan the readings q + o, whose limits are shifted by o
        shifted = arm.replace(joint_offsets=None, joint_limits=arm.joint_limits + offsets[:, None])
        return analytic_plan(shifted, m, turn_joint1=turn_joint1) - offsets
    n = arm.n_joints
    relative = np.diff(arm.joint_map, axis=0, prepend=0.0)  # r = D M q
    signs = np.diag(relative)
    # The plain arm places the end of link n; the targets' points are checked below.
    plain = arm.replace(joint_map=None, targets=(), base_rotation=False, fixed=())
    if np.array_equal(relative, np.diag(signs)) and np.all(np.abs(signs) == 1):
        lo, hi = (arm.joint_limits * signs[:, None]).T
        limits = np.column_stack([np.minimum(lo, hi), np.maximum(lo, hi)])
        q = analytic_plan(plain.replace(joint_limits=limits), m, turn_joint1=turn_joint1)
        q = q * signs
    else:
        r = analytic_plan(plain.replace(joint_limits=None), m, turn_joint1=turn_joint1)
        q = np.linalg.solve(arm.joint_map, np.cumsum(r, axis=1).T).T
        q = _wrap_readings(arm, q)
    if not np.all(feasible(arm, q)):
        raise ArmcalError(
            f"the closed-form orthogonal {m}-pose plan (the paper's Table I family), read "
            f"through the joint map and targets of {arm.name}, leaves the joint limits of "
            f"joints 1..{n} or puts a target outside the measurement region; other plans may "
            f"still be optimal ({action('method', 'optimize')})"
        )
    return q


def _reach(arm: PlanarArmSpec) -> float:
    return float(np.sum(arm.link_lengths))


def _chunks(m: int, candidates: int, targets: int = 1):
    """Slices of poses whose candidate scores fit in :data:`PLACEMENT_CHUNK_BYTES`."""
    size = max(1, PLACEMENT_CHUNK_BYTES // (BYTES_PER_CANDIDATE_POSE * candidates * targets))
    return (slice(i, min(i + size, m)) for i in range(0, m, size))


def _tip_after_joint1(arm: PlanarArmSpec, q_rest: np.ndarray) -> np.ndarray:
    """Every target's point ``(k, T)`` as complex numbers with joint 1 at 0.

    Joint 1 turns the whole arm about the base (the arm's link angles are
    ``cumsum(q)`` here): the points at ``q1`` are ``exp(i q1)`` times these.
    """
    q = np.concatenate([np.zeros((q_rest.shape[0], 1)), q_rest], axis=1)
    rows, target, _ = plan_rows(arm, q, None)  # every target of every pose
    tip = forward_kinematics(arm, rows, target=target)
    return (tip[:, 0] + 1j * tip[:, 1]).reshape(q.shape[0], arm.n_target_links)


def _region_margin(arm: PlanarArmSpec, tip: np.ndarray) -> np.ndarray:
    """Smallest region constraint ``(...)`` (mm, >= 0 inside) of complex tips ``(...)``."""
    assert arm.region is not None
    g, _ = arm.region.constraints(np.stack([tip.real, tip.imag], axis=-1))
    margin = g[..., 0].copy()
    for i in range(1, g.shape[-1]):  # faster than a reduction over the short last axis
        np.minimum(margin, g[..., i], out=margin)
    return margin


def _joint1_in_region(arm: PlanarArmSpec, q: np.ndarray, lo: float, hi: float) -> np.ndarray:
    """Joint 1 of every pose ``(m,)``: the candidate with the best limit and region margin."""
    candidates = np.linspace(lo, hi, PLACEMENT_CANDIDATES + 1)  # both ends and the middle
    limit_margin = np.minimum(candidates - lo, hi - candidates)[:, None]
    rotation = np.exp(1j * candidates)[:, None]
    reach = _reach(arm)
    q1 = np.empty(q.shape[0])
    for part in _chunks(q.shape[0], candidates.size, arm.n_target_links):
        # (candidates, chunk, T): every target of every pose at every candidate
        tip = rotation[..., None] * _tip_after_joint1(arm, q[part, 1:])[None, :, :]
        region = _region_margin(arm, tip).min(axis=-1)
        score = np.minimum(limit_margin, region / reach)
        best = np.argmax(score, axis=0)
        if np.any(score[best, np.arange(best.size)] < 0):
            raise ArmcalError(
                f"no angle of joint 1 puts every pose of the orthogonal {q.shape[0]}-pose plan "
                f"of {arm.name} inside the measurement region"
            )
        q1[part] = candidates[best]
    return q1


def _best_rotation_in_region(
    arm: PlanarArmSpec, q: np.ndarray, beta: float, lo: float, hi: float
) -> float:
    """The common rotation ``beta`` of joint 1 (base offset) with the best score."""
    m = q.shape[0]
    candidates = beta + 2 * np.pi * np.arange(PLACEMENT_CANDIDATES) / PLACEMENT_CANDIDATES
    rotation = np.exp(1j * candidates)[:, None]
    region = np.full(PLACEMENT_CANDIDATES, np.inf)
    for part in _chunks(m, candidates.size, arm.n_target_links):
        # Pose k turns joint 1 by beta + 2 pi k / m.
        steps = np.exp(2j * np.pi * np.arange(m)[part] / m)
        tip = rotation[..., None] * (steps[:, None] * _tip_after_joint1(arm, q[part, 1:]))[None]
        region = np.minimum(region, _region_margin(arm, tip).min(axis=(1, 2)))
    score = np.minimum(_shift_margin(candidates, lo, hi, m), region / _reach(arm))
    best = int(np.argmax(score))
    if score[best] < 0:
        raise ArmcalError(
            f"no rotation of the orthogonal {m}-pose plan keeps every pose of {arm.name} "
            "inside the joint limits and measurement region"
        )
    return float(candidates[best])


#: Labels of the two closed-form plans: the paper's (joint 1 held still) and the one
#: with joint 1 stepping too.
PAPER, JOINT1_STEPPING = "paper", "joint 1 stepping"


class PaperPlans:
    """The paper's closed-form orthogonal ``m``-pose plans that fit an arm's limits and region.

    The planar family's :class:`~armcal.models.interface.ClosedFormPlans`.  Besides
    the paper's family (joint 1 held still), the one with joint 1 stepping too when
    the model is not invariant to turning joint 1 (anisotropic instrument noise):
    for ``m > 2 n`` it is D-optimal there (:func:`analytic_plan`).
    """

    def __init__(self, arm: PlanarArmSpec, m: int) -> None:
        self._arm = arm
        self.m = m

    @property
    def model(self) -> FitModel:
        """The arm the plans are for (the :class:`~armcal.models.planar.arm.PlanarArm` that
        made them; :meth:`unconstrained` keeps its type)."""
        return cast("FitModel", self._arm)

    @cached_property
    def _placed(self) -> tuple[tuple[ClosedFormPlan, ...], ArmcalError | None]:
        arm, m = self._arm, self.m
        plans: list[ClosedFormPlan] = []
        failure: ArmcalError | None = None
        variants = [False] + ([True] if not (rotation_invariant(arm) or arm.base_offset) else [])
        for turns in variants:
            try:
                q = analytic_plan(arm, m, turn_joint1=turns)
            except ArmcalError as error:
                failure = failure if turns else error
                continue
            plans.append(ClosedFormPlan(q, JOINT1_STEPPING if turns else PAPER))
        return tuple(plans), failure

    @property
    def plans(self) -> tuple[ClosedFormPlan, ...]:
        """The closed-form plans that fit (placed when first asked for)."""
        return self._placed[0]

    @property
    def failure(self) -> ArmcalError | None:
        """Why the paper's own plan does not fit, or None."""
        return self._placed[1]

    def unconstrained(self) -> PaperPlans:
        """The same plans for the arm without joint limits and region."""
        return PaperPlans(self._arm.replace(joint_limits=None, region=None), self.m)

    def unfit(self) -> Note:
        """Why the closed-form plans were not used: only they, not orthogonal plans in general."""
        arm, m = self._arm, self.m
        return Note(
            "plans-unfit",
            {
                "first": 1 if arm.base_offset else 2,  # joint 1 steps when the base is identified
                "last": arm.n_joints,
                "m": m,
                "spacing": 360 / m,
                "region": arm.region is not None,
                "name": arm.name,
            },
        )

    def choice(
        self, chosen: ClosedFormPlan, d_criteria: Mapping[str, float], optimal: bool
    ) -> Note | None:
        """Why the chosen closed-form plan is (or is not) D-optimal for a model not the paper's.

        ``d_criteria``: the D-criterion of every closed-form plan that fits, by label.
        """
        arm = self._arm
        if arm.standard:
            return None
        differences = model_differences(arm)
        if not optimal:
            return Note(
                "closed-not-optimal",
                {"differences": differences, "d": d_criteria[chosen.label]},
            )
        return Note(
            "closed-optimal",
            {
                "differences": differences,
                "free": arm.n_free,
                "stepping": chosen.label == JOINT1_STEPPING,
                "paper_d": d_criteria.get(PAPER),
            },
        )

    def searched(
        self,
        closed_d: float | None,
        plan_d: float,
        method: str,
        would_be_optimal: Callable[[], bool],
    ) -> Note | None:
        """What a searched plan is against the closed-form plans, for a model not the paper's.

        ``closed_d``: the best closed-form plan's D-criterion (None when none fits);
        ``plan_d``: the searched plan's; ``would_be_optimal``: whether a
        closed-form plan would be optimal without the limits and region.
        """
        arm = self._arm
        if arm.standard:
            return None  # the paper's model: the unfit note says why the closed form was not used
        differences = model_differences(arm)
        if closed_d is not None:
            return Note(
                "closed-beaten",
                {"differences": differences, "closed_d": closed_d, "plan_d": plan_d},
            )
        if method == "auto" and not would_be_optimal():
            return Note("closed-never-optimal", {"differences": differences})
        return Note("optimized", {"differences": differences, "free": arm.n_free})
