"""Design and criteria with several targets: every target measured at every pose (issue 10)."""

import numpy as np
import pytest
from numpy.testing import assert_allclose

from armcal import (
    ArmcalError,
    PlanarArm,
    Target,
    design,
    evaluate_plan,
    orthogonal_plan,
    random_plan,
)
from armcal.doe import analytic_plan
from armcal.models import Annulus, every_target, forward_kinematics, plan_rows
from armcal.models.planar.closed_form import solve_closed_form
from armcal.models.planar.design import information_gradient, pose_model

NEST = (Target("A", 100.0, 0.0), Target("B", 80.0, 0.7), Target("C", 120.0, -0.5))


def test_an_orthogonal_plan_is_orthogonal_for_every_target():
    """Cross sums between a shared link and a target's last link are the single-target
    ones turned by the target's angle, and two targets share no row: all vanish."""
    arm = PlanarArm([260.0, 180.0, 100.0], targets=NEST)
    quality = evaluate_plan(
        arm, orthogonal_plan(arm, 12), sigma=0.1, test_q=random_plan(arm, 20, rng=0)
    )
    for value in quality.efficiencies.values():
        assert value == pytest.approx(1.0, abs=1e-12)
    # std of a target's length: sigma / sqrt(m), each target seen once per pose;
    # of a shared length: sigma / sqrt(m T) (orthogonal plan, paper eq. 24)
    std = dict(zip(arm.param_names, quality.predicted_std, strict=True))
    assert std["dl3@B"] == pytest.approx(0.1 / np.sqrt(12), rel=1e-12)
    assert std["dl1"] == pytest.approx(0.1 / np.sqrt(36), rel=1e-12)


def test_predicted_std_of_a_multi_target_plan_agrees_with_monte_carlo(rng):
    """4000 noisy sets: the sample std has 1.1 % relative std; 5 % is over 4 of them."""
    arm = PlanarArm([260.0, 180.0, 100.0], targets=NEST)
    q = random_plan(arm, 10, rng=rng)
    predicted = evaluate_plan(arm, q, sigma=0.1, test_q=q).predicted_std
    rows, target = every_target(arm, q)
    clean = forward_kinematics(arm, rows, target=target)
    sets = clean + 0.1 * rng.standard_normal((4000, *clean.shape))
    est = solve_closed_form(arm, rows, sets, target=target) * arm.display_scale
    assert_allclose(est.std(axis=0), predicted, rtol=0.05)


def test_the_information_gradient_sums_every_target_of_a_pose(rng):
    arm = PlanarArm([260.0, 180.0, 100.0], targets=NEST)
    q = rng.uniform(-np.pi, np.pi, (6, 3))
    phi = rng.standard_normal((arm.n_free, arm.n_free))
    phi = phi + phi.T

    def inner(x):
        c = pose_model(arm, x).columns
        return float(np.einsum("ma,ab,mb->", c.conj(), phi, c).real)

    grad = information_gradient(arm, pose_model(arm, q), phi)
    h = 1e-6
    for i, j in [(0, 0), (2, 1), (5, 2)]:
        step = np.zeros_like(q)
        step[i, j] = h
        numeric = (inner(q + step) - inner(q - step)) / (2 * h)
        assert grad[i, j] == pytest.approx(numeric, rel=1e-6, abs=1e-6)


def test_a_limited_multi_target_design_is_certified():
    limits = np.radians([[-170, 170], [-60, 60], [-60, 60]])
    arm = PlanarArm([260.0, 180.0, 100.0], limits, targets=NEST, sigma=0.02)
    result = design(arm, 15, rng=0)
    assert result.method == "optimize"  # exchange evaluates one point per pose
    assert np.all(arm.within_limits(result.q))
    assert result.certificate is not None
    assert result.certificate.certified_d_efficiency >= 0.98
    # the plan is better than the same design for the arm without its targets
    plain = design(
        PlanarArm([260.0, 180.0, 100.0], limits, sigma=0.02), 15, rng=0, with_certificate=False
    )
    from armcal import d_efficiency

    assert float(d_efficiency(arm, result.q)) >= float(d_efficiency(arm, plain.q)) - 1e-9


@pytest.mark.parametrize(("target", "prefix"), [("angle_std_deg", "dq"), ("length_std_mm", "dl")])
def test_poses_needed_counts_every_target_parameter(target: str, prefix: str) -> None:
    """The goal holds for every dl (dq) of the model, the targets' dl3@T (dq3@T) included."""
    from armcal import poses_needed, predicted_std

    arm = PlanarArm(
        [300.0, 200.0, 100.0],
        targets=(Target("A", 100.0), Target("B", 60.0, 0.5), Target("C", 140.0, -0.4)),
    )
    sigma = 0.02
    goal = 0.002 if prefix == "dq" else 0.006
    found = poses_needed(arm, target, goal, sigma=sigma, rng=0)
    std = predicted_std(arm, found.plan, sigma)
    picked = [i for i, name in enumerate(arm.param_names) if name.startswith(prefix)]
    assert any("@" in arm.param_names[i] for i in picked)
    assert std[picked].max() <= goal * (1 + 1e-9)
    smaller = design(arm, found.poses - 1, rng=0).q
    assert predicted_std(arm, smaller, sigma)[picked].max() > goal


@pytest.mark.parametrize(
    "targets", [(), (Target("A", 150.0, 0.6),), NEST], ids=["tip", "one target", "nest"]
)
def test_region_constraints_hold_every_target_and_their_gradient_is_exact(targets, rng):
    """The view's constraints are the region's at every target's point (forward
    kinematics), and their joint gradient matches central differences.

    With one target at 0.6 rad and 150 mm the target is not the end of link 3
    (the constraint there differs by up to the 150 mm lever), which the region
    must see.
    """
    region = Annulus((100.0, 50.0), 150.0, 500.0)
    arm = PlanarArm([260.0, 180.0, 100.0], targets=targets, region=region)
    q = random_plan(arm, 5, rng=rng)
    g, dg = arm.view_constraints(q)
    rows, target, _ = plan_rows(arm, q, None)
    expected, _ = region.constraints(forward_kinematics(arm, rows, target=target))
    assert_allclose(g, expected.reshape(g.shape), rtol=0, atol=1e-12)
    h = 1e-6
    for j in range(3):
        step = np.zeros(3)
        step[j] = h
        numeric = (arm.view_constraints(q + step)[0] - arm.view_constraints(q - step)[0]) / (2 * h)
        # g is O(100) mm with O(500) mm/rad^2 curvature: truncation ~h^2 500, round-off
        # ~1e-13 / h: 1e-6 mm/rad is far above both and far below the O(100) gradient.
        assert_allclose(dg[..., j], numeric, rtol=0, atol=1e-6)


@pytest.mark.parametrize("m", [6, 8, 12])
@pytest.mark.parametrize("count", [1, 2])
def test_a_closed_form_plan_never_puts_a_target_outside_the_region(m, count):
    """The closed form is placed for the end of link n; a target 150 mm off at 1 rad can
    fall outside the annulus (it did at 6 of these 10 placements): such a plan is refused,
    and design searches instead.  Whatever comes back has every target inside."""
    targets = (Target("A", 150.0, 1.0), Target("B", 100.0, -0.8))[:count]
    region = Annulus((60.0, 0.0), 200.0, 520.0)
    arm = PlanarArm([260.0, 180.0, 90.0], targets=targets, region=region)
    try:
        q = analytic_plan(arm, m)
    except ArmcalError:
        q = design(arm, m, rng=0, with_certificate=False).q
    assert np.all(arm.feasible(q))
