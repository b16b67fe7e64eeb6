"""Pictures of a spatial arm's plan: the arm at its poses, its joints against their limits,
the predicted error after calibration over the workspace, and the certificate's variance.

Imported only when a picture is asked for (matplotlib is slow to import), like
:mod:`armcal.plotting`, whose :func:`~armcal.plotting.save_figure` writes them.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from matplotlib.figure import Figure
from matplotlib.layout_engine import ConstrainedLayoutEngine

from .criteria import position_accuracy
from .doe import Certificate, feasible_poses
from .models import FitModel, SpatialArm
from .models.spatial.chain import joint_motion

__all__ = [
    "NUMBERED_POSES_MAX",
    "plot_spatial_plan",
]

#: Random feasible poses over which the error map and the variance function are drawn.
MAP_POSES = 2000

#: A plan of at most this many poses has every flange numbered (more would be a blur).
NUMBERED_POSES_MAX = 60


def _chain_points(arm: SpatialArm, q: np.ndarray) -> np.ndarray:
    """The joint origins and the flange ``(m, n + 2, 3)`` of poses ``q`` (robot frame, mm)."""
    u = q @ arm.joint_map.T
    frame = np.broadcast_to(np.eye(4), (q.shape[0], 4, 4)).copy()
    points = [frame[:, :3, 3].copy()]
    for k, kind in enumerate(arm.chain.kinds):
        frame = frame @ arm.chain.origins[k]
        points.append(frame[:, :3, 3].copy())
        frame = frame @ joint_motion(kind, u[:, k])
    points.append((frame @ arm.chain.tip)[:, :3, 3])
    return np.stack(points, axis=1)


def _sticks(
    fig: Figure,
    spec,
    arm: SpatialArm,
    q: np.ndarray,
    marks: tuple[tuple[str, np.ndarray], ...] = (),
) -> None:
    """The arm at every pose, each flange numbered by its row of the plan, and the
    instrument where the robot file's view puts it, or an instrument's ``marks`` (its
    features, labelled), on equal axes (a metre is a metre along x, y and z)."""
    ax = fig.add_subplot(spec, projection="3d")
    chain = _chain_points(arm, q)
    for pose in chain:
        ax.plot(pose[:, 0], pose[:, 1], pose[:, 2], color="0.4", lw=0.8, alpha=0.6)
    tips = chain[:, -1]
    ax.scatter(tips[:, 0], tips[:, 1], tips[:, 2], s=8, color="C0", label="flange")
    if q.shape[0] <= NUMBERED_POSES_MAX:
        for k, (x, y, z) in enumerate(tips):
            ax.text(x, y, z, f" {k + 1}", fontsize=7, color="C0")
    shown = chain.reshape(-1, 3)
    view = arm.view
    if view is not None:
        x, y, z = view.position
        ax.scatter([x], [y], [z], marker="^", s=60, color="C3", label="instrument")
        shown = np.vstack([shown, view.position])
    if marks:
        where = np.array([xyz for _, xyz in marks], dtype=float)
        ax.scatter(*where.T, marker="^", s=60, color="C3", label="instrument")
        for label, xyz in marks:
            ax.text(*xyz, f" {label}", fontsize=7, color="C3")
        shown = np.vstack([shown, where])
    low, high = shown.min(axis=0), shown.max(axis=0)
    pad = 0.05 * float(np.max(high - low))
    for setter, lo, hi in zip((ax.set_xlim, ax.set_ylim, ax.set_zlim), low, high, strict=True):
        setter(lo - pad, hi + pad)
    ax.set_box_aspect(tuple(high - low + 2 * pad))
    ax.set_title(f"{q.shape[0]} poses, numbered by row")
    ax.set_xlabel("x (mm)")
    ax.set_ylabel("y (mm)")
    ax.set_zlabel("z (mm)")
    ax.legend(loc="upper left", fontsize=7)


def _joints(fig: Figure, spec, arm: SpatialArm, q: np.ndarray) -> None:
    ax = fig.add_subplot(spec)
    n = arm.n_joints
    scale = np.where(arm.chain.revolute, 180.0 / np.pi, 1.0)
    limits = arm.limits * scale[:, None]
    for j in range(n):
        ax.plot([j + 1, j + 1], limits[j], color="0.8", lw=8, solid_capstyle="butt")
    jitter = np.linspace(-0.2, 0.2, q.shape[0])
    for j in range(n):
        ax.scatter(j + 1 + jitter, q[:, j] * scale[j], s=6, color="C0")
    ax.set_xticks(range(1, n + 1))
    ax.set_xlabel("joint")
    ax.set_ylabel("reading (deg; mm for a slide)")
    ax.set_title("joints against their limits")


def _error_map(
    fig: Figure, spec, model: FitModel, q: np.ndarray, sigma: float, poses: np.ndarray
) -> None:
    ax = fig.add_subplot(spec)
    per_point = position_accuracy(model, q, poses, sigma).per_pose_mm  # every target's
    error = np.sqrt(np.mean(per_point.reshape(poses.shape[0], -1) ** 2, axis=1))
    arm = _spatial(model)
    flange = _chain_points(arm, poses)[:, -1]
    shown = ax.scatter(flange[:, 0], flange[:, 1], c=error, s=4, cmap="viridis")
    fig.colorbar(shown, ax=ax, label="predicted error after calibration (mm RMS per point)")
    ax.set_aspect("equal")
    ax.set_xlabel("flange x (mm)")
    ax.set_ylabel("flange y (mm)")
    ax.set_title("over the workspace, seen from above")


def _spatial(model: FitModel) -> SpatialArm:
    """The spatial arm of ``model``: itself, or the arm an instrument measures."""
    alone = model.alone(np.zeros(model.n_params), np.zeros((model.n_params, model.n_params)))
    return alone[0].arm


def _variance(fig: Figure, spec, model: FitModel, certificate: Certificate, poses) -> None:
    ax = fig.add_subplot(spec)
    inverse = certificate.reference_inverse(model)
    values, _ = model.plan_information(poses).pose_variance(inverse)
    ax.plot(np.sort(values)[::-1], color="C0", label="d(x) at random feasible poses, sorted")
    ax.axhline(model.n_free, color="C2", ls="--", label=f"p = {model.n_free}: the optimum's")
    ax.axhline(certificate.max_variance, color="C3", ls=":", label="the maximum found")
    ax.set_xscale("log")
    ax.set_xlabel("pose (by rank)")
    ax.set_ylabel("variance function d(x)")
    ax.set_title(f"certified >= {certificate.certified_d_efficiency:.4f}")
    ax.legend(fontsize=7)


def plot_spatial_plan(
    model: FitModel,
    q: np.ndarray,
    *,
    sigma: float,
    certificate: Certificate | None = None,
    rng: int = 0,
) -> Figure:
    """A spatial arm's plan in four panels: the arm at every pose with the instrument, the
    joints against their limits, the predicted position error after calibration at
    :data:`MAP_POSES` random feasible poses (noise ``sigma`` mm), and the certificate's
    variance function there against its premise (where a certificate is given).

    An arm measured by an instrument other than a tracker: its features marked, the
    error of the arm's own tool point over poses within the limits (not only those that
    meet the instrument: the calibrated arm works everywhere), and the variance function
    over poses that meet it (the set the certificate is over)."""
    arm = _spatial(model)
    poses = feasible_poses(model, MAP_POSES, rng=rng)
    workspace = poses if arm is model.arm else feasible_poses(arm, MAP_POSES, rng=rng)
    fig = Figure(figsize=(12, 9))
    fig.set_layout_engine(ConstrainedLayoutEngine())
    grid = fig.add_gridspec(2, 2)
    instrument = getattr(model, "instrument", None)  # an instrumented arm's
    _sticks(fig, grid[0, 0], arm, q, () if instrument is None else instrument.marks)
    _joints(fig, grid[0, 1], arm, q)
    _error_map(fig, grid[1, 0], model, q, sigma, workspace)
    if certificate is not None:
        _variance(fig, grid[1, 1], model, certificate, poses)
    fig.suptitle(f"plan of {arm.name}")
    return fig


def spatial_plan_figure(robot: Any, run: Any, *, seed: int = 0) -> Figure:
    """A designed plan (a :class:`~armcal.workflow.DesignRun`) in four panels
    (:func:`plot_spatial_plan`; :mod:`armcal.families`, role ``plan_figure``)."""
    return plot_spatial_plan(
        run.design.model,
        run.q,
        sigma=run.quality.sigma_mm,
        certificate=run.design.certificate,
        rng=seed,
    )
