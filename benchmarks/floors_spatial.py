"""Plain-numpy floors of armcal's commands on a six-axis arm: the same files in, the same work,
the same kind of output.

Each floor is what a competent engineer would write with numpy alone to do a
command's job for a spatial serial arm measured by a laser tracker at several
reflectors: read the files with ``numpy.loadtxt`` and ``json.load``, do the
linear algebra in plain numpy, write the result with ``numpy.savetxt`` or
``json.dumps``.  It imports neither armcal nor scipy, and ``bench_floor_spatial.py``
runs it as a fresh process like the command it is set against, so both pay an
interpreter's start-up.

**The arm** comes in a small JSON config (:func:`load_config`, written by
``bench_floor_spatial.py`` from the robot file armcal reads): every joint's
nominal origin (4x4, its frame's z the joint's axis), the joints' kinds, the
tip frame, the joint map ``u = M (q + dq)``, the limits of the readings and of
the joint values, the targets' nominal positions in the tip frame, the
instrument noise sigma, the parameters armcal holds (its identifiable-set
rule's choice, which a floor takes as given) and, for ``simulate``, the
virtual arm's true parameters.

**The parameters** are armcal's, in armcal's order and units, so that every
estimate can be compared name by name: the base pose in the instrument's
frame (``base.x, .y, .z`` mm, ``base.rx, .ry, .rz`` roll, pitch, yaw), every
joint's placement error ``T(x, y, z) Rx(rx) Ry(ry)`` (and ``Rz(rz)`` for a
prismatic joint, which has no ``z``) right after its nominal origin, every
reading's zero ``dq``, every target's position.  The parameterisation is the
same as armcal's, so the floors' estimates are compared parameter by parameter
(``bench_floor_spatial.py`` checks every free one within 1e-6 of its std).

**The Jacobian** is analytic, in screw form: a parameter (or joint value)
that turns the chain about a unit axis ``w`` through a point ``c`` moves a
measured point ``p`` at ``w x (p - c)``; one that shifts it along ``v`` moves
it at ``v``.  A first walk along the chain gives the points; a second fills
every parameter's column as it meets its screw.  Products of every row's
rotation with one matrix are one BLAS product of the stacked rows
(:func:`times`).

**Least squares** is Gauss-Newton on the normal equations with the columns
scaled to unit norm (``J_s = J D``, ``D = diag(1 / |J_k|)``): the industrial
arm's 33 free columns have a scaled condition number of about 30 on random
poses, so the normal equations lose ``cond^2 eps`` ~ 2e-13 of a step that ends
at round-off.  The covariance is ``sigma^2 D (J_s^T J_s)^-1 D``.

Usage::

    python benchmarks/floors_spatial.py COMMAND CONFIG [FILES...]

with COMMAND one of ``identify``, ``validate``, ``compensate``, ``evaluate``,
``simulate`` (see each function for its files).  ``validate``, ``evaluate`` and
``simulate`` print a JSON document on stdout (as armcal's ``--json``).
"""

from __future__ import annotations

import json
import sys
from dataclasses import dataclass
from functools import cached_property

import numpy as np

COMPONENTS = ("x", "y", "z", "rx", "ry", "rz")
#: A joint's placement error components by kind (a turn about, or a slide along, its own
#: axis is its zero).
PLACEMENT = {"R": (0, 1, 2, 3, 4), "P": (0, 1, 3, 4, 5)}
BASE = ("base.x", "base.y", "base.z", "base.rx", "base.ry", "base.rz")

#: Gauss-Newton stops when its step moves a point by at most this fraction of the reach
#: (an angle counted at the reach), or when a step below 1e-9 of the reach no longer
#: halves (round-off): armcal's rule.
TOL = 1e-12
STALL = 1e-9

#: The tool's angles are counted as arcs at this radius (mm) in compensation, the
#: correction a pose may need is at most this many times its error as an angle, and it is
#: reached when the residual is below this (mm): armcal's compensation's constants.
ANGLE_SCALE_MM = 100.0
MAX_AMPLIFICATION = 20.0
COMPENSATE_TOL_MM = 1e-9


# --------------------------------------------------------------------------- the arm


