"""Commands over many rows: the same numbers a block of rows at a time, memory O(m).

What is made per row (a Jacobian, its products) is made a block of rows at a time
(:meth:`armcal.models.Conditions.blocks`) and reduced to a triangle
(:class:`armcal.numerics.RowTriangle`); a spatial arm keeps its latest kinematics on
the conditions (:meth:`armcal.models.Conditions.latest`).  These tests shrink the
block to a few rows, so that small problems take the many-block paths, and check
that every figure is the one the whole-matrix path gives (to round-off, stated per
test), and that memory grows with the rows by less than a Jacobian row per row.
No timing is asserted anywhere.
"""

from __future__ import annotations

import tracemalloc

import numpy as np
import pytest

import armcal.compensation as compensation_module
import armcal.identification.problem as problem_module
import armcal.identification.solvers as solvers_module
import armcal.models.information as information_module
import armcal.models.interface as interface_module
import armcal.models.spatial.arm as arm_module
import armcal.numerics as numerics_module
import armcal.simulate as simulate_module
from armcal.compensation import compensate
from armcal.criteria import evaluate_plan
from armcal.identification import identify
from armcal.identification.solvers import solve
from armcal.models import CalibratedArm
from armcal.models.information import refit_free, tip_variances
from armcal.noise import NoiseModel
from armcal.numerics import RowTriangle, scaled_svd, solve_least_squares
from armcal.simulate import monte_carlo
from armcal.synthesis import synthesize_measurements
from armcal.validation import validate
from helpers_spatial import industrial, labelled, random_poses, random_truth

SIGMA = 0.03  # mm: a laser tracker's noise at a few metres


def _small_blocks(monkeypatch, rows: int) -> None:
    """Every block of rows ``rows`` long, and no matrix factored whole: the many-block
    paths on a small problem."""
    for module in (
        interface_module,
        solvers_module,
        problem_module,
        information_module,
        arm_module,
    ):
        monkeypatch.setattr(module, "ROW_BLOCK", rows)
    monkeypatch.setattr(numerics_module, "WHOLE_ROWS", 0)
    monkeypatch.setattr(numerics_module, "TRIANGLE_BLOCK_ROWS", 7)


def _spatial_case(poses: int, seed: int = 3):
    """The industrial 6R with three reflectors, isotropic tracker noise, a random truth
    and ``poses`` poses measured at every reflector."""
    rng = np.random.default_rng(seed)
    arm = labelled(industrial(), 3).with_noise(NoiseModel.isotropic(SIGMA, dim=3))
    truth = random_truth(arm, rng)
    rows = arm.plan_conditions(random_poses(arm, poses, rng))
    points = synthesize_measurements(arm, rows.q, truth, rng=rng, target=rows.target)
    return arm, truth, rows, points


# --------------------------------------------------------------------------- the triangle


def test_a_triangle_of_blocks_solves_as_lstsq_does():
    """Least squares from blocks of rows against numpy's lstsq (an SVD of the whole
    matrix, independent of armcal's factorizations), with columns 10^4 apart in scale as
    mm and rad columns are: the same solution to 1e-12 of its size."""
    rng = np.random.default_rng(0)
    a = rng.standard_normal((500, 7)) * np.logspace(0, 4, 7)
    b = rng.standard_normal(500)
    rows = RowTriangle(7)
    for start in range(0, 500, 37):  # blocks of 37 rows, the last shorter
        rows.add(a[start : start + 37], b[start : start + 37])
    x, ok, svd = rows.solve()
    reference = np.linalg.lstsq(a, b, rcond=None)[0]
    assert bool(ok)
    assert np.max(np.abs(x - reference)) <= 1e-12 * np.max(np.abs(reference))
    whole = scaled_svd(a)
    assert np.allclose(svd.singular_values, whole.singular_values, rtol=1e-12, atol=0)


