"""The picture of an ISO 9283 acceptance test: every pose's accuracy and repeatability.

Imported only when a picture is asked for (matplotlib is slow to import), like
:mod:`armcal.plotting`, whose :func:`~armcal.plotting.save_figure` writes it.
"""

from __future__ import annotations

import numpy as np
from matplotlib.figure import Figure
from matplotlib.layout_engine import ConstrainedLayoutEngine

from .acceptance import PoseCharacteristics

__all__ = ["plot_acceptance"]


def plot_acceptance(found: PoseCharacteristics) -> Figure:
    """Three panels on linear axes: every pose's pose accuracy ``AP_P`` of the nominal arm
    and of the calibrated model; the calibrated model's ``AP_P`` beside the repeatability
    ``RP_l`` on their own scale (after calibration they are of one size, and a linear axis
    shows by how much one exceeds the other); and the components of ``AP`` after
    calibration in the robot's base frame (:attr:`PoseCharacteristics.accuracy_after_robot`),
    whose signs show a systematic error the model misses."""
    fig = Figure(figsize=(12.0, 4.2), layout=ConstrainedLayoutEngine())
    before_ax, after_ax, parts = fig.subplots(1, 3, gridspec_kw={"width_ratios": [3, 3, 2]})
    names = found.names
    x = np.arange(len(names))
    turn = 45 if len(names) > 8 else 0
    width = 0.38
    before_ax.bar(
        x - width / 2, found.accuracy_before_mm, width, color="C3",
        label="AP, nominal arm (registered on its own)",
    )  # fmt: skip
    before_ax.bar(
        x + width / 2, found.accuracy_after_mm, width, color="C0", label="AP, calibrated"
    )
    before_ax.set_title(f"ISO 9283 pose accuracy, {int(found.cycles.min())} cycles or more")
    after_ax.bar(x - width / 2, found.accuracy_after_mm, width, color="C0", label="AP, calibrated")
    after_ax.bar(x + width / 2, found.repeatability_mm, width, color="C2", label="RP")
    after_ax.set_title("after calibration: accuracy and repeatability")
    for ax in (before_ax, after_ax):
        ax.set_xticks(x, names, rotation=turn, ha="right" if turn else "center")
        ax.set_ylabel("mm")
        ax.set_ylim(bottom=0.0)
        ax.legend(fontsize="small", loc="upper right")
    d = found.accuracy_after.shape[-1]
    robot = found.accuracy_after_robot
    frame = "robot base frame" if found.robot_turn is not None else "instrument frame"
    for axis, colour in zip(range(d), ("C0", "C1", "C2"), strict=False):
        parts.plot(x, robot[:, axis], "o-", color=colour, label=f"AP_{'xyz'[axis]}")
    parts.axhline(0.0, color="0.6", lw=0.8)
    parts.set_xticks(x, names, rotation=turn, ha="right" if turn else "center")
    parts.set_ylabel(f"mm ({frame})")
    parts.set_title("AP components after calibration")
    parts.legend(fontsize="small", ncols=3, loc="upper right")
    return fig
