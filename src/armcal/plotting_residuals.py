"""Pictures of a fit's residuals, for every family: every pose's residual per target in
the model's own dimensions, and every row's against each joint's reading
(:func:`residual_figure`, the families' ``residual_figure`` role; ``armcal identify
--plot``).

Imported only when a picture is asked for (matplotlib is slow to import), like
:mod:`armcal.plotting`, whose :func:`~armcal.plotting.save_figure` writes them.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
from matplotlib.figure import Figure
from matplotlib.ticker import MaxNLocator

__all__ = [
    "clean_limit",
    "plot_residuals",
    "plot_residuals_by_joint",
    "residual_figure",
]


def clean_limit(sigma: float, dim: int, level: float = 0.99) -> float:
    """The Euclidean length (mm) below which a clean point's residual lies with probability
    ``level``: ``sigma sqrt(chi2_dim(level))`` for ``dim`` coordinates of iid noise ``sigma``
    (``sigma sqrt(-2 ln(1 - level))`` in the plane)."""
    from scipy.stats import chi2

    return float(sigma * np.sqrt(chi2.ppf(level, dim)))


def _pose_numbers(labels: Sequence[str] | None, q: np.ndarray) -> np.ndarray:
    """Every row's pose ``(m,)``, numbered from 1 in the order poses first appear: by the
    rows' ``pose`` labels where they group rows, else by equal joint readings (the rows of
    a pose measured at several targets)."""
    keys: Sequence[object] = (
        labels
        if labels is not None and len(set(labels)) < len(labels)
        else [tuple(row) for row in np.asarray(q).tolist()]
    )
    first: dict[object, int] = {}
    return np.array([first.setdefault(key, len(first) + 1) for key in keys])


def plot_residuals(
    residuals: np.ndarray,
    sigma: float,
    *,
    used: np.ndarray | None = None,
    title: str | None = None,
    pose: np.ndarray | None = None,
    target: np.ndarray | None = None,
    target_names: Sequence[str] = (),
    ax: Any = None,
) -> Figure:
    """Every pose's residual (Euclidean, mm) of a fit, one bar per target, with the noise
    level.

    Parameters
    ----------
    residuals : ndarray, shape (m, d)
        Measured minus fitted positions of every row, mm (``d`` = 2 in the plane, 3 in
        space): a bar is the length of a row's ``d``-vector.
    sigma : float
        The instrument noise (1 std per coordinate, mm): a clean row's residual is
        below :func:`clean_limit` (for ``d`` coordinates) with probability 0.99.
    used : ndarray of bool, shape (m,), optional
        Rows in the fit; the others (outliers left out) are drawn as crosses.
    pose : ndarray of int, shape (m,), optional
        Every row's pose, numbered from 1 (default: a pose per row); a pose's targets
        stand side by side above its number.
    target : ndarray of int, shape (m,), optional
        The target every row measures, for one colour per target (``target_names``).
    ax : Axes, optional
        Draw into these axes (of a larger figure) instead of a new figure.
    """
    residuals = np.asarray(residuals, dtype=float)
    if ax is None:
        fig = Figure(figsize=(8, 3.6), layout="constrained")
        ax = fig.subplots()
    fig = ax.figure
    distance = np.linalg.norm(residuals, axis=1)
    rows = distance.size
    pose = np.arange(1, rows + 1) if pose is None else np.asarray(pose)
    kept = np.ones(rows, dtype=bool) if used is None else np.asarray(used, dtype=bool)
    groups = np.zeros(rows, dtype=int) if target is None else np.asarray(target)
    count = max(int(groups.max(initial=0)) + 1, 1)
    width = 0.8 / count
    x = pose + (groups - (count - 1) / 2) * width
    several = target is not None and len(target_names) > 1
    for k in np.unique(groups):
        mine = kept & (groups == k)
        label = f"target {target_names[k]}" if several else "in the fit"
        ax.bar(x[mine], distance[mine], color=f"C{k}", width=width, label=label)
    if not kept.all():
        ax.plot(
            x[~kept],
            distance[~kept],
            "x",
            color="tab:red",
            ms=8,
            mew=2,
            label="left out (outlier)",
        )
    dim = residuals.shape[1]
    what = "rows" if several else "poses"
    ax.axhline(
        clean_limit(sigma, dim), color="k", lw=1, ls="--",
        label=f"99 % of clean {what} below ({dim}-D)",
    )  # fmt: skip
    ax.set_yscale("log")
    ax.xaxis.set_major_locator(MaxNLocator(integer=True))
    ax.set_xlabel("pose")
    ax.set_ylabel(f"{dim}-D residual [mm]")
    ax.legend(fontsize=8, frameon=False)
    ax.set_title(title if title is not None else "residual of every pose")
    return fig


def plot_residuals_by_joint(
    residuals: np.ndarray,
    q_deg: np.ndarray,
    sigma: float,
    *,
    joint_names: Sequence[str],
    units: Sequence[str],
    used: np.ndarray | None = None,
    axes: Sequence[Any] | None = None,
) -> Figure:
    """Every row's residual (Euclidean, mm) against each joint's reading, one panel per
    joint: a trend over one joint (a residual growing with its angle) shows an effect
    the model lacks at a glance; the noise level is drawn as in :func:`plot_residuals`.

    ``q_deg`` ``(m, n)`` are the readings in each joint's display unit (``units``: deg,
    or mm for a slide).
    """
    residuals = np.asarray(residuals, dtype=float)
    q_deg = np.asarray(q_deg, dtype=float)
    n = q_deg.shape[1]
    if axes is None:
        fig = Figure(figsize=(min(3.0 * n, 15.0), 2.8), layout="constrained")
        axes = [fig.add_subplot(1, n, 1)]
        axes += [fig.add_subplot(1, n, j + 1, sharey=axes[0]) for j in range(1, n)]
    fig = axes[0].figure
    distance = np.linalg.norm(residuals, axis=1)
    kept = np.ones(distance.size, dtype=bool) if used is None else np.asarray(used, dtype=bool)
    limit = clean_limit(sigma, residuals.shape[1])
    for j, ax in enumerate(axes):
        ax.plot(q_deg[kept, j], distance[kept], ".", color="tab:blue", ms=4)
        if not kept.all():
            ax.plot(q_deg[~kept, j], distance[~kept], "x", color="tab:red", ms=6)
        ax.axhline(limit, color="k", lw=1, ls="--")
        ax.set_yscale("log")
        ax.set_xlabel(f"{joint_names[j]} [{units[j]}]")
    axes[0].set_ylabel("residual [mm]")
    return fig


def residual_figure(cal: Any) -> Figure:
    """A fit's residuals (a :class:`~armcal.identification.Calibration` of any family): on
    top every pose's residual in the model's dimensions, one bar per target; below, every
    row's residual against each joint's reading (:mod:`armcal.families`, role
    ``residual_figure``; ``armcal identify --plot``)."""
    model = cal.model
    dim = model.position_dim
    conditions = cal.conditions
    target = None if conditions is None else conditions.target
    names = tuple(model.target_labels)
    rows = cal.residuals.shape[0]
    labels = cal.pose_labels if len(cal.pose_labels) == rows else None
    q = np.arange(rows)[:, None] if conditions is None else conditions.q
    fig = Figure(figsize=(max(8.0, 2.4 * model.n_joints), 6.4), layout="constrained")
    grid = fig.add_gridspec(2, model.n_joints)
    top = fig.add_subplot(grid[0, :])
    plot_residuals(
        cal.residuals[:, :dim], cal.sigma_mm, used=cal.used, pose=_pose_numbers(labels, q),
        target=target, target_names=names, ax=top,
    )  # fmt: skip
    if conditions is not None:
        bottom = [fig.add_subplot(grid[1, 0])]
        bottom += [fig.add_subplot(grid[1, j], sharey=bottom[0]) for j in range(1, model.n_joints)]
        slides = np.array([kind == "P" for kind in model.joint_kinds])
        shown = np.where(slides, np.asarray(conditions.q), np.degrees(conditions.q))
        plot_residuals_by_joint(
            cal.residuals[:, :dim], shown, cal.sigma_mm, joint_names=model.joint_names,
            units=["mm" if s else "deg" for s in slides], used=cal.used, axes=bottom,
        )  # fmt: skip
    return fig
