"""The default of every optional role: what a family that implements only the core gets.

:class:`~armcal.models.interface.FitModel` is a small required core and optional
roles.  A family that subclasses :class:`CoreModel` supplies the core:

* names and units: ``name``, ``family``, ``param_names``, ``param_units``,
  ``fixed``, ``with_fixed``;
* its joints: ``joint_limits`` (and ``joint_kinds`` for a prismatic joint);
* the instrument: ``noise``, ``with_noise`` and ``point_dim``;
* positions and Jacobians: ``positions`` and ``jacobian``;
* a start: ``nominal`` (the parameters a fit starts from; zeros by default).

It can then be identified, validated and simulated.  Each optional role has one
default here, from the core alone:

* **identifiability**: the rank of the whitened Jacobian's free columns
  (:func:`~armcal.models.information.column_identifiability`);
* **whitening**: the noise model's, for the family's points;
* **design**: the generic plan information and the default search effort; the
  poses a plan may hold are those within the limits;
* **tool and orientation**: none (``orientation_dim`` 0);
* **effect**: none (a rigid arm: no loads, no gravity);
* plausibility: deviations are bounded by 10 % of the reach or 10 degrees.

A family overrides a default where it knows better (a closed form, a rule for
what its data cannot separate, an instrument's view).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from functools import cached_property
from typing import TYPE_CHECKING, Any, Self

import numpy as np
from numpy.typing import ArrayLike

from ..errors import ArmcalError
from ..noise import NoiseModel, relative_noise
from ..numerics import ScaledSVD
from .defaults import LARGE_ANGLE_DEG, RigidLoads, SeesAnywhere
from .identifiability import Identifiability
from .information import (
    BlockInformation,
    column_identifiability,
    factor_from_svd,
    identifiable_or_raise,
    whitened_triangle,
)
from .interface import (
    Conditions,
    DesignEffort,
    DeviationBounds,
    Effect,
    Held,
    LinearPositions,
    Loads,
    refuse_feature,
)

__all__ = ["CoreModel"]

#: A deviation beyond this fraction of the reach is implausible for the defaults' bounds.
LARGE_LENGTH_FRACTION = 0.1

#: Poses at which the default reach is sampled (random, within the limits, seeded).
_REACH_POSES = 256


class CoreModel(RigidLoads, SeesAnywhere):
    """The defaults of every optional role of a fit model (module notes)."""

    if TYPE_CHECKING:  # the family's core (a class attribute here would shadow it)

        @property
        def name(self) -> str: ...
        @property
        def family(self) -> str: ...
        @property
        def param_names(self) -> tuple[str, ...]: ...
        @property
        def param_units(self) -> tuple[str, ...]: ...
        @property
        def fixed(self) -> tuple[str, ...]: ...
        @property
        def noise(self) -> NoiseModel | None: ...
        @property
        def joint_limits(self) -> np.ndarray: ...
        @property
        def point_dim(self) -> int: ...
        def with_noise(self, noise: NoiseModel | None) -> Self: ...
        def with_fixed(self, fixed: Sequence[str]) -> Self: ...
        def positions(
            self, conditions: Conditions, params: np.ndarray | None = None
        ) -> np.ndarray: ...
        def jacobian(
            self, conditions: Conditions, params: np.ndarray | None = None
        ) -> np.ndarray: ...

    # -- names and parameters ----------------------------------------------------------

    @property
    def display_scale(self) -> np.ndarray:
        """Degrees for a parameter in rad, the unit itself otherwise."""
        return np.array([180.0 / math.pi if u == "rad" else 1.0 for u in self.param_units])

    @property
    def free(self) -> np.ndarray:
        return np.array([name not in self.fixed for name in self.param_names], dtype=bool)

    @property
    def free_names(self) -> tuple[str, ...]:
        return tuple(n for n, f in zip(self.param_names, self.free, strict=True) if f)

    @property
    def n_params(self) -> int:
        return len(self.param_names)

    @property
    def n_free(self) -> int:
        return int(np.sum(self.free))

    @property
    def nominal(self) -> np.ndarray:
        """The parameters a fit starts from: zero deviations."""
        return np.zeros(self.n_params)

    @property
    def held_values(self) -> np.ndarray:
        return self.nominal

    @property
    def angle_params(self) -> np.ndarray:
        return np.array([u == "rad" for u in self.param_units], dtype=bool)

    @property
    def instrument_params(self) -> np.ndarray:
        return np.zeros(self.n_params, dtype=bool)

    @property
    def registration_params(self) -> np.ndarray:
        return np.zeros(self.n_params, dtype=bool)

    # -- joints ------------------------------------------------------------------------

    @property
    def n_joints(self) -> int:
        return int(np.shape(self.joint_limits)[0])

    @property
    def joint_kinds(self) -> tuple[str, ...]:
        return ("R",) * self.n_joints

    @property
    def joint_names(self) -> tuple[str, ...]:
        return tuple(f"joint {j + 1}" for j in range(self.n_joints))

    @cached_property  # not a property: a family's dataclass field of the name overrides it
    def joint_map(self) -> np.ndarray:
        return np.eye(self.n_joints)

    @property
    def value_limits(self) -> np.ndarray | None:
        return None

    def within_limits(self, q: np.ndarray, *, tol: float = 1e-9) -> np.ndarray:
        limits = np.asarray(self.joint_limits)
        q = np.asarray(q, dtype=float)
        return (q >= limits[:, 0] - tol) & (q <= limits[:, 1] + tol)

    @property
    def target_labels(self) -> tuple[str, ...]:
        return ()

    @property
    def arm(self) -> Any:
        return self

    # -- measurement -------------------------------------------------------------------

    @property
    def position_dim(self) -> int:
        return self.point_dim

    def conditions(
        self,
        q: ArrayLike,
        *,
        target: ArrayLike | None = None,
        loads: Loads | None = None,
        sigma_mm: np.ndarray | None = None,
        feature: ArrayLike | None = None,
    ) -> Conditions:
        q = self._readings(q)
        if target is not None:
            raise ValueError(f"{self.name} has one target: give no target indices")
        refuse_feature(self.name, feature)
        return Conditions(q, None, None, sigma_mm)

    def _readings(self, q: ArrayLike) -> np.ndarray:
        """``q`` as floats ``(..., m, n)``; ValueError for another shape."""
        q = np.asarray(q, dtype=float)
        if q.ndim < 2 or q.shape[-1] != self.n_joints:
            raise ValueError(f"q must have shape (m, {self.n_joints}), got {q.shape}")
        return q

    def plan_conditions(self, q: np.ndarray, loads: Loads | None = None) -> Conditions:
        return self.conditions(q)

    def anchor(self, conditions: Conditions, points: np.ndarray) -> tuple[Conditions, np.ndarray]:
        return conditions, np.asarray(points, dtype=float)

    def unanchor(self, conditions: Conditions, points: np.ndarray) -> np.ndarray:
        return np.asarray(points, dtype=float)

    def joint_jacobian(
        self, conditions: Conditions, params: np.ndarray | None = None
    ) -> np.ndarray:
        """``d point / d q`` ``(..., m, d, n)`` by central differences (a step of 1e-6 rad
        or mm): a family gives its analytic one where encoder noise matters."""
        q = np.asarray(conditions.q, dtype=float)
        step = 1e-6
        columns = []
        for j in range(q.shape[-1]):
            shift = np.zeros(q.shape[-1])
            shift[j] = step
            ahead = self.positions(Conditions(q + shift, conditions.target), params)
            behind = self.positions(Conditions(q - shift, conditions.target), params)
            columns.append((ahead - behind) / (2 * step))
        return np.stack(columns, axis=-1)

    def _core_noise(self, noise: NoiseModel | None) -> NoiseModel:
        return relative_noise(self.noise if noise is None else noise).for_dim(self.point_dim)

    def _core_row_noise(self, conditions: Conditions, noise: NoiseModel) -> dict[str, Any]:
        joint = None if noise.joint_sigma is None else self.joint_jacobian(conditions)
        return {
            "shape": np.shape(conditions.q)[:-1],
            "joint_jacobian": joint,
            "row_sigma": conditions.sigma_mm,
        }

    def pose_covariances(
        self,
        conditions: Conditions,
        params: np.ndarray | None = None,
        *,
        noise: NoiseModel | None = None,
    ) -> np.ndarray:
        found = self._core_noise(noise)
        return found.pose_covariances(**self._core_row_noise(conditions, found))

    def whitening(
        self, conditions: Conditions, params: np.ndarray | None = None
    ) -> np.ndarray | None:
        if (self.noise is None or self.noise.isotropic_iid) and conditions.sigma_mm is None:
            return None
        found = self._core_noise(None)
        return found.whitening(**self._core_row_noise(conditions, found))

    # -- fitting -----------------------------------------------------------------------

    @property
    def has_closed_form(self) -> bool:
        return False

    @property
    def closed_form_hold(self) -> None:
        return None

    def closed_form(self, conditions: Conditions) -> None:
        return None

    @property
    def nested(self) -> None:
        return None

    @property
    def effect(self) -> Effect | None:
        return None

    def lift(self, nested_params: np.ndarray) -> np.ndarray:
        return np.asarray(nested_params, dtype=float)

    def start(
        self, conditions: Conditions, points: np.ndarray, weights: np.ndarray | None = None
    ) -> np.ndarray:
        """The nominal parameters for every point set ``(N, m, d)``: Gauss-Newton from the
        nominal arm (a family whose fit needs a better start gives one)."""
        sets = np.shape(points)[0]
        return np.tile(self.nominal, (sets, 1))

    def canonical(self, params: np.ndarray) -> np.ndarray:
        return np.asarray(params, dtype=float)

    def step_scale(self, conditions: Conditions) -> np.ndarray:
        return np.ones(self.n_params)

    def prepared(self, conditions: Conditions, points: np.ndarray | None = None) -> Self:
        return self

    def expressed(self, conditions: Conditions, params: np.ndarray) -> np.ndarray:
        return np.asarray(params, dtype=float)

    @property
    def held_reasons(self) -> tuple[Held, ...]:
        return ()

    @property
    def rule_held(self) -> tuple[str, ...]:
        return ()

    @property
    def rank_bound(self) -> int | None:
        return None

    # -- identifiability ---------------------------------------------------------------

    def identifiability(self, conditions: Conditions) -> tuple[Identifiability, ScaledSVD]:
        return column_identifiability(self, conditions)

    def check_identifiable(self, conditions: Conditions) -> Identifiability:
        return identifiable_or_raise(
            self,
            conditions,
            self.name,
            "measure poses in which every joint takes several different values",
        )

    def covariance_factor(
        self, conditions: Conditions, params: np.ndarray | None = None
    ) -> tuple[np.ndarray, np.ndarray]:
        return factor_from_svd(whitened_triangle(self, conditions, params).svd(), self.free)

    def fit_details(self, conditions: Conditions, params: np.ndarray) -> dict[str, np.ndarray]:
        return {}

    def linear_positions(self, conditions: Conditions) -> LinearPositions | None:
        return None

    # -- plausibility ------------------------------------------------------------------

    @cached_property  # 256 poses' points: once per model, not per solve
    def reach_mm(self) -> float:
        """The largest distance of a point from the base over 256 seeded poses within
        the limits (at the nominal parameters)."""
        limits = np.clip(np.asarray(self.joint_limits, dtype=float), -math.pi, math.pi)
        rng = np.random.default_rng(0)
        q = rng.uniform(limits[:, 0], limits[:, 1], size=(_REACH_POSES, self.n_joints))
        points = self.positions(self.conditions(q))
        return float(np.max(np.linalg.norm(points, axis=-1)))

    @property
    def tip_reach_mm(self) -> float:
        return self.reach_mm

    @property
    def base_offset(self) -> bool:
        return False

    @property
    def deviation_bounds(self) -> DeviationBounds:
        """10 % of the reach for a length, 10 degrees for an angle."""
        angle = self.angle_params
        reach = self.reach_mm
        bounds = np.where(angle, math.radians(LARGE_ANGLE_DEG), LARGE_LENGTH_FRACTION * reach)
        return DeviationBounds(
            bounds,
            np.where(angle, np.nan, reach),
            tuple("" if a else "the reach" for a in angle),
            "reach",
            LARGE_LENGTH_FRACTION,
            LARGE_ANGLE_DEG,
            "description",
            np.zeros(self.n_params),
        )

    # -- design ------------------------------------------------------------------------

    @property
    def design_effort(self) -> DesignEffort:
        return DesignEffort()

    def feasible(self, q: np.ndarray, *, tol: float = 1e-9) -> np.ndarray:
        return np.all(self.within_limits(q, tol=tol), axis=-1)

    @property
    def has_view(self) -> bool:
        return False

    def view_constraints(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray] | None:
        return None

    @property
    def rotation_invariant(self) -> bool:
        return False

    @property
    def information_bound(self) -> bool:
        return False

    def plan_information(
        self, q: np.ndarray, loads: Loads | None = None, *, rows: Conditions | None = None
    ) -> BlockInformation:
        return BlockInformation(self, q, loads, rows=rows)

    def closed_form_plans(self, m: int) -> None:
        return None

    def paper_criteria(self, q: np.ndarray) -> None:
        return None

    def design_loads(self, payloads: Sequence[float] | None) -> None:
        return None

    # -- the tool ------------------------------------------------------------------------

    @property
    def orientation_dim(self) -> int:
        return 0

    @property
    def angle_scale_mm(self) -> float:
        return 100.0

    def _no_tool(self) -> ArmcalError:
        return ArmcalError(f"{self.name}: the {self.family} family does not model the tool")

    def orientation(self, conditions: Conditions, params: np.ndarray | None = None) -> np.ndarray:
        raise self._no_tool()

    def orientation_turn(
        self, conditions: Conditions, params: np.ndarray | None, reference: np.ndarray
    ) -> np.ndarray:
        raise self._no_tool()

    def orientation_joint_jacobian(
        self, conditions: Conditions, params: np.ndarray | None = None
    ) -> np.ndarray:
        raise self._no_tool()

    def orientation_jacobian(
        self, conditions: Conditions, params: np.ndarray | None = None
    ) -> np.ndarray:
        raise self._no_tool()

    def tip_rotation(self, conditions: Conditions, params: np.ndarray | None = None) -> np.ndarray:
        raise self._no_tool()

    def in_robot_frame(self, params: np.ndarray) -> tuple[Self, np.ndarray]:
        return self, np.asarray(params, dtype=float)

    def arm_params(self, params: np.ndarray) -> np.ndarray:
        return np.asarray(params, dtype=float)
