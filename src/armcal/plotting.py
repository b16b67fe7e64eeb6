"""Figures of calibration plans and accuracy studies (matplotlib, object-oriented API, Agg only).

Every function builds a :class:`matplotlib.figure.Figure` without touching
``pyplot`` or any global state and returns it; :func:`save_figure` renders it
to PNG through the Agg canvas.  Nothing else in :mod:`armcal` imports this
module, so ``import armcal`` does not import matplotlib.
"""

from __future__ import annotations

import io
import os
from collections.abc import Sequence
from typing import Any, BinaryIO

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
    "figure_png",
    "plot_accuracy_curves",
    "plot_error_map",
    "plot_plan",
    "plot_random_plans",
    "plot_validation",
    "save_figure",
]

_CMAP = "viridis"


#: A plan's poses are numbered when it has at most this many distinct ones; above,
#: the numbers would hide the poses (the plan CSV lists them) and the figure says so.
NUMBERED_POSES_MAX = 40

#: The frame of a plan's coordinates (the nominal arm's base at the origin).
BASE_FRAME = "base frame"


def _joint_positions(arm: PlanarArm, q: np.ndarray) -> np.ndarray:
    """Base and joint positions ``(m, n + 1, 2)`` in mm at the nominal geometry."""
    first = None if not arm.targets else np.zeros(q.shape[0], dtype=int)  # the first target's
    steps = link_vectors(arm, q, target=first)[..., : arm.n_joints]
    points = np.concatenate([np.zeros((q.shape[0], 1)), np.cumsum(steps, axis=1)], axis=1)
    return np.stack([points.real, points.imag], axis=-1)


def _distinct_poses(q: np.ndarray, payload_kg: np.ndarray | None = None) -> tuple[np.ndarray, ...]:
    """The distinct poses of a plan, in its order: first row and multiplicity of each.

    Parameters
    ----------
    q : ndarray, shape (m, n)
        Joint angles, rad.
    payload_kg : ndarray, shape (m,), optional
        Every pose's payload: the same joints with another payload is another pose.

    Returns
    -------
    first : ndarray of int, shape (k,)
        The 0-based row where every distinct pose first appears, increasing.
    count : ndarray of int, shape (k,)
        How many rows repeat it.
    """
    key = q if payload_kg is None else np.column_stack([q, payload_kg])
    _, first, count = np.unique(key, axis=0, return_index=True, return_counts=True)
    order = np.argsort(first)
    return first[order], count[order]


def _spread_angles(angles: np.ndarray, gap: float) -> np.ndarray:
    """Angles (rad) nearest ``angles`` in least squares that are ``gap`` apart around a circle.

    The circle is cut at the widest gap between the angles, so that the rest
    keep their order along a line; there, ``y_i - i gap`` must not decrease, an
    isotonic regression (pool adjacent violators).  When the ends then meet
    across the cut the angles are spaced evenly.
    """
    k = angles.size
    if k < 2:
        return angles.astype(float)
    gap = min(gap, 2.0 * np.pi / k)
    order = np.argsort(angles)
    ordered = angles[order]
    widest = np.diff(np.append(ordered, ordered[0] + 2.0 * np.pi))
    start = (int(np.argmax(widest)) + 1) % k
    line = np.concatenate([ordered[start:], ordered[:start] + 2.0 * np.pi])
    steps = gap * np.arange(k)
    blocks: list[list[float]] = []  # [mean, size] of the pooled runs
    for value in line - steps:
        blocks.append([value, 1.0])
        while len(blocks) > 1 and blocks[-2][0] > blocks[-1][0]:
            (mean2, size2), (mean1, size1) = blocks.pop(), blocks.pop()
            blocks.append([(mean1 * size1 + mean2 * size2) / (size1 + size2), size1 + size2])
    spread = np.repeat([b[0] for b in blocks], [int(b[1]) for b in blocks]) + steps
    if spread[-1] - spread[0] > 2.0 * np.pi - gap:  # the two ends meet: space them evenly
        even = 2.0 * np.pi / k * np.arange(k)
        spread = float(np.mean(line - even)) + even
    out = np.empty(k)
    out[order[(start + np.arange(k)) % k]] = spread
    return out


