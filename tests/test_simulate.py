"""Monte Carlo, random-plan studies and poses-needed against theory and closed forms."""

import io
import itertools
import json
import math
import tracemalloc

import numpy as np
import pytest
from numpy.testing import assert_allclose

from armcal import (
    NotIdentifiableError,
    PlanarArm,
    doe,
    forward_kinematics,
    report,
    solve_closed_form,
)
from armcal import simulate as sim
from armcal.criteria import d_efficiency, position_accuracy, predicted_std
from armcal.doe import orthogonal_plan, random_plan
from armcal.files import to_json
from armcal.models import link_phasors
from armcal.progress import ProgressBar
from armcal.reproduction.study import random_plan_study
from helpers import random_arm, random_truth


@pytest.mark.parametrize("method", ["closed-form", "gauss-newton"])
def test_ten_thousand_trials_match_theory(arm4, paper_truth4, method):
    """Issue 4: paper-4link, orthogonal 20-pose plan, sigma 0.1 mm, 10 000 trials."""
    q = orthogonal_plan(arm4, 20)
    result = sim.monte_carlo(arm4, q, paper_truth4, 0.1, 10_000, method=method, rng=7)
    # Sampling error of a std from 10 000 normal draws is 1/sqrt(20 000) = 0.7 %,
    # so 3 % is a 4-sigma bound.
    assert_allclose(result.std, result.predicted_std, rtol=0.03, atol=0)
    assert np.all(np.abs(result.bias) <= result.bias_limit)
    # Theory for the orthogonal plan (Table II): dl std = sigma / sqrt(m).
    assert_allclose(result.predicted_std[:4], 0.1 / np.sqrt(20), rtol=1e-9)
    assert result.not_converged == 0 and result.trials == 10_000


def test_solvers_give_the_same_monte_carlo(arm4, paper_truth4):
    q = random_plan(arm4, 12, rng=3)
    closed = sim.monte_carlo(arm4, q, paper_truth4, 0.1, 3000, rng=5)
    newton = sim.monte_carlo(arm4, q, paper_truth4, 0.1, 3000, method="gauss-newton", rng=5)
    assert_allclose(newton.mean, closed.mean, rtol=0, atol=1e-10)
    assert_allclose(newton.covariance, closed.covariance, rtol=1e-7, atol=0)


def test_chunking_does_not_change_the_result(arm4, paper_truth4, monkeypatch):
    """Moments merged chunk by chunk equal the moments of all trials at once."""
    q = orthogonal_plan(arm4, 20)
    test_q = random_plan(arm4, 50, rng=1)
    whole = sim.monte_carlo(arm4, q, paper_truth4, 0.1, 5000, rng=11, test_q=test_q)
    # The closed form holds 6m + 4p floats per trial: chunks of 37 trials.
    monkeypatch.setattr(sim, "CHUNK_BYTES", 8 * (6 * 20 + 4 * 8) * 37)
    calls = []
    chunked = sim.monte_carlo(
        arm4,
        q,
        paper_truth4,
        0.1,
        5000,
        rng=11,
        test_q=test_q,
        progress=lambda *a: calls.append(a),
    )
    assert len(calls) > 100 and calls[-1] == (5000, 5000)
    assert all(a[0] < b[0] for a, b in itertools.pairwise(calls))
    assert_allclose(chunked.mean, whole.mean, rtol=0, atol=1e-13)
    assert_allclose(chunked.covariance, whole.covariance, rtol=1e-10, atol=0)
    # The quantiles' subsample is drawn before the first chunk: the same pairs.  Their
    # errors differ by the round-off of solves batched differently, ~1e-16 of the
    # ~250 mm link phasors, i.e. ~1e-12 of the ~0.05 mm errors: 1e-10 is safe.
    pos, ref = chunked.position, whole.position
    assert pos.subsample < pos.pairs
    for key in ref.quantiles_mm:
        assert_allclose(pos.quantiles_mm[key], ref.quantiles_mm[key], rtol=1e-10)
        assert_allclose(pos.quantile_intervals_mm[key], ref.quantile_intervals_mm[key], rtol=1e-10)
    assert_allclose(pos.rms_mm, ref.rms_mm, rtol=1e-10)


