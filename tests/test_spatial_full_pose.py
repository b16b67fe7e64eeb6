"""Full-pose measurements of spatial arms: a 6-DoF instrument (a tracker's probe).

Every constant is derived or cited:

* the orientation residual is the turn ``rotvec(R_meas R_pred^T)``; its
  Jacobian ``J_l(phi)^-1 w`` uses SO(3)'s left Jacobian, checked here against
  central differences and against its inverse;
* the identifiable count for a full pose is Everett, Driels and Mooring's
  ``4R + 2P + 6`` (Everett, Driels, Mooring, "Kinematic modelling for robot
  calibration", ICRA 1987), plus 6 for every further target measured in full
  pose: ``4R + 2P + 6k``;
* Monte Carlo: the empirical std of N trials has a relative standard error of
  ``1 / sqrt(2 (N - 1))``, 1.6 % at 2000 trials, so the contract's 5 % is
  three standard errors.
"""

from __future__ import annotations

import json

import numpy as np
import pytest

from armcal.files import format_measurements_csv, read_measurements
from armcal.identification import identify
from armcal.models import SpatialArm
from armcal.models.spatial.chain import (
    left_jacobian,
    left_jacobian_inverse,
    rotation_vector,
    vector_rotation,
)
from armcal.models.wording import held_sentence
from armcal.noise import NoiseModel
from armcal.simulate import monte_carlo
from helpers import INDUSTRIAL_HEAD, central_differences, run_cli, write_cycles
from helpers_spatial import ARMS, labelled, plan_file, random_poses, random_truth

DEG = np.pi / 180
SIGMA_MM, SIGMA_DEG = 0.02, 0.005


def oriented(name: str, k: int) -> SpatialArm:
    """A built-in test arm with ``k`` targets measured in full pose."""
    noise = NoiseModel.isotropic(SIGMA_MM, dim=3).with_orientation(SIGMA_DEG * DEG)
    return labelled(ARMS[name](), k).replace(oriented=True).with_noise(noise)


def oriented_truth(arm: SpatialArm, rng: np.random.Generator) -> np.ndarray:
    """The errors of :func:`random_truth` (tracker 4 m away, turned by 120 degrees), and
    targets turned on the flange by up to a half turn; the first one square to it (a
    pitch of 90 degrees, where roll, pitch and yaw are singular)."""
    plain = labelled(ARMS[arm.name](), len(arm.targets))
    base = random_truth(plain, rng)
    lay = arm.layout
    out = arm.nominal.copy()
    out[: lay.target_start] = base[: lay.target_start]
    k = len(arm.targets)
    turns = rng.uniform(-1.5, 1.5, (k, 3))
    turns[0] = [0.0, np.pi / 2, 0.0]
    positions = base[lay.target_start :].reshape(k, 3)
    out[lay.target_start :] = np.concatenate([positions, turns], axis=1).ravel()
    return out


def measured(arm: SpatialArm, q: np.ndarray, truth: np.ndarray):
    """Rows measuring every target, and their points as the instrument gives them."""
    rows = arm.plan_conditions(q).with_frames(None)
    return rows, arm.positions(rows, truth)


def test_the_left_jacobian_and_its_inverse():
    rng = np.random.default_rng(0)
    # Small angles use series, larger ones the closed forms; near a half turn too.
    v = rng.normal(size=(40, 3)) * np.repeat([1e-6, 1e-3, 0.5, 2.0, 3.1], 8)[:, None]
    product = left_jacobian_inverse(v) @ left_jacobian(v)
    np.testing.assert_allclose(product, np.broadcast_to(np.eye(3), product.shape), atol=1e-12)
    for vector in v[8:]:  # exp(v + dv) = exp(J_l dv) exp(v) to first order
        back = vector_rotation(vector).T
        numeric = central_differences(
            lambda u, back=back: rotation_vector(vector_rotation(u) @ back), vector
        )
        np.testing.assert_allclose(left_jacobian(vector), numeric, atol=1e-8)