def test_a_triangle_with_more_sides_than_rows_solves_as_lstsq_does():
    """Many right-hand sides (a Monte Carlo's trials sharing a first step) and fewer rows
    than columns plus sides, added in blocks: every side's solution is lstsq's to 1e-12
    of its size.  Blocks wider than tall were once kept unreduced and cut to their first
    ``p`` rows, which lost the rest: a wrong shared step (an instrument's Monte Carlo,
    150 rows, 128 trials, blocks of 64 rows, diverged)."""
    rng = np.random.default_rng(1)
    a = rng.standard_normal((150, 26)) * np.logspace(0, 3, 26)
    b = rng.standard_normal((150, 128))
    rows = RowTriangle(26, sides=128)
    for start in range(0, 150, 64):
        rows.add(a[start : start + 64], b[start : start + 64])
    x, ok, _ = rows.solve()
    reference = np.linalg.lstsq(a, b, rcond=None)[0].T
    assert bool(np.all(ok))
    assert np.max(np.abs(x - reference)) <= 1e-12 * np.max(np.abs(reference))


def test_a_triangle_calls_dependent_columns_singular():
    """A column twice another: rank 4 of 5 by the rank policy, from blocks as from the
    whole matrix."""
    rng = np.random.default_rng(1)
    a = rng.standard_normal((300, 5))
    a[:, 4] = 2.0 * a[:, 3]
    rows = RowTriangle(5)
    for start in range(0, 300, 50):
        rows.add(a[start : start + 50])
    assert int(rows.svd().rank) == 4
    assert int(scaled_svd(a).rank) == 4


def test_a_small_system_given_whole_is_solved_as_before():
    """One matrix of few rows is factored whole, columns scaled first: the solution of
    solve_least_squares is numpy's lstsq's to 1e-13 of its size."""
    rng = np.random.default_rng(2)
    a = rng.standard_normal((2, 40, 6))
    b = rng.standard_normal((2, 40))
    x, ok, _ = solve_least_squares(a, b)
    for k in range(2):
        reference = np.linalg.lstsq(a[k], b[k], rcond=None)[0]
        assert np.max(np.abs(x[k] - reference)) <= 1e-13 * np.max(np.abs(reference))
    assert ok.tolist() == [True, True]


# --------------------------------------------------------------------------- identify


def test_identify_in_blocks_gives_the_whole_fit(monkeypatch):
    """120 poses (360 rows) identified whole, then with blocks of 50 rows (the last
    step's rows serving the covariance and leverage, every triangle from blocks): the
    estimates agree to 1e-9 of their std (round-off of Gauss-Newton's last step at
    1e-12 of the reach), the std and every row's studentized statistic to 1e-9."""
    arm, _, rows, points = _spatial_case(120)
    whole = identify(arm, rows.q, points, target=rows.target)
    _small_blocks(monkeypatch, 50)
    blocks = identify(arm, rows.q, points, target=rows.target)
    free = whole.model.free
    std = np.sqrt(np.diag(whole.covariance))[free]
    assert np.max(np.abs(blocks.params - whole.params)[free] / std) <= 1e-9
    assert np.allclose(np.sqrt(np.diag(blocks.covariance))[free], std, rtol=1e-9, atol=0)
    assert np.allclose(
        blocks.standardized_residuals, whole.standardized_residuals, rtol=0, atol=1e-9
    )
    assert [w.code for w in blocks.warnings] == [w.code for w in whole.warnings]


