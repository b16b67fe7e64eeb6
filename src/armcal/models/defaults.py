"""Parts of :class:`~armcal.models.interface.FitModel` that several families share.

* :class:`RigidLoads` -- an arm whose points do not depend on its load or on
  gravity (the planar and the spatial arm; a model of joint compliance
  overrides all four);
* :class:`MinimalPlanar` -- a planar family whose parameters are minimal: it
  needs no preparing for a set of rows, its truth is its own, nothing is held
  by a rule, and its tool's orientation is one angle in the plane.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Self

import numpy as np

from .interface import Conditions, DesignEffort, Loads
from .planar_geometry import wrap_angle

__all__ = [
    "MinimalPlanar",
    "RigidLoads",
]


class RigidLoads:
    """An arm whose points depend on neither its load nor gravity."""

    @property
    def default_payload_kg(self) -> None:
        """A rigid arm's points do not depend on its load."""
        return None

    def unpredicted_loads(self, loads: Loads) -> None:
        """A rigid arm's points do not depend on its load: nothing to predict."""
        return None

    @property
    def uses_gravity(self) -> bool:
        """A rigid arm's points do not depend on gravity."""
        return False

    def with_gravity(self, gravity: np.ndarray | None) -> Self:
        return self


class MinimalPlanar:
    """A planar family with minimal parameters (module notes)."""

    if TYPE_CHECKING:  # the family's own (a class attribute here would shadow it)

        @property
        def n_params(self) -> int: ...

    def prepared(self, conditions: Conditions, points: np.ndarray | None = None) -> Self:
        """Itself: its parameters are minimal and need no placing."""
        return self

    @property
    def design_effort(self) -> DesignEffort:
        """A planar start costs little and its criteria have many local optima: many
        starts, long ascents."""
        return DesignEffort()

    @property
    def position_dim(self) -> int:
        """Every coordinate of its points is a position."""
        return 2

    def anchor(self, conditions: Conditions, points: np.ndarray) -> tuple[Conditions, np.ndarray]:
        """The rows as they are: its points are positions only."""
        return conditions, np.asarray(points, dtype=float)

    def unanchor(self, conditions: Conditions, points: np.ndarray) -> np.ndarray:
        """The points as they are: they are positions only."""
        return np.asarray(points, dtype=float)

    def expressed(self, conditions: Conditions, params: np.ndarray) -> np.ndarray:
        """``params``: its parameters are minimal."""
        return np.asarray(params, dtype=float)

    @property
    def held_values(self) -> np.ndarray:
        """Zeros: a held deviation is 0."""
        return np.zeros(self.n_params)

    @property
    def held_notes(self) -> tuple[str, ...]:
        return ()

    def orientation_error(self, orientation: np.ndarray, reference: np.ndarray) -> np.ndarray:
        """The difference of the tool's directions, wrapped into ``(-pi, pi]``."""
        return wrap_angle(np.asarray(orientation) - np.asarray(reference))
