"""Figures of calibration plans and accuracy studies (matplotlib, object-oriented API, Agg only).

Every function builds a :class:`matplotlib.figure.Figure` without touching
``pyplot`` or any global state and returns it; :func:`save_figure` renders it
to PNG through the Agg canvas.  Nothing else in :mod:`armcal` imports this
module, so ``import armcal`` does not import matplotlib.
"""

from __future__ import annotations

import os
from typing import Any

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.collections import LineCollection
from matplotlib.colors import Normalize
from matplotlib.figure import Figure
from matplotlib.layout_engine import ConstrainedLayoutEngine
from matplotlib.lines import Line2D
from matplotlib.patches import Circle, Patch, Rectangle, Wedge
from matplotlib.ticker import FuncFormatter, MaxNLocator, NullFormatter

from .files import atomic_write
from .formats import FIGURE_FORMATS
from .models import Annulus, PlanarArm, link_vectors
from .numerics import rms

__all__ = [
    "plot_accuracy_curves",
    "plot_error_map",
    "plot_plan",
    "plot_random_plans",
    "plot_residuals",
    "plot_validation",
    "save_figure",
]

_CMAP = "viridis"


def _joint_positions(arm: PlanarArm, q: np.ndarray) -> np.ndarray:
    """Base and joint positions ``(m, n + 1, 2)`` in mm at the nominal geometry."""
    first = None if not arm.targets else np.zeros(q.shape[0], dtype=int)  # the first target's
    steps = link_vectors(arm, q, target=first)[..., : arm.n_joints]
    points = np.concatenate([np.zeros((q.shape[0], 1)), np.cumsum(steps, axis=1)], axis=1)
    return np.stack([points.real, points.imag], axis=-1)


def _draw_workspace(ax, arm: PlanarArm, joints: np.ndarray, norm: Normalize) -> None:
    m, n = joints.shape[0], joints.shape[1] - 1
    pose = np.arange(m)
    alpha = float(np.clip(3.0 / np.sqrt(m), 0.15, 0.8))
    arms = LineCollection(list(joints), cmap=_CMAP, norm=norm, linewidths=1.2, alpha=alpha)
    arms.set_array(pose)
    arms.set_gid("poses")
    ax.add_collection(arms)
    if n > 1:
        inner = joints[:, 1:-1].reshape(-1, 2)
        ax.scatter(
            *inner.T,
            c=np.repeat(pose, n - 1),
            cmap=_CMAP,
            norm=norm,
            s=6,
            alpha=alpha,
            linewidths=0,
            zorder=3,
        )
    ax.scatter(
        *joints[:, -1].T,
        c=pose,
        cmap=_CMAP,
        norm=norm,
        s=float(np.clip(480.0 / m, 8.0, 24.0)),
        marker="D",
        edgecolors="k",
        linewidths=0.4 if m <= 50 else 0.2,
        zorder=4,
    )
    ax.plot(0.0, 0.0, "ks", ms=8, zorder=5, label="base")
    reach = float(arm.link_lengths.sum())
    ax.add_patch(Circle((0.0, 0.0), reach, fill=False, ls="--", color="0.55", label="reach"))
    lo, hi = np.array([-reach, -reach]), np.array([reach, reach])
    region = arm.region
    patch: Patch | None = None
    if isinstance(region, Annulus):
        cx, cy = region.center
        width = region.r_max - region.r_min if region.r_min > 0 else None
        patch = Wedge((cx, cy), region.r_max, 0.0, 360.0, width=width)
        lo = np.minimum(lo, [cx - region.r_max, cy - region.r_max])
        hi = np.maximum(hi, [cx + region.r_max, cy + region.r_max])
    elif region is not None:
        (x0, x1), (y0, y1) = region.x, region.y
        patch = Rectangle((x0, y0), x1 - x0, y1 - y0)
        lo, hi = np.minimum(lo, [x0, y0]), np.maximum(hi, [x1, y1])
    if patch is not None:
        patch.set(facecolor="tab:orange", edgecolor="tab:orange", alpha=0.18, linewidth=1.0)
        patch.set_label("measurement region")
        patch.set_zorder(0)
        ax.add_patch(patch)
    pad = 0.05 * float(np.max(hi - lo))
    ax.set_xlim(lo[0] - pad, hi[0] + pad)
    ax.set_ylim(lo[1] - pad, hi[1] + pad)
    ax.set_aspect("equal")
    ax.set_xlabel("x [mm]")
    ax.set_ylabel("y [mm]")
    ax.set_title("workspace", fontsize="medium")
    ax.grid(True, lw=0.4, alpha=0.4)


