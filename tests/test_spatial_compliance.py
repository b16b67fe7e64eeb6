"""Joint compliance of spatial serial arms (:mod:`armcal.models.spatial.compliance`).

References used here, independent of the code under test:

* a twist ``du_j = k_j tau_j`` is a change of joint value, so the twisted arm's
  point is the chain's forward kinematics (:meth:`SerialChain.forward`) at
  ``u + K tau``, ``tau`` from :func:`gravity_torques` (itself tested against the
  potential energy's gradient in ``test_spatial_gravity.py``);
* a lumped station's lever arm about a vertical-plane joint is, for axes along
  ``z`` and gravity along ``-y``, ``-(x_s - x_j)`` (a weight to the joint's
  right twists it clockwise);
* with every link's centre of mass at a joint's origin, the lumped mode's
  ``c{j}.j{i}`` is ``k_j`` times the weight lumped at joint ``i`` (``m g``), and
  the payload's own torque gives ``k_j`` itself.

The virtual industrial arm is the built-in ``industrial-6r`` with three
reflectors and illustrative link masses (not a data sheet's), compliance
0.2 and 0.4 urad/(N m) on J2 and J3, measured with 0.02 mm noise under 0 and
165 kg (the R-2000iC/165F's rated payload).
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from armcal.files import load_spatial_robot, load_spatial_truth
from armcal.identification import identify
from armcal.models import (
    CompliantSpatialArm,
    LinkMasses,
    Loads,
    SerialChain,
    SpatialArm,
    SpatialElastics,
)
from armcal.models.spatial.gravity import STANDARD_GRAVITY, gravity_torques
from armcal.models.wording import held_sentence
from armcal.simulate import monte_carlo
from armcal.validation import validate
from helpers import cell_toml, run_cli

MASSES = [350.0, 150.0, 200.0, 60.0, 20.0, 5.0]
PAYLOAD = 165.0
K2, K3 = 0.2e-6, 0.4e-6  # rad/(N m)
TARGETS = {"A": [100.0, 0.0, 150.0], "B": [-50.0, 86.6, 150.0], "C": [-50.0, -86.6, 150.0]}


def _arm() -> SpatialArm:
    arm = load_spatial_robot("industrial-6r").arm
    return arm.replace(
        targets=tuple(TARGETS), target_positions=np.array(list(TARGETS.values())), view=None
    )


def _elastics(lumped: bool = False) -> SpatialElastics:
    return SpatialElastics.create(
        6,
        mass_kg=None if lumped else MASSES,
        com_mm=None if lumped else np.zeros((6, 3)),
        payload_kg=PAYLOAD,
        payload_com_mm=[0.0, 0.0, 100.0],
    )


def _poses(m: int, seed: int) -> tuple[np.ndarray, Loads]:
    arm = _arm()
    lo, hi = arm.joint_limits.T
    q = lo + (hi - lo) * np.random.default_rng(seed).random((m, 6))
    return q, Loads.create(m, np.where(np.arange(m) % 2, 0.0, PAYLOAD))


def _truth(model: CompliantSpatialArm) -> np.ndarray:
    """The built-in truth's geometry and instrument pose, K2 and K3."""
    geometry = load_spatial_truth(load_spatial_robot("industrial-6r").default_truth, model.arm)
    compliance = np.zeros(model.n_compliance)
    compliance[model.compliance_names.index("k2")] = K2
    compliance[model.compliance_names.index("k3")] = K3
    return np.concatenate([geometry, compliance])


def _measured(model: CompliantSpatialArm, q, loads, truth, sigma, seed):
    rows = model.plan_conditions(q, loads)
    points = model.positions(rows, truth)
    noise = np.random.default_rng(seed).normal(0.0, sigma, points.shape) if sigma else 0.0
    return rows, points + noise


