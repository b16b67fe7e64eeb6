"""Plain-numpy floors of armcal's commands: the same files in, the same work, the same files out.

Each floor is what a competent engineer would write with numpy alone to do a
command's job on the same input files: read them with ``numpy.loadtxt`` (and
``json.load``), do the linear algebra in plain numpy, and write the same output
with ``numpy.savetxt`` or ``json.dump`` (the C encoder, no indent).  It imports
neither armcal nor scipy, and is run by ``bench_floor.py`` as a fresh process
like the command it is set against, so both pay an interpreter's start-up.

The model is the paper's (eq. 1), linear in the complex link vectors
``z_k = (l_k + dl_k) exp(i (alpha_k + dtheta_k))`` and the base ``x0 + i y0``:
``x + i y = base + sum_k z_k exp(i theta_k)`` with ``theta = M q``.  A robot with
several targets has one last link per target.  Every floor takes the robot as a
small JSON file (:func:`load_config`) written by ``bench_floor.py`` from the
same values as the robot TOML armcal reads.

Usage::

    python benchmarks/floors.py COMMAND CONFIG [FILES...]

with COMMAND one of ``identify``, ``identify-3d``, ``validate``, ``compensate``,
``evaluate``, ``simulate``, ``synthesize``, ``design``, ``export`` (see each
function for its files).
"""

from __future__ import annotations

import json
import sys
from dataclasses import dataclass

import numpy as np

# --------------------------------------------------------------------------- the model


@dataclass
class Config:
    lengths: np.ndarray  # (n,) mm
    joint_map: np.ndarray  # (n, n)
    target_lengths: np.ndarray  # (T,) mm, the last link of every target (T = 1 without targets)
    target_angles: np.ndarray  # (T,) rad
    target_labels: list[str]
    base: bool
    rotation: bool  # the base rotation phi0 is identified and dq1 held
    sigma: float  # mm
    limits: np.ndarray  # (n, 2) rad
    truth: np.ndarray  # (n_links,) dl mm, then (n_links,) dtheta rad, of every link vector

    @property
    def n(self) -> int:
        return self.lengths.size

    @property
    def nominal(self) -> np.ndarray:
        """Nominal link vectors ``(K,)``: the shared links, then every target's last link."""
        last = self.target_lengths * np.exp(1j * self.target_angles)
        return np.concatenate([self.lengths[:-1].astype(complex), last])

    def angle_map(self) -> np.ndarray:
        """``A`` with ``dtheta = A u``: link-vector angle deviations of the user's angles ``u``.

        ``u`` is ``dq1..dq(n-1), dq_n@t...`` (and ``phi0`` with dq1 held).
        """
        n, t = self.n, self.target_lengths.size
        a = np.zeros((n - 1 + t, n - 1 + t))
        a[: n - 1, : n - 1] = self.joint_map[: n - 1, : n - 1]
        a[n - 1 :, : n - 1] = self.joint_map[n - 1, : n - 1]
        a[n - 1 :, n - 1 :] = self.joint_map[n - 1, n - 1] * np.eye(t)
        if self.rotation:  # phi0 replaces dq1: it turns every link vector
            a[:, 0] = 1.0
        return a

    def names(self) -> list[str]:
        n = self.n
        last = [f"{n}@{t}" for t in self.target_labels] if self.target_labels else [str(n)]
        links = [str(k) for k in range(1, n)] + last
        angles = ["dq" + k for k in links]
        if self.rotation:
            angles[0] = "phi0"
        return ["dl" + k for k in links] + angles + (["x0", "y0"] if self.base else [])


def load_config(path: str) -> Config:
    raw = json.load(open(path))
    targets = raw.get("targets") or []
    n = len(raw["lengths"])
    return Config(
        np.array(raw["lengths"], float),
        np.array(raw.get("joint_map", np.tril(np.ones((n, n)))), float),
        np.array([t[1] for t in targets] or raw["lengths"][-1:], float),
        np.radians([t[2] for t in targets] or [0.0]),
        [t[0] for t in targets],
        bool(raw.get("base", False)),
        bool(raw.get("rotation", False)),
        float(raw["sigma"]),
        np.radians(np.array(raw["limits"], float)),
        np.array(raw.get("truth", []), float),
    )


