"""A 6-DoF instrument's rows of a spatial arm: orientations as turns from reference frames.

A 6-DoF instrument (a tracker's probe, an optical tracker's rigid body) gives a
target's orientation ``R`` besides its position.  Rotation vectors of ``R``
itself are a chart with a seam at a half turn; the fit compares instead the turn
``rotvec(R F^T)`` from every row's reference frame ``F``
(:attr:`~armcal.models.interface.Conditions.frames`), which :func:`anchor` sets to
the measured orientation: the residual ``rotvec(R_meas R_pred^T)`` is then small
at every orientation.  A turn ``w`` of the prediction changes it by
``J_l(phi)^-1 w`` (:func:`~armcal.models.spatial.chain.left_jacobian_inverse`),
exactly.
"""

from __future__ import annotations

import numpy as np

from ..interface import Conditions
from .chain import left_jacobian_inverse, rotation_vector, vector_rotation

__all__ = [
    "anchor",
    "turn_rows",
    "turns",
    "unanchor",
]


def turns(rotation: np.ndarray, frames: np.ndarray | None) -> np.ndarray:
    """The rotation vectors ``(..., m, 3)`` of orientations ``R`` ``(..., m, 3, 3)`` from the
    rows' frames ``F``: of ``R F^T``, the instrument's axes where there are none."""
    if frames is None:
        return rotation_vector(rotation)
    return rotation_vector(rotation @ np.swapaxes(frames, -1, -2))


def turn_rows(angular: np.ndarray, turn: np.ndarray) -> np.ndarray:
    """The turns' Jacobian rows ``(..., m, 3, k)`` from angular velocities ``(..., m, 3, k)``
    at turns ``(..., m, 3)``: ``J_l(phi)^-1 w``."""
    return left_jacobian_inverse(turn) @ angular


def anchor(conditions: Conditions, points: np.ndarray) -> tuple[Conditions, np.ndarray]:
    """Rows ``(m, 6)`` as an instrument gives them (positions, rotation vectors in its frame)
    as the fit compares them: every measured orientation becomes its row's frame, the
    turn from it zero."""
    measured = vector_rotation(points[..., 3:])
    if conditions.frames is not None:
        measured = measured @ conditions.frames
    out = np.array(points, dtype=float)
    out[..., 3:] = 0.0
    return conditions.with_frames(measured), out


def unanchor(conditions: Conditions, points: np.ndarray) -> np.ndarray:
    """:func:`anchor` undone: orientations as rotation vectors in the instrument's frame."""
    if conditions.frames is None:
        return np.asarray(points, dtype=float)
    out = np.array(points, dtype=float)
    out[..., 3:] = rotation_vector(vector_rotation(points[..., 3:]) @ conditions.frames)
    return out
