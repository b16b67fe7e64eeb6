"""Spatial arms for the tests, built through armcal's chain: an industrial 6R with
coupled J2/J3, a cobot, a 7R and a SCARA-like arm with a slide; their targets, random
truths and poses; and a random plan file of a built-in robot.

The nominal geometries are the published ones the built-in robot files cite.
"""

from __future__ import annotations

import numpy as np

from armcal.doe import random_plan
from armcal.files import load_spatial_robot
from armcal.models import SerialChain, SpatialArm

DEG = np.pi / 180


def industrial() -> SpatialArm:
    """A 6R arm with parallel J2/J3 and a spherical wrist; J3 read relative to the horizon."""
    chain = SerialChain.from_mdh(
        np.radians([0, -90, 180, -90, 90, -90]),
        [0, 312, 1075, 225, 0, 0],
        np.radians([0, -90, 0, 0, 0, 0]),
        [0, 0, 0, -1280, 0, -215],
    )
    coupled = np.eye(6)
    coupled[2, 1] = 1.0
    return SpatialArm(chain, "industrial", coupled)


def cobot() -> SpatialArm:
    """A 6R arm with three parallel axes (2, 3, 4), as a UR5e."""
    chain = SerialChain.from_mdh(
        np.radians([0, 90, 0, 0, 90, -90]),
        [0, 0, -425, -392.2, 0, 0],
        np.zeros(6),
        [162.5, 0, 0, 133.3, 99.7, 99.6],
    )
    return SpatialArm(chain, "cobot")


def seven() -> SpatialArm:
    """A 7R arm, as a Panda."""
    chain = SerialChain.from_mdh(
        np.radians([0, -90, 90, 90, -90, 90, 90]),
        [0, 0, 0, 82.5, -82.5, 0, 88],
        np.zeros(7),
        [333, 0, 316, 0, 384, 0, 0],
    )
    return SpatialArm(chain, "seven")


def with_slide() -> SpatialArm:
    """A 4-joint arm with a prismatic third joint (a SCARA-like RRPR)."""
    chain = SerialChain.from_mdh(
        [0, 0, 0, 0], [0, 350, 300, 0], [0, 0, 0, 0], [400, 0, 0, 0], ("R", "R", "P", "R")
    )
    return SpatialArm(chain, "scara")


ARMS = {"industrial": industrial, "cobot": cobot, "seven": seven, "scara": with_slide}


def labelled(arm: SpatialArm, k: int) -> SpatialArm:
    """``arm`` with ``k`` targets labelled A, B, C, placed by the data."""
    return arm.replace(targets=tuple("ABC"[:k]), target_positions=np.zeros((0, 3)))


def random_truth(arm: SpatialArm, rng: np.random.Generator) -> np.ndarray:
    """Every joint's placement and zero off by a few tenths of a mm or degree; the
    instrument 4 m away, turned by 120 degrees; targets 100-200 mm from the flange."""
    lay = arm.layout
    truth = arm.nominal.copy()
    errors = slice(6, lay.target_start)
    truth[errors] = rng.normal(size=lay.target_start - 6) * np.where(
        lay.angles[errors], 0.2 * DEG, 0.5
    )
    truth[:6] = [4000 * np.cos(0.4), 4000 * np.sin(0.4), -600, 0.01, -0.02, 120 * DEG]
    k = len(arm.targets)
    truth[lay.target_start :] = (rng.uniform(-100, 100, (k, 3)) + np.array([0, 0, 150])).ravel()
    return truth


def random_poses(arm: SpatialArm, m: int, rng: np.random.Generator) -> np.ndarray:
    """``m`` readings ``(m, n)`` uniform over at most 2.4 rad (200 mm) of each joint's range."""
    lo, hi = arm.limits[:, 0], arm.limits[:, 1]
    span = np.minimum(hi - lo, np.where(arm.chain.revolute, 2.4, 200.0))
    middle = np.clip(0.0, lo + span / 2, hi - span / 2)
    return middle + (rng.uniform(size=(m, arm.n_joints)) - 0.5) * span


def plan_file(tmp_path, robot, m=30, seed=1, name="plan.csv"):
    """A random plan of ``m`` poses within the robot's limits, written to ``name``."""
    arm = load_spatial_robot(robot).arm
    q = random_plan(arm, m, rng=seed)
    head = ",".join(f"q{k + 1}_deg" for k in range(arm.n_joints))
    rows = [",".join(repr(float(v)) for v in np.degrees(row)) for row in q]
    (tmp_path / name).write_text("\n".join([head, *rows]) + "\n", encoding="utf-8")
    return arm, q