def link_columns(cfg: Config, q: np.ndarray, target: np.ndarray | None) -> np.ndarray:
    """``exp(i theta_k)`` of every row's link vectors ``(m, K)`` (0 for other targets' links)."""
    theta = q @ cfg.joint_map.T
    m, n, t = q.shape[0], cfg.n, cfg.target_lengths.size
    cols = np.zeros((m, n - 1 + t), complex)
    cols[:, : n - 1] = np.exp(1j * theta[:, : n - 1])
    last = np.exp(1j * theta[:, -1])
    cols[np.arange(m), n - 1 + (0 if target is None else target)] = last
    return cols


def regressor(cfg: Config, cols: np.ndarray) -> np.ndarray:
    """Real design matrix ``(2m, 2K [+2])`` in ``(Re z, Im z, x0, y0)``: rows x, y per point."""
    m, k = cols.shape
    h = np.zeros((m, 2, 2 * k + 2 * cfg.base))
    h[:, 0, :k], h[:, 0, k : 2 * k] = cols.real, -cols.imag
    h[:, 1, :k], h[:, 1, k : 2 * k] = cols.imag, cols.real
    if cfg.base:
        h[:, 0, -2], h[:, 1, -1] = 1.0, 1.0
    return h.reshape(2 * m, -1)


def user_params(cfg: Config, w: np.ndarray, cov_w: np.ndarray | None):
    """User deviations (mm, rad) of the solution ``w`` and, with its covariance, theirs."""
    k = cfg.nominal.size
    z = w[:k] + 1j * w[k : 2 * k]
    ratio = z / cfg.nominal
    dl = np.abs(z) - np.abs(cfg.nominal)
    a = cfg.angle_map()
    u = np.linalg.solve(a, np.angle(ratio))
    params = np.concatenate([dl, u, w[2 * k :]])
    if cov_w is None:
        return params, None
    g = np.zeros((params.size, w.size))  # d params / d w
    r2 = np.abs(z) ** 2
    idx = np.arange(k)
    g[idx, idx], g[idx, k + idx] = z.real / np.abs(z), z.imag / np.abs(z)
    d_angle = np.zeros((k, w.size))
    d_angle[idx, idx], d_angle[idx, k + idx] = -z.imag / r2, z.real / r2
    g[k : 2 * k] = np.linalg.solve(a, d_angle)
    g[2 * k :, 2 * k :] = np.eye(w.size - 2 * k)
    return params, g @ cov_w @ g.T


def display(cfg: Config) -> np.ndarray:
    """Display scale of the user parameters: 1 for mm, degrees per radian for angles."""
    k = cfg.nominal.size
    return np.concatenate([np.ones(k), np.full(k, 180 / np.pi), np.ones(2 * cfg.base)])


def positions(cfg: Config, q: np.ndarray, target, dl: np.ndarray, dtheta: np.ndarray):
    """Tips ``(m,)`` (complex) of link-vector deviations ``dl``, ``dtheta`` ``(K,)``."""
    z = (np.abs(cfg.nominal) + dl) * np.exp(1j * (np.angle(cfg.nominal) + dtheta))
    return link_columns(cfg, q, target) @ z


# --------------------------------------------------------------------------- files


def read_meas(path: str, n: int, labelled: bool):
    """Joint angles (rad), points ``(m, d)`` and, with ``pose,target`` columns first, those."""
    if not labelled:
        data = np.loadtxt(path, delimiter=",", skiprows=1)
        return np.radians(data[:, :n]), data[:, n:], None, None
    width = len(open(path).readline().split(","))
    data = np.loadtxt(path, delimiter=",", skiprows=1, usecols=range(2, width))
    text = np.loadtxt(path, delimiter=",", skiprows=1, usecols=(0, 1), dtype=str)
    return np.radians(data[:, :n]), data[:, n:], text[:, 0], text[:, 1]


def read_calibration(path: str, cfg: Config):
    """Deviations of the link vectors ``dl, dtheta`` (mm, rad), user params and covariance."""
    doc = json.load(open(path))
    by_name = {p["name"]: p["value"] for p in doc["parameters"]}
    names = cfg.names()
    scale = display(cfg)
    params = np.array([by_name[name] for name in names]) / scale
    index = [doc["covariance"]["names"].index(name) for name in names]
    cov = np.array(doc["covariance"]["matrix"])[np.ix_(index, index)] / np.outer(scale, scale)
    k = cfg.nominal.size
    return params[:k], cfg.angle_map() @ params[k : 2 * k], params, cov


