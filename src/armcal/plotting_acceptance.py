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
    """Two panels: every pose's pose accuracy ``AP_P`` against the nominal and the
    calibrated model, with its repeatability ``RP_l`` (mm, log scale: before and after
    calibration differ by orders of magnitude); and the components ``AP_x, AP_y, AP_z``
    after calibration, whose signs show a systematic error the model misses."""
    fig = Figure(figsize=(10.0, 4.2), layout=ConstrainedLayoutEngine())
    left, right = fig.subplots(1, 2, gridspec_kw={"width_ratios": [3, 2]})
    names = found.names
    x = np.arange(len(names))
    width = 0.27
    left.bar(
        x - width,
        found.accuracy_before_mm,
        width,
        label="AP, nominal arm (registered on its own)",
        color="C3",
    )
    left.bar(x, found.accuracy_after_mm, width, label="AP, calibrated model", color="C0")
    left.bar(x + width, found.repeatability_mm, width, label="RP", color="C2")
    left.set_yscale("log")
    left.set_xticks(x, names, rotation=45 if len(names) > 8 else 0, ha="right")
    left.set_ylabel("mm")
    left.set_title(f"ISO 9283, {int(found.cycles.min())} cycles or more per pose")
    left.legend(fontsize="small", ncols=3, loc="lower center", bbox_to_anchor=(0.5, 1.08))
    d = found.accuracy_after.shape[-1]
    for axis, colour in zip(range(d), ("C0", "C1", "C2"), strict=False):
        right.plot(x, found.accuracy_after[:, axis], "o-", color=colour, label=f"AP_{'xyz'[axis]}")
    right.axhline(0.0, color="0.6", lw=0.8)
    right.set_xticks(x, names, rotation=45 if len(names) > 8 else 0, ha="right")
    right.set_ylabel("mm (instrument frame)")
    right.set_title("AP components after calibration")
    right.legend(fontsize="small", ncols=3, loc="lower center", bbox_to_anchor=(0.5, 1.08))
    return fig