def test_the_estimates_are_those_of_the_solver(arm4, paper_truth4):
    """The Monte Carlo draws noise once per chunk and solves; redo it by hand."""
    q = random_plan(arm4, 15, rng=2)
    result = sim.monte_carlo(arm4, q, paper_truth4, 0.2, 400, rng=9)
    xy = forward_kinematics(arm4, q, paper_truth4) + 0.2 * np.random.default_rng(
        9
    ).standard_normal((400, 15, 2))
    estimates = solve_closed_form(arm4, q, xy)
    assert_allclose(result.mean, estimates.mean(axis=0), rtol=0, atol=1e-13)
    assert_allclose(result.covariance, np.cov(estimates.T), rtol=1e-9, atol=0)


def _all_tip_errors(arm, q, truth, sigma, trials, seed, test_q):
    """Every (trial, test pose) tip error of a run, by brute force: ``(trials, k)`` two ways.

    The noise is redrawn from the same seed (monte_carlo draws it chunk by chunk
    from ``rng`` in trial order).  Returns the errors from explicit phasor sums
    per pair, and from differences of forward kinematics.
    """
    noise = np.random.default_rng(seed).standard_normal((trials, q.shape[0], 2))
    estimates = solve_closed_form(arm, q, forward_kinematics(arm, q, truth) + sigma * noise)
    dz = link_phasors(arm, estimates) - link_phasors(arm, truth)  # (trials, n+1)
    unit = np.exp(1j * np.cumsum(test_q, axis=1))
    basis = np.concatenate([unit, np.ones((test_q.shape[0], 1))], axis=1)  # (k, n+1)
    phasor = np.abs(np.sum(dz[:, None, :] * basis[None, :, :], axis=-1))
    fk = np.linalg.norm(
        forward_kinematics(arm, test_q, estimates) - forward_kinematics(arm, test_q, truth),
        axis=-1,
    )
    return phasor, fk


@pytest.mark.parametrize("base_offset", [False, True])
def test_position_rms_is_exact(base_offset, rng):
    """RMS = sqrt(tr(S G)) equals the RMS of every (trial, test pose) error."""
    arm = random_arm(3, rng, base_offset=base_offset)
    truth = random_truth(arm, rng)
    q = random_plan(arm, 9, rng=rng)
    test_q = random_plan(arm, 70, rng=rng)
    result = sim.monte_carlo(arm, q, truth, 0.2, 300, rng=17, test_q=test_q)
    phasor, fk = _all_tip_errors(arm, q, truth, 0.2, 300, 17, test_q)
    pos = result.position
    assert pos.pairs == 300 * 70
    # Same numbers summed in another order: round-off only.
    assert_allclose(pos.rms_mm, np.sqrt(np.mean(phasor**2)), rtol=1e-12)
    # Differences of tip positions (~500 mm) cancel to errors of ~0.1 mm: ~1e-12 each.
    assert_allclose(pos.rms_mm, np.sqrt(np.mean(fk**2)), rtol=1e-9)


def test_small_runs_keep_every_error_for_exact_quantiles(arm4, paper_truth4):
    q = orthogonal_plan(arm4, 20)
    test_q = random_plan(arm4, 40, rng=4)
    result = sim.monte_carlo(arm4, q, paper_truth4, 0.1, 750, rng=13, test_q=test_q)
    pos = result.position
    assert pos.pairs == pos.subsample == 750 * 40 <= sim.POSITION_SUBSAMPLE
    assert pos.exact_quantiles
    phasor, _ = _all_tip_errors(arm4, q, paper_truth4, 0.1, 750, 13, test_q)
    for key, level in (("50", 0.5), ("95", 0.95), ("99", 0.99)):
        assert_allclose(pos.quantiles_mm[key], np.quantile(phasor, level), rtol=1e-12)
        assert pos.quantile_intervals_mm[key] == (pos.quantiles_mm[key],) * 2