def test_gauss_newton_holds_no_jacobian_of_every_row(monkeypatch):
    """Gauss-Newton on 1500 and 6000 rows in blocks of 256: its peak memory grows with
    the rows by less than one row of the Jacobian, d p = 3 x 51 float64 (1224 bytes),
    per row, so no (m, d, p) array is held (the data, the residuals and the kept points
    are a few tens of floats per row); and the peak at 4x the rows is within 4.5x."""
    _small_blocks(monkeypatch, 256)
    monkeypatch.setattr(numerics_module, "TRIANGLE_BLOCK_ROWS", 4096)
    peaks = {}
    for poses in (500, 2000):
        arm, truth, rows, points = _spatial_case(poses, seed=5)
        model = arm.prepared(rows, points)
        start = np.where(model.free, truth, model.held_values)
        tracemalloc.start()
        solve(model, rows, points, start=start)
        peaks[3 * poses] = tracemalloc.get_traced_memory()[1]
        tracemalloc.stop()
    p = arm.layout.n_params
    grown = (peaks[6000] - peaks[1500]) / (6000 - 1500)
    assert grown < 3 * p * 8
    assert peaks[6000] <= 4.5 * peaks[1500]


def test_the_spatial_arm_hands_out_copies_of_what_it_keeps():
    """The points a spatial arm keeps on the conditions are handed out as copies: a
    caller's change to them does not reach the next caller; other parameters miss."""
    arm, truth, rows, _ = _spatial_case(10)
    first = arm.positions(rows, truth)
    reference = first.copy()
    first[:] = 0.0
    assert np.array_equal(arm.positions(rows, truth), reference)
    moved = truth.copy()
    moved[0] += 1.0  # the instrument 1 mm along x: every point 1 mm along x
    assert np.allclose(arm.positions(rows, moved) - reference, [1.0, 0.0, 0.0], atol=1e-9)


# --------------------------------------------------------------------------- evaluate


def test_a_large_plan_is_judged_from_its_triangle(monkeypatch):
    """A plan of more rows than a block is judged from its rows' triangle: its
    efficiencies, observability, predicted std and predicted error are those of its
    whole blocks to 1e-10 (relative)."""
    arm, _, _, _ = _spatial_case(1)
    rng = np.random.default_rng(7)
    q, test_q = random_poses(arm, 80, rng), random_poses(arm, 20, rng)
    whole = evaluate_plan(arm, q, sigma=SIGMA, test_q=test_q)
    _small_blocks(monkeypatch, 40)
    blocks = evaluate_plan(arm, q, sigma=SIGMA, test_q=test_q)
    for name, value in whole.efficiencies.items():
        assert blocks.efficiencies[name] == pytest.approx(value, rel=1e-10)
    for name, value in whole.observability.items():
        assert blocks.observability[name] == pytest.approx(value, rel=1e-10)
    assert np.allclose(blocks.predicted_std, whole.predicted_std, rtol=1e-10, atol=0)
    assert whole.position is not None and blocks.position is not None
    assert blocks.position.rms_mm == pytest.approx(whole.position.rms_mm, rel=1e-10)


def test_tip_variances_are_the_trace_of_j_c_jt():
    """``tr(J C J^T)`` of every row against the three-operand einsum, for one covariance
    and for a stack of them (to 1e-12 relative)."""
    rng = np.random.default_rng(8)
    jac = rng.standard_normal((50, 3, 9))
    a = rng.standard_normal((2, 9, 9))
    cov = a @ np.swapaxes(a, -1, -2)
    reference = np.einsum("kia,ab,kib->k", jac, cov[0], jac)
    assert np.allclose(tip_variances(jac, cov[0]), reference, rtol=1e-12, atol=0)
    stacked = np.einsum("...kia,...ab,...kib->...k", jac[None], cov, jac[None])
    assert np.allclose(tip_variances(jac[None], cov), stacked, rtol=1e-12, atol=0)


# --------------------------------------------------------------------------- simulate


def test_the_truth_is_refitted_in_blocks_as_whole(monkeypatch):
    """The truth expressed in the prepared arm's free parameters, refitted whole and in
    blocks of 30 rows: the points it puts are the same to 1e-9 mm."""
    arm, truth, rows, points = _spatial_case(40)
    model = arm.prepared(rows, points)
    whole = refit_free(model, rows, truth)
    _small_blocks(monkeypatch, 30)
    blocks = refit_free(model, rows, truth)
    assert np.max(np.abs(model.positions(rows, blocks) - model.positions(rows, whole))) <= 1e-9