def jacobian_user(cfg: Config, q, target, dl, dtheta) -> np.ndarray:
    """``d tip / d user params`` ``(m, 2, p)`` at ``q``."""
    cols = link_columns(cfg, q, target)
    z = (np.abs(cfg.nominal) + dl) * np.exp(1j * (np.angle(cfg.nominal) + dtheta))
    d_dl = cols * np.exp(1j * np.angle(z))
    d_dtheta = 1j * cols * z
    d = np.concatenate([d_dl, d_dtheta @ cfg.angle_map()], axis=1)
    if cfg.base:
        d = np.concatenate([d, np.ones((q.shape[0], 1)), 1j * np.ones((q.shape[0], 1))], axis=1)
    return np.stack([d.real, d.imag], axis=1)


# --------------------------------------------------------------------------- the floors


def fit(cfg: Config, q, target, points):
    """Least squares by ``numpy.linalg.lstsq``: ``w``, its covariance and the residuals."""
    h = regressor(cfg, link_columns(cfg, q, target))
    y = points.reshape(-1)
    w = np.linalg.lstsq(h, y, rcond=None)[0]
    residuals = (y - h @ w).reshape(-1, 2)
    return w, cfg.sigma**2 * np.linalg.inv(h.T @ h), residuals


def write_calibration(path: str, cfg: Config, w, cov_w, residuals, labels, targets, plane=None):
    params, cov = user_params(cfg, w, cov_w)
    scale = display(cfg)
    values, cov = params * scale, cov * np.outer(scale, scale)
    std = np.sqrt(np.diag(cov))
    names = cfg.names()
    m = residuals.shape[0]
    rows = range(1, m + 1)
    labels = [str(r) for r in rows] if labels is None else labels.tolist()
    targets = [None] * m if targets is None else targets.tolist()
    dx, dy = residuals.T.tolist()
    sx, sy = (residuals / cfg.sigma).T.tolist()
    doc = {
        "parameters": [
            {"name": name, "value": v, "std": s}
            for name, v, s in zip(names, values, std, strict=True)
        ],
        "covariance": {"names": names, "matrix": cov.tolist()},
        "correlation": {"names": names, "matrix": (cov / np.outer(std, std)).tolist()},
        "residual_rms_mm": float(np.sqrt(np.mean(residuals**2))),
        "residuals": [
            {"row": r, "pose": p, "target": t, "dx_mm": x, "dy_mm": y, "used": True}
            for r, p, t, x, y in zip(rows, labels, targets, dx, dy, strict=True)
        ],
        "standardized_residuals": [
            {"row": r, "pose": p, "x": x, "y": y}
            for r, p, x, y in zip(rows, labels, sx, sy, strict=True)
        ],
        "plane": plane,
    }
    with open(path, "w") as f:
        f.write(json.dumps(doc))  # json.dump would use the pure-Python encoder


def identify(cfg: Config, meas: str, out: str) -> None:
    """A calibration JSON of 2-D measurements (one target): the fit, covariance, residuals."""
    q, xy, _, _ = read_meas(meas, cfg.n, labelled=False)
    w, cov_w, residuals = fit(cfg, q, None, xy)
    write_calibration(out, cfg, w, cov_w, residuals, None, None)


def identify_3d(cfg: Config, meas: str, out: str) -> None:
    """3-D tracker data with targets: the plane (one normal, an offset per target), both of
    its sides fitted in-plane and the better kept, then as :func:`identify`."""
    q, xyz, labels, names = read_meas(meas, cfg.n, labelled=True)
    found, index = np.unique(names, return_inverse=True)
    target = np.array([cfg.target_labels.index(label) for label in found])[index]
    centroids = np.array([xyz[target == t].mean(axis=0) for t in range(len(cfg.target_labels))])
    centred = xyz - centroids[target]
    normal = np.linalg.eigh(centred.T @ centred)[1][:, 0]
    u = np.array([1.0, 0.0, 0.0]) - normal[0] * normal
    u /= np.linalg.norm(u)
    v = np.cross(normal, u)
    origin = xyz.mean(axis=0)
    best = None
    for side in (v, -v):
        points = (xyz - origin) @ np.stack([u, side]).T
        w, cov_w, residuals = fit(cfg, q, target, points)
        rss = float(np.sum(residuals**2))
        if best is None or rss < best[0]:
            best = (rss, w, cov_w, residuals, side)
    _, w, cov_w, residuals, side = best
    distance = centred @ normal
    plane = {
        "origin_mm": origin.tolist(),
        "u": u.tolist(),
        "v": side.tolist(),
        "normal": np.cross(u, side).tolist(),
        "rms_mm": float(np.sqrt(np.mean(distance**2))),
    }
    write_calibration(out, cfg, w, cov_w, residuals, labels, names, plane)


