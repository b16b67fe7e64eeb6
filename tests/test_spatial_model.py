"""The spatial serial arm as a model: kinematics, Jacobians, the identifiable set, recovery.

Every constant is derived: the published nominal geometries are cited where
they are written (the built-in robot files); the counts follow Everett, Driels
and Mooring's ``4R + 2P + 6`` for a full pose, less the 3 orientation
coordinates a point cannot see, plus 3 per further point: ``4R + 2P + 3k``.
"""

from __future__ import annotations

import numpy as np
import pytest

from armcal.identification import identify
from armcal.models import SerialChain, UrdfJoint, matrix_rpy, rpy_matrix
from armcal.models.wording import held_sentence
from armcal.noise import NoiseModel
from helpers_spatial import ARMS, cobot, industrial, labelled, random_poses, random_truth


@pytest.mark.parametrize("name", sorted(ARMS))
def test_the_jacobians_agree_with_central_differences(name):
    arm = labelled(ARMS[name](), 2)
    rng = np.random.default_rng(1)
    params = random_truth(arm, rng)
    q = random_poses(arm, 6, rng)
    cond = arm.conditions(q, target=np.array([0, 1, 0, 1, 1, 0]))
    jac = arm.jacobian(cond, params)
    h = 1e-6  # central differences err by h^2 |p'''| ~ 1e-12 * 1e4 mm; round-off 1e-16 * 4e3 / h
    numeric = np.empty_like(jac)
    for i in range(arm.n_params):
        step = np.zeros(arm.n_params)
        step[i] = h
        numeric[..., i] = (
            arm.positions(cond, params + step) - arm.positions(cond, params - step)
        ) / (2 * h)
    np.testing.assert_allclose(jac, numeric, rtol=0, atol=1e-5)
    joint = arm.joint_jacobian(cond, params)
    for j in range(arm.n_joints):
        step = np.zeros(arm.n_joints)
        step[j] = h
        plus = arm.positions(arm.conditions(q + step, target=cond.target), params)
        minus = arm.positions(arm.conditions(q - step, target=cond.target), params)
        np.testing.assert_allclose(joint[..., j], (plus - minus) / (2 * h), rtol=0, atol=1e-5)


def test_a_batch_of_parameter_sets_is_each_set_alone():
    arm = labelled(industrial(), 3)
    rng = np.random.default_rng(2)
    stack = np.stack([random_truth(arm, rng) for _ in range(3)])
    cond = arm.plan_conditions(random_poses(arm, 4, rng))
    batched = arm.jacobian(cond, stack)
    for i in range(3):
        np.testing.assert_array_equal(batched[i], arm.jacobian(cond, stack[i]))


def test_the_nominal_points_are_the_chain_s_forward_kinematics():
    arm = cobot()
    q = random_poses(arm, 5, np.random.default_rng(3))
    frames = arm.chain.forward(q)
    params = arm.nominal.copy()
    params[arm.layout.target_start :] = 0.0  # the target at the flange
    np.testing.assert_allclose(
        arm.positions(arm.conditions(q), params), frames[:, :3, 3], rtol=0, atol=1e-9
    )


def test_a_urdf_chain_equals_its_dh_table():
    """A URDF joint about y with an rpy origin, folded fixed joints, and the same arm as MDH."""
    mdh = SerialChain.from_mdh(np.radians([0, -90]), [0, 100.0], [0, 0], [50.0, 0])
    joints = [
        UrdfJoint("mount", "fixed", (0, 0, 20.0), (0, 0, 0)),
        UrdfJoint("j1", "revolute", (0, 0, 30.0), (0, 0, 0), (0, 0, 1)),
        UrdfJoint("j2", "continuous", (100.0, 0, 0), (-np.pi / 2, 0, 0), (0, 0, 1)),
        UrdfJoint("flange", "fixed", (0, 0, 0), (0, 0, 0)),
    ]
    urdf = SerialChain.from_joints(joints)
    u = np.random.default_rng(4).uniform(-3, 3, (7, 2))
    np.testing.assert_allclose(urdf.forward(u), mdh.forward(u), rtol=0, atol=1e-12)
    # The same second joint described about -y in an unturned frame: the same points (the
    # link frame itself is another one).
    about_y = [*joints[:2], UrdfJoint("j2", "revolute", (100.0, 0, 0), (0, 0, 0), (0, -1, 0))]
    np.testing.assert_allclose(
        SerialChain.from_joints(about_y).forward(u)[..., :3, 3],
        mdh.forward(u)[..., :3, 3],
        rtol=0,
        atol=1e-12,
    )


