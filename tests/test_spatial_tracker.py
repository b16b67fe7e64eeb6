"""A laser tracker's noise model: range along the line of sight, angles across it.

The model is the data sheets' (a constant plus a term per metre of distance, for
the range and for the transverse, angular, direction).  The covariance is checked
against its definition, the whitening against ``W^T W = sigma_ref^2 Sigma^-1``,
and the statistics against the data: a fit weighted by the tracker's model is
consistent with its noise (chi-square), one that assumes isotropic noise is not,
and the Monte Carlo std agrees with the predicted std.

The terms used below are of a tracker's data-sheet size (about 0.01 mm and
0.0025 mm per metre across the line of sight, 1 std), not of a particular one.
"""

from __future__ import annotations

import json

import numpy as np
import pytest

from armcal.doe import random_plan
from armcal.files import load_spatial_robot, load_spatial_truth, read_calibration
from armcal.files.spatial import ROBOT_FOLDER
from armcal.identification import identify
from armcal.noise import TRACKER_REFERENCE_MM, NoiseModel, TrackerNoise
from armcal.synthesis import synthesize_measurements
from armcal.workflow import simulate_plan
from helpers import run_cli

TRACKER = TrackerNoise(0.008, 0.0004, 0.010, 0.0025)
TRACKER_TOML = (
    "[measurement.tracker]\nrange_mm = 0.008\nrange_mm_per_m = 0.0004\n"
    "transverse_mm = 0.010\ntransverse_mm_per_m = 0.0025\n"
)


def test_the_covariance_is_range_along_the_sight_and_angles_across():
    rng = np.random.default_rng(4)
    points = rng.normal(size=(50, 3)) * 2000.0
    cov = TRACKER.covariances(points)
    distance_m = np.linalg.norm(points, axis=1) / 1000.0
    along = 0.008 + 0.0004 * distance_m
    across = 0.010 + 0.0025 * distance_m
    sight = points / np.linalg.norm(points, axis=1)[:, None]
    # Sigma u = s_r^2 u; any direction v across the sight: Sigma v = s_t^2 v.
    np.testing.assert_allclose(np.einsum("mij,mj->mi", cov, sight), along[:, None] ** 2 * sight)
    across_dir = np.cross(sight, rng.normal(size=(50, 3)))
    np.testing.assert_allclose(
        np.einsum("mij,mj->mi", cov, across_dir),
        across[:, None] ** 2 * across_dir,
        atol=1e-18,
    )
    np.testing.assert_allclose(cov, np.swapaxes(cov, 1, 2))


def test_the_reference_sigma_is_the_isotropic_equivalent_at_one_metre():
    noise = NoiseModel.laser_tracker(TRACKER)
    along = 0.008 + 0.0004 * TRACKER_REFERENCE_MM / 1000.0
    across = 0.010 + 0.0025 * TRACKER_REFERENCE_MM / 1000.0
    # The same information per point: 3 / sigma^2 = 1 / s_r^2 + 2 / s_t^2.
    assert 3.0 / noise.sigma_mm**2 == pytest.approx(1 / along**2 + 2 / across**2, rel=1e-12)
    assert not noise.isotropic_iid
    with pytest.raises(ValueError, match="3-D points"):
        noise.for_dim(2)
    with pytest.raises(ValueError, match="finite and >= 0"):
        TrackerNoise(0.01, -0.001, 0.01, 0.0)


def test_the_arm_whitens_every_row_by_its_own_covariance():
    spec = load_spatial_robot("industrial-6r")
    arm = spec.arm.with_noise(NoiseModel.laser_tracker(TRACKER))
    truth = load_spatial_truth(spec.default_truth, spec.arm)
    cond = arm.plan_conditions(random_plan(arm, 20, rng=1))
    w = arm.whitening(cond, truth)
    cov = TRACKER.covariances(arm.positions(cond, truth))
    expected = arm.noise.sigma_mm**2 * np.linalg.inv(cov)
    np.testing.assert_allclose(np.swapaxes(w, 1, 2) @ w, expected, rtol=1e-10)


def _fit(noise_of_fit: NoiseModel, m: int = 1500):
    """Identify industrial-6r (a tracker 3.3 m away) from tracker-noise data."""
    spec = load_spatial_robot("industrial-6r")
    truth = load_spatial_truth(spec.default_truth, spec.arm)
    virtual = spec.arm.with_noise(NoiseModel.laser_tracker(TRACKER))
    cond = virtual.plan_conditions(random_plan(virtual, m, rng=7))
    points = synthesize_measurements(virtual, cond.q, truth, rng=8, target=cond.target)
    return identify(spec.arm.with_noise(noise_of_fit), cond.q, points, target=cond.target)