def validate(cfg: Config, calibration: str, meas: str) -> None:
    """Errors of held-out 2-D measurements before and after, and the predicted error."""
    dl, dtheta, _, cov = read_calibration(calibration, cfg)
    q, xy, _, _ = read_meas(meas, cfg.n, labelled=False)
    measured = xy[:, 0] + 1j * xy[:, 1]
    k = dl.size
    before = np.abs(measured - positions(cfg, q, None, np.zeros(k), np.zeros(k)))
    after = np.abs(measured - positions(cfg, q, None, dl, dtheta))
    jac = jacobian_user(cfg, q, None, dl, dtheta)
    variance = np.einsum("mdp,pr,mdr->m", jac, cov, jac, optimize=True)
    predicted = np.sqrt(variance + 2 * cfg.sigma**2)
    for name, e in (("before", before), ("after", after), ("predicted", predicted)):
        rms, top, p95 = np.sqrt(np.mean(e**2)), e.max(), np.percentile(e, 95)
        print(f"{name}: RMS {rms:.4g} mm, max {top:.4g} mm, 95 % {p95:.4g} mm")


def compensate(cfg: Config, calibration: str, program: str, out: str) -> None:
    """Commands with which the calibrated arm reaches the nominal tip and tool direction:
    batched Newton with minimum-norm steps from the command, the rest of the joint space
    pulled back to it, on the poses not yet converged; a pose that does not converge in 20
    steps or leaves the limits keeps its command."""
    dl, dtheta, _, _ = read_calibration(calibration, cfg)
    q0 = np.radians(np.loadtxt(program, delimiter=",", skiprows=1, ndmin=2))
    m, n = q0.shape
    nominal = link_columns(cfg, q0, None) @ cfg.nominal
    goal = np.stack([nominal.real, nominal.imag, q0 @ cfg.joint_map[-1]], axis=1)
    z = (np.abs(cfg.nominal) + dl) * np.exp(1j * (np.angle(cfg.nominal) + dtheta))
    q, ok = q0.copy(), np.zeros(m, dtype=bool)
    active = np.arange(m)
    for _ in range(20):
        qa = q[active]
        terms = link_columns(cfg, qa, None) * z  # (a, K): every link vector's part of the tip
        tip = terms.sum(axis=1)
        r = np.stack([tip.real, tip.imag, qa @ cfg.joint_map[-1] + dtheta[-1]], axis=1)
        r -= goal[active]
        r[:, 2] = (r[:, 2] + np.pi) % (2 * np.pi) - np.pi
        done = np.all(np.abs(r) < 1e-10, axis=1)
        ok[active[done]] = True
        active, qa, r, terms = active[~done], qa[~done], r[~done], terms[~done]
        if not active.size:
            break
        d_q = (1j * terms) @ cfg.joint_map  # d tip / d q (theta = M q)
        jac = np.empty((active.size, 3, n))
        jac[:, 0], jac[:, 1], jac[:, 2] = d_q.real, d_q.imag, cfg.joint_map[-1]
        jac_t = np.swapaxes(jac, 1, 2)
        gram = jac @ jac_t
        back = q0[active] - qa
        step = -(jac_t @ np.linalg.solve(gram, r[:, :, None]))[:, :, 0]
        step += back - (jac_t @ np.linalg.solve(gram, (jac @ back[:, :, None])))[:, :, 0]
        q[active] += step
    ok &= np.all((q >= cfg.limits[:, 0]) & (q <= cfg.limits[:, 1]), axis=1)
    q = np.where(ok[:, None], q, q0)
    header = ",".join([f"q{j}_deg" for j in range(1, n + 1)] + ["corrected"])
    table = np.column_stack([np.degrees(q), ok])
    np.savetxt(out, table, fmt=["%.12f"] * n + ["%d"], delimiter=",", header=header, comments="")