def _draw_joint_space(ax, arm: PlanarArm, q: np.ndarray, norm: Normalize) -> None:
    m, n = q.shape
    joint = np.arange(1, n + 1)
    limits = np.degrees(arm.joint_limits)
    for j, (lo, hi) in zip(joint, limits, strict=True):
        ax.fill_between([j - 0.38, j + 0.38], lo, hi, color="0.9", lw=0, zorder=0)
        ax.hlines([lo, hi], j - 0.38, j + 0.38, color="0.35", lw=1.5, zorder=1)
    # Spread the poses across each column in pose order: deterministic, and it
    # repeats the colour coding (pose 1 on the left, pose m on the right).
    jitter = np.linspace(-0.3, 0.3, m) if m > 1 else np.zeros(1)
    x = (joint[None, :] + jitter[:, None]).ravel()
    pose = np.repeat(np.arange(m), n)
    size = float(np.clip(600.0 / m, 4.0, 30.0))
    ax.scatter(
        x,
        np.degrees(q).ravel(),
        c=pose,
        cmap=_CMAP,
        norm=norm,
        s=size,
        edgecolors="k",
        linewidths=0.2,
        zorder=3,
        gid="joint angles",
    )
    ax.set_xticks(joint, [f"q{j}" for j in joint])
    ax.set_xlim(0.5, n + 0.5)
    ax.yaxis.set_major_locator(MaxNLocator(nbins=9, steps=[1, 1.5, 3, 4.5, 9, 10]))
    ax.set_ylabel("joint angle [deg]")
    ax.set_title("joint space", fontsize="medium")
    ax.grid(True, axis="y", lw=0.4, alpha=0.4)


def plot_plan(
    arm: PlanarArm, q: np.ndarray, *, title: str | None = None, numbers: bool = False
) -> Figure:
    """Draw a calibration plan in the workspace and in joint space.

    Parameters
    ----------
    arm : PlanarArm
        Nominal geometry (link lengths in mm), joint limits and measurement region.
    q : ndarray, shape (m, n)
        Commanded joint angles in rad, one row per pose.
    title : str, optional
        Figure title; default ``"<arm.name>: <m> poses"``.
    numbers : bool
        Write every pose's number (1-based, the plan's order) at its tip.

    Returns
    -------
    matplotlib.figure.Figure
        Two axes: the workspace (every pose as a stick arm at the nominal
        geometry, base, reach circle and measurement region; mm, equal aspect)
        and joint space (each ``q_j`` in degrees against its limits).  Poses are
        coloured by index (viridis) in both.

    Raises
    ------
    ValueError
        If ``q`` is not a finite array of shape ``(m, n)`` with ``m >= 1``.

    Examples
    --------
    >>> fig = plot_plan(PlanarArm([2.0, 1.0]), np.zeros((3, 2)))
    >>> [ax.get_xlabel() for ax in fig.axes]
    ['x [mm]', '']
    """
    q = np.asarray(q, dtype=float)
    n = arm.n_joints
    if q.ndim != 2 or q.shape[0] < 1 or q.shape[1] != n or not np.all(np.isfinite(q)):
        raise ValueError(f"q must be finite with shape (m, {n}) in rad, m >= 1; got {q.shape}")
    m = q.shape[0]
    fig = Figure(figsize=(11, 5), layout="constrained")
    ax_ws, ax_js = fig.subplots(1, 2, width_ratios=[1.0, 1.0])
    norm = Normalize(vmin=0, vmax=max(m - 1, 1))
    joints = _joint_positions(arm, q)
    _draw_workspace(ax_ws, arm, joints, norm)
    if numbers:
        for i, tip in enumerate(joints[:, -1]):
            ax_ws.annotate(str(i + 1), tip, xytext=(3, 3), textcoords="offset points", fontsize=7)
    _draw_joint_space(ax_js, arm, q, norm)
    cmap = ax_ws.collections[0].get_cmap()
    handles = [
        Line2D([], [], color=cmap(norm(0)), lw=2, label="pose 1"),
        *([Line2D([], [], color=cmap(norm(m - 1)), lw=2, label=f"pose {m}")] if m > 1 else []),
        Line2D([], [], ls="", marker="D", mfc="w", mec="k", label="tip"),
        *ax_ws.get_legend_handles_labels()[0],
        Rectangle((0, 0), 1, 1, fc="0.9", ec="0.35", label="joint limits"),
    ]
    fig.legend(handles=handles, loc="outside lower center", ncols=len(handles), frameon=False)
    fig.suptitle(title if title is not None else f"{arm.name}: {m} poses")
    return fig


