"""The certificate's ascent over a view with an inside (a camera's image less its margin):
:func:`armcal.doe.constrained.bounded_ascent` and the view's constraints it follows.

Against closed forms: the nearest point of a box is the clipped point, of a half-space
the point moved along its normal; a linear function over a disc is largest at the disc's
point along it, over a square at the square's corner (two bounds active at once, where
the earlier single-probe tangent stalled).  The camera's constraints are checked against
central differences of its readings and against its own miss.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pytest

from armcal.doe import feasible_poses
from armcal.doe.constrained import bounded_ascent
from armcal.files import load_robot
from armcal.models.information import pose_derivative
from armcal.numerics import nearest_in
from helpers_instruments import write_lab


def test_the_nearest_point_of_a_box_is_the_clipped_point():
    rng = np.random.default_rng(3)
    for _ in range(50):
        low = rng.uniform(-1, 0, 4)
        high = low + rng.uniform(0.1, 2, 4)
        v = rng.normal(0, 2, 4)
        a = np.concatenate([np.eye(4), -np.eye(4)])
        b = np.concatenate([low, -high])
        np.testing.assert_allclose(nearest_in(a, b, v), np.clip(v, low, high), atol=1e-12)


def test_the_nearest_point_of_a_half_space_moves_along_its_normal():
    rng = np.random.default_rng(4)
    for _ in range(50):
        normal, v = rng.normal(size=3), rng.normal(size=3)
        offset = float(normal @ v) + rng.uniform(0.1, 1)  # v is outside: normal . x >= offset
        expected = v + (offset - normal @ v) / (normal @ normal) * normal
        found = nearest_in(normal[None, :], np.array([offset]), v)
        np.testing.assert_allclose(found, expected, atol=1e-12)
    inside = np.array([0.5, 0.5])
    assert np.array_equal(nearest_in(np.eye(2), np.zeros(2), inside), inside)


@dataclass(frozen=True)
class _Region:
    """A model's view as :func:`bounded_ascent` asks it: joint limits, smooth constraints
    ``g >= 0`` and the poses that meet them (``g >= -1e-12``, none moved)."""

    kind: str  # "disc": |q| <= 1; "square": q_0 <= 1 and q_1 <= 1

    @property
    def joint_limits(self) -> np.ndarray:
        return np.array([[-2.0, 2.0], [-2.0, 2.0]])

    def view_constraints(self, q: np.ndarray):
        if self.kind == "disc":
            g = 1.0 - np.sum(q * q, axis=-1, keepdims=True)
            return g, -2.0 * q[..., None, :]
        g = 1.0 - q
        dg = np.broadcast_to(-np.eye(2), (*q.shape[:-1], 2, 2))
        return g, dg

    def feasible(self, q: np.ndarray):
        return np.all(np.abs(q) <= 2.0, axis=-1)

    def meeting_poses(self, q: np.ndarray):
        g, _ = self.view_constraints(q[:, None, :])
        return q, g[:, 0].min(axis=-1) >= -1e-12


def _linear(direction: np.ndarray):
    def objective(q: np.ndarray, gradient: bool):
        value = q @ direction
        return value, np.broadcast_to(direction, q.shape).copy() if gradient else None

    return objective


@pytest.mark.parametrize("kind", ["disc", "square"])
def test_a_linear_function_climbs_to_the_region_s_edge(kind):
    direction = np.array([0.6, 0.8])
    starts = np.array([[0.0, 0.0], [-0.5, 0.2], [0.3, -0.9]])
    found = bounded_ascent(_Region(kind), _linear(direction), starts, steps=400)  # type: ignore[arg-type]
    # the disc's point along the direction; the square's corner
    expected = direction if kind == "disc" else np.array([1.0, 1.0])
    np.testing.assert_allclose(found, np.broadcast_to(expected, found.shape), atol=1e-6)


@pytest.mark.parametrize("mount", ["eye-to-hand", "eye-in-hand"])
def test_a_camera_s_view_constraints_are_its_image_less_the_margin(tmp_path, mount):
    """Its slack (depth and tilt) by the camera's own geometry: checked in
    test_a_camera_s_slack_is_its_depth_and_tilt; the joint derivatives of both, the box's
    and the slack's (in closed form), against central differences."""
    robot_file, _ = write_lab(tmp_path, "industrial-6r", mount)
    model = load_robot(robot_file).arm
    q = feasible_poses(model, 6, rng=np.random.default_rng(2))
    g, dg = model.view_constraints(q)
    box = model.instrument.view_box
    corners = len(model.instrument.labels)
    # each corner's four edges, then its depth and tilt (the camera's slack)
    assert g.shape == (6, 6 * corners) and dg.shape == (6, 6 * corners, model.n_joints)
    assert g[:, : 4 * corners].min() >= -1e-9  # a pose that sees the board: every corner in
    reading = model.positions(model.plan_conditions(q)).reshape(6, -1)
    low = np.tile([box[0][0], box[1][0]], corners)
    np.testing.assert_allclose(g[:, : 2 * corners], reading - low, atol=1e-9)
    for c in [*range(0, 6 * corners, 37), 6 * corners - 2, 6 * corners - 1]:  # and the slack's
        numeric = pose_derivative(lambda x, c=c: model.view_constraints(x)[0][:, c], q)
        scale = np.abs(dg[:, c]).max()
        np.testing.assert_allclose(dg[:, c], numeric, atol=1e-6 * scale)
    pushed = q.copy()
    pushed[:, 0] += 0.6  # the base turned away: some corner leaves the box, and misses
    g_out, _ = model.view_constraints(pushed)
    rows = model.plan_conditions(pushed)  # the instrument's own miss: outside, or unseen
    miss = np.abs(model._miss(rows, model.nominal)).reshape(6, -1).max(axis=-1)
    assert np.array_equal(g_out[:, : 4 * corners].min(axis=-1) < 0, miss > 0)


