"""Plausibility checks: unit mistakes, a missing base offset, large deviations."""

import numpy as np
import pytest
from numpy.testing import assert_allclose

from armcal import PlanarArm, forward_kinematics, identify
from armcal.doe import random_plan
from armcal.plausibility import (
    IMPROVEMENT,
    LARGE_ANGLE_DEG,
    LARGE_LENGTH_FRACTION,
    MIN_DOF,
    SUSPICIOUS_RMS_FRACTION,
    deviation_warning,
    explain,
    large_deviations,
    suspicious,
)
from helpers import random_arm, random_truth

PAPER_LINKS = [260.0, 180.0, 120.0, 100.0]


def _data(arm, rng, m=30, sigma=0.02):
    q = random_plan(arm, m, rng=rng)
    truth = random_truth(arm, rng)
    xy = forward_kinematics(arm, q, truth) + rng.normal(0.0, sigma, (m, 2))
    return q, truth, xy


# --------------------------------------------------------------------------- deviations


def test_large_deviation_bounds_are_strict_and_per_link():
    arm = PlanarArm([200.0, 50.0])
    just = LARGE_LENGTH_FRACTION * 200.0  # exactly at the bound: not large
    params = arm.params_from_display([just, 0.0], [LARGE_ANGLE_DEG, -LARGE_ANGLE_DEG])
    assert large_deviations(arm, params) == []
    assert deviation_warning(arm, params) is None
    # 6 mm is small for the 200 mm link but 12 % of the 50 mm one.
    params = arm.params_from_display([6.0, 6.0], [0.0, LARGE_ANGLE_DEG * 1.01])
    found = large_deviations(arm, params)
    assert [item.split(" ")[0] for item in found] == ["dl2", "dq2"]
    assert "12 % of link 2" in found[0]
    warning = deviation_warning(arm, params)
    assert warning is not None and warning.code == "large-deviation"
    assert "dl2 = 6 mm" in warning.message and "dq2" in warning.message


def test_dq1_with_a_base_offset_is_named_as_a_possible_frame_rotation():
    arm = PlanarArm([200.0, 100.0], base_offset=True)
    params = arm.params_from_display([0.0, 0.0], [37.0, 0.0], [900.0, 40.0])
    assert large_deviations(arm, params, rotation_free=True) == []
    warning = deviation_warning(arm, params)
    assert warning is not None and "rotation of the instrument's axes" in warning.message


# --------------------------------------------------------------------------- explain


