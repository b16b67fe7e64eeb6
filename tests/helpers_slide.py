"""A five-joint arm whose fourth joint is a slide, written out independently of armcal:
its robot TOML (a modified DH table, Craig's convention), a true arm's file, its points
from the table (homogeneous transforms multiplied out), and random readings."""

from __future__ import annotations

import json
import math

import numpy as np

#: A five-joint arm whose fourth joint is a slide (modified DH, Craig's convention).
ALPHA_DEG = [0.0, -90.0, 0.0, 90.0, -90.0]
A_MM = [0.0, 150.0, 600.0, 50.0, 0.0]
THETA_DEG = [0.0, -90.0, 0.0, 0.0, 0.0]
D_MM = [0.0, 0.0, 0.0, 300.0, 0.0]
KINDS = ["R", "R", "R", "P", "R"]
TIP_MM = [0.0, 0.0, 100.0]
LIMITS = [[-170, 170], [-90, 90], [-120, 120], [0, 400], [-120, 120]]  # deg, mm for joint 4

SLIDE_TOML = f"""name = "rrp-arm"
joint_limits_deg = {LIMITS}
[mdh]
alpha_deg = {ALPHA_DEG}
a_mm = {A_MM}
theta_deg = {THETA_DEG}
d_mm = {D_MM}
joint_types = {json.dumps(KINDS)}
tip_xyz_mm = {TIP_MM}
"""

#: The true arm: errors of a revolute joint's placement and zero and of the slide's
#: zero (mm) and axis (deg), and a tracker placed away from the base.
SLIDE_TRUTH = """base = { xyz_mm = [2000.0, -500.0, -300.0], rpy_deg = [0.2, -0.1, 30.0] }
[errors]
"j3.x" = 0.3
"j4.rx" = 0.02
"dq2" = 0.03
"dq4" = 0.5
"""


def _rx(a: float) -> np.ndarray:
    c, s = math.cos(a), math.sin(a)
    return np.array([[1, 0, 0, 0], [0, c, -s, 0], [0, s, c, 0], [0, 0, 0, 1.0]])


def _rz(a: float) -> np.ndarray:
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, -s, 0, 0], [s, c, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1.0]])


def _shift(x: float, y: float, z: float) -> np.ndarray:
    out = np.eye(4)
    out[:3, 3] = x, y, z
    return out


def _small(e: np.ndarray) -> np.ndarray:
    """A shift ``e[:3]`` (mm) and turns ``e[3:]`` (mrad, about x, y, z)."""
    out = _shift(*e[:3])
    rx, ry, rz = e[3:] / 1000.0
    cy, sy = math.cos(ry), math.sin(ry)
    turn_y = np.array([[cy, 0, sy, 0], [0, 1, 0, 0], [-sy, 0, cy, 0], [0, 0, 0, 1.0]])
    return out @ _rz(rz) @ turn_y @ _rx(rx)


def slide_points(q: np.ndarray, errors: np.ndarray | None = None) -> np.ndarray:
    """Points ``(m, 3)`` (mm) of the slide arm at readings ``q`` (deg; mm for joint 4),
    written out from the modified DH table: ``Rx(alpha) Tx(a) Rz(theta) Tz(d)`` per row,
    the reading added to ``theta`` (revolute) or ``d`` (the slide).

    ``errors`` (an over-complete set, independent of armcal's): a base pose (6), each
    joint's placement after its row (6 each), each joint's zero (deg; mm) and the tool
    point in the tip frame (3), as :func:`_small` reads them.
    """
    n, m = len(KINDS), q.shape[0]
    e = np.zeros(6 + 7 * n + 3) if errors is None else errors
    frame = np.broadcast_to(_small(e[:6]), (m, 4, 4))
    for j in range(n):
        reading = q[:, j] + e[6 + 6 * n + j]
        fixed = _rx(math.radians(ALPHA_DEG[j])) @ _shift(A_MM[j], 0, 0)
        fixed = fixed @ _small(e[6 + 6 * j : 12 + 6 * j])
        theta = np.radians(THETA_DEG[j] + (reading if KINDS[j] == "R" else 0.0))
        d = D_MM[j] + (reading if KINDS[j] == "P" else 0.0) * np.ones(m)
        motion = np.zeros((m, 4, 4))  # Rz(theta) Tz(d), pose by pose
        motion[:, 0, 0] = motion[:, 1, 1] = np.cos(theta)
        motion[:, 1, 0] = np.sin(theta)
        motion[:, 0, 1] = -np.sin(theta)
        motion[:, 2, 2] = motion[:, 3, 3] = 1.0
        motion[:, 2, 3] = d
        frame = frame @ fixed @ motion
    tool = np.array([*TIP_MM, 0.0]) + np.append(e[-3:], 1.0)
    return (frame @ tool)[:, :3]


def slide_plan(m: int, seed: int) -> np.ndarray:
    """``m`` readings uniform within the limits (deg; mm), seeded."""
    rng = np.random.default_rng(seed)
    low, high = np.array(LIMITS, dtype=float).T
    return rng.uniform(low, high, (m, len(KINDS)))