def test_a_twist_is_the_chains_kinematics_at_the_twisted_joint_values():
    arm = _arm().replace(base_pose=np.zeros(6))
    q, loads = _poses(7, 1)
    model = CompliantSpatialArm.for_loads(arm, _elastics(), loads)
    k = np.array([0.0, K2, K3, 1e-6, 2e-6, 3e-6])
    rows = model.plan_conditions(q, loads)
    params = np.concatenate([arm.nominal, k[[model.joints]].ravel()])
    u = rows.q @ arm.joint_map.T
    links = LinkMasses(np.array(MASSES), np.zeros((6, 3)))
    g = [0.0, 0.0, -STANDARD_GRAVITY]
    tau = gravity_torques(
        arm.chain, u, links, g, payload_kg=rows.loads.payload_kg, payload_com_mm=[0, 0, 100]
    )
    frames = arm.chain.forward(u + k * tau)
    targets = arm.target_positions[rows.target]
    expected = np.einsum("mij,mj->mi", frames[:, :3, :3], targets) + frames[:, :3, 3]
    assert np.max(np.abs(model.positions(rows, params) - expected)) < 1e-9  # mm, round-off


def test_lumped_lever_arms_are_the_horizontal_distances_of_the_stations():
    chain = SerialChain.from_mdh([0, 0, 0], [0, 500.0, 300.0], [0, 0, 0], [0, 0, 0])
    tip = np.eye(4)
    tip[0, 3] = 200.0  # the flange 200 mm beyond joint 3 along its link
    chain = SerialChain(
        chain.origins, chain.kinds, tip, chain.joint_names, np.tile([-np.pi, np.pi], (3, 1))
    )
    arm = SpatialArm(chain)
    elastic = SpatialElastics.create(3, gravity=[0, -2, 0])  # axes along z: a vertical arm
    model = CompliantSpatialArm.for_loads(arm, elastic, Loads.create(1))
    q = np.radians([[30.0, -50.0, 70.0], [-120.0, 10.0, 95.0]])
    rows = model.conditions(q)
    a1 = np.cumsum(q, axis=1)
    x = np.stack(
        [np.zeros(2), 500 * np.cos(a1[:, 0]), 500 * np.cos(a1[:, 0]) + 300 * np.cos(a1[:, 1])],
        axis=1,
    )  # joints 1, 2, 3
    tip = x[:, 2] + 200 * np.cos(a1[:, 2])
    expected = {
        "c1.j2": x[:, 1],
        "c1.j3": x[:, 2],
        "c1.tip": tip,
        "c2.j3": x[:, 2] - x[:, 1],
        "c2.tip": tip - x[:, 1],
        "c3.tip": tip - x[:, 2],
    }
    terms = model.load_terms(rows)
    for name, value in expected.items():
        got = terms[:, model.compliance_names.index(name)]
        np.testing.assert_allclose(got, -value / 1000.0, atol=1e-12)


@pytest.mark.parametrize("lumped", [False, True])
def test_the_jacobian_agrees_with_central_differences(lumped):
    arm = _arm()
    q, loads = _poses(6, 2)
    model = CompliantSpatialArm.for_loads(arm, _elastics(lumped), loads)
    rows = model.plan_conditions(q, loads)
    truth = _truth(model)
    truth[arm.n_params :] += np.linspace(1e-7, 1e-6, model.n_compliance)
    jac = model.jacobian(rows, truth)
    # steps that move the points by 1e-4 to 1e-2 mm (round-off eps * 3000 mm / step stays
    # below 1e-8 of a column): 1e-4 mm and rad for the geometry, 1e-9 rad/(N m) for a k
    # (1e6 mm a unit), 1e-5 rad/m for a c (10 mm a unit)
    step = np.concatenate(
        [np.full(arm.n_params, 1e-4), [1e-9 if kind == "k" else 1e-5 for kind in model.kinds]]
    )
    for i in range(model.n_params):
        d = np.zeros(model.n_params)
        d[i] = step[i]
        numeric = (model.positions(rows, truth + d) - model.positions(rows, truth - d)) / (
            2 * d[i]
        )
        # truncation h^2 |f'''| / 6: about 1e-8 of the column at these steps; a column
        # of no effect (k6: the payload hangs on J6's axis) is round-off, 1e-11 mm
        scale = max(np.max(np.abs(jac[..., i])), 1e-3)
        assert np.max(np.abs(jac[..., i] - numeric)) <= 1e-6 * scale, model.param_names[i]


