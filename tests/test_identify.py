"""Identification: exact recovery, agreement of the solvers, and honest uncertainty."""

import numpy as np
import pytest
from numpy.testing import assert_allclose

from armcal import (
    ArmcalError,
    NotIdentifiableError,
    PlanarArm,
    forward_kinematics,
    identifiability,
    identify,
    orthogonal_plan,
    paper_from_user_matrix,
    random_plan,
    solve_closed_form,
)
from armcal.report import format_calibration as format_report
from armcal.reproduction.algorithm import solve_gauss_newton
from helpers import random_arm, random_truth

SOLVERS = ["closed-form", "gauss-newton"]


@pytest.mark.parametrize("method", SOLVERS)
@pytest.mark.parametrize("base_offset", [False, True])
@pytest.mark.parametrize("n", [1, 2, 3, 4, 5, 6, 7, 8, 12])
def test_noiseless_data_are_recovered_to_round_off(n, base_offset, method, rng):
    limits = rng.uniform(60.0, 180.0)
    arm = random_arm(n, rng, base_offset=base_offset, limits_deg=limits)
    q = random_plan(arm, 3 * n + 2, rng=rng)
    assert np.all(arm.within_limits(q, tol=0.0))
    truth = random_truth(arm, rng)
    cal = identify(arm, q, forward_kinematics(arm, q, truth), method=method, sigma=0.1)
    assert cal.converged
    # The contract: <= 1e-9 mm / deg for noiseless data.
    assert_allclose(cal.values, truth * arm.display_scale, rtol=0, atol=1e-9)
    assert cal.residual_max < 1e-9


@pytest.mark.parametrize("base_offset", [False, True])
@pytest.mark.parametrize("n", [2, 4, 6, 8])
def test_closed_form_and_gauss_newton_agree_on_noisy_data(n, base_offset, rng):
    arm = random_arm(n, rng, base_offset=base_offset)
    q = random_plan(arm, 4 * n, rng=rng)
    truth = random_truth(arm, rng)
    for sigma in (0.01, 0.1, 0.5):
        xy = forward_kinematics(arm, q, truth) + rng.normal(0.0, sigma, (q.shape[0], 2))
        closed = identify(arm, q, xy, method="closed-form")
        newton = identify(arm, q, xy, method="gauss-newton")
        assert newton.converged
        assert newton.iterations <= 10
        assert_allclose(closed.values, newton.values, rtol=0, atol=1e-9)
        assert_allclose(closed.std, newton.std, rtol=1e-9, atol=0)


def test_closed_form_batches_over_measurement_sets(arm4, paper_truth4, rng):
    q = random_plan(arm4, 15, rng=rng)
    xy = forward_kinematics(arm4, q, paper_truth4) + rng.normal(0.0, 0.1, (6, 15, 2))
    batched = solve_closed_form(arm4, q, xy)
    assert batched.shape == (6, 8)
    for k in range(6):
        assert_allclose(batched[k], solve_closed_form(arm4, q, xy[k]), rtol=0, atol=1e-12)


def test_gauss_newton_reports_non_convergence_honestly(arm4, paper_truth4, rng):
    q = random_plan(arm4, 20, rng=rng)
    xy = forward_kinematics(arm4, q, paper_truth4) + rng.normal(0.0, 0.1, (20, 2))
    _, iterations, converged = solve_gauss_newton(arm4, q, xy, max_iter=1)
    assert (iterations, converged) == (1, False)
    _, iterations, converged = solve_gauss_newton(arm4, q, xy)
    assert converged and 2 <= iterations <= 8


def _monte_carlo(arm, q, truth, sigma, trials, rng):
    clean = forward_kinematics(arm, q, truth)
    xy = clean + rng.normal(0.0, sigma, (trials, *clean.shape))
    return xy, solve_closed_form(arm, q, xy) * arm.display_scale


@pytest.mark.parametrize(
    ("robot", "base_offset", "plan"),
    [
        ("paper", False, "random"),
        ("paper", False, "orthogonal"),
        ("paper", True, "random"),
        ("random6", True, "random"),
    ],
)
def test_reported_std_matches_monte_carlo(robot, base_offset, plan, rng):
    """Paper Section IV: the estimates are unbiased with cov = sigma^2 (J^T J)^-1."""
    if robot == "paper":
        arm = PlanarArm([260.0, 180.0, 120.0, 100.0], base_offset=base_offset)
        truth = arm.params_from_display(
            [1.5, -0.6, -0.4, 0.7], [0.5, -0.5, 0.7, -0.3], [3.0, -4.0] if base_offset else None
        )
    else:
        arm = random_arm(6, rng, base_offset=base_offset)
        truth = random_truth(arm, rng)
    q = random_plan(arm, 20, rng=rng) if plan == "random" else orthogonal_plan(arm, 20)
    sigma, trials = 0.1, 4000
    xy, estimates = _monte_carlo(arm, q, truth, sigma, trials, rng)
    reported = identify(arm, q, xy[0], sigma=sigma).std
    empirical = estimates.std(axis=0, ddof=1)
    # The relative sampling error of a std from 4000 normal draws is 1/sqrt(2*4000) = 1.1 %,
    # so 5 % is a 4.5-sigma bound.
    assert_allclose(empirical, reported, rtol=0.05, atol=0)
    bias = estimates.mean(axis=0) - truth * arm.display_scale
    assert np.all(np.abs(bias) <= 4 * reported / np.sqrt(trials))