@pytest.mark.parametrize("name", sorted(ARMS))
def test_the_full_pose_jacobians_agree_with_central_differences(name):
    arm = oriented(name, 2)
    rng = np.random.default_rng(1)
    params = oriented_truth(arm, rng)
    rows, points = measured(arm, random_poses(arm, 6, rng), params)
    # About measured frames a little off the prediction, as in a fit.
    turned = points.copy()
    turned[:, 3:] = rotation_vector(
        vector_rotation(rng.normal(scale=0.01, size=(rows.m, 3))) @ vector_rotation(points[:, 3:])
    )
    rows, _ = arm.anchor(rows, turned)
    jac = arm.jacobian(rows, params)
    assert jac.shape == (rows.m, 6, arm.n_params)
    # Errors: h^2 |p'''| (1e-12 x 1e4 mm, 1e-12 rad) and round-off 1e-16 x 4e3 / h (h = 1e-6).
    numeric = central_differences(lambda p: arm.positions(rows, p), params)
    np.testing.assert_allclose(jac[:, :3], numeric[:, :3], rtol=0, atol=1e-5)
    np.testing.assert_allclose(jac[:, 3:], numeric[:, 3:], rtol=0, atol=1e-8)

    def at(q: np.ndarray) -> np.ndarray:
        moved = arm.conditions(q.reshape(rows.q.shape), target=rows.target)
        return arm.positions(moved.with_frames(rows.frames), params)

    numeric = central_differences(at, rows.q.ravel())  # (m, 6, m n): each row its own
    every = np.arange(rows.m)
    blocks = numeric.reshape(rows.m, 6, rows.m, arm.n_joints)[every, :, every]
    np.testing.assert_allclose(arm.joint_jacobian(rows, params), blocks, rtol=0, atol=1e-5)


@pytest.mark.parametrize("name", sorted(ARMS))
@pytest.mark.parametrize("k", [1, 2, 3])
def test_the_identifiable_count_is_4r_plus_2p_plus_6k(name, k):
    arm = oriented(name, k)
    rng = np.random.default_rng(6)
    rows, points = measured(arm, random_poses(arm, 30, rng), oriented_truth(arm, rng))
    rows, points = arm.anchor(rows, points)
    chosen = arm.prepared(rows, points)
    revolute = int(np.sum(arm.chain.revolute))
    prismatic = arm.n_joints - revolute
    assert chosen.n_free == 4 * revolute + 2 * prismatic + 6 * k
    assert chosen.check_identifiable(rows).identifiable
    assert any(f"dq{arm.n_joints}" in s and "pose" in s for s in map(held_sentence, chosen.merges))


@pytest.mark.parametrize("name", ["industrial", "cobot", "seven"])
def test_noiseless_full_poses_are_recovered_to_round_off(name):
    """The tracker 4 m away, turned by 120 degrees; no start given."""
    arm = oriented(name, 2)
    rng = np.random.default_rng(10)
    truth = oriented_truth(arm, rng)
    rows, points = measured(arm, random_poses(arm, 40, rng), truth)
    cal = identify(arm, rows.q, points, target=rows.target)
    assert cal.model.n_free == 4 * arm.n_joints + 12
    held, exact = measured(arm, random_poses(arm, 200, rng), truth)
    found = cal.model.positions(held, cal.params)
    assert np.max(np.abs(found[:, :3] - exact[:, :3])) < 1e-9
    turn = rotation_vector(
        vector_rotation(found[:, 3:]) @ np.swapaxes(vector_rotation(exact[:, 3:]), -1, -2)
    )
    assert np.max(np.abs(turn)) < 1e-12
    assert cal.residual_rms < 1e-9 and cal.orientation_residual_rms_deg < 1e-10


def test_noisy_full_pose_estimates_lie_within_four_predicted_std():
    arm = oriented("industrial", 1)
    rng = np.random.default_rng(11)
    truth = oriented_truth(arm, rng)
    rows, points = measured(arm, random_poses(arm, 60, rng), truth)
    exact = identify(arm, rows.q, points)
    noisy = points.copy()
    noisy[:, :3] += rng.normal(scale=SIGMA_MM, size=(rows.m, 3))
    noisy[:, 3:] = rotation_vector(  # the instrument's turn about the true orientation
        vector_rotation(rng.normal(scale=SIGMA_DEG * DEG, size=(rows.m, 3)))
        @ vector_rotation(points[:, 3:])
    )
    cal = identify(arm, rows.q, noisy)
    free = cal.model.free
    z = (cal.params - exact.params)[free] / (cal.std[free] / cal.model.display_scale[free])
    assert np.max(np.abs(z)) < 4
    assert cal.goodness_of_fit is not None and cal.goodness_of_fit.consistent


def test_monte_carlo_agrees_with_the_predicted_std():
    arm = oriented("industrial", 1)
    rng = np.random.default_rng(12)
    truth = oriented_truth(arm, rng)
    q = random_poses(arm, 40, rng)
    rows, points = measured(arm, q, truth)
    model = arm.prepared(*arm.anchor(rows, points))
    result = monte_carlo(
        model, q, model.expressed(model.plan_conditions(q), truth), None, trials=2000, rng=13
    )
    free = model.free
    ratio = np.sqrt(np.diag(result.covariance)[free] / np.diag(result.predicted_covariance)[free])
    assert np.all(np.abs(ratio - 1) < 0.05), ratio


