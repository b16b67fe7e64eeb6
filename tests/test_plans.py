"""Analytic placement of orthogonal plans: closed form against brute force, limits, regions."""

import tracemalloc

import numpy as np
import pytest
from numpy.testing import assert_allclose

from armcal import Annulus, ArmcalError, Box, PlanarArm, forward_kinematics, wrap_angle
from armcal.criteria import d_efficiency
from armcal.doe import analytic_plan, feasible
from armcal.models.planar import plans as plans_module
from armcal.models.planar.criteria import optimality_sums
from armcal.models.planar.plans import _best_common_shift

#: Shifts of the brute-force grid over one turn.  The margin is piecewise linear in
#: the shift with slopes +-1 (each angle moves with the shift), so the best grid
#: point is within half a grid step of the true maximum.
GRID = 36_000
GRID_STEP = 2 * np.pi / GRID


def brute_force_margins(shifts, lo, hi, m):
    """Margin of every shift, the way the old placement grid computed it.

    Angles ``shift + 2 pi k / m`` wrapped into ``(-pi, pi]``; the margin is the
    smallest distance to a limit over angles and joints (negative outside).
    """
    angles = wrap_angle(np.asarray(shifts)[:, None] + 2 * np.pi * np.arange(m) / m)
    per_joint = np.minimum(angles[:, :, None] - lo, hi - angles[:, :, None])
    return per_joint.min(axis=(1, 2))


def random_limits(rng, joints, m):
    """Intervals inside one turn whose forbidden arc ranges over [0, 1.5 * 2 pi / m]."""
    gap = rng.uniform(0.0, 1.5 * 2 * np.pi / m, joints)
    gap[rng.uniform(size=joints) < 0.15] = 0.0  # full-turn joints too
    width = 2 * np.pi - gap
    lo = -np.pi + rng.uniform(0.0, 1.0, joints) * gap
    return lo, lo + width


@pytest.mark.parametrize("joints", [1, 2, 3, 5])
def test_common_shift_closed_form_matches_a_brute_force_grid(joints, rng):
    grid = np.linspace(-np.pi, np.pi, GRID, endpoint=False)
    checked = feasible_seen = 0
    for _ in range(60):
        m = int(rng.integers(2, 13))
        lo, hi = random_limits(rng, joints, m)
        shift, margin = _best_common_shift(lo, hi, m)
        best_on_grid = brute_force_margins(grid, lo, hi, m).max()
        if margin < 0:
            # No shift fits: then no grid shift fits either.
            assert best_on_grid < 0
        else:
            feasible_seen += 1
            # The closed form is the maximum over all shifts: never below the grid's
            # best, and above it by at most half a grid step.
            assert margin >= best_on_grid - 1e-12
            assert margin <= best_on_grid + GRID_STEP / 2 + 1e-12
            # The shift it returns has that margin, evaluated independently.
            at_shift = brute_force_margins(np.array([shift]), lo, hi, m)[0]
            assert at_shift == pytest.approx(margin, abs=1e-12)
        checked += 1
    assert checked == 60 and 0 < feasible_seen < 60  # both outcomes occurred


def test_one_joint_margin_is_half_of_step_minus_gap(rng):
    """The formula of the docs: fits iff gap <= 2 pi / m, margin (2 pi / m - gap) / 2."""
    for _ in range(200):
        m = int(rng.integers(1, 40))
        lo, hi = random_limits(rng, 1, m)
        step, gap = 2 * np.pi / m, 2 * np.pi - (hi[0] - lo[0])
        shift, margin = _best_common_shift(lo, hi, m)
        if gap <= step:
            assert margin == pytest.approx((step - gap) / 2, abs=1e-12)
            # Centred: the lowest and the highest angle are equally far from their limits.
            angles = lo[0] + np.mod(shift + step * np.arange(m) - lo[0], 2 * np.pi)
            assert angles.min() - lo[0] == pytest.approx(hi[0] - angles.max(), abs=1e-12)
        else:
            assert margin < 0


def test_unlimited_joints_get_half_the_spacing_as_margin():
    for m in (1, 2, 3, 7, 20, 1000):
        lo, hi = np.full(3, -np.pi), np.full(3, np.pi)
        _, margin = _best_common_shift(lo, hi, m)
        assert margin == pytest.approx(np.pi / m, rel=1e-12)


def _margins(arm, q):
    lo, hi = arm.joint_limits[:, 0], arm.joint_limits[:, 1]
    return np.minimum(q - lo, hi - q)


