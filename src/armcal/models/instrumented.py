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

An instrument that reads the tool anywhere (partial coordinates) has no
symmetry that holds only where the tool meets it: its rows are judged at the
nominal arm, as a tracker's, and its features are read at every pose at once
(a pose is a row per axis read, :meth:`InstrumentedArm.plan_conditions`), each
with its own sigma (:attr:`InstrumentedArm.feature_sigma`).
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
from ..noise import NoiseModel, relative_noise
from ..numerics import RowTriangle, nearest_in
from .core import CoreModel
from .information import (
    BlockInformation,
    Linearization,
    pose_derivative,
    refit_free,
    whitened_blocks,
)
from .interface import (
    Conditions,
    DesignEffort,
    DeviationBounds,
    FitModel,
    Held,
    Loads,
    target_indices,
)

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
        frame, where the instrument's parameters are given; on its one tool point (which
        names a tool's turns)."""
        held = tuple(dict.fromkeys((*arm.fixed, *_base_names(arm))))
        labels = tuple(arm.target_labels)
        if len(labels) == 1:
            instrument = instrument.for_tool(labels[0])
        return cls(arm.with_fixed(held), instrument, tuple(instrument.held))

    # -- names and parameters ----------------------------------------------------------

    @property
    def base_names(self) -> tuple[str, ...]:
        """The arm's base pose, held at the origin of its frame."""
        return _base_names(self.inner)

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
        """``"instrumented"``: the edge's pieces wrap the arm's own family's
        (:mod:`armcal.families`)."""
        return "instrumented"

    @property
    def n_arm(self) -> int:
        """The arm's parameters: the first of the model's."""
        return int(self.inner.n_params)

    @property
    def param_names(self) -> tuple[str, ...]:
        return tuple(self.inner.param_names) + self.instrument.param_names

    @property
    def param_units(self) -> tuple[str, ...]:
        """Display units: an instrument's angle (rad inside) is shown in degrees."""
        mine = tuple("deg" if u == "rad" else u for u in self.instrument.param_units)
        return tuple(self.inner.param_units) + mine

    @property
    def display_scale(self) -> np.ndarray:
        mine = np.where(np.array(self.instrument.param_units) == "rad", 180.0 / np.pi, 1.0)
        return np.concatenate([self.inner.display_scale, mine])

    @cached_property
    def fixed(self) -> tuple[str, ...]:
        return tuple(self.inner.fixed) + self.instrument_fixed

    @cached_property
    def free(self) -> np.ndarray:
        held = set(self.fixed)
        return np.array([name not in held for name in self.param_names], dtype=bool)

    @cached_property
    def nominal(self) -> np.ndarray:
        """The arm's nominal parameters with its base at the origin, then where the user
        says the instrument is."""
        arm = np.array(self.inner.nominal, dtype=float)
        arm[np.isin(self.inner.param_names, _base_names(self.inner))] = 0.0
        return np.concatenate([arm, self.instrument.start])

    @property
    def deviation_bounds(self) -> DeviationBounds:
        """The arm's; the instrument's parameters are no deviation of the robot."""
        return self.inner.deviation_bounds.extended(len(self.instrument.param_names))

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

    @cached_property
    def noise(self) -> NoiseModel | None:
        """The arm's noise for the instrument's readings; where its features' sigmas differ
        (:attr:`feature_sigma`: ``sigma_mm = [sx, sy, sz]`` of partial coordinates) the
        arm's own, as the robot file gave it, every row carrying its feature's sigma
        (:meth:`conditions`)."""
        noise = self.inner.noise
        if noise is None or self.feature_sigma is not None:
            return noise
        return noise.for_dim(self.instrument.dim)

    def _core_noise(self, noise: NoiseModel | None) -> NoiseModel:
        """The noise of a reading: of the reference sigma where the features' differ (each
        row's own sigma is then its feature's)."""
        found = relative_noise(self.noise if noise is None else noise)
        if self.feature_sigma is not None and found.dim != self.instrument.dim:
            return NoiseModel.isotropic(found.sigma_mm, found.joint_sigma, dim=self.instrument.dim)
        return found.for_dim(self.instrument.dim)

    @cached_property
    def feature_sigma(self) -> np.ndarray | None:
        """Every feature's reading std (mm) where they differ (a partial instrument's axes of
        ``sigma_mm = [sx, sy, sz]``): every row without a sigma of its own is given its
        feature's (:meth:`conditions`)."""
        noise = self.inner.noise
        return None if noise is None else self.instrument.feature_sigma(noise)

    def with_noise(self, noise: NoiseModel | None) -> InstrumentedArm:
        return replace(self, inner=self.inner.with_noise(noise))

    def with_fixed(self, fixed: Sequence[str]) -> InstrumentedArm:
        mine = set(self.instrument.param_names)
        theirs = (*_base_names(self.inner), *(n for n in fixed if n not in mine))
        arm = self.inner.with_fixed(tuple(dict.fromkeys(theirs)))
        held = (*self.instrument.held, *(n for n in fixed if n in mine))
        return replace(self, inner=arm, instrument_fixed=tuple(dict.fromkeys(held)))

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
        """The arm's conditions of the rows, with the feature every row touches or reads
        (its index or its label among the instrument's), and the sigma of its feature
        where the features' differ and the row has none of its own."""
        rows = self.inner.conditions(q, target=target, loads=loads, sigma_mm=sigma_mm)
        labels = self.instrument.labels
        index = feature_index(
            target_indices(feature, labels, rows.m, what="feature"), rows.m, labels
        )
        return self._with_feature(rows, index)

    def _with_feature(self, rows: Conditions, feature: np.ndarray) -> Conditions:
        sigma = rows.sigma_mm
        if sigma is None and self.feature_sigma is not None:
            sigma = self.feature_sigma[feature]
        return replace(rows, feature=feature, sigma_mm=sigma)

    def plan_conditions(self, q: np.ndarray, loads: Loads | None = None) -> Conditions:
        """The rows of a plan's poses: each touches the feature it is nearest to at the
        nominal parameters (the one it is on, for a pose that touches one); a pose of an
        instrument that reads every feature at once is a row per feature, one after
        the other."""
        labels = self.instrument.labels
        if self.instrument.reads_every_feature:
            k = len(labels)
            q = np.asarray(q, dtype=float)
            many = None if loads is None else loads.repeat(k)
            rows = self.inner.plan_conditions(np.repeat(q, k, axis=-2), many)
            found = self._with_feature(rows, np.tile(np.arange(k), q.shape[-2]))
            if q.ndim == 2:  # every pose once for the arm, known without a sort
                poses = self.inner.plan_conditions(q, loads)
                found.memo(_ARM_ROWS, lambda: (poses, np.repeat(np.arange(q.shape[0]), k)))
            return found
        rows = self.inner.plan_conditions(q, loads)
        tool = self._tool(rows, self.split(self.nominal)[0])
        each = [
            np.linalg.norm(
                self.instrument.miss(tool, np.full(rows.m, k), self.instrument.start), axis=-1
            )
            for k in range(len(labels))
        ]
        return self._with_feature(rows, np.argmin(np.stack(each), axis=0))

    @property
    def constrained(self) -> bool:
        """Whether a pose is measured only where the tool meets the instrument (a plane, a
        fixed point, a distance within range; not partial coordinates)."""
        return bool(self.instrument.constrained)

    @property
    def has_view(self) -> bool:
        """Whether the instrument's view is a region with an inside a pose keeps to (a
        camera's image less its margin, a turn's range: :meth:`view_constraints`)."""
        return self.instrument.view_box is not None or bool(self.instrument.has_slack)

    def view_constraints(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray] | None:
        """How far inside the instrument's view every reading of poses ``q`` ``(..., n)``
        lies, at the nominal parameters: ``g`` ``(..., c)`` (``reading - low`` then ``high
        - reading`` of each of the ``k`` features' readings, ``2 k dim`` values, then the
        instrument's slack, :meth:`~armcal.instruments.base.Instrument.slack`: a camera's
        corners' depth and tilt, a turn's range) and ``dg/dq`` ``(..., c, n)`` (the slack's
        as :meth:`_slack_rows` gives it); None without a view.  Where :meth:`meeting_poses` also
        asks that the board be in front of the lens, these are the smooth part."""
        if not self.has_view:
            return None
        box = self.instrument.view_box
        q = np.asarray(q, dtype=float)
        flat = q.reshape(-1, q.shape[-1])
        count, n = flat.shape
        g, dg = np.zeros((count, 0)), np.zeros((count, 0, n))
        if box is not None:
            rows = self.plan_conditions(flat)
            reading = self.positions(rows).reshape(count, -1)
            jac = self.joint_jacobian(rows).reshape(count, -1, n)
            g, dg = _box_rows(reading, jac, box)
        found = self._slack_rows(flat)
        if found is not None:
            g = np.concatenate([g, found[0]], axis=-1)
            dg = np.concatenate([dg, found[1]], axis=-2)
        return g.reshape(*q.shape[:-1], -1), dg.reshape(*q.shape[:-1], -1, n)

    def _slack_rows(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray] | None:
        """The slack of poses ``q`` ``(k, n)`` pose by pose ``(k, rows s)`` and its joint
        derivatives ``(k, rows s, n)``: the instrument's by the tool's, by the chain rule
        where it gives them (a turn's range, a camera's depth and tilt), else central
        differences; None without a slack."""
        if not self.instrument.has_slack:
            return None
        slack, rows, tool = self._slack_of(q)
        x, theta = self.split(self.nominal)
        assert slack is not None
        by_tool = self.instrument.slack_derivatives(tool, rows.feature, theta)
        if by_tool is None:
            by_q = pose_derivative(lambda x: np.asarray(self._slack(x)), q, _SLACK_STEP)
            return slack, by_q
        by_q = self._by_arm(by_tool, rows, x, joints=True)  # (rows, s, n)
        return slack, by_q.reshape(q.shape[0], -1, q.shape[-1])

    def _slack(self, q: np.ndarray) -> np.ndarray | None:
        """The instrument's :meth:`~armcal.instruments.base.Instrument.slack` of every
        row of poses ``q`` ``(k, n)`` at the nominal parameters, pose by pose ``(k,
        rows s)``; None for an instrument without."""
        return self._slack_of(q)[0]

    def _slack_of(self, q: np.ndarray) -> tuple[np.ndarray | None, Conditions, np.ndarray]:
        """:meth:`_slack`, with the rows and the tool it was found at (its derivative's)."""
        rows = self.plan_conditions(q)
        x, theta = self.split(self.nominal)
        tool = self._tool(rows, x)
        found = self.instrument.slack(tool, rows.feature, theta)
        return (None if found is None else found.reshape(q.shape[0], -1)), rows, tool

    def feasible(self, q: np.ndarray, *, tol: float = 1e-9) -> np.ndarray:
        """Within the limits, and within the instrument's slack where it has one (a
        camera's nearest depth and largest tilt, a turn's range, at the nominal
        parameters)."""
        inside = np.asarray(super().feasible(q, tol=tol))
        q = np.asarray(q, dtype=float)
        flat = q.reshape(-1, q.shape[-1])
        if not self.instrument.has_slack or not flat.shape[0]:
            return inside
        slack = self._slack(flat)
        if slack is None:
            return inside
        return inside & (slack.min(axis=-1) >= -tol).reshape(q.shape[:-1])

    def alone(
        self, params: np.ndarray, covariance: np.ndarray
    ) -> tuple[FitModel, np.ndarray, np.ndarray]:
        """The arm in its own base frame, where the instrument was placed, with its
        parameters and their covariance (the instrument's dropped: the marginal); without
        noise where the instrument's is not in mm (a camera's pixels say nothing of where
        the tool is)."""
        k = self.n_arm
        arm = self.inner if self.reading_unit == "mm" else self.inner.with_noise(None)
        return arm, np.asarray(params)[:k], np.asarray(covariance)[:k, :k]

    @property
    def feature_labels(self) -> tuple[str, ...]:
        """The instrument's features (its planes, its points; a distance's pivot)."""
        return self.instrument.labels

    @property
    def reading_unit(self) -> str:
        """The instrument's: ``"mm"``, a camera's ``"px"``."""
        return str(self.instrument.unit)

    def turn_rows(self, conditions: Conditions) -> np.ndarray | None:
        """The rows of the instrument's features that read angles (partial coordinates'
        turns), None for an instrument without."""
        turns = self.instrument.turn_features
        if not turns:
            return None
        index = feature_index(conditions.feature, conditions.m, self.instrument.labels)
        return np.isin(index, turns)

    @property
    def reads_turns(self) -> bool:
        """Whether the instrument has features that read angles (partial coordinates'
        turns)."""
        return bool(self.instrument.turn_features)

    @property
    def touches(self) -> bool:
        """Whether a row reports nothing but that it meets the instrument (a plane, a fixed
        point; a distance reports its reading)."""
        return not self.instrument.reading_columns

    def meeting_poses(
        self,
        q: np.ndarray,
        params: np.ndarray | None = None,
        miss: np.ndarray | None = None,
        feature: np.ndarray | None = None,
    ) -> tuple[np.ndarray, np.ndarray]:
        """The poses moved onto the feature each is nearest to (at the nominal parameters,
        or ``feature``) where ``params`` (default nominal) put it, by Newton's smallest joint
        steps on the instrument's miss, each taken back
        within the joint limits (a projected Newton: a pose whose plain steps would leave
        them meets the feature at the limit instead, where it can) (module notes
        of :meth:`~armcal.models.interface.FitModel.meeting_poses`): the reading of a
        touch, a distance's excess over its range; to ``miss`` ``(m, d)`` where given, on
        ``feature`` where given."""
        at = self._params(params)
        q = np.array(q, dtype=float)
        if not self.constrained:
            return q, self.feasible(q)
        every = self.instrument.reads_every_feature  # a photo: every corner of a pose
        k = len(self.instrument.labels) if every else 1
        if feature is None or every:
            feature = self.plan_conditions(q).feature
        assert feature is not None
        width = k * self.instrument.dim
        goal = np.zeros((q.shape[0], width)) if miss is None else miss
        goal = np.broadcast_to(np.asarray(goal, dtype=float), (q.shape[0], width))
        tol = _MEET_RTOL * self.reach_mm
        limits = self.joint_limits
        box = self.instrument.view_box if every else None

        def rows_of(poses: np.ndarray) -> Conditions:
            chosen = (poses[:, None] * k + np.arange(k)).ravel()
            rows = self.conditions(np.repeat(q[poses], k, axis=0), feature=feature[chosen])
            if every:  # every pose once for the arm, known without a sort
                once = self.inner.conditions(q[poses])
                rows.memo(_ARM_ROWS, lambda: (once, np.repeat(np.arange(poses.size), k)))
            return rows

        live = np.arange(q.shape[0])  # the poses still moving: each stops where it meets
        for _ in range(_MEET_STEPS):
            off = self._miss(rows_of(live), at).reshape(live.size, width) - goal[live]
            moving = np.max(np.abs(off), axis=-1, initial=0.0) > tol
            live, off = live[moving], off[moving]
            if not live.size:
                break
            rows = rows_of(live)
            full = self.joint_jacobian(rows, at).reshape(live.size, width, -1)
            jac = full
            if every:  # a row within the instrument's bounds may move freely within them
                jac = np.where((off == 0.0)[..., None], 0.0, jac)
            step = np.einsum("mnk,mk->mn", np.linalg.pinv(jac, rcond=1e-10), off)
            if every:  # a photo's many rows pull far: a step of a tenth of a turn at most
                size = np.max(np.abs(step), axis=-1, keepdims=True)
                step *= np.minimum(1.0, _MEET_STEP_RAD / np.maximum(size, 1e-300))
            if box is not None and miss is None:
                self._into_box(rows, at, full, off, step, box)
            q[live] = np.clip(q[live] - step, limits[:, 0], limits[:, 1])  # projected Newton
        everything = np.arange(q.shape[0])
        off = self._miss(rows_of(everything), at).reshape(q.shape[0], width) - goal
        # within the limits (not the slack a plan keeps to: where a pose is met again for
        # the true arm, the board seen whole is a photo)
        inside = np.all(self.within_limits(q), axis=-1)
        return q, (np.max(np.abs(off), axis=-1, initial=0.0) <= tol) & inside

    def _into_box(
        self,
        rows: Conditions,
        params: np.ndarray,
        full: np.ndarray,
        off: np.ndarray,
        step: np.ndarray,
        box: tuple[tuple[float, float], ...],
    ) -> None:
        """``step`` ``(m, n)`` (subtracted) of the poses a little outside the view box made
        the nearest joint step that puts every reading's linearization in it at once
        (:func:`~armcal.numerics.nearest_in`): Newton's steps on the readings outside
        alone push those on the edge out, and crawl (a camera's pose at a plan's edge,
        met again for the true arm: 12 steps did not reach it).  A pose whose readings
        lie :data:`_INTO_BOX_PX` or more outside keeps Newton's step."""
        near = np.flatnonzero(np.max(np.abs(off), axis=-1) < _INTO_BOX_PX)
        if not near.size:
            return
        count, width, n = full.shape  # the readings' joint Jacobian (m, width, n)
        g, dg = _box_rows(self.positions(rows, params).reshape(count, width), full, box)
        for i in near:
            step[i] = -nearest_in(dg[i], -g[i], np.zeros(n))

    def _miss(self, rows: Conditions, params: np.ndarray) -> np.ndarray:
        x, theta = self.split(params)
        return self.instrument.miss(self._tool(rows, x), rows.feature, theta)

    def orientation_joint_jacobian(
        self, conditions: Conditions, params: np.ndarray | None = None
    ) -> np.ndarray:
        """The tool's angular velocity per reading ``(..., m, 3, n)``: the arm's."""
        x, _ = self.split(self._params(params))
        return np.asarray(self.inner.orientation_joint_jacobian(conditions, x))

    # -- what the instrument reports ---------------------------------------------------------

    @property
    def _frame(self) -> bool:
        """Whether the instrument reads the tool's frame, not only its point (a camera)."""
        return bool(self.instrument.frame)

    def _arm_rows(self, conditions: Conditions) -> tuple[Conditions, np.ndarray | None]:
        """The rows the arm is evaluated at: every pose once where the instrument reads
        several features at each (a photo's 48 corners: the arm's kinematics once, not 48
        times), with the index that spreads them back to the rows; else the rows."""
        if (
            not self.instrument.reads_every_feature
            or np.ndim(conditions.q) != 2
            or conditions.m < 2
        ):
            return conditions, None

        def once() -> tuple[Conditions, np.ndarray | None]:
            q = np.asarray(conditions.q)
            _, first, inverse = np.unique(q, axis=0, return_index=True, return_inverse=True)
            if first.size == q.shape[0]:
                return conditions, None
            return conditions.take(first), np.asarray(inverse).reshape(-1)

        found: tuple[Conditions, np.ndarray | None] = conditions.memo(_ARM_ROWS, once)
        return found

    def _tool(self, conditions: Conditions, arm_params: np.ndarray) -> np.ndarray:
        """What the instrument reads of the tool: its point ``(..., m, 3)``; for one that
        reads its frame, the tip's origin and rotation, row by row ``(..., m, 12)``."""
        rows, back = self._arm_rows(conditions)
        points = np.asarray(self.inner.positions(rows, arm_params))[..., :3]
        if self._frame:
            rotation = np.asarray(self.inner.tip_rotation(rows, arm_params))
            flat = rotation.reshape(*rotation.shape[:-2], 9)
            points = np.concatenate([points, flat], axis=-1)
        return points if back is None else points[..., back, :]

    def _by_arm(
        self,
        by_tool: np.ndarray,
        conditions: Conditions,
        arm_params: np.ndarray,
        *,
        joints: bool,
    ) -> np.ndarray:
        """``by_tool @ J`` ``(..., m, d, k)`` of every row's derivative by the tool ``(...,
        m, d, 3 or 6)`` and the arm's Jacobian ``J`` (:meth:`_arm_jacobian`), a pose's once
        for all its rows: multiplied :data:`ROW_CHUNK` rows at a time, never repeated row
        by row (a certificate's 20 000 photos of 48 corners: 2.3 GB of one pose's Jacobian
        48 times)."""
        arm, back = self._arm_jacobian(conditions, arm_params, joints=joints)
        if back is None:
            return by_tool @ arm
        out = np.empty((*by_tool.shape[:-1], arm.shape[-1]))
        for start in range(0, back.size, ROW_CHUNK):
            part = slice(start, start + ROW_CHUNK)
            out[..., part, :, :] = by_tool[..., part, :, :] @ arm[..., back[part], :, :]
        return out

    def _arm_jacobian(
        self, conditions: Conditions, arm_params: np.ndarray, *, joints: bool
    ) -> tuple[np.ndarray, np.ndarray | None]:
        """The tool point's Jacobian ``(..., poses, 3, k)`` in the arm's parameters
        (``joints``: in the joints), with the tip's angular one below it for an instrument
        that reads the tool's frame ``(..., poses, 6, k)``; each pose's once, with the
        index of every row's pose (None: a row each)."""
        rows, back = self._arm_rows(conditions)
        turn = None
        if self._frame:  # first: the arm keeps this pass for the point's Jacobian next
            turn = (
                self.inner.orientation_joint_jacobian(rows, arm_params)
                if joints
                else self.inner.orientation_jacobian(rows, arm_params)
            )
        if joints:
            found = np.asarray(self.inner.joint_jacobian(rows, arm_params))[..., :3, :]
        else:
            found = np.asarray(self.inner.jacobian(rows, arm_params))[..., :3, :]
        if turn is not None:
            found = np.concatenate([found, np.asarray(turn)], axis=-2)
        return found, back

    def positions(self, conditions: Conditions, params: np.ndarray | None = None) -> np.ndarray:
        """What the instrument reports at every row ``(..., m, dim)`` (mm)."""
        x, theta = self.split(self._params(params))
        return self.instrument.reading(self._tool(conditions, x), conditions.feature, theta)

    def jacobian(self, conditions: Conditions, params: np.ndarray | None = None) -> np.ndarray:
        """``[dh/dp . dp/dx, dh/dtheta]`` ``(..., m, dim, p)`` (with the tool's turn
        ``dh/dw . dw/dx`` for an instrument that reads its frame)."""
        x, theta = self.split(self._params(params))
        by_point, by_theta = self.instrument.derivatives(
            self._tool(conditions, x), conditions.feature, theta
        )
        by_arm = self._by_arm(by_point, conditions, x, joints=False)
        by_theta = np.broadcast_to(by_theta, (*by_arm.shape[:-1], by_theta.shape[-1]))
        return np.concatenate([by_arm, by_theta], axis=-1)

    def joint_jacobian(
        self, conditions: Conditions, params: np.ndarray | None = None
    ) -> np.ndarray:
        """``dh/dp . dp/dq`` ``(..., m, dim, n)`` (and ``dh/dw . dw/dq``)."""
        x, theta = self.split(self._params(params))
        by_point = self.instrument.tool_derivatives(
            self._tool(conditions, x), conditions.feature, theta
        )
        return self._by_arm(by_point, conditions, x, joints=True)

    # -- design ------------------------------------------------------------------------

    @property
    def design_effort(self) -> DesignEffort:
        """The arm's own, its certificate's sample of :data:`CERTIFICATE_SAMPLE` poses
        where a pose must meet the instrument: the poses that meet it are a thin set of
        the joint space (a touch, a seating) or a small one (a camera's, the whole board
        in view, near enough and not too oblique), whose variance function's maxima lie
        apart (a face's far corner, another face), and a sample of the arm's own 3000
        misses some (found by a dense search of 20 000,
        ``tests/test_instrument_design.py``; a camera's, 35.0 against the certificate's
        30.3)."""
        effort = self.inner.design_effort
        if not self.constrained:  # a turn's range: its maxima on its edge, kept step by step
            return replace(effort, bounded=True) if self.has_view else effort
        if self.has_view:  # a camera's hills are many: ascents from more of them
            effort = replace(effort, last_starts=LAST_STARTS_IN_VIEW)
        return replace(effort, search=CERTIFICATE_SAMPLE)

    def plan_information(
        self, q: np.ndarray, loads: Loads | None = None, *, rows: Conditions | None = None
    ) -> BlockInformation:
        """The rows' information, its gradient in the poses in closed form where the arm
        gives its own (:meth:`linearize`)."""
        return BlockInformation(self, q, loads, linearize=self.linearize, rows=rows)

    @cached_property
    def _bare_linearize(self) -> Any:
        """The arm's own linearization of its points unwhitened (the instrument whitens),
        where its family has one (optional: central differences without); made once, not
        at every step of a design's search."""
        return getattr(self.inner.with_noise(None), "linearize", None)

    def linearize(self, conditions: Conditions) -> Linearization:
        """The rows' whitened blocks ``W [B J_x, D]`` at the nominal parameters and their
        pullback in the poses, from the arm's own (``B``, ``D`` the instrument's
        derivatives by the point and by its parameters, ``J_x`` the arm's point Jacobian).

        ``<G, d(B J_x)/dq> = <B^T G_x, dJ_x/dq> + <G_x J_x^T, dB/dq>`` and
        ``<G_t, dD/dq>``; ``dB/dq = H J_q`` and ``dD/dq = K J_q`` with the instrument's
        curvatures ``H``, ``K`` (:meth:`~armcal.instruments.base.Instrument.curvatures`)
        and ``J_q`` the point's joint Jacobian: the arm's pullback of ``B^T G_x``, plus
        ``(sum G_x J_x^T H + sum G_t K) J_q``.  Without the arm's pullback (a family
        without one, noise that moves with the poses, rows' own sigmas) the blocks
        alone: central differences then.  The rows' own sigmas weigh them alike at every
        pose."""
        arm_linearize = self._bare_linearize
        noise = self.noise
        moving = noise is not None and (noise.joint_sigma is not None or noise.tracker is not None)
        x, theta = self.split(self.nominal)
        if (
            arm_linearize is None
            or moving
            or self._frame  # no curvatures of a frame's reading: central differences
            or not np.array_equal(x, self.inner.nominal)
        ):
            return Linearization(whitened_blocks(self, conditions), None)
        arm = arm_linearize(replace(conditions, sigma_mm=None))  # unwhitened: W is below
        if arm.pullback is None:
            return Linearization(whitened_blocks(self, conditions), None)
        tool = self._tool(conditions, x)
        by_point, by_theta = self.instrument.derivatives(tool, conditions.feature, theta)
        bend, twist = self.instrument.curvatures(tool, conditions.feature, theta)
        joints = np.asarray(self.inner.joint_jacobian(conditions, x))[..., :3, :]
        mine = self.free[self.n_arm :]
        jac_x = arm.blocks  # (m, 3, free arm)
        blocks = np.concatenate([by_point @ jac_x, by_theta[..., mine]], axis=-1)
        w = self.whitening(conditions, None)
        if w is not None:
            blocks = w @ blocks
        k = jac_x.shape[-1]
        pullback = arm.pullback

        def pulled(cotangent: np.ndarray) -> np.ndarray:
            g = cotangent if w is None else np.swapaxes(w, -1, -2) @ cotangent
            g_x, g_t = g[..., :k], g[..., k:]
            out = pullback(np.swapaxes(by_point, -1, -2) @ g_x)
            v = np.zeros(joints.shape[:-1])
            if bend is not None:
                v += np.einsum("mda,mdab->mb", g_x @ np.swapaxes(jac_x, -1, -2), bend)
            if twist is not None:
                v += np.einsum("mdt,mdtb->mb", g_t, twist[..., mine, :])
            return out + np.einsum("mb,mbn->mn", v, joints)

        return Linearization(blocks, pulled)

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
        """Where the readings are met (:meth:`_seated`; registered, for an instrument that
        reads the tool anywhere) from the nominal arm and where the user says the
        instrument is: once for the mean of sets of one experiment (a Monte
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
        seated = points is not None and self._seats  # a tracker's is the nominal arm
        at = self._seated(conditions, points) if points is not None and seated else self.nominal
        triangle = self._rows(conditions, at)
        mine = self.instrument_params & self.free
        theta = triangle[:, mine]
        scale = np.linalg.norm(theta, axis=0)
        singular = np.linalg.svd(theta / np.where(scale > 0, scale, 1.0), compute_uv=False)
        if np.any(scale == 0) or (singular.size and singular[-1] <= _FIXES * singular[0]):
            raise ArmcalError(
                f"the rows do not fix the instrument ({self.instrument.kind}): measure every "
                "feature (plane, point, axis read, corner) at poses spread over it (three "
                "touches not on a line fix a plane; an axis of partial coordinates needs "
                "readings of its own)"
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
        by 1e-9 of the reach.

        An instrument that reads the tool anywhere (partial coordinates), or every
        corner of a board (a camera), has no symmetry that holds only where the tool
        meets it (:attr:`_seats`): the nominal arm is where its rows are judged
        (:meth:`prepared`), as a tracker's, and the fit starts from the instrument's
        parameters alone fitted to the readings (a registration), the arm's at nominal:
        those of the arm its readings barely see would move far."""
        x = self.nominal.copy()
        free = self.free if self._seats else self.free & self.instrument_params
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
    def _seats(self) -> bool:
        """Whether the rows meet one feature each where the arm is judged and the fit starts
        (a touch, a seating, a distance: :meth:`_seated`); not an instrument that reads the
        tool anywhere, nor a photo of every corner, whose rows are judged at the nominal
        arm and fitted from a registration."""
        return self.constrained and not self.instrument.reads_every_feature

    @property
    def held_reasons(self) -> tuple[Held, ...]:
        return tuple(self.inner.held_reasons)

    @property
    def rule_held(self) -> tuple[str, ...]:
        return tuple(self.inner.rule_held)

    def expressed(self, conditions: Conditions, params: np.ndarray) -> np.ndarray:
        return refit_free(self, conditions, params)


