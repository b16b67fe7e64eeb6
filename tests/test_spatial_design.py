"""Designing plans for spatial arms: the information's analytic gradient in the poses.

The optimizer and the certificate climb per-pose quadratic forms of the
whitened Jacobian blocks; for spatial arms their gradient comes from the
Jacobian's derivative in the readings (the serial-chain Hessian: a joint before
a screw turns its column, a joint after it moves the point).  Both are checked
against central differences of step 1e-6 rad, whose error is about
``h^2 |f'''| + eps |f| / h``: 1e-12 x 1e4 mm and 1e-16 x 1e3 / 1e-6, so 1e-6
relative is a safe tolerance.
"""

from __future__ import annotations

import numpy as np
import pytest

from armcal.models.information import BlockInformation, pose_derivative
from armcal.models.spatial.gradient import jacobian_pose_pullback
from armcal.models.spatial.kinematics import kinematics
from armcal.noise import NoiseModel, TrackerNoise
from helpers import INDUSTRIAL_HEAD, central_differences
from helpers_spatial import ARMS, labelled, random_poses, random_truth


@pytest.mark.parametrize("name", sorted(ARMS))
def test_the_jacobian_s_pullback_in_the_readings_agrees_with_central_differences(name):
    """``<C, d J / d q>`` for a random cotangent ``C``, every column (base, placements,
    zeros, targets), against central differences of ``<C, J(q)>`` row by row."""
    arm = labelled(ARMS[name](), 2)  # the industrial arm's coupled J2/J3 included
    rng = np.random.default_rng(3)
    params = random_truth(arm, rng)
    q = random_poses(arm, 5, rng)
    target = np.array([0, 1, 0, 1, 1])
    weight = rng.normal(size=(5, 3, arm.n_params))

    def weighted(reading: np.ndarray) -> np.ndarray:
        found = kinematics(
            arm.chain, arm.joint_map, arm.layout, reading, target, params, derivatives=True
        )
        return np.einsum("mxp,mxp->m", weight, found.jacobian)

    kin = kinematics(arm.chain, arm.joint_map, arm.layout, q, target, params, derivatives=True)
    columns = np.arange(arm.n_params)
    found = jacobian_pose_pullback(kin, arm.layout, arm.joint_map, columns, weight)
    numeric = pose_derivative(weighted, q)
    np.testing.assert_allclose(found, numeric, rtol=0, atol=1e-6 * np.max(np.abs(numeric)))
    some = columns[::3]  # a subset of the columns, as the free set is
    found = jacobian_pose_pullback(kin, arm.layout, arm.joint_map, some, weight[..., some])
    weight[..., np.setdiff1d(columns, some)] = 0.0
    np.testing.assert_allclose(
        found, pose_derivative(weighted, q), rtol=0, atol=1e-6 * np.max(np.abs(numeric))
    )


@pytest.mark.parametrize(
    "noise",
    [
        NoiseModel.isotropic(0.03, dim=3),
        NoiseModel(np.diag([0.01, 0.02, 0.05]) ** 2),
        NoiseModel.laser_tracker(TrackerNoise(0.008, 0.0004, 0.010, 0.0025)),
        NoiseModel(np.diag([0.01, 0.02, 0.05]) ** 2, np.radians([0.002, 0.001, 0.003] * 2)),
        NoiseModel(
            np.eye(3), np.radians(0.002), tracker=TrackerNoise(0.008, 0.0004, 0.010, 0.0025)
        ),
    ],
    ids=["isotropic", "per-axis", "tracker", "encoder", "tracker-and-encoder"],
)
def test_the_plan_information_s_gradient_is_exact(noise):
    """A tracker's weights move with the point, encoder noise's with the joint Jacobian:
    the metric ``W^T W`` enters the derivative (noise module).  The tracker 3.4 m away,
    turned, as in a cell."""
    arm = labelled(ARMS["industrial"](), 3).with_noise(noise)
    arm = arm.replace(base_pose=np.array([3000.0, -1500.0, -600.0, 0.01, -0.02, 2.0]))
    rng = np.random.default_rng(4)
    model = arm.prepared(arm.plan_conditions(random_poses(arm, 40, rng)))
    q = random_poses(model, 30, rng).reshape(3, 10, model.n_joints)
    p = model.n_free
    phi = rng.normal(size=(3, p, p))
    phi = phi + np.swapaxes(phi, -1, -2)
    analytic = model.plan_information(q).gradient(phi)
    numeric = BlockInformation(model, q, unit_columns=True).gradient(phi)
    np.testing.assert_allclose(analytic, numeric, rtol=0, atol=1e-6 * np.max(np.abs(numeric)))
    m_inv = phi[0] @ phi[0].T
    value, slope = model.plan_information(q[0]).pose_variance(m_inv)
    again, numeric = BlockInformation(model, q[0], unit_columns=True).pose_variance(m_inv)
    np.testing.assert_array_equal(value, again)
    np.testing.assert_allclose(slope, numeric, rtol=0, atol=1e-6 * np.max(np.abs(numeric)))