@dataclass
class Arm:
    origins: np.ndarray  # (n, 4, 4) every joint's nominal origin, mm
    kinds: tuple[str, ...]  # "R" or "P"
    tip: np.ndarray  # (4, 4)
    joint_map: np.ndarray  # (n, n): u = M (q + dq)
    limits: np.ndarray  # (n, 2) of the readings q, rad (mm)
    value_limits: np.ndarray  # (n, 2) of the joint values u
    targets: list[str]
    target_positions: np.ndarray  # (k, 3) nominal, tip frame, mm
    sigma: float  # mm
    fixed: frozenset[str]
    truth: np.ndarray | None  # (p,) internal units, for simulate

    @property
    def n(self) -> int:
        return len(self.kinds)

    @cached_property
    def names(self) -> list[str]:
        joints = [
            f"j{k + 1}.{COMPONENTS[c]}"
            for k, kind in enumerate(self.kinds)
            for c in PLACEMENT[kind]
        ]
        zeros = [f"dq{k + 1}" for k in range(self.n)]
        targets = [f"{label}.{axis}" for label in self.targets for axis in "xyz"]
        return [*BASE, *joints, *zeros, *targets]

    @property
    def zero_start(self) -> int:
        return 6 + 5 * self.n

    @property
    def target_start(self) -> int:
        return 6 + 6 * self.n

    @cached_property
    def angles(self) -> np.ndarray:
        """Boolean ``(p,)``: the parameters that are angles (rad inside, deg in files)."""
        out = np.zeros(len(self.names), dtype=bool)
        out[3:6] = True
        for k, kind in enumerate(self.kinds):
            for slot, c in enumerate(PLACEMENT[kind]):
                out[6 + 5 * k + slot] = c >= 3
            out[self.zero_start + k] = kind == "R"
        return out

    @property
    def display(self) -> np.ndarray:
        return np.where(self.angles, 180.0 / np.pi, 1.0)

    @property
    def units(self) -> list[str]:
        return ["deg" if a else "mm" for a in self.angles]

    @cached_property
    def free(self) -> np.ndarray:
        return np.array([name not in self.fixed for name in self.names])

    @cached_property
    def reach(self) -> float:
        """The sum of the joint origins' and the tip's offsets, plus 1 mm (armcal's)."""
        offsets = np.linalg.norm(self.origins[:, :3, 3], axis=1)
        return float(offsets.sum() + np.linalg.norm(self.tip[:3, 3]) + 1.0)

    def nominal(self) -> np.ndarray:
        """Parameters of the nominal arm: no errors, targets at their nominal positions."""
        out = np.zeros(len(self.names))
        out[self.target_start :] = self.target_positions.ravel()
        return out

    def target_points(self, params: np.ndarray) -> np.ndarray:
        """The targets' positions ``(k, 3)`` in the tip frame within ``params``."""
        return params[self.target_start :].reshape(-1, 3)

    def target_index(self, labels: np.ndarray) -> np.ndarray:
        lookup = {label: i for i, label in enumerate(self.targets)}
        found, inverse = np.unique(labels, return_inverse=True)
        return np.array([lookup[str(label)] for label in found])[inverse]


def config_of(arm, fixed: list[str], truth: np.ndarray) -> dict:
    """The config of an arm given as armcal's ``SpatialArm`` (read by its attributes, so this
    module imports nothing of armcal's): its chain, joint map, limits, targets and sigma,
    the parameters armcal holds, and the virtual arm's ``truth`` ``(p,)``."""
    chain = arm.chain
    return {
        "origins": chain.origins.tolist(),
        "kinds": list(chain.kinds),
        "tip": chain.tip.tolist(),
        "joint_map": arm.joint_map.tolist(),
        "limits": arm.limits.tolist(),
        "value_limits": np.clip(chain.joint_limits, -1e300, 1e300).tolist(),
        "targets": list(arm.targets),
        "target_positions": arm.target_positions.tolist(),
        "sigma": arm.noise.sigma_mm,
        "fixed": list(fixed),
        "truth": np.asarray(truth, dtype=float).tolist(),
    }


def load_config(path: str) -> Arm:
    with open(path) as f:
        raw = json.load(f)
    truth = raw.get("truth")
    return Arm(
        np.array(raw["origins"], float),
        tuple(raw["kinds"]),
        np.array(raw["tip"], float),
        np.array(raw["joint_map"], float),
        np.array(raw["limits"], float),
        np.array(raw["value_limits"], float),
        list(raw["targets"]),
        np.array(raw["target_positions"], float),
        float(raw["sigma"]),
        frozenset(raw["fixed"]),
        None if truth is None else np.array(truth, float),
    )