def test_subsample_quantiles_are_within_their_sampling_error(arm4, paper_truth4, monkeypatch):
    """B pairs drawn uniformly with replacement are iid draws from all the pairs' errors.

    The fraction of all errors below the subsample's P-quantile is then within
    P +- 4 sqrt(P (1 - P) / B) (+ 2 / B for interpolation between order
    statistics) but with probability ~6e-5; the 95 % interval ends sit at the
    levels P -+ 1.96 sqrt(P (1 - P) / B), within the same tolerance.
    """
    budget = 4000
    monkeypatch.setattr(sim, "POSITION_SUBSAMPLE", budget)
    q = orthogonal_plan(arm4, 20)
    test_q = random_plan(arm4, 100, rng=4)
    trials = 2000
    result = sim.monte_carlo(arm4, q, paper_truth4, 0.1, trials, rng=13, test_q=test_q)
    pos = result.position
    assert pos.pairs == trials * 100 and pos.subsample == budget
    phasor, _ = _all_tip_errors(arm4, q, paper_truth4, 0.1, trials, 13, test_q)
    ordered = np.sort(phasor.ravel())

    def level_of(value: float) -> float:
        return np.searchsorted(ordered, value, side="right") / ordered.size

    for key, level in (("50", 0.5), ("95", 0.95), ("99", 0.99)):
        sd = np.sqrt(level * (1 - level) / budget)
        assert abs(level_of(pos.quantiles_mm[key]) - level) <= 4 * sd + 2 / budget
        low, high = pos.quantile_intervals_mm[key]
        assert low <= pos.quantiles_mm[key] <= high
        assert abs(level_of(low) - (level - 1.96 * sd)) <= 4 * sd + 2 / budget
        assert abs(level_of(high) - (level + 1.96 * sd)) <= 4 * sd + 2 / budget
    # The prediction is linearized at the truth: sigma sqrt(2n/m) to about 1e-3.  A
    # trial's mean square error over the test poses is a quadratic form in the 8 normal
    # phasor errors (relative std at most 1); over 2000 trials the RMS has a relative
    # std of at most 1 / (2 sqrt(2000)) = 1.1 %, so 5 % is a 4.5-sigma bound.
    assert_allclose(pos.predicted_rms_mm, 0.1 * np.sqrt(8 / 20), rtol=1e-3)
    assert_allclose(pos.rms_mm, pos.predicted_rms_mm, rtol=0.05)


@pytest.mark.parametrize("test_poses", [0, 200])
def test_memory_stays_flat_for_a_million_trials(arm2, test_poses):
    q = orthogonal_plan(arm2, 8)
    test_q = random_plan(arm2, test_poses, rng=0) if test_poses else None
    peaks = []
    # Both several chunks: the closed form's chunk holds CHUNK_BYTES / (8 (6m + 4p)) trials.
    chunk = sim.CHUNK_BYTES // (8 * (6 * q.shape[0] + 4 * arm2.n_params))
    for trials in (3 * chunk, 1_000_000):
        tracemalloc.start()
        sim.monte_carlo(arm2, q, np.zeros(4), 0.1, trials, rng=0, test_q=test_q)
        peaks.append(tracemalloc.get_traced_memory()[1])
        tracemalloc.stop()
    # Both runs hold one chunk of working arrays and, with test poses,
    # the same subsample of POSITION_SUBSAMPLE errors (0.7 MB); a million stored
    # estimates alone would add 32 MB, and the errors at 200 test poses 1.6 GB.
    assert peaks[1] < 1.05 * peaks[0]


def test_unidentifiable_plan_and_bad_arguments_are_refused(arm4, paper_truth4):
    with pytest.raises(NotIdentifiableError):
        sim.monte_carlo(arm4, random_plan(arm4, 3, rng=0), paper_truth4, 0.1, 100)
    q = orthogonal_plan(arm4, 8)
    for kwargs in ({"trials": 1}, {"sigma": 0.0}, {"sigma": float("nan")}):
        args = {"sigma": 0.1, "trials": 100, **kwargs}
        with pytest.raises(ValueError, match="Monte Carlo"):
            sim.monte_carlo(arm4, q, paper_truth4, args["sigma"], args["trials"])


