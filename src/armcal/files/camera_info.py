"""A camera's intrinsics from its ROS/OpenCV ``camera_info`` file, YAML or JSON.

The fields (PRODUCT.md, "Instruments"): ``image_width``, ``image_height``,
``camera_matrix {rows: 3, cols: 3, data: [fx, s, cx, 0, fy, cy, 0, 0, 1]}``,
``distortion_model: plumb_bob`` and ``distortion_coefficients {rows: 1, cols: 5,
data: [k1, k2, p1, p2, k3]}``, as ``camera_calibration`` writes them; other fields
(``camera_name``, ``rectification_matrix``, ``projection_matrix``) are ignored.
YAML is read by PyYAML (a YAML reader's grammar, flow and block lists, comments and
quoting, is not worth writing again); a file whose text starts with ``{`` is JSON.
"""

from __future__ import annotations

import json
import os
from typing import Any

import numpy as np

from ..instruments.camera import Intrinsics
from .common import fail, read_text

__all__ = ["camera_info_table", "intrinsics_of", "read_camera_info"]

_EXAMPLE = (
    "image_width: 1280, image_height: 800, camera_matrix: {rows: 3, cols: 3, data: [fx, 0, "
    "cx, 0, fy, cy, 0, 0, 1]}, distortion_model: plumb_bob, distortion_coefficients: "
    "{rows: 1, cols: 5, data: [k1, k2, p1, p2, k3]}"
)


def read_camera_info(path: str | os.PathLike) -> Intrinsics:
    """The intrinsics of a ``camera_info`` file (module notes).

    Raises
    ------
    InputError
        Naming the file and the field: not YAML or JSON, a field missing or of the
        wrong shape, a distortion model other than ``plumb_bob``.
    """
    text = read_text(path, "camera")
    try:
        if text.lstrip().startswith("{"):
            data = json.loads(text)
        else:
            import yaml  # imported here: only a camera needs it

            data = yaml.safe_load(text)
    except Exception as exc:  # a YAML or JSON syntax error, in its own words
        first = str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__
        raise fail(path, f"not a camera_info file (YAML or JSON): {first}") from None
    return intrinsics_of(path, data)


def intrinsics_of(path: str | os.PathLike, data: Any) -> Intrinsics:
    """The intrinsics of a ``camera_info`` mapping ``data`` (a file's, or a calibration
    file's section), checked field by field."""
    if not isinstance(data, dict):
        raise fail(path, f"expected a camera_info mapping: {_EXAMPLE}")
    for key in ("image_width", "image_height", "camera_matrix", "distortion_coefficients"):
        if key not in data:
            raise fail(path, f"field '{key}' is missing; a camera_info file has {_EXAMPLE}")
    model = data.get("distortion_model", "plumb_bob")
    if model != "plumb_bob":
        raise fail(
            path,
            f"field 'distortion_model': {model!r} is not read; armcal reads plumb_bob (OpenCV's "
            "k1 k2 p1 p2 k3): calibrate the camera with that model",
        )
    size = []
    for key in ("image_width", "image_height"):
        value = data[key]
        if isinstance(value, bool) or not isinstance(value, int) or value <= 0:
            raise fail(path, f"field '{key}': expected a positive number of pixels, got {value!r}")
        size.append(value)
    matrix = _matrix(path, data["camera_matrix"], "camera_matrix", (3, 3))
    coefficients = _matrix(path, data["distortion_coefficients"], "distortion_coefficients")
    if coefficients.size not in (4, 5, 8) or coefficients.ndim != 2 or 1 not in coefficients.shape:
        raise fail(
            path,
            "field 'distortion_coefficients': expected 5 numbers k1 k2 p1 p2 k3 (rows 1, cols "
            f"5), got {coefficients.size}",
        )
    if coefficients.size == 8 and np.any(coefficients.ravel()[5:] != 0):
        raise fail(
            path,
            "field 'distortion_coefficients': 8 numbers are the rational model, not plumb_bob "
            "(k1 k2 p1 p2 k3)",
        )
    try:
        return Intrinsics(matrix, coefficients.ravel()[:5], size[0], size[1])
    except ValueError as exc:
        raise fail(path, f"field 'camera_matrix': {exc}") from None


def _matrix(
    path: str | os.PathLike, value: Any, key: str, shape: tuple[int, int] | None = None
) -> np.ndarray:
    """A ``{rows, cols, data}`` field as an array of its shape."""
    if not isinstance(value, dict) or not {"rows", "cols", "data"} <= set(value):
        raise fail(path, f"field '{key}': expected {{rows, cols, data}}")
    rows, cols, data = value["rows"], value["cols"], value["data"]
    for name, count in (("rows", rows), ("cols", cols)):
        if isinstance(count, bool) or not isinstance(count, int) or count <= 0:
            raise fail(
                path, f"field '{key}.{name}': expected a positive whole number, got {count!r}"
            )
    if not isinstance(data, list) or len(data) != rows * cols:
        raise fail(path, f"field '{key}': data must be rows x cols = {rows * cols} numbers")
    numbers = []
    for i, v in enumerate(data):
        try:  # YAML 1.1 reads 1e-05 (no dot) as text: a number all the same
            if isinstance(v, bool) or not isinstance(v, int | float | str):
                raise ValueError
            numbers.append(float(v))
        except ValueError:
            raise fail(path, f"field '{key}': data[{i}] = {v!r} is not a number") from None
    found = np.array(numbers, dtype=float).reshape(rows, cols)
    if shape is not None and found.shape != shape:
        raise fail(path, f"field '{key}': expected {shape[0]} x {shape[1]}, got {rows} x {cols}")
    if not np.all(np.isfinite(found)):
        raise fail(path, f"field '{key}': every number must be finite")
    return found


def camera_info_table(intrinsics: Intrinsics) -> dict[str, Any]:
    """``intrinsics`` as a ``camera_info`` mapping (a calibration file's copy of the camera,
    read back by :func:`intrinsics_of`)."""
    return {
        "image_width": intrinsics.width,
        "image_height": intrinsics.height,
        "camera_matrix": {"rows": 3, "cols": 3, "data": intrinsics.matrix.ravel().tolist()},
        "distortion_model": "plumb_bob",
        "distortion_coefficients": {
            "rows": 1,
            "cols": 5,
            "data": intrinsics.distortion.tolist(),
        },
    }