def test_joint_1_about_gravity_and_a_wrist_on_its_axis_are_held_and_named():
    q, loads = _poses(40, 3)
    loaded = CompliantSpatialArm.for_loads(_arm(), _elastics(), loads)
    model = loaded.prepared(loaded.plan_conditions(q, loads))
    assert set(model.held) == {"k1", "k6"}  # J1 is vertical; the payload hangs on J6's axis
    # The bound on what rows identify: the arm's 4R + 2P + 3k and every free stiffness.
    k = len(model.arm.targets)
    assert loaded.rank_bound == 4 * 6 + 3 * k + 6 and model.rank_bound == 4 * 6 + 3 * k + 4
    assert "k1 cannot be seen: there is no torque on joint 1 that varies" in map(
        held_sentence, model.merges
    )
    lumped = CompliantSpatialArm.for_loads(_arm(), _elastics(lumped=True), loads)
    lumped = lumped.prepared(lumped.plan_conditions(q, loads))
    assert "c2.j5 merges into c2.j4" in map(held_sentence, lumped.merges)  # a spherical wrist
    assert {"k2", "k3", "c2.j3", "c3.j4"} <= set(lumped.free_names)


def test_noiseless_data_give_the_compliance_to_round_off():
    q, loads = _poses(40, 4)
    model = CompliantSpatialArm.for_loads(_arm(), _elastics(), loads)
    truth = _truth(model)
    rows, points = _measured(model, q, loads, truth, 0.0, 0)
    cal = identify(model, rows.q, points, target=rows.target, loads=rows.loads, sigma=0.02)
    assert abs(cal["k2"].value * 1e-6 - K2) < 1e-9 * K2
    assert abs(cal["k3"].value * 1e-6 - K3) < 1e-9 * K3
    assert cal.residual_max < 1e-9  # mm


def test_the_lumped_mode_finds_the_weights_at_its_stations():
    """Every link's centre at a joint's origin: the lumped mode is exact, ``c = k m g``."""
    q, loads = _poses(60, 5)
    virtual = CompliantSpatialArm.for_loads(_arm(), _elastics(), loads)
    rows, points = _measured(virtual, q, loads, _truth(virtual), 0.0, 0)
    lumped = CompliantSpatialArm.for_loads(_arm(), _elastics(lumped=True), loads)
    cal = identify(lumped, rows.q, points, target=rows.target, loads=rows.loads, sigma=0.02)
    g = STANDARD_GRAVITY
    to_mdeg = 1e3 * 180.0 / np.pi
    expected = {
        "c2.j3": K2 * MASSES[2] * g,
        "c2.j4": K2 * (MASSES[3] + MASSES[4]) * g,  # joints 4 and 5 meet at the wrist
        "c2.j6": K2 * MASSES[5] * g,
        "c3.j4": K3 * (MASSES[3] + MASSES[4]) * g,
        "c3.j6": K3 * MASSES[5] * g,
    }
    for name, value in expected.items():
        assert cal[name].value == pytest.approx(value * to_mdeg, rel=1e-7), name
    assert cal["k2"].value == pytest.approx(K2 * 1e6, rel=1e-7)


def test_a_virtual_six_axis_arm_under_two_payloads():
    """The issue's case: within 3 std, and better on held-out poses than geometry alone."""
    q, loads = _poses(40, 6)
    model = CompliantSpatialArm.for_loads(_arm(), _elastics(), loads)
    truth = _truth(model)
    rows, points = _measured(model, q, loads, truth, 0.02, 7)
    cal = identify(model, rows.q, points, target=rows.target, loads=rows.loads, sigma=0.02)
    for name in ("k2", "k3", "k4", "k5"):
        i = cal.names.index(name)
        assert abs(cal.values[i] - truth[i] * 1e6) < 3 * cal.std[i], name
    rigid = identify(model.arm, rows.q, points, target=rows.target, sigma=0.02)
    held_q, held_loads = _poses(30, 8)
    held, held_points = _measured(model, held_q, held_loads, truth, 0.02, 9)
    errors = []
    for fitted in (cal, rigid):
        check = validate(
            fitted.calibrated(), held.q, held_points, target=held.target, loads=held.loads
        )
        errors.append(check.summary()["rms_after_per_point_mm"])
    assert errors[0] < 0.5 * errors[1]
    assert errors[0] < 0.05  # mm: noise 0.02 mm per coordinate is 0.035 mm per point


