"""identify() judges its fit: goodness of fit, outliers, robust fits, noise models, fixed params.

Every expectation is derived here: exact laws of the test statistics, dense
generalized-least-squares references, brute-force leave-one-out refits.
"""

from __future__ import annotations

import numpy as np
import pytest

from armcal.cli import CLI_ACTIONS
from armcal.doe import random_plan
from armcal.errors import ArmcalError
from armcal.identification import HUBER_K, identify, solve
from armcal.identification.judgement import FEW_DOF, OUTLIER_ALPHA, studentized_test
from armcal.models import PlanarArm, forward_kinematics, jacobian
from armcal.noise import NoiseModel
from armcal.paper import paper_arm
from armcal.synthesis import synthesize_measurements

SIGMA = 0.02  # mm, a laser tracker


def _dataset(seed: int, m: int = 30, sigma: float = SIGMA):
    arm, truth = paper_arm(4)
    rng = np.random.default_rng(seed)
    q = random_plan(arm, m, rng=rng)
    return arm, truth, q, synthesize_measurements(arm, q, truth, sigma, rng=rng)


def _codes(cal) -> list[str]:
    return [w.code for w in cal.warnings]


def _gls_covariance(arm: PlanarArm, q: np.ndarray, params: np.ndarray, cov_i: np.ndarray):
    """Dense reference (sum_i J_i^T Sigma_i^-1 J_i)^-1 over the free parameters, in p x p."""
    jac = jacobian(arm, q, params)[..., arm.free]
    info = sum(j.T @ np.linalg.inv(c) @ j for j, c in zip(jac, cov_i, strict=True))
    out = np.zeros((arm.n_params, arm.n_params))
    out[np.ix_(arm.free, arm.free)] = np.linalg.inv(info)
    return out


def _assert_covariance(actual: np.ndarray, reference: np.ndarray) -> None:
    # Relative to the largest entry: off-diagonal zeros are round-off of ~1e-22.
    np.testing.assert_allclose(actual, reference, rtol=0, atol=1e-9 * np.max(np.abs(reference)))


# ----------------------------------------------------------------- goodness of fit


def test_chi2_of_clean_fits_follows_its_law():
    # chi2 on dof = 2m - p degrees of freedom has mean dof and variance 2 dof; the mean
    # of 200 fits lies within 4 standard errors sqrt(2 dof / 200) of dof.
    values = []
    for seed in range(200):
        arm, _, q, xy = _dataset(seed)
        cal = identify(arm, q, xy, sigma=SIGMA)
        assert cal.goodness_of_fit.dof == 2 * 30 - 8
        values.append(cal.goodness_of_fit.chi2)
    dof = 52
    assert abs(np.mean(values) - dof) < 4 * np.sqrt(2 * dof / 200)


def test_fit_inconsistent_with_sigma_warns_with_causes_in_order():
    arm, _, q, xy = _dataset(1, sigma=0.1)  # data five times noisier than claimed
    cal = identify(arm, q, xy, sigma=SIGMA)
    assert cal.goodness_of_fit.p_value < 1e-3
    (warning,) = [w for w in cal.warnings if w.code == "fit-inconsistent"]
    text = warning.message
    order = [text.index(word) for word in ("outliers", "unit", "model", "sigma too small")]
    assert order == sorted(order)
    # The residuals suggest sigma: sqrt(chi2 / dof) * 0.02 is near the true 0.1 mm.
    suggested = float(text.rsplit("about ", 1)[1].split(" mm")[0])
    assert 0.08 < suggested < 0.12


def test_estimated_sigma_has_no_test_and_no_warning():
    arm, _, q, xy = _dataset(2, sigma=0.1)
    cal = identify(arm, q, xy)
    assert cal.sigma_source == "estimated"
    assert cal.goodness_of_fit.chi2 is None and cal.goodness_of_fit.p_value is None
    assert "fit-inconsistent" not in _codes(cal)


