"""Optimal plans: analytic optimum, constrained optimization, exchange, certificate."""

import itertools

import numpy as np
import pytest

from armcal import Annulus, ArmcalError, PlanarArm, jacobian, random_plan
from armcal.cli import main
from armcal.criteria import d_efficiency
from armcal.doe import (
    analytic_plan,
    certify,
    design,
    exchange_plan,
    feasible,
    feasible_poses,
    optimize_plan,
)
from armcal.models.planar.criteria import information_matrix, optimality_sums

PAPER_LENGTHS = [260.0, 180.0, 120.0, 100.0]
LIMITS_60 = np.radians([[-180, 180], [-60, 60], [-60, 60], [-60, 60]])


@pytest.fixture(scope="module")
def arm60() -> PlanarArm:
    return PlanarArm(PAPER_LENGTHS, LIMITS_60, name="paper-4link-60")


def _corner_plan() -> np.ndarray:
    """The 8 corners of the +-60 deg cube of joints 2..4 (joint 1 at 0), one pose each."""
    q = np.zeros((8, 4))
    q[:, 1:] = np.array(list(itertools.product((-1.0, 1.0), repeat=3))) * LIMITS_60[1:, 1]
    return q


#: D-efficiency of the best design within +-60 deg: the equal-weight 8-corner design,
#: whose optimality test_corner_design_is_d_optimal proves (Kiefer-Wolfowitz).
BEST_60 = float(d_efficiency(PlanarArm(PAPER_LENGTHS, LIMITS_60), _corner_plan()))


def test_corner_design_is_d_optimal(arm60, rng):
    # Kiefer-Wolfowitz: a design xi is D-optimal iff max_x d(x, xi) = p, where
    # d(x, xi) = tr(M(xi)^-1 J(x)^T J(x)) (any parametrization gives the same d).
    corners = _corner_plan()
    info = information_matrix(arm60, corners) / corners.shape[0]
    inverse = np.linalg.inv(info)

    def variance(q):
        jac = jacobian(arm60, q, parametrization="paper")
        return np.einsum("kip,pr,kir->k", jac, inverse, jac)

    p = arm60.n_params
    np.testing.assert_allclose(variance(corners), p, rtol=1e-12)
    # The maximum over 50 000 random feasible poses stays below p (the bound is attained
    # only at the corners, which a random pose reaches with probability 0).
    assert float(variance(random_plan(arm60, 50_000, rng=rng)).max()) <= p * (1 + 1e-12)


@pytest.fixture(scope="module")
def designs60(arm60):
    return {m: design(arm60, m, rng=0) for m in (8, 20)}


@pytest.mark.parametrize("base_offset", [False, True])
@pytest.mark.parametrize("n", range(2, 9))
def test_unconstrained_designs_are_optimal_for_every_m(n, base_offset):
    arm = PlanarArm(np.linspace(300.0, 80.0, n), base_offset=base_offset)
    first = n + 1 if base_offset else n
    for m in range(first, 61):
        result = design(arm, m, rng=0)
        assert result.method == "analytic"
        assert np.all(feasible(arm, result.q))
        assert result.d_efficiency == pytest.approx(1.0, abs=1e-9)
        assert float(d_efficiency(arm, result.q)) == pytest.approx(1.0, abs=1e-9)
        assert max(abs(v) for v in optimality_sums(arm, result.q).values()) <= 1e-9
        assert result.certificate.certified_d_efficiency == pytest.approx(1.0, abs=1e-9)


@pytest.mark.parametrize(("n", "m", "base_offset"), [(2, 2, False), (4, 5, True), (8, 60, False)])
def test_design_takes_the_analytic_plan_when_unconstrained(n, m, base_offset):
    arm = PlanarArm(np.linspace(300.0, 80.0, n), base_offset=base_offset)
    result = design(arm, m, rng=0)
    assert result.method == "analytic"
    assert result.d_efficiency == pytest.approx(1.0, abs=1e-9)
    assert result.certificate.certified_d_efficiency == pytest.approx(1.0, abs=1e-9)