def plot_random_plans(
    det_d: np.ndarray,
    det_c: np.ndarray,
    abs_det_s: np.ndarray,
    *,
    poses: int,
    title: str | None = None,
) -> Figure:
    """Histograms of the paper's Figure 1 criteria over random plans, against the optimum.

    Parameters
    ----------
    det_d, det_c, abs_det_s : ndarray, shape (N,)
        ``det D'``, ``det C'`` and ``|det S'|`` of ``N`` random plans
        (:class:`armcal.reproduction.study.PlanStudy`).
    poses : int
        Poses per plan (for the labels).
    title : str, optional

    Returns
    -------
    matplotlib.figure.Figure
        Three panels; the optimal plan's value (1, 1, 0) is a vertical line.
    """
    fig = Figure(figsize=(11, 3.6), layout="constrained")
    axes = fig.subplots(1, 3)
    panels = (
        (det_d, "det(D')  (= D-efficiency$^p$)", 1.0),
        (det_c, "det(C'),  C' = C / m", 1.0),
        (abs_det_s, "|det(S')|,  S' = S / m", 0.0),
    )
    for ax, (values, label, optimum) in zip(axes, panels, strict=True):
        top = max(float(np.max(values)), optimum) * 1.02 or 1.0
        ax.hist(values, bins=60, range=(0.0, top), color="tab:blue", alpha=0.75)
        ax.axvline(optimum, color="tab:red", lw=2, label=f"optimal plan ({optimum:g})")
        ax.axvline(float(np.median(values)), color="k", ls="--", lw=1, label="median, random")
        ax.set_xlabel(label)
        ax.set_ylabel("random plans")
        ax.legend(loc="upper center", fontsize=8, frameon=False)
    fig.suptitle(
        title
        if title is not None
        else f"{det_d.size} random {poses}-pose plans (uniform joint angles) vs the optimum"
    )
    return fig


def plot_accuracy_curves(curves: dict[str, np.ndarray], *, title: str | None = None) -> Figure:
    """Accuracy against the number of poses: analytic, simulated optimal and random plans.

    Parameters
    ----------
    curves : dict of str to ndarray
        ``poses`` and, for ``key`` in ``length`` (mm), ``angle`` (deg) and
        ``position`` (mm): ``analytic_key``, ``simulated_key``,
        ``random_mean_key`` and ``random_median_key`` (see
        :class:`armcal.reproduction.Reproduction`).
    title : str, optional

    Returns
    -------
    matplotlib.figure.Figure
        Three log-log panels in the paper's Figure 2 style: curve 1 analytic, x
        simulated, curve 2 the random-plan average.
    """
    fig = Figure(figsize=(12, 4), layout="constrained")
    axes = fig.subplots(1, 3)
    poses = curves["poses"]
    panels = (
        ("length", "length deviation std (mm)"),
        ("angle", "worst joint-offset std (deg)"),
        ("position", "RMS tip error per point after calibration (mm)"),
    )
    for ax, (key, label) in zip(axes, panels, strict=True):
        ax.plot(poses, curves[f"analytic_{key}"], color="tab:blue", label="1: analytic, optimal")
        ax.plot(
            poses,
            curves[f"simulated_{key}"],
            "x",
            color="k",
            ms=6,
            label="x: simulated, optimal",
        )
        ax.plot(poses, curves[f"random_mean_{key}"], color="tab:red", label="2: random, mean")
        ax.plot(
            poses,
            curves[f"random_median_{key}"],
            color="tab:red",
            ls="--",
            lw=1,
            label="random, median",
        )
        ax.set_xscale("log")
        ax.set_yscale("log")
        ticks = [m for m in (2, 3, 4, 6, 10, 20, 30, 50, 100, 200) if poses[0] <= m <= poses[-1]]
        ax.set_xticks(ticks, labels=[str(m) for m in ticks])
        ax.xaxis.set_minor_formatter(NullFormatter())
        ax.yaxis.set_major_formatter(FuncFormatter(lambda v, _: f"{v:g}"))
        ax.yaxis.set_minor_formatter(FuncFormatter(lambda v, _: f"{v:g}"))
        ax.tick_params(axis="y", which="minor", labelsize=7)
        ax.set_xlabel("poses m")
        ax.set_ylabel(label)
        ax.grid(True, which="both", alpha=0.3)
    axes[0].legend(fontsize=8, frameon=False)
    fig.suptitle(title if title is not None else "Accuracy against the number of poses")
    engine = fig.get_layout_engine()
    if isinstance(engine, ConstrainedLayoutEngine):
        engine.set(w_pad=0.1)
    return fig