def test_gauss_newton_monte_carlo_matches_reported_std(arm4, paper_truth4, rng):
    q = random_plan(arm4, 20, rng=rng)
    sigma, trials = 0.1, 2000
    xy, closed = _monte_carlo(arm4, q, paper_truth4, sigma, trials, rng)
    params, iterations, converged = solve_gauss_newton(arm4, q, xy)
    assert converged.all() and iterations.max() <= 8
    newton = params * arm4.display_scale
    assert_allclose(newton, closed, rtol=0, atol=1e-9)
    # The batched solve is the per-set solve, set by set.
    for k in range(0, trials, 400):
        assert_allclose(params[k], solve_gauss_newton(arm4, q, xy[k])[0], rtol=0, atol=1e-12)
    reported = identify(arm4, q, xy[0], method="gauss-newton", sigma=sigma).std
    # 2000 draws: relative sampling error of a std is 1.6 %, 5 % is a 3-sigma bound.
    assert_allclose(newton.std(axis=0, ddof=1), reported, rtol=0.05, atol=0)
    bias = newton.mean(axis=0) - paper_truth4 * arm4.display_scale
    assert np.all(np.abs(bias) <= 4 * reported / np.sqrt(trials))


@pytest.mark.parametrize("m", [4, 20, 100])
@pytest.mark.parametrize("n", [2, 3, 4])
def test_joint_offset_std_on_orthogonal_plans(n, m):
    """std(dq_i) = sigma/sqrt(m) * sqrt(1/l_i^2 + 1/l_(i-1)^2); std(dl_i) = sigma/sqrt(m)."""
    lengths = np.array([260.0, 180.0, 120.0, 100.0])[:n]
    arm = PlanarArm(lengths)
    q = orthogonal_plan(arm, m)
    sigma = 0.1
    cal = identify(arm, q, forward_kinematics(arm, q), sigma=sigma)
    inv_sq = 1.0 / lengths**2
    expected_dq = sigma / np.sqrt(m) * np.sqrt(inv_sq + np.concatenate([[0.0], inv_sq[:-1]]))
    assert_allclose(cal.std[:n], sigma / np.sqrt(m), rtol=1e-12, atol=0)
    assert_allclose(cal.std[n:], np.degrees(expected_dq), rtol=1e-12, atol=0)


def test_joint_offset_std_uses_the_identified_lengths(arm4, paper_truth4):
    """At the solution the link lengths are l + dl: the std follows the actual arm."""
    q = orthogonal_plan(arm4, 20)
    cal = identify(arm4, q, forward_kinematics(arm4, q, paper_truth4), sigma=0.1)
    actual = arm4.link_lengths + cal.values[:4]
    inv_sq = 1.0 / actual**2
    expected = 0.1 / np.sqrt(20) * np.sqrt(inv_sq + np.concatenate([[0.0], inv_sq[:-1]]))
    assert_allclose(cal.std[4:], np.degrees(expected), rtol=1e-12, atol=0)
    # The cumulative dtheta_i = dq_1 + ... + dq_i are uncorrelated for an orthogonal plan,
    # with std sigma / (sqrt(m) L_i) at the identified lengths L_i = l_i + dl_i.
    to_paper = paper_from_user_matrix(4)
    dtheta_std = np.sqrt(np.diag(to_paper @ cal.covariance @ to_paper.T))[:4]
    assert_allclose(dtheta_std, 0.1 / np.sqrt(20) / actual, rtol=1e-12, atol=0)
    # On the nominal arm they are the paper's Table III, printed to 3 significant digits.
    nominal = identify(arm4, q, forward_kinematics(arm4, q), sigma=0.1)
    dtheta_deg = np.degrees(np.sqrt(np.diag(to_paper @ nominal.covariance @ to_paper.T))[:4])
    assert_allclose(dtheta_deg, [0.00493, 0.00712, 0.01068, 0.01281], rtol=1e-3)