def test_whitening_weighs_orientations_by_their_noise():
    noise = NoiseModel.isotropic(0.02, dim=3).with_orientation(0.001)
    w = noise.whitening((4,), oriented=True)
    # W^T W = sigma_ref^2 Sigma^-1 with Sigma = diag(0.02^2 I, 0.001^2 I).
    expected = np.diag([1.0, 1.0, 1.0, 20.0, 20.0, 20.0])
    np.testing.assert_allclose(w, np.broadcast_to(expected, (4, 6, 6)), rtol=1e-12, atol=1e-12)
    with pytest.raises(ValueError, match="orientation_sigma_deg"):
        NoiseModel.isotropic(0.02, dim=3).whitening((4,), oriented=True)


def test_orientation_columns_round_trip_through_a_file(tmp_path):
    from armcal.files import load_spatial_robot

    arm = load_spatial_robot("industrial-6r").arm
    rng = np.random.default_rng(14)
    q = random_poses(arm, 9, rng)
    points = np.column_stack([rng.uniform(-1e3, 1e3, (9, 3)), rng.uniform(-1.8, 1.8, (9, 3))])
    (tmp_path / "m.csv").write_text(format_measurements_csv(q, points), encoding="utf-8")
    meas = read_measurements(tmp_path / "m.csv", arm)
    np.testing.assert_allclose(meas.instrument_points, points, rtol=0, atol=1e-12)


ROBOT = """[measurement]
sigma_mm = {sigma_mm}
orientation_sigma_deg = {sigma_deg}
"""


def test_a_six_dof_campaign_from_the_command_line(tmp_path):
    """synthesize -> identify --cross-validate -> validate -> export -> identify again."""
    from armcal.files import load_spatial_robot
    from armcal.files.spatial import ROBOT_FOLDER

    urdf = (ROBOT_FOLDER / "industrial-6r.urdf").as_posix()
    (tmp_path / "cell.toml").write_text(
        INDUSTRIAL_HEAD.format(name="probe-6r", urdf=urdf)
        + ROBOT.format(sigma_mm=SIGMA_MM, sigma_deg=SIGMA_DEG),
        encoding="utf-8",
    )
    truth = (ROBOT_FOLDER / "industrial-6r-truth.toml").read_text(encoding="utf-8")
    truth = "\n".join(line for line in truth.splitlines() if not line.startswith("robot"))
    (tmp_path / "truth.toml").write_text('robot = "cell.toml"\n' + truth, encoding="utf-8")
    arm = load_spatial_robot(tmp_path / "cell.toml").arm
    assert arm.oriented
    plan_file(tmp_path, tmp_path / "cell.toml", 60, 1)
    plan_file(tmp_path, tmp_path / "cell.toml", 40, 2, name="test.csv")
    for plan, out, seed in (("plan.csv", "meas.csv", "1"), ("test.csv", "held.csv", "2")):
        result = run_cli(
            tmp_path, "synthesize", "--robot", "cell.toml", "--truth", "truth.toml", "--plan",
            plan, "--seed", seed, "-o", out,
        )  # fmt: skip
        assert result.returncode == 0, result.stderr
    assert "rx_deg,ry_deg,rz_deg" in (tmp_path / "meas.csv").read_text(encoding="utf-8")
    result = run_cli(
        tmp_path, "identify", "--robot", "cell.toml", "--measurements", "meas.csv",
        "--cross-validate", "5", "-o", "cal.json", "--json",
    )  # fmt: skip
    assert result.returncode == 0, result.stderr
    document = json.loads(result.stdout)
    free = [p for p in document["parameters"] if not p["fixed"]]
    assert len(free) == 4 * 6 + 6
    assert 0.5 * SIGMA_DEG < document["orientation_residual_rms_per_axis_deg"] < 1.5 * SIGMA_DEG
    assert document["warnings"] == []
    result = run_cli(
        tmp_path, "validate", "--calibration", "cal.json", "--measurements", "held.csv", "--json"
    )
    assert result.returncode == 0, result.stderr
    check = json.loads(result.stdout)
    assert check["orientation_rms_after_deg"] < 0.1 * check["orientation_rms_before_deg"]
    assert check["warnings"] == []
    # ISO 9283 with the probe: 5 poses x 12 cycles; RP_a..c = 3 S of the attained turns,
    # whose std per axis is the probe's (15 values, each with a relative error of about
    # 1 / sqrt(2 x 11) = 21 %: their mean within 20 %).
    cell = load_spatial_robot(tmp_path / "cell.toml").arm
    poses = random_poses(cell, 5, np.random.default_rng(15))
    write_cycles(tmp_path / "cycles.csv", poses, 12)
    result = run_cli(
        tmp_path, "synthesize", "--robot", "cell.toml", "--truth", "truth.toml", "--plan",
        "cycles.csv", "--seed", "3", "-o", "iso.csv",
    )  # fmt: skip
    assert result.returncode == 0, result.stderr
    result = run_cli(
        tmp_path, "validate", "--calibration", "cal.json", "--measurements", "iso.csv",
        "--iso9283", "--json",
    )  # fmt: skip
    assert result.returncode == 0, result.stderr
    iso = json.loads(result.stdout)["iso9283"]
    spread = np.array([p["rp_abc_deg"] for p in iso["per_pose"]])
    assert np.mean(spread) == pytest.approx(3 * SIGMA_DEG, rel=0.2)
    after = np.abs([p["ap_after_abc_deg"] for p in iso["per_pose"]])
    before = np.abs([p["ap_before_abc_deg"] for p in iso["per_pose"]])
    assert np.max(after) < 0.2 * np.max(before)
    result = run_cli(tmp_path, "export", "--calibration", "cal.json", "--robot-toml", "cal.toml")
    assert result.returncode == 0, result.stderr
    result = run_cli(
        tmp_path, "identify", "--robot", "cal.toml", "--measurements", "meas.csv", "--json"
    )
    assert result.returncode == 0, result.stderr
    again = json.loads(result.stdout)
    for entry in again["parameters"]:  # the robot's corrections: zero within their std
        robot = not entry["name"].startswith(("base.", "tool."))
        if robot and not entry["fixed"]:
            assert abs(entry["value"]) < entry["std"], entry


