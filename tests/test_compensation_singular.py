"""Compensation near singularities: corrections stay small or are refused, never swung.

The arm is the built-in ``industrial-6r`` with its built-in virtual truth (every joint
placement 0.1-0.5 mm and 0.01-0.05 deg off, src/armcal/robots/industrial-6r-truth.toml),
calibrated exactly: the calibration is the truth, so the true arm is the calibrated one.

The bound is the module's (armcal.compensation notes): a correction moves no joint by
more than ``MAX_AMPLIFICATION`` times the pose's error as an angle, ``hypot(e / R, a)``
for a tool ``e`` mm and ``a`` rad off, ``R`` the reach.  The contract's tolerances are
PRODUCT.md's ("Serial arms in 3-D": compensation reaches the nominal poses within 0.01 mm
and 0.001 deg).
"""

from __future__ import annotations

import numpy as np
import pytest

from armcal.compensation import MAX_AMPLIFICATION, compensate
from armcal.files import load_spatial_robot, load_spatial_truth
from armcal.models import (
    CalibratedArm,
    PlanarArm,
    SerialChain,
    SpatialArm,
    forward_kinematics,
    rotation_vector,
    vector_rotation,
)

CONTRACT_MM = 0.01
CONTRACT_DEG = 0.001


def _industrial() -> tuple[SpatialArm, np.ndarray, CalibratedArm]:
    spec = load_spatial_robot("industrial-6r")
    truth = load_spatial_truth(spec.default_truth, spec.arm)
    p = truth.size
    return spec.arm, truth, CalibratedArm(spec.arm, truth, np.zeros((p, p)), 0.03)


def _wrist_centre(arm: SpatialArm, q: np.ndarray) -> np.ndarray:
    """``(m, 3)``: where the axes of J4, J5 and J6 meet (nominal arm, robot frame).

    The URDF puts joint 5's origin at joint 4's (xyz 0) and the two axes through it, so
    the chain cut after joint 4 ends at the wrist centre.
    """
    chain = arm.chain
    upper = SerialChain(
        chain.origins[:4], chain.kinds[:4], np.eye(4), chain.joint_names[:4],
        chain.joint_limits[:4],
    )  # fmt: skip
    u = q @ arm.joint_map.T
    return upper.forward(u[:, :4])[:, :3, 3]


def _shoulder_singular_j3(arm: SpatialArm, j2: float) -> float:
    """The J3 reading (rad) that puts the wrist centre on the axis of J1 at this J2.

    The wrist centre's distance from the J1 axis, signed by its x in the arm's plane
    (J1 = 0), changes sign between J3 = 60 and 150 deg (the forearm, 1280 mm, swings
    back over the 312 mm shoulder offset): bisection to round-off.
    """

    def x(j3: float) -> float:
        return float(_wrist_centre(arm, np.array([[0.0, j2, j3, 0.0, 0.0, 0.0]]))[0, 0])

    lo, hi = np.radians(60.0), np.radians(150.0)
    assert x(lo) * x(hi) < 0
    for _ in range(100):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if x(lo) * x(mid) > 0 else (lo, mid)
    return 0.5 * (lo + hi)


def _meant_and_error(arm: SpatialArm, truth: np.ndarray, q0: np.ndarray) -> tuple:
    """Where the nominal arm (standing where the truth's base is) puts the tool, its
    rotation, and the true arm's error at the program as an angle (rad)."""
    nominal = np.where(arm.instrument_params, truth, arm.nominal)
    cond = arm.conditions(q0)
    meant = arm.positions(cond, nominal)
    meant_turn = vector_rotation(arm.orientation(cond, nominal))
    shift = np.linalg.norm(arm.positions(cond, truth) - meant, axis=1)
    turn = vector_rotation(arm.orientation(cond, truth)) @ np.swapaxes(meant_turn, 1, 2)
    angle = np.linalg.norm(rotation_vector(turn), axis=1)
    return meant, meant_turn, np.hypot(shift / arm.reach_mm, angle)


