"""The general model: controller joint maps, several targets, a base rotation (issue 10).

Checked against an independent tip formula written out link by link, against
central finite differences, and by noiseless recovery to round-off.
"""

import math

import numpy as np
import pytest
from numpy.testing import assert_allclose

from armcal import PlanarArm, identify
from armcal.errors import NotIdentifiableError
from armcal.identification import solve
from armcal.models import (
    Target,
    forward_kinematics,
    jacobian,
    joint_jacobian,
    paper_from_user,
    tool_angles,
)
from armcal.models.planar.closed_form import solve_closed_form
from armcal.reproduction.algorithm import solve_gauss_newton

#: Joint maps of real controllers, 3 joints: the default, joint 2 counted the other
#: way round, joint 3 reported from the horizon (coupled), and both at once.
REVERSED = [[1, 0, 0], [1, -1, 0], [1, -1, 1]]
COUPLED = [[1, 0, 0], [1, 1, 0], [0, 0, 1]]
COUPLED_REVERSED = [[1, 0, 0], [1, -1, 0], [0, 0, -1]]
MAPS = [None, REVERSED, COUPLED, COUPLED_REVERSED]
NEST = (Target("A", 120.0, 0.0), Target("B", 95.0, 0.6), Target("C", 140.0, -0.4))


def independent_tip(q, lengths, targets, mapping, dl, dq, base=(0.0, 0.0), phi0=0.0, label=None):
    """The tip written out from the model's definition, without armcal (mm, rad inputs)."""
    n = len(lengths)
    mapping = np.asarray(mapping, float)
    names = [t.label for t in targets]
    t = names.index(label) if targets else None
    # joint readings with offsets: the shared joints' own, the last one the target's
    offsets = [*dq[: n - 1], dq[n - 1 + (t or 0)]]
    angles = mapping @ (np.asarray(q, float) + np.asarray(offsets))
    x, y = base
    for i in range(n):
        if i < n - 1:
            length, extra, d_length = lengths[i], 0.0, dl[i]
        elif targets:
            length, extra, d_length = targets[t].length, targets[t].angle, dl[n - 1 + t]
        else:
            length, extra, d_length = lengths[i], 0.0, dl[i]
        a = angles[i] + extra + phi0
        x += (length + d_length) * math.cos(a)
        y += (length + d_length) * math.sin(a)
    return x, y


def _arm(mapping, *, targets=(), base=False, rotation=False, fixed=()):
    return PlanarArm(
        [260.0, 180.0, 120.0],
        joint_map=mapping,
        targets=targets,
        base_offset=base,
        base_rotation=rotation,
        fixed=fixed,
        name="arm3",
    )


def _truth(arm, rng):
    k = arm.n_links
    values = np.concatenate([rng.uniform(-2, 2, k), np.radians(rng.uniform(-1, 1, k))])
    if arm.base_offset:
        values = np.concatenate([values, rng.uniform(-30, 30, 2)])
    if arm.base_rotation:
        values = np.concatenate([values, [rng.uniform(-np.pi, np.pi)]])
    return values * arm.free


def _targets_of(arm, m, rng):
    return rng.integers(0, arm.n_target_links, m) if arm.targets else None


@pytest.mark.parametrize("mapping", MAPS)
@pytest.mark.parametrize("targets", [(), NEST])
def test_forward_kinematics_matches_the_written_out_model(mapping, targets, rng):
    arm = _arm(mapping, targets=targets, base=True, rotation=True, fixed=("phi0",))
    q = rng.uniform(-np.pi, np.pi, (6, 3))
    params = _truth(arm, rng)
    params[-1] = 0.3  # a base rotation too, though phi0 is held when identifying
    target = _targets_of(arm, 6, rng)
    tip = forward_kinematics(arm, q, params, target=target)
    k = arm.n_links
    dl, dq, base = params[:k], params[k : 2 * k], params[2 * k : 2 * k + 2]
    full_map = np.tril(np.ones((3, 3))) if mapping is None else np.asarray(mapping, float)
    for i in range(6):
        label = None if target is None else targets[target[i]].label
        expect = independent_tip(
            q[i], [260.0, 180.0, 120.0], targets, full_map, dl, dq, base, 0.3, label
        )
        assert_allclose(tip[i], expect, rtol=0, atol=1e-9)  # mm; round-off of ~600 mm sums


@pytest.mark.parametrize("mapping", MAPS)
def test_jacobians_match_central_differences(mapping, rng):
    arm = _arm(mapping, targets=NEST, base=True, rotation=True, fixed=("phi0",))
    q = rng.uniform(-np.pi, np.pi, (5, 3))
    target = _targets_of(arm, 5, rng)
    params = _truth(arm, rng)
    jac = jacobian(arm, q, params, target=target)
    h = 1e-6
    for j in range(arm.n_params):
        step = np.zeros(arm.n_params)
        step[j] = h
        diff = (
            forward_kinematics(arm, q, params + step, target=target)
            - forward_kinematics(arm, q, params - step, target=target)
        ) / (2 * h)
        # central differences err by h^2 |f'''| ~ 1e-12 * 600 mm, plus round-off 1e-13/h
        assert_allclose(jac[..., j], diff, rtol=0, atol=1e-6)
    jq = joint_jacobian(arm, q, params, target=target)
    for j in range(3):
        step = np.zeros(3)
        step[j] = h
        diff = (
            forward_kinematics(arm, q + step, params, target=target)
            - forward_kinematics(arm, q - step, params, target=target)
        ) / (2 * h)
        assert_allclose(jq[..., j], diff, rtol=0, atol=1e-6)