def test_a_6_dof_instrument_s_turns_fall_back_to_central_differences():
    """The turns' rows go through the SO(3) chart of each row's frame: no closed form is
    claimed for their derivative in the poses."""
    noise = NoiseModel.isotropic(0.03, dim=3).with_orientation(np.radians(0.005))
    arm = labelled(ARMS["industrial"](), 1).replace(oriented=True).with_noise(noise)
    rows = arm.plan_conditions(random_poses(arm, 4, np.random.default_rng(5)))
    assert arm.linearize(rows).pullback is None


def test_design_for_a_six_axis_arm_from_the_command_line(tmp_path):
    """One target, 30 poses: the plan is within the limits, certified, and better on D than
    the best of 30 random plans within the limits (the comparison the issue asks for)."""
    import json

    from armcal.criteria import d_efficiency
    from armcal.doe import feasible_poses, random_plan
    from armcal.files import load_spatial_robot, read_plan
    from helpers import run_cli

    result = run_cli(
        tmp_path, "design", "--robot", "industrial-6r", "--poses", "30", "--json", "-o", "p.csv",
        "--plot", "p.png",
    )  # fmt: skip
    assert result.returncode == 0, result.stderr
    document = json.loads(result.stdout)
    arm = load_spatial_robot("industrial-6r").arm
    q = read_plan(tmp_path / "p.csv", arm)
    assert q.shape == (30, 6) and np.all(arm.feasible(q))
    model = arm.prepared(arm.plan_conditions(feasible_poses(arm, 200, rng=0)))
    assert model.n_free == 27  # 4R + 3 (one point)
    found = float(d_efficiency(model, q))
    assert found == pytest.approx(document["d_efficiency"], rel=1e-9)
    best = max(float(d_efficiency(model, random_plan(model, 30, rng=s))) for s in range(30))
    assert found > best
    assert 0.9 <= document["certified_d_efficiency"] <= 1.0
    # det M against the certificate's best weighted design, as the report's first figure;
    # with the variance function's maximum it is the Kiefer-Wolfowitz bound.
    log_det = np.linalg.slogdet(model.plan_information(q).information())[1]
    against = np.exp(log_det / 27) / document["best_weighted_design_d_efficiency"]
    assert document["d_efficiency_vs_best_weighted_design"] == pytest.approx(against, rel=1e-9)
    kiefer_wolfowitz = against * np.exp(1 - document["max_variance"] / 27)
    assert document["certified_d_efficiency"] >= kiefer_wolfowitz * (1 - 1e-12)
    assert (tmp_path / "p.png").stat().st_size > 10_000  # the plan's four panels