def test_roll_pitch_yaw_round_trips():
    rpy = np.random.default_rng(5).uniform([-3, -1.5, -3], [3, 1.5, 3], (50, 3))
    np.testing.assert_allclose(matrix_rpy(rpy_matrix(rpy)), rpy, rtol=0, atol=1e-12)


@pytest.mark.parametrize("name", sorted(ARMS))
@pytest.mark.parametrize("k", [1, 2, 3])
def test_the_identifiable_count_is_4r_plus_2p_plus_3k(name, k):
    arm = labelled(ARMS[name](), k)
    rng = np.random.default_rng(6)
    cond = arm.plan_conditions(random_poses(arm, 30, rng))
    chosen = arm.prepared(cond)
    revolute = int(np.sum(arm.chain.revolute))
    prismatic = arm.n_joints - revolute
    assert chosen.n_free == 4 * revolute + 2 * prismatic + 3 * k
    assert chosen.check_identifiable(cond).identifiable
    # The count bounds the rank over any rows: the arm as loaded surely needs preparing,
    # with no rank analysis; the prepared one reaches the bound.
    from armcal.models.information import surely_unidentified

    assert arm.rank_bound == chosen.rank_bound == chosen.n_free
    assert surely_unidentified(arm) and not surely_unidentified(chosen)
    assert not arm.identifiability(cond)[0].identifiable


def test_the_chosen_set_is_the_same_for_any_row_order_and_run():
    arm = labelled(industrial(), 3)
    rng = np.random.default_rng(7)
    q = random_poses(arm, 25, rng)
    truth = random_truth(arm, rng)
    cond = arm.plan_conditions(q)
    points = arm.positions(cond, truth)
    first = arm.prepared(cond, points)
    for seed in range(5):
        order = np.random.default_rng(seed).permutation(cond.m)
        shuffled = arm.conditions(cond.q[order], target=cond.target[order])
        again = arm.prepared(shuffled, points[order])
        assert again.free_names == first.free_names
        assert again.merges == first.merges


def test_the_report_names_what_merges_and_why():
    arm = labelled(industrial(), 3)
    cond = arm.plan_conditions(random_poses(arm, 30, np.random.default_rng(8)))
    notes = "\n".join(map(held_sentence, arm.prepared(cond).merges))
    assert "the zero of joint 1 (dq1) merges into the base rotation" in notes
    assert "joints 2 and 3 are parallel" in notes
    assert "the zero of joint 6 (dq6) merges into the positions of A, B and C" in notes


def test_a_joint_that_never_moves_is_named():
    arm = labelled(industrial(), 3)
    q = random_poses(arm, 30, np.random.default_rng(9))
    q[:, 3] = 0.2
    chosen = arm.prepared(arm.plan_conditions(q))
    assert chosen.n_free < 33
    said = map(held_sentence, chosen.merges)
    assert any("joint 4 does not move in these measurements" in s for s in said)


@pytest.mark.parametrize("name", ["industrial", "cobot", "seven"])
def test_noiseless_data_are_recovered_to_round_off(name):
    """The tracker 4 m away and turned by 120 degrees; no start given."""
    arm = labelled(ARMS[name](), 3)
    rng = np.random.default_rng(10)
    truth = random_truth(arm, rng)
    cond = arm.plan_conditions(random_poses(arm, 40, rng))
    points = arm.positions(cond, truth)
    cal = identify(arm, cond.q, points, target=cond.target)
    assert cal.model.n_free == 4 * arm.n_joints + 9
    held_out = arm.plan_conditions(random_poses(arm, 200, rng))
    error = cal.model.positions(held_out, cal.params) - arm.positions(held_out, truth)
    assert np.max(np.abs(error)) < 1e-9
    # A truth within the chosen set is recovered parameter by parameter.
    reduced = truth.copy()
    reduced[~cal.model.free] = cal.model.nominal[~cal.model.free]
    again = identify(cal.model, cond.q, cal.model.positions(cond, reduced), target=cond.target)
    np.testing.assert_allclose(again.params, reduced, rtol=0, atol=1e-9)