def test_a_fit_weighted_by_the_tracker_model_is_consistent_with_its_noise():
    cal = _fit(NoiseModel.laser_tracker(TRACKER))
    fit = cal.goodness_of_fit
    assert fit is not None and fit.chi2 is not None
    dof = fit.dof
    assert dof == 3 * 1500 - cal.model.n_free
    # chi^2 / dof of a correct model lies within 4 of its standard errors sqrt(2 / dof).
    ratio = fit.chi2 / dof
    assert abs(ratio - 1.0) < 4 * np.sqrt(2.0 / dof), ratio
    assert "fit-inconsistent" not in [w.code for w in cal.warnings]


def test_assuming_isotropic_noise_of_the_same_reference_is_flagged():
    # At 3-4 m the transverse noise (about 0.019 mm) is twice the reference 0.0105 mm,
    # so isotropic weights at the reference give chi^2 / dof near 2.5: inconsistent.
    reference = NoiseModel.laser_tracker(TRACKER).sigma_mm
    cal = _fit(NoiseModel.isotropic(reference, dim=3))
    assert "fit-inconsistent" in [w.code for w in cal.warnings]


@pytest.mark.slow
def test_monte_carlo_agrees_with_the_tracker_model():
    spec = load_spatial_robot("industrial-6r")
    arm = spec.arm.with_noise(NoiseModel.laser_tracker(TRACKER))
    truth = load_spatial_truth(spec.default_truth, spec.arm)
    result = simulate_plan(arm, random_plan(arm, 40, rng=3), truth, trials=4000, seed=1)
    free = result.model.free
    # 4000 trials: an empirical std's relative standard error is 1.1 %, so 5 % is > 4 of them.
    ratio = result.std[free] / result.predicted_std[free]
    assert np.all(np.abs(ratio - 1.0) < 0.05), ratio


def _robot(tmp_path, measurement: str) -> None:
    urdf = json.dumps(str(ROBOT_FOLDER / "industrial-6r.urdf"))
    (tmp_path / "robot.toml").write_text(
        f"urdf = {urdf}\njoint_map = [[1,0,0,0,0,0],[0,1,0,0,0,0],[0,1,1,0,0,0],"
        f"[0,0,0,1,0,0],[0,0,0,0,1,0],[0,0,0,0,0,1]]\n{measurement}",
        encoding="utf-8",
    )


def test_the_robot_file_gives_the_tracker_and_the_calibration_keeps_it(tmp_path):
    _robot(tmp_path, TRACKER_TOML)
    assert load_spatial_robot(tmp_path / "robot.toml").arm.noise.tracker == TRACKER
    arm = load_spatial_robot("industrial-6r").arm
    q = random_plan(arm, 30, rng=2)
    head = ",".join(f"q{k + 1}_deg" for k in range(6))
    rows = [",".join(repr(float(v)) for v in np.degrees(row)) for row in q]
    (tmp_path / "plan.csv").write_text("\n".join([head, *rows]) + "\n", encoding="utf-8")
    result = run_cli(
        tmp_path, "synthesize", "--robot", "robot.toml", "--truth",
        str(ROBOT_FOLDER / "industrial-6r-truth.toml"), "--plan", "plan.csv", "-o", "meas.csv",
    )  # fmt: skip
    assert result.returncode == 0, result.stderr
    result = run_cli(
        tmp_path, "identify", "--robot", "robot.toml", "--measurements", "meas.csv",
        "-o", "cal.json",
    )  # fmt: skip
    assert result.returncode == 0, result.stderr
    assert "laser tracker, range 0.008 mm + 0.0004 mm/m" in result.stdout
    assert read_calibration(tmp_path / "cal.json").model.noise.tracker == TRACKER
    # The exported robot TOML keeps the instrument's noise model.
    result = run_cli(tmp_path, "export", "--calibration", "cal.json", "--robot-toml", "cal.toml")
    assert result.returncode == 0, result.stderr
    assert load_spatial_robot(tmp_path / "cal.toml").arm.noise.tracker == TRACKER


@pytest.mark.parametrize(
    ("measurement", "expected"),
    [
        ("[measurement]\nsigma_mm = 0.01\ntracker = { range_mm = 0.008 }\n", "keep one"),
        ("[measurement.tracker]\nrange_mm = 0.008\n", "missing range_mm_per_m"),
        (TRACKER_TOML.replace("transverse_mm = 0.010", "transverse_mm = -0.01"), "check the unit"),
        (TRACKER_TOML.replace("range_mm = 0.008", "range_m = 0.008"), "range_m"),
    ],
)  # fmt: skip
def test_a_wrong_tracker_table_is_a_clear_error(tmp_path, measurement, expected):
    _robot(tmp_path, measurement)
    (tmp_path / "plan.csv").write_text(
        "q1_deg,q2_deg,q3_deg,q4_deg,q5_deg,q6_deg\n" + "0,0,0,0,0,0\n"
    )
    result = run_cli(tmp_path, "evaluate", "--robot", "robot.toml", "--plan", "plan.csv")
    assert result.returncode == 2
    line = result.stderr.strip()
    assert line.startswith("armcal: error: ") and "robot.toml" in line and expected in line, line
    assert "\n" not in line
