"""The order of a plan's poses: joint travel, the ordering heuristic, and design's use of it."""

import itertools
from functools import cache

import numpy as np
import pytest
from numpy.testing import assert_allclose

from armcal import ArmcalError
from armcal.doe import joint_travel, order_poses


def test_joint_travel_is_the_sum_of_every_joints_moves():
    q = np.array([[0.1, -0.2], [0.4, 0.3], [-0.5, 0.3]])
    # |0.4 - 0.1| + |0.3 + 0.2| from pose 1 to 2, |-0.5 - 0.4| + 0 from pose 2 to 3
    assert_allclose(joint_travel(q), 0.3 + 0.5 + 0.9, rtol=1e-14, atol=0)
    # the same poses backwards travel as far; one pose travels nowhere
    assert_allclose(joint_travel(q[::-1]), joint_travel(q), rtol=1e-14, atol=0)
    assert joint_travel(q[:1]) == 0.0


def test_joint_travel_does_not_wrap_around():
    # 170 deg to -170 deg passes through 0 (a hard stop at 180 deg): 340 deg, not 20 deg
    q = np.radians([[170.0, 0.0], [-170.0, 0.0]])
    assert_allclose(np.degrees(joint_travel(q)), 340.0, rtol=1e-14, atol=0)


@pytest.mark.parametrize("bad", [np.zeros(4), np.zeros((2, 2, 2)), [[0.0, np.nan], [1.0, 2.0]]])
def test_poses_must_be_a_finite_matrix(bad):
    with pytest.raises(ArmcalError, match="poses must be"):
        joint_travel(bad)
    with pytest.raises(ArmcalError, match="poses must be"):
        order_poses(bad)


def _is_permutation(order: np.ndarray, m: int) -> bool:
    return order.dtype.kind == "i" and np.array_equal(np.sort(order), np.arange(m))


@pytest.mark.parametrize("m", [0, 1, 2, 3, 4, 17, 600])
def test_order_is_a_permutation(m, rng):
    q = rng.uniform(-np.pi, np.pi, size=(m, 3))
    assert _is_permutation(order_poses(q), m)


def test_repeated_and_tied_poses_are_ordered(rng):
    # integer grids: many equal distances and every pose three times
    q = np.repeat(rng.integers(-2, 3, size=(40, 3)).astype(float), 3, axis=0)
    order = order_poses(q)
    assert _is_permutation(order, q.shape[0])
    # equal poses end up next to each other, so no move is longer than the longest needed
    travel = np.abs(np.diff(q[order], axis=0)).sum(axis=1)
    assert np.count_nonzero(travel == 0) >= 2 * 40


def test_poses_on_a_line_are_visited_end_to_end():
    # the shortest open path along a line is the sorted order: travel = the line's length
    t = np.linspace(-3.0, 3.0, 101)
    q = np.stack([t, 0.5 * t, -t], axis=1)[np.random.default_rng(1).permutation(101)]
    assert_allclose(joint_travel(q[order_poses(q)]), 6.0 * 2.5, rtol=1e-12, atol=0)


def test_order_is_deterministic(rng):
    q = rng.uniform(-np.pi, np.pi, size=(300, 4))
    assert np.array_equal(order_poses(q), order_poses(q.copy()))


@cache
def _permutations(m: int) -> np.ndarray:
    return np.array(list(itertools.permutations(range(m))), dtype=np.intp)


def _shortest_travel(q: np.ndarray) -> float:
    """The shortest open path through the poses, by trying every order."""
    distance = np.abs(q[:, None, :] - q[None, :, :]).sum(axis=-1)
    orders = _permutations(q.shape[0])
    return float(distance[orders[:, :-1], orders[:, 1:]].sum(axis=1).min())


def test_order_is_near_the_brute_force_optimum(rng):
    # A heuristic: over 1050 random sets of 3..9 poses of 4 joints it found the shortest
    # order for 99 % of them and was at most 1.6 % longer for the others.  Asserted with
    # a margin: optimal for at least 95 % of these sets, never more than 3 % longer.
    ratios = []
    for m in range(3, 10):
        for _ in range(20):
            q = rng.uniform(-np.pi, np.pi, size=(m, 4))
            order = order_poses(q)
            assert _is_permutation(order, m)
            ratios.append(joint_travel(q[order]) / _shortest_travel(q))
    ratios = np.array(ratios)
    assert ratios.min() >= 1 - 1e-12  # nothing beats the brute force
    assert np.mean(ratios <= 1 + 1e-12) >= 0.95
    assert ratios.max() <= 1.03


def _grid_sweep(q: np.ndarray, lo: float, hi: float) -> np.ndarray:
    """The order of a boustrophedon sweep through a grid of about one pose per cell.

    With ``g = m^(1/n)`` cells per joint, consecutive poses lie in the same or
    adjacent cells, about ``2 (hi - lo) / g`` apart in 4 joints against
    ``4 (hi - lo) / 3`` for a random order: a space-filling baseline.
    """
    m, n = q.shape
    g = max(1, round(m ** (1 / n)))
    cell = np.clip(((q - lo) / (hi - lo) * g).astype(int), 0, g - 1)
    key = np.zeros(m, dtype=np.int64)
    for j in range(n):
        key = key * g + np.where(key % 2 == 1, g - 1 - cell[:, j], cell[:, j])
    return np.argsort(key, kind="stable")


def test_large_plans_are_ordered_in_neighbour_lists(rng):
    # 20 000 poses: no m x m matrix (that alone would take 3.2 GB); speed is for make bench
    q = rng.uniform(-np.pi, np.pi, size=(20_000, 4))
    order = order_poses(q)
    assert _is_permutation(order, q.shape[0])
    assert joint_travel(q[order]) < joint_travel(q[_grid_sweep(q, -np.pi, np.pi)])