def _plan(path: str) -> np.ndarray:
    return np.radians(np.loadtxt(path, delimiter=",", skiprows=1, ndmin=2))


def _test_poses(cfg: Config, seed: int, count: int = 1000) -> np.ndarray:
    rng = np.random.default_rng(seed)
    return rng.uniform(cfg.limits[:, 0], cfg.limits[:, 1], (count, cfg.n))


def _quality(cfg: Config, q: np.ndarray) -> None:
    """Predicted std, D/A/E efficiencies and the predicted error at 1000 test poses."""
    k = cfg.nominal.size
    jac = jacobian_user(cfg, q, None, np.zeros(k), np.zeros(k)).reshape(2 * q.shape[0], -1)
    information = jac.T @ jac / cfg.sigma**2
    cov = np.linalg.inv(information)
    # The orthogonal optimum per pose: 1 per length, |sum of the links it turns|^2 per angle.
    turned = np.abs(cfg.nominal) ** 2 @ np.abs(cfg.angle_map())
    ideal = np.concatenate([np.ones(k), turned]) * q.shape[0] / cfg.sigma**2
    relative = information / np.sqrt(np.outer(ideal, ideal))
    eig = np.linalg.eigvalsh(relative)
    d_eff = np.exp(np.linalg.slogdet(relative)[1] / eig.size)
    a_eff = eig.size / np.trace(np.linalg.inv(relative))
    test = _test_poses(cfg, 0)
    tj = jacobian_user(cfg, test, None, np.zeros(k), np.zeros(k))
    tip = np.sqrt(np.einsum("mdp,pr,mdr->m", tj, cov, tj, optimize=True))
    print(f"efficiency D {d_eff:.4f} A {a_eff:.4f} E {eig[0]:.4f}")
    print("predicted std", np.sqrt(np.diag(cov)) * display(cfg))
    print(f"predicted error RMS {np.sqrt(np.mean(tip**2)):.4g} mm, max {tip.max():.4g} mm")


def evaluate(cfg: Config, plan: str) -> None:
    """A plan's information, criteria, predicted std and error at 1000 test poses."""
    _quality(cfg, _plan(plan))


def design(cfg: Config, poses: str, out: str) -> None:
    """The orthogonal plan design finds for an arm without limits (every joint after the
    first at ``poses`` angles ``360/m`` apart, from 180 down), its quality, written out."""
    m = int(poses)
    angles = np.pi - (2 * np.arange(m) + 1) * np.pi / m
    q = np.zeros((m, cfg.n))
    q[:, 1:] = angles[:, None]
    _quality(cfg, q)
    header = ",".join(f"q{j}_deg" for j in range(1, cfg.n + 1))
    np.savetxt(out, np.degrees(q), fmt="%.12g", delimiter=",", header=header, comments="")


def design_pool(cfg: Config, pool: str, poses: str, out: str) -> None:
    """The convex relaxation of picking ``poses`` from a pool (the pool method of issue 22):
    D-optimal weights on the pool by the multiplicative algorithm (Titterington's
    ``w_i <- w_i d_i / p``) until ``max d <= p (1 + 1e-3)``, then the poses of the largest
    weights, their quality, written out."""
    m = int(poses)
    q = _plan(pool)
    k = cfg.nominal.size
    blocks = jacobian_user(cfg, q, None, np.zeros(k), np.zeros(k))  # (N, 2, p)
    p = blocks.shape[2]
    w = np.full(q.shape[0], 1.0 / q.shape[0])
    for _ in range(10_000):
        information = np.einsum("i,idp,idr->pr", w, blocks, blocks, optimize=True)
        half = np.linalg.cholesky(np.linalg.inv(information))
        d = np.sum((blocks @ half) ** 2, axis=(1, 2))  # tr(M^-1 I_i)
        if d.max() <= p * (1 + 1e-3):
            break
        w *= d / p
    chosen = q[np.argsort(w)[-m:]]
    _quality(cfg, chosen)
    header = ",".join(f"q{j}_deg" for j in range(1, cfg.n + 1))
    np.savetxt(out, np.degrees(chosen), fmt="%.12g", delimiter=",", header=header, comments="")


