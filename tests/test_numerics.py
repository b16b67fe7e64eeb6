"""The one rank and conditioning policy: no crash, no made-up number, O(m) memory.

The ill-conditioned plan used throughout is the paper's 4-link arm measured in
12 poses in which joint 4 stays within ``spread`` rad of 0: links 3 and 4 are
then almost collinear, and only ``dl3 + dl4`` and ``L3 dtheta3 + L4 dtheta4``
are well seen.  The two poorly seen directions are ``dl3 - dl4`` and
``dq3 - ((L3 + L4) / L4) dq4 = dq3 - 2.2 dq4`` (``dtheta4 = dq3 + dq4`` moves
the tip by ``L3 dq3 + L4 (dq3 + dq4) = 0``).  Their relative singular value
is proportional to ``spread``: a spread of 1e-8 rad gives a condition number
near 1e9 -- above the warning threshold, below the rank limit.

Reference values are computed here with plain numpy from the test's own
regressor, independently of armcal.
"""

from __future__ import annotations

import json
import math
import tracemalloc
from pathlib import Path

import numpy as np
import pytest
from numpy.testing import assert_allclose

from armcal import (
    NotIdentifiableError,
    PlanarArm,
    certify,
    check_identifiable,
    d_efficiency,
    evaluate_plan,
    forward_kinematics,
    identifiability,
    identify,
    monte_carlo,
    position_accuracy,
    predicted_std,
    random_plan,
    solve_closed_form,
    solve_gauss_newton,
)
from armcal.criteria import CRITERIA, efficiencies, observability_indices
from armcal.models.planar.criteria import inverse_information, scaled_information
from armcal.numerics import (
    COND_WARN,
    RANK_RTOL,
    factor_least_squares,
    scaled_svd,
    spd_inverse,
)
from helpers import run_cli

EPS = np.finfo(float).eps

#: paper-4link (the CLI's default robot): the paper's lengths, and its Table III
#: deviations, which are paper-4link's default truth.
LINKS_MM = np.array([260.0, 180.0, 120.0, 100.0])
DL_MM = np.array([1.5, -0.6, -0.4, 0.7])
DQ_DEG = np.array([0.5, -0.5, 0.7, -0.3])
ARM = PlanarArm(LINKS_MM, name="paper-4link")
TRUTH = ARM.params_from_display(DL_MM, DQ_DEG)

#: Round-off allowance: Householder QR and the SVD are backward stable with errors
#: of a modest multiple of eps (24 rows, 8 columns here), and the positions the
#: test writes carry a few ulps of their ~600 mm; 100 covers both.
ROUND_OFF = 100.0


def _plan_deg(spread_rad: float, m: int = 12) -> np.ndarray:
    """``m`` poses (deg) with joints 1-3 spread over their range and joint 4 in [0, spread]."""
    k = np.arange(m)
    q = np.column_stack(
        [
            -170.0 + 29.0 * k,
            -160.0 + 337.0 * k % 320.0,
            -150.0 + 211.0 * k % 300.0,
            np.degrees(spread_rad * k / (m - 1)),
        ]
    )
    return q


def _regressor(q_rad: np.ndarray) -> np.ndarray:
    """The test's own Hadamard-scaled Jacobian ``(2m, 8)``.

    Link columns ``(cos theta_k, sin theta_k)`` and ``(-sin theta_k, cos theta_k)`` per pose.
    """
    theta = np.cumsum(q_rad, axis=1)
    c, s = np.cos(theta), np.sin(theta)
    m = q_rad.shape[0]
    rows = np.zeros((m, 2, 8))
    rows[:, 0, :4], rows[:, 1, :4] = c, s
    rows[:, 0, 4:], rows[:, 1, 4:] = -s, c
    return rows.reshape(2 * m, 8) / np.sqrt(m)


def _positions(q_deg: np.ndarray) -> np.ndarray:
    """Noiseless positions of the true arm, computed with ``math`` (independent of armcal)."""
    out = []
    for pose in q_deg:
        x = y = angle = 0.0
        for length, dl, q, dq in zip(LINKS_MM, DL_MM, pose, DQ_DEG, strict=True):
            angle += math.radians(q + dq)
            x += (length + dl) * math.cos(angle)
            y += (length + dl) * math.sin(angle)
        out.append((x, y))
    return np.array(out)


