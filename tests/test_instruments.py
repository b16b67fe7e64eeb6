"""Instruments other than a tracker: planes and fixed points (issue 38, first part).

The arms are the built-in six-axis ``industrial-6r`` and ``cobot-6r`` with their
built-in virtual truths (every joint placement and zero a few tenths of a mm and
hundredths of a degree off), the base at the origin of the robot's frame.  The
virtual data are the true arm's touches and seatings: random poses within the limits
moved onto the true instrument by :meth:`InstrumentedArm.meeting_poses` (Newton on the
reading), so every reading is 0 to round-off for the arm as it really is.

The user's rough instrument is the true one 10 mm off in every offset or coordinate and
its normals 1-2 degrees off (what a user with a ruler knows).  Tolerances: a reading of
points about 2 m from the base is exact to round-off near 1e-12 mm (5 ulp at 2000 mm is
2e-12); central differences with a step h have an error of order h^2 (curvature) plus
eps |value| / h.
"""

from __future__ import annotations

import numpy as np
import pytest

from armcal.criteria import d_efficiency
from armcal.doe import design, random_plan
from armcal.files import load_spatial_robot, load_spatial_truth
from armcal.identification import identify
from armcal.instruments import Coordinates, Distance, FixedPoints, Plane, Planes
from armcal.instruments.partial import COMPONENTS
from armcal.models.instrumented import InstrumentedArm
from armcal.noise import NoiseModel
from armcal.report import format_monte_carlo
from armcal.simulate import monte_carlo

ROUND_OFF_MM = 1e-10
#: A draw-wire sensor's zero, unknown to the user (who starts from 0).
TRUE_OFFSET_MM = 50.0


def _arm(name: str) -> tuple:
    spec = load_spatial_robot(name)
    truth = load_spatial_truth(spec.default_truth, spec.arm)
    truth[:6] = 0.0  # the robot's own frame: the instruments are placed in it
    return spec.arm, truth


def _instruments(reach: float, kind: str) -> tuple:
    """The true instrument and the user's rough one (module notes)."""
    if kind == "plane":
        true = Planes(
            {
                "top": Plane(np.array([0.01, -0.02, 1.0]), 0.1 * reach),
                "side": Plane(np.array([1.0, 0.03, -0.01]), 0.45 * reach),
            }
        )
        rough = Planes(
            {
                "top": Plane(np.array([0.0, 0.0, 1.0]), 0.1 * reach + 10.0),
                "side": Plane(np.array([1.0, 0.0, 0.0]), 0.45 * reach - 10.0),
            }
        )
        return true, rough
    if kind == "partial":  # a CMM's frame, turned a quarter about z
        where = np.array([0.5, 0.1, 0.0]) * reach
        true = Coordinates(("x", "y", "z"), where, np.array([1.0, -1.5, 92.0]))
        return true, Coordinates(("x", "y", "z"), where + 10.0, np.array([0.0, 0.0, 90.0]))
    if kind == "dial":  # one dial indicator along the base's x axis (its z turned onto x)
        where = np.array([0.6, 0.0, 0.1]) * reach
        true = Coordinates(("z",), where, np.array([1.0, 88.5, 2.0]))
        return true, Coordinates(("z",), where + 10.0, np.array([0.0, 90.0, 0.0]))
    if kind in TURNED:  # a 6-DoF tracker's frame, or some of it, with the tool's turn
        reads = TURNED[kind]
        if kind != "z-rz":  # a CMM's frame, turned a quarter about z
            where, rpy, true_rpy = [0.5, 0.1, 0.0], [0.0, 0.0, 90.0], [1.0, -1.5, 92.0]
        else:  # along the base's x axis (its z turned onto x), as the dial
            where, rpy, true_rpy = [0.6, 0.0, 0.1], [0.0, 90.0, 0.0], [1.0, 88.5, 2.0]
        at = np.array(where) * reach
        true = Coordinates(reads, at, np.array(true_rpy), np.array([1.2, -0.8, 31.0]))
        return true, Coordinates(reads, at + 10.0, np.array(rpy), TOOL_RPY_DEG)
    if kind == "distance":  # a draw-wire sensor's long travel
        pivot = np.array([0.5, 0.1, 0.3]) * reach
        span = (0.2 * reach, 0.7 * reach)
        return Distance(pivot, span), Distance(pivot + 10.0, span)
    centres = {
        "A": np.array([0.45, 0.1, 0.2]) * reach,
        "B": np.array([0.4, -0.2, 0.1]) * reach,
    }
    rough = {k: v + 10.0 for k, v in centres.items()}
    if kind == "bar":  # a calibrated bar between the cones: B tied to A
        bar = (("A", "B", float(np.linalg.norm(centres["B"] - centres["A"]))),)
        return FixedPoints(centres, bar), FixedPoints(rough, bar)
    return FixedPoints(centres), FixedPoints(rough)