def test_paper_jacobian_is_the_user_one_through_the_constant_map(rng):
    arm = _arm(COUPLED_REVERSED, targets=NEST, base=True)
    q = rng.uniform(-np.pi, np.pi, (4, 3))
    target = _targets_of(arm, 4, rng)
    params = _truth(arm, rng)
    user = jacobian(arm, q, params, target=target)
    paper = jacobian(arm, q, params, target=target, parametrization="paper")
    assert_allclose(user, paper @ paper_from_user(arm), rtol=0, atol=1e-10)


def test_tool_angle_is_the_last_link_vector_direction(rng):
    arm = _arm(REVERSED, targets=NEST)
    q = rng.uniform(-np.pi, np.pi, (4, 3))
    target = np.array([0, 1, 2, 1])
    params = _truth(arm, rng)
    tip = forward_kinematics(arm, q, params, target=target)
    # the tip minus the tip of the arm without its last link vector points along it
    shorter = params.copy()
    k = arm.n_links
    shorter[2:k] = -arm.link_nominal[2:k]  # every target's last link of length 0
    elbow = forward_kinematics(arm, q, shorter, target=target)
    direction = np.arctan2(*(tip - elbow)[:, ::-1].T)
    got = tool_angles(arm, q, params, target=target)
    assert_allclose(np.angle(np.exp(1j * (got - direction))), 0.0, atol=1e-12)


def test_base_rotation_holds_the_offset_on_its_direction():
    # Default map: turning the base is turning joint 1.
    assert _arm(None, base=True, rotation=True).fixed == ("dq1",)
    # Coupled axes read from the horizon: a base rotation turns every joint reading
    # that is absolute; holding dq1 still removes it (its first joint offset).
    arm = _arm(COUPLED, base=True, rotation=True)
    assert arm.fixed == ("dq1",)
    assert_allclose(arm.rotation_direction[3:6], [-1.0, 0.0, -1.0], atol=1e-12)
    # Holding phi0 instead frees dq1.
    assert _arm(COUPLED, base=True, rotation=True, fixed=("phi0",)).fixed == ("phi0",)


@pytest.mark.parametrize("mapping", MAPS)
@pytest.mark.parametrize("targets", [(), NEST])
@pytest.mark.parametrize("rotation", [False, True])
def test_noiseless_data_are_recovered_to_round_off(mapping, targets, rotation, rng):
    arm = _arm(mapping, targets=targets, base=rotation, rotation=rotation)
    m = 12 * arm.n_target_links
    q = rng.uniform(-np.pi, np.pi, (m, 3))
    target = np.arange(m) % arm.n_target_links if targets else None
    truth = _truth(arm, rng)
    xy = forward_kinematics(arm, q, truth, target=target)
    closed = solve_closed_form(arm, q, xy, target=target)
    newton, _, converged = solve_gauss_newton(arm, q, xy, target=target)
    assert bool(converged)
    for est in (closed, newton):
        # round-off of a least-squares solve on ~500 mm tips: 1e-9 mm, 1e-11 rad
        assert_allclose(est, truth, rtol=0, atol=1e-8)
    cal = identify(arm, q, xy, sigma=0.02, target=target)
    assert_allclose(cal.params, truth, rtol=0, atol=1e-8)
    assert np.all(cal.std[arm.free] > 0)
    assert np.all(cal.std[~arm.free] == 0)


@pytest.mark.parametrize("fixed", [("dl2",), ("phi0", "dl1")])
def test_reduced_general_models_are_recovered(fixed, rng):
    arm = _arm(COUPLED_REVERSED, targets=NEST, base=True, rotation=True, fixed=fixed)
    m = 30
    q = rng.uniform(-np.pi, np.pi, (m, 3))
    target = np.arange(m) % 3
    truth = _truth(arm, rng)
    xy = forward_kinematics(arm, q, truth, target=target)
    found = solve(arm, arm.conditions(q, target=target), xy)
    est, converged = found.params[0], found.converged[0]
    assert bool(converged)
    assert_allclose(est, truth, rtol=0, atol=1e-8)


def test_a_target_never_measured_is_not_identifiable(rng):
    arm = _arm(None, targets=NEST)
    q = rng.uniform(-np.pi, np.pi, (12, 3))
    target = np.arange(12) % 2  # C never measured
    xy = forward_kinematics(arm, q, target=target)
    with pytest.raises(NotIdentifiableError, match="dl3@C"):
        identify(arm, q, xy, sigma=0.02, target=target)


def test_predicted_std_agrees_with_monte_carlo_for_a_general_arm(rng):
    """Batched closed form on 4000 noisy sets: the empirical std within 6 % of the prediction.

    With N = 4000 sets the sample std has relative standard error 1/sqrt(2N) = 1.1 %,
    so 6 % is over 5 of them.
    """
    arm = _arm(COUPLED_REVERSED, targets=NEST, base=True, rotation=True)
    m = 24
    q = rng.uniform(-np.pi, np.pi, (m, 3))
    target = np.arange(m) % 3
    truth = _truth(arm, rng)
    sigma = 0.05
    xy = forward_kinematics(arm, q, truth, target=target)
    sets = xy + sigma * rng.standard_normal((4000, m, 2))
    est = solve_closed_form(arm, q, sets, target=target)
    cal = identify(arm, q, xy, sigma=sigma, target=target)
    free = arm.free
    empirical = np.std(est[:, free] * arm.display_scale[free], axis=0)
    assert_allclose(empirical, cal.std[free], rtol=0.06)