def _error_arrows(ax, positions: np.ndarray, errors: np.ndarray, scale: float, **style) -> None:
    """Arrows from each position along its error, drawn ``scale`` times longer (mm)."""
    ax.quiver(
        positions[:, 0],
        positions[:, 1],
        errors[:, 0] * scale,
        errors[:, 1] * scale,
        angles="xy",
        scale_units="xy",
        scale=1.0,
        width=0.004,
        **style,
    )


def _arrow_scale(positions: np.ndarray, errors: np.ndarray) -> float:
    """A round factor that draws the largest error at about a tenth of the points' spread."""
    spread = float(np.ptp(positions, axis=0).max()) if positions.shape[0] > 1 else 1.0
    largest = float(np.max(np.hypot(errors[:, 0], errors[:, 1]), initial=0.0))
    if largest <= 0 or spread <= 0:
        return 1.0
    raw = 0.1 * spread / largest
    return float(10 ** np.floor(np.log10(raw)))


def plot_validation(arm: PlanarArm, q: np.ndarray, result, *, title: str | None = None) -> Figure:
    """Error vectors on the workspace and every pose's error against its prediction.

    Parameters
    ----------
    arm : PlanarArm
    q : ndarray, shape (m, n)
        The held-out poses (rad).
    result : armcal.validation.Validation
    title : str, optional

    Returns
    -------
    matplotlib.figure.Figure
        Left: the measured positions with their errors before (grey) and after
        (red) calibration as arrows, magnified by a stated factor.  Right: every
        pose's error before and after, and the error the calibration predicts.
    """
    fig = Figure(figsize=(11, 4.8), layout="constrained")
    ax_ws, ax_err = fig.subplots(1, 2)
    positions = result.positions
    scale = _arrow_scale(positions, result.before)
    scale_after = _arrow_scale(positions, result.after)
    ax_ws.plot(positions[:, 0], positions[:, 1], ".", color="0.3", ms=3)
    _error_arrows(
        ax_ws, positions, result.before, scale, color="0.55", label=f"nominal model, x{scale:g}"
    )
    _error_arrows(
        ax_ws,
        positions,
        result.after,
        scale_after,
        color="tab:red",
        label=f"calibrated, x{scale_after:g}",
    )
    ax_ws.set_aspect("equal", adjustable="datalim")
    ax_ws.set_xlabel("x [mm]")
    ax_ws.set_ylabel("y [mm]")
    ax_ws.set_title("position errors (arrows magnified)")
    ax_ws.legend(fontsize=8, frameon=False, loc="best")
    index = np.arange(1, positions.shape[0] + 1)
    ax_err.semilogy(index, result.before_mm, "o", color="0.55", ms=3, label="nominal model")
    ax_err.semilogy(index, result.after_mm, "o", color="tab:red", ms=3, label="calibrated")
    ax_err.semilogy(
        index, result.predicted_mm, "-", color="k", lw=1, label="predicted (RMS per point)"
    )
    ax_err.set_xlabel("held-out pose")
    ax_err.set_ylabel("position error [mm]")
    ax_err.legend(fontsize=8, frameon=False)
    fig.suptitle(title if title is not None else f"{arm.name}: validation on held-out poses")
    return fig


