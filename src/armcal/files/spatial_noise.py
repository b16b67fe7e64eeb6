"""The ``[measurement]`` table of a spatial robot file: the instrument's noise.

Isotropic (``sigma_mm``), per axis (``[sx, sy, sz]``), a covariance
(``covariance_mm2``) or a laser tracker's range and transverse terms
(``[measurement.tracker]``), and a 6-DoF instrument's orientation noise
(``orientation_sigma_deg``), each checked against the range of real instruments
so that a wrong unit is an error, not a calibration.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from ..errors import unrendered
from ..formats import SPATIAL_KEYS, allowed_keys
from ..noise import NoiseModel, TrackerNoise
from .common import check_keys, fail, number, number_within, numbers
from .robots import SIGMA_RANGE_MM

__all__ = [
    "ORIENTATION_SIGMA_RANGE_DEG",
    "SIGMA_RANGE_PX",
    "TRACKER_KEYS",
    "read_spatial_noise",
]

#: The four terms of a laser tracker's noise, in the order of :class:`TrackerNoise`.
TRACKER_KEYS = ("range_mm", "range_mm_per_m", "transverse_mm", "transverse_mm_per_m")

#: A camera's noise (px, 1 std) outside this range is a wrong unit: a board's corners are
#: found to 0.05-1 px.
SIGMA_RANGE_PX = (1e-3, 20.0)

#: A 6-DoF instrument's orientation noise (deg, 1 std) outside this range is a wrong unit:
#: the probes on trackers and the optical trackers state 0.001-0.1 deg.
ORIENTATION_SIGMA_RANGE_DEG = (1e-5, 5.0)


def read_spatial_noise(path: Path, table: Any) -> NoiseModel | None:
    """``[measurement]``: the instrument's noise, and a 6-DoF instrument's orientation noise."""
    if table is None:
        return None
    if not isinstance(table, dict):
        raise fail(path, "key 'measurement': expected a table [measurement]")
    check_keys(path, table, allowed_keys("measurement", SPATIAL_KEYS), "measurement.")
    noise = _position_noise(path, table)
    if "orientation_sigma_deg" not in table:
        return noise
    value = number_within(
        path,
        table["orientation_sigma_deg"],
        "measurement.orientation_sigma_deg",
        ORIENTATION_SIGMA_RANGE_DEG,
        "deg",
    )
    if noise is None:
        raise fail(
            path,
            "key 'measurement.orientation_sigma_deg': give the instrument's position noise "
            "too (sigma_mm, covariance_mm2 or tracker)",
        )
    return noise.with_orientation(np.radians(value))


def _position_noise(path: Path, table: dict) -> NoiseModel | None:
    """The instrument's position noise of ``[measurement]``, if it gives one."""
    given = [key for key in ("sigma_mm", "covariance_mm2", "tracker", "sigma_px") if key in table]
    if len(given) > 1:
        raise fail(
            path,
            f"keys {' and '.join(f'measurement.{k}' for k in given)} all give the instrument's "
            "noise; keep one",
        )
    if "tracker" in table:
        return NoiseModel.laser_tracker(_tracker(path, table["tracker"]))
    if "sigma_px" in table:  # a camera's, in its readings' unit
        sigma = number_within(
            path, table["sigma_px"], "measurement.sigma_px", SIGMA_RANGE_PX, "px"
        )
        return NoiseModel.isotropic(sigma, dim=3)
    if "sigma_mm" in table:
        raw = table["sigma_mm"]
        values = (
            numbers(path, raw, "measurement.sigma_mm", 3)
            if isinstance(raw, list)
            else [number(path, raw, "measurement.sigma_mm")] * 3
        )
        low, high = SIGMA_RANGE_MM
        if not all(low <= v <= high for v in values):
            raise fail(
                path,
                f"key 'measurement.sigma_mm': must be between {low:g} and {high:g} mm; check "
                "the unit (mm)",
            )
        return NoiseModel(np.diag(np.square(values)))
    if "covariance_mm2" in table:
        raw = table["covariance_mm2"]
        if not isinstance(raw, list) or len(raw) != 3:
            raise fail(path, "key 'measurement.covariance_mm2': expected a 3 x 3 matrix in mm^2")
        cov = np.array(
            [numbers(path, r, f"measurement.covariance_mm2[{i}]", 3) for i, r in enumerate(raw)]
        )
        try:
            return NoiseModel(cov)
        except ValueError as exc:
            raise fail(path, f"key 'measurement.covariance_mm2': {unrendered(exc)}") from None
    return None


def _tracker(path: Path, table: Any) -> TrackerNoise:
    """``[measurement.tracker]``: the four terms of a laser tracker's noise (1 std)."""
    keys = list(TRACKER_KEYS)
    if not isinstance(table, dict):
        raise fail(
            path,
            "key 'measurement.tracker': expected a table { range_mm = a, range_mm_per_m = b, "
            "transverse_mm = c, transverse_mm_per_m = d } (1 std: a + b per metre of distance)",
        )
    check_keys(path, table, keys, "measurement.tracker.")
    missing = [k for k in keys if k not in table]
    if missing:
        raise fail(
            path,
            f"key 'measurement.tracker': missing {', '.join(missing)} (1 std in mm and mm per "
            "metre of distance; 0 for a term the data sheet does not give)",
        )
    values = [number(path, table[k], f"measurement.tracker.{k}") for k in keys]
    low, high = SIGMA_RANGE_MM
    for key, value in zip(keys, values, strict=True):
        if not (0 <= value <= high) or (value < low and not key.endswith("_per_m")):
            bounds = (
                f"between {low:g} and {high:g}"
                if not key.endswith("_per_m")
                else f"in [0, {high:g}]"
            )
            raise fail(
                path,
                f"key 'measurement.tracker.{key}': must be {bounds} mm; check the unit "
                "(mm, 1 std; data sheets often quote 2 std)",
            )
    return TrackerNoise(*values)
