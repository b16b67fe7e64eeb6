"""The user shapes the compliance terms; an impossible sign is warned of; a rigid export says
what it loses (issue 34).

References independent of the code under test:

* a fit with ``k3`` held at zero is the least-squares fit of every other parameter: its
  residual is orthogonal to their Jacobian columns (the normal equations), and the held
  term's value and std are exactly 0;
* the virtual six-axis arm is ``tests/test_spatial_compliance.py``'s (the built-in
  ``industrial-6r``, three reflectors, link masses 350/150/200/60/20/5 kg at the joints'
  origins, ``k2 = 0.2`` and ``k3 = 0.4`` urad/(N m), 40 poses under 0 and 165 kg, noise
  0.02 mm); a gravity balancer on joint 2 that lifts 400 kg at joint 3's origin twists
  joint 2 as a mass of ``200 - 400 = -200`` kg there would (joint 3's origin is on no
  axis beyond joint 2, and joint 1 is vertical), so the lumped weight at joint 3,
  ``c2.j3 = k2 m g``, is ``0.2e-6 * -200 * 9.80665`` rad/m: -22.5 mdeg/m;
* a planar arm's points are ``sum_i l_i exp(i theta_i)`` (complex notation), and a
  joint's twist under gravity is ``k_j tau_j`` with ``tau_j = -g sum_i m_i x_i`` over
  the centres of mass beyond joint ``j`` (lever arms in m, gravity along ``-y``);
* a registration is checked against :func:`scipy.optimize.least_squares`, another solver
  of the same least-squares problem.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from scipy.optimize import least_squares

from armcal.export_rigid import rigid_export
from armcal.files import (
    load_robot,
    load_spatial_robot,
    load_spatial_truth,
    read_calibration,
    read_measurements,
)
from armcal.identification import identify
from armcal.models import (
    STANDARD_GRAVITY,
    CalibratedArm,
    CompliantArm,
    CompliantSpatialArm,
    Conditions,
    Elastostatic,
    LinkMasses,
    Loads,
    PlanarArm,
    SpatialElastics,
)
from armcal.workflow import export_files
from helpers import VERTICAL_3LINK, cell_toml, planar_cell, run_cli

# -- a planar vertical arm with its masses known ----------------------------------------

PLANAR = VERTICAL_3LINK


def _identify(folder: Path, robot: str, *options: str):
    run = run_cli(
        folder, "identify", "--robot", robot, "--measurements", "meas.csv", "-o", "cal.json",
        *options,
    )  # fmt: skip
    assert run.returncode == 0, run.stderr
    return run, json.loads((folder / "cal.json").read_text())


def _entries(doc: dict) -> dict[str, dict]:
    return {p["name"]: p for p in doc["parameters"]}


def _held_by_the_user(run, doc: dict, folder: Path, name: str) -> None:
    """``name`` held at 0 (std 0, not identified), listed fixed in the file and read back so,
    and the report saying the user holds it."""
    entry = _entries(doc)[name]
    assert entry["fixed"] and entry["value"] == 0.0 and entry["std"] == 0.0
    assert name in doc["fixed"]
    assert f"{name} is held by the user" in run.stdout
    shown = [line.split()[0] for line in run.stdout.splitlines() if line[:1].isalnum()]
    assert name not in shown  # not a row of the table of identified values
    cal = read_calibration(folder / "cal.json")
    i = cal.model.param_names.index(name)
    assert not cal.model.free[i] and cal.params[i] == 0.0 and name in cal.model.fixed
    assert name not in cal.model.free_names


@pytest.mark.parametrize("how", ["robot file", "--fix"])
def test_a_planar_compliance_term_is_held_by_the_robot_file_or_fix(tmp_path, how):
    table = (
        '[identify]\nfixed = ["k3"]\n' if how == "robot file" else '[identify]\nfixed = ["dl1"]\n'
    )
    planar_cell(tmp_path, table)
    options = () if how == "robot file" else ("--fix", "k3")  # replaces the file's dl1
    run, doc = _identify(tmp_path, "robot.toml", *options)
    _held_by_the_user(run, doc, tmp_path, "k3")
    assert not _entries(doc)["dl1"]["fixed"]
    # the same fit as the model without k3's column: k3 = 0 moves no point
    cal = read_calibration(tmp_path / "cal.json")
    model = cal.model
    assert isinstance(model, CompliantArm)
    free = np.flatnonzero(model.free)
    assert model.param_names[free[-1]] == "k2" and model.n_free == model.n_params - 1
    # validation reads the file's model: k3 stays held and the held-out rows are predicted
    checked = run_cli(
        tmp_path, "validate", "--calibration", "cal.json", "--measurements", "meas.csv", "--json"
    )
    assert checked.returncode == 0, checked.stderr


def test_a_planar_fit_with_a_held_term_is_the_least_squares_fit_of_the_others(tmp_path):
    planar_cell(tmp_path)
    spec = load_robot(tmp_path / "robot.toml")
    meas = read_measurements(tmp_path / "meas.csv", spec.arm)
    loads = meas.loads(10.0)
    model = spec.elastic.model_for(spec.arm, loads)
    whole = identify(model, meas.q, meas.xy, loads=loads)
    assert abs(whole["k3"].value - 6.0) < 3 * whole["k3"].std  # free: the truth's, 6.0
    held = identify(model.with_fixed(["k3"]), meas.q, meas.xy, loads=loads)
    assert held["k3"].fixed and held["k3"].value == 0.0 and held["k3"].std == 0.0
    assert held.model.free_names == tuple(n for n in model.param_names if n != "k3")
    # the optimality of least squares over every parameter but k3 (isotropic noise: no
    # weights): the residual is orthogonal to each of their columns, to round-off
    rows = held.conditions
    residual = (meas.xy - model.positions(rows, held.params)).ravel()
    jac = model.jacobian(rows, held.params).reshape(-1, model.n_params)
    others = [i for i, name in enumerate(model.param_names) if name != "k3"]
    cosines = jac[:, others].T @ residual / np.linalg.norm(jac[:, others], axis=0)
    assert np.max(np.abs(cosines)) <= 1e-8 * np.linalg.norm(residual)
    k3 = model.param_names.index("k3")  # and not to k3's: holding it costs a fit
    assert abs(jac[:, k3] @ residual) > 1e-3 * np.linalg.norm(jac[:, k3]) * np.linalg.norm(
        residual
    )


def test_a_planar_free_list_names_the_only_terms_identified(tmp_path):
    planar_cell(tmp_path, '[identify]\nfree = ["k1", "k2"]\n')
    run, doc = _identify(tmp_path, "robot.toml")
    _held_by_the_user(run, doc, tmp_path, "k3")
    entries = _entries(doc)
    # the list names no geometric parameter: the geometry stays free
    assert not any(entries[n]["fixed"] for n in ("dl1", "dl2", "dl3", "dq1", "dq2", "dq3"))
    for name, truth in (("k1", 1.5), ("k2", 3.0)):
        assert not entries[name]["fixed"]
        assert abs(entries[name]["value"] - truth) < 4 * entries[name]["std"], name


@pytest.mark.parametrize(
    ("options", "table", "words"),
    [
        (("--fix", "k9"), "", "unknown parameter 'k9'"),
        (("--fix", "k1,k2,k3"), "", "every term of the joint compliance (k1, k2, k3) would be"),
        ((), '[identify]\nfixed = ["c1"]\n', "key 'identify.fixed': unknown parameter 'c1'"),
    ],
)
def test_bad_choices_of_terms_are_one_line_errors(tmp_path, options, table, words):
    planar_cell(tmp_path)
    (tmp_path / "robot.toml").write_text(PLANAR + table)
    run = run_cli(
        tmp_path, "identify", "--robot", "robot.toml", "--measurements", "meas.csv", *options
    )
    assert run.returncode == 2
    assert run.stderr.startswith("armcal: error:") and words in run.stderr, run.stderr
    assert len(run.stderr.strip().splitlines()) == 1
    if "unknown" in words:  # the error lists the terms there are
        assert "k1, k2, k3" in run.stderr


# -- the virtual six-axis arm ---------------------------------------------------------

MASSES = [350.0, 150.0, 200.0, 60.0, 20.0, 5.0]
PAYLOAD = 165.0
K2, K3 = 0.2e-6, 0.4e-6  # rad/(N m)
TARGETS = {"A": [100.0, 0.0, 150.0], "B": [-50.0, 86.6, 150.0], "C": [-50.0, -86.6, 150.0]}


def _six_axis_cell(folder: Path, identify_table: str = "") -> None:
    """The lumped cell of ``test_spatial_compliance.py`` (its robot TOML with ``lumped =
    true``, its truth) and 30 measured poses under 0 and 165 kg."""
    from armcal.files.spatial import BUILTIN_SPATIAL_ROBOTS

    source = BUILTIN_SPATIAL_ROBOTS["industrial-6r"]
    (folder / "industrial-6r.urdf").write_text(source.with_suffix(".urdf").read_text())
    (folder / "cell.toml").write_text(cell_toml(lumped=True, extra=identify_table))
    (folder / "truth.toml").write_text(
        'robot = "truth-robot.toml"\n'
        "base = { xyz_mm = [2850.0, -1700.0, -650.0], rpy_deg = [0.3, -0.2, 120.0] }\n"
        '[errors]\n"j2.y" = -0.2\ndq3 = -0.03\n[compliance]\nk2 = 0.2\nk3 = 0.4\n'
    )
    # the truth's robot: the cell with its masses known (lumped weights follow from them)
    robot = (folder / "cell.toml").read_text().split("[identify]")[0]
    (folder / "truth-robot.toml").write_text(
        robot.replace("lumped = true", f"link_masses_kg = {MASSES}")
    )
    arm = load_spatial_robot(folder / "cell.toml").arm
    lo, hi = arm.joint_limits.T
    q = lo + (hi - lo) * np.random.default_rng(11).random((30, 6))
    rows = ["q1_deg,q2_deg,q3_deg,q4_deg,q5_deg,q6_deg,payload_kg"]
    for i, pose in enumerate(np.degrees(q)):
        rows.append(",".join(f"{v:.6f}" for v in pose) + f",{0 if i % 2 else PAYLOAD:g}")
    (folder / "plan.csv").write_text("\n".join(rows) + "\n")
    made = run_cli(
        folder, "synthesize", "--robot", "truth-robot.toml", "--plan", "plan.csv",
        "--truth", "truth.toml", "--sigma", "0.02", "--seed", "1", "-o", "meas.csv",
    )  # fmt: skip
    assert made.returncode == 0, made.stderr


def test_six_axis_terms_are_held_by_the_robot_file_or_fix_and_freed_by_name(tmp_path):
    _six_axis_cell(tmp_path, '[identify]\nfixed = ["c2.j3"]\n')
    run, doc = _identify(tmp_path, "cell.toml")
    _held_by_the_user(run, doc, tmp_path, "c2.j3")
    # --fix replaces the robot file's set: c2.j3 is free again, k4 held
    run, doc = _identify(tmp_path, "cell.toml", "--fix", "k4")
    _held_by_the_user(run, doc, tmp_path, "k4")
    assert not _entries(doc)["c2.j3"]["fixed"]
    # held by the rule, with why, and apart from what the user holds
    assert "k1 cannot be seen" in " ".join(doc["elastostatic"]["merges"])
    assert "k4" not in " ".join(doc["elastostatic"]["merges"])
    # free names the only terms identified: the rest of the compliance is the user's
    robot = (tmp_path / "cell.toml").read_text()
    (tmp_path / "cell.toml").write_text(robot.replace('fixed = ["c2.j3"]', 'free = ["k2", "k3"]'))
    run, doc = _identify(tmp_path, "cell.toml")
    entries = _entries(doc)
    compliance = doc["elastostatic"]["parameters"]
    fitted = [n for n in compliance if not entries[n]["fixed"]]
    assert fitted == ["k2", "k3"]
    sentence = next(line for line in run.stdout.splitlines() if "held by the user" in line)
    assert "c2.j3" in sentence and "k4" in sentence and "k2" not in sentence
    assert not entries["j2.y"]["fixed"]  # the geometry as the rule chooses


@pytest.mark.parametrize(
    ("free", "words"),
    [
        # the rule holds k1 (joint 1 is vertical): refused with its reason
        ('["k1", "k2"]', "free lists k1, which these rows cannot identify (k1 cannot be seen"),
        # the spherical wrist: stations j4 and j5 are one (either alone is identified)
        ('["c2.j4", "c2.j5"]', "lists c2.j5, which these rows cannot identify (c2.j5 merges"),
    ],
)
def test_freeing_a_term_the_rows_cannot_identify_is_refused_with_why(tmp_path, free, words):
    _six_axis_cell(tmp_path, f"[identify]\nfree = {free}\n")
    run = run_cli(tmp_path, "identify", "--robot", "cell.toml", "--measurements", "meas.csv")
    assert run.returncode == 2, run.stderr
    assert words in run.stderr and "leave it out of free" in run.stderr, run.stderr
    assert len(run.stderr.strip().splitlines()) == 1


def test_freeing_k_under_one_payload_is_refused(tmp_path):
    """Lumped mode under one payload has no k: a free list that names one is refused."""
    _six_axis_cell(tmp_path, '[identify]\nfree = ["k2"]\n')
    lines = (tmp_path / "meas.csv").read_text().splitlines()
    header = lines[0].split(",")
    at = header.index("payload_kg")
    one = [lines[0]] + [
        ",".join(v if j != at else "0" for j, v in enumerate(line.split(",")))
        for line in lines[1:]
    ]
    (tmp_path / "meas.csv").write_text("\n".join(one) + "\n")
    run = run_cli(tmp_path, "identify", "--robot", "cell.toml", "--measurements", "meas.csv")
    assert run.returncode == 2
    assert "free lists k2, which these rows cannot identify" in run.stderr
    assert "payloads that vary" in run.stderr


# -- a compliance term with an impossible sign ------------------------------------------


def _six_axis_rows(balancer_kg: float, *, lumped: bool):
    """``test_spatial_compliance.py``'s virtual arm (40 poses, seed 6; noise 0.02 mm,
    seed 7), joint 2 relieved by a balancer of ``balancer_kg`` at joint 3's origin (module
    notes), and the model a fit uses (lumped, or with the robot file's masses)."""
    spec = load_spatial_robot("industrial-6r")
    arm = spec.arm.replace(
        targets=tuple(TARGETS), target_positions=np.array(list(TARGETS.values())), view=None
    )
    lo, hi = arm.joint_limits.T
    q = lo + (hi - lo) * np.random.default_rng(6).random((40, 6))
    loads = Loads.create(40, np.where(np.arange(40) % 2, 0.0, PAYLOAD))
    mass = np.array(MASSES)
    mass[2] -= balancer_kg
    gravity = np.array([0.0, 0.0, -STANDARD_GRAVITY])
    pulled = SpatialElastics(
        gravity, LinkMasses(mass, np.zeros((6, 3))), PAYLOAD, np.array([0, 0, 100.0])
    )
    virtual = CompliantSpatialArm.for_loads(arm, pulled, loads, virtual=True)
    compliance = np.zeros(virtual.n_compliance)
    compliance[virtual.compliance_names.index("k2")] = K2
    compliance[virtual.compliance_names.index("k3")] = K3
    truth = np.concatenate([load_spatial_truth(spec.default_truth, virtual.arm), compliance])
    rows = virtual.plan_conditions(q, loads)
    points = virtual.positions(rows, truth)
    points = points + np.random.default_rng(7).normal(0.0, 0.02, points.shape)
    elastic = SpatialElastics.create(
        6,
        mass_kg=None if lumped else MASSES,
        com_mm=None if lumped else np.zeros((6, 3)),
        payload_kg=PAYLOAD,
        payload_com_mm=[0.0, 0.0, 100.0],
    )
    model = CompliantSpatialArm.for_loads(arm, elastic, loads)
    return identify(model, rows.q, points, target=rows.target, loads=rows.loads, sigma=0.02)


@pytest.mark.parametrize("lumped", [True, False])
def test_no_negative_compliance_is_warned_of_on_the_issues_virtual_arm(lumped):
    cal = _six_axis_rows(0.0, lumped=lumped)
    assert "compliance-negative" not in [w.code for w in cal.warnings]


def test_a_balancer_the_model_lacks_gives_a_negative_weight_and_a_warning():
    cal = _six_axis_rows(400.0, lumped=True)
    expected = K2 * (MASSES[2] - 400.0) * STANDARD_GRAVITY * 1e3 * 180 / np.pi  # mdeg/m
    assert abs(cal["c2.j3"].value - expected) < 3 * cal["c2.j3"].std  # -22.5 mdeg/m
    warned = [w for w in cal.warnings if w.code == "compliance-negative"]
    assert len(warned) == 1
    text = warned[0].message
    assert "c2.j3 = -" in text and "std below 0" in text
    assert "gravity balancer" in text and "link masses" in text and "barely excite" in text
    assert "hold it at zero" in text and "[identify]" in text
    # only c2.j3 is named: every other term is within 3 std of 0 or positive
    named = [n for n in cal.names if f"{n} = " in text]
    assert named == ["c2.j3"]
    # held as the warning advises, the term is 0 and the warning gone
    held = identify(
        cal.model.with_fixed(["c2.j3"]),
        cal.conditions.q,
        cal.model.positions(cal.conditions, cal.params) + cal.residuals,
        target=cal.conditions.target,
        loads=cal.conditions.loads,
        sigma=0.02,
    )
    assert held["c2.j3"].value == 0.0 and held["c2.j3"].fixed
    assert "c2.j3 = " not in " ".join(w.message for w in held.warnings)


# -- what a rigid export loses ---------------------------------------------------------


def test_the_rigid_export_figures_equal_an_independent_computation(tmp_path):
    _six_axis_cell(tmp_path)
    _identify(tmp_path, "cell.toml")
    doc = json.loads((tmp_path / "cal.json").read_text())
    stored = doc["training_rows"]
    # the rows stored are the measurement file's (readings in rad), every target's
    header = (tmp_path / "meas.csv").read_text().splitlines()[0].split(",")
    columns = [header.index(f"q{j}_deg") for j in range(1, 7)]
    meas = np.loadtxt(tmp_path / "meas.csv", delimiter=",", skiprows=1, usecols=columns)
    np.testing.assert_allclose(stored["q"], np.radians(meas), rtol=0, atol=1e-12)
    assert len(stored["payload_kg"]) == meas.shape[0] == 90
    cal = read_calibration(tmp_path / "cal.json")
    rows = Conditions(
        np.array(stored["q"]), np.array(stored["target"]), Loads.create(90, stored["payload_kg"])
    )
    model, arm = cal.model, cal.model.nested
    compliant = model.positions(rows, cal.params)
    geometry = model.arm_params(cal.params)
    distance = np.linalg.norm(compliant - arm.positions(rows, geometry), axis=1)
    lost = rigid_export(cal)
    assert lost is not None and lost.rows == 90
    assert lost.rms_per_point_mm == pytest.approx(np.sqrt(np.mean(distance**2)), rel=1e-12)
    assert lost.max_mm == pytest.approx(np.max(distance), rel=1e-12)

    def registered(start: np.ndarray) -> np.ndarray:
        """Distances after fitting the instrument's free parameters by another solver."""
        free = np.flatnonzero(arm.instrument_params & arm.free)

        def miss(x):
            p = start.copy()
            p[free] = x
            return (compliant - arm.positions(rows, p)).ravel()

        found = least_squares(miss, start[free], xtol=1e-15, ftol=1e-15, gtol=1e-15)
        return np.linalg.norm(found.fun.reshape(-1, 3), axis=1)

    again = registered(geometry)
    nominal = registered(np.where(arm.instrument_params, geometry, 0.0))
    # both solvers stop at the least-squares minimum, where the RMS is flat: they agree to
    # 1e-13 of it (measured), the max (first order in the parameters) to 2e-7
    assert lost.registered_rms_per_point_mm == pytest.approx(np.sqrt(np.mean(again**2)), rel=1e-9)
    assert lost.nominal_rms_per_point_mm == pytest.approx(np.sqrt(np.mean(nominal**2)), rel=1e-9)
    assert lost.registered_max_mm == pytest.approx(np.max(again), rel=1e-5)
    assert lost.nominal_max_mm == pytest.approx(np.max(nominal), rel=1e-5)
    # the command says it, in mm per point, in the text and the JSON
    run = run_cli(tmp_path, "export", "--calibration", "cal.json", "--urdf", "out.urdf", "--json")
    assert run.returncode == 0, run.stderr
    shown = json.loads(run.stdout)["rigid_export"]
    assert shown["rms_per_point_mm"] == pytest.approx(lost.rms_per_point_mm, rel=1e-12)
    assert f"by {lost.rms_per_point_mm:.3g} mm RMS per point (max {lost.max_mm:.3g} mm)" in (
        run.stderr
    )
    assert f"nominal arm so fitted misses them by {lost.nominal_rms_per_point_mm:.3g} mm" in (
        run.stderr
    )
    # this cell's geometry (j2.y and dq3 off nominal) exported rigid still beats the nominal
    assert not shown["worse_than_nominal"] and "rigid-export-worse" not in run.stderr


def _planar_points(lengths, theta: np.ndarray) -> np.ndarray:
    """A planar arm's tip ``(m, 2)`` at absolute link angles ``theta`` ``(m, n)``."""
    tip = np.sum(np.asarray(lengths) * np.exp(1j * theta), axis=1)
    return np.column_stack([tip.real, tip.imag])


def test_a_rigid_export_worse_than_the_nominal_arm_says_so():
    """A joint zero that holds the opposite of the mean sag: the compliant model is near the
    nominal arm, the exported geometry (the zero without the sag) is not."""
    arm = PlanarArm([500.0, 300.0])
    elastic = Elastostatic.create(2, gravity_xy=[0, -1], link_masses_kg=[10.0, 4.0])
    model = CompliantArm.for_loads(arm, elastic, Loads.create(1))
    q = np.radians(np.stack(np.meshgrid(np.linspace(-10, 10, 5), np.linspace(-10, 10, 5)), -1))
    q = q.reshape(-1, 2)
    k1, zero = 2e-6, 1e-4  # rad/(N m), rad: the sag of the level arm is -1.0e-4 rad
    params = np.array([0.0, 0.0, zero, 0.0, k1, 0.0])
    rows = model.conditions(q)
    cal = CalibratedArm(model, params, np.zeros((6, 6)), 0.02, training_rows=rows)
    # by hand: the torque on joint 1 of the arm at q + zero (module notes), its twist
    a1, a12 = q[:, 0] + zero, q[:, 0] + zero + q[:, 1]
    lever = 10 * 0.25 * np.cos(a1) + 4 * (0.5 * np.cos(a1) + 0.15 * np.cos(a12))  # kg m
    twist = k1 * -STANDARD_GRAVITY * lever
    compliant = _planar_points([500, 300], np.column_stack([a1 + twist, a12 + twist]))
    rigid = _planar_points([500, 300], np.column_stack([a1, a12]))
    nominal = _planar_points([500, 300], np.column_stack([q[:, 0], q.sum(axis=1)]))
    lost = rigid_export(cal)
    assert lost is not None
    # no instrument pose to fit (2-D data, no base offset): registered = as calibrated
    rigid_rms = np.sqrt(np.mean(np.sum((compliant - rigid) ** 2, axis=1)))
    nominal_rms = np.sqrt(np.mean(np.sum((compliant - nominal) ** 2, axis=1)))
    assert lost.rms_per_point_mm == pytest.approx(rigid_rms, rel=1e-9)
    assert lost.registered_rms_per_point_mm == pytest.approx(rigid_rms, rel=1e-9)
    assert lost.nominal_rms_per_point_mm == pytest.approx(nominal_rms, rel=1e-9)
    assert rigid_rms > 10 * nominal_rms  # 0.079 mm against 0.0008 mm, the sag's change
    run = export_files(cal, robot_toml_path="out.toml")
    codes = [w.code for w in run.warnings]
    assert codes == ["compliance-not-exported", "rigid-export-worse"]
    worse = run.warnings[1].message
    assert "WORSE than the nominal arm" in worse
    assert f"{rigid_rms:.3g} mm against {nominal_rms:.3g} mm RMS per point" in worse
    assert "fit the geometry alone" in worse


def test_a_calibration_file_without_rows_exports_without_the_figure(tmp_path):
    planar_cell(tmp_path)
    _identify(tmp_path, "robot.toml")
    doc = json.loads((tmp_path / "cal.json").read_text())
    assert len(doc["training_rows"]["q"]) == 40
    doc["training_rows"] = None  # a file written before the rows were stored
    (tmp_path / "old.json").write_text(json.dumps(doc))
    run = run_cli(
        tmp_path, "export", "--calibration", "old.json", "--robot-toml", "r.toml", "--json"
    )
    assert run.returncode == 0, run.stderr
    assert "rigid_export" not in json.loads(run.stdout)
    assert "compliance-not-exported" in run.stdout
    rows = {"q": [[0, 0]], "target": None, "payload_kg": [0.0], "force_n": None}  # 2 of 3 joints
    bad = dict(doc, training_rows=rows)
    (tmp_path / "bad.json").write_text(json.dumps(bad))
    run = run_cli(tmp_path, "export", "--calibration", "bad.json", "--robot-toml", "r.toml")
    assert run.returncode == 2 and "key 'training_rows'" in run.stderr, run.stderr


# -- the unit of every RMS the compliance paths print -----------------------------------


def test_the_compliance_lines_say_per_coordinate(tmp_path):
    planar_cell(tmp_path)
    run, _ = _identify(tmp_path, "robot.toml")
    line = next(x for x in run.stdout.splitlines() if "geometry alone leaves" in x)
    assert line.count("per coordinate") == 2, line