@pytest.mark.slow
@pytest.mark.parametrize("m", [40, 60, 100])
def test_certificates_with_three_reflectors_never_overclaim(m):
    """The issue's case: the built-in 6R industrial arm within its limits, 3 reflectors.
    At m >= 3p (p = 33: 4R + 3k) the plan is certified within 0.95 of the best plan, and
    a dense random search of 10^5 feasible poses finds no pose whose variance exceeds the
    maximum the bound rests on (Kiefer-Wolfowitz: the bound needs max_x d(x, xi*))."""
    from armcal.criteria import d_efficiency
    from armcal.doe import design, feasible_poses, random_plan
    from armcal.files import load_spatial_robot

    arm = load_spatial_robot("industrial-6r").arm.replace(
        targets=("A", "B", "C"),
        target_positions=np.array([[100.0, 0, 150], [-50, 87, 150], [-50, -87, 150]]),
        known_targets=True,
    )
    arm = arm.with_noise(NoiseModel.isotropic(0.03, dim=3))
    model = arm.prepared(arm.plan_conditions(feasible_poses(arm, 200, rng=0)))
    p = model.n_free
    assert p == 33
    made = design(model, m, rng=1)
    assert np.all(model.feasible(made.q))
    certificate = made.certificate
    assert certificate is not None
    if m >= 3 * p:
        assert certificate.certified_d_efficiency >= 0.95
    blocks = model.plan_information(certificate.support).blocks() / np.sqrt(3)
    information = np.einsum("k,krp,krq->pq", certificate.weights, blocks, blocks)
    inverse = np.linalg.inv(information)
    largest = 0.0
    for chunk in np.array_split(feasible_poses(model, 100_000, rng=9), 20):
        variance, _ = model.plan_information(chunk).pose_variance(inverse)
        largest = max(largest, float(variance.max()))
    assert largest <= certificate.max_variance * (1 + 1e-9)
    at, _ = model.plan_information(certificate.max_pose[None, :]).pose_variance(inverse)
    assert at[0] == pytest.approx(certificate.max_variance, rel=1e-6)  # where it lies
    best = max(float(d_efficiency(model, random_plan(model, m, rng=s))) for s in range(30))
    assert made.d_efficiency > best


def _three_reflectors():
    from armcal.doe import feasible_poses
    from armcal.files import load_spatial_robot

    arm = load_spatial_robot("industrial-6r").arm.replace(
        targets=("A", "B", "C"),
        target_positions=np.array([[100.0, 0, 150], [-50, 87, 150], [-50, -87, 150]]),
        known_targets=True,
    )
    arm = arm.with_noise(NoiseModel.isotropic(0.03, dim=3))
    return arm.prepared(arm.plan_conditions(feasible_poses(arm, 200, rng=0)))


@pytest.mark.slow
def test_an_i_optimal_plan_aimed_at_a_program_beats_the_d_optimal_plan_there():
    """A program in one corner of the workspace (joints within 0.25 rad of one pose): the
    I-optimal plan predicts a lower error there than the D-optimal plan of the same size,
    and a Monte Carlo of 2000 trials agrees with its prediction within 5 % (the empirical
    covariance's position RMS; its relative standard error is about 1/sqrt(2 N), 1.6 %)."""
    from armcal.criteria import position_accuracy
    from armcal.doe import design
    from armcal.models import position_jacobian
    from armcal.models.information import tip_variances
    from armcal.simulate import monte_carlo

    model = _three_reflectors()
    rng = np.random.default_rng(5)
    program = np.array([0.3, 0.2, -0.3, 0.5, 0.8, 0.0]) + rng.uniform(-0.25, 0.25, (30, 6))
    plans = {
        c: design(model, 40, criterion=c, rng=1, test_q=program, with_certificate=False)
        for c in ("D", "I")
    }
    accuracy = {c: position_accuracy(model, made.q, program, 0.03) for c, made in plans.items()}
    assert accuracy["I"].rms_mm < accuracy["D"].rms_mm
    q = plans["I"].q
    result = monte_carlo(model, q, model.nominal, None, trials=2000, rng=6)
    test = model.plan_conditions(program)
    jac = position_jacobian(model, test)
    empirical = np.sqrt(np.mean(tip_variances(jac, result.covariance)))
    assert empirical == pytest.approx(accuracy["I"].rms_mm, rel=0.05)


def test_the_task_criteria_need_test_poses_and_position_data():
    from armcal.doe import design, task_criterion
    from armcal.errors import ArmcalError

    model = _three_reflectors()
    with pytest.raises(ArmcalError, match="test poses"):
        design(model, 20, criterion="I", with_certificate=False)
    oriented = labelled(ARMS["industrial"](), 1).replace(oriented=True)
    with pytest.raises(ArmcalError, match="6-DoF"):
        task_criterion("G", oriented, np.zeros((3, 6)))


