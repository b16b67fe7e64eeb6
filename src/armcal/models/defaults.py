"""Parts of :class:`~armcal.models.interface.FitModel` that several families share.

* :class:`RigidLoads` -- an arm whose points do not depend on its load or on
  gravity (the planar and the spatial arm; a model of joint compliance
  overrides all four);
* :class:`MinimalPlanar` -- a planar family whose parameters are minimal: it
  needs no preparing for a set of rows, its truth is its own, nothing is held
  by a rule, and its tool's orientation is one angle in the plane;
* :class:`ArmEffect` -- a model that adds an effect's parameters after an arm's
  (joint compliance, planar or spatial): what it passes through to the arm, and
  which of its terms the user holds (:class:`TermChoice`).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Self

import numpy as np

from ..noise import NoiseModel
from ..numerics import wrap_angle
from .information import covariance_factor_from, whitened_free_jacobian
from .interface import Conditions, DesignEffort, DeviationBounds, Held, Loads

__all__ = [
    "LARGE_ANGLE_DEG",
    "ArmEffect",
    "MinimalPlanar",
    "RigidLoads",
    "TermChoice",
]

#: An angular deviation (a joint zero, a turn of a joint's placement) beyond this many
#: degrees is implausible for a calibration, in every family: calibration-sized angles
#: are about a degree at most (a zero mastered by eye), while a unit mistake or a wrong
#: robot file gives tens of degrees (radians read as degrees: 57 times the angle), so
#: 10 deg leaves a factor of several on either side (the ``large-deviation`` warning).
LARGE_ANGLE_DEG = 10.0


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


class SeesAnywhere:
    """A model measured by an instrument that sees the tool wherever it is (a tracker, a
    probe): a plan's poses need not meet it, and what another instrument's rows cannot
    separate is not this model's rule to choose (:mod:`~armcal.models.instrumented`
    measures an arm that has one: the spatial arm's)."""

    @property
    def constrained(self) -> bool:
        """False: the instrument sees the tool at any pose."""
        return False

    def alone(
        self, params: np.ndarray, covariance: np.ndarray
    ) -> tuple[Any, np.ndarray, np.ndarray]:
        """Itself: a tracker sees the arm whole."""
        return self, params, covariance

    @property
    def feature_labels(self) -> tuple[str, ...]:
        """None: a tracker's rows touch no feature."""
        return ()

    @property
    def touches(self) -> bool:
        """False: a row reports where the tool is."""
        return False

    @property
    def reading_unit(self) -> str:
        """``"mm"``: a row reads a position."""
        return "mm"

    def turn_rows(self, conditions: Conditions) -> np.ndarray | None:
        """None: a row reads a position (a 6-DoF instrument's turns are columns of it)."""
        return None

    @property
    def reads_turns(self) -> bool:
        """False: no row reads an angle alone."""
        return False

    def meeting_poses(
        self,
        q: np.ndarray,
        params: np.ndarray | None = None,
        miss: np.ndarray | None = None,
        feature: np.ndarray | None = None,
    ) -> tuple[np.ndarray, np.ndarray]:
        """The poses as they are, every one met: the instrument sees the tool anywhere."""
        q = np.asarray(q, dtype=float)
        return q, np.ones(q.shape[0], dtype=bool)

    def selected_by(
        self, rows: np.ndarray, conditions: Conditions, first: Sequence[str] = ()
    ) -> Self:
        """Itself: its identifiable set is not chosen by a rule (minimal parameters)."""
        return self


class MinimalPlanar(SeesAnywhere):
    """A planar family with minimal parameters (module notes)."""

    if TYPE_CHECKING:  # the family's own (a class attribute here would shadow it)

        @property
        def n_params(self) -> int: ...
        @property
        def n_joints(self) -> int: ...
        def orientation(
            self, conditions: Conditions, params: np.ndarray | None = None
        ) -> np.ndarray: ...

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
    def held_reasons(self) -> tuple[Held, ...]:
        return ()

    @property
    def rule_held(self) -> tuple[str, ...]:
        """None: the parameters are minimal."""
        return ()

    @property
    def rank_bound(self) -> int | None:
        """None: minimal parameters are all identified by rows that can."""
        return None

    @property
    def joint_names(self) -> tuple[str, ...]:
        """``joint 1`` ...: a planar arm's description does not name its joints."""
        return tuple(f"joint {j + 1}" for j in range(self.n_joints))

    @property
    def value_limits(self) -> np.ndarray | None:
        """None: the readings' limits are all a planar arm has."""
        return None

    def orientation_turn(
        self, conditions: Conditions, params: np.ndarray | None, reference: np.ndarray
    ) -> np.ndarray:
        """The difference of the tool's directions from ``reference``, wrapped into
        ``(-pi, pi]``."""
        return wrap_angle(self.orientation(conditions, params) - np.asarray(reference))


