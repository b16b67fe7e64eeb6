"""Judgements the second bad-input battery found wanting (issue 34).

* A robot file whose ``joint_map`` reads the joints another way than the controller
  reports them is named (``coupled-joints``) in both directions, for a planar arm
  (the identity map where the default relative map is needed, and the other way
  round: every reading of the chain is wrong, not one pair) and for a spatial arm
  whose URDF has a calibration's small errors folded in (its J2 and J3 axes are
  parallel to a calibration's tilt, not to round-off).
* A fixed instrument parameter (a spatial arm's base pose) is said to be held at the
  value registered from the data, not at a nominal value.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from armcal.demo_spatial import DEMO_REFLECTORS
from armcal.doe import random_plan
from armcal.errors import ArmcalError
from armcal.files import format_measurements_csv, load_spatial_robot, load_spatial_truth
from armcal.files.spatial import ROBOT_FOLDER
from armcal.identification import identify
from armcal.models import PlanarArm
from armcal.noise import NoiseModel
from armcal.synthesis import synthesize_measurements
from helpers import run_cli

# --------------------------------------------------------------------------- joint maps

#: The planar bench of the battery (b.toml): 300/200/100 mm, tracker noise 0.05 mm.
LINKS = [300.0, 200.0, 100.0]
PLANAR_SIGMA = 0.05  # mm
#: The default joint map of a planar arm (PRODUCT.md: theta_i = q_1 + ... + q_i).
RELATIVE = "[[1, 0, 0], [1, 1, 0], [1, 1, 1]]"
ABSOLUTE = "[[1, 0, 0], [0, 1, 0], [0, 0, 1]]"


def _coupled_message(warnings) -> str | None:
    return next((w.message for w in warnings if w.code == "coupled-joints"), None)


def _planar_data(reading_map: np.ndarray, seed: int):
    """Readings of the bench at 15 random poses and its points under a controller whose
    link angles are ``reading_map @ q``, with small errors (1 mm, 0.3 deg) and noise."""
    arm = PlanarArm(LINKS, sigma=PLANAR_SIGMA)  # no limits: the readings may be absolute
    q = random_plan(arm, 15, rng=seed)
    controller = arm.replace(joint_map=reading_map)
    truth = controller.params_from_display([1.0, -0.5, 0.8], [0.3, -0.2, 0.4])
    rng = np.random.default_rng(seed + 1)
    points = controller.positions(controller.conditions(q), truth)
    return arm, q, points + rng.normal(0.0, PLANAR_SIGMA, points.shape)


def test_relative_readings_under_an_identity_joint_map_are_named():
    """The battery's bid.toml: joint_map the identity (readings taken for absolute link
    angles), the data relative (the default map).  No one pair explains it (J3 needs
    J1 + J2 + J3); the running sums of the whole chain do, and the warning gives the
    default map to set.  The right file fits without the warning."""
    arm, q, points = _planar_data(np.tril(np.ones((3, 3))), seed=3)
    wrong = arm.replace(joint_map=np.eye(3))
    message = _coupled_message(identify(wrong, q, points).warnings)
    assert message is not None
    assert "read with J2 as J1 + J2, J3 as J1 + J2 + J3" in message
    assert f"joint_map = {RELATIVE}" in message
    assert _coupled_message(identify(arm, q, points).warnings) is None


def test_absolute_readings_under_the_default_joint_map_are_named():
    """The other way round: a controller reporting each link's absolute angle, the robot
    file without joint_map (relative): differences of consecutive readings, the identity
    map."""
    arm, q, points = _planar_data(np.eye(3), seed=4)
    message = _coupled_message(identify(arm, q, points).warnings)
    assert message is not None
    assert "read with J2 as J2 - J1, J3 as J3 - J2" in message
    assert f"set joint_map = {ABSOLUTE} in the robot file" in message
    right = arm.replace(joint_map=np.eye(3))
    assert _coupled_message(identify(right, q, points).warnings) is None


#: A calibration's tilt of J3's axis (rad): the built-in truth's errors are 0.01-0.05 deg
#: (its file), 0.03 deg = 5.2e-4 rad; an exported calibrated URDF carries such a tilt.
TILT = float(np.radians(0.03))


def _tilted_robot(folder: Path, joint_map: bool) -> Path:
    """The industrial-6r's URDF with joint_3 tilted by TILT about y, and its robot TOML
    (the built-in's keys, with or without its J2/J3 joint_map)."""
    text = (ROBOT_FOLDER / "industrial-6r.urdf").read_text(encoding="utf-8")
    old = '<origin xyz="1.075 0 0" rpy="3.1415926535897931 0 0"/>'
    assert old in text  # the built-in's joint_3, as shipped
    (folder / "tilted.urdf").write_text(
        text.replace(old, f'<origin xyz="1.075 0 0" rpy="3.1415926535897931 {TILT!r} 0"/>'),
        encoding="utf-8",
    )
    robot = folder / "tilted.toml"
    mapping = "joint_map = [[1,0,0,0,0,0],[0,1,0,0,0,0],[0,1,1,0,0,0],[0,0,0,1,0,0],"
    mapping += "[0,0,0,0,1,0],[0,0,0,0,0,1]]\n"
    robot.write_text(
        'name = "tilted"\nurdf = "tilted.urdf"\nbase_link = "base_link"\ntip_link = "flange"\n'
        + (mapping if joint_map else ""),
        encoding="utf-8",
    )
    return robot


def test_a_forgotten_joint_map_is_named_under_a_calibrated_urdf(tmp_path):
    """The battery's t8.toml: an exported (calibrated) URDF of the industrial-6r, whose
    J2 and J3 axes are parallel only to a calibration's tilt, without the FANUC map,
    fitted to the built-in arm's data (coupled J2/J3): the fit diverged silently
    (j3.x = 1.85e7 mm); the coupling is named, with its fix, and the file with the map has
    no warning."""
    spec = load_spatial_robot("industrial-6r")
    sigma = 0.03  # mm
    truth_model = spec.arm.replace(
        targets=tuple(DEMO_REFLECTORS),
        target_positions=np.array(list(DEMO_REFLECTORS.values())),
        view=None,
    ).with_noise(NoiseModel.isotropic(sigma, dim=3))
    truth = load_spatial_truth(spec.default_truth, truth_model)
    rng = np.random.default_rng(2)
    rows = truth_model.plan_conditions(random_plan(truth_model, 20, rng=rng))
    points = synthesize_measurements(truth_model, rows.q, truth, rng=rng, target=rows.target)

    def fitted(joint_map: bool):
        arm = load_spatial_robot(_tilted_robot(tmp_path, joint_map)).arm
        model = arm.replace(
            targets=tuple(DEMO_REFLECTORS), target_positions=np.zeros((0, 3)), view=None
        ).with_noise(NoiseModel.isotropic(sigma, dim=3))
        return identify(model, rows.q, points, target=rows.target).warnings

    # Without the map the fit diverges to an estimate of no meaning (tens of km): where its
    # Jacobian is still regular, the coupling is a warning; where it is singular (which
    # round-off decides), the error says it.
    try:
        message = _coupled_message(fitted(joint_map=False))
    except ArmcalError as error:
        assert str(error).startswith("the Jacobian is singular at the estimate; ")
        message = str(error)
    assert message is not None
    assert "couples J2 and J3" in message and "read with J3 as J3 + J2" in message
    assert "add joint_map = [[1, 0, 0, 0, 0, 0], [0, 1, 0, 0, 0, 0], [0, 1, 1, 0" in message
    assert _coupled_message(fitted(joint_map=True)) is None


# --------------------------------------------------------------------------- fixed instrument


def test_a_fixed_base_coordinate_is_held_at_its_registered_value_not_at_nominal(tmp_path):
    """``--fix base.x``: the base pose is the instrument's, registered from the data (the
    built-in truth file puts the base metres from the tracker, xyz_mm = [2850, -1700,
    -650], far from any nominal 0); the report says where the held value comes from,
    and keeps "held at nominal" for a robot parameter fixed with it."""
    spec = load_spatial_robot("industrial-6r")
    model = spec.arm.replace(
        targets=tuple(DEMO_REFLECTORS),
        target_positions=np.array(list(DEMO_REFLECTORS.values())),
        view=None,
    ).with_noise(NoiseModel.isotropic(0.03, dim=3))
    truth = load_spatial_truth(spec.default_truth, model)
    rng = np.random.default_rng(5)
    rows = model.plan_conditions(random_plan(model, 20, rng=rng))
    points = synthesize_measurements(model, rows.q, truth, rng=rng, target=rows.target)
    labels = [f"P{i + 1}" for i in np.repeat(np.arange(20), len(DEMO_REFLECTORS))]
    text = format_measurements_csv(rows.q, points, labels, [model.targets[t] for t in rows.target])
    (tmp_path / "meas.csv").write_text(text, encoding="utf-8")
    run = run_cli(
        tmp_path, "identify", "--robot", "industrial-6r", "--measurements", "meas.csv",
        "--fix", "base.x", "--fix", "j2.y",
    )  # fmt: skip
    assert run.returncode == 0, run.stderr
    lines = run.stdout.splitlines()
    assert "fixed (held at nominal, not identified): j2.y" in lines
    registered = [line for line in lines if "base.x" in line and line.startswith("fixed")]
    assert registered == [
        "fixed (held at the value registered from the data, where the nominal arm placed on "
        "the measured points puts it; not identified): base.x"
    ]
    shown = next(line for line in lines if line.startswith("base.x "))
    assert abs(float(shown.split()[1])) > 100.0  # the base is metres away: no nominal 0


# --------------------------------------------------------------------------- horizontal compliance

HORIZONTAL = """name = "horizontal"
link_lengths_mm = [600.0, 450.0, 200.0]
[measurement]
sigma_mm = 0.02
[elastostatic]
link_masses_kg = [20, 12, 6]
payload_kg = 10
"""


def test_a_horizontal_compliant_arm_is_told_to_add_gravity_or_forces(tmp_path):
    """The battery's r_horiz.toml: [elastostatic] without gravity_xy is a horizontal arm,
    whose poses and payloads (weight across the plane) twist no joint; the advice is
    gravity_xy or tip forces, not poses "relative to gravity" (there is none)."""
    (tmp_path / "r.toml").write_text(HORIZONTAL, encoding="utf-8")
    arm = PlanarArm([600.0, 450.0, 200.0])
    q = np.degrees(random_plan(arm, 15, rng=7))
    lines = ["q1_deg,q2_deg,q3_deg", *(",".join(f"{v:.6f}" for v in row) for row in q)]
    (tmp_path / "plan.csv").write_text("\n".join(lines) + "\n", encoding="utf-8")
    run = run_cli(tmp_path, "evaluate", "--robot", "r.toml", "--plan", "plan.csv")
    assert run.returncode == 2
    assert "not identifiable: k1, k2 and k3" in run.stderr
    assert "relative to gravity" not in run.stderr
    assert "add gravity_xy if the arm is vertical" in run.stderr
    assert "tip forces that vary (the measurements' fx_N, fy_N columns)" in run.stderr


# --------------------------------------------------------------------------- validation headline

BENCH = """name = "bench"
link_lengths_mm = [300, 200, 100]
[measurement]
sigma_mm = 0.05
"""


def _bench_csv(path: Path, q: np.ndarray, points: np.ndarray) -> None:
    lines = ["q1_deg,q2_deg,q3_deg,x_mm,y_mm"]
    table = np.column_stack([np.degrees(q), points])
    lines += [",".join(repr(float(v)) for v in row) for row in table]
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")


def test_the_validation_headline_does_not_call_the_calibration_s_own_rows_held_out(tmp_path):
    """The battery's validate of bcal.json on its own bmeas.csv: warned not-held-out, but
    headlined "on 15 held-out poses".  Here a calibration on 15 rows is validated on 10
    of its own rows and 5 new ones, on its own 15, and on the 5 new ones only."""
    (tmp_path / "b.toml").write_text(BENCH, encoding="utf-8")
    _, q, points = _planar_data(np.tril(np.ones((3, 3))), seed=8)  # the default map
    _bench_csv(tmp_path / "own.csv", q, points)
    _, fresh_q, fresh_points = _planar_data(np.tril(np.ones((3, 3))), seed=9)
    _bench_csv(
        tmp_path / "mixed.csv",
        np.vstack([q[:10], fresh_q[:5]]),
        np.vstack([points[:10], fresh_points[:5]]),
    )
    _bench_csv(tmp_path / "fresh.csv", fresh_q[:5], fresh_points[:5])
    run = run_cli(
        tmp_path, "identify", "--robot", "b.toml", "--measurements", "own.csv", "-o", "cal.json"
    )
    assert run.returncode == 0, run.stderr

    def headline(csv: str) -> str:
        run = run_cli(tmp_path, "validate", "--calibration", "cal.json", "--measurements", csv)
        assert run.returncode == 0, run.stderr
        return run.stdout.splitlines()[0]

    own = "the calibration's own rows, not held out"
    assert headline("mixed.csv") == f"validation of bench on 15 poses (10 of them {own})"
    assert headline("own.csv") == f"validation of bench on 15 poses (all of them {own})"
    assert headline("fresh.csv") == "validation of bench on 5 held-out poses"