def _number_poses(ax, tips: np.ndarray, labels: list[str], radius: float) -> None:
    """Write the labels on a circle of ``radius`` (mm) about the base, each joined to its tip.

    A label sits at its tip's bearing from the base, moved along the circle
    only as far as it must to keep clear of its neighbours (9 degrees: room for
    :data:`NUMBERED_POSES_MAX` labels), and reads outward along its leader
    line, so that its width, however long, never reaches the next one.  No
    label crowds the base, where the tips of folded poses lie close together.
    """
    bearing = _spread_angles(np.arctan2(tips[:, 1], tips[:, 0]), 2.0 * np.pi / NUMBERED_POSES_MAX)
    for tip, label, angle in zip(tips, labels, bearing, strict=True):
        c, s = np.cos(angle), np.sin(angle)
        ax.annotate(
            label,
            tip,
            xytext=(radius * c, radius * s),
            ha="left" if c >= 0 else "right",
            va="center",
            rotation=np.degrees(angle) if c >= 0 else np.degrees(angle) - 180.0,
            rotation_mode="anchor",
            fontsize=7,
            arrowprops={"arrowstyle": "-", "color": "0.6", "lw": 0.5, "shrinkA": 1, "shrinkB": 2},
            gid="pose number",
        )


def _draw_gravity(ax, gravity: np.ndarray) -> None:
    """An arrow along gravity's direction in the workspace's upper left corner."""
    direction = gravity / np.hypot(*gravity)
    (x0, x1), (y0, y1) = ax.get_xlim(), ax.get_ylim()
    size = 0.07 * max(x1 - x0, y1 - y0)
    centre = np.array([x0 + 1.4 * size, y1 - 1.4 * size])
    ax.annotate(
        "",
        centre + size * direction,
        xytext=centre - size * direction,
        arrowprops={"arrowstyle": "-|>", "color": "tab:blue", "lw": 2.0, "mutation_scale": 15},
        gid="gravity",
    )
    side = centre + 0.35 * size * np.array([abs(direction[1]), abs(direction[0])])
    ax.text(*side, "gravity", color="tab:blue", ha="left", va="center", fontsize=8)


def _mark_payloads(ax, tips: np.ndarray, payload_kg: np.ndarray) -> None:
    """A ring round every tip that carries a payload: one size per payload, up to four."""
    values = np.unique(payload_kg[payload_kg > 0])
    groups = [(payload_kg == v, f"payload {v:g} kg") for v in values]
    if values.size > 4:  # a size per value would not be told apart
        groups = [(payload_kg > 0, f"payload {values[0]:g}-{values[-1]:g} kg")]
    for rank, (ring, label) in enumerate(groups):
        ax.scatter(
            *tips[ring].T,
            s=70.0 + 50.0 * rank,
            facecolors="none",
            edgecolors="tab:red",
            linewidths=1.0,
            zorder=4.5,
            label=label,
            gid="payload",
        )


def _draw_workspace(ax, arm: PlanarArm, joints: np.ndarray, first: np.ndarray, norm) -> None:
    """The distinct poses as stick arms coloured by their first row, with reach and region."""
    k, n = joints.shape[0], joints.shape[1] - 1
    alpha = float(np.clip(3.0 / np.sqrt(k), 0.15, 0.8))
    arms = LineCollection(list(joints), cmap=_CMAP, norm=norm, linewidths=1.2, alpha=alpha)
    arms.set_array(first)
    arms.set_gid("poses")
    ax.add_collection(arms)
    if n > 1:
        inner = joints[:, 1:-1].reshape(-1, 2)
        ax.scatter(
            *inner.T,
            c=np.repeat(first, n - 1),
            cmap=_CMAP,
            norm=norm,
            s=6,
            alpha=alpha,
            linewidths=0,
            zorder=3,
        )
    ax.scatter(
        *joints[:, -1].T,
        c=first,
        cmap=_CMAP,
        norm=norm,
        s=float(np.clip(480.0 / k, 8.0, 24.0)),
        marker="D",
        edgecolors="k",
        linewidths=0.4 if k <= 50 else 0.2,
        zorder=4,
    )
    ax.plot(0.0, 0.0, "ks", ms=8, zorder=5, label="base")
    reach = float(arm.link_lengths.sum())
    ax.add_patch(Circle((0.0, 0.0), reach, fill=False, ls="--", color="0.55", label="reach"))
    region = arm.region
    patch: Patch | None = None
    if isinstance(region, Annulus):
        cx, cy = region.center
        width = region.r_max - region.r_min if region.r_min > 0 else None
        patch = Wedge((cx, cy), region.r_max, 0.0, 360.0, width=width)
    elif region is not None:
        (x0, x1), (y0, y1) = region.x, region.y
        patch = Rectangle((x0, y0), x1 - x0, y1 - y0)
    if patch is not None:
        patch.set(facecolor="tab:orange", edgecolor="tab:orange", alpha=0.18, linewidth=1.0)
        patch.set_label("measurement region")
        patch.set_zorder(0)
        ax.add_patch(patch)
    ax.set_aspect("equal")
    ax.set_xlabel(f"x in {BASE_FRAME} [mm]")
    ax.set_ylabel(f"y in {BASE_FRAME} [mm]")
    ax.grid(True, lw=0.4, alpha=0.4)


