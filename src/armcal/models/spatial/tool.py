"""The tool role of a spatial arm: the tip frame's orientation and its Jacobians.

:class:`SpatialTool` is the part of :class:`~armcal.models.spatial.arm.SpatialArm`
that a 6-DoF instrument and compensation use (the optional *tool and orientation*
role of :class:`~armcal.models.interface.FitModel`): orientations as rotation
vectors, their error and their angular Jacobians.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Self

import numpy as np

from ..interface import Conditions
from .chain import rotation_vector, vector_rotation
from .kinematics import ChainKinematics

__all__ = ["SpatialTool"]


class SpatialTool:
    """The tool role of :class:`~armcal.models.spatial.arm.SpatialArm` (module notes)."""

    if TYPE_CHECKING:  # the arm's own (a class attribute here would shadow it)

        def chain_kinematics(
            self, conditions: Conditions, params: np.ndarray | None, *, derivatives: bool = False
        ) -> ChainKinematics: ...
        def derivative(
            self, conditions: Conditions, params: np.ndarray | None, name: str
        ) -> np.ndarray: ...

    @property
    def orientation_dim(self) -> int:
        return 3

    @property
    def angle_scale_mm(self) -> float:
        """The distance at which a tool angle counts like a position: 100 mm."""
        return 100.0

    def orientation(self, conditions: Conditions, params: np.ndarray | None = None) -> np.ndarray:
        """The tip frame's orientation ``(..., m, 3)`` in the instrument frame, as a rotation
        vector (axis times angle, rad)."""
        return rotation_vector(self.chain_kinematics(conditions, params).rotation)

    def orientation_turn(
        self, conditions: Conditions, params: np.ndarray | None, reference: np.ndarray
    ) -> np.ndarray:
        """The small turn ``(..., m, 3)`` (rad, instrument frame) from ``reference`` to the
        tip frame's orientation ``R``: the rotation vector of ``R R_ref^T``, from the
        pass's rotations (no round trip through rotation vectors)."""
        rotation = self.chain_kinematics(conditions, params).rotation
        return rotation_vector(rotation @ np.swapaxes(vector_rotation(reference), -1, -2))

    def tip_rotation(self, conditions: Conditions, params: np.ndarray | None = None) -> np.ndarray:
        """The tip frame's rotation ``(..., m, 3, 3)`` in the instrument frame."""
        return self.chain_kinematics(conditions, params).rotation

    def orientation_joint_jacobian(
        self, conditions: Conditions, params: np.ndarray | None = None
    ) -> np.ndarray:
        """The tip frame's angular velocity per reading ``(..., m, 3, n)``."""
        return self.derivative(conditions, params, "tip_angular")

    def orientation_jacobian(
        self, conditions: Conditions, params: np.ndarray | None = None
    ) -> np.ndarray:
        """The tip frame's angular velocity per parameter ``(..., m, 3, p)``."""
        return self.derivative(conditions, params, "angular")

    def in_robot_frame(self, params: np.ndarray) -> tuple[Self, np.ndarray]:
        out = np.array(params, dtype=float)
        out[..., :6] = 0.0
        return self, out

    def arm_params(self, params: np.ndarray) -> np.ndarray:
        return np.asarray(params, dtype=float)