@pytest.mark.parametrize("n", [2, 3, 4])
@pytest.mark.parametrize("base_offset", [False, True])
def test_clean_data_have_no_other_explanation(rng, n, base_offset):
    """No alternative reading fits 100 times better than clean data, over 100 data sets.

    ``explain`` is called directly here, not only after a suspicious fit, so this
    bounds the false alarms of the CLI's checks from above.
    """
    for _ in range(100 // 6 + 1):
        arm = random_arm(n, rng, base_offset=base_offset)
        q, _, xy = _data(arm, rng, m=int(rng.integers(2 * n + 1, 40)))
        assert explain(arm, q, xy) is None


def test_noiseless_data_have_no_other_explanation(arm4, paper_truth4, rng):
    """Fits to round-off prove nothing: a base offset fits noiseless data as well."""
    q = random_plan(arm4, 12, rng=rng)
    assert explain(arm4, q, forward_kinematics(arm4, q, paper_truth4)) is None


def test_angles_in_radians_are_found_and_the_alternative_recovers_the_truth(arm4, rng):
    q, truth, _ = _data(arm4, rng)
    xy = forward_kinematics(arm4, q, truth)  # noiseless: the alternative is exact
    as_read = np.radians(q)  # the file held radians under q*_deg
    found = explain(arm4, as_read, xy + rng.normal(0, 0.02, xy.shape))
    assert found is not None and found.code == "angles-in-radians"
    assert found.improvement >= IMPROVEMENT
    assert "q1_deg..q4_deg" in found.message and "convert them to degrees" in found.message
    exact = explain(arm4, as_read, xy)
    assert exact is not None and exact.code == "angles-in-radians"
    # Round-off of a closed-form fit over 30 random poses: ~1e-12 mm and rad.
    assert_allclose(exact.params, truth, rtol=0, atol=1e-9)


@pytest.mark.parametrize(("scale", "unit"), [(1000.0, "metres"), (10.0, "centimetres")])
def test_positions_in_another_length_unit_are_found(arm4, rng, scale, unit):
    q, truth, xy = _data(arm4, rng)
    found = explain(arm4, q, xy / scale)
    assert found is not None and found.code == f"positions-in-{unit}"
    assert "x_mm, y_mm" in found.message and "convert them to mm" in found.message
    # The scaled reading is the data in mm again: its deviations are the truth's,
    # within 4 predicted std of a 30-pose fit at sigma 0.02 mm (about 0.01 mm, 0.003 deg).
    cal = identify(arm4, q, xy, sigma=0.02)
    assert_allclose(found.params, cal.params, rtol=0, atol=1e-9)  # same fit, round-off apart
    assert np.all(np.abs(cal.params - truth) <= 4 * cal.std / arm4.display_scale)


def test_a_missing_base_offset_is_found(arm4, rng):
    q, truth, xy = _data(arm4, rng)
    base = np.array([60.0, -40.0])
    found = explain(arm4, q, xy + base)
    assert found is not None and found.code == "missing-base-offset"
    assert "base_offset = true" in found.message
    # The alternative is the least-squares fit with a base offset; within 4 std of the truth.
    based = arm4.replace(base_offset=True)
    cal = identify(based, q, xy + base, sigma=0.02)
    assert_allclose(found.params, cal.params, rtol=0, atol=1e-9)
    expected = np.concatenate([truth, base])
    assert np.all(np.abs(cal.params - expected) <= 4 * cal.std / based.display_scale)


def test_an_exactly_determined_alternative_proves_nothing():
    """Three poses of a 2-link arm: with a base offset, 6 parameters fit 6 numbers exactly."""
    arm = PlanarArm([260.0, 180.0])
    q = np.radians([[0.0, 0.0], [0.0, 90.0], [90.0, 90.0]])
    xy = forward_kinematics(arm, q, arm.params_from_display([1.5, -0.6], [0.5, -0.5]))
    xy += [[0.3, -0.2], [-0.1, 0.4], [0.2, 0.1]]  # misfit the 4-parameter model leaves
    assert 2 * 3 - (arm.n_params + 2) < MIN_DOF
    assert explain(arm, q, xy) is None


def test_fixed_parameters_are_held_in_every_reading(rng):
    arm = PlanarArm(PAPER_LINKS, fixed=["dl4"])
    q = random_plan(arm, 30, rng=rng)
    truth = arm.params_from_display([1.5, -0.6, -0.4, 0.0], [0.5, -0.5, 0.7, -0.3])
    xy = forward_kinematics(arm, q, truth)
    found = explain(arm, q, (xy + rng.normal(0, 0.02, xy.shape)) / 1000)
    assert found is not None and found.code == "positions-in-metres"
    assert found.params[3] == 0.0


# --------------------------------------------------------------------------- suspicious


def test_suspicious_fits(arm4, paper_truth4, rng):
    q = random_plan(arm4, 30, rng=rng)
    xy = forward_kinematics(arm4, q, paper_truth4) + rng.normal(0, 0.02, (30, 2))
    assert not suspicious(identify(arm4, q, xy, sigma=0.02))
    assert not suspicious(identify(arm4, q, xy))
    # Residual RMS above the bound with sigma estimated: 2 mm noise leaves an RMS of
    # about 2 sqrt(52 / 60) = 1.9 mm against 0.66 mm for the 660 mm arm.
    assert SUSPICIOUS_RMS_FRACTION * sum(PAPER_LINKS) < 1.0
    noisy = forward_kinematics(arm4, q, paper_truth4) + rng.normal(0, 2.0, (30, 2))
    assert suspicious(identify(arm4, q, noisy))
    # Inconsistent with sigma: the same noise claimed to be 0.02 mm.
    assert suspicious(identify(arm4, q, noisy, sigma=0.02))