def test_a_probe_that_moved_on_the_flange_is_caught_by_cross_validation():
    """Half the campaign with the probe turned by 0.05 deg (ten times its noise) about x:
    the positions barely move, the orientations are predicted far worse than promised."""
    from armcal.validation import cross_validate, cross_validation_warning

    arm = oriented("industrial", 1)
    rng = np.random.default_rng(15)
    truth = oriented_truth(arm, rng)
    rows, points = measured(arm, random_poses(arm, 60, rng), truth)
    noisy = points.copy()
    noisy[:, :3] += rng.normal(scale=SIGMA_MM, size=(rows.m, 3))
    slip = np.where(np.arange(rows.m)[:, None] >= rows.m // 2, [0.05 * DEG, 0.0, 0.0], 0.0)
    turn = rng.normal(scale=SIGMA_DEG * DEG, size=(rows.m, 3))
    # The slip is in the probe's own frame: R = R_true exp(slip), then the instrument's noise.
    noisy[:, 3:] = rotation_vector(
        vector_rotation(turn) @ vector_rotation(points[:, 3:]) @ vector_rotation(slip)
    )
    checked = cross_validate(arm, rows.q, noisy, 5, rng=16)
    warning = cross_validation_warning(checked)
    assert warning is not None and "orientation RMS" in warning.message
    summary = checked.summary()
    assert summary["orientation_rms_deg"] > 2 * summary["predicted_orientation_rms_deg"]


def test_validation_s_predictions_are_the_same_in_chunks(monkeypatch):
    """validate predicts held-out errors a chunk of rows at a time (memory flat in the
    rows): chunks of 7 rows give what one pass gives, positions and turns alike."""
    import armcal.validation as validation
    from armcal.models import CalibratedArm

    rng = np.random.default_rng(17)
    full = oriented("industrial", 2)
    arm = full.prepared(full.plan_conditions(random_poses(full, 30, rng)))
    factor = rng.normal(size=(arm.n_params, arm.n_params)) * 1e-4
    cal = CalibratedArm(arm, arm.nominal, factor @ factor.T, 0.01)
    rows = arm.plan_conditions(random_poses(arm, 25, rng))
    whole = validation._predicted(cal, rows)
    monkeypatch.setattr(validation, "PREDICTED_CHUNK", 7)
    chunked = validation._predicted(cal, rows)
    for one, other in zip(whole, chunked, strict=True):
        np.testing.assert_allclose(other, one, rtol=1e-12)