#: The memo slot of :meth:`InstrumentedArm._arm_rows`.
_ARM_ROWS = "instrumented arm: every pose once"

#: Poses that meet the instrument the certificate's search samples (:attr:`design_effort`).
CERTIFICATE_SAMPLE = 20_000

#: Ascents of a certificate's last search within a view with an inside (a camera's): its
#: variance function has many hills (the board's corners on the image's edges, near, at
#: the largest tilt, in many combinations), and 32 ascents missed one a dense search found.
LAST_STARTS_IN_VIEW = 128

#: An instrument's parameters are fixed by the rows when their scaled columns' smallest
#: singular value is above this fraction of the largest.
_FIXES = 1e-9

#: Newton's steps of :meth:`InstrumentedArm.meeting_poses` at most, and how near (a
#: fraction of the reach, above the readings' round-off of about 2e-16 of the reach) a
#: pose meets its feature.  From random poses within the limits, 12 steps meet 88 % to 100 %
#: of those 40 steps meet (a plane, a distance; 78 % for a fixed point, whose three
#: equations pull a pose farther); the rest creep along a limit, and are better drawn
#: anew than followed: a search's step from a pose that meets takes 3 or 4.
_MEET_STEPS = 12
_MEET_RTOL = 1e-14

#: Rows whose derivatives by the tool meet their pose's arm Jacobian at a time
#: (:meth:`InstrumentedArm._by_arm`): a few MB of the repeated Jacobian at once.
ROW_CHUNK = 8192