def test_a_monte_carlo_peak_is_flat_in_trials(monkeypatch):
    """A Monte Carlo of 300 poses (900 rows) in blocks of 200 rows, one trial per solve
    (a chunk of 1 MiB): its peak memory with 6 trials is within 10 % of its peak with 2
    (each solve frees what it held; only the moments, p x p, accumulate)."""
    _small_blocks(monkeypatch, 200)
    monkeypatch.setattr(numerics_module, "TRIANGLE_BLOCK_ROWS", 4096)
    monkeypatch.setattr(simulate_module, "CHUNK_BYTES", 2**20)
    arm, truth, rows, points = _spatial_case(300, seed=9)
    model = arm.prepared(rows, points)
    truth = model.expressed(rows, truth)
    q = rows.q[::3]
    peaks = []
    for trials in (2, 6):
        tracemalloc.start()
        monte_carlo(model, q, truth, None, trials, rng=np.random.default_rng(1))
        peaks.append(tracemalloc.get_traced_memory()[1])
        tracemalloc.stop()
    assert peaks[1] <= 1.1 * peaks[0]


# --------------------------------------------------------------------------- validate, compensate


def _calibrated(poses: int = 60):
    arm, _, rows, points = _spatial_case(poses, seed=11)
    return identify(arm, rows.q, points, target=rows.target)


def test_validate_in_blocks_gives_the_whole_validation(monkeypatch):
    """Held-out rows validated whole and with blocks of 25 rows: the errors after and
    the predicted errors agree to 1e-12 mm."""
    cal = _calibrated()
    arm = cal.model
    rng = np.random.default_rng(12)
    held = arm.plan_conditions(random_poses(arm, 30, rng))
    points = cal.calibrated().positions(held) + rng.normal(scale=SIGMA, size=(held.m, 3))
    whole = validate(cal, held.q, points, target=held.target)
    monkeypatch.setattr(interface_module, "ROW_BLOCK", 25)
    blocks = validate(cal, held.q, points, target=held.target)
    assert np.max(np.abs(blocks.after - whole.after)) <= 1e-12
    assert np.max(np.abs(blocks.predicted_mm - whole.predicted_mm)) <= 1e-12


def test_compensation_in_blocks_and_by_newton_gives_the_svd_correction(monkeypatch):
    """A program of 200 poses compensated with blocks of 16 rows and Newton's step where
    it is the trust-region step, then as before (one block, every step from the SVD):
    the same poses corrected, the commands within 1e-9 deg, the predicted errors within
    1e-12 mm.  The calibrated arm puts the tool where the nominal program meant (the
    module's own promise) within 1e-8 mm."""
    cal = _calibrated()
    calibrated = CalibratedArm(cal.model, cal.params, cal.covariance, cal.sigma_mm)
    rng = np.random.default_rng(13)
    program = random_poses(cal.model, 200, rng)
    target = np.zeros(200, dtype=int)
    monkeypatch.setattr(interface_module, "ROW_BLOCK", 16)
    fast = compensate(calibrated, program, target=target)
    monkeypatch.undo()
    monkeypatch.setattr(compensation_module, "_newton_steps", lambda *args: None)
    slow = compensate(calibrated, program, target=target)
    assert np.array_equal(fast.corrected, slow.corrected)
    assert fast.corrected.sum() > 150  # most random poses are far from a singularity
    assert np.max(np.degrees(np.abs(fast.q - slow.q))) <= 1e-9
    assert np.max(np.abs(fast.position_after_mm - slow.position_after_mm)) <= 1e-12
    model, robot = calibrated.in_robot_frame()
    rows = model.conditions(program, target=target)
    nominal = np.where(model.instrument_params, robot, 0.0)
    ok = fast.corrected
    reached = model.positions(model.conditions(fast.q, target=target), robot)
    assert np.max(np.abs(reached - model.positions(rows, nominal))[ok]) <= 1e-8