def test_a_camera_s_slack_is_its_depth_and_tilt(tmp_path):
    """Depth and tilt recomputed from the corners' camera-frame points of the camera's
    own readings: the board's plane through three corners gives its normal."""
    robot_file, _ = write_lab(tmp_path, "cobot-6r", "eye-to-hand")
    model = load_robot(robot_file).arm
    camera = model.instrument
    q = feasible_poses(model, 4, rng=np.random.default_rng(5))
    rows = model.plan_conditions(q)
    x, theta = model.split(model.nominal)
    tool = model._tool(rows, x)
    p, _ = camera._seen(tool, rows.feature, theta)
    p = p.reshape(4, -1, 3)
    slack = camera.slack(tool, rows.feature, theta).reshape(4, -1, 2)
    np.testing.assert_allclose(slack[..., 0], p[..., 2] - camera.min_depth_mm, atol=1e-9)
    cols = camera.board.cols
    normal = np.cross(p[:, 1] - p[:, 0], p[:, cols] - p[:, 0])  # along a row, a column
    normal /= np.linalg.norm(normal, axis=-1, keepdims=True)
    cosine = np.abs(np.einsum("kc,kmc->km", normal, p)) / np.linalg.norm(p, axis=-1)
    expected = cosine - np.cos(np.radians(camera.max_tilt_deg))
    np.testing.assert_allclose(slack[..., 1], expected, atol=1e-9)
    assert np.all(model.feasible(q))  # a pool's poses keep to it


def test_a_rebased_certificate_is_the_kiefer_wolfowitz_bound_of_the_other_plan(tmp_path):
    """The same reference design's bound for another plan: recomputed here from the
    reference's support and weights, ``(det M_q / det M(xi*))^(1/p) exp(1 - max d / p)``
    with ``M`` the mean of the rows' Gram matrices, and for the plan itself the figure
    :func:`certify` gave (its Kiefer-Wolfowitz bound, the largest of its bounds here)."""
    from armcal.doe.certificate import certify
    from armcal.models.information import identifying

    robot_file, _ = write_lab(tmp_path, "industrial-6r", "plane")
    model = load_robot(robot_file).arm
    plan = feasible_poses(model, 12, rng=np.random.default_rng(1))
    model = identifying(model, model.plan_conditions(plan))
    cert = certify(model, plan, rng=0, search=500, rounds=1, candidates=50)
    assert cert.certified_d_efficiency > cert.plan_only_bound  # the bound is the KW one
    same = cert.rebased(model, plan)
    assert same is not None
    assert same.certified_d_efficiency == pytest.approx(cert.certified_d_efficiency, rel=1e-9)
    other = feasible_poses(model, 12, rng=np.random.default_rng(2))
    p = model.n_free

    def logdet(blocks: np.ndarray, weights: np.ndarray) -> float:
        m = np.einsum("k,krp,krq->pq", weights, blocks, blocks)
        return float(np.linalg.slogdet(m)[1])

    info = model.plan_information
    star = logdet(info(cert.support).blocks(), cert.weights)
    mine = logdet(info(other).blocks(), np.full(12, 1 / 12))
    expected = np.exp((mine - star) / p + 1 - cert.max_variance / p)
    found = cert.rebased(model, other)
    assert found is not None
    assert found.certified_d_efficiency == pytest.approx(min(1.0, expected), rel=1e-9)
    assert found.plan_only_bound == 0.0 and found.max_variance == cert.max_variance


def test_a_camera_design_identifies_what_photos_that_see_the_board_identify(tmp_path):
    """The command line's design reduces the model on random poses moved until the camera
    sees the board (it reduced it on random poses, which seldom do: 13 of 57 parameters,
    the arm's 1); the count is the rank of photos that do (test_camera: 30)."""
    from armcal.workflow.plan import moving_set

    robot_file, _ = write_lab(tmp_path, "cobot-6r", "eye-to-hand")
    model = load_robot(robot_file).arm
    q = feasible_poses(model, 40, rng=np.random.default_rng(4))
    jac = model.jacobian(model.plan_conditions(q)).reshape(-1, model.n_params)
    scaled = jac / np.maximum(np.linalg.norm(jac, axis=0), 1e-300)
    s = np.linalg.svd(scaled[:, np.linalg.norm(jac, axis=0) > 0], compute_uv=False)
    rank = int(np.sum(s > 1e-9 * s[0]))
    assert moving_set(model, 0).n_free == rank
