"""An arm measured by an instrument other than a tracker: :class:`InstrumentedArm`.

The arm is any model of the interface whose points are the tool's in its own
base frame (its base pose held at the origin: the instrument's unknowns are in
that frame, :mod:`armcal.instruments`); the instrument turns the points into
what it reports.  A row's reported numbers are ``h(p(q, x), theta)`` for the
arm's parameters ``x`` and the instrument's ``theta``, and the model's
Jacobian is the chain rule's ``[dh/dp . dp/dx, dh/dtheta]``.  What the rows
measure is ``h``'s value at the true arm: 0 for a touch or a seating.

**What the rows identify.**  The instrument's parameters come first: they are
what the rows are about, and all of them are kept (rows that do not fix them,
a plane touched along one line, are refused).  The arm's parameters are chosen
by the arm's own rule (:meth:`~armcal.models.interface.FitModel.selected_by`)
beside the instrument's columns, which it keeps first: what the instrument's
parameters can mimic, or what the instrument cannot see (a shift of the whole
arm along a plane, a turn of it about a fixed point), is held, and named.

The rule runs on the Jacobian where the arm meets the rows' readings
(:meth:`InstrumentedArm._seated`), not at the nominal arm: a turn of the whole
arm about a fixed point keeps a tool that sits *in* the point there, but moves
the nominal arm's tool, a few mm off it, by a little, and the rule would keep
what no seating can see.  The fit starts there too.

The plane, the fixed point and the distance are the first instruments; the
command line, the robot file's ``[instrument]`` table, designs over the
constrained poses and the guide pages are still to come (issue 38).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, replace
from functools import cached_property
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from ..errors import ArmcalError
from ..instruments.base import Instrument, feature_index
from ..noise import NoiseModel
from ..numerics import RowTriangle
from .core import CoreModel
from .information import refit_free
from .interface import Conditions, FitModel, Held, Loads, target_indices

__all__ = ["InstrumentedArm"]


@dataclass(frozen=True, eq=False)
class InstrumentedArm(CoreModel):
    """An arm measured by an instrument (module notes).

    Attributes
    ----------
    inner : FitModel
        The arm's model, its base at the origin and held there (:meth:`of`).
    instrument : Instrument
        What the rows report of the tool point.
    instrument_fixed : tuple of str
        The instrument's parameters the user holds.
    """

    inner: Any
    instrument: Instrument
    instrument_fixed: tuple[str, ...] = ()

    @classmethod
    def of(cls, arm: FitModel, instrument: Instrument) -> InstrumentedArm:
        """``arm`` measured by ``instrument``: its base held at the origin of its own
        frame, where the instrument's parameters are given."""
        held = tuple(dict.fromkeys((*arm.fixed, *_base_names(arm))))
        return cls(arm.with_fixed(held), instrument)

    # -- names and parameters ----------------------------------------------------------

    @property
    def arm(self) -> InstrumentedArm:
        """The geometric arm measured by the same instrument (itself for a rigid arm):
        what a baseline registers, the instrument's parameters with the targets."""
        geometric = self.inner.arm
        return self if geometric is self.inner else replace(self, inner=geometric)

    def arm_params(self, params: np.ndarray) -> np.ndarray:
        x, theta = self.split(params)
        return np.concatenate([self.inner.arm_params(x), theta], axis=-1)

    @property
    def name(self) -> str:
        return str(self.inner.name)

    @property
    def family(self) -> str:
        return str(self.inner.family)

    @property
    def n_arm(self) -> int:
        """The arm's parameters: the first of the model's."""
        return int(self.inner.n_params)

    @property
    def param_names(self) -> tuple[str, ...]:
        return tuple(self.inner.param_names) + self.instrument.param_names

    @property
    def param_units(self) -> tuple[str, ...]:
        return tuple(self.inner.param_units) + self.instrument.param_units

    @property
    def display_scale(self) -> np.ndarray:
        mine = np.where(np.array(self.instrument.param_units) == "rad", 180.0 / np.pi, 1.0)
        return np.concatenate([self.inner.display_scale, mine])

    @property
    def fixed(self) -> tuple[str, ...]:
        return tuple(self.inner.fixed) + self.instrument_fixed

    @cached_property
    def nominal(self) -> np.ndarray:
        """The arm's nominal parameters with its base at the origin, then where the user
        says the instrument is."""
        arm = np.array(self.inner.nominal, dtype=float)
        arm[np.isin(self.inner.param_names, _base_names(self.inner))] = 0.0
        return np.concatenate([arm, self.instrument.start])

    @property
    def held_values(self) -> np.ndarray:
        return self.nominal

    @property
    def angle_params(self) -> np.ndarray:
        mine = np.array([u == "rad" for u in self.instrument.param_units], dtype=bool)
        return np.concatenate([self.inner.angle_params, mine])

    @property
    def instrument_params(self) -> np.ndarray:
        """The instrument's own parameters (the arm's base is held at its origin)."""
        extra = np.ones(len(self.instrument.param_names), dtype=bool)
        return np.concatenate([np.zeros(self.n_arm, dtype=bool), extra])

    @property
    def registration_params(self) -> np.ndarray:
        """The instrument's parameters and the arm's targets (what a nominal arm's fit to
        the rows moves: the honest baseline)."""
        targets = np.asarray(self.inner.registration_params, dtype=bool) & np.asarray(
            self.inner.free, dtype=bool
        )
        return np.concatenate([targets, self.instrument_params[self.n_arm :]])

    def split(self, params: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """``params`` ``(..., p)`` as the arm's and the instrument's."""
        params = np.asarray(params, dtype=float)
        return params[..., : self.n_arm], params[..., self.n_arm :]

    def _params(self, params: np.ndarray | None) -> np.ndarray:
        return self.nominal if params is None else np.asarray(params, dtype=float)

    # -- the arm's own ---------------------------------------------------------------

    @property
    def noise(self) -> NoiseModel | None:
        noise = self.inner.noise
        return None if noise is None else noise.for_dim(self.instrument.dim)

    def with_noise(self, noise: NoiseModel | None) -> InstrumentedArm:
        return replace(self, inner=self.inner.with_noise(noise))

    def with_fixed(self, fixed: Sequence[str]) -> InstrumentedArm:
        mine = set(self.instrument.param_names)
        theirs = (*_base_names(self.arm), *(n for n in fixed if n not in mine))
        arm = self.inner.with_fixed(tuple(dict.fromkeys(theirs)))
        return replace(self, inner=arm, instrument_fixed=tuple(n for n in fixed if n in mine))

    @property
    def n_joints(self) -> int:
        return int(self.inner.n_joints)

    @property
    def joint_limits(self) -> np.ndarray:
        return np.asarray(self.inner.joint_limits)

    @property
    def joint_kinds(self) -> tuple[str, ...]:
        return tuple(self.inner.joint_kinds)

    @property
    def joint_names(self) -> tuple[str, ...]:
        return tuple(self.inner.joint_names)

    @property
    def joint_map(self) -> np.ndarray:
        return np.asarray(self.inner.joint_map)

    def within_limits(self, q: np.ndarray, *, tol: float = 1e-9) -> np.ndarray:
        return np.asarray(self.inner.within_limits(q, tol=tol))

    @property
    def value_limits(self) -> np.ndarray | None:
        return self.inner.value_limits

    @property
    def target_labels(self) -> tuple[str, ...]:
        return tuple(self.inner.target_labels)

    @property
    def reach_mm(self) -> float:
        return float(self.inner.reach_mm)

    @property
    def tip_reach_mm(self) -> float:
        return float(self.inner.tip_reach_mm)

    @property
    def point_dim(self) -> int:
        return self.instrument.dim

    @property
    def position_dim(self) -> int:
        return self.instrument.dim

    def conditions(
        self,
        q: ArrayLike,
        *,
        target: ArrayLike | None = None,
        loads: Loads | None = None,
        sigma_mm: np.ndarray | None = None,
        feature: ArrayLike | None = None,
    ) -> Conditions:
        """The arm's conditions of the rows, with the feature every row touches (its
        index or its label among the instrument's)."""
        rows = self.inner.conditions(q, target=target, loads=loads, sigma_mm=sigma_mm)
        labels = self.instrument.labels
        index = target_indices(feature, labels, rows.m, what="feature")
        return replace(rows, feature=feature_index(index, rows.m, labels))

    def plan_conditions(self, q: np.ndarray, loads: Loads | None = None) -> Conditions:
        """The rows of a plan's poses: each touches the feature it is nearest to at the
        nominal parameters (the one it is on, for a pose that touches one)."""
        rows = self.inner.plan_conditions(q, loads)
        tool = self._tool(rows, self.split(self.nominal)[0])
        labels = self.instrument.labels
        each = [
            np.linalg.norm(
                self.instrument.miss(tool, np.full(rows.m, k), self.instrument.start), axis=-1
            )
            for k in range(len(labels))
        ]
        return replace(rows, feature=np.argmin(np.stack(each), axis=0))

    def meeting_poses(self, q: np.ndarray, params: np.ndarray | None = None) -> np.ndarray:
        """The poses moved onto the feature each is nearest to at ``params`` (default
        nominal) by Newton's smallest joint steps on the instrument's miss (module notes
        of :meth:`~armcal.models.interface.FitModel.meeting_poses`): the reading of a
        touch, a distance's excess over its range."""
        at = self._params(params)
        q = np.array(q, dtype=float)
        feature = self.plan_conditions(q).feature
        tol = _MEET_RTOL * self.reach_mm
        for _ in range(_MEET_STEPS):
            rows = self.conditions(q, feature=feature)
            jac = self.joint_jacobian(rows, at)  # its pass has the points the miss needs
            miss = self._miss(rows, at)
            if np.max(np.abs(miss), initial=0.0) <= tol:
                break
            q -= np.einsum("mnk,mk->mn", np.linalg.pinv(jac, rcond=1e-10), miss)
        miss = np.max(np.abs(self._miss(self.conditions(q, feature=feature), at)), axis=-1)
        return q[(miss <= tol) & self.feasible(q)]

    def _miss(self, rows: Conditions, params: np.ndarray) -> np.ndarray:
        x, theta = self.split(params)
        return self.instrument.miss(self._tool(rows, x), rows.feature, theta)

    # -- what the instrument reports ---------------------------------------------------------

    def _tool(self, conditions: Conditions, arm_params: np.ndarray) -> np.ndarray:
        return np.asarray(self.inner.positions(conditions, arm_params))[..., :3]

    def positions(self, conditions: Conditions, params: np.ndarray | None = None) -> np.ndarray:
        """What the instrument reports at every row ``(..., m, dim)`` (mm)."""
        x, theta = self.split(self._params(params))
        return self.instrument.reading(self._tool(conditions, x), conditions.feature, theta)

    def jacobian(self, conditions: Conditions, params: np.ndarray | None = None) -> np.ndarray:
        """``[dh/dp . dp/dx, dh/dtheta]`` ``(..., m, dim, p)``."""
        x, theta = self.split(self._params(params))
        arm_jacobian = np.asarray(self.inner.jacobian(conditions, x))[..., :3, :]
        by_point, by_theta = self.instrument.derivatives(
            self._tool(conditions, x), conditions.feature, theta
        )
        by_arm = by_point @ arm_jacobian
        by_theta = np.broadcast_to(by_theta, (*by_arm.shape[:-1], by_theta.shape[-1]))
        return np.concatenate([by_arm, by_theta], axis=-1)

    def joint_jacobian(
        self, conditions: Conditions, params: np.ndarray | None = None
    ) -> np.ndarray:
        """``dh/dp . dp/dq`` ``(..., m, dim, n)``."""
        x, theta = self.split(self._params(params))
        joint = np.asarray(self.inner.joint_jacobian(conditions, x))[..., :3, :]
        by_point, _ = self.instrument.derivatives(  # the points from the Jacobian's pass
            self._tool(conditions, x), conditions.feature, theta
        )
        return by_point @ joint

    # -- fitting -----------------------------------------------------------------------

    def step_scale(self, conditions: Conditions) -> np.ndarray:
        """A millimetre per mm; the reach per radian."""
        return np.where(self.angle_params, self.reach_mm, 1.0)

    def canonical(self, params: np.ndarray) -> np.ndarray:
        x, theta = self.split(params)
        return np.concatenate([self.inner.canonical(x), theta], axis=-1)

    def start(
        self, conditions: Conditions, points: np.ndarray, weights: np.ndarray | None = None
    ) -> np.ndarray:
        """Where the readings are met (:meth:`_seated`) from the nominal arm and where the
        user says the instrument is: once for the mean of sets of one experiment (a Monte
        Carlo's), else for every set (its rows of weight 0 left out)."""
        points = np.asarray(points, dtype=float)
        sets = points.reshape(-1, *points.shape[-2:])
        if weights is None:
            return np.tile(self._seated(conditions, sets.mean(axis=0)), (sets.shape[0], 1))
        w = np.broadcast_to(weights, sets.shape[:2])
        return np.array(
            [
                self._seated(conditions.take(wi > 0), s[wi > 0])
                for s, wi in zip(sets, w, strict=True)
            ]
        )

    def prepared(
        self, conditions: Conditions, points: np.ndarray | None = None
    ) -> InstrumentedArm:
        """The model with what the rows cannot separate held (module notes): the arm's
        rule on the rows of its columns, the instrument's projected out, at the arm that
        puts the readings where they were measured (:meth:`_seated`; the plan's poses
        are taken as meeting the instrument at nominal where there are no readings).

        A symmetry of a seating holds only where the tool sits in its feature: the
        whole arm turned about a fixed point keeps a tool that is *in* it there, and
        moves one a few mm off it.  At the nominal arm, which misses the features by
        the arm's errors, such a turn would look faintly seen, and be kept.
        """
        at = self.nominal if points is None else self._seated(conditions, points)
        triangle = self._rows(conditions, at)
        mine = self.instrument_params & self.free
        theta = triangle[:, mine]
        scale = np.linalg.norm(theta, axis=0)
        singular = np.linalg.svd(theta / np.where(scale > 0, scale, 1.0), compute_uv=False)
        if np.any(scale == 0) or (singular.size and singular[-1] <= _FIXES * singular[0]):
            raise ArmcalError(
                f"the rows do not fix the instrument ({self.instrument.kind}): touch every "
                "feature at poses spread over it (three touches not on a line fix a plane)"
            )
        rows = np.column_stack([triangle[:, : self.n_arm], theta])
        names = tuple(np.array(self.param_names)[mine])
        return replace(self, inner=self.inner.selected_by(rows, conditions, names))

    def _rows(self, conditions: Conditions, params: np.ndarray) -> np.ndarray:
        """The whitened Jacobian's triangle ``(p, p)`` of the rows at ``params``."""
        p = self.n_params
        rows = RowTriangle(p)
        for block, _ in conditions.blocks():
            jac = self.jacobian(block, params)
            w = self.whitening(block, params)
            rows.add((jac if w is None else w @ jac).reshape(-1, p))
        return rows.triangle()

    def _seated(self, conditions: Conditions, points: np.ndarray) -> np.ndarray:
        """Parameters that put the readings at ``points``: Gauss-Newton's minimum-norm
        steps over every free parameter from the nominal ones, directions seen by less
        than :data:`_SEAT_RCOND` of the best left alone (a step along one would be long
        and move the arm far from its nominal geometry), until a step moves no reading
        by 1e-9 of the reach."""
        x = self.nominal.copy()
        free = self.free
        goal = np.asarray(points, dtype=float)
        for _ in range(_SEAT_STEPS):
            jac = self.jacobian(conditions, x)[..., free].reshape(goal.size, -1)
            miss = (goal - self.positions(conditions, x)).reshape(-1)  # the same pass's
            scale = np.linalg.norm(jac, axis=0)
            scale = np.where(scale > 0, scale, 1.0)
            u, sv, vt = np.linalg.svd(jac / scale, full_matrices=False)
            damped = sv / (sv**2 + (_SEAT_RCOND * sv[0]) ** 2)
            step = (vt.T @ (damped * (u.T @ miss))) / scale
            x[free] += step
            if np.max(np.abs(jac @ step), initial=0.0) <= 1e-9 * self.reach_mm:
                break
        return x

    @property
    def held_reasons(self) -> tuple[Held, ...]:
        return tuple(self.inner.held_reasons)

    @property
    def rule_held(self) -> tuple[str, ...]:
        return tuple(self.inner.rule_held)

    def expressed(self, conditions: Conditions, params: np.ndarray) -> np.ndarray:
        return refit_free(self, conditions, params)


#: An instrument's parameters are fixed by the rows when their scaled columns' smallest
#: singular value is above this fraction of the largest.
_FIXES = 1e-9

#: Newton's steps of :meth:`InstrumentedArm.meeting_poses` at most, and how near (a
#: fraction of the reach) a pose meets its feature.
_MEET_STEPS = 30
_MEET_RTOL = 1e-12

#: Gauss-Newton steps of :meth:`InstrumentedArm._seated` at most, and the relative
#: singular value (of the unit-norm columns) below which a direction is left alone.
_SEAT_STEPS = 100
_SEAT_RCOND = 1e-3


def _base_names(arm: FitModel) -> tuple[str, ...]:
    """The arm's base pose in the instrument's frame: its ``base.`` parameters."""
    return tuple(
        n for n, mine in zip(arm.param_names, arm.instrument_params, strict=True)
        if mine and n.startswith("base.")
    )  # fmt: skip