def _workspace_limits(ax, arm: PlanarArm, radius: float) -> None:
    """Limits that hold the circle of ``radius`` (mm) about the base and the region."""
    lo, hi = np.array([-radius, -radius]), np.array([radius, radius])
    region = arm.region
    if isinstance(region, Annulus):
        cx, cy = region.center
        lo = np.minimum(lo, [cx - region.r_max, cy - region.r_max])
        hi = np.maximum(hi, [cx + region.r_max, cy + region.r_max])
    elif region is not None:
        (x0, x1), (y0, y1) = region.x, region.y
        lo, hi = np.minimum(lo, [x0, y0]), np.maximum(hi, [x1, y1])
    pad = 0.05 * float(np.max(hi - lo))
    ax.set_xlim(lo[0] - pad, hi[0] + pad)
    ax.set_ylim(lo[1] - pad, hi[1] + pad)


def _draw_joint_space(ax, arm: PlanarArm, q: np.ndarray, first: np.ndarray, norm) -> None:
    k, n = q.shape
    joint = np.arange(1, n + 1)
    limits = np.degrees(arm.joint_limits)
    for j, (lo, hi) in zip(joint, limits, strict=True):
        ax.fill_between([j - 0.38, j + 0.38], lo, hi, color="0.9", lw=0, zorder=0)
        ax.hlines([lo, hi], j - 0.38, j + 0.38, color="0.35", lw=1.5, zorder=1)
    # Spread the poses across each column in pose order: deterministic, and it
    # repeats the colour coding (pose 1 on the left, pose m on the right).
    jitter = np.linspace(-0.3, 0.3, k) if k > 1 else np.zeros(1)
    x = (joint[None, :] + jitter[:, None]).ravel()
    size = float(np.clip(600.0 / k, 4.0, 30.0))
    ax.scatter(
        x,
        np.degrees(q).ravel(),
        c=np.repeat(first, n),
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
    arm: PlanarArm,
    q: np.ndarray,
    *,
    title: str | None = None,
    numbers: bool = True,
    payload_kg: np.ndarray | None = None,
    gravity: np.ndarray | None = None,
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
        Number the distinct poses (by the row where each first appears; a pose
        the plan repeats as ``"3 ×4"``), on a circle round the workspace, each
        joined to its tip.  Plans of more than :data:`NUMBERED_POSES_MAX`
        distinct poses are not numbered, and the workspace's title says so.
    payload_kg : ndarray, shape (m,), optional
        Every pose's payload (kg): a pose that carries one gets a ring at its
        tip, one size per payload (labelled in the legend).
    gravity : ndarray, shape (2,), optional
        Gravity's direction in the base frame (``[elastostatic] gravity_xy``),
        drawn as an arrow marked g.

    Returns
    -------
    matplotlib.figure.Figure
        Two axes: the workspace in the base frame (every distinct pose once as
        a stick arm at the nominal geometry, base, reach circle and measurement
        region; mm, equal aspect) and joint space (each ``q_j`` in degrees
        against its limits).  Poses are coloured by their row (viridis) in both.

    Raises
    ------
    ValueError
        If ``q`` is not a finite array of shape ``(m, n)`` with ``m >= 1``, or
        ``payload_kg`` or ``gravity`` have the wrong shape.

    Examples
    --------
    >>> fig = plot_plan(PlanarArm([2.0, 1.0]), np.zeros((3, 2)))
    >>> [ax.get_xlabel() for ax in fig.axes]
    ['x in base frame [mm]', '']
    >>> [t.get_text() for t in fig.axes[0].texts]
    ['1 ×3']
    """
    q = np.asarray(q, dtype=float)
    n = arm.n_joints
    if q.ndim != 2 or q.shape[0] < 1 or q.shape[1] != n or not np.all(np.isfinite(q)):
        raise ValueError(f"q must be finite with shape (m, {n}) in rad, m >= 1; got {q.shape}")
    m = q.shape[0]
    if payload_kg is not None:
        payload_kg = np.asarray(payload_kg, dtype=float)
        if payload_kg.shape != (m,):
            raise ValueError(f"payload_kg must have shape ({m},); got {payload_kg.shape}")
    if gravity is not None and np.shape(gravity) != (2,):
        raise ValueError(f"gravity must be a direction of shape (2,); got {np.shape(gravity)}")
    first, count = _distinct_poses(q, payload_kg)
    fig = Figure(figsize=(11, 5), layout="constrained")
    ax_ws, ax_js = fig.subplots(1, 2, width_ratios=[1.0, 1.0])
    norm = Normalize(vmin=0, vmax=max(m - 1, 1))
    joints = _joint_positions(arm, q[first])
    tips = joints[:, -1]
    _draw_workspace(ax_ws, arm, joints, first, norm)
    radius = max(float(arm.link_lengths.sum()), float(np.max(np.hypot(*tips.T))))
    heading = f"workspace ({BASE_FRAME})"
    if numbers and first.size <= NUMBERED_POSES_MAX:
        labels = [
            f"{row + 1} ×{c}" if c > 1 else str(row + 1)
            for row, c in zip(first, count, strict=True)
        ]
        _number_poses(ax_ws, tips, labels, 1.08 * radius)
        radius *= 1.3  # room for the numbers outside their circle
    elif numbers:
        heading += f": {first.size} distinct poses, too many to number"
    ax_ws.set_title(heading, fontsize="medium")
    _workspace_limits(ax_ws, arm, radius)
    if payload_kg is not None:
        _mark_payloads(ax_ws, tips, payload_kg[first])
    if gravity is not None:
        _draw_gravity(ax_ws, np.asarray(gravity, dtype=float))
    _draw_joint_space(ax_js, arm, q[first], first, norm)
    cmap = ax_ws.collections[0].get_cmap()
    handles = [
        Line2D([], [], color=cmap(norm(0)), lw=2, label="pose 1"),
        *([Line2D([], [], color=cmap(norm(m - 1)), lw=2, label=f"pose {m}")] if m > 1 else []),
        Line2D([], [], ls="", marker="D", mfc="w", mec="k", label="tip"),
        *ax_ws.get_legend_handles_labels()[0],
        Rectangle((0, 0), 1, 1, fc="0.9", ec="0.35", label="joint limits"),
    ]
    columns = len(handles) if len(handles) <= 7 else -(-len(handles) // 2)
    fig.legend(handles=handles, loc="outside lower center", ncols=columns, frameon=False)
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


def _nice_below(value: float) -> float:
    """The largest of 1, 2, 5 times a power of ten not above ``value`` (> 0)."""
    power = 10.0 ** np.floor(np.log10(value))
    return float(max(step * power for step in (1.0, 2.0, 5.0) if step * power <= value * 1.000001))


def _arrow_scale(positions: np.ndarray, errors: np.ndarray) -> float:
    """A round factor that draws the largest error at about a tenth of the points' spread."""
    spread = float(np.ptp(positions, axis=0).max()) if positions.shape[0] > 1 else 1.0
    largest = float(np.max(np.hypot(errors[:, 0], errors[:, 1]), initial=0.0))
    if largest <= 0 or spread <= 0:
        return 1.0
    return _nice_below(0.1 * spread / largest)


def _error_arrows(ax, positions: np.ndarray, errors: np.ndarray, name: str, colour: str) -> None:
    """One model's errors as arrows at one stated magnification, with a key arrow in mm.

    The arrows are the errors themselves (mm) drawn ``scale`` times longer: one
    quiver per axes, so that no two magnifications ever share one.
    """
    scale = _arrow_scale(positions, errors)
    ax.plot(positions[:, 0], positions[:, 1], ".", color="0.3", ms=3)
    arrows = ax.quiver(
        positions[:, 0],
        positions[:, 1],
        errors[:, 0],
        errors[:, 1],
        angles="xy",
        scale_units="xy",
        scale=1.0 / scale,
        width=0.005,
        color=colour,
        gid=name,
    )
    largest = float(np.max(np.hypot(errors[:, 0], errors[:, 1]), initial=0.0))
    key = _nice_below(largest) if largest > 0 else 1.0  # about as long as the longest arrow
    label = f"{key:g} mm"
    ax.quiverkey(arrows, 0.8, 1.03, key, label, labelpos="E", fontproperties={"size": 8})
    ax.set_title(f"{name}: errors ×{scale:g}", loc="left", fontsize="medium")


def _pose_of_rows(pose: Sequence[str] | np.ndarray | None, rows: int) -> np.ndarray:
    """Every row's pose ``(rows,)``, numbered from 0 in the order the poses first appear."""
    if pose is None:
        return np.arange(rows)
    labels = np.asarray(pose)
    if labels.shape != (rows,):
        raise ValueError(f"pose must give one label per row, shape ({rows},); got {labels.shape}")
    _, first, which = np.unique(labels, return_index=True, return_inverse=True)
    rank = np.empty(first.size, dtype=int)
    rank[np.argsort(first)] = np.arange(first.size)
    return rank[which.ravel()]


def _side_by_side(of_pose: np.ndarray) -> np.ndarray:
    """Every row's x ``(rows,)``: its pose's number (from 1), a pose's rows spread over +-0.3."""
    count = np.bincount(of_pose)
    order = np.argsort(of_pose, kind="stable")
    rank = np.empty(of_pose.size)
    rank[order] = np.arange(of_pose.size) - np.repeat(np.cumsum(count) - count, count)
    size = count[of_pose]
    return of_pose + 1.0 + np.where(size > 1, 0.6 * rank / np.maximum(size - 1, 1) - 0.3, 0.0)


def _error_ecdf(ax, before_mm: np.ndarray, after_mm: np.ndarray) -> None:
    """The held-out errors before and after as empirical distribution functions on one
    logarithmic scale: the fraction of points within each error."""
    for errors, colour, name in (
        (before_mm, "0.45", "nominal arm"),
        (after_mm, "tab:red", "calibrated"),
    ):
        ordered = np.sort(np.asarray(errors, dtype=float))
        share = np.arange(1, ordered.size + 1) / ordered.size
        ax.step(ordered, share, where="post", color=colour, label=name, gid=f"ecdf {name}")
    ax.set_xscale("log")
    ax.set_ylim(0.0, 1.0)
    ax.set_xlabel("position error [mm]")
    ax.set_ylabel("fraction of held-out points within")
    ax.legend(fontsize=8, frameon=False, loc="upper left")


def plot_validation(
    arm: PlanarArm,
    q: np.ndarray,
    result,
    *,
    pose: Sequence[str] | np.ndarray | None = None,
    title: str | None = None,
) -> Figure:
    """Error vectors in the instrument frame and every pose's error against its prediction.

    Parameters
    ----------
    arm : PlanarArm
    q : ndarray, shape (m, n)
        The held-out rows' joint angles (rad).
    result : armcal.validation.Validation
    pose : sequence of str, shape (m,), optional
        Every row's pose label, when a pose has several rows (one per target):
        the rows of a pose share it.  Default: every row is a pose.
    title : str, optional

    Returns
    -------
    matplotlib.figure.Figure
        Top: the measured positions in the instrument frame (for 3-D data, the
        plane of motion fitted in it) with the errors of the nominal arm
        registered on its own (left; the calibration's baseline) and of the
        calibrated one (right) as arrows, each panel at one
        stated magnification with a key arrow in mm.  Bottom: every row's
        error before and after, and the error the calibration predicts (RMS
        over a pose's rows), against the pose; a pose's rows side by side; and the
        errors before and after as distribution functions on one scale.  Rows that
        read no position in a plane (a touch of a plane, a seating, a distance) have
        the bottom panels alone.

    Raises
    ------
    ValueError
        If ``pose`` does not give one label per row.
    """
    positions = result.positions
    rows = positions.shape[0]
    of_pose = _pose_of_rows(pose, rows)
    placed = positions.shape[1] >= 2 and not arm.touches  # positions to draw arrows at
    fig = Figure(figsize=(11, 8.4 if placed else 4.2), layout="constrained")
    grid = fig.add_gridspec(2, 6, height_ratios=[1.25, 1.0]) if placed else fig.add_gridspec(1, 6)
    if placed:  # the axes in the order they always had: arrows, distribution, errors
        _placed_errors(fig, grid, positions, result)
    low = 1 if placed else 0
    _error_ecdf(fig.add_subplot(grid[low, 4:]), result.before_mm, result.after_mm)
    ax_err = fig.add_subplot(grid[low, :4])
    x = _side_by_side(of_pose)
    ax_err.semilogy(
        x, result.before_mm, "o", color="0.45", ms=3, label="nominal arm (registered on its own)"
    )
    ax_err.semilogy(x, result.after_mm, "o", color="tab:red", ms=3, label="calibrated")
    count = np.bincount(of_pose)
    predicted = np.sqrt(np.bincount(of_pose, result.predicted_mm**2) / count)
    number = np.arange(1, count.size + 1)
    label = "predicted (RMS per point)"
    ax_err.semilogy(number, predicted, "-", color="k", lw=1, label=label, gid="predicted")
    ax_err.xaxis.set_major_locator(MaxNLocator(integer=True))
    several = count.size < rows
    ax_err.set_xlabel("held-out pose" + (" (its points side by side)" if several else ""))
    ax_err.set_ylabel("position error [mm]")
    ax_err.legend(fontsize=8, frameon=False, ncols=3, loc="lower left", bbox_to_anchor=(0, 1))
    points = f" ({rows} points)" if several else ""
    default = f"{arm.name}: validation on {count.size} held-out poses{points}"
    fig.suptitle(title if title is not None else default)
    return fig


def _placed_errors(fig: Figure, grid, positions: np.ndarray, result) -> None:
    """The top panels of :func:`plot_validation`: the errors as arrows where they were."""
    ax_before = fig.add_subplot(grid[0, :3])
    ax_after = fig.add_subplot(grid[0, 3:], sharex=ax_before, sharey=ax_before)
    x_name, y_name, frame = ("x", "y", "instrument frame")
    if result.out_of_plane_mm is not None:  # 3-D data: the plane fitted in the instrument frame
        x_name, y_name, frame = ("u", "v", "instrument's plane of motion")
    _error_arrows(ax_before, positions, result.before, "nominal arm", "0.45")
    _error_arrows(ax_after, positions, result.after, "calibrated", "tab:red")
    lo, hi = positions.min(axis=0), positions.max(axis=0)
    pad = 0.12 * max(float(np.max(hi - lo)), 1.0)  # the longest arrow is a tenth of the spread
    ax_before.set(xlim=(lo[0] - pad, hi[0] + pad), ylim=(lo[1] - pad, hi[1] + pad))
    for ax in (ax_before, ax_after):
        ax.set_aspect("equal", adjustable="box")
        ax.set_xlabel(f"{x_name} in {frame} [mm]")
    ax_before.set_ylabel(f"{y_name} in {frame} [mm]")


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

    ``positions`` ``(k, 2)`` are the tips of the poses ``q`` in the base frame
    (mm); the errors ``(k,)`` colour them on one shared logarithmic scale.
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
        ax.set_xlabel(f"x in {BASE_FRAME} [mm]")
    axes[0].set_ylabel(f"y in {BASE_FRAME} [mm]")
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
    kind = FIGURE_FORMATS.get(os.path.splitext(os.fspath(path))[1].lower(), "png")
    atomic_write(path, lambda handle: _render(fig, handle, kind, dpi=120))


def figure_png(fig: Figure) -> bytes:
    """``fig`` as PNG bytes at 100 dpi (for a page that embeds it)."""
    buffer = io.BytesIO()
    _render(fig, buffer, "png", dpi=100)
    return buffer.getvalue()


def _render(fig: Figure, handle: BinaryIO, kind: str, *, dpi: int) -> None:
    """``fig`` written to ``handle`` as ``kind`` through the Agg canvas (never a GUI
    backend)."""
    FigureCanvasAgg(fig)
    fig.savefig(handle, format=kind, dpi=dpi)


def planar_plan_figure(robot: Any, run: Any, *, seed: int = 0) -> Figure:
    """A designed plan (a :class:`~armcal.workflow.DesignRun`) of a planar robot (a
    :class:`~armcal.families.RobotSpec`) in the workspace and in joint space, with its
    payloads and gravity (:mod:`armcal.families`, role ``plan_figure``)."""
    gravity = None if robot.elastic is None else robot.elastic.gravity
    return plot_plan(robot.arm, run.q, payload_kg=run.payload_kg, gravity=gravity)