def test_report_and_json_name_every_parameter(arm4, paper_truth4):
    result = sim.monte_carlo(arm4, orthogonal_plan(arm4, 8), paper_truth4, 0.1, 500, rng=1)
    text = report.format_monte_carlo(result)
    document = report.monte_carlo_to_dict(result)
    for name in arm4.param_names:
        assert f"\n{name} " in text
        assert name in document["empirical_std"] and name in document["bias"]
    assert document["trials"] == 500 and document["seconds"] >= 0


@pytest.mark.parametrize(("trials", "exact"), [(100, True), (500, False)])
def test_report_says_where_the_quantiles_come_from(arm4, paper_truth4, trials, exact):
    assert 100 * 300 <= sim.POSITION_SUBSAMPLE < 500 * 300
    test_q = random_plan(arm4, 300, rng=2)
    q = orthogonal_plan(arm4, 8)
    result = sim.monte_carlo(arm4, q, paper_truth4, 0.1, trials, rng=1, test_q=test_q)
    assert result.position.exact_quantiles is exact
    text = report.format_monte_carlo(result)
    document = json.loads(to_json(report.monte_carlo_to_dict(result)))
    errors = document["position_error_mm"]
    assert errors["pairs"] == trials * 300
    assert errors["quantile_subsample"] == min(trials * 300, sim.POSITION_SUBSAMPLE)
    assert set(errors["quantiles"]) == set(errors["quantile_intervals_95"]) == {"50", "95", "99"}
    assert "max" not in errors and "max" not in text
    assert ("random subsample" in text) is not exact
    assert f"over all {trials * 300} (trial, test pose) pairs" in text


# --------------------------------------------------------------------------- random plans


def test_random_plan_study_matches_plan_by_plan_evaluation(arm4):
    test_q = random_plan(arm4, 100, rng=1)
    study = random_plan_study(arm4, 10, 300, sigma=0.1, rng=21, test_q=test_q)
    plans = random_plan(arm4, 3000, rng=np.random.default_rng(21)).reshape(300, 10, 4)
    for k in (0, 17, 299):
        assert_allclose(study.det_d[k], d_efficiency(arm4, plans[k]) ** 8, rtol=1e-9)
        assert_allclose(study.std[k], predicted_std(arm4, plans[k], 0.1), rtol=1e-9)
        rms = position_accuracy(arm4, plans[k], test_q, 0.1).rms_mm
        assert_allclose(study.position_rms[k], rms, rtol=1e-9)
    # Hadamard: every random plan is below the orthogonal optimum (1).
    assert np.all(study.det_d < 1) and np.all(study.det_c < 1)
    assert study.identifiable.all()


def test_det_s_vanishes_for_odd_n_and_optimum_is_one(rng):
    arm3 = random_arm(3, rng)
    study = random_plan_study(arm3, 10, 200, sigma=0.1, rng=rng)
    # S is antisymmetric, so det S = 0 for odd n whatever the plan.
    assert np.max(study.abs_det_s) < 1e-12


# --------------------------------------------------------------------------- poses needed


def _ceil(x: float) -> int:
    return math.ceil(x - 1e-9)  # (sigma / goal)^2 = 100 may round to 100.00000000000001


@pytest.mark.parametrize("n", [1, 2, 3, 4, 6])
@pytest.mark.parametrize("goal", [0.05, 0.02, 0.0123])
def test_poses_needed_matches_closed_forms_for_unconstrained_arms(n, goal, rng):
    arm = random_arm(n, rng)
    sigma = 0.1
    lengths = arm.link_lengths
    # Worst joint-offset std of an orthogonal plan times sqrt(m), in deg: dq_1 = dtheta_1 has
    # sigma/l_1, dq_i = dtheta_i - dtheta_{i-1} has sigma sqrt(1/l_i^2 + 1/l_{i-1}^2).
    angle = sigma * np.degrees(
        max([1 / lengths[0], *list(np.hypot(1 / lengths[1:], 1 / lengths[:-1]))])
    )
    expected = {
        "length_std_mm": _ceil((sigma / goal) ** 2),
        "angle_std_deg": _ceil((angle / goal) ** 2),
        "position_rms_mm": _ceil(2 * n * (sigma / goal) ** 2),
    }
    goals = {"length_std_mm": goal, "angle_std_deg": goal, "position_rms_mm": goal}
    min_poses = n  # ceil(2n / 2)
    for target, poses in expected.items():
        found = doe.poses_needed(arm, target, goals[target], sigma=sigma, rng=0)
        assert found.poses == max(poses, min_poses), target
        assert found.method == "analytic"
        assert found.achieved <= goals[target] * (1 + 1e-9)
        assert found.previous > goals[target] or found.poses == min_poses


