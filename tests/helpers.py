"""Helpers shared by the tests: random arms and deviations, and the program in a subprocess."""

import math
import subprocess
import sys
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from armcal import PlanarArm


def random_arm(
    n: int, rng: np.random.Generator, *, base_offset: bool = False, limits_deg: float = 180.0
) -> PlanarArm:
    """An n-link arm with link lengths in [50, 300] mm and symmetric joint limits."""
    lengths = rng.uniform(50.0, 300.0, n)
    limits = np.radians(np.tile([-limits_deg, limits_deg], (n, 1)))
    return PlanarArm(lengths, limits, base_offset=base_offset, name=f"random-{n}link")


def random_truth(arm: PlanarArm, rng: np.random.Generator) -> np.ndarray:
    """Deviations of a few mm and about a degree, as PRODUCT.md describes real arms."""
    n = arm.n_joints
    dl = rng.uniform(-3.0, 3.0, n)
    dq = rng.uniform(-1.0, 1.0, n)
    base = rng.uniform(-20.0, 20.0, 2) if arm.base_offset else None
    return arm.params_from_display(dl, dq, base)


def run_cli(cwd: Path, *args: str, timeout: float = 120) -> subprocess.CompletedProcess[str]:
    """Run ``python -m armcal *args`` in the folder ``cwd``, capturing stdout and stderr."""
    return subprocess.run(
        [sys.executable, "-m", "armcal", *args],
        cwd=cwd,
        capture_output=True,
        text=True,
        encoding="utf-8",
        timeout=timeout,
        check=False,
    )


def deviated_tip(
    q_deg: Sequence[float], links: Sequence[float], dl: Sequence[float], dq: Sequence[float]
) -> tuple[float, float]:
    """Paper eq. (1), written out link by link independently of armcal: the tip (mm)."""
    x = y = angle = 0.0
    for length, d_length, q, d_q in zip(links, dl, q_deg, dq, strict=True):
        angle += math.radians(q + d_q)
        x += (length + d_length) * math.cos(angle)
        y += (length + d_length) * math.sin(angle)
    return x, y