@pytest.mark.parametrize("base_offset", [False, True])
@pytest.mark.parametrize("n", [2, 3, 4, 6])
def test_placed_plans_are_orthogonal_within_random_limits(n, base_offset, rng):
    grid = np.linspace(-np.pi, np.pi, GRID, endpoint=False)
    outcomes = set()
    for _ in range(12):
        m = int(rng.integers(n + 1, 30))
        lo, hi = random_limits(rng, n, m)
        arm = PlanarArm(
            rng.uniform(50, 300, n), np.stack([lo, hi], axis=1), base_offset=base_offset
        )
        best_rest = brute_force_margins(grid, lo[1:], hi[1:], m).max()
        best_first = brute_force_margins(grid, lo[:1], hi[:1], m).max() if base_offset else 0.0
        # The true best margin lies in [grid best, grid best + half a step].
        if min(best_rest, best_first) < -GRID_STEP:
            with pytest.raises(ArmcalError, match=r"joint limits|joint 1"):
                analytic_plan(arm, m)
            outcomes.add("refused")
            continue
        if min(best_rest, best_first) < 0:
            continue  # too close to the edge for the grid to judge
        q = analytic_plan(arm, m)
        outcomes.add("placed")
        assert q.shape == (m, n)
        assert np.all(feasible(arm, q)) and np.all(np.abs(q) <= np.pi)
        # Pose k: joints 2..n all at alpha + 2 pi k / m.
        step = wrap_angle(q[:, 1] - q[0, 1] - 2 * np.pi * np.arange(m) / m)
        assert_allclose(np.sin(step), 0, atol=1e-12) and np.all(np.cos(step) > 0)
        for j in range(2, n):
            assert_allclose(wrap_angle(q[:, j] - q[:, 1]), 0, atol=1e-12)
        assert max(abs(v) for v in optimality_sums(arm, q).values()) <= 1e-9 * m
        assert float(d_efficiency(arm, q)) == pytest.approx(1.0, abs=1e-12)
        margins = _margins(arm, q)
        # Joints 2..n get the largest margin any common shift can give.
        assert margins[:, 1:].min() >= best_rest - 1e-12
        assert margins[:, 1:].min() <= best_rest + GRID_STEP / 2 + 1e-12
        if base_offset:
            rotation = wrap_angle(q[:, 0] - q[0, 0] - 2 * np.pi * np.arange(m) / m)
            assert_allclose(np.sin(rotation), 0, atol=1e-12)
            assert margins[:, 0].min() >= best_first - 1e-12
        else:
            assert_allclose(q[:, 0], (lo[0] + hi[0]) / 2, rtol=0, atol=1e-15)
    assert outcomes == {"placed", "refused"}


def test_paper_arm_plan_is_the_textbook_one_centred():
    arm = PlanarArm([260.0, 180.0, 120.0, 100.0])
    q = np.degrees(analytic_plan(arm, 20))
    # Joint 1 mid-limit; joints 2..4 at 9 + 18 k deg: 20 angles 18 deg apart, 9 deg from +-180.
    expected = np.degrees(wrap_angle(np.radians(9.0 + 18.0 * np.arange(20))))
    assert_allclose(q[:, 0], 0.0, atol=1e-12)
    for j in (1, 2, 3):
        assert_allclose(q[:, j], expected, rtol=0, atol=1e-9)


def test_limits_beyond_half_a_turn_are_used_as_they_are():
    """Joints that turn 200..300 deg or more than a full turn: the plan stays inside."""
    limits = np.radians([[200.0, 300.0], [100.0, 460.0], [-400.0, 400.0], [-150.0, 150.0]])
    arm = PlanarArm([260.0, 180.0, 120.0, 100.0], limits)
    # Joint 4 leaves a gap of 60 deg: 12 angles 30 deg apart cannot avoid it ...
    with pytest.raises(ArmcalError, match="joint limits"):
        analytic_plan(arm, 12)
    m = 6  # ... 6 angles 60 deg apart just fit, with margin 0
    q = analytic_plan(arm, m)
    assert np.all(feasible(arm, q))
    assert_allclose(q[:, 0], np.radians(250.0), rtol=0, atol=1e-12)  # middle of 200..300
    assert max(abs(v) for v in optimality_sums(arm, q).values()) <= 1e-9 * m
    assert _margins(arm, q)[:, 1:].min() == pytest.approx(0.0, abs=1e-12)


REGIONS = {
    "box off the base": Box((-100.0, 700.0), (-300.0, 300.0)),
    "annulus off the base": Annulus((200.0, 100.0), 50.0, 500.0),
}

#: Regions a common rotation of the whole plan can satisfy (base offset).
ROTATION_REGIONS = {
    "box off the base": Box((-500.0, 700.0), (-450.0, 700.0)),
    "annulus off the base": Annulus((80.0, -40.0), 20.0, 700.0),
}