@pytest.mark.slow  # 2000 fits: run by make test-slow
def test_monte_carlo_agrees_with_the_predicted_std():
    q, loads = _poses(40, 6)
    model = CompliantSpatialArm.for_loads(_arm(), _elastics(), loads)
    model = model.prepared(model.plan_conditions(q, loads))
    result = monte_carlo(model, q, _truth(model), 0.02, 2000, rng=10, loads=loads)
    # the std of a std from N normal draws is 1/sqrt(2N) = 1.6 % of it: 5 % is 3 of them
    for name in ("k2", "k3", "k4", "k5"):
        i = result.names.index(name)
        assert result.std[i] / result.predicted_std[i] == pytest.approx(1.0, abs=0.05), name


URDF = """<?xml version="1.0"?>
<robot name="two">
  <link name="base_link"/>
  <link name="link1"><inertial><origin xyz="0.2 0 0"/><mass value="10"/></inertial></link>
  <link name="link1b"><inertial><origin xyz="0 0 0.1"/><mass value="2"/></inertial></link>
  <link name="link2"><inertial><origin xyz="0 0.3 0"/><mass value="3"/></inertial></link>
  <link name="tool"><inertial><mass value="1"/></inertial></link>
  <joint name="j1" type="revolute"><parent link="base_link"/><child link="link1"/>
    <origin xyz="0 0 0.5"/><axis xyz="0 1 0"/><limit lower="-3" upper="3"/></joint>
  <joint name="bracket" type="fixed"><parent link="link1"/><child link="link1b"/>
    <origin xyz="0.4 0 0"/></joint>
  <joint name="j2" type="revolute"><parent link="link1b"/><child link="link2"/>
    <origin xyz="0.1 0 0"/><axis xyz="0 0 1"/><limit lower="-3" upper="3"/></joint>
  <joint name="flange" type="fixed"><parent link="link2"/><child link="tool"/>
    <origin xyz="0 0.5 0" rpy="0 0 1.2"/></joint>
  <link name="finger"><inertial><origin xyz="0.05 0 0"/><mass value="0.5"/></inertial></link>
  <joint name="grip" type="prismatic"><parent link="tool"/><child link="finger"/>
    <origin xyz="0 0 0.1"/><axis xyz="1 0 0"/><limit lower="0" upper="0.04"/></joint>
  <link name="camera"/>
  <joint name="mount" type="fixed"><parent link="link2"/><child link="camera"/>
    <origin xyz="0.1 0 0"/></joint>
</robot>
"""


def test_a_urdfs_inertials_fold_through_fixed_joints(tmp_path):
    """Link 1 carries link1 and the bracket (10 + 2 kg), link 2 carries link2, the tool and
    a gripper's finger beyond the tip link, at the finger's zero (3 + 1 + 0.5 kg; a camera
    without <inertial> weighs nothing); their centres in the world frame are the URDF's
    own transforms'."""
    from armcal.files.urdf import read_urdf
    from armcal.models.spatial.chain import elementary
    from armcal.models.spatial.gravity import chain_frames

    (tmp_path / "two.urdf").write_text(URDF)
    found = read_urdf(tmp_path / "two.urdf", tip_link="tool")
    assert found.masses is not None
    np.testing.assert_allclose(found.masses.mass_kg, [12.0, 4.5])
    u = np.array([0.7, -0.4])
    _, _, after, _ = chain_frames(found.chain, u)
    world = after[:, :3, :3] @ found.masses.com_mm[:, :, None]
    world = world[..., 0] + after[:, :3, 3]
    # by hand, in the URDF's frames: link1 = T(0, 0, 500) Ry(u1); link2 = link1 T(500, 0, 0)
    # Rz(u2); the bracket at (400, 0, 0) in link1, the tool at (0, 500, 0) in link2
    link1 = elementary(1, u[0])
    centre1 = (10 * link1 @ [200, 0, 0] + 2 * link1 @ [400, 0, 100]) / 12 + [0, 0, 500]
    link2 = link1 @ elementary(2, u[1])
    at2 = link1 @ [500, 0, 0] + [0, 0, 500]
    tool = link2 @ elementary(2, 1.2)  # the flange's rpy
    finger = link2 @ [0, 500, 0] + tool @ [50, 0, 100]  # grip at 0: (0, 0, 100) + (50, 0, 0)
    centre2 = (3 * (link2 @ [0, 300, 0]) + 1 * (link2 @ [0, 500, 0]) + 0.5 * finger) / 4.5
    centre2 = centre2 + at2
    np.testing.assert_allclose(world, [centre1, centre2], atol=1e-9)