def plot_residuals(
    residuals: np.ndarray,
    sigma: float,
    *,
    used: np.ndarray | None = None,
    title: str | None = None,
) -> Figure:
    """Every pose's residual (Euclidean, mm) of a fit, with the noise level.

    Parameters
    ----------
    residuals : ndarray, shape (m, 2)
        Measured minus fitted positions, mm.
    sigma : float
        The instrument noise (1 std per coordinate, mm): a clean pose's
        residual is below ``sigma sqrt(-2 ln 0.01)`` with probability 0.99.
    used : ndarray of bool, shape (m,), optional
        Poses in the fit; the others (outliers left out) are drawn as crosses.
    """
    fig = Figure(figsize=(8, 3.6), layout="constrained")
    ax = fig.subplots()
    distance = np.hypot(residuals[:, 0], residuals[:, 1])
    index = np.arange(1, distance.size + 1)
    kept = np.ones(distance.size, dtype=bool) if used is None else used
    ax.bar(index[kept], distance[kept], color="tab:blue", width=0.8, label="in the fit")
    if not kept.all():
        ax.plot(
            index[~kept],
            distance[~kept],
            "x",
            color="tab:red",
            ms=8,
            mew=2,
            label="left out (outlier)",
        )
    limit = sigma * np.sqrt(-2.0 * np.log(0.01))
    ax.axhline(limit, color="k", lw=1, ls="--", label="99 % of clean poses below")
    ax.set_yscale("log")
    ax.xaxis.set_major_locator(MaxNLocator(integer=True))
    ax.set_xlabel("pose")
    ax.set_ylabel("residual [mm]")
    ax.legend(fontsize=8, frameon=False)
    ax.set_title(title if title is not None else "residual of every pose")
    return fig


def plot_error_map(
    arm: PlanarArm,
    q: np.ndarray,
    before_mm: np.ndarray,
    after_mm: np.ndarray,
    positions: np.ndarray,
    *,
    title: str | None = None,
) -> Figure:
    """The positioning error over the workspace before and after calibration (two panels).

    ``positions`` ``(k, 2)`` are the tips of the poses ``q`` (mm); the errors
    ``(k,)`` colour them on one shared logarithmic scale.
    """
    from matplotlib.colors import LogNorm

    fig = Figure(figsize=(11, 4.8), layout="constrained")
    axes = fig.subplots(1, 2)
    low = max(float(np.min(after_mm)), 1e-6)
    norm = LogNorm(vmin=low, vmax=max(float(np.max(before_mm)), low * 10))
    image: Any = None
    for ax, values, name in zip(
        axes, (before_mm, after_mm), ("nominal model", "calibrated"), strict=True
    ):
        image = ax.scatter(
            positions[:, 0], positions[:, 1], c=values, s=8, cmap="magma_r", norm=norm
        )
        ax.plot([0], [0], "k+", ms=10)
        ax.set_aspect("equal", adjustable="datalim")
        ax.set_title(f"{name}: RMS {rms(values):.3g} mm per point")
        ax.set_xlabel("x [mm]")
    axes[0].set_ylabel("y [mm]")
    fig.colorbar(image, ax=list(axes), label="position error [mm]")
    fig.suptitle(title if title is not None else f"{arm.name}: error over the workspace")
    return fig


def save_figure(fig: Figure, path: str | os.PathLike) -> None:
    """Write ``fig`` to ``path`` in the format its suffix names, through a temporary file.

    PNG at 120 dpi; ``.pdf``, ``.svg`` and ``.eps`` as vector files
    (:data:`armcal.formats.FIGURE_FORMATS`); any other suffix is PNG.

    Parameters
    ----------
    fig : matplotlib.figure.Figure
    path : str or os.PathLike
        Target file; its folder must exist.  An existing file is replaced; a
        symbolic link is written through (see :func:`armcal.files.atomic_write`).

    Raises
    ------
    InputError
        If the folder does not exist or is not writable, or ``path`` is a
        directory or a special file (FIFO, device, socket).
    """
    FigureCanvasAgg(fig)  # attach the Agg canvas: no GUI backend is ever involved
    kind = FIGURE_FORMATS.get(os.path.splitext(os.fspath(path))[1].lower(), "png")
    atomic_write(path, lambda handle: fig.savefig(handle, format=kind, dpi=120))