def test_zero_degrees_of_freedom_with_sigma_given_warns():
    arm, truth = paper_arm(3)  # 6 parameters, 3 poses: 6 equations
    q = np.radians([[0, 0, 0], [60, 120, -90], [-45, 90, 150]])
    cal = identify(arm, q, forward_kinematics(arm, q, truth), sigma=SIGMA)
    assert cal.goodness_of_fit.dof == 0
    (warning,) = [w for w in cal.warnings if w.code == "few-dof"]
    assert "0 degrees of freedom" in warning.message
    # FEW_DOF - 0 more equations need ceil(FEW_DOF / 2) more poses.
    assert f"at least {-(-FEW_DOF // 2)} more poses" in warning.message


# ----------------------------------------------------------------- outliers


def _with_outliers(seed: int):
    arm, truth, q, xy = _dataset(seed)
    rng = np.random.default_rng(seed + 10_000)
    rows = rng.choice(30, size=2, replace=False)
    size = rng.uniform(3.0, 5.0, size=2)  # mm, 150 to 250 sigma
    angle = rng.uniform(0, 2 * np.pi, size=2)
    xy = xy.copy()
    xy[rows] += (size * np.array([np.cos(angle), np.sin(angle)])).T
    return arm, truth, q, xy, sorted(int(r) + 1 for r in rows)


@pytest.mark.parametrize("seed", [3, 4, 5])
def test_two_gross_outliers_are_flagged_and_left_out(seed):
    arm, truth, q, xy, rows = _with_outliers(seed)
    cal = identify(arm, q, xy, sigma=SIGMA, robust=True)
    assert [o.row for o in cal.outliers] == rows
    assert all(o.removed for o in cal.outliers)
    assert cal.n_used == 28 and cal.goodness_of_fit.dof == 2 * 28 - 8
    # After leaving them out the fit is least squares on clean data: within 4 std.
    error = (cal.params - truth) * arm.display_scale / cal.std
    assert np.max(np.abs(error)) < 4
    assert "outlier" in _codes(cal) and "fit-inconsistent" not in _codes(cal)


def test_plain_fit_warns_about_the_same_poses_and_keeps_them():
    arm, _, q, xy, rows = _with_outliers(6)
    cal = identify(arm, q, xy, sigma=SIGMA)
    assert [o.row for o in cal.outliers] == rows
    assert not any(o.removed for o in cal.outliers)
    assert cal.n_used == 30
    (warning,) = [w for w in cal.warnings if w.code == "outlier"]
    assert all(f"row {r} " in warning.message for r in rows)
    # the library's words name the option, the command line's the flag
    assert "robust=True" in warning.message
    assert "--robust" in warning.render(CLI_ACTIONS)


def test_robust_fit_with_estimated_sigma_finds_them_too():
    arm, _, q, xy, rows = _with_outliers(7)
    cal = identify(arm, q, xy, robust=True)
    assert [o.row for o in cal.outliers] == rows
    assert abs(cal.sigma_mm / SIGMA - 1) < 0.5  # 56 - 8 dof: the estimate is within ~10 %


def test_false_alarms_on_clean_data_are_rare():
    # Bonferroni bounds the chance that any pose of a clean fit is flagged by
    # OUTLIER_ALPHA = 0.001: over 100 datasets the expected count is 0.1 and
    # P(count >= 3) < 2e-4 (Poisson).  `make bench` runs 1000 and prints the rate.
    alarms = 0
    for seed in range(100):
        arm, _, q, xy = _dataset(20_000 + seed)
        alarms += bool(identify(arm, q, xy, sigma=SIGMA, robust=True).outliers)
    assert OUTLIER_ALPHA == 1e-3
    assert alarms < 3


@pytest.mark.slow
def test_false_alarm_rate_over_1000_clean_datasets_is_at_most_one_percent():
    # The robust fit, the one that leaves poses out.  `make bench`
    # (benchmarks/bench_outliers.py) prints the rates of every kind of fit.
    alarms = 0
    for seed in range(1000):
        arm, _, q, xy = _dataset(30_000 + seed)
        alarms += bool(identify(arm, q, xy, sigma=SIGMA, robust=True).outliers)
    print(f"false alarms over 1000 clean datasets: {alarms / 10:.1f} %")
    assert alarms <= 10