def test_noisy_estimates_lie_within_four_predicted_std():
    arm = labelled(industrial(), 3).with_noise(NoiseModel.isotropic(0.05, dim=3))
    rng = np.random.default_rng(11)
    truth = random_truth(arm, rng)
    cond = arm.plan_conditions(random_poses(arm, 60, rng))
    exact = identify(arm, cond.q, arm.positions(cond, truth), target=cond.target)
    noisy = arm.positions(cond, truth) + rng.normal(scale=0.05, size=(cond.m, 3))
    cal = identify(arm, cond.q, noisy, target=cond.target)
    free = cal.model.free
    z = (cal.params - exact.params)[free] / (cal.std[free] / cal.model.display_scale[free])
    assert np.max(np.abs(z)) < 4


@pytest.mark.parametrize("name", sorted(ARMS))
def test_the_instruments_columns_from_the_points_are_the_jacobians(name):
    """What registering the nominal arm fits (the base pose and the targets) is made from
    the points and the tip's rotation alone (no derivatives): equal to the Jacobian's
    columns to round-off, for one parameter set and a stack of them; None for columns of
    the robot's geometry, whose screws need the chain's derivatives."""
    from armcal.models.interface import columns_jacobian

    arm = labelled(ARMS[name](), 3)
    rng = np.random.default_rng(4)
    truth = random_truth(arm, rng)
    rows = arm.conditions(random_poses(arm, 60, rng), target=np.arange(60) % 3)
    instrument = np.asarray(arm.registration_params, dtype=bool)
    for params in (truth, np.stack([truth, random_truth(arm, rng)])):
        whole = arm.jacobian(rows, params)
        part = arm.columns_jacobian(rows, params, instrument)
        assert part is not None and part.shape == (*whole.shape[:-1], instrument.sum())
        # Round-off of points ~4 m out: 1e-15 of the largest column.
        assert np.max(np.abs(part - whole[..., instrument])) <= 1e-12 * np.max(np.abs(whole))
        generic = columns_jacobian(arm, rows, params, arm.free)
        assert np.array_equal(generic, whole[..., arm.free])
    assert arm.columns_jacobian(rows, truth, arm.free) is None