@dataclass(frozen=True)
class TermChoice:
    """Which of an effect's terms (joint compliance: ``k{j}``, ``c{j}``, ``c{j}.{s}``) the
    user holds at zero: a robot file's ``[identify]`` table, or the fix option.

    Attributes
    ----------
    fixed : tuple of str
        Terms held at zero (``[identify] fixed``, the fix option).
    free : tuple of str or None
        The only terms identified, every other held (``[identify] free``); None when
        the user did not list them.  A term listed here is one the user asks for:
        a model that cannot identify it from the rows refuses rather than hold it.

    Examples
    --------
    >>> TermChoice(fixed=("k2",)).held(("k1", "k2", "k3"))
    ('k2',)
    >>> TermChoice(free=("k2",)).held(("k1", "k2", "k3"))
    ('k1', 'k3')
    """

    fixed: tuple[str, ...] = ()
    free: tuple[str, ...] | None = None

    def held(self, names: Sequence[str]) -> tuple[str, ...]:
        """The terms of ``names`` the user holds, in their order."""
        if self.free is not None:
            return tuple(n for n in names if n not in self.free)
        return tuple(n for n in names if n in self.fixed)

    @property
    def asked(self) -> tuple[str, ...]:
        """The terms the user asks to identify by name (``free``)."""
        return () if self.free is None else self.free