@pytest.mark.parametrize("name", ["I", "G"])
def test_the_task_criteria_s_gradients_in_the_information(name):
    """I's log-efficiency gradient exactly; G's is that of the smooth maximum the
    optimizer climbs, ``-(1/beta) log sum exp(beta log v_t)``."""
    from armcal.doe import task_criterion
    from armcal.doe.task import SMOOTH_MAX_BETA

    model = _three_reflectors()
    rng = np.random.default_rng(7)
    program = random_poses(model, 12, rng)
    criterion = task_criterion(name, model, program)
    # A well-conditioned information (the gradient's formula holds for any): a plan's Fs
    # in mm and rad has a condition number near 1e10, and differences of it lose digits.
    a = rng.normal(size=(model.n_free, model.n_free))
    fs = a @ a.T + model.n_free * np.eye(model.n_free)
    blocks = model.with_noise(None).plan_information(program).blocks().reshape(-1, 3, model.n_free)

    def objective(matrix: np.ndarray) -> float:
        if name == "I":
            return np.log(criterion.efficiency(matrix))
        inv = np.linalg.inv(matrix)
        v = np.einsum(
            "pq,tq,tp->t", inv, blocks.reshape(-1, model.n_free), blocks.reshape(-1, model.n_free)
        )
        v = v.reshape(-1, 3).sum(axis=1)
        return -np.log(np.sum(np.exp(SMOOTH_MAX_BETA * np.log(v)))) / SMOOTH_MAX_BETA

    # Directional derivatives along symmetric directions E = L S L^T (Fs = L L^T), which
    # keep Fs + h E positive definite and probe every scale of its eigenvalues.
    lower = np.linalg.cholesky(fs)
    analytic = criterion.log_gradient(fs)
    for _ in range(5):
        s = rng.normal(size=fs.shape)
        direction = lower @ ((s + s.T) / 2) @ lower.T
        h = 1e-5  # truncation h^2 ~ 1e-10, round-off eps / h ~ 1e-11 (times the scales)
        numeric = (objective(fs + h * direction) - objective(fs - h * direction)) / (2 * h)
        assert np.sum(analytic * direction) == pytest.approx(numeric, rel=1e-7, abs=1e-10)


CELL = """[measurement]
sigma_mm = 0.03
[instrument]
position_mm = [3500.0, 0.0, 800.0]
{volume}
acceptance_deg = 30.0
floor_z_mm = 100.0
[targets]
A = {{ xyz_mm = [100.0, 0.0, 150.0], normal = [0.3, 0.0, 1.0] }}
B = {{ xyz_mm = [-50.0, 87.0, 150.0], normal = [-0.15, 0.26, 1.0] }}
C = {{ xyz_mm = [-50.0, -87.0, 150.0], normal = [-0.15, -0.26, 1.0] }}
"""

#: A tracker's range, or a box that a camera sees (both in the robot's base frame).
VOLUMES = {
    "range": "range_mm = [1000.0, 6000.0]",
    "box": "box_mm = [[-500.0, 2500.0], [-2000.0, 2000.0], [0.0, 2500.0]]",
}


def _cell(tmp_path, volume: str = "range"):
    from armcal.files import load_spatial_robot
    from armcal.files.spatial import ROBOT_FOLDER

    urdf = (ROBOT_FOLDER / "industrial-6r.urdf").as_posix()
    path = tmp_path / "cell.toml"
    head = INDUSTRIAL_HEAD.format(name="cell-6r", urdf=urdf)
    path.write_text(head + CELL.format(volume=VOLUMES[volume]), encoding="utf-8")
    return load_spatial_robot(path).arm


@pytest.mark.parametrize("volume", sorted(VOLUMES))
def test_the_view_s_constraints_have_exact_gradients(tmp_path, volume):
    arm = _cell(tmp_path, volume)
    q = random_poses(arm, 5, np.random.default_rng(8))
    g, dg = arm.view_constraints(q)
    # Per reflector: the volume (2 for a range, 6 for a box), acceptance, the floor for it
    # and for the flange.
    assert g.shape == (5, 3 * ((2 if volume == "range" else 6) + 3))
    numeric = central_differences(lambda x: arm.view_constraints(x.reshape(q.shape))[0], q.ravel())
    every = np.arange(5)
    own = numeric.reshape(5, g.shape[1], 5, 6)[every, :, every, :]
    np.testing.assert_allclose(dg, own, rtol=0, atol=1e-6 * np.max(np.abs(own)))


