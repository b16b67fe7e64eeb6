"""The arm model: forward kinematics and analytic Jacobians (paper eq. 1, 7-8)."""

import numpy as np
import pytest
from numpy.testing import assert_allclose

from armcal import PlanarArm, forward_kinematics, jacobian, paper_from_user_matrix, wrap_angle
from armcal.doe import random_plan
from helpers import random_arm, random_truth


def test_forward_kinematics_matches_a_hand_computed_pose():
    arm = PlanarArm([260.0, 180.0, 120.0, 100.0])
    q = np.radians([[30.0, -45.0, 90.0, 10.0]])
    theta = np.cumsum(q[0])
    expected = [np.sum(arm.link_lengths * np.cos(theta)), np.sum(arm.link_lengths * np.sin(theta))]
    assert_allclose(forward_kinematics(arm, q)[0], expected, rtol=0, atol=1e-12)


def test_forward_kinematics_applies_deviations_as_paper_eq1():
    arm = PlanarArm([2.0, 1.0], base_offset=True)
    params = arm.params_from_display([0.5, -0.25], [90.0, -90.0], [10.0, 20.0])
    # theta + dtheta = (90, 0) deg: link 1 points up with length 2.5, link 2 right with 0.75.
    assert_allclose(forward_kinematics(arm, np.zeros((1, 2)), params), [[10.75, 22.5]], atol=1e-12)


def test_forward_kinematics_batches_over_parameter_sets(rng):
    arm = random_arm(3, rng)
    q = random_plan(arm, 7, rng=rng)
    params = np.stack([random_truth(arm, rng) for _ in range(5)])
    batched = forward_kinematics(arm, q, params)
    assert batched.shape == (5, 7, 2)
    for k in range(5):
        assert_allclose(batched[k], forward_kinematics(arm, q, params[k]), rtol=0, atol=1e-12)


def _central_difference(arm, q, params, parametrization, h):
    to_paper = paper_from_user_matrix(arm.n_joints, base_offset=arm.base_offset)
    to_user = np.linalg.inv(to_paper)
    base = params if parametrization == "user" else to_paper @ params
    cols = []
    for k in range(arm.n_params):
        step = np.zeros(arm.n_params)
        step[k] = h
        plus, minus = base + step, base - step
        if parametrization == "paper":
            plus, minus = to_user @ plus, to_user @ minus
        cols.append((forward_kinematics(arm, q, plus) - forward_kinematics(arm, q, minus)) / 2 / h)
    return np.stack(cols, axis=-1)


@pytest.mark.parametrize("parametrization", ["user", "paper"])
@pytest.mark.parametrize("base_offset", [False, True])
@pytest.mark.parametrize("n", [1, 2, 3, 4, 7, 12])
def test_jacobian_matches_central_differences(n, base_offset, parametrization, rng):
    arm = random_arm(n, rng, base_offset=base_offset)
    q = random_plan(arm, 6, rng=rng)
    params = random_truth(arm, rng)
    analytic = jacobian(arm, q, params, parametrization=parametrization)
    assert analytic.shape == (6, 2, arm.n_params)
    numeric = _central_difference(arm, q, params, parametrization, h=1e-6)
    # Central differences have O(h^2 |f'''|) ~ 1e-12 * reach truncation and
    # O(eps * reach / h) ~ 1e-7 mm round-off at h = 1e-6; the Jacobian entries are O(reach).
    assert_allclose(analytic, numeric, rtol=0, atol=1e-6)


def test_user_and_paper_jacobians_are_related_by_the_conversion_matrix(rng):
    arm = random_arm(5, rng, base_offset=True)
    q = random_plan(arm, 9, rng=rng)
    params = random_truth(arm, rng)
    to_paper = paper_from_user_matrix(5, base_offset=True)
    j_user = jacobian(arm, q, params)
    j_paper = jacobian(arm, q, params, parametrization="paper")
    assert_allclose(j_user, j_paper @ to_paper, rtol=0, atol=1e-10)


def test_covariance_propagation_between_parametrizations(rng):
    arm = random_arm(4, rng)
    q = random_plan(arm, 12, rng=rng)
    j_user = jacobian(arm, q).reshape(-1, arm.n_params)
    j_paper = jacobian(arm, q, parametrization="paper").reshape(-1, arm.n_params)
    to_paper = paper_from_user_matrix(4)
    cov_paper = np.linalg.inv(j_paper.T @ j_paper)
    to_user = np.linalg.inv(to_paper)
    propagated = to_user @ cov_paper @ to_user.T
    direct = np.linalg.inv(j_user.T @ j_user)
    # Entries range over ~1e-1 .. 1e-6 (mm^2, mm·rad, rad^2); some vanish by symmetry.
    assert_allclose(propagated, direct, rtol=1e-9, atol=1e-15)


def test_paper_from_user_matrix_makes_cumulative_offsets():
    dq = np.array([0.5, -0.5, 0.7, -0.3])
    user = np.concatenate([np.zeros(4), dq])
    paper = paper_from_user_matrix(4) @ user
    assert_allclose(paper[:4], np.cumsum(dq), rtol=0, atol=1e-15)


def test_wrap_angle_range():
    angles = np.linspace(-10, 10, 1001)
    wrapped = wrap_angle(angles)
    assert np.all((wrapped > -np.pi) & (wrapped <= np.pi))
    assert_allclose(np.exp(1j * wrapped), np.exp(1j * angles), rtol=0, atol=1e-12)


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"link_lengths": []}, "n >= 1"),
        ({"link_lengths": [1.0, -2.0]}, "positive"),
        ({"link_lengths": [1.0], "joint_limits": [[1.0, -1.0]]}, "lo < hi"),
        ({"link_lengths": [1.0, 1.0], "joint_limits": [[-1.0, 1.0]]}, "shape"),
    ],
)
def test_planar_arm_rejects_invalid_geometry(kwargs, match):
    with pytest.raises(ValueError, match=match):
        PlanarArm(**kwargs)


def test_arm_is_immutable():
    arm = PlanarArm([1.0, 2.0])
    with pytest.raises(ValueError):
        arm.link_lengths[0] = 3.0
