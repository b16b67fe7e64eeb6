"""The weights behind a certificate: the algorithms that find them, and the claim checked
from the design's JSON alone (issue 37).

Every expectation is derived here: the D-optimal design of quadratic regression on
``[-1, 1]`` is weight 1/3 at -1, 0 and 1 (Kiefer and Wolfowitz 1960; Atkinson, Donev and
Tobias 2007, sec. 11.3), and the Kiefer-Wolfowitz bound is recomputed from the reported
poses and weights with the model's own per-pose information.
"""

from __future__ import annotations

import json

import numpy as np
import pytest

from armcal.cli import main
from armcal.doe.weights import (
    multiplicative_weights,
    newton_weights,
    optimal_weights,
    variances,
)


def _quadratic_blocks(x: np.ndarray) -> np.ndarray:
    """One row ``(1, x, x^2)`` per candidate: blocks ``(N, 1, 3)``."""
    return np.stack([np.ones_like(x), x, x**2], axis=-1)[:, None, :]


def test_newton_weights_find_the_quadratic_regression_optimum():
    """Candidates on a grid of [-1, 1] holding -1, 0, 1: weights 1/3 there to 1e-6, 0
    elsewhere, and max d = p = 3 (the equivalence theorem) to 1e-6 relative."""
    x = np.linspace(-1.0, 1.0, 41)
    blocks = _quadratic_blocks(x)
    found = newton_weights(blocks, np.full(x.size, 1.0 / x.size), tolerance=1e-9)
    support = {-1.0: 0, 0.0: 20, 1.0: 40}
    for index in support.values():
        assert found.weights[index] == pytest.approx(1 / 3, abs=1e-6)
    others = np.delete(found.weights, list(support.values()))
    assert others.max() <= 1e-6
    assert found.max_variance == pytest.approx(3.0, rel=1e-6)


def test_newton_weights_take_in_candidates_of_weight_zero():
    """Started on -1, -0.5 and 0.5 only, the active set takes in 0 and 1 (their d > p)."""
    x = np.linspace(-1.0, 1.0, 5)  # -1, -0.5, 0, 0.5, 1
    blocks = _quadratic_blocks(x)
    start = np.array([1.0, 1.0, 0.0, 1.0, 0.0])
    found = newton_weights(blocks, start, tolerance=1e-9)
    np.testing.assert_allclose(found.weights, [1 / 3, 0, 1 / 3, 0, 1 / 3], atol=1e-6)


def test_optimal_weights_meet_their_tolerance_and_keep_the_tightest_bound():
    """Several rows a pose (two responses, 4 parameters): the multiplicative algorithm run
    to a tolerance ends with max d <= p (1 + tol), its variances are those of its weights,
    and no iterate of the plain algorithm gives a lower bound log det M + max d."""
    rng = np.random.default_rng(4)
    blocks = rng.normal(size=(300, 2, 4))
    found = optimal_weights(blocks, tolerance=1e-3, power=2.0, iterations=5000)
    assert found.max_variance <= 4 * (1 + 1e-3)
    information = np.einsum("k,krp,krq->pq", found.weights, blocks, blocks)
    np.testing.assert_allclose(
        found.variances, variances(blocks, np.linalg.inv(information)), rtol=1e-9
    )
    np.testing.assert_allclose(found.m_inv, np.linalg.inv(information), rtol=1e-8)
    bound = np.linalg.slogdet(information)[1] + found.max_variance
    weights = np.full(300, 1 / 300)
    for _ in range(found.iterations):
        weights = multiplicative_weights(blocks, weights, 1, power=2.0)
        m = np.einsum("k,krp,krq->pq", weights, blocks, blocks)
        d = variances(blocks, np.linalg.inv(m))
        assert np.linalg.slogdet(m)[1] + d.max() >= bound - 1e-9


def test_variances_agree_with_the_trace_formula():
    rng = np.random.default_rng(5)
    blocks = rng.normal(size=(7, 3, 5))
    a = rng.normal(size=(5, 5))
    m_inv = a @ a.T
    expected = [np.trace(m_inv @ b.T @ b) for b in blocks]
    np.testing.assert_allclose(variances(blocks, m_inv), expected, rtol=1e-12)