def synthesize(cfg: Config, plan: str, seed: str, out: str) -> None:
    """Measurements of the true arm at a plan's poses with noise of sigma, written out."""
    q = _plan(plan)
    k = cfg.nominal.size
    tip = positions(cfg, q, None, cfg.truth[:k], cfg.truth[k:])
    xy = np.stack([tip.real, tip.imag], axis=1)
    xy += np.random.default_rng(int(seed)).normal(0.0, cfg.sigma, xy.shape)
    n = cfg.n
    header = ",".join([f"q{j}_deg" for j in range(1, n + 1)] + ["x_mm", "y_mm"])
    table = np.column_stack([np.degrees(q), xy])
    np.savetxt(
        out, table, fmt=["%.12g"] * n + ["%.17g"] * 2, delimiter=",", header=header, comments=""
    )


def simulate(cfg: Config, plan: str, trials: str, seed: str) -> None:
    """Monte Carlo of a plan: noise, one least-squares solve per chunk of trials (trials as
    right-hand sides of one factorization), the map to the user's parameters, their mean and
    std against the predicted std, and the RMS tip error at 1000 test poses."""
    q = _plan(plan)
    k = cfg.nominal.size
    truth_tip = positions(cfg, q, None, cfg.truth[:k], cfg.truth[k:])
    clean = np.stack([truth_tip.real, truth_tip.imag], axis=1).reshape(-1)
    h = regressor(cfg, link_columns(cfg, q, None))
    qr_q, qr_r = np.linalg.qr(h)
    rng = np.random.default_rng(int(seed))
    total, chunk = int(trials), max(1, 2**22 // clean.size)
    test_cols = link_columns(cfg, _test_poses(cfg, int(seed)), None)
    gram = test_cols.T.conj() @ test_cols / test_cols.shape[0]
    z_true = (np.abs(cfg.nominal) + cfg.truth[:k]) * np.exp(
        1j * (np.angle(cfg.nominal) + cfg.truth[k:])
    )
    sums, squares, tip_sq, done = 0.0, 0.0, 0.0, 0
    while done < total:
        size = min(chunk, total - done)
        y = rng.standard_normal((size, clean.size))
        y *= cfg.sigma
        y += clean
        w = np.linalg.solve(qr_r, qr_q.T @ y.T).T
        z = w[:, :k] + 1j * w[:, k : 2 * k]
        dl = np.abs(z) - np.abs(cfg.nominal)
        u = np.linalg.solve(cfg.angle_map(), np.angle(z / cfg.nominal).T).T
        params = np.concatenate([dl, u], axis=1)
        sums = sums + params.sum(axis=0)
        squares = squares + (params**2).sum(axis=0)
        dz = z - z_true
        tip_sq += float(np.real(np.einsum("tk,kl,tl->", dz.conj(), gram, dz, optimize=True)))
        done += size
    mean = sums / total
    std = np.sqrt((squares - total * mean**2) / (total - 1))
    cov = cfg.sigma**2 * np.linalg.inv(qr_r.T @ qr_r)
    predicted = np.sqrt(
        np.diag(user_params(cfg, np.concatenate([z_true.real, z_true.imag]), cov)[1])
    )
    print("empirical / predicted std", std / predicted)
    truth = np.concatenate([cfg.truth[:k], np.linalg.solve(cfg.angle_map(), cfg.truth[k:])])
    print("bias", (mean - truth) * display(cfg))
    print(f"tip RMS at test poses {np.sqrt(tip_sq / total):.4g} mm")


def export(cfg: Config, calibration: str, out: str) -> None:
    """The calibrated arm as a robot TOML: lengths ``l + dl``, joint offsets."""
    dl, _, params, _ = read_calibration(calibration, cfg)
    k = dl.size
    offsets = np.degrees(params[k : 2 * k])
    lengths = np.abs(cfg.nominal) + dl
    text = (
        'name = "calibrated"\n'
        f"link_lengths_mm = {json.dumps(lengths.tolist())}\n"
        f"joint_offsets_deg = {json.dumps(offsets.tolist())}\n"
    )
    with open(out, "w") as f:
        f.write(text)


FLOORS = {
    "identify": identify,
    "identify-3d": identify_3d,
    "validate": validate,
    "compensate": compensate,
    "evaluate": evaluate,
    "design": design,
    "design-pool": design_pool,
    "synthesize": synthesize,
    "simulate": simulate,
    "export": export,
}

if __name__ == "__main__":
    FLOORS[sys.argv[1]](load_config(sys.argv[2]), *sys.argv[3:])