def test_studentized_statistic_equals_a_leave_one_out_refit():
    # With sigma estimated, pose i's statistic is its prediction error from a fit
    # without it, over the scale of that fit: refit without each pose and compare.
    arm, _, q, xy = _dataset(8, m=12)
    cal = identify(arm, q, xy)
    expected = []
    for i in range(12):
        keep = np.arange(12) != i
        sub = identify(arm, q[keep], xy[keep])
        e = xy[i] - forward_kinematics(arm, q[i : i + 1], sub.params)[0]
        j = jacobian(arm, q[i : i + 1], sub.params)[0]
        v = sub.sigma_mm**2 * np.eye(2) + j @ sub.covariance @ j.T
        expected.append(np.sqrt(e @ np.linalg.solve(v, e)))
    # Leverages B_i B_i^T = J_i (J^T J)^-1 J_i^T = J_i cov J_i^T / sigma^2 of the full fit.
    jac = jacobian(arm, q, cal.params)
    leverage = jac @ (cal.covariance / cal.sigma_mm**2) @ np.swapaxes(jac, 1, 2)
    test = studentized_test(
        cal.residuals / cal.sigma_mm, leverage, np.ones(12, bool), 8, sigma_given=False
    )
    # The leave-one-out refit is linearized at its own estimate; the formula at the
    # full fit's: they agree to the model's curvature over a 0.02 mm noise, ~1e-6.
    np.testing.assert_allclose(test.statistic, expected, rtol=1e-5)


def test_huber_constant_is_the_95_percent_point_of_a_clean_pose():
    # A clean pose's standardized distance^2 is chi2(2), P(d > k) = exp(-k^2 / 2).
    assert np.isclose(np.exp(-(HUBER_K**2) / 2), 0.05)


# ----------------------------------------------------------------- noise models


@pytest.mark.parametrize(
    "noise",
    [
        NoiseModel.per_axis(4 * SIGMA, SIGMA),
        NoiseModel.isotropic(SIGMA, np.radians(0.01)),
        NoiseModel([[4e-4, 1e-4], [1e-4, 2e-4]], np.radians([0.01, 0.02, 0.0, 0.01])),
    ],
    ids=["per-axis", "encoder", "covariance+encoder"],
)
def test_weighted_fit_recovers_noiseless_data_and_has_the_gls_covariance(noise):
    arm, truth = paper_arm(4)
    arm = arm.replace(noise=noise)
    q = random_plan(arm, 25, rng=9)
    cal = identify(arm, q, forward_kinematics(arm, q, truth))
    np.testing.assert_allclose(cal.params, truth, rtol=0, atol=1e-11)
    reference = _gls_covariance(arm, q, cal.params, arm.covariances_at(q, cal.params, noise=noise))
    _assert_covariance(cal.covariance, reference)
    assert cal.sigma_source == "given"


def test_weighted_fit_is_the_gls_estimate():
    # The weighted closed form minimizes sum e_i^T Sigma_i^-1 e_i: its gradient
    # J^T Sigma^-1 e vanishes at the estimate (Sigma_i fixed: no encoder noise).
    arm, truth = paper_arm(4)
    arm = arm.replace(noise=NoiseModel([[1.6e-3, 3e-4], [3e-4, 4e-4]]))
    q = random_plan(arm, 25, rng=10)
    xy = synthesize_measurements(arm, q, truth, 0.04, rng=11)
    cal = identify(arm, q, xy)
    jac = jacobian(arm, q, cal.params)
    inv = np.linalg.inv(arm.noise.covariance_mm2)
    gradient = np.einsum("mip,ij,mj->p", jac, inv, cal.residuals)
    scale = np.einsum("mip,ij,mj->p", np.abs(jac), np.abs(inv), np.abs(cal.residuals))
    assert np.max(np.abs(gradient) / scale) < 1e-10