def _ordinary(arm: SpatialArm, rng: np.random.Generator, m: int) -> np.ndarray:
    """Poses tens of degrees from every singularity of this arm.

    J5 at 30-90 deg from 0 (the wrist amplifies by 1 / sin J5 <= 2); J2 within 30 deg
    and J3 within 45 deg of 0: the forearm stays 35 deg or more from stretched along
    the upper arm (at J2 = 0 that is J3 near 80 deg) and the wrist centre more than
    500 mm from the J1 axis; J1, J4 and J6 anywhere within the limits.
    """
    q = rng.uniform(arm.limits[:, 0], arm.limits[:, 1], (m, 6))
    q[:, 1] = rng.uniform(*np.radians([-30.0, 30.0]), m)
    q[:, 2] = rng.uniform(*np.radians([-45.0, 45.0]), m)
    q[:, 4] = rng.choice([-1.0, 1.0], m) * rng.uniform(*np.radians([30.0, 90.0]), m)
    return q


def test_poses_at_the_wrist_and_shoulder_singularities_are_refused_not_swung():
    arm, truth, cal = _industrial()
    rng = np.random.default_rng(11)
    ordinary = _ordinary(arm, rng, 40)
    # The shoulder: a J1 turn moves the tool by the wrist centre's distance from the J1
    # axis; the bound allows it when that distance is R / MAX_AMPLIFICATION or more.
    reach = np.hypot(*_wrist_centre(arm, ordinary)[:, :2].T)
    assert np.min(reach) > 2 * arm.reach_mm / MAX_AMPLIFICATION
    j3 = _shoulder_singular_j3(arm, np.radians(10.0))
    singular = np.radians(
        [
            [30.0, 10.0, 20.0, 40.0, 0.0, -30.0],  # J5 = 0: J4 and J6 on one axis
            [30.0, 10.0, 20.0, 40.0, np.degrees(1e-4), -30.0],  # J5 = 1e-4 rad
            [-60.0, 5.0, -10.0, -120.0, np.degrees(-1e-4), 75.0],
            [30.0, 10.0, np.degrees(j3), 40.0, -40.0, -30.0],  # wrist centre on J1's axis
            [30.0, 10.0, np.degrees(j3 + 1e-4), 40.0, -40.0, -30.0],  # 0.1 mm from it
        ]
    )
    assert np.hypot(*_wrist_centre(arm, singular[3:4])[0, :2]) < 1e-9
    q0 = np.concatenate([ordinary[:20], singular, ordinary[20:]])
    rows = np.arange(20, 20 + len(singular))
    result = compensate(cal, q0)

    refused = np.flatnonzero(~result.corrected)
    assert refused.tolist() == rows.tolist()
    for i in rows:
        assert result.reasons[i].startswith("near a singularity"), result.reasons[i]
    np.testing.assert_array_equal(result.q[rows], q0[rows])  # kept, never clipped

    # Every corrected row within its bound, derived here from the truth.
    meant, meant_turn, error = _meant_and_error(arm, truth, q0)
    bound = MAX_AMPLIFICATION * error
    np.testing.assert_allclose(np.radians(result.bound_deg), bound, rtol=1e-6, atol=0)
    change = np.max(np.abs(result.q - q0), axis=1)
    assert np.all(change[result.corrected] <= bound[result.corrected])

    # The true arm at the corrected commands reaches where the nominal arm meant.
    ok = result.corrected
    cond = arm.conditions(result.q[ok])
    reached = arm.positions(cond, truth)
    assert np.max(np.linalg.norm(reached - meant[ok], axis=1)) < CONTRACT_MM
    turn = vector_rotation(arm.orientation(cond, truth)) @ np.swapaxes(meant_turn[ok], 1, 2)
    assert np.degrees(np.max(np.linalg.norm(rotation_vector(turn), axis=1))) < CONTRACT_DEG


