"""Joint compliance under gravity and payload: model, identification, design, command line.

Reference values are closed forms: the static torque of point masses on a
stretched horizontal arm, ``tau_j = sum_i m_i g (x_i - x_j)`` (lever arms in m),
and the expected residual RMS of least squares, ``sigma sqrt(1 - p / (2 m))``.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from armcal.compensation import compensate
from armcal.compliance_check import check_compliance, virtual_vertical_arm
from armcal.doe import design_with_loads
from armcal.errors import ArmcalError, NotIdentifiableError
from armcal.files import read_calibration
from armcal.identification import identify, solve
from armcal.instrument import identify_3d
from armcal.models import (
    STANDARD_GRAVITY,
    CompliantArm,
    Elastostatic,
    Loads,
    PlanarArm,
    Target,
    check_compliance_identifiable,
    forward_kinematics,
)
from armcal.synthesis import synthesize_measurements
from armcal.validation import validate
from helpers import VERTICAL_3LINK, Run, run_cli

G = STANDARD_GRAVITY


def _two_link(**kwargs) -> tuple[PlanarArm, Elastostatic]:
    arm = PlanarArm([500.0, 300.0])
    return arm, Elastostatic.create(2, gravity_xy=[0, -1], **kwargs)


def test_torques_of_a_stretched_horizontal_arm_match_point_masses():
    arm, elastic = _two_link(link_masses_kg=[10.0, 4.0], com_fraction=[0.5, 0.25])
    model = CompliantArm.for_loads(arm, elastic, Loads.create(1, 2.0))
    torque = model.load_terms(np.zeros((1, 2)), None, Loads.create(1, 2.0))[0]
    # joint 1 at x = 0, joint 2 at 0.5 m, link 2's centre at 0.5 + 0.075 m, the tip at 0.8 m
    tau1 = -G * (10.0 * 0.25 + 4.0 * 0.575 + 2.0 * 0.8)
    tau2 = -G * (4.0 * 0.075 + 2.0 * 0.3)
    np.testing.assert_allclose(torque, [tau1, tau2], rtol=1e-12)


def test_tip_force_and_lumped_lever_arms():
    arm, elastic = _two_link()  # lumped: no masses
    # 50 N upwards at the tip in one row, none in the other: a known load that varies
    loads = Loads.create(2, 0.0, [[0.0, 50.0], [0.0, 0.0]])
    model = CompliantArm.for_loads(arm, elastic, loads)
    assert model.compliance_names == ("c1", "c2", "k1", "k2")
    values = model.load_terms(np.zeros((2, 2)), None, loads)[0]
    # h_j: horizontal lever arm (m) to the tip, signed as a weight's torque; force torque 50 x
    np.testing.assert_allclose(values, [-0.8, -0.3, 50 * 0.8, 50 * 0.3], rtol=1e-12)


def test_a_constant_payload_only_adds_to_the_lumped_weight():
    arm, elastic = _two_link(payload_kg=5.0)
    constant = CompliantArm.for_loads(arm, elastic, Loads.create(4, 5.0))
    varying = CompliantArm.for_loads(arm, elastic, Loads.create(4, [0.0, 5.0, 0.0, 5.0]))
    assert constant.compliance_names == ("c1", "c2")
    assert varying.compliance_names == ("c1", "c2", "k1", "k2")


def test_deflected_tip_is_a_rotation_about_each_joint():
    arm, elastic = _two_link(link_masses_kg=[10.0, 4.0])
    loads = Loads.create(1, 0.0)
    model = CompliantArm.for_loads(arm, elastic, loads)
    k = np.array([2e-6, 5e-6])
    rows = model.conditions(np.zeros((1, 2)), loads=loads)
    tip = model.positions(rows, np.concatenate([np.zeros(4), k]))[0]
    tau = model.load_terms(np.zeros((1, 2)), None, loads)[0]
    bend = k * tau
    # joint 1 turns the whole arm by bend1, joint 2 the last link by bend2 in addition
    expected = 500 * np.exp(1j * bend[0]) + 300 * np.exp(1j * (bend[0] + bend[1]))
    np.testing.assert_allclose(tip, [expected.real, expected.imag], rtol=0, atol=1e-12)


def test_compliance_columns_match_central_differences():
    arm, elastic, truth = virtual_vertical_arm()
    rng = np.random.default_rng(3)
    q = rng.uniform(-2.5, 2.5, (6, 3))
    loads = Loads.create(6, [0, 10, 0, 10, 0, 10])
    model = CompliantArm.for_loads(arm, elastic, loads)
    rows = model.conditions(q, loads=loads)
    jac = model.jacobian(rows, truth)
    p = arm.n_params
    for i in range(p, model.n_params):
        h = 1e-9
        up, down = truth.copy(), truth.copy()
        up[i] += h
        down[i] -= h
        numeric = (model.positions(rows, up) - model.positions(rows, down)) / (2 * h)
        np.testing.assert_allclose(jac[..., i], numeric, rtol=1e-6, atol=1e-6)
    # the geometric columns leave out the torques' own change with the geometry:
    # a relative error of the order of the deflection over the reach (< 1e-3)
    for i in range(p):
        h = 1e-6
        up, down = truth.copy(), truth.copy()
        up[i] += h
        down[i] -= h
        numeric = (model.positions(rows, up) - model.positions(rows, down)) / (2 * h)
        scale = np.max(np.abs(numeric))
        assert np.max(np.abs(jac[..., i] - numeric)) < 1e-3 * scale


@pytest.mark.parametrize("lumped", [False, True])
def test_noiseless_data_are_recovered_to_round_off(lumped):
    arm, elastic, truth = virtual_vertical_arm()
    if lumped:
        elastic = Elastostatic.create(3, gravity_xy=[0.3, -1.0], payload_kg=10.0)
    rng = np.random.default_rng(11)
    q = rng.uniform(-2.6, 2.6, (30, 3))
    loads = Loads.create(30, np.where(np.arange(30) % 3 == 0, 0.0, 10.0))
    model = CompliantArm.for_loads(arm, elastic, loads)
    if lumped:  # c (mdeg/m) of a few mdeg per metre, then k
        truth = np.concatenate([truth[:6], np.radians([3e-3, 2e-3, 1e-3]), truth[6:]])
        assert model.compliance_names == ("c1", "c2", "c3", "k1", "k2", "k3")
    rows = model.conditions(q, loads=loads)
    xy = model.positions(rows, truth)
    found = solve(model, rows, xy)
    est, converged = found.params[0], bool(found.converged[0])
    assert converged
    scale = np.concatenate([np.ones(6), 1.0 / np.abs(truth[6:])])
    np.testing.assert_allclose((est - truth) * scale, 0.0, atol=1e-8)


def test_identical_poses_cannot_identify_compliance_and_say_why():
    arm, elastic, _ = virtual_vertical_arm()
    q = np.tile(np.radians([[10.0, 20.0, 30.0]]), (20, 1))
    loads = Loads.create(20, 0.0)
    model = CompliantArm.for_loads(arm, elastic, loads)
    with pytest.raises(NotIdentifiableError, match="k1"):
        check_compliance_identifiable(model, model.conditions(q, loads=loads))


def test_lumped_k_needs_a_varying_payload():
    arm = PlanarArm([600.0, 450.0, 200.0])
    elastic = Elastostatic.create(3, payload_kg=10.0)  # no gravity: torques only from loads
    loads = Loads.create(10, 0.0)
    with pytest.raises(ArmcalError, match="nothing twists the joints"):
        CompliantArm.for_loads(arm, elastic, loads)


def test_compensation_takes_out_the_deflection_under_the_programs_payload():
    arm, elastic, truth = virtual_vertical_arm()
    rng = np.random.default_rng(5)
    q = rng.uniform(-2.5, 2.5, (40, 3))
    loads = Loads.create(40, np.where(np.arange(40) % 2 == 0, 0.0, 10.0))
    model = CompliantArm.for_loads(arm, elastic, loads)
    xy = model.positions(model.conditions(q, loads=loads), truth)
    cal = identify(model, q, xy, sigma=0.02, loads=loads).calibrated()
    program = rng.uniform(-1.5, 1.5, (20, 3))
    program_loads = Loads.create(20, 10.0)
    result = compensate(cal, program, loads=program_loads)
    assert result.corrected.all()
    reached = model.positions(model.conditions(result.q, loads=program_loads), truth)
    goal = forward_kinematics(arm, program)
    assert np.max(np.linalg.norm(reached - goal, axis=1)) < 1e-6
    at_program = model.positions(model.conditions(program, loads=program_loads), truth)
    before = np.linalg.norm(at_program - goal, axis=1)
    np.testing.assert_allclose(result.position_before_mm, before, rtol=1e-9)


def test_compliance_unseen_judges_the_weighted_fit():
    """Per-row sigma: the F test compares the weighted sums of squares the fits minimised.

    A 2-link vertical arm, 40 poses, payloads 0/5/10 kg, 0.5 mm on every fifth pose and
    0.005 mm on the others: the compliance is identified at 18-100 std in every trial,
    so ``compliance-unseen`` must not fire.  (Compared unweighted, the five noisy poses
    dominate both sums of squares and the test fired in 15 of these 20 trials.)
    """
    arm = PlanarArm([500.0, 300.0], np.radians([[-170, 170], [-150, 150]]))
    elastic = Elastostatic.create(2, gravity_xy=[0, -1], link_masses_kg=[15.0, 8.0])
    m = 40
    loads = Loads.create(m, np.array([0.0, 5.0, 10.0])[np.arange(m) % 3])
    model = CompliantArm.for_loads(arm, elastic, loads)
    k_true = np.array([2.0, 4.0]) * 1e-6
    truth = np.concatenate([arm.params_from_display([0.5, -0.3], [0.2, -0.1]), k_true])
    row_sigma = np.where(np.arange(m) % 5 == 0, 0.5, 0.005)
    for seed in range(20):
        rng = np.random.default_rng(seed)
        q = rng.uniform(-2.5, 2.5, (m, 2))
        xy = synthesize_measurements(model, q, truth, rng=rng, row_sigma=row_sigma, loads=loads)
        cal = identify(model, q, xy, row_sigma=row_sigma, loads=loads)
        assert cal.nested is not None
        k_std = np.sqrt(np.diag(cal.covariance)[-2:])
        assert np.all(cal.params[-2:] / k_std > 10)  # seen, clearly
        assert "compliance-unseen" not in [w.code for w in cal.warnings], seed


@pytest.mark.slow
def test_self_check_meets_the_issue_thresholds():
    check = check_compliance(seed=0, trials=2000)
    rigid, fit = check.rigid, check.compliant
    assert "fit-inconsistent" in [w.code for w in rigid.warnings]
    assert rigid.residual_rms > 5 * 0.02
    assert np.max(np.abs(check.rigid_length_bias_in_std)) > 3  # biased lengths
    assert not fit.warnings
    n_free = fit.n_free
    expected = 0.02 * np.sqrt(1 - n_free / (2 * fit.n_poses))  # least squares' residual RMS
    assert abs(fit.residual_rms / expected - 1) < 0.10
    assert np.all(np.abs(check.errors_in_std) < 3)
    # held-out error: the noise of a point (sqrt(2) sigma) and the model's uncertainty
    assert abs(check.validation_rms_mm / check.validation_predicted_mm - 1) < 0.15
    mc = check.monte_carlo
    k = [i for i, name in enumerate(mc.names) if name.startswith("k")]
    np.testing.assert_allclose(mc.std[k] / mc.predicted_std[k], 1.0, atol=0.05)
    assert np.all(np.abs(mc.bias) <= mc.bias_limit)
    assert check.certified_d_efficiency >= 0.99
    # the design's predicted std is reported per parameter, and is no worse in det
    assert check.design_quality.predicted_std.shape == (9,)


@pytest.mark.slow
def test_design_splits_payloads_when_the_masses_are_unknown():
    arm = PlanarArm([600.0, 450.0, 200.0], np.radians([[-170, 170], [-150, 150], [-150, 150]]))
    elastic = Elastostatic.create(3, gravity_xy=[0, -1], payload_kg=10.0)
    model = CompliantArm(arm, elastic)
    plan = design_with_loads(model, 30, rng=2, candidates=1500, search=5000)
    assert plan.payload_kg is not None and plan.certificate is not None
    counts = {v: int(np.count_nonzero(plan.payload_kg == v)) for v in plan.payloads}
    assert plan.model.compliance_names == ("c1", "c2", "c3", "k1", "k2", "k3")
    assert counts[0.0] > 0 and counts[10.0] > 0  # k is seen only through the payload's change
    assert plan.certificate.certified_d_efficiency >= 0.97
    assert np.all(arm.within_limits(plan.q))


def test_3d_data_with_gravity_in_the_instrument_frame():
    arm, elastic, truth = virtual_vertical_arm()
    base = arm.replace(base_offset=True, base_rotation=True, fixed=("dq1",))
    rng = np.random.default_rng(8)
    q = rng.uniform(-2.5, 2.5, (40, 3))
    loads = Loads.create(40, np.where(np.arange(40) % 2 == 0, 0.0, 10.0))
    # the arm moves in the instrument's x-z plane, gravity along -z
    full = np.concatenate([truth[:6], [20.0, -30.0, 0.0], truth[6:]])
    full[3] = 0.0  # dq1 is held: the base rotation takes its place
    model = CompliantArm.for_loads(base, elastic, loads)
    xy = model.positions(model.conditions(q, loads=loads), full)
    xyz = np.column_stack([xy[:, 0], np.full(40, 5.0), xy[:, 1]])
    cal = identify_3d(model, q, xyz, sigma=0.02, loads=loads, gravity_3d=np.array([0, 0, -1.0]))
    k = cal.params[-3:] * 1e6
    np.testing.assert_allclose(k, [1.5, 3.0, 6.0], rtol=1e-6)


def _armcal(*args: str, cwd: Path) -> Run:
    return run_cli(cwd, *args)


ROBOT = VERTICAL_3LINK

TRUTH = """
dl_mm = [1.0, -0.5, 0.8]
dq_deg = [0.3, -0.2, 0.4]
k_urad_per_Nm = [1.5, 3.0, 6.0]
"""


def test_command_line_round_trip_with_compliance(tmp_path):
    (tmp_path / "robot.toml").write_text(ROBOT)
    (tmp_path / "truth.toml").write_text(TRUTH)
    plan = "\n".join(
        ["q1_deg,q2_deg,q3_deg,payload_kg"]
        + [
            f"{a},{b},{c},{10 if i % 2 else 0}"
            for i, (a, b, c) in enumerate(np.random.default_rng(4).uniform(-140, 140, (40, 3)))
        ]
    )
    (tmp_path / "plan.csv").write_text(plan + "\n")
    common = ["--robot", "robot.toml"]
    run = _armcal("synthesize", *common, "--plan", "plan.csv", "--truth", "truth.toml",
                  "-o", "meas.csv", "--seed", "3", cwd=tmp_path)  # fmt: skip
    assert run.returncode == 0, run.stderr
    run = _armcal("identify", *common, "--measurements", "meas.csv", "-o", "cal.json",
                  "--json", cwd=tmp_path)  # fmt: skip
    assert run.returncode == 0, run.stderr
    doc = json.loads(run.stdout)
    values = {p["name"]: (p["value"], p["std"]) for p in doc["parameters"]}
    for name, truth in zip(("k1", "k2", "k3"), (1.5, 3.0, 6.0), strict=True):
        value, std = values[name]
        assert abs(value - truth) < 3 * std
    assert doc["elastostatic"]["parameters"] == ["k1", "k2", "k3"]
    cal = read_calibration(tmp_path / "cal.json")
    assert isinstance(cal.model, CompliantArm)
    np.testing.assert_allclose(cal.params[-3:] * 1e6, [values[f"k{j}"][0] for j in (1, 2, 3)])
    run = _armcal("identify", *common, "--measurements", "meas.csv", "--no-compliance",
                  cwd=tmp_path)  # fmt: skip
    assert "inconsistent with sigma" in run.stderr and "loads-ignored" not in run.stderr
    run = _armcal("validate", "--calibration", "cal.json", "--measurements", "meas.csv",
                  "--json", cwd=tmp_path)  # fmt: skip
    assert run.returncode == 0, run.stderr
    assert json.loads(run.stdout)["rms_after_mm"] < 0.04
    (tmp_path / "prog.csv").write_text("q1_deg,q2_deg,q3_deg\n10,20,30\n-40,50,-60\n")
    run = _armcal("compensate", "--calibration", "cal.json", "--program", "prog.csv",
                  "--payload-kg", "10", "-o", "out.csv", "--json", cwd=tmp_path)  # fmt: skip
    assert run.returncode == 0, run.stderr
    assert json.loads(run.stdout)["rms_before_mm"] > 0.1  # deflection and geometry
    run = _armcal("evaluate", *common, "--plan", "plan.csv", "--json", cwd=tmp_path)
    assert run.returncode == 0, run.stderr
    assert set(json.loads(run.stdout)["predicted_std"]) >= {"k1", "k2", "k3"}
    run = _armcal("simulate", *common, "--plan", "plan.csv", "--truth", "truth.toml",
                  "--trials", "300", "--json", cwd=tmp_path)  # fmt: skip
    assert run.returncode == 0, run.stderr
    assert "k3" in json.loads(run.stdout)["empirical_std"]


@pytest.mark.parametrize(
    ("table", "message"),
    [
        ("[elastostatic]\ngravity = [0, -1]\n", "unknown key 'elastostatic.gravity'"),
        ("[elastostatic]\ngravity_xy = [0, 0]\n", "non-zero direction"),
        ("[elastostatic]\nlink_masses_kg = [1, 2]\n", "link_masses_kg"),
        ("[elastostatic]\ngravity_xy = [0, -1]\npayload_kg = -1\n", "payload_kg"),
        ("[elastostatic]\ngravity_xy = [0, -1]\ncom_fraction = 1.5\n", "com_fraction"),
    ],
)
def test_bad_elastostatic_tables_are_one_line_errors(tmp_path, table, message):
    base = "link_lengths_mm = [600.0, 450.0, 200.0]\n"
    (tmp_path / "robot.toml").write_text(base + table)
    (tmp_path / "plan.csv").write_text("q1_deg,q2_deg,q3_deg\n0,0,0\n")
    run = _armcal("evaluate", "--robot", "robot.toml", "--plan", "plan.csv", cwd=tmp_path)
    assert run.returncode == 2
    assert run.stderr.startswith("armcal: error: ") and message in run.stderr
    assert len(run.stderr.strip().splitlines()) == 1


def test_payloads_need_an_elastostatic_robot(tmp_path):
    run = _armcal("design", "--poses", "8", "--payloads", "0,10", cwd=tmp_path)
    assert run.returncode == 2 and "no [elastostatic]" in run.stderr
    (tmp_path / "m.csv").write_text("q1_deg,q2_deg,q3_deg,q4_deg,x_mm,y_mm,payload_kg\n"
                                    "0,0,0,0,660,0,-1\n")  # fmt: skip
    run = _armcal("identify", "--robot", "paper-4link", "--measurements", "m.csv", cwd=tmp_path)
    assert run.returncode == 2 and "payload_kg" in run.stderr and "negative" in run.stderr


def _nest_arm() -> tuple[PlanarArm, Elastostatic, np.ndarray]:
    """The virtual vertical arm with a nest of three tracker reflectors on its last link."""
    arm, elastic, truth = virtual_vertical_arm()
    nest = arm.replace(
        targets=[
            Target("A", 200.0),
            Target("B", 160.0, np.radians(25.0)),
            Target("C", 160.0, np.radians(-25.0)),
        ]
    )
    # dl and dq of links 1, 2, then each reflector's last link (3@A, 3@B, 3@C)
    geometry = nest.params_from_display([1.0, -0.5, 0.8, 0.3, -0.4], [0.3, -0.2, 0.4, 0.25, 0.45])
    return nest, elastic, np.concatenate([geometry, truth[arm.n_params :]])


def test_compliance_with_a_nest_of_three_reflectors():
    """Every pose measured at three reflectors: the compliance is recovered within 3 std,
    the residual falls to the noise against the geometry alone, and validation and
    compensation take the calibration (with each row's reflector and payload)."""
    nest, elastic, truth = _nest_arm()
    rng = np.random.default_rng(21)
    poses = 40
    q = rng.uniform(-2.5, 2.5, (poses, 3))
    payload = np.where(np.arange(poses) % 2 == 1, 10.0, 0.0)
    model = CompliantArm.for_loads(nest, elastic, Loads.create(poses, payload))
    rows = model.plan_conditions(q, Loads.create(poses, payload))  # 3 rows per pose
    assert rows.m == 3 * poses and rows.target.tolist()[:3] == [0, 1, 2]
    sigma = 0.02
    xy = synthesize_measurements(
        model, rows.q, truth, sigma, rng=rng, target=rows.target, loads=rows.loads
    )
    cal = identify(model, rows.q, xy, sigma=sigma, target=rows.target, loads=rows.loads)
    assert cal.names[-3:] == ("k1", "k2", "k3")
    errors = (cal.params - truth) * cal.display_scale / cal.std
    assert np.all(np.abs(errors) < 3), dict(zip(cal.names, errors.round(2), strict=True))
    assert not cal.warnings, [w.code for w in cal.warnings]
    # residual RMS per coordinate: at sigma with compliance, many sigma without it
    assert cal.nested is not None
    assert cal.residual_rms < 1.2 * sigma
    assert cal.nested.rms_per_coordinate_mm > 5 * sigma
    assert cal.nested.p_value is not None and cal.nested.p_value < 1e-12
    # held-out poses, each reflector and payload: calibrated at the predicted error
    q_test = rng.uniform(-2.5, 2.5, (60, 3))
    test_loads = Loads.create(60, rng.choice([0.0, 10.0], 60))
    test = model.plan_conditions(q_test, test_loads)
    xy_test = synthesize_measurements(
        model, test.q, truth, sigma, rng=rng, target=test.target, loads=test.loads
    )
    fitted = cal.calibrated()
    check = validate(fitted, test.q, xy_test, target=test.target, loads=test.loads)
    summary = check.summary()
    assert summary["rms_after_mm"] < 1.2 * summary["predicted_rms_after_per_point_mm"]
    assert summary["rms_before_mm"] > 10 * summary["rms_after_mm"]
    # a program for reflector B under 10 kg: the true arm reaches where the nominal meant
    program = rng.uniform(-1.5, 1.5, (10, 3))
    target = np.full(10, 1)
    program_loads = Loads.create(10, 10.0)
    result = compensate(fitted, program, target=target, loads=program_loads)
    assert result.corrected.all()
    reached = model.positions(
        model.conditions(result.q, target=target, loads=program_loads), truth
    )
    goal = forward_kinematics(nest, program, target=target)
    # the calibration's error, a few sigma/sqrt(m), not the deflection (up to ~1 mm)
    assert np.max(np.linalg.norm(reached - goal, axis=1)) < 0.05
    assert np.max(result.position_before_mm) > 0.3


LUMPED_ROBOT = ROBOT.replace("link_masses_kg = [20, 12, 6]\n", "")
LUMPED_TRUTH = TRUTH + "c_mdeg_per_m = [0.5, 1.0, 2.0]\n"


def test_a_lumped_robot_takes_the_truth_of_the_plans_loads(tmp_path):
    """Masses unknown: with the robot file's payload alone only c1..c3 are seen, with a
    payload column that varies k1..k3 too (12 parameters, not 9).  The truth is read for
    the plan's model, so synthesize and simulate accept a truth with both."""
    (tmp_path / "robot.toml").write_text(LUMPED_ROBOT)
    (tmp_path / "truth.toml").write_text(LUMPED_TRUTH)
    q = np.random.default_rng(5).uniform(-140, 140, (30, 3))
    rows = [f"{a},{b},{c},{10 if i % 2 else 0}" for i, (a, b, c) in enumerate(q)]
    (tmp_path / "plan.csv").write_text("\n".join(["q1_deg,q2_deg,q3_deg,payload_kg", *rows]))
    common = ["--robot", "robot.toml", "--plan", "plan.csv", "--truth", "truth.toml"]
    run = _armcal("synthesize", *common, "-o", "meas.csv", cwd=tmp_path)
    assert run.returncode == 0, run.stderr
    run = _armcal("simulate", *common, "--trials", "50", "--json", cwd=tmp_path)
    assert run.returncode == 0, run.stderr
    names = list(json.loads(run.stdout)["predicted_std"])
    assert names[-6:] == ["c1", "c2", "c3", "k1", "k2", "k3"]


def test_the_demo_of_a_robot_with_compliance_takes_a_geometric_truth(tmp_path):
    """The demo calibrates the geometry: its truth file needs no compliance."""
    (tmp_path / "robot.toml").write_text(ROBOT)
    (tmp_path / "truth.toml").write_text("dl_mm = [1.0, -0.5, 0.8]\ndq_deg = [0.3, -0.2, 0.4]\n")
    run = _armcal("demo", "--robot", "robot.toml", "--truth", "truth.toml", cwd=tmp_path)
    assert run.returncode == 0, run.stderr