def test_per_row_sigma_weights_rows_and_sets_the_reference():
    arm, truth, q, _ = _dataset(12)
    row_sigma = np.where(np.arange(30) < 10, 0.05, 0.02)
    cal = identify(arm, q, forward_kinematics(arm, q, truth), row_sigma=row_sigma)
    np.testing.assert_allclose(cal.params, truth, atol=1e-11)
    cov_i = row_sigma[:, None, None] ** 2 * np.eye(2)
    _assert_covariance(cal.covariance, _gls_covariance(arm, q, truth, cov_i))
    assert np.isclose(cal.sigma_mm, np.sqrt(1 / np.mean(1 / row_sigma**2)))


def test_sigma_option_replaces_the_instrument_noise_and_keeps_the_encoders():
    arm, truth = paper_arm(4)
    arm = arm.replace(noise=NoiseModel.per_axis(0.1, 0.1, np.radians(0.01)))
    q = random_plan(arm, 20, rng=13)
    cal = identify(arm, q, forward_kinematics(arm, q, truth), sigma=SIGMA)
    assert cal.arm.noise.isotropic_instrument and cal.sigma_mm == pytest.approx(SIGMA)
    np.testing.assert_allclose(cal.arm.noise.joint_sigma, np.radians(0.01))


# ----------------------------------------------------------------- fixed parameters


def test_known_last_link_recovers_the_rest():
    arm, truth = paper_arm(4)
    arm = arm.replace(fixed=("dl4",), sigma=SIGMA)
    truth = truth.copy()
    truth[3] = 0.0  # measured otherwise: held at its nominal value
    q = random_plan(arm, 20, rng=14)
    cal = identify(arm, q, forward_kinematics(arm, q, truth))
    assert cal.method == "gauss-newton" and cal.converged
    np.testing.assert_allclose(cal.params, truth, atol=1e-11)
    assert cal.std[3] == 0 and np.all(cal.std[[0, 1, 2, 4, 5, 6, 7]] > 0)
    assert cal.goodness_of_fit.dof == 2 * 20 - 7
    cov_i = np.broadcast_to(SIGMA**2 * np.eye(2), (20, 2, 2))
    _assert_covariance(cal.covariance, _gls_covariance(arm, q, truth, cov_i))


def test_fixed_parameters_with_noise_give_unbiased_estimates():
    arm, truth = paper_arm(4)
    arm = arm.replace(fixed=("dl4", "dq1"), sigma=SIGMA)
    truth = truth * arm.free
    q = random_plan(arm, 20, rng=15)
    xy = synthesize_measurements(arm, q, truth, SIGMA, rng=16, trials=400)
    found = solve(arm, arm.conditions(q), xy)
    est, converged = found.params, found.converged
    assert np.all(converged) and np.all(est[:, [3, 4]] == 0)
    cal = identify(arm, q, xy[0])
    # The mean of 400 fits is within 4 standard errors (std / sqrt(400)) of the truth.
    mean_error = np.mean(est - truth, axis=0) * arm.display_scale
    assert np.all(np.abs(mean_error) <= 4 * cal.std / 20)


def test_joint_offsets_only_calibration():
    arm, truth = paper_arm(4)
    arm = arm.replace(fixed=("dl1", "dl2", "dl3", "dl4"))
    truth = truth * arm.free
    q = random_plan(arm, 6, rng=17)
    cal = identify(arm, q, forward_kinematics(arm, q, truth), method="gauss-newton")
    np.testing.assert_allclose(cal.params, truth, atol=1e-12)


def test_closed_form_with_fixed_parameters_is_an_error_that_says_what_to_use():
    arm = paper_arm(4)[0].replace(fixed=("dl4",))
    q = random_plan(arm, 10, rng=18)
    with pytest.raises(ArmcalError, match="gauss-newton"):
        identify(arm, q, forward_kinematics(arm, q), method="closed-form")


def test_unknown_fixed_name_lists_the_valid_ones():
    with pytest.raises(ValueError, match="dl1, dl2, dq1, dq2"):
        PlanarArm([1.0, 1.0], fixed=("dl3",))