@pytest.mark.parametrize(
    ("name", "m"), [(n, 60) for n in sorted(ARMS)] + [("industrial", 4000), ("seven", 4000)]
)
def test_the_selection_pass_gives_the_nominal_triangle_and_the_first_step(name, m):
    """Preparing an arm for measured rows reduces its Jacobian with the base at the origin
    (the selection rule's frame), the registered arm's residuals beside it.  Where the
    whitening is the identity, the rank analysis and the covariance at nominal take their
    triangle from it, turned to the registered base, and Gauss-Newton its first step.  The
    Gram matrix and the step equal those made directly from the free columns at nominal,
    to round-off; the start is the registration the arm was prepared with."""
    from armcal.models.information import _row_triangle, known_start, whitened_triangle
    from armcal.numerics import RowTriangle

    arm = labelled(ARMS[name](), 3)
    rng = np.random.default_rng(7)
    truth = random_truth(arm, rng)
    rows = arm.plan_conditions(random_poses(arm, m // 3, rng))
    points = arm.positions(rows, truth) + rng.normal(scale=0.03, size=(rows.m, 3))
    prepared = arm.prepared(rows, points)
    assert prepared.whitening(rows, None) is None
    derived = whitened_triangle(prepared, rows).triangle()
    direct = _row_triangle(prepared, rows, None, True).triangle()
    gram, expected = derived.T @ derived, direct.T @ direct
    # Round-off of a Gram matrix of rows whose points lie ~4 m out: 1e-13 of its largest entry.
    assert np.max(np.abs(gram - expected)) <= 1e-13 * np.max(np.abs(expected))
    # The memo is the prepared arm's alone: the arm as given makes its own.
    assert whitened_triangle(arm, rows) is not whitened_triangle(prepared, rows)

    start = prepared.start(rows, points)[0]
    assert np.array_equal(start, prepared.nominal)
    found = known_start(prepared, rows, points)
    assert found is not None and np.array_equal(found[0], start)
    known = found[1]
    assert known_start(prepared, rows, points + 1e-9) is None  # other points: none
    made = RowTriangle(prepared.n_free)
    jac = prepared.jacobian(rows, start)[..., prepared.free]
    made.add(jac.reshape(-1, prepared.n_free), (points - prepared.positions(rows, start)).ravel())
    step, ok, _ = known.solve()
    reference, _, _ = made.solve()
    assert bool(ok)
    # The step (~the errors, 0.1-1 mm and mrad) to 1e-9 of itself: round-off of
    # residuals of ~1 mm over points ~4 m out, through cond(J) ~1e3.
    assert np.max(np.abs(step - reference)) <= 1e-9 * np.max(np.abs(reference))


def test_a_refit_leaves_the_triangle_at_its_result():
    """Expressing a truth in a prepared arm's parameters (a refit over more rows than a
    block) ends on a pass at its result: that pass's triangle is the covariance's there,
    to round-off, and serves it."""
    from armcal.models.information import _row_triangle, whitened_triangle
    from armcal.models.interface import ROW_BLOCK

    arm = labelled(industrial(), 3)
    rng = np.random.default_rng(8)
    truth = random_truth(arm, rng)
    rows = arm.plan_conditions(random_poses(arm, ROW_BLOCK // 3 + 500, rng))
    assert rows.m > ROW_BLOCK
    prepared = arm.prepared(rows, arm.positions(rows, truth))
    expressed = prepared.expressed(rows, truth)
    kept = whitened_triangle(prepared, rows, expressed)
    assert kept is whitened_triangle(prepared, rows, expressed.copy())  # by value, not identity
    derived, direct = kept.triangle(), _row_triangle(prepared, rows, expressed, True).triangle()
    gram, expected = derived.T @ derived, direct.T @ direct
    # Round-off of a Gram matrix of rows whose points lie ~4 m out: 1e-13 of its largest entry.
    assert np.max(np.abs(gram - expected)) <= 1e-13 * np.max(np.abs(expected))
    assert whitened_triangle(prepared, rows, truth) is not kept  # elsewhere: made anew


def test_a_plan_evaluated_on_its_prepared_rows_shares_their_triangle():
    """``evaluate`` prepares the arm on the plan's rows and evaluates the plan on the same
    rows: the rank analysis and the criteria take the triangle the preparation left (no
    pass of their own), and every figure is that of rows made anew, to round-off."""
    from armcal.criteria import evaluate_plan
    from armcal.models.information import whitened_triangle
    from armcal.models.interface import ROW_BLOCK

    arm = labelled(industrial(), 3)
    rng = np.random.default_rng(9)
    q = random_poses(arm, ROW_BLOCK // 3 + 200, rng)
    rows = arm.plan_conditions(q)
    prepared = arm.prepared(rows)
    made = whitened_triangle(prepared, rows)  # what preparing left
    shared = evaluate_plan(prepared, q, sigma=0.03, test_q=q[:40], rows=rows)
    assert shared.model is prepared and whitened_triangle(prepared, rows) is made
    fresh = evaluate_plan(prepared, q, sigma=0.03, test_q=q[:40])
    # Two factorizations of the same Gram matrix: 1e-12 relative (the figures' round-off).
    np.testing.assert_allclose(shared.predicted_std, fresh.predicted_std, rtol=1e-12)
    for name, value in fresh.efficiencies.items():
        assert abs(shared.efficiencies[name] - value) <= 1e-12 * abs(value)