# --------------------------------------------------------------------------- kinematics


def elementary(axis: int, angle: float) -> np.ndarray:
    c, s = np.cos(angle), np.sin(angle)
    i, j = (axis + 1) % 3, (axis + 2) % 3
    out = np.eye(3)
    out[i, i], out[j, j], out[j, i], out[i, j] = c, c, s, -s
    return out


def cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """``a x b`` of broadcast ``(..., 3)`` vectors."""
    a0, a1, a2 = a[..., 0], a[..., 1], a[..., 2]
    b0, b1, b2 = b[..., 0], b[..., 1], b[..., 2]
    return np.stack([a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0], axis=-1)


def rotation_vector(r: np.ndarray) -> np.ndarray:
    """Rotation vectors ``(m, 3)`` of rotations ``(m, 3, 3)`` turned by well under a half turn."""
    skew = np.stack([r[:, 2, 1] - r[:, 1, 2], r[:, 0, 2] - r[:, 2, 0], r[:, 1, 0] - r[:, 0, 1]], 1)
    sin2 = np.linalg.norm(skew, axis=1)  # 2 sin(angle)
    angle = np.arctan2(sin2 / 2, (np.trace(r, axis1=1, axis2=2) - 1) / 2)
    small = sin2 < 1e-12
    return skew * np.where(small, 0.5, angle / np.where(small, 1.0, sin2))[:, None]


@dataclass
class Kinematics:
    points: np.ndarray  # (m, 3) mm
    rotation: np.ndarray  # (m, 3, 3) the tip frame
    columns: np.ndarray | None  # (m, 3, c): d points / d params[columns]
    joint: np.ndarray | None  # (m, 3, n): d points / d q
    angular: np.ndarray | None  # (m, 3, n): the tip frame's angular velocity per reading


def times(stack: np.ndarray, other: np.ndarray) -> np.ndarray:
    """``stack @ other`` of matrices ``(..., r, a)`` and one matrix ``(a, b)`` or vector
    ``(a,)``: one BLAS product of the stacked rows, not one small product per matrix."""
    if stack.ndim == 2:
        return stack @ other
    flat = stack.reshape(-1, stack.shape[-1]) @ other
    return flat.reshape(*stack.shape[:-1], *other.shape[1:])


def walk(arm: Arm, params: np.ndarray, u: np.ndarray, visit=None) -> tuple[np.ndarray, np.ndarray]:
    """The tip frame's position ``(m, 3)`` and rotation ``(m, 3, 3)`` at joint values ``u``
    ``(m, n)``; with ``visit``, ``visit(key, axis, at)`` for every screw on the way: ``key``
    a parameter's index, or ``-1 - k`` for joint ``k``'s value, ``at`` the point the turn
    is about (None for a shift along ``axis``).

    Until the first joint moves, every frame is the same for every row: the position and
    rotation stay ``(3,)``, ``(3, 3)`` and broadcast from there.
    """
    m = u.shape[0]
    roll, pitch, yaw = params[3:6]
    turn_z, turn_y = elementary(2, yaw), elementary(1, pitch)
    rot: np.ndarray = turn_z @ turn_y @ elementary(0, roll)
    pos: np.ndarray = params[:3].copy()
    if visit is not None:
        for i in range(3):
            visit(i, np.eye(3)[i], None)
        visit(3, rot[:, 0], pos)
        visit(4, turn_z[:, 1], pos)
        visit(5, np.array([0.0, 0.0, 1.0]), pos)
    for k, kind in enumerate(arm.kinds):
        pos = pos + times(rot, arm.origins[k, :3, 3])
        rot = times(rot, arm.origins[k, :3, :3])
        start = 6 + 5 * k
        slots = {c: start + slot for slot, c in enumerate(PLACEMENT[kind])}
        shift = np.array([params[slots[c]] if c in slots else 0.0 for c in (0, 1, 2)])
        if visit is not None:
            for c in (0, 1, 2):
                if c in slots:
                    visit(slots[c], rot[..., :, c], None)
        pos = pos + times(rot, shift)
        for c in (3, 4, 5):
            if c in slots:
                if visit is not None:
                    visit(slots[c], rot[..., :, c - 3], pos)
                rot = times(rot, elementary(c - 3, params[slots[c]]))
        axis = rot[..., :, 2]
        if kind == "R":
            if visit is not None:
                visit(-1 - k, axis, pos)
            cos, sin = np.cos(u[:, k])[:, None], np.sin(u[:, k])[:, None]
            x, y = rot[..., :, 0], rot[..., :, 1]
            turned = np.empty((m, 3, 3))
            turned[:, :, 0] = x * cos + y * sin
            turned[:, :, 1] = y * cos - x * sin
            turned[:, :, 2] = axis
            rot = turned
        else:
            if visit is not None:
                visit(-1 - k, axis, None)
            pos = pos + axis * u[:, k, None]
    return pos + times(rot, arm.tip[:3, 3]), times(rot, arm.tip[:3, :3])