def test_the_view_s_constraints_say_what_they_check(tmp_path):
    """One pose's values by hand: the distance to the tracker, the normal's angle to it
    and the height above the floor (the constraints' definitions, module notes)."""
    from armcal.models.spatial.view import ACCEPTANCE_SCALE_MM

    arm = _cell(tmp_path)
    q = random_poses(arm, 1, np.random.default_rng(9))
    rows = arm.plan_conditions(q)
    params = arm.in_robot_frame(arm.nominal)[1]
    points = arm.positions(rows, params)  # the three reflectors, robot frame
    tip = arm.tip_rotation(rows, params)
    g, _ = arm.view_constraints(q)
    view = arm.view
    per_target = g[0].reshape(3, 5)  # range (2), acceptance, floor, the flange's floor
    distance = np.linalg.norm(points - view.position, axis=1)
    low, high = view.range_mm
    np.testing.assert_allclose(per_target[:, 0], (high**2 - distance**2) / (2 * high))
    np.testing.assert_allclose(per_target[:, 1], (distance**2 - low**2) / (2 * high))
    normals = np.einsum("tij,tj->ti", tip, view.normals)
    cosine = np.sum(normals * (view.position - points), axis=1) / distance
    np.testing.assert_allclose(
        per_target[:, 2], ACCEPTANCE_SCALE_MM * (cosine - np.cos(np.radians(30.0)))
    )
    np.testing.assert_allclose(per_target[:, 3], points[:, 2] - 100.0)
    flange = arm.positions(rows, np.where(arm.layout.instrument, 0.0, params))
    np.testing.assert_allclose(per_target[:, 4], flange[:, 2] - 100.0)


@pytest.mark.slow
@pytest.mark.parametrize("volume", sorted(VOLUMES))
def test_a_constrained_design_keeps_every_pose_inside_every_constraint(tmp_path, volume):
    """Limits, the tracker's range or a measuring box, the reflectors' 30 degree acceptance
    and the floor: random poses within the limits satisfy them about 1.5 % of the time.
    The optimum presses against the constraints: some pose has one active (within 1 mm),
    and a box's faces (which about 22 % of the poses within the limits leave) are among
    them."""
    from armcal.criteria import d_efficiency
    from armcal.doe import design, feasible_poses

    arm = _cell(tmp_path, volume)
    model = arm.prepared(arm.plan_conditions(feasible_poses(arm, 200, rng=0)))
    made = design(model, 30, rng=1)
    assert np.all(model.within_limits(made.q))
    g, _ = model.view_constraints(made.q)
    assert np.min(g) >= 0.0
    assert np.min(g) < 1.0
    if volume == "box":  # the box itself binds: a fifth of the poses within limits leave it
        assert np.min(g.reshape(30, 3, -1)[..., :6]) < 1.0
    best = max(float(d_efficiency(model, feasible_poses(model, 30, rng=s))) for s in range(30))
    assert made.d_efficiency > best
    certificate = made.certificate
    assert certificate is not None and certificate.certified_d_efficiency > 0.9
    # Never overclaims against a dense search of the view (its maxima lie on its edges: a
    # penalized ascent's polish fell short of them, and a tracker's range was certified
    # 0.9826 where 20 000 poses bound it by 0.9787).
    blocks = made.model.plan_information(certificate.support).blocks() / np.sqrt(3)
    inverse = np.linalg.inv(np.einsum("k,krp,krq->pq", certificate.weights, blocks, blocks))
    largest = 0.0
    for chunk in np.array_split(feasible_poses(made.model, 20_000, rng=9), 20):
        variance, _ = made.model.plan_information(chunk).pose_variance(inverse)
        largest = max(largest, float(variance.max()))
    assert largest <= certificate.max_variance * (1 + 1e-6)


def test_a_pool_plan_takes_every_pose_from_the_pool_and_beats_the_pool_method():
    """The open tools' pool method (continuous D-optimal weights, the largest kept) is
    where the exchange starts, and DETMAX never lowers det M: at equal m it is at least
    as good."""
    from armcal.doe import feasible_poses
    from armcal.doe.pool import pool_plan, pool_weights_plan

    model = _three_reflectors()
    pool = feasible_poses(model, 800, rng=3)
    for m in (15, 30):
        baseline = pool_weights_plan(model, m, pool)
        ours = pool_plan(model, m, pool)
        assert ours.shape == (m,) and np.all((ours >= 0) & (ours < len(pool)))
        # On det M, what both maximize and the certificate bounds (d_efficiency of a spatial
        # arm normalizes each plan's columns: how orthogonal they are).
        ours_det = np.linalg.slogdet(model.plan_information(pool[ours]).information())[1]
        base_det = np.linalg.slogdet(model.plan_information(pool[baseline]).information())[1]
        assert ours_det >= base_det - 1e-9


