"""One Python API for every family of arm (issue 35, items 4 and 5).

Every entry -- ``design``, ``evaluate_plan``, ``synthesize_measurements``, ``identify``,
``validate``, ``compensate``, ``monte_carlo`` -- takes a six-axis arm with three
reflectors, as loaded (the built-in arm given three targets in Python, and a robot
TOML over the URDF with a ``[targets]`` table), exactly as it takes a planar arm
with three targets: the same calls, the targets by label, the result of
``identify`` handed on as it is.  Then the precedence of ``sigma`` over per-row
sigma, the short reprs and notebook tables of the results, and ``py.typed``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pytest
from numpy.testing import assert_allclose

import armcal
from armcal import ArmcalError, FitModel, PlanarArm, Target, load_robot
from armcal.doe import random_plan

ROOT = Path(__file__).resolve().parents[1]
ROBOTS = ROOT / "src" / "armcal" / "robots"

#: The three reflectors of a nest on the flange (mm, flange frame), as in docs/six-axis.md.
NEST_MM = np.array([[100.0, 0.0, 150.0], [-50.0, 86.6, 150.0], [-50.0, -86.6, 150.0]])
LABELS = ("A", "B", "C")

#: What the points of a plan that moves every joint identify of a six-axis revolute arm
#: measured at k point targets by an instrument whose pose is unknown: 4R + 2P + 3k
#: (Everett, Driels and Mooring's count, armcal.models.spatial.selection).
SIX_AXIS_THREE_TARGETS = 4 * 6 + 3 * 3


@dataclass(frozen=True)
class Family:
    """An arm with three targets as a Python user has it, its truth and a plan."""

    name: str
    arm: FitModel
    truth: np.ndarray
    identified: int  # free parameters a plan moving every joint identifies

    def plan(self, m: int, seed: int) -> np.ndarray:
        return random_plan(self.arm, m, rng=seed)


def _spatial_truth(arm, rng: np.random.Generator) -> np.ndarray:
    """A cell's truth: a tracker 3.4 m away turned by 120 deg about the vertical, joint
    placements off by a few tenths of a mm and a few hundredths of a degree, zeros by
    0.05 deg, reflectors 0.3 mm from their drawing (docs/six-axis.md's setup)."""
    truth = arm.nominal.copy()
    truth[:6] = [3400.0, 200.0, -300.0, 0.01, -0.02, np.radians(120.0)]
    units = np.array(arm.param_units)
    errors = np.arange(6, arm.n_params - 9)  # every joint's placement and zero
    size = np.where(units[errors] == "mm", 0.2, 0.02)  # mm, deg
    truth[errors] += rng.normal(0.0, 1.0, errors.size) * size / arm.display_scale[errors]
    truth[-9:] += rng.normal(0.0, 0.3, 9)
    return truth


def _builtin_six_axis() -> Family:
    arm = load_robot("industrial-6r").arm.replace(targets=LABELS, target_positions=NEST_MM)
    return Family("six-axis", arm, _spatial_truth(arm, np.random.default_rng(4)), 33)


def _urdf_cell(tmp_path: Path) -> Family:
    """A robot TOML over the built-in URDF with a tracker's noise and a [targets] table,
    written as docs/six-axis.md writes it."""
    text = f"""
name = "cell"
urdf = "{(ROBOTS / "industrial-6r.urdf").as_posix()}"
base_link = "base_link"
tip_link = "flange"
joint_map = [[1, 0, 0, 0, 0, 0], [0, 1, 0, 0, 0, 0], [0, 1, 1, 0, 0, 0],
             [0, 0, 0, 1, 0, 0], [0, 0, 0, 0, 1, 0], [0, 0, 0, 0, 0, 1]]
joint_limits_deg = [[-185, 185], [-60, 76], [-132, 150], [-360, 360], [-125, 125], [-360, 360]]

[measurement.tracker]
range_mm = 0.008
range_mm_per_m = 0.0004
transverse_mm = 0.010
transverse_mm_per_m = 0.0025

[targets]
A = {{ xyz_mm = [100, 0, 150] }}
B = {{ xyz_mm = [-50, 86.6, 150] }}
C = {{ xyz_mm = [-50, -86.6, 150] }}
"""
    path = tmp_path / "cell.toml"
    path.write_text(text, encoding="utf-8")
    arm = load_robot(path).arm
    return Family("urdf", arm, _spatial_truth(arm, np.random.default_rng(5)), 33)


def _planar() -> Family:
    """A 3-link planar arm with a nest of three targets and an unknown base position."""
    nest = (Target("A", 120.0, 0.0), Target("B", 95.0, 0.6), Target("C", 140.0, -0.4))
    arm = PlanarArm([260.0, 180.0, 120.0], targets=nest, base_offset=True)
    truth = np.random.default_rng(6).uniform(-1.0, 1.0, arm.n_params) * 0.5  # mm, rad/100
    truth[arm.angle_params] *= 0.01
    return Family("planar", arm, truth, arm.n_params)


@pytest.fixture(params=["planar", "six-axis", "urdf"])
def family(request, tmp_path) -> Family:
    if request.param == "planar":
        return _planar()
    if request.param == "six-axis":
        return _builtin_six_axis()
    return _urdf_cell(tmp_path)


def _rows(family: Family, q: np.ndarray):
    """Every target of every pose as rows, and their target labels."""
    rows = family.arm.plan_conditions(q)
    return rows, [LABELS[t] for t in rows.target]


def _noiseless(family: Family, m: int = 12, seed: int = 2):
    rows, labels = _rows(family, family.plan(m, seed))
    points = armcal.synthesize_measurements(family.arm, rows.q, family.truth, 0.0, target=labels)
    return rows, labels, points


# -- the entries, for every family -----------------------------------------------------


def test_synthesize_takes_labels_and_gives_the_truths_points(family):
    """sigma 0: the points are the model's at the truth, exactly; labels and indices agree."""
    rows, labels = _rows(family, family.plan(5, 1))
    by_label = armcal.synthesize_measurements(family.arm, rows.q, family.truth, 0.0, target=labels)
    by_index = armcal.synthesize_measurements(
        family.arm, rows.q, family.truth, 0.0, target=rows.target
    )
    assert np.array_equal(by_label, by_index)
    assert np.array_equal(by_label, family.arm.positions(rows, family.truth))


def test_identify_recovers_noiseless_data_to_round_off(family):
    """The arm as loaded, the rows' targets by label: the points are fitted to round-off and
    the estimate is the truth as the fit's parameters express it (a spatial arm's held
    parameters merged into the kept ones by exact symmetries, FitModel.expressed)."""
    rows, labels, points = _noiseless(family)
    cal = armcal.identify(family.arm, rows.q, points, target=labels, sigma=0.01)
    assert cal.n_free == family.identified
    # Where the family's theory bounds what rows identify, the fit's model reaches it.
    assert cal.model.rank_bound in (None, family.identified)
    # Round-off: the points lie 3.5 m from the tracker, so 1e-12 of that is 3.5e-9 mm.
    assert_allclose(cal.calibrated().positions(cal.conditions), points, rtol=0, atol=1e-8)
    expected = cal.model.expressed(cal.conditions, family.truth)
    # mm and rad alike: a parameter seen through a 1 m lever moves the points 1e3 times
    # its own change, so round-off of 1e-8 mm in the points is about 1e-8 in it.
    assert_allclose(cal.params, expected, rtol=0, atol=1e-6)
    assert [w.code for w in cal.warnings] == ["fit-too-good"]  # noiseless: chi-square ~ 0


def test_identify_takes_indices_as_labels(family):
    rows, labels, points = _noiseless(family, m=8)
    by_label = armcal.identify(family.arm, rows.q, points, target=labels, sigma=0.01)
    by_index = armcal.identify(family.arm, rows.q, points, target=rows.target, sigma=0.01)
    assert np.array_equal(by_label.params, by_index.params)


def test_a_model_with_several_targets_says_what_to_pass(family):
    rows, _, points = _noiseless(family, m=6)
    for call in (
        lambda: armcal.identify(family.arm, rows.q, points, sigma=0.01),
        lambda: armcal.synthesize_measurements(family.arm, rows.q, family.truth, 0.0),
    ):
        with pytest.raises(ArmcalError, match=r"3 targets \(A, B, C\): give every row's target"):
            call()
    with pytest.raises(ArmcalError, match=r"unknown target 'D'; the model's targets are A, B, C"):
        armcal.identify(family.arm, rows.q, points, target=["D"] * rows.m, sigma=0.01)


def test_evaluate_plan_takes_the_arm_as_loaded(family):
    """The plan's quality on the arm as loaded is that on the model the command line
    prepares for the plan (FitModel.prepared on the plan's rows)."""
    q = family.plan(12, 3)
    test_q = family.plan(5, 4)
    quality = armcal.evaluate_plan(family.arm, q, sigma=0.05, test_q=test_q)
    prepared = family.arm.prepared(family.arm.plan_conditions(q))
    reference = armcal.evaluate_plan(prepared, q, sigma=0.05, test_q=test_q)
    assert quality.model.n_free == family.identified
    # The same Gram matrix, factored once from the preparation's rows and once anew: the
    # same std to round-off (1e-12 relative).
    np.testing.assert_allclose(quality.predicted_std, reference.predicted_std, rtol=1e-12)
    assert quality.position is not None and math.isfinite(quality.position.rms_mm)


def test_monte_carlo_takes_the_arm_as_loaded(family):
    """Noise of 0.01 mm keeps the fit linear: every free parameter's empirical std is its
    predicted one within 5 standard errors of a std from N trials, 1 / sqrt(2 (N - 1))."""
    q = family.plan(10, 5)
    trials = 200
    result = armcal.monte_carlo(family.arm, q, family.truth, 0.01, trials, rng=7)
    assert result.model.n_free == family.identified
    free = result.model.free
    ratio = result.std[free] / result.predicted_std[free]
    assert np.all(np.abs(ratio - 1) <= 5 / np.sqrt(2 * (trials - 1)))
    # the truth as the prepared model's parameters express it (held ones merged)
    rows = result.model.plan_conditions(q)
    assert_allclose(
        result.model.positions(rows, result.truth),
        family.arm.positions(rows, family.truth),
        rtol=0,
        atol=1e-8,
    )


def test_validate_takes_what_identify_returns(family):
    """Held-out poses of the noiseless truth: the calibration misses them by round-off."""
    rows, labels, points = _noiseless(family)
    cal = armcal.identify(family.arm, rows.q, points, target=labels, sigma=0.01)
    held, held_labels = _rows(family, family.plan(4, 9))
    measured = armcal.synthesize_measurements(
        family.arm, held.q, family.truth, 0.0, target=held_labels
    )
    checked = armcal.validate(cal, held.q, measured, target=held_labels)
    assert float(np.max(checked.after_mm)) < 1e-7  # mm: round-off, as above
    assert float(np.min(checked.before_mm)) > 1e-3  # the nominal arm misses by far more
    again = armcal.validate(cal.calibrated(), held.q, measured, target=held.target)
    assert np.array_equal(again.after, checked.after)


def test_compensate_takes_what_identify_returns(family):
    """Noiseless: the true arm at the corrected commands puts every target where the nominal
    arm, standing where the calibration found the instrument and targets, meant it (the
    instrument frame; compensation works in the robot's, a rigid motion of it)."""
    rows, labels, points = _noiseless(family)
    cal = armcal.identify(family.arm, rows.q, points, target=labels, sigma=0.01)
    # Poses away from singularities (a random pose may stretch the arm or line up the
    # wrist; those are kept with a reason: tests/test_compensation_singular.py).
    program, program_labels = _rows(family, family.plan(4, 14))
    result = armcal.compensate(cal, program.q, target=program_labels)
    assert result.corrected.all(), result.reasons
    model = cal.model
    nominal = np.where(model.instrument_params, cal.params, 0.0)
    meant = model.positions(model.conditions(program.q, target=program_labels), nominal)
    reached = family.arm.positions(
        family.arm.conditions(result.q, target=program_labels), family.truth
    )
    assert_allclose(reached, meant, rtol=0, atol=1e-6)  # mm: compensation's 1e-9 and round-off


def test_design_takes_the_arm_as_loaded(family):
    """A six-axis arm used to be searched over its 51 over-complete parameters and to fail
    at the certificate; it is designed for what a plan moving every joint identifies."""
    m = 6  # few poses keep the search short: ceil(33 / 9) = 4 at least
    made = armcal.design(family.arm, m, rng=0, with_certificate=False)
    assert made.q.shape == (m, family.arm.n_joints)
    assert made.model.n_free == family.identified
    quality = armcal.evaluate_plan(family.arm, made.q, sigma=0.05, test_q=np.zeros((0, 6)))
    assert quality.model.n_free == family.identified


@pytest.mark.slow
def test_a_six_axis_design_is_certified():
    family = _builtin_six_axis()
    made = armcal.design(family.arm, 12, rng=0)
    assert made.certificate is not None
    assert 0 < made.certificate.certified_d_efficiency <= 1 + 1e-9


def test_a_spatial_arm_given_new_targets_starts_them_unplaced():
    """replace(targets=...) alone: the targets start where unplaced targets do, found from
    the data by the fit (the old single target's position no longer fits)."""
    arm = load_robot("industrial-6r").arm.replace(targets=LABELS)
    assert arm.target_positions.shape == (3, 3)
    assert not arm.known_targets


# -- one rule: an explicit sigma replaces per-row sigma --------------------------------


def _planar_rows():
    arm = PlanarArm([260.0, 180.0, 120.0])
    q = random_plan(arm, 20, rng=1)
    truth = np.zeros(arm.n_params)
    points = armcal.forward_kinematics(arm, q, truth)
    points = points + np.random.default_rng(2).normal(0.0, 0.05, points.shape)
    row_sigma = np.where(np.arange(20) % 2 == 0, 0.02, 0.2)
    return arm, q, points, row_sigma


def test_identify_with_sigma_ignores_per_row_sigma():
    arm, q, points, row_sigma = _planar_rows()
    both = armcal.identify(arm, q, points, sigma=0.05, row_sigma=row_sigma)
    alone = armcal.identify(arm, q, points, sigma=0.05)
    rows_only = armcal.identify(arm, q, points, row_sigma=row_sigma)
    assert both.sigma_mm == 0.05 and both.sigma_source == "given"
    assert np.array_equal(both.params, alone.params)
    assert np.array_equal(both.covariance, alone.covariance)
    # the per-row weights would have changed the estimate: the test can fail
    assert not np.allclose(rows_only.params, alone.params, rtol=0, atol=1e-9)
    # conditions made with per-row sigma: the given sigma replaces theirs too
    conditions = arm.conditions(q, sigma_mm=row_sigma)
    given = armcal.identify(arm, q, points, sigma=0.05, conditions=conditions)
    assert np.array_equal(given.params, alone.params)


def test_cross_validate_with_sigma_ignores_per_row_sigma():
    arm, q, points, row_sigma = _planar_rows()
    both = armcal.cross_validate(arm, q, points, 4, sigma=0.05, row_sigma=row_sigma, rng=0)
    alone = armcal.cross_validate(arm, q, points, 4, sigma=0.05, rng=0)
    assert np.array_equal(both.errors, alone.errors)
    assert np.array_equal(both.predicted_mm, alone.predicted_mm)


def test_synthesize_with_sigma_ignores_per_row_sigma():
    """The draw follows the same rule: the same seed gives the points of sigma alone."""
    arm, q, _, row_sigma = _planar_rows()
    truth = np.zeros(arm.n_params)
    both = armcal.synthesize_measurements(arm, q, truth, 0.05, rng=3, row_sigma=row_sigma)
    alone = armcal.synthesize_measurements(arm, q, truth, 0.05, rng=3)
    assert np.array_equal(both, alone)


# -- short reprs and notebook tables ------------------------------------------------------


def _is_short(text: str) -> bool:
    """One line of at most 200 characters, no array dumped."""
    return "\n" not in text and len(text) <= 200 and "array(" not in text


def test_every_result_has_a_short_repr_and_the_tables_a_notebook_shows():
    family = _builtin_six_axis()
    rows, labels, points = _noiseless(family, m=8)
    cal = armcal.identify(family.arm, rows.q, points, target=labels, sigma=0.01)
    held, held_labels = _rows(family, family.plan(3, 9))
    measured = family.arm.positions(held, family.truth)
    planar = PlanarArm([260.0, 180.0])
    made = armcal.design(planar, 8, rng=0)
    results = {
        "Calibration": cal,
        "Estimate": cal["dq2"],
        "Validation": armcal.validate(cal, held.q, measured, target=held_labels),
        "Compensation": armcal.compensate(cal, held.q, target=held_labels),
        "CrossValidation": armcal.cross_validate(
            planar, made.q, planar.positions(planar.conditions(made.q)), 2, sigma=0.1, rng=0
        ),
        "PlanQuality": armcal.evaluate_plan(family.arm, rows.q[::3], sigma=0.05, test_q=held.q),
        "MonteCarlo": armcal.monte_carlo(planar, made.q, np.zeros(4), 0.1, 50, rng=1),
        "Design": made,
        "Certificate": made.certificate,
        "PosesNeeded": armcal.poses_needed(planar, "length_std_mm", 0.05, sigma=0.1),
    }
    for name, result in results.items():
        text = repr(result)
        assert _is_short(text), (name, text)
        assert type(result).__name__ == name
    assert "24 measurements" in repr(cal)  # 8 poses, each at 3 targets: rows, not poses
    html = cal._repr_html_()
    assert html.count("<tr>") == 1 + cal.model.n_params  # the header and every parameter
    assert "<td>dq2</td>" in html
    assert "fixed" in html  # a held parameter says so, not a std of 0
    table = results["Validation"]._repr_html_()
    assert "<th>before</th><th>after</th>" in table and "RMS per point (mm)" in table
    quality = results["PlanQuality"]._repr_html_()
    assert quality.count("<tr>") == 1 + family.arm.n_params
    assert results["MonteCarlo"]._repr_html_().count("<tr>") == 1 + 4


def test_py_typed_is_shipped():
    """PEP 561: the marker sits in the package, and the wheel takes the package directory
    whole (hatch's packages), so every file in it ships."""
    assert (ROOT / "src" / "armcal" / "py.typed").is_file()
    config = (ROOT / "pyproject.toml").read_text(encoding="utf-8")
    wheel = config[config.index("[tool.hatch.build.targets.wheel]") :].split("\n[", 1)[0]
    assert 'packages = ["src/armcal"]' in wheel


def test_the_residual_picture_draws_every_pose_and_every_joint(family):
    """The family's residual_figure role (armcal.families): on top one bar per row, its
    Euclidean position residual in the family's dimensions, standing above its pose's
    number beside the pose's other targets, under the line 99 % of clean rows stay below:
    sigma sqrt(chi2_d(0.99)), the chi-square quantile from the regularized incomplete
    gamma function, P(d/2, x/2) = 0.99; below, every row's residual against each joint's
    reading in degrees."""
    from scipy.special import gammaincinv

    from armcal.families import family_of

    q = family.plan(12, 3)
    rows, labels = _rows(family, q)
    points = armcal.synthesize_measurements(
        family.arm, rows.q, family.truth, 0.05, target=labels, rng=7
    )
    cal = armcal.identify(family.arm, rows.q, points, sigma=0.05, target=labels)
    fig = family_of(cal.model).role("residual_figure")(cal)
    top, *joints = fig.axes
    dim = cal.model.position_dim
    assert dim == (2 if family.name == "planar" else 3)
    expected = np.sqrt(np.sum(cal.residuals[:, :dim] ** 2, axis=1))
    # plan_conditions: every target of every pose, pose-major; a pose's three bars share
    # its number, 0.8 wide together.
    pose = np.repeat(np.arange(1, q.shape[0] + 1), 3)
    x = pose + (rows.target - 1) * 0.8 / 3
    bars = sorted((p.get_x() + p.get_width() / 2, p.get_height()) for p in top.patches)
    order = np.argsort(x, kind="stable")
    assert_allclose([b for b, _ in bars], x[order], atol=1e-12)
    assert_allclose([h for _, h in bars], expected[order], rtol=1e-12)
    (line,) = [ln for ln in top.lines if ln.get_linestyle() == "--"]
    limit = 0.05 * math.sqrt(2.0 * gammaincinv(dim / 2.0, 0.99))
    assert_allclose(line.get_ydata(), limit, rtol=1e-9)
    assert top.get_xlabel() == "pose"
    legend = {t.get_text() for t in top.get_legend().get_texts()}
    targets = {f"target {label}" for label in LABELS}
    assert legend == targets | {f"99 % of clean rows below ({dim}-D)"}
    assert len(joints) == cal.model.n_joints
    for j, ax in enumerate(joints):
        (dots, _) = ax.lines
        assert_allclose(dots.get_xdata(), np.degrees(rows.q[:, j]), rtol=1e-12)
        assert_allclose(dots.get_ydata(), expected, rtol=1e-12)