#: Partial coordinates with turns (issue 38): every component (a 6-DoF tracker read as
#: partial coordinates), one coordinate and one turn about another axis, and a
#: coordinate and the turn about its own axis (the instrument and the tool turned
#: together about it unseen), along the base's x axis as the dial.  Where the user puts
#: an axis the instrument reads along joint 1's (the dial's frame reading its x, along
#: the base's z), a turn of the whole arm about it is seen only by the true instrument's
#: tilt (a few hundredths of the effect), which the rule at the nominal arm holds.
TURNED = {"pose": COMPONENTS, "x-rz": ("x", "rz"), "z-rz": ("z", "rz")}
#: A turn's component's std (a 6-DoF tracker's probe: about 0.001 degrees).
TURN_SIGMA_DEG = 0.001
#: Where the user says the tool's axes roughly are in the tip frame (roll, pitch, yaw).
TOOL_RPY_DEG = np.array([0.0, 0.0, 30.0])


def _lab(name: str, kind: str, m: int) -> tuple:
    """The true model and parameters, ``m`` of its touches or seatings, and the model
    of the user's rough instrument (module notes)."""
    arm, truth = _arm(name)
    if kind in TURNED:  # a turn's component read to a thousandth of a degree
        arm = arm.with_noise(
            NoiseModel.isotropic(0.02).with_orientation(np.radians(TURN_SIGMA_DEG))
        )
    true, rough = _instruments(arm.reach_mm, kind)
    true_model = InstrumentedArm.of(arm, true)
    x_true = np.concatenate([truth, true.start])
    if kind == "distance":
        x_true[-1] = TRUE_OFFSET_MM
    q = _rows(true_model, x_true, m, seed=1)
    return true_model, x_true, q, InstrumentedArm.of(arm, rough)