class ArmEffect(SeesAnywhere):
    """A model whose parameters are an arm's followed by an effect's (module notes): the
    arm's limits, instrument, view and tool, and the effect's parameters appended.

    The family gives ``arm``, ``elastic`` (with ``payload_kg``, ``terms``, a
    :class:`TermChoice`, and ``term_names(arm)``, every term its model of any rows
    can have), ``n_compliance``, ``compliance_names``, ``compliance_units``,
    ``compliance_scale`` and ``free``.
    """

    if TYPE_CHECKING:  # the family's own (a class attribute here would shadow it)
        arm: Any
        elastic: Any

        @property
        def n_compliance(self) -> int: ...
        @property
        def compliance_names(self) -> tuple[str, ...]: ...
        @property
        def compliance_units(self) -> tuple[str, ...]: ...
        @property
        def compliance_scale(self) -> np.ndarray: ...
        @property
        def free(self) -> np.ndarray: ...

    @property
    def name(self) -> str:
        return self.arm.name

    @property
    def family(self) -> str:
        """The arm's family: an effect does not change the family of the arm it is on."""
        return str(self.arm.family)

    @property
    def value_limits(self) -> np.ndarray | None:
        return self.arm.value_limits

    @property
    def joint_names(self) -> tuple[str, ...]:
        return tuple(self.arm.joint_names)

    @property
    def tip_reach_mm(self) -> float:
        return float(self.arm.tip_reach_mm)

    @property
    def base_offset(self) -> bool:
        return bool(self.arm.base_offset)

    @property
    def rule_held(self) -> tuple[str, ...]:
        """The arm's (an effect's own held terms are its :meth:`held_reasons`' business)."""
        return tuple(self.arm.rule_held)

    @property
    def rank_bound(self) -> int | None:
        """The arm's, and every free term of the effect."""
        bound = self.arm.rank_bound
        effect = int(np.count_nonzero(self.free)) - int(np.count_nonzero(self.arm.free))
        return None if bound is None else int(bound) + effect

    @property
    def user_held(self) -> tuple[str, ...]:
        """The effect's terms the user holds at zero (:class:`TermChoice`)."""
        return self.elastic.terms.held(self.compliance_names)

    @property
    def user_reason(self) -> tuple[Held, ...]:
        """The terms the user holds, for :attr:`held_reasons` (none: empty)."""
        held = self.user_held
        return (Held(held, reason="user"),) if held else ()

    @property
    def closed_form_hold(self) -> None:
        """None: the effect has no closed form (its nested arm may have one)."""
        return None

    def split_fixed(self, fixed: Sequence[str]) -> tuple[tuple[str, ...], TermChoice]:
        """``fixed`` (the arm's parameters and the effect's terms, as the fix option gives
        them) as the arm's and the effect's: a term any rows could give the model is the
        effect's, every other name the arm's."""
        terms = set(self.elastic.term_names(self.arm))
        return (
            tuple(n for n in fixed if n not in terms),
            TermChoice(fixed=tuple(n for n in fixed if n in terms)),
        )

    @property
    def param_names(self) -> tuple[str, ...]:
        """The arm's parameter names, then the effect's."""
        return self.arm.param_names + self.compliance_names

    @property
    def param_units(self) -> tuple[str, ...]:
        return self.arm.param_units + self.compliance_units

    @property
    def display_scale(self) -> np.ndarray:
        return np.concatenate([self.arm.display_scale, self.compliance_scale])

    @property
    def n_params(self) -> int:
        return self.arm.n_params + self.n_compliance

    @property
    def angle_params(self) -> np.ndarray:
        return np.concatenate([self.arm.angle_params, np.zeros(self.n_compliance, dtype=bool)])

    @property
    def instrument_params(self) -> np.ndarray:
        extra = np.zeros(self.n_compliance, dtype=bool)
        return np.concatenate([self.arm.instrument_params, extra])

    @property
    def registration_params(self) -> np.ndarray:
        extra = np.zeros(self.n_compliance, dtype=bool)
        return np.concatenate([self.arm.registration_params, extra])

    @property
    def noise(self) -> NoiseModel | None:
        return self.arm.noise

    @property
    def n_joints(self) -> int:
        return self.arm.n_joints

    @property
    def joint_limits(self) -> np.ndarray:
        return self.arm.joint_limits

    @property
    def joint_kinds(self) -> tuple[str, ...]:
        return self.arm.joint_kinds

    def within_limits(self, q: np.ndarray, *, tol: float = 1e-9) -> np.ndarray:
        return self.arm.within_limits(q, tol=tol)

    @property
    def point_dim(self) -> int:
        return self.arm.point_dim

    @property
    def reach_mm(self) -> float:
        return self.arm.reach_mm

    @property
    def deviation_bounds(self) -> DeviationBounds:
        """The arm's; the effect's parameters are no deviation of the robot's geometry."""
        bounds: DeviationBounds = self.arm.deviation_bounds
        return bounds.extended(self.n_compliance)

    @property
    def joint_map(self) -> np.ndarray:
        """The arm's joint map."""
        return np.asarray(self.arm.joint_map)

    @property
    def target_labels(self) -> tuple[str, ...]:
        return self.arm.target_labels

    def split(self, params: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The arm's parameters ``(..., p)`` and the effect's ``(..., P)`` of a full vector."""
        p = self.arm.n_params
        return params[..., :p], params[..., p:]

    def lift(self, nested_params: np.ndarray) -> np.ndarray:
        """The arm's parameters with no effect."""
        shape = (*np.shape(nested_params)[:-1], self.n_compliance)
        return np.concatenate([nested_params, np.zeros(shape)], axis=-1)

    def arm_params(self, params: np.ndarray) -> np.ndarray:
        return self.split(np.asarray(params, dtype=float))[0]

    def canonical(self, params: np.ndarray) -> np.ndarray:
        """The arm's canonical parameters (the points do not change), the effect's kept."""
        geometry, effect = self.split(np.asarray(params, dtype=float))
        return np.concatenate([self.arm.canonical(geometry), effect], axis=-1)

    @property
    def nested(self) -> Any:
        """The arm without the effect."""
        return self.arm

    @property
    def has_closed_form(self) -> bool:
        return False

    def closed_form(self, conditions: Conditions) -> None:
        return None

    def linear_positions(self, conditions: Conditions) -> None:
        """None: the effect's points are not linear in any coordinates of the parameters."""
        return None

    def covariance_factor(
        self, conditions: Conditions, params: np.ndarray | None = None
    ) -> tuple[np.ndarray, np.ndarray]:
        """From the SVD of the whitened free columns (:mod:`armcal.models.information`)."""
        model: Any = self  # a whole FitModel once its family adds the rest
        return covariance_factor_from(whitened_free_jacobian(model, conditions, params), self.free)

    def pose_covariances(
        self,
        conditions: Conditions,
        params: np.ndarray | None = None,
        *,
        noise: NoiseModel | None = None,
    ) -> np.ndarray:
        """The arm's: the effect moves the points, not the instrument's noise."""
        geometry = None if params is None else self.split(np.asarray(params, dtype=float))[0]
        return self.arm.pose_covariances(conditions, geometry, noise=noise)

    def whitening(
        self, conditions: Conditions, params: np.ndarray | None = None
    ) -> np.ndarray | None:
        geometry = None if params is None else self.split(np.asarray(params, dtype=float))[0]
        return self.arm.whitening(conditions, geometry)

    def feasible(self, q: np.ndarray, *, tol: float = 1e-9) -> np.ndarray:
        return self.arm.feasible(q, tol=tol)

    @property
    def has_view(self) -> bool:
        return self.arm.has_view

    def view_constraints(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray] | None:
        return self.arm.view_constraints(q)

    @property
    def information_bound(self) -> bool:
        """No bound on the information of a pose with the effect's parameters."""
        return False

    def closed_form_plans(self, m: int) -> None:
        return None

    def paper_criteria(self, q: np.ndarray) -> None:
        return None

    @property
    def angle_scale_mm(self) -> float:
        return self.arm.angle_scale_mm

    @property
    def default_payload_kg(self) -> float:
        """The robot file's payload."""
        return float(self.elastic.payload_kg)

    def default_loads(self, m: int) -> Loads:
        """The robot file's payload on every one of ``m`` rows."""
        return Loads.create(m, self.elastic.payload_kg)
