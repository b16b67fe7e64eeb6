"""Property-based tests (hypothesis) of armcal's core invariants.

1. The analytic Jacobians agree with central differences of the forward kinematics.
2. Noiseless measurements are identified to round-off.
3. The paper's closed-form (orthogonal) plans have identity normalized information.
4. The covariance of an identification is symmetric positive definite.
5. The file readers raise nothing but armcal's own error, whatever the file holds.

Every tolerance is a first-order round-off (and truncation) bound derived where it
is used, from the double-precision unit ``EPS`` and the sizes of the problem at hand.
Every test is derandomized (the same examples on every run, so CI is reproducible)
and keeps no example database.  An ``@example`` is the smallest case of a bug the
property found (since fixed).
"""

from __future__ import annotations

import json
import math
import string
import sys

import numpy as np
import pytest
from hypothesis import HealthCheck, assume, example, given, reject, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from armcal import (
    ArmcalError,
    NotIdentifiableError,
    PlanarArm,
    Target,
    d_efficiency,
    design,
    forward_kinematics,
    identify,
    jacobian,
    joint_jacobian,
    orthogonal_plan,
    synthesize_measurements,
)
from armcal.criteria import efficiencies
from armcal.doe import analytic_plan
from armcal.files import (
    calibration_document,
    load_robot,
    load_truth,
    read_calibration,
    read_measurements,
    read_plan,
    read_program,
    to_json,
)
from armcal.models import every_target, paper_from_user, wrap_angle
from armcal.models.planar.criteria import scaled_information
from armcal.noise import NoiseModel

#: Unit round-off of double precision (2.2e-16).
EPS = float(np.finfo(float).eps)

#: Common settings: reproducible examples (derandomize), no example database written
#: into the work tree.  ``too_slow``: an example of the numeric properties runs a
#: least-squares identification (tens of ms), which is the point of the test, not slow
#: data generation; ``data_too_large``: a plan of up to 8 joints x 20 poses is drawn
#: float by float (so that every pose shrinks), more than the default budget expects.
NUMERIC = settings(
    deadline=None,
    derandomize=True,
    database=None,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large],
)
#: The readers: each example writes one small file and parses it.
PARSING = settings(deadline=None, derandomize=True, database=None, max_examples=60)


# ------------------------------------------------------------------------------ arms

#: Link lengths from 1 mm to 10 m (log-uniform): a watch-maker's arm to a crane.
LENGTHS_MM = st.floats(0.0, 4.0).map(lambda e: float(10.0**e))
#: Link lengths of one real arm: 10 mm to 2 m (a ratio of 200 between two links).
REAL_LENGTHS_MM = st.floats(1.0, math.log10(2000.0)).map(lambda e: float(10.0**e))
ANGLES = st.floats(-math.pi, math.pi)
LABELS = ("A", "B", "C")


@st.composite
def joint_maps(draw, n: int, several_targets: bool, ratios: bool) -> np.ndarray | None:
    """``None`` (the paper's map) or an invertible ``M``: a lower-triangular factor with
    +-1 on its diagonal (joints counted the other way round) and couplings below it
    (with ``ratios`` also gear ratios 0.5 and -2), optionally times an upper-triangular
    +-1 one.
    Both factors have determinant +-1, so ``M`` is invertible; with several targets
    the upper factor's last column is +-e_n, which keeps ``M``'s last column 0 above
    its last row, as the model requires."""
    if draw(st.booleans()):
        return None
    signs = draw(st.lists(st.sampled_from([1.0, -1.0]), min_size=n, max_size=n))
    lower = np.diag(signs)
    couplings = st.sampled_from([1.0, 1.0, 0.0, -1.0, *((0.5, -2.0) if ratios else ())])
    for i in range(n):
        for j in range(i):
            lower[i, j] = draw(couplings)
    mapping = lower
    if n > 1 and draw(st.booleans()):
        upper = np.diag(draw(st.lists(st.sampled_from([1.0, -1.0]), min_size=n, max_size=n)))
        last = n - 1 if several_targets else n
        for i in range(n):
            for j in range(i + 1, last):
                upper[i, j] = draw(st.sampled_from([0.0, 0.0, 1.0, -1.0]))
        mapping = lower @ upper
    return mapping


@st.composite
def arms(
    draw,
    *,
    fixed: bool = False,
    limits: bool = True,
    rotation: bool | None = None,
    ratios: bool = True,
    lengths_mm: st.SearchStrategy[float] = LENGTHS_MM,
) -> PlanarArm:
    """Any arm of 1..8 joints: lengths, joint map (with ``ratios``, gear ratios too),
    nominal joint offsets, 0/2/3 targets, base offset, base rotation (drawn, or as
    ``rotation`` says), joint limits, and (with ``fixed``) up to two fixed parameters
    besides the one a base rotation holds."""
    n = draw(st.integers(1, 8))
    lengths = draw(st.lists(lengths_mm, min_size=n, max_size=n))
    count = draw(st.sampled_from([0, 0, 2, 3]))
    targets = tuple(Target(LABELS[t], draw(lengths_mm), draw(ANGLES)) for t in range(count))
    mapping = draw(joint_maps(n, count > 1, ratios))
    offsets = draw(st.none() | st.lists(ANGLES, min_size=n, max_size=n))
    joint_limits = None
    if limits and draw(st.booleans()):
        centre = np.radians(draw(st.lists(st.floats(-90, 90), min_size=n, max_size=n)))
        half = np.radians(draw(st.lists(st.floats(45, 180), min_size=n, max_size=n)))
        joint_limits = np.column_stack([centre - half, centre + half])
    arm = PlanarArm(
        lengths,
        joint_limits,
        base_offset=draw(st.booleans()),
        base_rotation=draw(st.booleans()) if rotation is None else rotation,
        joint_map=mapping,
        targets=targets,
        joint_offsets=offsets,
        name="hypothesis-arm",
    )
    if fixed and draw(st.booleans()):
        names = arm.param_names
        held = draw(st.lists(st.sampled_from(names), max_size=min(2, len(names) - 1), unique=True))
        arm = arm.replace(fixed=tuple(held))
    return arm


