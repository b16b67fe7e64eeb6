"""Valid input files of the default robot, paper-4link: a 20-pose plan and its
measurements (the paper's deviated arm, eq. 1, with a small deterministic noise), from
which the error tests spoil one field at a time."""

from __future__ import annotations

import math

from helpers import deviated_tip

#: Joint columns of the default robot, paper-4link (4 joints, ±180 deg, 8 parameters).
JOINTS = ("q1_deg", "q2_deg", "q3_deg", "q4_deg")
PLAN_HEADER = ",".join(JOINTS)
MEAS_HEADER = ",".join((*JOINTS, "x_mm", "y_mm"))

#: The paper's lengths and deviations, used to make measurements that identify cleanly.
LINKS_MM = (260.0, 180.0, 120.0, 100.0)
DL_MM = (1.5, -0.6, -0.4, 0.7)
DQ_DEG = (0.5, -0.5, 0.7, -0.3)


def _wrap(deg: float) -> float:
    """An angle (deg) below 360 wrapped into (-180, 180]."""
    return deg - 360.0 if deg > 180.0 else deg


#: A valid 20-pose plan: q1 = 0, q2 = q3 = q4 = 18 k deg (k = 0..19), wrapped to ±180.
POSES = [(0.0, a, a, a) for a in (_wrap(18.0 * k) for k in range(20))]


def exact_position(q_deg: tuple[float, ...]) -> tuple[float, float]:
    """Position of the deviated arm (paper eq. 1, written out independently)."""
    return deviated_tip(q_deg, LINKS_MM, DL_MM, DQ_DEG)


def noisy_position(q_deg: tuple[float, ...], k: int) -> tuple[float, float]:
    """Position of the deviated arm plus a deterministic ~0.1 mm 'noise'."""
    x, y = exact_position(q_deg)
    return x + 0.1 * math.sin(3.7 * k), y + 0.1 * math.cos(2.3 * k)


PLAN_ROWS = [",".join(f"{v:g}" for v in pose) for pose in POSES]
MEAS_ROWS = [
    ",".join([*(f"{v:g}" for v in pose), *(repr(v) for v in noisy_position(pose, k))])
    for k, pose in enumerate(POSES)
]


def csv_file(header: str, rows: list[str]) -> str:
    """A CSV file's text: the header line, then the rows, each line ended."""
    return "\n".join([header, *rows]) + "\n"


VALID_PLAN = csv_file(PLAN_HEADER, PLAN_ROWS)
VALID_MEAS = csv_file(MEAS_HEADER, MEAS_ROWS)