def _region_score(arm, q):
    """The documented score of joint 1's placement, from plain forward kinematics."""
    lo, hi = arm.joint_limits[0]
    g, _ = arm.region.constraints(forward_kinematics(arm, q))
    return np.minimum(
        np.minimum(q[..., 0] - lo, hi - q[..., 0]), g.min(axis=-1) / arm.link_lengths.sum()
    )


@pytest.mark.parametrize("name", list(REGIONS))
def test_joint1_is_the_best_candidate_for_the_region(name):
    limits = np.radians([[-150, 170], [-180, 180], [-180, 180], [-180, 180]])
    arm = PlanarArm([260.0, 180.0, 120.0, 100.0], limits, region=REGIONS[name])
    m = 24
    q = analytic_plan(arm, m)
    assert np.all(feasible(arm, q))
    assert max(abs(v) for v in optimality_sums(arm, q).values()) <= 1e-9 * m
    # Every candidate angle of joint 1 for every pose, by forward kinematics.
    candidates = np.linspace(limits[0, 0], limits[0, 1], plans_module.PLACEMENT_CANDIDATES + 1)
    trial = np.repeat(q[None], candidates.size, axis=0)
    trial[:, :, 0] = candidates[:, None]
    best = _region_score(arm, trial).max(axis=0)
    assert_allclose(_region_score(arm, q), best, rtol=0, atol=1e-12)
    assert np.all(best >= 0)
    # The region decides for some poses: joint 1 leaves the middle of its limits.
    assert np.any(np.abs(q[:, 0] - limits[0].mean()) > 0.1)


@pytest.mark.parametrize("name", list(ROTATION_REGIONS))
def test_base_offset_rotation_is_the_best_candidate_for_the_region(name):
    region = ROTATION_REGIONS[name]
    arm = PlanarArm([260.0, 180.0, 120.0, 100.0], base_offset=True, region=region)
    m = 15
    q = analytic_plan(arm, m)
    assert np.all(feasible(arm, q))
    assert max(abs(v) for v in optimality_sums(arm, q).values()) <= 1e-9 * m
    # Rotations beta over a full turn, the same for every pose; score = worst pose.
    count = plans_module.PLACEMENT_CANDIDATES
    beta = q[0, 0] + 2 * np.pi * np.arange(count) / count
    trial = np.repeat(q[None], count, axis=0)
    trial[:, :, 0] = wrap_angle(beta[:, None] + 2 * np.pi * np.arange(m) / m)
    g, _ = arm.region.constraints(forward_kinematics(arm, trial))
    region = g.min(axis=(-2, -1)) / arm.link_lengths.sum()
    limit = np.minimum(trial[:, :, 0] + np.pi, np.pi - trial[:, :, 0]).min(axis=1)
    score = np.minimum(limit, region)
    assert score[0] == pytest.approx(score.max(), abs=1e-12)
    assert score[0] >= 0
    assert np.any(region < limit)  # the region decides, not only the limits


def test_a_region_no_pose_can_reach_is_refused():
    arm = PlanarArm([260.0, 180.0, 120.0, 100.0], region=Box((2000.0, 2100.0), (0.0, 100.0)))
    with pytest.raises(ArmcalError, match="measurement region"):
        analytic_plan(arm, 20)
    arm = PlanarArm(arm.link_lengths, base_offset=True, region=arm.region)
    with pytest.raises(ArmcalError, match="measurement region"):
        analytic_plan(arm, 20)


def _peak_bytes(function):
    tracemalloc.start()
    try:
        function()
        return tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()


def test_memory_is_linear_in_the_poses():
    """m = 10^5 poses: the plan (8 m n bytes) and a few m-vectors, no grid over m.

    The old placement held a 720 x m x (n - 1) grid of angles (1.7 GB here).
    """
    m, n = 100_000, 4
    arm = PlanarArm([260.0, 180.0, 120.0, 100.0])
    peak = _peak_bytes(lambda: analytic_plan(arm, m))
    plan_bytes = 8 * m * n
    assert peak <= plan_bytes + 8 * (8 * m)  # the plan plus eight vectors of m doubles


def test_memory_with_a_region_is_bounded_by_the_chunk():
    """With a region the candidate scores of a chunk of poses add at most PLACEMENT_CHUNK_BYTES.

    Scoring every candidate for all 10^4 poses at once would need about
    720 x 10^4 x 100 bytes = 0.7 GB.
    """
    m, n = 10_000, 4
    limits = np.radians([[-150, 170], [-180, 180], [-180, 180], [-180, 180]])
    arm = PlanarArm([260.0, 180.0, 120.0, 100.0], limits, region=REGIONS["annulus off the base"])
    peak = _peak_bytes(lambda: analytic_plan(arm, m))
    candidates = plans_module.PLACEMENT_CANDIDATES + 1
    assert peak <= 8 * m * n + 8 * (8 * m) + plans_module.PLACEMENT_CHUNK_BYTES + 64 * candidates