def _rows(model: InstrumentedArm, params: np.ndarray, m: int, seed: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    q, met = model.meeting_poses(random_plan(model.arm.inner, 10 * m, rng=rng), params)
    q = q[met]
    assert q.shape[0] >= m
    return q[:m]


def _read(features: InstrumentedArm, model: InstrumentedArm, q: np.ndarray):
    """The rows of poses ``q`` for ``model``, each pose meeting or reading the features
    ``features`` gives it (a touch its plane at the truth, every axis of partial
    coordinates)."""
    rows = features.plan_conditions(q)
    return model.conditions(rows.q, feature=rows.feature)


KINDS = ["plane", "point", "distance", "partial", "dial"]


@pytest.mark.parametrize("kind", [*KINDS, "bar"])
def test_readings_derivatives_are_central_differences(kind):
    """d reading / d point and d reading / d params against central differences (step
    1e-4 mm or rad: error h^2 |d3| ~ 1e-8 relative, round-off eps 2000 / h ~ 4e-9 mm)."""
    true, _ = _instruments(2000.0, kind)
    rng = np.random.default_rng(3)
    points = rng.normal(size=(7, 3)) * 800.0
    feature = rng.integers(0, len(true.labels), 7)
    params = true.start + rng.normal(size=true.start.size) * 0.01
    by_point, by_params = true.derivatives(points, feature, params)
    h = 1e-4

    def diff(f, x):
        return np.stack([(f(x + h * e) - f(x - h * e)) / (2 * h) for e in np.eye(x.size)], axis=-1)

    numeric = diff(lambda t: true.reading(points, feature, t), params)
    np.testing.assert_allclose(by_params, numeric, atol=1e-6 * 2000.0 * h / h)
    for i in range(7):
        row = diff(lambda p, i=i: true.reading(p[None], feature[i : i + 1], params)[0], points[i])
        np.testing.assert_allclose(by_point[i], row, atol=1e-7)
    # Batched parameters: every set's reading is its own.
    sets = np.stack([params, params * 1.001])
    batched = true.reading(points, feature, sets)
    np.testing.assert_allclose(batched[1], true.reading(points, feature, params * 1.001))


@pytest.mark.parametrize("kind", list(TURNED))
def test_a_turns_derivatives_are_central_differences(kind):
    """Partial coordinates with turns read the tool's frame: d reading / d (point, tip's
    turn) and d reading / d params against central differences (step 1e-6 mm or rad:
    truncation h^2 |d3| ~ 1e-12 relative, round-off eps 2000 / h ~ 4e-10 mm), the tip
    turned by ``exp([w]) R`` (the base frame's small turn, module notes of
    :mod:`armcal.instruments.partial`); a turn's reading is the rotation vector of
    ``R^T R_tip R_tool`` recomputed here from the matrices."""
    from armcal.models.spatial.chain import rotation_vector, rpy_matrix, vector_rotation

    true, _ = _instruments(2000.0, kind)
    rng = np.random.default_rng(3)
    m = 9
    p = rng.normal(size=(m, 3)) * 800.0
    tip = vector_rotation(rng.normal(size=(m, 3)) * 0.8)
    frame = np.concatenate([p, tip.reshape(m, 9)], axis=-1)
    feature = rng.integers(0, len(true.labels), m)
    params = true.start + rng.normal(size=true.start.size) * 0.01
    by_frame, by_params = true.derivatives(frame, feature, params)
    assert by_frame.shape == (m, 1, 6) and by_params.shape == (m, 1, 9)
    h = 1e-6

    def moved(w: np.ndarray) -> np.ndarray:
        turned = vector_rotation(w[3:]) @ tip
        return true.reading(np.concatenate([p + w[:3], turned.reshape(m, 9)], -1), feature, params)

    numeric = np.stack([(moved(h * e) - moved(-h * e)) / (2 * h) for e in np.eye(6)], axis=-1)
    np.testing.assert_allclose(by_frame, numeric, atol=1e-7)
    numeric = np.stack(
        [
            (
                true.reading(frame, feature, params + h * e)
                - true.reading(frame, feature, params - h * e)
            )
            / (2 * h)
            for e in np.eye(params.size)
        ],
        axis=-1,
    )
    np.testing.assert_allclose(by_params, numeric, atol=1e-6)
    # The reading itself: the instrument's frame R0 Rx Ry Rz (one axis's own turn last)
    # and the tool's, from the parameters' angles, recomputed.
    at = true.start
    r = rpy_matrix(np.radians(true.rpy_deg))
    tool = rpy_matrix(np.radians(true.tool_rpy_deg))
    phi = rotation_vector(r.T @ tip @ tool)
    component = np.array(["xyz".index(a[-1]) for a in true.labels])[feature]
    turn = np.array([a.startswith("r") for a in true.labels])[feature]
    expected = np.where(
        turn,
        phi[np.arange(m), component],
        np.einsum("mi,mi->m", (p - true.xyz_mm), r.T[component]),
    )
    np.testing.assert_allclose(true.reading(frame, feature, at)[:, 0], expected, atol=1e-9)


def test_a_turns_range_and_its_derivatives():
    """A plan keeps the tool within ``max_turn_deg`` of the instrument's axes: the view's
    constraint is that angle's slack, ``max - |phi|`` (recomputed from the matrices), and
    its joint derivatives are central differences of it (step 1e-6 rad: error about
    1e-10); poses beyond it are not feasible."""
    from armcal.models.spatial.chain import rotation_vector, rpy_matrix

    _, _, _, model = _lab("industrial-6r", "pose", 10)
    assert model.has_view
    q = random_plan(model.inner, 40, rng=np.random.default_rng(5))
    g, dg = model.view_constraints(q)
    rows = model.plan_conditions(q)
    r = rpy_matrix(np.radians(model.instrument.rpy_deg))
    tool = rpy_matrix(np.radians(model.instrument.tool_rpy_deg))
    tip = model.inner.tip_rotation(model.inner.conditions(q))
    angle = np.linalg.norm(rotation_vector(r.T @ tip @ tool), axis=-1)
    turns = len(model.instrument.labels)
    assert g.shape == (40, turns)  # every row of a pose: its pose's turn
    np.testing.assert_allclose(
        g, np.broadcast_to(np.radians(150.0) - angle[:, None], g.shape), atol=1e-12
    )
    h = 1e-6
    numeric = np.stack(
        [
            (model.view_constraints(q + h * e)[0] - model.view_constraints(q - h * e)[0]) / (2 * h)
            for e in np.eye(q.shape[1])
        ],
        axis=-1,
    )
    np.testing.assert_allclose(dg, numeric, atol=1e-8)
    assert rows.m == 40 * turns
    np.testing.assert_array_equal(model.feasible(q), angle <= np.radians(150.0))


@pytest.mark.parametrize("kind", [*KINDS, "bar"])
def test_curvatures_are_central_differences_of_the_derivatives(kind):
    """d^2 reading / d point^2 and d^2 reading / d params d point against central
    differences of the analytic derivatives (step 1e-4 mm: truncation h^2 |d3| ~ 1e-14
    at ~1 m from the pivot; round-off eps |derivative| / h, a plane's turn derivative
    being the point itself, up to 2000 mm: 4e-9)."""
    true, _ = _instruments(2000.0, kind)
    rng = np.random.default_rng(5)
    points = rng.normal(size=(7, 3)) * 800.0
    feature = rng.integers(0, len(true.labels), 7)
    params = true.start + rng.normal(size=true.start.size) * 0.01
    bend, twist = true.curvatures(points, feature, params)
    h = 1e-4
    shifts = [h * e for e in np.eye(3)]
    by_point = np.stack(
        [
            (
                true.derivatives(points + s, feature, params)[0]
                - true.derivatives(points - s, feature, params)[0]
            )
            / (2 * h)
            for s in shifts
        ],
        axis=-1,
    )  # (m, d, 3, 3): the last axis the point's coordinate
    by_params = np.stack(
        [
            (
                true.derivatives(points + s, feature, params)[1]
                - true.derivatives(points - s, feature, params)[1]
            )
            / (2 * h)
            for s in shifts
        ],
        axis=-1,
    )  # (m, d, t, 3)
    np.testing.assert_allclose(0.0 if bend is None else bend, by_point, atol=1e-8)
    np.testing.assert_allclose(0.0 if twist is None else twist, by_params, atol=1e-8)


@pytest.mark.parametrize("kind", [*KINDS, "partial per axis"])
def test_the_design_gradient_in_the_poses_is_central_differences(kind):
    """The variance function's gradient in the poses, from the arm's pullback and the
    instrument's curvatures, against the central differences of the same blocks that a
    model without a pullback takes (step 1e-6 rad): their round-off, eps |d| / h with
    |d| up to 1e3 times the gradient's scale here, is below 1e-6 of the largest entry."""
    from armcal.models.information import BlockInformation

    arm, _ = _arm("industrial-6r")
    if kind == "partial per axis":  # every row weighed by its axis's sigma
        arm = arm.with_noise(NoiseModel(np.diag([0.01, 0.02, 0.04]) ** 2))
    true, _ = _instruments(arm.reach_mm, kind.split()[0])
    model = InstrumentedArm.of(arm, true)
    q = _rows(model, model.nominal, 40, seed=6)
    model = model.prepared(model.plan_conditions(q))
    info = model.plan_information(q)
    inverse = np.linalg.inv(info.information())
    value, grad = info.pose_variance(inverse)
    plain_value, plain_grad = BlockInformation(model, q).pose_variance(inverse)
    np.testing.assert_allclose(value, plain_value, rtol=1e-12)
    np.testing.assert_allclose(grad, plain_grad, atol=1e-6 * np.abs(plain_grad).max())
    assert np.abs(grad).max() > 0


@pytest.mark.parametrize("kind", [*KINDS, *TURNED])
def test_the_models_jacobians_are_central_differences(kind):
    """The chain rule's Jacobian in every parameter (mm per mm or rad) and in every
    joint, against central differences (step 1e-6: error about 1e-6 mm at 2 m)."""
    arm, truth = _arm("industrial-6r")
    true, _ = _instruments(arm.reach_mm, kind)
    model = InstrumentedArm.of(arm, true)
    params = np.concatenate([truth, true.start])
    q = _rows(model, params, 12, seed=4)
    rows = _read(model, model, q)
    jac = model.jacobian(rows, params)
    h = 1e-6
    numeric = np.stack(
        [
            (model.positions(rows, params + h * e) - model.positions(rows, params - h * e))
            / (2 * h)
            for e in np.eye(params.size)
        ],
        axis=-1,
    )
    np.testing.assert_allclose(jac, numeric, atol=2e-5 * max(1.0, np.abs(jac).max() / 1e3))
    joint = model.joint_jacobian(rows, params)
    numeric = np.stack(
        [
            (
                model.positions(model.conditions(rows.q + h * e, feature=rows.feature), params)
                - model.positions(model.conditions(rows.q - h * e, feature=rows.feature), params)
            )
            / (2 * h)
            for e in np.eye(rows.q.shape[1])
        ],
        axis=-1,
    )
    np.testing.assert_allclose(joint, numeric, atol=2e-5 * np.abs(joint).max() / 1e3 + 1e-6)


@pytest.mark.parametrize("name", ["industrial-6r", "cobot-6r"])
@pytest.mark.parametrize("kind", [*KINDS, *TURNED])
def test_noiseless_touches_are_recovered_to_round_off(name, kind):
    """From the rough instrument, 150 touches, seatings, distances or poses read in part
    of the true arm identify a model whose readings at 60 held-out poses are the true
    instrument's to round-off (0 for a touch or a seating); the identifiable count is
    the rank of the whole Jacobian at the truth (unit columns, singular values above
    1e-10), and the instrument's own parameters are all identified but those no row
    can see (an unread axis's shift)."""
    true_model, x_true, q, model = _lab(name, kind, 150)
    rows = _read(true_model, model, q)
    measured = true_model.positions(rows, x_true)
    cal = identify(model, rows.q, measured, conditions=rows, sigma=0.02)
    held_out = _rows(true_model, x_true, 60, seed=2)
    again = _read(true_model, model, held_out)
    miss = cal.model.positions(again, cal.params) - true_model.positions(again, x_true)
    assert np.max(np.abs(miss)) < ROUND_OFF_MM
    whole = true_model.jacobian(rows, x_true).reshape(-1, model.n_params)
    norms = np.linalg.norm(whole, axis=0)
    s = np.linalg.svd(whole[:, norms > 0] / norms[norms > 0], compute_uv=False)
    assert cal.model.n_free == int(np.sum(s > 1e-10 * s[0]))
    held = np.isin(cal.model.param_names, model.instrument.held)
    assert np.all(cal.model.free[cal.model.instrument_params & ~held])
    assert not np.any(cal.model.free[held])
    assert not any(w.code == "plan-degenerate" for w in cal.warnings)


@pytest.mark.parametrize("kind", ["x-rz", "partial"])
def test_a_calibrations_std_is_of_the_rows_own_sigmas(kind):
    """Rows of coordinates (0.02 mm) and of turns (0.001 deg), or of axes of their own
    sigmas (0.01, 0.02, 0.04 mm) with some cells empty, weigh a fit by their own sigmas:
    the calibration's covariance is ``(J^T S^-2 J)^-1`` over the free parameters,
    recomputed here from the model's Jacobian at the estimate and the sigmas of the rows'
    features.  The fit once scaled it by the noise model's reference sigma instead of
    the rows' (std 400 times too large with turns; off by the share of each axis's
    readings with empty cells)."""
    true_model, x_true, q, model = _lab("industrial-6r", kind, 150)
    each = {"x": 0.02, "z": 0.02, "rz": np.radians(TURN_SIGMA_DEG)}
    if kind == "partial":
        each = {"x": 0.01, "y": 0.02, "z": 0.04}
        model = model.with_noise(NoiseModel(np.diag([0.01, 0.02, 0.04]) ** 2))
    rows = _read(true_model, model, q)
    if kind == "partial":  # every third pose's x reading empty
        keep = (rows.feature != 0) | ((np.arange(rows.m) // 3) % 3 != 0)
        rows = model.conditions(rows.q[keep], feature=rows.feature[keep])
    cal = identify(model, rows.q, true_model.positions(rows, x_true), conditions=rows)
    free = cal.model.free
    sigma = np.array([each[model.instrument.labels[k]] for k in rows.feature])
    jac = cal.model.jacobian(rows, cal.params)[:, 0, free] / sigma[:, None]
    expected = np.linalg.inv(jac.T @ jac)
    np.testing.assert_allclose(cal.covariance[np.ix_(free, free)], expected, rtol=1e-6)


def test_what_partial_turns_cannot_see_is_held_and_said():
    """A coordinate and the turn about its own axis (z and rz) cannot see the instrument
    and the tool turned together about that axis: the tool's turn about it is held, and
    the words say so; a coordinate and a turn about another axis (x and rz) see every
    turn, and hold only the unread axes' shifts."""
    _, rough = _instruments(2000.0, "z-rz")
    assert rough.held == ("instrument.x", "instrument.y", "tool.rz")
    assert "nor the instrument and the tool turned together about its z axis" in rough.unseen
    _, rough = _instruments(2000.0, "x-rz")
    assert rough.held == ("instrument.y", "instrument.z")
    assert "turned together" not in rough.unseen and "turn (rz)" in rough.unseen


def test_what_a_plane_cannot_see_is_held_and_said():
    """One plane (z up) cannot see a turn of the whole arm about its normal: joint 1's
    zero (its axis is the plane's normal) merges into what is kept, and the instrument
    says so in words."""
    arm, truth = _arm("industrial-6r")
    reach = arm.reach_mm
    true = Planes({"table": Plane(np.array([0.0, 0.0, 1.0]), 0.1 * reach)})
    model = InstrumentedArm.of(arm, true)
    x_true = np.concatenate([truth, true.start])
    q = _rows(model, x_true, 120, seed=5)
    prepared = model.prepared(model.conditions(q), np.zeros((q.shape[0], 1)))
    held = {name for merge in prepared.held_reasons for name in merge.members}
    assert "dq1" in held
    assert "turn about its normal" in true.unseen


def test_rows_that_do_not_fix_the_instrument_are_refused():
    """Twenty touches at one pose cannot fix a plane's tilt (its three columns are the
    same at every row: rank 1 of 3)."""
    arm, truth = _arm("industrial-6r")
    true = Planes({"table": Plane(np.array([0.0, 0.0, 1.0]), 0.1 * arm.reach_mm)})
    model = InstrumentedArm.of(arm, true)
    one = _rows(model, np.concatenate([truth, true.start]), 1, seed=6)
    q = np.repeat(one, 20, axis=0)
    with pytest.raises(ValueError, match="do not fix the instrument"):
        model.prepared(model.conditions(q), np.zeros((20, 1)))


def test_a_row_must_name_its_feature_where_there_are_several():
    arm, _ = _arm("industrial-6r")
    true, _ = _instruments(arm.reach_mm, "plane")
    model = InstrumentedArm.of(arm, true)
    with pytest.raises(ValueError, match="every row must say which"):
        model.conditions(np.zeros((3, 6)))
    with pytest.raises(
        ValueError, match="unknown feature 'floor'; the model's features are top, side"
    ):
        model.conditions(np.zeros((2, 6)), feature=["top", "floor"])
    rows = model.conditions(np.zeros((2, 6)), feature=["side", "top"])
    assert rows.feature.tolist() == [1, 0]


def _monte_carlo_ratios(name: str, kind: str, trials: int) -> np.ndarray:
    _, x_true, q, model = _lab(name, kind, 150)
    mc = monte_carlo(model, q, x_true, 0.02, trials, rng=np.random.default_rng(8))
    assert mc.not_converged == 0
    free = mc.model.free
    return mc.std[free] / mc.predicted_std[free]


#: The Monte Carlo's agreement (issue 38): within 5 %.  With 4000 trials a std is known
#: to 1 / sqrt(2 * 3999) = 1.1 % (1 std), so 5 % is 4.5 of its std's: a real mismatch
#: fails, chance over 26 parameters does not (2000 trials, 1.6 %, left a 3.5-sigma
#: 0.944 in one of four runs tried).
MC_TRIALS = 4000
MC_AGREEMENT = 0.05


@pytest.mark.parametrize(
    ("name", "kind"),
    [
        ("industrial-6r", "plane"),
        ("cobot-6r", "point"),
        pytest.param("industrial-6r", "point", marks=pytest.mark.slow),
        pytest.param("cobot-6r", "plane", marks=pytest.mark.slow),
        pytest.param("industrial-6r", "distance", marks=pytest.mark.slow),
        pytest.param("cobot-6r", "distance", marks=pytest.mark.slow),
    ],
)
def test_monte_carlo_std_agrees_with_the_predicted_std(name, kind):
    """4000 noisy touch sets (sigma 0.02 mm along the normal, or per coordinate of a
    seating) identified from the truth: every free parameter's std within 5 % of the
    predicted one."""
    ratios = _monte_carlo_ratios(name, kind, MC_TRIALS)
    assert np.all(np.abs(ratios - 1.0) <= MC_AGREEMENT), ratios


@pytest.mark.parametrize(
    ("name", "kind"),
    [("industrial-6r", "partial"), pytest.param("cobot-6r", "dial", marks=pytest.mark.slow)],
)
def test_monte_carlo_std_agrees_with_the_predicted_std_per_axis(name, kind):
    """4000 noisy sets of partial coordinates, every axis with its own sigma (0.01, 0.02
    and 0.04 mm for x, y and z: ``sigma_mm = [sx, sy, sz]``), identified from the truth:
    every free parameter's std within 5 % of the predicted one."""
    _, x_true, q, model = _lab(name, kind, 150)
    model = model.with_noise(NoiseModel(np.diag([0.01, 0.02, 0.04]) ** 2))
    reads = [("x", "y", "z").index(a) for a in model.instrument.reads]
    np.testing.assert_array_equal(model.feature_sigma, np.array([0.01, 0.02, 0.04])[reads])
    mc = monte_carlo(model, q, x_true, None, MC_TRIALS, rng=np.random.default_rng(8))
    assert mc.not_converged == 0
    free = mc.model.free
    ratios = mc.std[free] / mc.predicted_std[free]
    assert np.all(np.abs(ratios - 1.0) <= MC_AGREEMENT), ratios


@pytest.mark.parametrize(
    ("name", "kind"),
    [("industrial-6r", "x-rz"), pytest.param("cobot-6r", "pose", marks=pytest.mark.slow)],
)
def test_monte_carlo_std_agrees_with_the_predicted_std_with_turns(name, kind):
    """4000 noisy sets of partial coordinates with turns (0.02 mm a coordinate, 0.001
    degrees a turn's component: every row weighed by its own sigma, in its own unit),
    identified from the truth: every free parameter's std within 5 % of the predicted
    one."""
    _, x_true, q, model = _lab(name, kind, 150)
    turn = np.array([a.startswith("r") for a in model.instrument.reads])
    sigma = np.where(turn, np.radians(TURN_SIGMA_DEG), 0.02)
    np.testing.assert_allclose(model.feature_sigma, sigma, rtol=1e-15)
    mc = monte_carlo(model, q, x_true, None, MC_TRIALS, rng=np.random.default_rng(8))
    assert mc.not_converged == 0
    free = mc.model.free
    ratios = mc.std[free] / mc.predicted_std[free]
    assert np.all(np.abs(ratios - 1.0) <= MC_AGREEMENT), ratios
    assert model.reads_turns and not _lab(name, "plane", 10)[3].reads_turns
    assert f"sigma 0.02 mm, {TURN_SIGMA_DEG:g} deg a turn" in format_monte_carlo(mc)


def test_a_plan_designed_from_touches_beats_random_touch_plans():
    """A 40-touch plan designed from a pool of the two planes' touches (random poses moved
    onto them at the user's rough planes) has a larger D-criterion than each of 100
    random 40-touch plans from the same pool; its certificate is a lower bound in
    (0, 1]."""
    _, _, _, model = _lab("industrial-6r", "plane", 10)
    rng = np.random.default_rng(3)
    pool, met = model.meeting_poses(random_plan(model.arm.inner, 4000, rng=rng))
    pool = pool[met]
    found = design(model, 40, candidates=pool, rng=1)
    ours = float(d_efficiency(found.model, found.q))
    draws = np.random.default_rng(4)
    chance = [
        float(d_efficiency(found.model, pool[draws.choice(len(pool), 40, replace=False)]))
        for _ in range(100)
    ]
    assert ours > max(chance)
    assert found.certificate is not None
    assert 0.0 < found.certificate.certified_d_efficiency <= 1.0


@pytest.mark.parametrize("kind", ["plane", "dial"])
def test_the_predicted_position_error_is_the_arms_own(kind):
    """evaluate's predicted position error after calibration with an instrument is the
    arm's own tool point's in 3-D, not the error of a reading: recomputed here from the
    plan's whitened Jacobian (sigma^2 (J^T J)^-1, its arm block) and central differences
    of the arm's tool point at random poses (step 1e-6 mm or rad: relative error about
    1e-6), against the touch or dial reading's own error, which is smaller."""
    from armcal.criteria import position_accuracy

    arm, _ = _arm("industrial-6r")
    _, rough = _instruments(arm.reach_mm, kind)
    model = InstrumentedArm.of(arm, rough)
    q = _rows(model, model.nominal, 60, seed=9)
    model = model.prepared(model.plan_conditions(q))
    test_q = random_plan(model.inner, 50, rng=np.random.default_rng(10))
    sigma = 0.01
    found = position_accuracy(model, q, test_q, sigma)
    jac = model.jacobian(model.plan_conditions(q))[..., model.free]
    jac = jac.reshape(-1, model.n_free)
    covariance = sigma**2 * np.linalg.inv(jac.T @ jac)
    k = model.inner.n_free
    inner, x = model.inner, model.split(model.nominal)[0]
    rows = inner.plan_conditions(test_q)
    h = 1e-6
    columns = np.flatnonzero(inner.free)
    tool = np.stack(
        [
            (inner.positions(rows, x + h * e) - inner.positions(rows, x - h * e))[..., :3]
            / (2 * h)
            for e in np.eye(x.size)[columns]
        ],
        axis=-1,
    )  # (50, 3, k)
    per_pose = np.einsum("tia,ab,tib->t", tool, covariance[:k, :k], tool)
    np.testing.assert_allclose(found.rms_mm, np.sqrt(per_pose.mean()), rtol=1e-5)
    reading = model.jacobian(model.plan_conditions(test_q))[..., model.free]
    reading_rms = np.sqrt(
        np.einsum("tia,ab,tib->", reading, covariance, reading) / reading.shape[0]
    )
    assert found.rms_mm > 1.2 * reading_rms