def test_poses_needed_paper_examples(arm4):
    """Issue 4: sigma 0.1 mm -- length std 0.01 mm needs 100 poses, position RMS 0.02 mm 200."""
    assert doe.poses_needed(arm4, "length_std_mm", 0.01, sigma=0.1).poses == 100
    assert doe.poses_needed(arm4, "position_rms_mm", 0.02, sigma=0.1).poses == 200
    # One link, one offset: sigma / (sqrt(m) l).
    one = PlanarArm([250.0])
    goal = np.degrees(0.1 / (np.sqrt(30) * 250.0))
    assert doe.poses_needed(one, "angle_std_deg", goal, sigma=0.1).poses == 30


def test_poses_needed_searches_under_joint_limits():
    """With joints 2-4 limited to +-60 deg no orthogonal plan fits: the answer is found by
    designing plans, and is more than the unconstrained closed form."""
    limits = np.radians([[-180, 180], [-60, 60], [-60, 60], [-60, 60]])
    arm = PlanarArm([260.0, 180.0, 120.0, 100.0], limits)
    found = doe.poses_needed(arm, "length_std_mm", 0.03, sigma=0.1, rng=1)
    assert found.method != "analytic"
    assert found.achieved <= 0.03 < found.previous
    assert found.poses > _ceil((0.1 / 0.03) ** 2)  # 12 without limits
    assert np.all(arm.within_limits(found.plan))
    assert found.poses in found.evaluated and found.poses - 1 in found.evaluated


def test_poses_needed_gives_up_with_a_reason(arm4):
    with pytest.raises(ValueError, match="relax the target"):
        doe.poses_needed(arm4, "length_std_mm", 1e-4, sigma=0.1, max_poses=500)
    with pytest.raises(ValueError, match="unknown requirement"):
        doe.poses_needed(arm4, "speed", 1.0, sigma=0.1)


# --------------------------------------------------------------------------- progress


class _Terminal(io.StringIO):
    def isatty(self) -> bool:
        return True


def test_progress_bar_appears_only_after_the_delay():
    now = [0.0]
    stream = _Terminal()
    bar = ProgressBar("simulate", stream=stream, delay=2.0, clock=lambda: now[0])
    bar(1, 4)
    assert stream.getvalue() == ""
    now[0] = 2.5
    bar(2, 4)
    bar(4, 4)
    text = stream.getvalue()
    assert "simulate [" in text and " 50%" in text and "100%" in text and text.endswith("\n")


def test_the_arm_is_evaluated_once_however_many_chunks(arm4, paper_truth4, monkeypatch):
    """Only the noise differs between chunks of trials: the noiseless points are computed
    once, so the cost stays linear in the plan's size (issue 20: at 1e5 poses a chunk held
    ~6 trials, and every chunk redid the forward kinematics)."""
    q = orthogonal_plan(arm4, 20)
    monkeypatch.setattr(sim, "CHUNK_BYTES", 8 * (6 * 20 + 4 * 8) * 37)  # 37 trials a chunk
    calls = []
    real = type(arm4).positions

    def counted(self, *args, **kwargs):
        calls.append(1)
        return real(self, *args, **kwargs)

    monkeypatch.setattr(type(arm4), "positions", counted)
    chunks = []
    sim.monte_carlo(arm4, q, paper_truth4, 0.1, 2000, rng=1, progress=lambda *a: chunks.append(a))
    assert len(chunks) == -(-2000 // 37)
    assert len(calls) == 1