def _cell(folder: Path, extra: str = "") -> None:
    """The virtual cell's robot TOML and truth, as in the module notes."""
    from armcal.files.spatial import BUILTIN_SPATIAL_ROBOTS

    source = BUILTIN_SPATIAL_ROBOTS["industrial-6r"]
    (folder / "industrial-6r.urdf").write_text(source.with_suffix(".urdf").read_text())
    lumped = "lumped = true" in extra
    (folder / "cell.toml").write_text(
        cell_toml(lumped=lumped, extra=extra.replace("lumped = true", ""))
    )
    (folder / "truth.toml").write_text(
        'robot = "cell.toml"\n'
        "base = { xyz_mm = [2850.0, -1700.0, -650.0], rpy_deg = [0.3, -0.2, 120.0] }\n"
        '[errors]\n"j2.y" = -0.2\ndq3 = -0.03\n[compliance]\nk2 = 0.2\nk3 = 0.4\n'
    )
    for name, seed in (("plan.csv", 11), ("other.csv", 12)):  # measured, then held out
        q, loads = _poses(30, seed)
        rows = ["q1_deg,q2_deg,q3_deg,q4_deg,q5_deg,q6_deg,payload_kg"]
        for pose, payload in zip(np.degrees(q), loads.payload_kg, strict=True):
            rows.append(",".join(f"{v:.6f}" for v in pose) + f",{payload:g}")
        (folder / name).write_text("\n".join(rows) + "\n")


def _synthesize(folder: Path, plan: str, out: str, *options: str, robot: str = "cell.toml"):
    """``armcal synthesize`` of ``plan`` on the virtual cell's truth, written to ``out``."""
    truth = ("--truth", "truth.toml")
    return run_cli(
        folder, "synthesize", "--robot", robot, "--plan", plan, *truth, *options, "-o", out
    )


def test_a_compliant_six_axis_cell_from_the_command_line(tmp_path):
    _cell(tmp_path)
    ok = _synthesize(tmp_path, "plan.csv", "meas.csv", "--sigma", "0.02", "--seed", "1")
    assert ok.returncode == 0, ok.stderr
    assert "payload_kg" in (tmp_path / "meas.csv").read_text().splitlines()[0]
    run = run_cli(
        tmp_path,
        "identify",
        "--robot",
        "cell.toml",
        "--measurements",
        "meas.csv",
        "--cross-validate",
        "5",
        "--json",
        "-o",
        "cal.json",
    )
    assert run.returncode == 0, run.stderr
    doc = json.loads((tmp_path / "cal.json").read_text())
    values = {p["name"]: p for p in doc["parameters"]}
    for name, truth in (("k2", 0.2), ("k3", 0.4)):
        assert abs(values[name]["value"] - truth) < 3 * values[name]["std"]
    assert values["k1"]["fixed"] and "k1" in doc["fixed"]
    assert "k1 cannot be seen" in " ".join(doc["elastostatic"]["merges"])
    assert "compliance-unseen" not in run.stderr
    # held-out poses: the file's calibration predicts them; geometry alone does not
    _synthesize(tmp_path, "other.csv", "held.csv", "--sigma", "0.02", "--seed", "2")
    checked = run_cli(
        tmp_path, "validate", "--calibration", "cal.json", "--measurements", "held.csv", "--json"
    )
    assert checked.returncode == 0, checked.stderr
    rigid = run_cli(
        tmp_path,
        "identify",
        "--robot",
        "cell.toml",
        "--measurements",
        "meas.csv",
        "--no-compliance",
        "-o",
        "rigid.json",
    )
    assert "columns are not used: --no-compliance" in rigid.stderr
    worse = run_cli(
        tmp_path, "validate", "--calibration", "rigid.json", "--measurements", "held.csv", "--json"
    )
    ignored = [w for w in json.loads(worse.stdout)["warnings"] if w["code"] == "loads-ignored"]
    assert len(ignored) == 1 and "no joint compliance" in ignored[0]["message"]
    assert "columns are not used: the calibration has no" in worse.stderr  # loaded rows
    after = json.loads(checked.stdout)["rms_after_per_point_mm"]
    rigid_after = json.loads(worse.stdout)["rms_after_per_point_mm"]
    assert after < 0.05 < 0.5 < rigid_after  # mm
    # compensation corrects the sag under the program's payload: it differs by the payload
    program = "q1_deg,q2_deg,q3_deg,q4_deg,q5_deg,q6_deg\n10,20,-30,40,50,60\n"
    (tmp_path / "program.csv").write_text(program)
    corrected = []
    for payload in ("0", "165"):
        out = f"comp{payload}.csv"
        run = run_cli(
            tmp_path,
            "compensate",
            "--calibration",
            "cal.json",
            "--program",
            "program.csv",
            "--payload-kg",
            payload,
            "--target",
            "A",
            "-o",
            out,
        )
        assert run.returncode == 0, run.stderr
        assert f"sag corrected under a payload of {payload} kg (--payload-kg)" in run.stdout
        line = (tmp_path / out).read_text().splitlines()[1].split(",")
        corrected.append(np.array([float(v) for v in line[:6]]))
    default = run_cli(
        tmp_path, "compensate", "--calibration", "cal.json", "--program", "program.csv",
        "--target", "A", "-o", "comp.csv", "--json",
    )  # fmt: skip
    assert json.loads(default.stdout)["payload_kg"] == {
        "min": PAYLOAD,
        "max": PAYLOAD,
        "from": "the calibration's default",
    }  # the robot file's, which the program does not say
    # J2's sag under 165 kg at 0.2 urad/(N m): about 165 * 9.8 * 1.5 m * 0.2e-6 rad, 0.03 deg
    assert 0.005 < abs(corrected[1][1] - corrected[0][1]) < 0.1
    sim = run_cli(
        tmp_path,
        "simulate",
        "--robot",
        "cell.toml",
        "--plan",
        "plan.csv",
        "--truth",
        "truth.toml",
        "--sigma",
        "0.02",
        "--trials",
        "50",
        "--json",
    )
    assert sim.returncode == 0, sim.stderr