def _tolerances(q_deg: np.ndarray) -> tuple[float, float, float]:
    """``cond``, and the error bounds (mm) on any link phasor and on links 1 and 2.

    Noiseless data are consistent, so a backward-stable solve errs by about
    ``cond eps`` relative to the link phasors ``|v| = sqrt(sum L_k^2)``: that
    bounds every parameter.  Links 1 and 2 lie outside the poorly seen plane:
    their error is the well-conditioned part's, ``(s_1 / s_6) eps |v|``, plus the
    poorly seen error times the sine of the angle between that plane and the
    null space of the exactly collinear plan, at most ``|H - H0| / s_6`` (Wedin).
    """
    q = np.radians(q_deg)
    h = _regressor(q)
    s = np.linalg.svd(h, compute_uv=False)
    collinear = q.copy()
    collinear[:, 3] = 0.0
    leak = np.linalg.norm(h - _regressor(collinear), 2) / s[5]
    phasors = float(np.linalg.norm(LINKS_MM + DL_MM))
    cond = s[0] / s[-1]
    every = ROUND_OFF * EPS * cond * phasors
    well = ROUND_OFF * EPS * (s[0] / s[5]) * phasors + leak * every
    return cond, every, well


def _phasor_errors(values_display: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Per link ``|Delta dl_k|`` and ``L_k |Delta dtheta_k|`` (mm) of display values vs truth."""
    delta = values_display - np.concatenate([DL_MM, DQ_DEG])
    dtheta = np.radians(np.cumsum(delta[4:]))
    return np.abs(delta[:4]), (LINKS_MM + DL_MM) * np.abs(dtheta)


def _write_csv(path: Path, header: str, rows: np.ndarray) -> None:
    lines = [header, *(",".join(repr(float(v)) for v in row) for row in rows)]
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")


# --------------------------------------------------------------------------- the program


@pytest.mark.parametrize("method", ["gauss-newton", "closed-form"])
def test_ill_conditioned_plan_identifies_with_a_warning(tmp_path, method):
    q_deg = _plan_deg(1e-8)
    cond, every, well = _tolerances(q_deg)
    assert COND_WARN < cond < 1.0 / RANK_RTOL  # warns, yet passes the rank check
    header = "q1_deg,q2_deg,q3_deg,q4_deg,x_mm,y_mm"
    _write_csv(tmp_path / "meas.csv", header, np.hstack([q_deg, _positions(q_deg)]))

    result = run_cli(tmp_path, "identify", "--robot", "paper-4link", "--measurements", "meas.csv",
                     "--method", method, "--sigma", "0.1", "--json")  # fmt: skip

    assert result.returncode == 0, result.stderr
    assert "Traceback" not in result.stderr
    warnings = [line for line in result.stderr.splitlines() if line.startswith("armcal: warning:")]
    # Noiseless data are too good for sigma = 0.1 mm, and say so (fit-too-good).
    assert len(warnings) == 2 and "better than sigma" in warnings[1], result.stderr
    assert "dl3 - dl4" in warnings[0] and "dq3 - 2.2*dq4" in warnings[0]
    assert "joint 4" in warnings[0] and "armcal design" in warnings[0]
    document = json.loads(result.stdout)
    assert [w["code"] for w in document["warnings"]] == ["ill-conditioned", "fit-too-good"]
    assert document["converged"] is True
    values = np.array([p["value"] for p in document["parameters"]])
    length_err, angle_err = _phasor_errors(values)
    # Every parameter to cond * eps (~1e-3 mm here); links 1 and 2 to round-off (~1e-10 mm).
    assert np.all(length_err <= every) and np.all(angle_err <= every)
    assert np.all(length_err[:2] <= well) and np.all(angle_err[:2] <= well)
    assert well < 1e-9  # the recovery promised for noiseless data holds where it can


def test_evaluate_six_identical_poses_is_one_error_line(tmp_path):
    _write_csv(
        tmp_path / "plan.csv", "q1_deg,q2_deg,q3_deg,q4_deg", np.tile([30, -60, 90, 45], (6, 1))
    )

    result = run_cli(tmp_path, "evaluate", "--plan", "plan.csv")

    assert result.returncode == 2
    assert "Traceback" not in result.stderr and result.stdout == ""
    lines = result.stderr.splitlines()
    assert len(lines) == 1 and lines[0].startswith("armcal: error: plan.csv: ")
    # 2 equations for 8 parameters: a 6-dimensional null space, 3 combinations shown.
    assert "rank 2 of 8" in lines[0] and "(and 3 more)" in lines[0]
    assert lines[0].count(";") >= 3 and "unseen combinations: dl1" in lines[0]


def test_design_from_identical_candidates_is_one_error_line_and_writes_nothing(tmp_path):
    # Exchange can only pick copies of one pose, so the certificate's plan is singular.
    _write_csv(
        tmp_path / "cands.csv", "q1_deg,q2_deg,q3_deg,q4_deg", np.tile([10, 20, 30, 40], (8, 1))
    )

    result = run_cli(
        tmp_path, "design", "--poses", "6", "--method", "exchange", "--candidates", "cands.csv",
        "-o", "plan.csv",
    )  # fmt: skip

    assert result.returncode == 2
    assert "Traceback" not in result.stderr and result.stdout == ""
    lines = result.stderr.splitlines()
    assert len(lines) == 1 and "rank 2 of 8" in lines[0] and "unseen combinations" in lines[0]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["cands.csv"]


# --------------------------------------------------------------------------- the library


SINGULAR_PLANS = {
    "identical": np.tile(np.radians([30.0, -60.0, 90.0, 45.0]), (6, 1)),
    "too-few": np.radians(_plan_deg(0.5)[:3]),
    "collinear": np.radians(_plan_deg(0.0)),
    "spread-1e-11": np.radians(_plan_deg(1e-11)),
}


@pytest.mark.parametrize("case", list(SINGULAR_PLANS))
def test_singular_plans_raise_armcal_errors_or_report_zero(case, rng):
    q = SINGULAR_PLANS[case]
    xy = forward_kinematics(ARM, q, TRUTH)
    test_q = random_plan(ARM, 20, rng=rng)
    for call in (
        lambda: identify(ARM, q, xy, sigma=0.1),
        lambda: identify(ARM, q, xy, sigma=0.1, method="gauss-newton"),
        lambda: solve_closed_form(ARM, q, xy),
        lambda: solve_gauss_newton(ARM, q, xy),
        lambda: evaluate_plan(ARM, q, sigma=0.1, test_q=test_q),
        lambda: position_accuracy(ARM, q, test_q, 0.1),
        lambda: certify(ARM, q, rng=rng, candidates=50, rounds=1, search=50),
        lambda: check_identifiable(ARM, q),
        lambda: monte_carlo(ARM, q, TRUTH, 0.1, 10, rng=rng),
    ):
        with pytest.raises(NotIdentifiableError) as info:
            call()
        assert info.value.combinations
    assert float(d_efficiency(ARM, q)) == 0.0
    assert all(float(v) == 0.0 for v in efficiencies(ARM, q).values())
    assert all(float(v) == 0.0 for v in observability_indices(ARM, q).values())
    assert np.all(np.isinf(predicted_std(ARM, q, 0.1)))
    assert inverse_information(ARM, q) is None
    # The optimizer's gradients on a singular Fs: huge, but no LinAlgError.
    for criterion in CRITERIA.values():
        criterion.log_gradient(scaled_information(ARM, q))


@pytest.mark.parametrize("spread", [1e-4, 1e-7, 1e-8, 1e-10, 1e-11, 1e-13, 0.0])
def test_criteria_agree_with_identifiability_at_tiny_singular_values(spread):
    """Eigenvalues of Fs cannot see a relative singular value of 1e-10; the policy must."""
    q = np.radians(_plan_deg(spread))
    s = np.linalg.svd(_regressor(q), compute_uv=False)
    relative = s[-1] / s[0]  # the test's own reference
    info = identifiability(ARM, q)
    assert_allclose(info.singular_values / info.singular_values[0], s / s[0], rtol=0, atol=1e-13)
    identifiable = relative > RANK_RTOL
    assert info.identifiable == identifiable
    eff = efficiencies(ARM, q)
    obs = observability_indices(ARM, q)
    std = predicted_std(ARM, q, 0.1)
    if identifiable:
        # E = s_p^2 and O3 = s_p for unit-norm columns scaled by 1/sqrt(m).
        assert_allclose(eff["E"], s[-1] ** 2, rtol=1e-6)
        assert_allclose(obs["O2"], relative, rtol=1e-6)
        assert all(v > 0 for v in eff.values()) and np.all(np.isfinite(std))
        check_identifiable(ARM, q)
    else:
        assert all(v == 0 for v in (*eff.values(), *obs.values()))
        assert np.all(np.isinf(std))
        with pytest.raises(NotIdentifiableError, match=r"dl3 - dl4; dq3 - 2\.2\*dq4"):
            check_identifiable(ARM, q)


@pytest.mark.parametrize("spread", [1e-6, 1e-7])
def test_gauss_newton_and_closed_form_agree_on_ill_conditioned_plans(spread, rng):
    q_deg = _plan_deg(spread)
    q = np.radians(q_deg)
    cond, every, _ = _tolerances(q_deg)
    assert 1e6 <= cond <= 1e8
    # Noise small enough that the fitted weak combination stays ~1e-3 mm from the
    # truth (its std is sigma cond / sqrt(m)): a fit a real arm could have.
    sigma = 1e-3 * math.sqrt(q.shape[0]) / cond
    clean = _positions(q_deg)
    sets = np.stack([clean, clean + rng.normal(0.0, sigma, clean.shape)])
    closed = solve_closed_form(ARM, q, sets)
    newton, iterations, converged = solve_gauss_newton(ARM, q, sets)
    assert converged.all() and iterations.max() <= 10
    # Gauss-Newton stops once its step is below tol * reach (1e-12 * 660 mm) and
    # converges quadratically; both solvers share the one least-squares fit.
    reach = float(np.sum(LINKS_MM))
    step_bound = 1e-12 * reach
    assert_allclose(newton[:, :4], closed[:, :4], rtol=0, atol=step_bound)
    theta_n, theta_c = np.cumsum(newton[:, 4:], axis=1), np.cumsum(closed[:, 4:], axis=1)
    assert_allclose(LINKS_MM * (theta_n - theta_c), 0.0, atol=step_bound)
    for method in ("closed-form", "gauss-newton"):
        cal = identify(ARM, q, clean, sigma=0.1, method=method)
        assert cal.converged
        # Noiseless data are too good for sigma = 0.1 mm, and say so.
        assert [w.code for w in cal.warnings] == ["ill-conditioned", "fit-too-good"]
        length_err, angle_err = _phasor_errors(cal.values)
        assert np.all(length_err <= every) and np.all(angle_err <= every)


def test_well_conditioned_plans_carry_no_warning(rng):
    q = random_plan(ARM, 20, rng=rng)
    cal = identify(ARM, q, forward_kinematics(ARM, q, TRUTH), sigma=0.1)
    # Noiseless data are too good for sigma = 0.1 mm (fit-too-good), nothing else.
    assert [w.code for w in cal.warnings] == ["fit-too-good"]
    assert not identifiability(ARM, q).ill_conditioned


# --------------------------------------------------------------------------- memory


@pytest.fixture(scope="module")
def big_problem():
    rng = np.random.default_rng(12)
    arm = PlanarArm(rng.uniform(50.0, 300.0, 12))
    q = random_plan(arm, 10_000, rng=rng)
    truth = arm.params_from_display(rng.uniform(-3, 3, 12), rng.uniform(-1, 1, 12))
    xy = forward_kinematics(arm, q, truth) + rng.normal(0.0, 0.1, (10_000, 2))
    return arm, q, xy


@pytest.mark.parametrize("task", ["identifiability", "closed-form", "gauss-newton"])
def test_identification_memory_is_linear_in_the_poses(big_problem, task):
    arm, q, xy = big_problem
    m, p = q.shape[0], arm.n_params
    regressor = 2 * m * p * 8  # bytes of one 2m x p float array: 3.8 MB
    tracemalloc.start()
    try:
        if task == "identifiability":
            identifiability(arm, q)
        else:
            identify(arm, q, xy, method=task)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    # A few arrays the size of the regressor (complex columns, the scaled copy, Q of
    # the thin QR); a 2m x 2m factor would be 2m / p = 833 times one of them.
    assert peak < 8 * regressor, f"{peak / 1e6:.1f} MB"


# --------------------------------------------------------------------------- numerics


def test_scaled_svd_pads_and_batches(rng):
    wide = rng.normal(size=(3, 2, 5))  # 2 rows, 5 columns: rank 2 at most
    svd = scaled_svd(wide)
    assert svd.singular_values.shape == (3, 5) and svd.vt.shape == (3, 5, 5)
    assert np.all(svd.rank == 2) and not np.any(svd.full_rank)
    assert np.all(svd.singular_values[:, 2:] == 0.0)
    tall = rng.normal(size=(4, 40, 3)) * [1.0, 1e3, 1e-3]  # scaling does not matter
    svd = scaled_svd(tall)
    inverse, ok = svd.inverse_gram()
    assert ok.all()
    expected = np.linalg.inv(np.swapaxes(tall, -1, -2) @ tall)
    assert_allclose(inverse, expected, rtol=1e-10, atol=0)
    _, logdet = np.linalg.slogdet(np.swapaxes(tall, -1, -2) @ tall)
    assert_allclose(svd.log_det_gram(), logdet, rtol=1e-12)


def test_least_squares_matches_lstsq_and_drops_unseen_directions(rng):
    a = rng.normal(size=(30, 4))
    b = rng.normal(size=(5, 30))
    factor = factor_least_squares(a)
    reference = np.linalg.lstsq(a, b.T, rcond=None)[0].T
    assert_allclose(factor.solve(b), reference, rtol=1e-12, atol=1e-14)
    singular = np.column_stack([a[:, :3], a[:, 0] - 2.0 * a[:, 1]])  # column 4 is dependent
    factor = factor_least_squares(singular)
    assert not factor.svd.full_rank
    x = factor.solve(b)
    assert np.all(np.isfinite(x))
    # The least-squares fit is still exact in the seen directions.
    best = np.linalg.lstsq(singular, b.T, rcond=None)[0].T
    assert_allclose(x @ singular.T, best @ singular.T, rtol=0, atol=1e-12)


@pytest.mark.parametrize("rows", [90, 151])  # blocks of 20 rows: 4 and 7 blocks, the last longer
def test_least_squares_in_blocks_of_rows_is_the_same_factorization(rng, monkeypatch, rows):
    import armcal.numerics as numerics

    a = rng.normal(size=(rows, 4)) * [1.0, 1e3, 1e-3, 5.0]
    b = rng.normal(size=(3, rows))
    whole = factor_least_squares(a)
    monkeypatch.setattr(numerics, "QR_BLOCK_ROWS", 20)
    blocked = factor_least_squares(a)
    assert blocked.basis.shape == (rows, 4)
    assert_allclose(blocked.basis.T @ blocked.basis, np.eye(4), rtol=0, atol=1e-14)
    assert_allclose(blocked.svd.singular_values, whole.svd.singular_values, rtol=1e-13)
    assert_allclose(blocked.solve(b), whole.solve(b), rtol=1e-12)
    singular = np.column_stack([a[:, :3], a[:, 0] - 2.0 * a[:, 1]])
    assert not factor_least_squares(singular).svd.full_rank


def test_spd_inverse_never_raises():
    assert_allclose(spd_inverse(np.diag([2.0, 4.0])), np.diag([0.5, 0.25]), rtol=1e-15)
    inverse = spd_inverse(np.ones((3, 3)))  # rank 1: np.linalg.inv raises on it
    assert np.all(np.isfinite(inverse))
