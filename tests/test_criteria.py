"""Plan criteria against closed forms (paper eq. 17-25, Table I-II)."""

import numpy as np
import pytest
from numpy.testing import assert_allclose

from armcal import (
    NotIdentifiableError,
    PlanarArm,
    forward_kinematics,
    identify,
    orthogonal_plan,
    random_plan,
)
from armcal.criteria import (
    CRITERIA,
    d_efficiency,
    efficiencies,
    evaluate_plan,
    observability_indices,
    position_accuracy,
    predicted_std,
)
from armcal.doe.optimizer import _criterion_value_and_gradient
from armcal.models.planar.criteria import dstar, information_matrix, optimality_sums
from helpers import random_arm


@pytest.mark.parametrize("base_offset", [False, True])
@pytest.mark.parametrize("n", [1, 2, 3, 4, 6, 8])
def test_orthogonal_plans_have_the_diagonal_information_of_table_ii(n, base_offset, rng):
    arm = random_arm(n, rng, base_offset=base_offset)
    m = 3 * n + 2
    q = orthogonal_plan(arm, m)
    expected = np.concatenate([m * arm.link_lengths**2, np.full(arm.n_params - n, float(m))])
    # Entries are up to m * 300^2 ~ 2e6 mm^2; off-diagonals vanish to round-off (~1e-15 rel).
    assert_allclose(information_matrix(arm, q), np.diag(expected), rtol=1e-12, atol=1e-8)
    for value in efficiencies(arm, q).values():
        assert value == pytest.approx(1.0, abs=1e-12)
    for value in observability_indices(arm, q).values():
        assert value == pytest.approx(1.0, abs=1e-12)


def test_hadamard_bound_holds_for_random_plans(rng):
    arm = random_arm(5, rng, base_offset=True)
    plans = np.stack([random_plan(arm, 12, rng=rng) for _ in range(500)])
    values = efficiencies(arm, plans)
    for name in CRITERIA:
        assert np.all((values[name] > 0) & (values[name] < 1))
    # D >= A >= E-style ordering of means for positive definite matrices (AM-GM-HM).
    assert np.all(values["D"] >= values["A"] - 1e-12)
    assert np.all(values["A"] >= values["E"] - 1e-12)


def test_dstar_uses_m_and_det_s_vanishes_for_odd_n(rng):
    arm4 = PlanarArm([260.0, 180.0, 120.0, 100.0])
    optimal = dstar(arm4, orthogonal_plan(arm4, 10))
    assert optimal.det_c == pytest.approx(1.0, abs=1e-12)
    assert optimal.abs_det_s == pytest.approx(0.0, abs=1e-12)
    arm3 = PlanarArm([260.0, 180.0, 120.0])
    plans = np.stack([random_plan(arm3, 10, rng=rng) for _ in range(200)])
    assert np.all(dstar(arm3, plans).abs_det_s < 1e-12)  # S skew-symmetric, n odd
    assert np.all(
        dstar(arm4, np.stack([random_plan(arm4, 10, rng=rng) for _ in range(20)])).abs_det_s > 0
    )


def test_optimality_sums_name_the_table_i_conditions():
    arm = PlanarArm([260.0, 180.0, 120.0, 100.0])
    q = np.radians([[10.0, 20.0, 30.0, 40.0]])
    sums = optimality_sums(arm, q)
    assert set(sums) == {
        f"{f}({a})"
        for f in ("cos", "sin")
        for a in ("q2", "q3", "q4", "q2+q3", "q3+q4", "q2+q3+q4")
    }
    assert sums["cos(q2+q3)"] == pytest.approx(np.cos(np.radians(50.0)), abs=1e-15)
    assert sums["sin(q3+q4)"] == pytest.approx(np.sin(np.radians(70.0)), abs=1e-15)
    with_base = optimality_sums(PlanarArm([1.0, 1.0], base_offset=True), q[:, :2])
    assert set(with_base) == {f"{f}({a})" for f in ("cos", "sin") for a in ("q1", "q1+q2", "q2")}


@pytest.mark.parametrize("base_offset", [False, True])
@pytest.mark.parametrize(("n", "m"), [(2, 5), (4, 20), (7, 30)])
def test_position_rms_of_orthogonal_plans_is_sigma_sqrt_2n_over_m(n, m, base_offset, rng):
    arm = random_arm(n, rng, base_offset=base_offset)
    q = orthogonal_plan(arm, m)
    accuracy = position_accuracy(arm, q, random_plan(arm, 200, rng=rng), 0.1)
    k = n + (1 if base_offset else 0)
    assert_allclose(accuracy.per_pose_mm, 0.1 * np.sqrt(2 * k / m), rtol=1e-10)
    assert accuracy.rms_mm == pytest.approx(0.1 * np.sqrt(2 * k / m), rel=1e-10)


def test_predicted_std_equals_the_std_identify_reports_for_nominal_truth(rng):
    arm = random_arm(4, rng, base_offset=True)
    q = random_plan(arm, 15, rng=rng)
    cal = identify(arm, q, forward_kinematics(arm, q), sigma=0.2)
    assert_allclose(predicted_std(arm, q, 0.2), cal.std, rtol=1e-9)


def test_unidentifiable_plan_is_an_error_not_numbers(rng):
    arm = PlanarArm([260.0, 180.0, 120.0, 100.0])
    q = np.tile(random_plan(arm, 1, rng=rng), (6, 1))
    # Six identical poses give 2 independent equations for 8 parameters: rank 2.
    with pytest.raises(NotIdentifiableError, match="rank 2 of 8") as info:
        evaluate_plan(arm, q, sigma=0.1, test_q=random_plan(arm, 10, rng=rng))
    assert len(info.value.combinations) == 6  # the null space has dimension 8 - 2
    for name, value in efficiencies(arm, q).items():
        assert value == 0.0, name
    assert np.all(np.isinf(predicted_std(arm, q, 0.1)))


@pytest.mark.parametrize("criterion", list(CRITERIA))
@pytest.mark.parametrize("base_offset", [False, True])
def test_criterion_gradient_matches_central_differences(criterion, base_offset, rng):
    arm = random_arm(3, rng, base_offset=base_offset)
    q = random_plan(arm, 7, rng=rng)
    value, grad = _criterion_value_and_gradient(arm, q, CRITERIA[criterion])
    h = 1e-6
    numeric = np.zeros_like(q)
    for index in np.ndindex(q.shape):
        step = np.zeros_like(q)
        step[index] = h
        plus, _ = _criterion_value_and_gradient(arm, q + step, CRITERIA[criterion])
        minus, _ = _criterion_value_and_gradient(arm, q - step, CRITERIA[criterion])
        numeric[index] = (plus - minus) / (2 * h)
    # log-efficiencies are O(1) with O(1) curvature: truncation ~h^2, round-off ~1e-16/h.
    assert_allclose(grad, numeric, rtol=0, atol=1e-7)
    assert value == pytest.approx(np.log(efficiencies(arm, q)[criterion]), abs=1e-12)


def test_d_efficiency_is_batched(rng):
    arm = PlanarArm([2.0, 1.0, 0.5])
    plans = np.stack([random_plan(arm, 6, rng=rng) for _ in range(4)])
    batched = d_efficiency(arm, plans)
    assert_allclose(batched, [d_efficiency(arm, p) for p in plans], rtol=1e-12)