@st.composite
def deviations(draw, arm: PlanarArm, *, scale: float = 1.0) -> np.ndarray:
    """User deviations (mm, rad) of a real arm, times ``scale``: lengths by up to 3 mm
    (at most 10 % of the link), joint offsets by up to 1 deg, the base by 20 mm and
    any rotation; 0 for fixed parameters."""
    k = arm.n_links
    unit = st.floats(-1.0, 1.0)
    dl = [draw(unit) * min(3.0, 0.1 * length) * scale for length in arm.link_nominal]
    dq = [math.radians(draw(unit) * scale) for _ in range(k)]
    values = dl + dq
    if arm.base_offset:
        values += [20.0 * draw(unit) * scale, 20.0 * draw(unit) * scale]
    if arm.base_rotation:
        values.append(draw(ANGLES))
    return np.array(values) * arm.free


@st.composite
def plans(draw, arm: PlanarArm, m: int) -> np.ndarray:
    """``m`` poses within the joint limits, every angle drawn on its own (no fill value,
    which would make plans of repeated angles)."""
    u = draw(arrays(float, (m, arm.n_joints), elements=st.floats(0.0, 1.0), fill=st.nothing()))
    lo, hi = arm.joint_limits[:, 0], arm.joint_limits[:, 1]
    return lo + u * (hi - lo)


def measured_rows(arm: PlanarArm, q: np.ndarray) -> tuple[np.ndarray, np.ndarray | None]:
    """Every target measured at every pose (several reflectors on the end effector)."""
    return every_target(arm, q) if arm.targets else (q, None)


# ------------------------------------------------------------------ round-off bounds


def angle_bound(arm: PlanarArm, q: np.ndarray, params: np.ndarray) -> np.ndarray:
    """Bound ``(m, K)`` on |angle| (rad) of every link vector of every row, plus 1 rad
    for the steps of the differences: ``|M| (|q| + |o|) + |alpha| + |A| |dq| + |phi0|``."""
    k = arm.n_links
    reading = np.abs(q) + np.abs(arm.joint_offsets)
    theta = (reading @ np.abs(arm.joint_map).T)[:, arm.link_joint]
    dtheta = np.abs(arm.angle_map) @ np.abs(params[k : 2 * k])
    if arm.base_rotation:
        dtheta = dtheta + abs(params[-1])
    return theta + np.abs(arm.link_angle0) + dtheta + 1.0


def tip_roundoff(arm: PlanarArm, q: np.ndarray, params: np.ndarray, weights=None) -> np.ndarray:
    """Bound ``(m,)`` on the round-off (mm) of a computed tip coordinate.

    The link angle ``M (q + o) + alpha + dtheta`` is a dot product of ``n`` terms and
    two sums: error ``<= (n + 2) EPS |angle|``; the phasor ``exp(i angle)`` adds
    2 ulp, the product with the length 1, and the sum of ``K`` link vectors and the
    base ``K + 1`` more.  ``weights`` ``(K,)`` weigh each link's share (the
    coefficients of a Jacobian column) instead of 1.
    """
    n, k = arm.n_joints, arm.n_links
    lengths = np.abs(arm.link_nominal + params[:k]) + 1.0  # +1 mm: the steps of 1 mm
    w = np.ones(k) if weights is None else np.abs(weights)
    links = ((n + 2) * angle_bound(arm, q, params) + k + 4) @ (lengths * w)
    base = (k + 1) * np.sum(np.abs(params[2 * k : 2 * k + 2]) + 1.0) if arm.base_offset else 0.0
    return EPS * (links + base)


# --------------------------------------------------------- 1. Jacobian = differences


def central_difference(f, x: np.ndarray, steps: np.ndarray) -> np.ndarray:
    """Central differences ``(m, 2, len(x))`` of ``f`` at ``x``, dividing by the step
    actually taken (``x + h`` and ``x - h`` are rounded)."""
    columns = []
    for j, h in enumerate(steps):
        plus, minus = x.copy(), x.copy()
        plus[j] += h
        minus[j] -= h
        columns.append((f(plus) - f(minus)) / (plus[j] - minus[j]))
    return np.stack(columns, axis=-1)


def difference_tolerance(e_tip: np.ndarray, third: np.ndarray, e_column: np.ndarray):
    """The best step per column and the bound on |analytic - difference| ``(m, 1, p)``.

    A central difference errs by ``h^2 / 6 |f'''|`` (truncation) plus ``E / h`` (the
    two tips' round-off ``E`` over the step ``2 h``); the analytic column itself errs
    by its own round-off.  ``h = (3 E / |f'''|)^(1/3)`` minimizes the first two; a
    column linear in its parameter (``f''' = 0``) takes a 1 mm step.
    """
    e_max = float(np.max(e_tip))
    third_max = np.max(third, axis=0)
    with np.errstate(divide="ignore"):
        steps = np.where(third_max > 0, np.cbrt(3 * e_max / third_max), 1.0)
    tol = third * steps**2 / 6 + e_tip[:, None] / steps + e_column
    return steps, tol[:, None, :]