@pytest.mark.parametrize("pool", [False, True])
def test_the_certified_figure_is_checked_from_the_json_alone(tmp_path, capsys, pool):
    """A planar arm within +-60 deg (no closed form fits, so the certificate searches):
    from the JSON's reference design (poses, weights), the plan's poses and the reported
    max_variance, the Kiefer-Wolfowitz bound recomputed with the model's information is at
    least the certified figure (to 1e-9) whenever it exceeds the plan-only bound; the
    reported max_variance is d at the reported pose (1e-9); a dense random search of 20 000
    feasible poses (or the whole pool) finds no d above it."""
    from armcal.doe import feasible_poses
    from armcal.models import PlanarArm

    limits = "[[-60, 60], [-60, 60], [-60, 60]]"
    robot = tmp_path / "r.toml"
    robot.write_text(
        f"name = 'r'\nlink_lengths_mm = [260, 180, 120]\njoint_limits_deg = {limits}\n"
        "[measurement]\nsigma_mm = 0.1\n",
        encoding="utf-8",
    )
    arm = PlanarArm(np.array([260.0, 180.0, 120.0]), np.radians([[-60, 60]] * 3))
    args = ["design", "--robot", str(robot), "--poses", "9", "--seed", "2", "--json"]
    candidates = feasible_poses(arm, 2000, rng=3)
    if pool:
        path = tmp_path / "pool.csv"
        np.savetxt(
            path, np.degrees(candidates), delimiter=",", header="q1_deg,q2_deg,q3_deg",
            comments="", fmt="%.9f",
        )  # fmt: skip
        candidates = np.radians(np.loadtxt(path, delimiter=",", skiprows=1))
        args += ["--candidates", str(path)]
    args += ["-o", str(tmp_path / "plan.csv")]
    assert main(args) == 0
    document = json.loads(capsys.readouterr().out)
    plan = np.radians(np.loadtxt(tmp_path / "plan.csv", delimiter=",", skiprows=1))
    reference = document["reference_design"]
    support = np.radians(np.array(reference["poses_deg"]))
    weights = np.array(reference["weights"])
    assert weights.sum() == pytest.approx(1.0, abs=1e-12)
    p = arm.n_free
    info = arm.plan_information(support)
    blocks = info.blocks() / np.sqrt(info.rows_per_pose)
    star = np.einsum("k,krp,krq->pq", weights, blocks, blocks)
    plan_m = arm.plan_information(plan).information()
    log_ratio = np.linalg.slogdet(plan_m)[1] - np.linalg.slogdet(star)[1]
    largest = document["max_variance"]
    kw = np.exp(log_ratio / p + 1 - largest / p)
    certified = document["certified_d_efficiency"]
    if certified > document["plan_only_bound"] + 1e-12 and certified < 1.0:
        assert kw == pytest.approx(certified, rel=1e-9)
    at = np.radians(np.array(document["max_variance_pose_deg"]))[None, :]
    inverse = np.linalg.inv(star)
    value, _ = arm.plan_information(at).pose_variance(inverse)
    assert value[0] == pytest.approx(largest, rel=1e-9)
    dense = candidates if pool else feasible_poses(arm, 20_000, rng=11)
    found, _ = arm.plan_information(dense).pose_variance(inverse)
    assert found.max() <= largest * (1 + 1e-9)


def test_optimal_weights_on_one_reading_a_pose_reach_the_known_optimum():
    """Cubic regression on [-1, 1], one row (1, x, x^2, x^3) a candidate (rank-1 blocks,
    as a plane's touches give): the D-optimal design puts 1/4 on -1, -1/sqrt(5),
    1/sqrt(5) and 1 (Guest 1958).  From uniform weights on 2000 random candidates and
    those four, the weights found have a D-efficiency of at least 0.99 against it
    (``exp(-TOLERANCE)`` = 0.997 is what the stopping rule aims at; exponent 4 alone
    oscillated there and stopped at 0.68)."""
    rng = np.random.default_rng(0)
    x = np.concatenate([rng.uniform(-1, 1, 2000), [-1, -1 / np.sqrt(5), 1 / np.sqrt(5), 1]])
    blocks = np.stack([np.ones_like(x), x, x**2, x**3], axis=-1)[:, None, :]
    found = optimal_weights(blocks, None)

    def det(w: np.ndarray) -> float:
        rows = blocks[:, 0, :]
        return float(np.linalg.det((rows * w[:, None]).T @ rows))

    guest = np.zeros(x.size)
    guest[-4:] = 0.25
    assert (det(found.weights) / det(guest)) ** 0.25 >= 0.99


@pytest.mark.parametrize("per_pose, p", [(2, 4), (3, 30), (12, 5)])
def test_the_weight_hessian_is_the_squared_cross_products_either_way(per_pose, p):
    """``H_xy = ||F_x M^-1 F_y^T||_F^2`` (the definition, pair by pair) from both routes:
    the rows' cross products (few rows a pose) and the Gram matrices' (many), to 1e-12
    relative."""
    from armcal.doe.weights import _weight_hessian

    rng = np.random.default_rng(7)
    blocks = rng.normal(size=(9, per_pose, p))
    half = rng.normal(size=(p, p))
    m_inv = half @ half.T / p
    expected = np.array([[np.sum((fx @ m_inv @ fy.T) ** 2) for fy in blocks] for fx in blocks])
    found = _weight_hessian(blocks, m_inv)
    np.testing.assert_allclose(found, expected, rtol=1e-12, atol=1e-12 * np.abs(expected).max())