def test_compliance_the_data_cannot_see_is_warned_of(tmp_path):
    _cell(tmp_path)
    truth = (tmp_path / "truth.toml").read_text()
    truth = truth.replace("k2 = 0.2", "k2 = 0").replace("k3 = 0.4", "k3 = 0")
    (tmp_path / "truth.toml").write_text(truth)
    _synthesize(tmp_path, "plan.csv", "meas.csv", "--sigma", "0.02", "--seed", "1")
    run = run_cli(tmp_path, "identify", "--robot", "cell.toml", "--measurements", "meas.csv")
    assert run.returncode == 0, run.stderr
    assert "compliance-unseen" in run.stderr or "do not show the joint compliance" in run.stderr
    # what a rule holds is listed with why, not as a value: the arm's and the compliance's
    assert "k1 cannot be seen" in run.stdout and "j1.x, j1.y and j1.z merge" in run.stdout
    shown = [line.split()[0] for line in run.stdout.splitlines() if line[:1].isalnum()]
    assert "k1" not in shown and "j1.x" not in shown and "k2" in shown


@pytest.mark.parametrize(
    ("extra", "words"),
    [
        ("gravity = [0, 0, 0]", "gravity must be a non-zero direction"),
        ("lumped = 1", "elastostatic.lumped"),
        ("link_com_mm = [[0, 0, 0]]", "elastostatic.link_com_mm"),
        ("lumped = true\nlink_masses_kg = [1, 1, 1, 1, 1, 1]", "remove one of them"),
    ],
)
def test_a_bad_elastostatic_table_is_refused_with_its_key(tmp_path, extra, words):
    _cell(tmp_path, extra)
    run = run_cli(tmp_path, "identify", "--robot", "cell.toml", "--measurements", "plan.csv")
    assert run.returncode == 2
    assert words in run.stderr and "cell.toml" in run.stderr
    assert len(run.stderr.strip().splitlines()) == 1


def test_a_truth_with_an_unknown_compliance_is_refused(tmp_path):
    _cell(tmp_path)
    with (tmp_path / "truth.toml").open("a") as f:
        f.write("k7 = 1\n")
    run = _synthesize(tmp_path, "plan.csv", "meas.csv")
    assert run.returncode == 2
    assert "compliance.k7" in run.stderr and not (tmp_path / "meas.csv").exists()