@settings(NUMERIC, max_examples=50)
@given(data=st.data())
def test_jacobians_agree_with_central_differences(data):
    arm = data.draw(arms(limits=False), label="arm")
    params = data.draw(deviations(arm, scale=30.0), label="params")
    m = data.draw(st.integers(1, 4), label="rows")
    q = data.draw(arrays(float, (m, arm.n_joints), elements=ANGLES, fill=st.nothing()), label="q")
    target = None
    if arm.targets:
        target = np.array(
            data.draw(
                st.lists(st.integers(0, len(arm.targets) - 1), min_size=m, max_size=m),
                label="target",
            )
        )
    k, p = arm.n_links, arm.n_params
    lengths = np.abs(arm.link_nominal + params[:k])
    e_tip = tip_roundoff(arm, q, params)

    # Parameters: dl_k and the base move the tip linearly (f''' = 0); dq_j turns link
    # vector k by A_kj and phi0 turns them all, so |f'''| <= sum_k L_k |c_kj|^3.
    coefficients = np.zeros((k, p))  # how each parameter turns or stretches each link
    coefficients[:, :k] = np.eye(k)
    coefficients[:, k : 2 * k] = arm.angle_map
    if arm.base_rotation:
        coefficients[:, -1] = 1.0
    angle = arm.angle_params
    third = np.where(angle, lengths @ np.abs(coefficients) ** 3, 0.0)[None, :].repeat(m, 0)
    e_column = np.stack(
        [tip_roundoff(arm, q, params, coefficients[:, j]) for j in range(p)], axis=-1
    )
    if arm.base_offset:
        e_column[:, 2 * k : 2 * k + 2] = EPS  # constant columns (1, 0) and (0, 1)
    steps, tol = difference_tolerance(e_tip, third, e_column)
    analytic = jacobian(arm, q, params, target=target)
    numeric = central_difference(
        lambda x: forward_kinematics(arm, q, x, target=target), params, steps
    )
    assert np.all(np.abs(analytic - numeric) <= tol)

    # The paper's parametrization is the user one through the constant map P
    # (J_user = J_paper P).  The round-off bound is linear in the column weights, so
    # the paper columns' round-off carried through |P| is the user columns' own; the
    # product adds K + 2 EPS times the sum of the magnitudes it adds up.
    mapping = paper_from_user(arm)
    paper = jacobian(arm, q, params, target=target, parametrization="paper")
    size = np.abs(paper) @ np.abs(mapping)
    bound = 2 * e_column[:, None, :] + (k + 2) * EPS * size
    assert np.all(np.abs(paper @ mapping - analytic) <= bound)

    # Joints: q_j turns link vector k by M[a(k), j].
    turns = arm.joint_map[arm.link_joint]  # (K, n)
    third = (lengths @ np.abs(turns) ** 3)[None, :].repeat(m, 0)
    e_column = np.stack(
        [tip_roundoff(arm, q, params, turns[:, j]) for j in range(arm.n_joints)], axis=-1
    )
    steps, tol = difference_tolerance(e_tip, third, e_column)
    analytic = joint_jacobian(arm, q, params, target=target)
    rows = [
        central_difference(
            lambda x, i=i: forward_kinematics(
                arm, x[None, :], params, target=None if target is None else target[i : i + 1]
            ),
            q[i],
            steps,
        )[0]
        for i in range(m)
    ]
    assert np.all(np.abs(analytic - np.stack(rows)) <= tol)


# ------------------------------------------------------------- 2. noiseless recovery