def test_ordinary_poses_still_converge_to_round_off():
    """Damping vanishes where Newton's step is within the bound: the iteration stops
    within tol_mm (1e-9 mm) of the goal, and the calibration is the truth here, so the
    true arm is there too, give or take the round-off of points 3 m out (~1e-12 mm)."""
    arm, truth, cal = _industrial()
    q0 = _ordinary(arm, np.random.default_rng(5), 200)
    result = compensate(cal, q0)
    assert result.corrected.all()
    meant, _, error = _meant_and_error(arm, truth, q0)
    reached = arm.positions(arm.conditions(result.q), truth)
    assert np.max(np.linalg.norm(reached - meant, axis=1)) < 2e-9
    # The corrections are the calibration's: a joint moves by a few times the error.
    assert np.all(np.max(np.abs(result.q - q0), axis=1) <= 4 * error)


def test_no_corrected_pose_of_a_random_program_leaves_its_bound():
    """Poses anywhere within the limits, singular ones included: a corrected pose
    reaches the goal within its bound, an uncorrected one keeps its command and says
    why; none is a swing to another branch of the inverse kinematics."""
    arm, truth, cal = _industrial()
    q0 = np.random.default_rng(2).uniform(arm.limits[:, 0], arm.limits[:, 1], (2000, 6))
    result = compensate(cal, q0)
    meant, meant_turn, error = _meant_and_error(arm, truth, q0)
    ok = result.corrected
    assert np.all(np.max(np.abs(result.q - q0), axis=1)[ok] <= MAX_AMPLIFICATION * error[ok])
    cond = arm.conditions(result.q[ok])
    reached = arm.positions(cond, truth)
    assert np.max(np.linalg.norm(reached - meant[ok], axis=1)) < CONTRACT_MM
    turn = vector_rotation(arm.orientation(cond, truth)) @ np.swapaxes(meant_turn[ok], 1, 2)
    assert np.degrees(np.max(np.linalg.norm(rotation_vector(turn), axis=1))) < CONTRACT_DEG
    np.testing.assert_array_equal(result.q[~ok], q0[~ok])
    assert all(result.reasons[i] for i in np.flatnonzero(~ok))
    assert all(not result.reasons[i] for i in np.flatnonzero(ok))


@pytest.mark.parametrize("elbow", [0.0, 1e-4])
def test_a_stretched_planar_arm_is_refused(elbow):
    """A 2-link arm stretched out (q2 = 0) cannot move its tip along the arm at first
    order.  The true arm is 0.5 mm longer (link errors 1.0 and -0.5 mm): to pull its tip
    in by 0.5 mm it must bend the elbow by sqrt(2 * 0.5 * 440 / (240 * 200)) = 5.5 deg,
    where the bound is 20 times the error as an angle, about 0.5 / 440 rad (1.3 deg).
    Refused; the bent pose (elbow 69 deg) is corrected to round-off."""
    arm = PlanarArm([240.0, 200.0])
    truth = arm.params_from_display([1.0, -0.5], [0.02, -0.01])
    cal = CalibratedArm(arm, truth, np.zeros((4, 4)), 0.01)
    q0 = np.array([[0.3, elbow], [0.3, 1.2]])
    result = compensate(cal, q0)
    assert result.corrected.tolist() == [False, True]
    assert result.reasons[0].startswith("near a singularity")
    np.testing.assert_array_equal(result.q[0], q0[0])
    reached = forward_kinematics(arm, result.q[1:], truth)
    np.testing.assert_allclose(reached, forward_kinematics(arm, q0[1:]), rtol=0, atol=1e-9)