#: The joint step (rad) of the central differences of an instrument's slack.
_SLACK_STEP = 1e-6


def _box_rows(
    reading: np.ndarray, jac: np.ndarray, box: tuple[tuple[float, float], ...]
) -> tuple[np.ndarray, np.ndarray]:
    """How far inside ``box`` every reading ``(k, w)`` of a pose lies, ``reading - low``
    then ``high - reading`` ``(k, 2 w)``, and their joint derivatives ``(k, 2 w, n)``
    from the readings' ``jac`` ``(k, w, n)``; the box is per reading component, repeated
    over the features."""
    low, high = (np.tile(side, reading.shape[-1] // len(box)) for side in np.asarray(box).T)
    g = np.concatenate([reading - low, high - reading], axis=-1)
    return g, np.concatenate([jac, -jac], axis=-2)


#: How far outside its view box (px) a reading may lie for its pose to be moved in by
#: the nearest step of the box's linearization (:meth:`InstrumentedArm._into_box`): a
#: pose near the box, where the linearization holds.
_INTO_BOX_PX = 200.0

#: The largest joint step (rad) of a pose moved until a camera sees the whole board: its
#: 96 equations' Newton steps, from a pose that sees little of it, are long, and a pose
#: clipped at several limits at once lands where others did (the same pose, twice).
_MEET_STEP_RAD = 0.6

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