@pytest.mark.slow
def test_design_with_candidates_keeps_to_the_pool(tmp_path):
    from armcal.doe import design, feasible_poses

    model = _three_reflectors()
    pool = feasible_poses(model, 1500, rng=3)
    made = design(model, 40, candidates=pool, rng=1)
    assert made.method == "pool"
    assert np.all(np.any(np.all(pool[:, None, :] == made.q[None], axis=-1), axis=0))
    assert made.certificate is not None and made.certificate.certified_d_efficiency > 0.9


def test_a_spatial_plan_s_picture_is_written(tmp_path):
    """design --plot draws the four panels of a spatial plan; the variance function's
    largest value at the random poses stays at or below the certificate's maximum."""
    from armcal.doe import certify, feasible_poses, random_plan
    from armcal.plotting import save_figure
    from armcal.plotting_spatial import plot_spatial_plan

    arm = labelled(ARMS["industrial"](), 1).with_noise(NoiseModel.isotropic(0.03, dim=3))
    model = arm.prepared(arm.plan_conditions(feasible_poses(arm, 100, rng=0)))
    q = random_plan(model, 20, rng=1)
    certificate = certify(model, q, rng=2, candidates=300, rounds=1, search=500)
    figure = plot_spatial_plan(model, q, sigma=0.03, certificate=certificate)
    assert len(figure.axes) >= 4
    variance = figure.axes[-1].lines[0].get_ydata()
    assert np.max(variance) <= certificate.max_variance * (1 + 1e-9)
    save_figure(figure, tmp_path / "plan.png")
    assert (tmp_path / "plan.png").stat().st_size > 10_000
    # The arm panel: every flange numbered by its row, where the chain puts it (the
    # flange frame's origin, from the URDF's own product of origins and joint motions,
    # SerialChain.forward), on axes of equal scale.
    sticks = figure.axes[0]
    flanges = model.arm.chain.forward(q @ model.arm.joint_map.T)[:, :3, 3]
    labels = {int(t.get_text()): t.get_position_3d() for t in sticks.texts}
    assert sorted(labels) == list(range(1, q.shape[0] + 1))
    for k, place in labels.items():
        np.testing.assert_allclose(place, flanges[k - 1], rtol=0, atol=1e-6)
    spans = np.array(
        [np.ptp(sticks.get_xlim()), np.ptp(sticks.get_ylim()), np.ptp(sticks.get_zlim())]
    )
    aspect = np.asarray(sticks.get_box_aspect())
    np.testing.assert_allclose(aspect / aspect.max(), spans / spans.max(), rtol=1e-9)


def test_a_plan_close_enough_to_the_optimum_is_its_own_reference(monkeypatch):
    """When the plan's own variance function certifies CLOSE_ENOUGH, the plan is the
    certificate's design: its distinct poses weighted by their counts, the bound
    ``exp(1 - max d / p)``, and a dense random search finds no pose above that max.
    (The threshold is lowered to 0.5 so that a short 20-pose plan takes this branch.)"""
    from armcal.doe import certificate, feasible_poses, optimize_plan

    arm = labelled(ARMS["industrial"](), 1).with_noise(NoiseModel.isotropic(0.03, dim=3))
    model = arm.prepared(arm.plan_conditions(random_poses(arm, 60, np.random.default_rng(6))))
    plan = optimize_plan(model, 20, rng=1)
    q = np.concatenate([plan, plan[:5]])  # 5 poses measured twice
    monkeypatch.setattr(certificate, "CLOSE_ENOUGH", 0.5)
    found = certificate.certify(model, q, rng=2)
    p = model.n_free
    assert found.support.shape == (20, model.n_joints)
    counts = np.array([np.sum(np.all(q == pose, axis=1)) for pose in found.support])
    np.testing.assert_array_equal(found.weights, counts / 25)
    assert found.certified_d_efficiency == pytest.approx(np.exp(1 - found.max_variance / p))
    inverse = np.linalg.inv(model.plan_information(q).information())
    variance, _ = model.plan_information(feasible_poses(model, 20_000, rng=3)).pose_variance(
        inverse
    )
    assert variance.max() <= found.max_variance * (1 + 1e-9)
    at, _ = model.plan_information(found.max_pose[None, :]).pose_variance(inverse)
    assert at[0] == pytest.approx(found.max_variance, rel=1e-9)