@pytest.mark.parametrize("lumped", [False, True])
def test_the_design_gradient_pulls_back_the_compliance_columns_exactly(lumped):
    """Against central differences of the blocks themselves (step 1e-6 rad: truncation and
    round-off near 1e-9 of the gradient), with a laser tracker's pose-dependent weights."""
    from armcal.models.information import BlockInformation
    from armcal.noise import NoiseModel, TrackerNoise

    arm = _arm().with_noise(NoiseModel.laser_tracker(TrackerNoise(0.01, 0.002, 0.01, 0.003)))
    q, loads = _poses(8, 3)
    model = CompliantSpatialArm.for_loads(arm, _elastics(lumped), loads)
    model = model.prepared(model.plan_conditions(*_poses(60, 4)))
    weight = np.random.default_rng(0).normal(size=(model.n_free, model.n_free))
    weight = weight @ weight.T
    fast = model.plan_information(q, loads)
    slow = BlockInformation(model, q, loads, unit_columns=True)  # no pullback
    np.testing.assert_array_equal(fast.blocks(), slow.blocks())
    grad = fast.pose_variance(weight)[1]
    reference = slow.pose_variance(weight)[1]
    assert np.max(np.abs(grad - reference)) < 1e-7 * np.max(np.abs(reference))


@pytest.mark.slow  # a design with its certificate: run by make test-slow
def test_a_design_chooses_poses_and_payloads_and_certifies_them(tmp_path):
    """Lumped mode needs two payloads (k from the payload's own torque): the design uses
    both and reports its Kiefer-Wolfowitz certificate."""
    _cell(tmp_path, "lumped = true")
    run = run_cli(
        tmp_path,
        "design",
        "--robot",
        "cell.toml",
        "--poses",
        "40",
        "--payloads",
        "0,165",
        "--json",
        "-o",
        "designed.csv",
    )
    assert run.returncode == 0, run.stderr
    doc = json.loads(run.stdout)
    certified = doc["certified_d_efficiency"]
    assert 0.95 <= certified <= 1.0
    payloads = np.loadtxt(tmp_path / "designed.csv", delimiter=",", skiprows=1)[:, -1]
    assert set(payloads) == {0.0, PAYLOAD}
    checked = run_cli(tmp_path, "evaluate", "--robot", "cell.toml", "--plan", "designed.csv")
    assert checked.returncode == 0, checked.stderr


def test_a_lumped_calibration_under_one_payload_warns_under_another(tmp_path):
    """With one payload the lumped weights hold it: another payload is not predicted."""
    _cell(tmp_path, "lumped = true")
    plan = (tmp_path / "plan.csv").read_text().replace(",0\n", ",165\n")  # every pose at 165
    (tmp_path / "plan.csv").write_text(plan)
    _synthesize(tmp_path, "plan.csv", "meas.csv", "--sigma", "0.02")
    fit = run_cli(
        tmp_path,
        "identify",
        "--robot",
        "cell.toml",
        "--measurements",
        "meas.csv",
        "-o",
        "cal.json",
    )
    assert fit.returncode == 0, fit.stderr
    assert (
        "k2" not in json.loads((tmp_path / "cal.json").read_text())["elastostatic"]["parameters"]
    )
    program = "q1_deg,q2_deg,q3_deg,q4_deg,q5_deg,q6_deg\n10,20,-30,40,50,60\n"
    (tmp_path / "program.csv").write_text(program)
    run = run_cli(
        tmp_path,
        "compensate",
        "--calibration",
        "cal.json",
        "--program",
        "program.csv",
        "--payload-kg",
        "0",
        "--target",
        "A",
        "-o",
        "out.csv",
    )
    assert run.returncode == 0, run.stderr
    assert "deflection under payloads of 0 kg is not predicted" in run.stderr
    assert "armcal: warning: program.csv: " in run.stderr  # the warning names the program


def test_tip_force_columns_are_refused_for_a_spatial_arm(tmp_path):
    _cell(tmp_path)
    _synthesize(tmp_path, "plan.csv", "meas.csv", "--sigma", "0.02")
    lines = (tmp_path / "meas.csv").read_text().splitlines()
    forced = [lines[0] + ",fx_N"] + [line + ",10" for line in lines[1:]]
    (tmp_path / "forced.csv").write_text("\n".join(forced) + "\n")
    run = run_cli(tmp_path, "identify", "--robot", "cell.toml", "--measurements", "forced.csv")
    assert run.returncode == 2
    assert "payloads (payload_kg), not tip forces" in run.stderr