def kinematics(
    arm: Arm,
    q: np.ndarray,
    target: np.ndarray,
    params: np.ndarray,
    columns: np.ndarray | None = None,
    joints: bool = False,
) -> Kinematics:
    """Points of rows ``q`` ``(m, n)`` measuring targets ``target`` ``(m,)`` at ``params``,
    and (``columns``, ``joints``) their Jacobians.

    The Jacobians take a second walk along the chain, which fills every column as it
    meets the parameter's screw (the points known from the first): nothing of the walk
    is kept but the columns.
    """
    m, n = q.shape
    u = (q + params[arm.zero_start : arm.target_start]) @ arm.joint_map.T
    pos, rot = walk(arm, params, u)
    points = pos + np.einsum("mij,mj->mi", rot, arm.target_points(params)[target])
    if columns is None and not joints:
        return Kinematics(points, rot, None, None, None)
    slot_of = {} if columns is None else {int(i): s for s, i in enumerate(columns)}
    jac = None if columns is None else np.empty((m, 3, len(slot_of)))
    by_value = np.empty((m, 3, n))  # d points / d u
    axes = np.zeros((m, 3, n)) if joints else None  # the joints' angular velocities

    def visit(key: int, axis: np.ndarray, at: np.ndarray | None) -> None:
        if key >= 0 and key not in slot_of:
            return
        column = np.broadcast_to(axis, (m, 3)) if at is None else cross(axis, points - at)
        if key >= 0:
            assert jac is not None
            jac[:, :, slot_of[key]] = column
            return
        by_value[:, :, -1 - key] = column
        if axes is not None and at is not None:
            axes[:, :, -1 - key] = axis

    walk(arm, params, u, visit)
    joint = times(by_value, arm.joint_map)
    if jac is not None:
        for i, slot in slot_of.items():
            if i >= arm.target_start:
                t, axis_index = divmod(i - arm.target_start, 3)
                jac[:, :, slot] = np.where((target == t)[:, None], rot[:, :, axis_index], 0.0)
            elif i >= arm.zero_start:
                jac[:, :, slot] = joint[:, :, i - arm.zero_start]
    angular = None if axes is None else times(axes, arm.joint_map)
    return Kinematics(points, rot, jac, joint, angular)