def test_sigma_is_estimated_without_bias(arm4, paper_truth4, rng):
    q = random_plan(arm4, 20, rng=rng)
    clean = forward_kinematics(arm4, q, paper_truth4)
    variances = [
        identify(arm4, q, clean + rng.normal(0.0, 0.2, clean.shape)).sigma_mm ** 2
        for _ in range(400)
    ]
    # s^2 = RSS/(2m - p) with 32 dof: sd of the mean of 400 draws is sqrt(2/32/400) = 1.25 %.
    assert_allclose(np.mean(variances), 0.04, rtol=0.05)


def test_sigma_source_given_or_estimated(arm4, paper_truth4, rng):
    q = random_plan(arm4, 12, rng=rng)
    xy = forward_kinematics(arm4, q, paper_truth4) + rng.normal(0.0, 0.1, (12, 2))
    assert identify(arm4, q, xy).sigma_source == "estimated"
    given = identify(arm4, q, xy, sigma=0.3)
    assert (given.sigma_mm, given.sigma_source) == (0.3, "given")
    with_file_sigma = PlanarArm(arm4.link_lengths, sigma=0.05)
    assert identify(with_file_sigma, q, xy).sigma_mm == 0.05


def test_estimating_sigma_needs_residual_freedom(arm4, paper_truth4, rng):
    q = random_plan(arm4, 4, rng=rng)  # 8 equations, 8 parameters
    xy = forward_kinematics(arm4, q, paper_truth4)
    with pytest.raises(ArmcalError, match="give the instrument noise with sigma or measure"):
        identify(arm4, q, xy)
    cal = identify(arm4, q, xy, sigma=0.1)
    assert cal.dof == 0
    assert np.all(np.isfinite(cal.std))


@pytest.mark.parametrize(
    ("case", "expected_bad"),
    [
        ("too-few", None),
        ("identical", None),
        ("joint4-fixed", {"dl3", "dl4", "dq4"}),
        ("single-q2", {"dl1", "dl2", "dq2"}),
    ],
)
def test_unidentifiable_plans_are_errors_naming_parameters(case, expected_bad, arm4, rng):
    if case == "too-few":
        q = random_plan(arm4, 3, rng=rng)
    elif case == "identical":
        q = np.tile(random_plan(arm4, 1, rng=rng), (10, 1))
    elif case == "joint4-fixed":
        q = random_plan(arm4, 10, rng=rng)
        q[:, 3] = 0.0  # links 3 and 4 always collinear
    else:
        q = random_plan(arm4, 10, rng=rng)
        q[:, 1] = 0.7  # links 1 and 2 always at the same relative angle
    with pytest.raises(NotIdentifiableError, match="not identifiable") as info:
        identify(arm4, q, forward_kinematics(arm4, q), sigma=0.1)
    assert info.value.combinations
    if expected_bad is not None:
        assert set(identifiability(arm4, q).unidentifiable) >= expected_bad
    if case == "too-few":
        assert "at least 4 poses" in str(info.value)


def test_identifiability_of_a_collinear_pair_names_the_combination(rng):
    arm = PlanarArm([2.0, 1.0])
    q = np.column_stack([rng.uniform(-3, 3, 8), np.zeros(8)])
    info = identifiability(arm, q)
    assert info.rank == 2
    # Collinear links: only the sum of the lengths and L1*dtheta1 + L2*dtheta2 are seen,
    # i.e. dl1 - dl2 and the direction (L1 + L2) dq1 + L2 dq2 = 0, dq1 - 3 dq2, are unseen.
    assert info.combinations == ("dl1 - dl2", "dq1 - 3*dq2")


def test_report_lists_every_parameter_with_unit(arm4, paper_truth4, rng):
    q = orthogonal_plan(arm4, 20)
    xy = forward_kinematics(arm4, q, paper_truth4) + rng.normal(0.0, 0.1, (20, 2))
    text = format_report(identify(arm4, q, xy, sigma=0.1), truth=paper_truth4)
    for name in arm4.param_names:
        assert f"\n{name} " in text
    assert "deg" in text and "mm" in text and "given" in text and "nan" not in text.lower()


@pytest.mark.parametrize("dq2_deg", [90.0, 150.0, 179.0])
def test_gauss_newton_reports_large_offsets_in_canonical_form(dq2_deg):
    # (L, dtheta) and (-L, dtheta + pi) are the same link: both solvers must report the
    # positive length and a joint offset in (-180, 180] deg, whichever branch GN reaches.
    arm = PlanarArm([250.0, 180.0, 120.0])
    q = orthogonal_plan(arm, 8)
    truth = arm.params_from_display([0.5, 0.2, 0.1], [0.3, dq2_deg, 0.1])
    xy = forward_kinematics(arm, q, truth)
    for method in SOLVERS:
        cal = identify(arm, q, xy, method=method, sigma=0.1)
        assert_allclose(cal.values, truth * arm.display_scale, rtol=0, atol=1e-9)