def test_conditions_copied_for_other_readings_do_not_share_their_loads():
    """A copy by dataclasses.replace (another q) computes its own loads, and two models
    whose default payloads differ do not share theirs on the same rows."""
    import dataclasses

    from armcal.models import Conditions

    q, loads = _poses(4, 13)
    model = CompliantSpatialArm.for_loads(_arm(), _elastics(), loads)
    rows = Conditions(q)
    first = model.load_terms(rows)
    moved = model.load_terms(dataclasses.replace(rows, q=q + 0.3))
    assert not np.allclose(first, moved)
    light = CompliantSpatialArm(model.arm, dataclasses.replace(model.elastic, payload_kg=0.0))
    assert not np.allclose(light.load_terms(rows), first)


def test_held_compliance_is_neither_tested_nor_shown():
    """The F test of compliance counts its free parameters only (k2..k5 here, 4; not k1, k6,
    which gravity does not show)."""
    q, loads = _poses(40, 14)
    model = CompliantSpatialArm.for_loads(_arm(), _elastics(), loads)
    rows, points = _measured(model, q, loads, _truth(model), 0.02, 15)
    cal = identify(model, rows.q, points, target=rows.target, loads=rows.loads, sigma=0.02)
    assert cal.nested is not None
    assert cal.nested.names == ("k2", "k3", "k4", "k5")


def test_tip_forces_and_a_rigid_truths_compliance_are_refused(tmp_path):
    _cell(tmp_path)
    _synthesize(tmp_path, "plan.csv", "meas.csv", "--sigma", "0.02")
    run_cli(
        tmp_path,
        "identify",
        "--robot",
        "cell.toml",
        "--measurements",
        "meas.csv",
        "-o",
        "cal.json",
    )
    program = "q1_deg,q2_deg,q3_deg,q4_deg,q5_deg,q6_deg,fx_N\n10,20,-30,40,50,60,500\n"
    (tmp_path / "program.csv").write_text(program)
    run = run_cli(
        tmp_path,
        "compensate",
        "--calibration",
        "cal.json",
        "--program",
        "program.csv",
        "--target",
        "A",
        "-o",
        "out.csv",
    )
    assert run.returncode == 2 and "not tip forces" in run.stderr
    assert not (tmp_path / "out.csv").exists()
    rigid = (tmp_path / "cell.toml").read_text().split("[elastostatic]")[0]
    (tmp_path / "rigid.toml").write_text(rigid)
    (tmp_path / "truth.toml").write_text(
        (tmp_path / "truth.toml")
        .read_text()
        .replace('robot = "cell.toml"', 'robot = "rigid.toml"')
    )
    plan = [line.rsplit(",", 1)[0] for line in (tmp_path / "plan.csv").read_text().splitlines()]
    (tmp_path / "rigid-plan.csv").write_text("\n".join(plan) + "\n")  # no payload column
    run = _synthesize(tmp_path, "rigid-plan.csv", "rigid.csv", robot="rigid.toml")
    assert run.returncode == 2 and "key 'compliance'" in run.stderr


def test_geometry_alone_on_a_sagging_arm_stops_reweighting_early(tmp_path, monkeypatch):
    """The sag leaves every pose far off a rigid fit: Huber leaves all below full weight,
    round after round.  The reweighting stops after MISFIT_ROUNDS of it, and the document
    is the one iterating the weights to 1e-9 gives (the fit falls back to every pose
    either way)."""
    from armcal.identification import problem, robust

    _cell(tmp_path)
    _synthesize(tmp_path, "plan.csv", "meas.csv", "--sigma", "0.02")
    counted = []
    fit = problem.Problem.fit

    def counting(self, *args, **kwargs):
        counted.append(1)
        return fit(self, *args, **kwargs)

    monkeypatch.setattr(problem.Problem, "fit", counting)
    rigid = (
        "identify",
        "--robot",
        "cell.toml",
        "--measurements",
        "meas.csv",
        "--no-compliance",
        "--json",
    )
    quick = run_cli(tmp_path, *rigid)
    fits_quick = len(counted)
    counted.clear()
    monkeypatch.setattr(robust, "MISFIT_ROUNDS", 10**9)  # the reweighting to 1e-9
    slow = run_cli(tmp_path, *rigid)
    assert quick.returncode == slow.returncode == 0
    assert json.loads(quick.stdout) == json.loads(slow.stdout)
    assert quick.stderr == slow.stderr
    assert fits_quick + 10 < len(counted)