def rows_of_plan(arm: Arm, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Every target of every pose, pose after pose: readings ``(m k, n)``, targets ``(m k,)``."""
    k = len(arm.targets)
    return np.repeat(q, k, axis=0), np.tile(np.arange(k), q.shape[0])


# --------------------------------------------------------------------------- least squares


@dataclass
class Fit:
    params: np.ndarray  # (p,)
    iterations: int
    jacobian: np.ndarray  # (3 m, p_f) free columns at the last linearization
    norms: np.ndarray  # (p_f,) its column norms
    normal: np.ndarray  # (p_f, p_f): J_s^T J_s, unit-norm columns


def scaled_normal(jac: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    norms = np.sqrt(np.einsum("ij,ij->j", jac, jac))
    return jac.T @ jac / np.outer(norms, norms), norms


def gauss_newton(
    arm: Arm, q: np.ndarray, target: np.ndarray, points: np.ndarray, params: np.ndarray
) -> Fit:
    """Least squares over the free parameters from ``params`` (module notes)."""
    params = params.copy()
    free = np.flatnonzero(arm.free)
    step_scale = np.where(arm.angles, arm.reach, 1.0)[free]
    previous = np.inf
    iterations = 0
    while iterations < 50:
        iterations += 1
        kin = kinematics(arm, q, target, params, columns=free)
        assert kin.columns is not None
        jac = kin.columns.reshape(-1, free.size)
        residual = (points - kin.points).reshape(-1)
        normal, norms = scaled_normal(jac)
        step = np.linalg.solve(normal, (jac.T @ residual) / norms) / norms
        params[free] += step
        size = float(np.max(np.abs(step * step_scale)))
        if size <= TOL * arm.reach or (size < STALL * arm.reach and size >= 0.5 * previous):
            break
        previous = size
    return Fit(params, iterations, jac, norms, normal)


def covariance(arm: Arm, fit: Fit) -> np.ndarray:
    """``sigma^2 (J^T J)^-1`` ``(p, p)`` in internal units; held parameters' rows 0."""
    inverse = np.linalg.inv(fit.normal) / np.outer(fit.norms, fit.norms)
    free = np.flatnonzero(arm.free)
    out = np.zeros((arm.free.size, arm.free.size))
    out[np.ix_(free, free)] = arm.sigma**2 * inverse
    return out


def kabsch(arm: Arm, q: np.ndarray, target: np.ndarray, points: np.ndarray) -> np.ndarray:
    """The start: the nominal arm's base pose fitted to the points (Kabsch), its targets
    at their nominal positions, every error 0."""
    params = arm.nominal()
    local = kinematics(arm, q, target, params).points
    a, b = local - local.mean(axis=0), points - points.mean(axis=0)
    u, _, vt = np.linalg.svd(a.T @ b)
    d = np.sign(np.linalg.det(vt.T @ u.T))
    r = vt.T @ np.diag([1.0, 1.0, d]) @ u.T
    params[:3] = points.mean(axis=0) - r @ local.mean(axis=0)
    params[3:6] = np.arctan2(r[2, 1], r[2, 2]), np.arcsin(-r[2, 0]), np.arctan2(r[1, 0], r[0, 0])
    return params


# --------------------------------------------------------------------------- files


def read_measurements(arm: Arm, path: str):
    """Readings (rad, mm) ``(m, n)``, points ``(m, 3)``, pose labels and target indices."""
    with open(path) as f:
        header = f.readline().strip().split(",")
    col = {name: i for i, name in enumerate(header)}
    joints = [col.get(f"q{j + 1}_deg", col.get(f"q{j + 1}_mm")) for j in range(arm.n)]
    numeric = [*joints, col["x_mm"], col["y_mm"], col["z_mm"]]
    data = np.loadtxt(path, delimiter=",", skiprows=1, usecols=numeric, ndmin=2)
    text = np.loadtxt(
        path, delimiter=",", skiprows=1, usecols=(col["pose"], col["target"]), dtype=str, ndmin=2
    )
    q = data[:, : arm.n]
    revolute = np.array([kind == "R" for kind in arm.kinds])
    q[:, revolute] = np.radians(q[:, revolute])
    return q, data[:, arm.n :], text[:, 0], text[:, 1]


def read_plan(arm: Arm, path: str) -> np.ndarray:
    q = np.loadtxt(path, delimiter=",", skiprows=1, ndmin=2)[:, : arm.n]
    revolute = np.array([kind == "R" for kind in arm.kinds])
    q[:, revolute] = np.radians(q[:, revolute])
    return q


def read_calibration(arm: Arm, path: str):
    """Parameters ``(p,)`` and covariance ``(p, p)`` (internal units), sigma, and the
    baseline's parameters (the nominal arm's own base pose and targets)."""
    with open(path) as f:
        doc = json.load(f)
    scale = arm.display
    by_name = {p["name"]: p["value"] for p in doc["parameters"]}
    params = np.array([by_name[name] for name in arm.names]) / scale
    index = [doc["covariance"]["names"].index(name) for name in arm.names]
    cov = np.array(doc["covariance"]["matrix"])[np.ix_(index, index)] / np.outer(scale, scale)
    baseline = arm.nominal()
    for p in doc["baseline"]["parameters"]:
        i = arm.names.index(p["name"])
        baseline[i] = p["value"] / scale[i]
    return params, cov, float(doc["sigma_mm"]), baseline


def dumps(doc: dict) -> str:
    return json.dumps(doc)  # json.dump would use the pure-Python encoder


def summary(errors: np.ndarray) -> tuple[float, float, float]:
    """RMS, max and 95 % quantile of Euclidean errors ``(m,)``."""
    rms = float(np.sqrt(np.mean(errors**2)))
    return rms, float(errors.max()), float(np.percentile(errors, 95))


# --------------------------------------------------------------------------- the floors


def identify(arm: Arm, meas: str, out: str) -> None:
    """A calibration JSON of tracker measurements (``pose, q.., x_mm, y_mm, z_mm, target``):
    the Kabsch start, Gauss-Newton, the covariance, every row's residual and standardized
    residual, chi-square."""
    q, points, poses, labels = read_measurements(arm, meas)
    target = arm.target_index(labels)
    fit = gauss_newton(arm, q, target, points, kabsch(arm, q, target, points))
    residuals = points - kinematics(arm, q, target, fit.params).points
    cov = covariance(arm, fit)
    scale = arm.display
    values, cov = fit.params * scale, cov * np.outer(scale, scale)
    std = np.sqrt(np.diag(cov))
    safe = np.where(std > 0, std, 1.0)
    m = q.shape[0]
    dof = 3 * m - int(arm.free.sum())
    rows = range(1, m + 1)
    dx, dy, dz = residuals.T.tolist()
    sx, sy, sz = (residuals / arm.sigma).T.tolist()
    pose_list, label_list = poses.tolist(), labels.tolist()
    doc = {
        "parameters": [
            {"name": name, "unit": unit, "value": v, "std": s, "fixed": not free}
            for name, unit, v, s, free in zip(
                arm.names, arm.units, values.tolist(), std.tolist(), arm.free.tolist(), strict=True
            )
        ],
        "covariance": {"names": arm.names, "matrix": cov.tolist()},
        "correlation": {"names": arm.names, "matrix": (cov / np.outer(safe, safe)).tolist()},
        "residual_rms_mm": float(np.sqrt(np.mean(residuals**2))),
        "goodness_of_fit": {"chi2": float(np.sum(residuals**2)) / arm.sigma**2, "dof": dof},
        "iterations": fit.iterations,
        "residuals": [
            {"row": r, "pose": p, "target": t, "dx_mm": x, "dy_mm": y, "dz_mm": z, "used": True}
            for r, p, t, x, y, z in zip(rows, pose_list, label_list, dx, dy, dz, strict=True)
        ],
        "standardized_residuals": [
            {"row": r, "pose": p, "x": x, "y": y, "z": z}
            for r, p, x, y, z in zip(rows, pose_list, sx, sy, sz, strict=True)
        ],
    }
    with open(out, "w") as f:
        f.write(dumps(doc))


def tip_variance(columns: np.ndarray, cov_free: np.ndarray) -> np.ndarray:
    """``tr(J C J^T)`` ``(m,)`` of every point from its free columns ``(m, 3, p_f)``."""
    m, _, p = columns.shape
    flat = columns.reshape(-1, p)
    return np.einsum("ij,ij->i", flat @ cov_free, flat).reshape(m, 3).sum(axis=1)


def validate(arm: Arm, calibration: str, meas: str) -> None:
    """Errors of held-out measurements before (the nominal arm at its own base pose and
    targets, the calibration's baseline) and after, and the predicted error
    ``sqrt(tr(J C J^T) + 3 sigma^2)``: RMS, max and 95 % of each."""
    params, cov, sigma, baseline = read_calibration(arm, calibration)
    q, points, _, labels = read_measurements(arm, meas)
    target = arm.target_index(labels)
    free = np.flatnonzero(arm.free)
    before = np.linalg.norm(points - kinematics(arm, q, target, baseline).points, axis=1)
    kin = kinematics(arm, q, target, params, columns=free)
    assert kin.columns is not None
    after = np.linalg.norm(points - kin.points, axis=1)
    model = tip_variance(kin.columns, cov[np.ix_(free, free)])
    predicted = np.sqrt(model + 3 * sigma**2)
    rms_b, max_b, p95_b = summary(before)
    rms_a, max_a, p95_a = summary(after)
    doc = {
        "poses": int(q.shape[0]),
        "rms_before_mm": rms_b,
        "rms_after_mm": rms_a,
        "max_before_mm": max_b,
        "max_after_mm": max_a,
        "p95_before_mm": p95_b,
        "p95_after_mm": p95_a,
        "predicted_rms_after_per_point_mm": float(np.sqrt(np.mean(predicted**2))),
        "model_rms_per_point_mm": float(np.sqrt(np.mean(model))),
    }
    print(dumps(doc))


def compensate(arm: Arm, calibration: str, program: str, label: str, out: str) -> None:
    """Commands with which the calibrated arm puts target ``label`` where the nominal
    program meant it, and keeps the tool's orientation, in the robot's frame: batched
    Newton (6 readings, 6 equations: the position in mm and the turn as an arc at
    100 mm) on the poses not yet within 1e-9 mm, each step cut to the pose's bound (20
    times its error as an angle, as armcal's); a pose whose command ends beyond its bound,
    does not converge in 50 steps or leaves a limit keeps its command."""
    params, *_ = read_calibration(arm, calibration)
    q0 = read_plan(arm, program)
    m = q0.shape[0]
    target = np.full(m, arm.targets.index(label))
    robot = params.copy()
    robot[:6] = 0.0  # the instrument's pose is not the robot's
    goal = arm.nominal()
    goal[arm.target_start :] = params[arm.target_start :]  # the nominal arm, calibrated targets
    aim = kinematics(arm, q0, target, goal)

    def residual(kin: Kinematics, rows: np.ndarray) -> np.ndarray:
        turn = rotation_vector(np.einsum("mij,mkj->mik", kin.rotation, aim.rotation[rows]))
        return np.concatenate([kin.points - aim.points[rows], ANGLE_SCALE_MM * turn], axis=1)

    everyone = np.arange(m)
    r = residual(kinematics(arm, q0, target, robot), everyone)
    shift = np.linalg.norm(r[:, :3], axis=1) / arm.reach
    bound = MAX_AMPLIFICATION * np.hypot(shift, np.linalg.norm(r[:, 3:], axis=1) / ANGLE_SCALE_MM)
    q = q0.copy()
    beyond = np.zeros(m, dtype=bool)
    for _ in range(50):
        active = np.flatnonzero((np.linalg.norm(r, axis=1) > COMPENSATE_TOL_MM) & ~beyond)
        if not active.size:
            break
        kin = kinematics(arm, q[active], target[active], robot, joints=True)
        assert kin.joint is not None and kin.angular is not None
        jac = np.concatenate([kin.joint, ANGLE_SCALE_MM * kin.angular], axis=1)
        step = -np.linalg.solve(jac, residual(kin, active)[:, :, None])[:, :, 0]
        length = np.linalg.norm(step, axis=1)
        step *= np.minimum(1.0, bound[active] / np.where(length > 0, length, 1.0))[:, None]
        q[active] += step
        # A pose whose iterate is twice its bound away has left for another branch of the
        # inverse kinematics; one just beyond it may still come back (the bound is judged at
        # the end).
        beyond[active] = np.max(np.abs(q[active] - q0[active]), axis=1) > 2 * bound[active]
        r[active] = residual(kinematics(arm, q[active], target[active], robot), active)
    within = np.max(np.abs(q - q0), axis=1) <= bound
    done = (np.linalg.norm(r, axis=1) <= COMPENSATE_TOL_MM) & within
    u = q @ arm.joint_map.T
    inside = (q >= arm.limits[:, 0] - 1e-9) & (q <= arm.limits[:, 1] + 1e-9)
    inside &= (u >= arm.value_limits[:, 0] - 1e-9) & (u <= arm.value_limits[:, 1] + 1e-9)
    done &= np.all(inside, axis=1)
    q = np.where(done[:, None], q, q0)
    revolute = np.array([kind == "R" for kind in arm.kinds])
    q[:, revolute] = np.degrees(q[:, revolute])
    names = [f"q{j + 1}_{'deg' if r else 'mm'}" for j, r in enumerate(revolute)]
    table = np.column_stack([np.char.mod("%.12f", q), np.full(m, label), done.astype(int)])
    np.savetxt(
        out, table, fmt="%s", delimiter=",", header=",".join([*names, "target", "corrected"]),
        comments="",
    )  # fmt: skip


def evaluate(arm: Arm, plan: str, test: str) -> None:
    """A plan's information at the nominal arm (every target of every pose), its D, A and
    E criteria (of the information with unit-norm columns, as armcal's for a spatial arm),
    the predicted std of every parameter, and the predicted error at the test poses
    (every target of each): RMS and max of ``sqrt(tr(J C J^T))``."""
    params = arm.nominal()
    free = np.flatnonzero(arm.free)
    q, target = rows_of_plan(arm, read_plan(arm, plan))
    kin = kinematics(arm, q, target, params, columns=free)
    assert kin.columns is not None
    normal, norms = scaled_normal(kin.columns.reshape(-1, free.size))
    eig = np.linalg.eigvalsh(normal)
    inverse = np.linalg.inv(normal) / np.outer(norms, norms)
    cov_free = arm.sigma**2 * inverse
    std = np.zeros(arm.free.size)
    std[free] = np.sqrt(np.diag(cov_free))
    tq, tt = rows_of_plan(arm, read_plan(arm, test))
    tests = kinematics(arm, tq, tt, params, columns=free)
    assert tests.columns is not None
    error = np.sqrt(tip_variance(tests.columns, cov_free))
    doc = {
        "poses": int(q.shape[0] // len(arm.targets)),
        "d_efficiency": float(np.exp(np.mean(np.log(eig)))),
        "a_efficiency": float(eig.size / np.sum(1.0 / eig)),
        "e_efficiency": float(eig[0]),
        "predicted_std": dict(zip(arm.names, (std * arm.display).tolist(), strict=True)),
        "predicted_position_rms_mm": float(np.sqrt(np.mean(error**2))),
        "predicted_position_max_mm": float(error.max()),
    }
    print(dumps(doc))


def simulate(arm: Arm, plan: str, trials: str, seed: str) -> None:
    """Monte Carlo of a plan on the virtual arm ``truth``: the truth as the fit sees it
    (Gauss-Newton of the free parameters on its noiseless points), then per trial noise of
    sigma on every point (one ``standard_normal((trials, m, 3))`` draw of
    ``default_rng(seed)``, the stream armcal draws) and its nonlinear least-squares
    estimate: the first Gauss-Newton step from the truth for every trial at once (the
    Jacobian at the truth is the same for all: trials are right-hand sides of one
    factorization), then one Gauss-Newton step of each trial's own (its Jacobian at that
    estimate), which leaves it within 1e-8 of its std of the converged estimate (the first
    step is off by about 1e-4 std: the Jacobian's change times a residual of the noise's
    size).  Then the mean and std of the estimates, their bias and the predicted std."""
    assert arm.truth is not None, "simulate needs the truth in the config"
    q, target = rows_of_plan(arm, read_plan(arm, plan))
    clean = kinematics(arm, q, target, arm.truth).points
    start = np.where(arm.free, arm.truth, 0.0)  # a held parameter is held at 0
    truth = gauss_newton(arm, q, target, clean, start)
    free = np.flatnonzero(arm.free)
    kin = kinematics(arm, q, target, truth.params, columns=free)  # at the truth as fitted
    assert kin.columns is not None
    jac = kin.columns.reshape(-1, free.size)
    normal, norms = scaled_normal(jac)
    total = int(trials)
    noise = np.random.default_rng(int(seed)).standard_normal((total, *clean.shape))
    noise *= arm.sigma
    miss = (noise + (clean - kin.points)).reshape(total, -1).T  # (3 m, trials)
    estimates = np.tile(truth.params, (total, 1))
    estimates[:, free] += (np.linalg.solve(normal, (jac.T @ miss) / norms[:, None]).T) / norms
    del jac, kin, miss
    for t in range(total):  # one Gauss-Newton step of each trial's own
        own = kinematics(arm, q, target, estimates[t], columns=free)
        assert own.columns is not None
        rows = own.columns.reshape(-1, free.size)
        step_normal, step_norms = scaled_normal(rows)
        residual = (clean + noise[t] - own.points).reshape(-1)
        step = np.linalg.solve(step_normal, (rows.T @ residual) / step_norms) / step_norms
        estimates[t, free] += step
    scale = arm.display
    mean = estimates.mean(axis=0)
    std = estimates.std(axis=0, ddof=1)
    predicted = np.zeros(arm.free.size)
    predicted[free] = arm.sigma * np.sqrt(np.diag(np.linalg.inv(normal))) / norms

    def named(values: np.ndarray) -> dict[str, float]:
        return dict(zip(arm.names, (values * scale).tolist(), strict=True))

    doc = {
        "trials": total,
        "poses": int(q.shape[0] // len(arm.targets)),
        "truth": named(truth.params),
        "empirical_mean": named(mean),
        "empirical_std": named(std),
        "predicted_std": named(predicted),
        "bias": named(mean - truth.params),
    }
    print(dumps(doc))


FLOORS = {
    "identify": identify,
    "validate": validate,
    "compensate": compensate,
    "evaluate": evaluate,
    "simulate": simulate,
}

if __name__ == "__main__":
    FLOORS[sys.argv[1]](load_config(sys.argv[2]), *sys.argv[3:])