def test_analytic_plan_reports_when_limits_forbid_it(arm60):
    with pytest.raises(ArmcalError, match="joint limits"):
        analytic_plan(arm60, 8)
    # Limits of +-170 deg still admit 18 poses spaced 20 deg apart, not 19.
    arm170 = PlanarArm(PAPER_LENGTHS, np.radians([[-170, 170]] * 4))
    assert d_efficiency(arm170, analytic_plan(arm170, 18)) == pytest.approx(1.0, abs=1e-12)
    with pytest.raises(ArmcalError):
        analytic_plan(arm170, 19)


@pytest.mark.parametrize("m", [8, 20])
def test_limited_paper_arm_design_is_certified(m, arm60, designs60, rng):
    result = designs60[m]
    assert result.method.startswith("optimize")
    assert result.d_efficiency >= 0.80
    lo, hi = LIMITS_60[:, 0], LIMITS_60[:, 1]
    assert np.all((result.q >= lo - 1e-9) & (result.q <= hi + 1e-9))
    cert = result.certificate
    assert cert.certified_d_efficiency >= 0.99
    # Never overclaim: the certificate bounds the efficiency relative to the best plan known.
    assert cert.certified_d_efficiency <= result.d_efficiency / BEST_60 + 1e-6
    assert cert.plan_only_bound <= cert.certified_d_efficiency
    random_best = float(
        d_efficiency(arm60, np.stack([random_plan(arm60, m, rng=rng) for _ in range(1000)])).max()
    )
    print(f"m={m}: design {result.d_efficiency:.4f} vs best of 1000 random {random_best:.4f}")
    assert result.d_efficiency > 1.4 * random_best


def test_plan_only_bound_is_looser_at_m20(designs60):
    result = designs60[20]
    cert = result.certificate
    # Both are lower bounds on the efficiency relative to the best design, d / BEST_60;
    # the plan-only bound ignores the reference design, so it is the looser one here.
    assert cert.plan_only_bound <= result.d_efficiency / BEST_60 + 1e-9
    assert cert.plan_only_bound < cert.certified_d_efficiency
    # The certificate's reference design is the 8-corner optimum (to the multiplicative
    # algorithm's convergence).
    assert cert.reference_d_efficiency == pytest.approx(BEST_60, rel=1e-4)


@pytest.mark.slow  # seconds of certificate searches: run by make test-slow
def test_certificate_never_overclaims_for_random_plans(arm60, rng):
    for _ in range(3):
        q = random_plan(arm60, 12, rng=rng)
        cert = certify(arm60, q, rng=rng)
        true_upper = float(d_efficiency(arm60, q)) / BEST_60
        assert cert.certified_d_efficiency <= true_upper + 1e-9
        assert cert.certified_d_efficiency >= cert.plan_only_bound


@pytest.mark.slow  # seconds of certificate searches: run by make test-slow
def test_annulus_region_keeps_every_tip_inside():
    region = Annulus((0.0, 0.0), 300.0, 520.0)  # excludes the inner workspace and the rim
    arm = PlanarArm(PAPER_LENGTHS, LIMITS_60, name="annulus", region=region)
    result = design(arm, 12, rng=1)
    tips = np.sum(arm.link_lengths * np.exp(1j * np.cumsum(result.q, axis=1)), axis=1)
    assert np.all((np.abs(tips) >= 300.0 - 1e-9) & (np.abs(tips) <= 520.0 + 1e-9))
    assert result.d_efficiency > 0.6
    assert result.certificate.certified_d_efficiency > 0.95


def test_exchange_swap_ratio_matches_direct_determinants(rng):
    arm = PlanarArm([2.0, 1.5, 1.0])
    candidates = random_plan(arm, 50, rng=rng)
    start = random_plan(arm, 8, rng=rng)
    plan = exchange_plan(arm, 8, candidates, start=start)
    assert d_efficiency(arm, plan) > d_efficiency(arm, start)
    # Exchange optimality: no single swap improves the determinant.
    blocks = arm.plan_information(plan).blocks()
    info = np.einsum("iap,iaq->pq", blocks, blocks)
    logdet = np.linalg.slogdet(info)[1]
    cand_blocks = arm.plan_information(candidates).blocks()
    for i in range(8):
        for x in range(0, 50, 7):
            swapped = info - blocks[i].T @ blocks[i] + cand_blocks[x].T @ cand_blocks[x]
            assert np.linalg.slogdet(swapped)[1] <= logdet + 1e-9