@st.composite
def experiments(
    draw,
    *,
    fixed: bool,
    spare: tuple[int, int],
    rotation: bool | None = None,
    lengths_mm: st.SearchStrategy[float] = LENGTHS_MM,
):
    """An arm, its true deviations, and a random plan of enough poses: every target
    measured at every pose, ``2 m T`` equations for ``p_f`` free parameters plus
    ``spare`` (a range) more poses."""
    arm = draw(arms(fixed=fixed, rotation=rotation, lengths_mm=lengths_mm), label="arm")
    truth = draw(deviations(arm), label="truth")
    least = -(-arm.n_free // (2 * arm.n_target_links))
    m = draw(st.integers(least + spare[0], least + spare[1]), label="poses")
    q = draw(plans(arm, m), label="plan")
    return arm, truth, q


def pseudo_inverse_row_norms(jac: np.ndarray) -> np.ndarray:
    """``||e_j^T J^+||`` ``(p,)`` of a full-rank ``J`` ``(r, p)``, by the SVD of ``J`` with
    unit-norm columns (so that mm and rad columns do not spoil its accuracy)."""
    norms = np.linalg.norm(jac, axis=0)
    _, s, vt = np.linalg.svd(jac / norms, full_matrices=False)
    return np.linalg.norm(vt.T / s, axis=1) / norms


def recovery_tolerance(arm: PlanarArm, rows: np.ndarray, truth: np.ndarray, target) -> np.ndarray:
    """Bound ``(p,)`` on |identified - truth| (mm, rad) for noiseless data, from the
    condition of the problem.

    To first order the estimate errs by ``J^+ r``, with ``J`` the free columns of the
    Jacobian at the truth and ``r`` the perturbation the round-off amounts to in the
    data: the measured tips' own round-off (``tip_roundoff`` per coordinate, once for
    the data and once for the model the solver subtracts) and the backward error of
    the Householder-QR least-squares solve (Higham, Accuracy and Stability of
    Numerical Algorithms, 2nd ed., Thm 20.3: columnwise ``||dA_j|| <= gamma ||A_j||``
    and ``||db|| <= gamma ||b||`` with ``gamma = r p EPS``).  In the link-phasor
    regressor every column has norm ``<= sqrt(rows)`` and its coefficient is a link's
    length, so ``||dA x|| <= gamma sqrt(rows) (2 sum L + 2 |base|)``;
    ``||b|| <= sqrt(2 rows) max |tip|``.  Then ``|dp_j| <= ||e_j^T J^+|| ||r||``.  The map
    back to lengths and angles (``|z| - l``, ``arg z``, the joint map's inverse) adds
    a few EPS of the reach and of pi times ``||P^-1||``.
    """
    k, count = arm.n_links, rows.shape[0]
    free = arm.free
    jac = jacobian(arm, rows, truth, target=target)[..., free].reshape(2 * count, -1)
    gamma = 2 * count * arm.n_free * EPS
    lengths = np.abs(arm.link_nominal + truth[:k])
    base = float(np.sum(np.abs(truth[2 * k : 2 * k + 2]))) if arm.base_offset else 0.0
    tips = np.abs(forward_kinematics(arm, rows, truth, target=target))
    data = 2 * np.linalg.norm(tip_roundoff(arm, rows, truth)) * math.sqrt(2)
    solve = gamma * (
        math.sqrt(count) * 2 * (np.sum(lengths) + base) + math.sqrt(2 * count) * np.max(tips)
    )
    reach = float(np.sum(lengths) + base)
    back = np.linalg.norm(np.linalg.pinv(paper_from_user(arm)[:, free]), np.inf)
    floor = np.where(arm.angle_params[free], math.pi * back, reach) * 8 * EPS
    return pseudo_inverse_row_norms(jac) * (data + solve) + floor


def check_noiseless_recovery(arm: PlanarArm, truth: np.ndarray, q: np.ndarray) -> None:
    """Measure the plan without noise, identify, and compare with the truth."""
    rows, target = measured_rows(arm, q)
    xy = synthesize_measurements(arm, rows, truth, 0.0, target=target, rng=0)
    try:
        cal = identify(arm, rows, xy, sigma=0.05, target=target)
    except NotIdentifiableError:
        reject()  # a random plan that cannot see some combination: the library says so
    assert cal.converged
    free = arm.free
    error = cal.params - truth
    error[arm.angle_params] = wrap_angle(error[arm.angle_params])  # the same link angles
    assert np.all(cal.params[~free] == 0.0)
    assert np.all(np.abs(error[free]) <= recovery_tolerance(arm, rows, truth, target))


@settings(NUMERIC, max_examples=40)
@given(
    st.one_of(
        experiments(fixed=False, spare=(1, 6)),  # every parameter free: the closed form
        experiments(fixed=True, spare=(1, 6), rotation=False),  # fixed: Gauss-Newton
    )
)
def test_noiseless_measurements_are_identified_to_round_off(experiment):
    check_noiseless_recovery(*experiment)


#: The smallest case of the bug below: a 2-link arm with a base rotation (3-D data,
#: whose fitted in-plane axes turn the base by any angle) and dl1 fixed, the base
#: turned by 3 rad, nothing else deviating.
FAR_ROTATION = (
    PlanarArm([260.0, 180.0], base_rotation=True, fixed=("dl1",)),
    np.array([0.0, 0.0, 0.0, 0.0, 3.0]),
    np.radians([[0, 0], [0, 90], [90, 90], [45, -120], [-60, 30]]),
)


@settings(NUMERIC, max_examples=20)
@example(FAR_ROTATION)
@given(experiments(fixed=True, spare=(1, 6), rotation=True))
def test_noiseless_3d_arms_with_fixed_parameters_are_identified_to_round_off(experiment):
    arm = experiment[0]
    assume(not arm.complete)  # fixed parameters besides the one the rotation holds
    check_noiseless_recovery(*experiment)


# -------------------------------------------------- 3. analytic plans are orthogonal


def expected_information(arm: PlanarArm, rows: np.ndarray, target) -> np.ndarray:
    """The paper's information ``F`` of an orthogonal plan (eq. 24, Table II), any arm:
    diagonal, ``c_k L_k^2`` for ``dtheta_k`` and ``c_k`` for ``dl_k`` with ``c_k`` the rows
    that measure link vector ``k`` (all of them for a shared link, one per pose for a
    target's last link), and the row count for each base coordinate."""
    k0 = arm.n_joints - 1
    counts = np.full(arm.n_links, float(rows.shape[0]))
    if target is not None:
        counts[k0:] = np.bincount(target, minlength=arm.n_target_links)
    diagonal = [counts * arm.link_nominal**2, counts]
    if arm.base_offset:
        diagonal.append(np.full(2, float(rows.shape[0])))
    return np.diag(np.concatenate(diagonal))


def orthogonality_tolerance(arm: PlanarArm, q: np.ndarray) -> float:
    """Bound on ``|Fs - I|`` entrywise for a computed orthogonal plan.

    In exact arithmetic the sums ``sum_i exp(i (theta_a - theta_b))`` vanish.  The
    computed plan's link angles err by the steps ``2 pi k / m`` (2 ulp of pi), the
    joint map's solve (``cond(M) n EPS`` of the angles), the wrap and the offsets
    (a few EPS of ``pi + |o|``), and the library's ``M (q + o)`` again: at most
    ``delta = 4 (n + 2) cond(M) EPS Theta`` with ``Theta`` the largest |angle|.  Each
    normalized entry is a mean of unit products, off by ``2 delta`` each plus the sum's
    ``rows EPS``; a target's columns carry weight ``sqrt(T)`` (their rows are ``1 / T``
    of all), so its entries by ``T`` times that.
    """
    n, count = arm.n_joints, arm.n_target_links
    theta = float(np.max(angle_bound(arm, q, np.zeros(arm.n_params))))
    delta = 4 * (n + 2) * np.linalg.cond(arm.joint_map) * EPS * theta
    return count * (2 * delta + (q.shape[0] * count + 3) * EPS)


def check_orthogonal(arm: PlanarArm, q: np.ndarray) -> None:
    """``Fs = I`` (paper eq. 21), efficiencies 1, and ``F = F_opt`` computed apart."""
    p = arm.n_paper
    tol = orthogonality_tolerance(arm, q)
    assert np.all(np.abs(scaled_information(arm, q) - np.eye(p)) <= tol)
    # |s_i^2 - 1| <= ||Fs - I||_2 <= p tol for the singular values of H (Weyl); every
    # efficiency is a mean of s_i^2 (or their inverse, or the least): within 2 p tol,
    # plus the SVD's own p EPS.
    for name, value in efficiencies(arm, q).items():
        assert abs(float(value) - 1.0) <= 2 * p * tol + p * EPS, name
    assert abs(float(d_efficiency(arm, q)) - 1.0) <= 2 * p * tol + p * EPS
    # The information from the analytic Jacobian, measured at every target of every pose.
    rows, target = measured_rows(arm, q)
    jac = jacobian(arm, rows, target=target, parametrization="paper").reshape(-1, p)
    expected = expected_information(arm, rows, target)
    scale = np.sqrt(np.diag(expected))
    normalized = (jac.T @ jac) / np.outer(scale, scale)
    assert np.all(np.abs(normalized - np.eye(p)) <= tol)


@st.composite
def orthogonal_designs(draw, *, ratios: bool) -> tuple[PlanarArm, int]:
    """An arm whose every parameter is free under isotropic noise (the paper's model,
    up to joint map, targets, offsets and base rotation) and a number of poses for
    which the closed form exists: ``m >= n``, ``m > n`` with a base offset."""
    arm = draw(arms(ratios=ratios), label="arm")
    least = arm.n_joints + (1 if arm.base_offset else 0)
    return arm, draw(st.integers(least, least + 24), label="poses")


def check_closed_form_plans(arm: PlanarArm, m: int) -> None:
    """orthogonal_plan, analytic_plan (within the limits, where it fits: the library
    says when it does not) and design(method="analytic") are all orthogonal."""
    check_orthogonal(arm, orthogonal_plan(arm, m))
    try:
        placed = analytic_plan(arm, m)
    except ArmcalError:
        return
    assert np.all(arm.within_limits(placed))
    check_orthogonal(arm, placed)
    if 2 * m < arm.n_free:  # design asks for ceil(p_f / 2) poses, whatever the targets
        return
    chosen = design(arm, m, method="analytic", with_certificate=False, order="none")
    assert chosen.method == "analytic"
    assert np.all(arm.within_limits(chosen.q))
    check_orthogonal(arm, chosen.q)


@settings(NUMERIC, max_examples=40)
@given(orthogonal_designs(ratios=False))
def test_closed_form_plans_are_orthogonal(case):
    check_closed_form_plans(*case)


@settings(NUMERIC, max_examples=20)
@example((PlanarArm([100.0, 100.0], joint_map=[[1, 0], [0.5, 1]], base_offset=True), 3))
@given(orthogonal_designs(ratios=True))
def test_closed_form_plans_are_orthogonal_with_gear_ratios(case):
    check_closed_form_plans(*case)


# --------------------------------------------------- 4. covariance is positive definite


@st.composite
def noisy_identifications(draw) -> tuple:
    """An experiment measured with noise, and how it is identified: the noise given or
    estimated, isotropic, per axis or with encoder noise, robust or not.

    The links are those of one real arm (``REAL_LENGTHS_MM``): with a 1 mm link next to
    a 10 m one the joint offsets' estimates correlate to within 1e-12 of +-1, and no
    eigensolver in double precision can then tell the correlation matrix's least
    eigenvalue from 0 (the check below needs it above ``p EPS``).
    """
    arm, truth, q = draw(
        experiments(fixed=True, spare=(2, 8), rotation=False, lengths_mm=REAL_LENGTHS_MM),
        label="case",
    )
    kind = draw(st.sampled_from(["isotropic", "per-axis", "encoder"]), label="noise")
    sigma = draw(st.floats(1e-3, 1.0), label="sigma")
    if kind == "per-axis":
        arm = arm.replace(noise=NoiseModel.per_axis(sigma, draw(st.floats(1e-3, 1.0))))
    elif kind == "encoder":
        arm = arm.replace(noise=NoiseModel.isotropic(sigma, math.radians(0.001)))
    options = {
        "sigma": draw(st.sampled_from([None, sigma])) if kind == "isotropic" else None,
        "robust": draw(st.booleans(), label="robust"),
    }
    seed = draw(st.integers(0, 2**32 - 1), label="seed")
    return arm, truth, q, sigma, seed, options


@settings(NUMERIC, max_examples=30)
@given(noisy_identifications())
def test_covariance_is_symmetric_positive_definite(case):
    arm, truth, q, sigma, seed, options = case
    rows, target = measured_rows(arm, q)
    drawn = sigma if arm.noise is None else None  # else the arm's own noise model
    xy = synthesize_measurements(arm, rows, truth, drawn, target=target, rng=seed)
    try:
        cal = identify(arm, rows, xy, target=target, **options)
    except NotIdentifiableError:
        reject()
    free = arm.free
    cov = cal.covariance
    assert cov.shape == (arm.n_params, arm.n_params)
    assert np.all(np.isfinite(cov))
    assert np.all(cov[~free] == 0.0) and np.all(cov[:, ~free] == 0.0)
    c = cov[np.ix_(free, free)]
    p = c.shape[0]
    d = np.sqrt(np.diag(c))
    assert np.all(d > 0)
    # C = s^2 G G^T: entry (i, j) and (j, i) are dot products of the same p terms,
    # each within gamma_p |g_i| |g_j| = p EPS sqrt(C_ii C_jj) of the exact value.
    assert np.all(np.abs(c - c.T) <= 2 * p * EPS * np.outer(d, d))
    # Positive definite: the correlation matrix has the same inertia (Sylvester) and
    # unit diagonal; a symmetric eigensolver finds its eigenvalues within p EPS of its
    # norm, so the least one above that bound proves every eigenvalue positive.
    corr = c / np.outer(d, d)
    values = np.linalg.eigvalsh((corr + corr.T) / 2)
    assert values[0] > p * EPS * values[-1]
    assert np.all(cal.std[free] > 0) and np.all(cal.std[~free] == 0)


# ------------------------------------------------------------------- 5. the readers

#: Robots the CSV and truth readers are given: no limits, limits, several targets with a
#: base offset, one joint.
PARSER_ARMS = (
    PlanarArm([260.0, 180.0], name="plain2"),
    PlanarArm(
        [260.0, 180.0, 120.0], np.radians([[-170, 170], [-150, 150], [-150, 150]]), name="lim3"
    ),
    PlanarArm(
        [260.0, 180.0, 100.0],
        targets=(Target("A", 100.0), Target("B", 80.0, 0.7)),
        base_offset=True,
        name="nest",
    ),
    PlanarArm([400.0], name="one"),
)

#: Every file reader, taking the path (and the robot for those that need one).
READERS = {
    "measurements": lambda path, arm: read_measurements(path, arm),
    "plan": lambda path, arm: read_plan(path, arm),
    "program": lambda path, arm: read_program(path, arm),
    "robot": lambda path, arm: load_robot(path),
    "truth": lambda path, arm: load_truth(path, arm),
    "calibration": lambda path, arm: read_calibration(path),
}


@pytest.fixture(scope="module")
def scratch(tmp_path_factory):
    """One folder for the files the examples write: hypothesis refuses function-scoped
    fixtures such as ``tmp_path``, which every example of a test would share."""
    return tmp_path_factory.mktemp("readers")


def read_only_armcal_errors(reader: str, folder, content: str | bytes, arm=PARSER_ARMS[0]):
    """Write ``content`` to a file and read it: anything but an ArmcalError propagates."""
    path = folder / "input.txt"
    path.write_bytes(content.encode("utf-8") if isinstance(content, str) else content)
    try:
        READERS[reader](path, arm)
    except ArmcalError:
        pass  # the one error a file may cause: exit status 2 and one line


#: Characters of the formats: CSV and TOML punctuation, digits, the letters of the
#: column names and keys, both line ends, a tab, a BOM, a NUL and a non-ASCII letter.
SYNTAX = string.digits + "qdegxyzmm_,;\t\n\r \"'#=[]{}.-+eE@" + "\ufeff\x00é"
ANY_TEXT = st.one_of(st.text(max_size=300), st.binary(max_size=300), st.text(SYNTAX, max_size=300))


@pytest.mark.parametrize("reader", list(READERS))
@settings(PARSING)
@given(content=ANY_TEXT, arm=st.sampled_from(PARSER_ARMS))
def test_readers_raise_only_armcal_errors_on_any_text(reader, content, arm, scratch):
    read_only_armcal_errors(reader, scratch, content, arm)


# CSV-like text: plausible columns, numbers and the things spreadsheets and instruments
# write (separators, quotes, BOM, CRLF, comment lines, decimal commas, nan and inf).

COLUMN_NAMES = (
    *(f"q{j}_deg" for j in range(1, 5)),
    "q0_deg",
    "q10_deg",
    "q1_rad",
    "x_mm",
    "y_mm",
    "z_mm",
    "x_m",
    "pose",
    "target",
    "sigma_mm",
    "payload_kg",
    "fx_N",
    "fy_N",
    "corrected",
    "Q1_DEG",
    " x_mm ",
    "",
    '"y_mm"',
)
NUMBER_TEXTS = st.one_of(
    st.floats(-400.0, 400.0).map(repr),
    st.floats(-400.0, 400.0).map(lambda x: f"{x:.3f}".replace(".", ",")),  # decimal comma
    st.floats(allow_nan=True, allow_infinity=True).map(lambda x: f"{x:g}"),
    st.integers(-(10**20), 10**20).map(str),
    st.sampled_from(
        ["nan", "NaN", "inf", "-inf", "1e999", "-0", "1e-400", "1_000", "0x10", "", " ", "A"]
    ),
    st.sampled_from(["B", "C", '"1,5"', '"', "'", "#", "\x00", "١٢", "  12  ", '"A"']),
)
#: A field that is usually right for its column: a joint angle or position of a few
#: hundred (deg or mm), a small sigma or load, a target or pose label.
FIELD_TEXTS = {
    "target": st.sampled_from(["A", "B", "C", "", "A B"]),
    "pose": st.text(max_size=4) | st.sampled_from(['"P1"', '"pose\n2"']),  # quoted: legal
    "sigma_mm": st.floats(1e-7, 2.0).map(repr),
    "payload_kg": st.floats(-1.0, 20.0).map(repr),
}
PLAIN_NUMBERS = st.floats(-200.0, 200.0).map(lambda x: f"{x:.6g}")


@st.composite
def csv_like(draw, arm: PlanarArm, required: tuple[str, ...], optional: tuple[str, ...]) -> str:
    """A CSV file as people write them: often the right columns for ``arm`` (the joint
    columns, ``required`` and some ``optional`` ones, in any order) with fields that are
    mostly right, else any plausible column names and fields; mostly one field per
    column, a separator, line ends, comment and blank lines, maybe a BOM."""
    right = draw(st.booleans())
    if right:
        names = [f"q{j}_deg" for j in range(1, arm.n_joints + 1)] + list(required)
        names += draw(st.lists(st.sampled_from(optional), unique=True, max_size=3))
        header = draw(st.permutations(names))
    else:
        header = draw(st.lists(st.sampled_from(COLUMN_NAMES), max_size=8))
    separator = draw(st.sampled_from([",", ",", ",", ";", "\t", ", ", " ", "|"]))
    end = draw(st.sampled_from(["\n", "\r\n", "\r"]))
    lines = [separator.join(header)]
    for _ in range(draw(st.integers(1 if right else 0, 6))):
        count = len(header) if not draw(one_in(5)) else draw(st.integers(0, len(header) + 2))
        columns = header + [""] * max(0, count - len(header))
        fields = []
        for name in columns[:count]:
            usual = FIELD_TEXTS.get(name, PLAIN_NUMBERS)
            field = draw(NUMBER_TEXTS if draw(one_in(8)) or not right else usual)
            fields.append(f'"{field}"' if draw(one_in(10)) else field)  # quoted, as some write
        if separator == ";":  # a European spreadsheet's decimal comma
            fields = [f.replace(".", ",") for f in fields]
        lines.append(separator.join(fields))
    for _ in range(draw(st.integers(0, 2))):  # comment and blank lines anywhere
        where = draw(st.integers(0, len(lines)))
        lines.insert(where, draw(st.sampled_from(["# exported by a tracker", "", "  #", " "])))
    bom = draw(st.sampled_from(["", "\ufeff"]))
    return bom + end.join(lines) + draw(st.sampled_from(["", end]))


#: Each CSV reader's required columns besides the joints, and its optional ones.
CSV_READERS = {
    "measurements": (
        ("x_mm", "y_mm"),
        ("z_mm", "pose", "target", "sigma_mm", "payload_kg", "fx_N", "fy_N"),
    ),
    "plan": ((), ("payload_kg",)),
    "program": ((), ("pose", "target", "payload_kg", "fx_N", "fy_N")),
}


@st.composite
def csv_cases(draw) -> tuple[str, PlanarArm, str]:
    reader = draw(st.sampled_from(list(CSV_READERS)))
    arm = draw(st.sampled_from(PARSER_ARMS))
    return reader, arm, draw(csv_like(arm, *CSV_READERS[reader]))


@settings(PARSING)
@example(case=("plan", PARSER_ARMS[3], 'q1_deg\n"1\n2\n'))
@given(case=csv_cases())
def test_csv_readers_raise_only_armcal_errors_on_csv_like_text(case, scratch):
    reader, arm, text = case
    read_only_armcal_errors(reader, scratch, text, arm)


@settings(PARSING)
@example(case=("m", None, "q1_deg,q2_deg,x_mm,y_mm,pose\n1,2,3,4,a\n 5 ,6,7,8, b\n"))
@example(case=("m", None, "\n \nq1_deg|target\n1|A\n2|B"))
@example(case=("m", None, "q1_deg\n1\n2\n\u00a0\n"))
@example(case=("m", None, "q1_deg,x_mm\n1,2\n ,\n3,4\n"))
@given(case=csv_cases())
def test_the_plain_split_is_the_general_reader_s(case):
    """A file with no comment, quote, carriage return or blank line (what instruments and
    armcal write) is split in one call; where it is, the header, every row's file line
    and every column's fields are the general reader's."""
    from armcal.files.csv_read import _plain_fields, general_split

    text = case[2]
    plain = _plain_fields(text)
    if plain is None:
        return
    general = general_split("f.csv", text, "(layout)")
    assert (plain.header_line, plain.header_raw, plain.header, plain.delimiter) == (
        general.header_line, general.header_raw, general.header, general.delimiter,
    )  # fmt: skip
    assert plain.lines == general.lines
    assert plain.fields is not None and general.fields is not None
    for c in range(len(plain.header)):
        assert plain.fields(c) == general.fields(c)


# Robot and truth TOML: keys from the real ones (in their tables and in others), values
# of every TOML type, often plausible ones.

TABLE_KEYS = {
    "": (
        "name",
        "link_lengths_mm",
        "joint_limits_deg",
        "base_offset",
        "joint_map",
        "joint_offsets_deg",
    ),
    "measurement": ("sigma_mm", "covariance_mm2", "joint_sigma_deg", "region", "gravity"),
    "identify": ("fixed", "free"),
    "elastostatic": ("gravity_xy", "link_masses_kg", "com_fraction", "payload_kg"),
}
REGION_KEYS = ("kind", "center_mm", "r_min_mm", "r_max_mm", "x_mm", "y_mm")
PARAMETER_NAMES = ("dl1", "dl2", "dl3", "dq1", "dq2", "x0", "y0", "phi0", "dl3@A", "dq9")
NUMBERS = st.one_of(
    st.floats(-400.0, 400.0),
    st.integers(-400, 400),
    st.floats(allow_nan=True, allow_infinity=True),
    st.integers(-(2**63), 2**63 - 1),
    st.sampled_from([0, 1, 2, 1e-7, 1e-320, 1e9, 1e10, -1]),
)
TOML_SCALARS = st.one_of(NUMBERS, st.booleans(), st.text(max_size=8))
TOML_VALUES = st.recursive(
    TOML_SCALARS,
    lambda inner: (
        st.lists(inner, max_size=4)
        | st.dictionaries(st.sampled_from([*REGION_KEYS, "length_mm", "x"]), inner, max_size=3)
    ),
    max_leaves=8,
)


def one_in(k: int) -> st.SearchStrategy[bool]:
    """True about once in ``k`` draws (``integers`` would favour its bounds)."""
    return st.sampled_from([False] * (k - 1) + [True])


def numbers(max_size: int = 4) -> st.SearchStrategy[list]:
    return st.lists(NUMBERS, max_size=max_size)


PLAUSIBLE = {
    "name": st.text(min_size=1, max_size=8),
    "link_lengths_mm": numbers(),
    "joint_limits_deg": st.lists(numbers(3), max_size=4),
    "base_offset": st.booleans(),
    "joint_map": st.lists(st.lists(st.sampled_from([-1, 0, 1, 0.5]), max_size=4), max_size=4),
    "joint_offsets_deg": numbers(),
    "sigma_mm": NUMBERS | numbers(3),
    "covariance_mm2": st.lists(numbers(3), max_size=3),
    "joint_sigma_deg": NUMBERS | numbers(),
    "region": st.fixed_dictionaries(
        {"kind": st.sampled_from(["annulus", "box", "disc", 3])},
        optional={key: NUMBERS | numbers(3) for key in REGION_KEYS[1:]},
    ),
    "gravity": numbers(),
    "fixed": st.lists(st.sampled_from(PARAMETER_NAMES), max_size=3),
    "free": st.lists(st.sampled_from(PARAMETER_NAMES), max_size=3),
    "gravity_xy": numbers(3),
    "link_masses_kg": numbers(),
    "com_fraction": NUMBERS | numbers(),
    "payload_kg": NUMBERS,
    "dl_mm": numbers(5),
    "dq_deg": numbers(5),
    "base_mm": numbers(3),
    "k_urad_per_Nm": numbers(),
    "c_mdeg_per_m": numbers(),
}


def toml_key(key: str) -> str:
    bare = key and all(c.isascii() and (c.isalnum() or c in "_-") for c in key)
    return key if bare else json.dumps(key, ensure_ascii=False)


def toml_value(value) -> str:
    """TOML for a value (JSON's escapes are TOML's; nan and inf are TOML floats)."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, float):
        return "nan" if math.isnan(value) else repr(value)  # inf, -inf: TOML's own
    if isinstance(value, int | str):
        return json.dumps(value, ensure_ascii=False)
    if isinstance(value, list):
        return "[" + ", ".join(toml_value(v) for v in value) + "]"
    return "{" + ", ".join(f"{toml_key(k)} = {toml_value(v)}" for k, v in value.items()) + "}"


@st.composite
def toml_lines(draw, keys: tuple[str, ...]) -> list[str]:
    """``key = value`` lines for some of ``keys`` (now and then a stranger), with
    plausible values or any."""
    chosen = draw(st.lists(st.sampled_from(keys), unique=True, max_size=5)) if keys else []
    if draw(one_in(8)):
        chosen.append(draw(st.sampled_from(["bogus", "sigma", "Link_lengths_mm"])))
    return [
        f"{toml_key(key)} = {toml_value(draw(PLAUSIBLE.get(key, TOML_VALUES) | TOML_VALUES))}"
        for key in chosen
    ]


@st.composite
def robot_files(draw) -> str:
    lines = []
    top = TABLE_KEYS[""]
    if not draw(one_in(4)):  # usually the one required key, with plausible lengths
        lengths = draw(st.lists(st.floats(1.0, 500.0), min_size=1, max_size=4))
        lines.append(f"link_lengths_mm = {toml_value(lengths)}")
        top = tuple(key for key in top if key != "link_lengths_mm")
    lines += draw(toml_lines(top))
    tables = st.sampled_from(["measurement", "identify", "elastostatic", "targets"] * 3 + ["x"])
    for table in draw(st.lists(tables, unique=True, max_size=4)):
        lines.append(f"[{table}]")
        if table == "targets":
            labels = st.sampled_from(["A", "B", "C", "", "a b", "x@y"])
            for label in draw(st.lists(labels, unique=True, max_size=3)):
                entry = st.fixed_dictionaries(
                    {}, optional={"length_mm": NUMBERS, "angle_deg": NUMBERS, "x": NUMBERS}
                )
                lines.append(f"{toml_key(label)} = {toml_value(draw(entry | TOML_VALUES))}")
        else:  # its own keys, and now and then one of another table
            keys = TABLE_KEYS.get(table, ())
            if draw(one_in(4)):
                keys += (draw(st.sampled_from(TABLE_KEYS[""] + TABLE_KEYS["measurement"])),)
            lines += draw(toml_lines(keys))
    return "\n".join(lines) + "\n"


@settings(PARSING)
@given(text=robot_files())
def test_load_robot_raises_only_armcal_errors(text, scratch):
    read_only_armcal_errors("robot", scratch, text)


@st.composite
def truth_cases(draw) -> tuple[PlanarArm, str]:
    """A robot and a truth file for it: usually the required keys with one number per
    joint or per link vector (or another count), then any of the keys."""
    arm = draw(st.sampled_from(PARSER_ARMS))
    lines = []
    keys: tuple[str, ...] = ("dl_mm", "dq_deg", "base_mm", "k_urad_per_Nm", "c_mdeg_per_m")
    count = st.sampled_from([arm.n_joints, arm.n_links, 1, 2, 3, 4])
    for key in ("dl_mm", "dq_deg"):
        if not draw(one_in(5)):
            size = draw(count)
            values = draw(st.lists(st.floats(-5.0, 5.0), min_size=size, max_size=size))
            lines.append(f"{key} = {toml_value(values)}")
            keys = tuple(k for k in keys if k != key)
    return arm, "\n".join(lines + draw(toml_lines(keys))) + "\n"


@settings(PARSING)
@given(case=truth_cases())
def test_load_truth_raises_only_armcal_errors(case, scratch):
    arm, text = case
    read_only_armcal_errors("truth", scratch, text, arm)


# Calibration JSON: random documents, and valid ones from identify with a few values
# replaced, removed or added anywhere.

JSON_VALUES = st.recursive(
    st.none()
    | st.booleans()
    | st.integers()
    | st.just(10**400)  # beyond any float
    | st.floats(allow_nan=True, allow_infinity=True)  # json writes NaN and Infinity
    | st.text(max_size=8),
    lambda inner: (
        st.lists(inner, max_size=4) | st.dictionaries(st.text(max_size=8), inner, max_size=4)
    ),
    max_leaves=10,
)
CALIBRATION_KEYS = ("format", "robot", "noise", "fixed", "parameters", "covariance", "sigma_mm")


@settings(PARSING)
@given(
    document=st.one_of(
        JSON_VALUES,
        st.fixed_dictionaries(
            {"format": st.sampled_from(["armcal-calibration/1", "armcal-calibration/2", 1])}
        ),
        st.dictionaries(st.sampled_from(CALIBRATION_KEYS), JSON_VALUES, max_size=3),
    )
)
def test_read_calibration_raises_only_armcal_errors_on_random_json(document, scratch):
    read_only_armcal_errors("calibration", scratch, json.dumps(document))


_CALIBRATIONS: list[dict] = []


def calibration_documents() -> list[dict]:
    """Calibration documents of identify, made once: a plain arm; several targets, a base
    offset, anisotropic and encoder noise and a fixed length; 3-D data with its plane."""
    if _CALIBRATIONS:
        return _CALIBRATIONS
    from armcal import identify_3d

    plain = PlanarArm([260.0, 180.0], name="plain")
    q = orthogonal_plan(plain, 6)
    cals = [identify(plain, q, forward_kinematics(plain, q), sigma=0.1)]
    nest = PlanarArm(
        [260.0, 180.0, 100.0],
        targets=(Target("A", 100.0), Target("B", 80.0, 0.7)),
        base_offset=True,
        noise=NoiseModel.per_axis(0.05, 0.02, math.radians(0.001)),
        fixed=("dl1",),
        name="nest",
    )
    rows, target = every_target(nest, orthogonal_plan(nest, 8))
    cals.append(identify(nest, rows, forward_kinematics(nest, rows, target=target), target=target))
    tilted = PlanarArm([260.0, 180.0], base_offset=True, base_rotation=True, name="tilted")
    q = orthogonal_plan(tilted, 7)
    xy = forward_kinematics(tilted, q)
    xyz = np.column_stack([xy[:, 0], 0.6 * xy[:, 1], 0.8 * xy[:, 1]])  # a tilted plane
    cals.append(identify_3d(tilted, q, xyz, sigma=0.1))
    _CALIBRATIONS.extend(json.loads(to_json(calibration_document(cal))) for cal in cals)
    return _CALIBRATIONS


#: An integer no float can hold (JSON has no limit on the digits of a number).
HUGE = "1" + "0" * 400


@st.composite
def mutated_calibrations(draw) -> str:
    """A valid calibration document with one to three changes: walk down from the top to
    any value and replace it by any JSON value, or remove it, or add a key beside it."""
    document = json.loads(json.dumps(draw(st.sampled_from(calibration_documents()))))
    for _ in range(draw(st.integers(1, 3))):
        parent, key = None, None
        node = document
        while isinstance(node, dict | list) and node and not draw(one_in(3)):
            keys = list(node) if isinstance(node, dict) else list(range(len(node)))
            parent, key = node, draw(st.sampled_from(keys))
            node = node[key]
        if parent is None:
            continue
        change = draw(st.sampled_from(["replace", "remove", "add"]))
        if change == "replace":
            parent[key] = draw(JSON_VALUES)
        elif change == "remove":
            del parent[key]
        elif isinstance(parent, dict):
            parent[draw(st.text(max_size=8))] = draw(JSON_VALUES)
    return json.dumps(document)


# too_slow: the first draw makes the three calibrations (about a second, once).
@settings(PARSING, suppress_health_check=[HealthCheck.too_slow])
@example(text='{"format": "armcal-calibration/1", "robot": []}')
@example(text='{"format": "armcal-calibration/1", "robot": {"link_lengths_mm": [' + HUGE + "]}}")
@given(text=mutated_calibrations())
def test_read_calibration_raises_only_armcal_errors_on_altered_documents(text, scratch):
    read_only_armcal_errors("calibration", scratch, text)


# Inputs of absurd size that the property covers too: explicit reproductions (hypothesis
# does not make files this large).

_DEEP = 100_000  # nesting far beyond Python's recursion limit (1000 by default)
#: Whether int() refuses long digit strings (Python >= 3.11, 3.10.7 and later 3.10s).
_INT_DIGITS_LIMITED = getattr(sys, "get_int_max_str_digits", lambda: 0)() > 0


@pytest.mark.parametrize(
    ("reader", "content"),
    [
        pytest.param(
            "calibration",
            "[" * _DEEP,
            id="json-nested",
        ),
        pytest.param(
            "robot",
            "a = " + "[" * _DEEP,
            id="toml-nested",
        ),
        pytest.param(
            "plan",
            "q1_deg,q2_deg\n1," + "2" * 131_073 + "\n",
            id="csv-long-field",
        ),
        pytest.param(
            "measurements",
            "q" + "1" * 5000 + "_deg,x_mm,y_mm\n1,2,3\n",
            id="csv-long-joint-number",
        ),
        pytest.param(
            "truth",
            "dl_mm = [" + "9" * 5000 + "]\n",
            id="toml-long-integer",
        ),
        pytest.param(
            "calibration",
            '{"format": "armcal-calibration/1", "sigma_mm": ' + "9" * 5000 + "}",
            id="json-long-integer",
        ),
        pytest.param("plan", "q1_deg,q2_deg\n1," + "9" * 5000 + "\n", id="csv-long-number"),
    ],
)
def test_readers_raise_only_armcal_errors_on_huge_inputs(reader, content, scratch):
    read_only_armcal_errors(reader, scratch, content)