def test_a_correction_within_its_bound_is_found_where_newtons_step_overshoots_it():
    """Poses whose exact correction lies within the bound while the linearized one (a
    Newton step from the program's commands) goes beyond it: the steps stop on the
    bound rather than the pose being refused.  Found among 20 000 random poses within
    the limits (seed 1): these five were refused while an iterate leaving the bound
    stopped the iteration; the linearized need is derived here by central differences
    of the true arm."""
    arm, truth, cal = _industrial()
    lim = arm.joint_limits
    q0 = np.random.default_rng(1).uniform(lim[:, 0], lim[:, 1], (20000, 6))
    q0 = q0[[1525, 5311, 7066, 11307, 11861]]
    meant, meant_turn, error = _meant_and_error(arm, truth, q0)
    bound = MAX_AMPLIFICATION * error

    def miss(q: np.ndarray) -> np.ndarray:  # (k, 6): mm and rad, the true arm's
        cond = arm.conditions(q)
        turn = vector_rotation(arm.orientation(cond, truth)) @ np.swapaxes(meant_turn, 1, 2)
        return np.concatenate([arm.positions(cond, truth) - meant, rotation_vector(turn)], 1)

    h = 1e-6  # rad: central differences, truncation ~ h^2, round-off ~ 1e-12 mm / h
    jac = np.stack([(miss(q0 + h * e) - miss(q0 - h * e)) / (2 * h) for e in np.eye(6)], axis=-1)
    linear = np.linalg.solve(jac, -miss(q0)[..., None])[..., 0]
    assert np.all(np.max(np.abs(linear), axis=1) > bound)  # Newton's step leaves the bound

    result = compensate(cal, q0)
    assert result.corrected.all(), result.reasons
    assert np.all(np.max(np.abs(result.q - q0), axis=1) <= bound)
    done = miss(result.q)
    assert np.max(np.linalg.norm(done[:, :3], axis=1)) < CONTRACT_MM
    assert np.degrees(np.max(np.linalg.norm(done[:, 3:], axis=1))) < CONTRACT_DEG


def test_newtons_step_is_taken_only_where_every_singular_value_is_kept():
    """The determinant rule of ``_newton_steps`` (``|det J| / |J|_F^n`` above 1e-8) admits
    no matrix whose condition number reaches ``1 / RANK_RTOL`` (1e-10), and the step it
    takes is the SVD's (``mu = 0``, every singular value kept) to round-off.  Matrices
    with condition numbers 1 to 1e14 by construction (``U diag(s) V^T``, log-uniform
    spread), one exactly singular, none within the radius for the last 10; every matrix
    with a condition number below 13.6 is admitted."""
    from armcal.compensation import _newton_steps, _svd_step
    from armcal.numerics import RANK_RTOL

    rng = np.random.default_rng(5)
    a, n = 400, 6
    u = np.linalg.qr(rng.standard_normal((a, n, n)))[0]
    v = np.linalg.qr(rng.standard_normal((a, n, n)))[0]
    cond = 10.0 ** rng.uniform(0, 14, a)
    s = np.exp(-np.log(cond)[:, None] * np.sort(rng.uniform(0, 1, (a, n)), axis=1))
    s[:, 0], s[np.arange(a), -1] = 1.0, 1.0 / cond  # s_max / s_min = cond exactly
    s *= 10.0 ** rng.uniform(-3, 3, (a, 1))  # the scale does not matter
    jac = np.einsum("aij,aj,akj->aik", u, s, v)
    jac[0, :, 0] = 0.0  # exactly singular
    residual = rng.standard_normal((a, n))
    radius = np.full(a, np.inf)
    radius[-10:] = 0.0
    found = _newton_steps(jac, residual, radius)
    assert found is not None
    easy, dq, gain = found
    true_cond = np.linalg.cond(jac[easy])
    assert np.all(true_cond < RANK_RTOL**-1 / 100)  # the margin of 100
    # It admits every matrix with cond^(n-1) n^(n/2) < 1e8 (|det J| >= s_max s_min^(n-1),
    # |J|_F <= sqrt(n) s_max): cond below 13.6 for n = 6.
    sure = (cond ** (n - 1) * n ** (n / 2) < 1e8) & (radius > 0)
    sure[0] = False
    assert sure.sum() > 20 and np.all(easy[sure])
    assert not easy[0] and not easy[-10:].any()
    svd = _svd_step(jac[easy], residual[easy], radius[easy], np.zeros((easy.sum(), n)))
    scale = np.linalg.norm(svd.dq, axis=1, keepdims=True)
    assert np.max(np.abs(dq[easy] - svd.dq) / scale / true_cond[:, None]) < 1e-13
    np.testing.assert_allclose(gain[easy], np.sum(residual[easy] ** 2, axis=1))