def test_exchange_uses_user_candidates_only(rng):
    arm = PlanarArm(PAPER_LENGTHS, LIMITS_60)
    candidates = feasible_poses(arm, 300, rng=rng)
    plan = exchange_plan(arm, 10, candidates, rng=rng)
    assert all(any(np.array_equal(p, c) for c in candidates) for p in plan)


@pytest.mark.parametrize("criterion", ["A", "E"])
def test_other_criteria_optimize_their_own_efficiency(criterion, arm60):
    from armcal.criteria import efficiencies

    q_d = optimize_plan(arm60, 12, criterion="D", rng=0, starts=16)
    q_c = optimize_plan(arm60, 12, criterion=criterion, rng=0, starts=16)
    assert efficiencies(arm60, q_c)[criterion] >= efficiencies(arm60, q_d)[criterion] - 1e-6


@pytest.mark.slow  # seconds of certificate searches: run by make test-slow
def test_same_seed_gives_the_same_plan_file(tmp_path):
    robot = tmp_path / "robot.toml"
    robot.write_text(
        "link_lengths_mm = [260.0, 180.0, 120.0, 100.0]\n"
        "joint_limits_deg = [[-180, 180], [-60, 60], [-60, 60], [-60, 60]]\n"
    )
    files = []
    for name, seed in (("a", "3"), ("b", "3")):
        out = tmp_path / f"{name}.csv"
        args = ["design", "--robot", str(robot), "--poses", "10", "--seed", seed]
        assert main([*args, "-o", str(out)]) == 0
        files.append(out.read_bytes())
    assert files[0] == files[1]


def test_a_large_searched_plan_is_a_smaller_optimal_plan_repeated():
    """Issue 20: design --poses 10000 with limits ran 325 s and took 15.5 GB.  Above
    REPLICATE_ABOVE poses the plan is the best plan of m // k poses taken k times (and
    a few of its poses once more): its normalized information is the base plan's."""
    from armcal.doe import designer as designer_module

    arm = PlanarArm([260.0, 180.0, 120.0, 100.0], np.radians([[-170, 170]] + [[-150, 150]] * 3))
    m = 2 * designer_module.REPLICATE_ABOVE + 7  # 3 copies of 82 poses and 1 more
    found = designer_module.design(arm, m, rng=1, with_certificate=True, order="none")
    copies, size = 3, m // 3
    base = found.q[:size]
    np.testing.assert_array_equal(found.q[: copies * size], np.tile(base, (copies, 1)))
    np.testing.assert_array_equal(found.q[copies * size :], base[: m - copies * size])
    assert any(f"the optimal {size}-pose plan taken {copies} times" in n for n in found.notes)
    # Normalized (per pose) information: a repeated plan's D-efficiency is its base's.
    np.testing.assert_allclose(
        d_efficiency(arm, np.tile(base, (copies, 1))), d_efficiency(arm, base), rtol=1e-12
    )
    assert found.d_efficiency > 0.99
    assert found.certificate is not None and found.certificate.certified_d_efficiency > 0.99


def test_design_reports_its_progress():
    """The command line draws a bar from these calls on a terminal after 2 s (issue 20)."""
    from armcal.doe import designer as designer_module

    calls = []
    designer_module.design(
        PlanarArm([260.0, 180.0]), 6, rng=0, progress=lambda *a: calls.append(a)
    )
    assert calls[-3:] == [(500, 1000), (950, 1000), (1000, 1000)]
    done = [d for d, total in calls]
    assert all(total == 1000 for _, total in calls) and done == sorted(done)


def test_a_spatial_design_reports_its_progress_as_it_goes():
    """Its optimizer and certificate take seconds: the bar moves through both, not only at
    their ends, and never backwards."""
    from armcal.doe import designer as designer_module
    from armcal.doe import feasible_poses
    from armcal.files import load_spatial_robot

    arm = load_spatial_robot("industrial-6r").arm
    model = arm.prepared(arm.plan_conditions(feasible_poses(arm, 100, rng=0)))
    calls = []
    designer_module.design(model, 16, rng=0, progress=lambda *a: calls.append(a))
    done = [d for d, _ in calls]
    assert done == sorted(done) and done[-1] == 1000
    assert sum(0 < d < 500 for d in done) >= 5 and sum(500 < d < 950 for d in done) >= 5
