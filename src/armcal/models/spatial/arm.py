"""A spatial serial arm as a fit model: :class:`SpatialArm`.

The arm is a :class:`~armcal.models.spatial.chain.SerialChain` (from a URDF or a
modified DH table) read through a joint map; its parameters are those of
:mod:`~armcal.models.spatial.kinematics` (base pose, every joint's placement
error and zero, every target's position), of which the measurements at hand
identify a subset chosen by :mod:`~armcal.models.spatial.selection`
(:meth:`SpatialArm.prepared`).  The base pose and the targets start where
:mod:`~armcal.models.spatial.registration` puts them.  Every method of
:class:`~armcal.models.interface.FitModel` is a thin call into those modules or
into the generic ones of :mod:`~armcal.models.information`.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field, fields, replace
from functools import cached_property
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from ...noise import NoiseModel, relative_noise
from ...numerics import RowTriangle
from ..core import CoreModel
from ..information import (
    known_start,
    nominal_triangle_known,
    refit_free,
    start_known,
)
from ..interface import (
    ROW_BLOCK,
    Conditions,
    DeviationBounds,
    Held,
    LinearPositions,
    Loads,
    refuse_feature,
    target_indices,
    targets_missing,
)
from ..joint_maps import checked_joint_map
from . import pose as spatial_pose
from .chain import (
    SerialChain,
    elementary,
    joint_motion,
    matrix_rpy,
    rotation_vector,
    rpy_matrix,
    transform,
    vector_rotation,
)
from .design import SpatialDesign
from .kinematics import (
    ChainKinematics,
    SpatialLayout,
    base_turn_axes,
    cross,
    default_targets,
    deviation_bounds,
    kinematics,
    target_columns_into,
)
from .registration import register, registered_targets
from .selection import select_from_rows
from .tool import SpatialTool
from .view import SpatialView

__all__ = [
    "SINGLE_TARGET",
    "SpatialArm",
]


#: The label of the one target of data without a target column.
SINGLE_TARGET = "tool"


@dataclass(frozen=True, eq=False)
class SpatialArm(SpatialDesign, SpatialTool, CoreModel):
    """A spatial serial arm to calibrate.

    Attributes
    ----------
    chain : SerialChain
        The nominal kinematics.
    name : str
    joint_map : ndarray, shape (n, n)
        ``u = M q``: the chain's joint values from the controller's readings.
    limits : ndarray, shape (n, 2)
        Limits of the readings ``q`` (rad, mm).
    targets : tuple of str
        Target labels (``("tool",)`` for data without a target column).
    target_positions : ndarray, shape (k, 3)
        Nominal positions of the targets in the tip frame (mm).
    base_pose : ndarray, shape (6,)
        Nominal base pose (mm, rad): identity until registered to data.
    noise : NoiseModel or None
        3-D instrument noise (and encoder noise).
    user_fixed : tuple of str
        Parameters the user holds.
    held : tuple of str
        Parameters left out by the identifiable-set rule for the measurements
        at hand (:meth:`prepared`).
    merges : tuple of Held
        Why they are left out, one record per group.
    known_targets : bool
        Whether the robot file gives the targets' positions.
    oriented : bool
        Whether the instrument measures every target's orientation too (a 6-DoF
        probe): a point is then ``(x, y, z)`` and a rotation vector, and every
        target's orientation is a parameter.
    target_turns : ndarray, shape (k, 3)
        Nominal orientations of the targets in the tip frame (rotation vectors,
        rad): zero until registered to data.
    view : SpatialView or None
        What the instrument can measure, for plans (:mod:`~armcal.models.spatial.view`).
    """

    chain: SerialChain
    name: str = "arm"
    joint_map: np.ndarray = field(default_factory=lambda: np.zeros((0, 0)))
    limits: np.ndarray = field(default_factory=lambda: np.zeros((0, 2)))
    targets: tuple[str, ...] = (SINGLE_TARGET,)
    target_positions: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))
    base_pose: np.ndarray = field(default_factory=lambda: np.zeros(6))
    noise: NoiseModel | None = None
    user_fixed: tuple[str, ...] = ()
    held: tuple[str, ...] = ()
    merges: tuple[Held, ...] = ()
    known_targets: bool = False
    oriented: bool = False
    target_turns: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))
    view: SpatialView | None = None

    @property
    def family(self) -> str:
        """``"spatial"``: the registry's key (:mod:`armcal.families`)."""
        return "spatial"

    @property
    def value_limits(self) -> np.ndarray:
        """The chain's joint limits (a URDF's), on the joint values ``u = M q``."""
        return self.chain.joint_limits

    @property
    def joint_names(self) -> tuple[str, ...]:
        """The chain's joint names (a URDF's)."""
        return self.chain.joint_names

    @property
    def rule_held(self) -> tuple[str, ...]:
        """The parameters :mod:`~armcal.models.spatial.selection` holds."""
        return self.held

    def __post_init__(self) -> None:
        n = self.chain.n_joints
        if self.joint_map.size == 0:
            object.__setattr__(self, "joint_map", np.eye(n))
        checked_joint_map(self.joint_map, n)
        if self.limits.size == 0:
            object.__setattr__(self, "limits", self._limits_from_chain())
        if self.limits.shape != (n, 2) or not np.all(self.limits[:, 0] < self.limits[:, 1]):
            raise ValueError(f"joint limits must have shape ({n}, 2) with lo < hi")
        if not self.targets or len(set(self.targets)) != len(self.targets):
            raise ValueError("targets need distinct labels")
        if self.target_positions.size == 0:
            object.__setattr__(self, "target_positions", default_targets(len(self.targets)))
        if self.target_positions.shape != (len(self.targets), 3):
            raise ValueError("one nominal position (x, y, z) per target")
        if not np.any(self.target_turns):  # none given (or all zero for other targets)
            object.__setattr__(self, "target_turns", np.zeros((len(self.targets), 3)))
        if self.target_turns.shape != (len(self.targets), 3):
            raise ValueError("one nominal orientation (a rotation vector) per target")
        if self.noise is not None and self.noise.dim != 3:
            object.__setattr__(self, "noise", self.noise.for_dim(3))
        if self.noise is not None:
            self.noise.check_joints(n)
        unknown = [p for p in (*self.user_fixed, *self.held) if p not in self.layout.names]
        if unknown:
            raise ValueError(f"unknown parameters {unknown}; {self.name} has {self.layout.names}")

    def _limits_from_chain(self) -> np.ndarray:
        """Limits of ``q``: the chain's (of ``u``) for an identity map, else a turn each way;
        a continuous joint turns a full turn each way."""
        identity = np.array_equal(self.joint_map, np.eye(self.chain.n_joints))
        base = self.chain.joint_limits if identity else np.full((self.chain.n_joints, 2), np.inf)
        turn = np.where(self.chain.revolute, 2 * np.pi, 1000.0)[:, None] * np.array([-1.0, 1.0])
        return np.where(np.isfinite(base), base, turn)

    def replace(self, **changes: Any) -> SpatialArm:
        """The same arm with fields changed.

        New ``targets`` without their ``target_positions`` start where targets the robot
        file does not place start (:func:`~armcal.models.spatial.kinematics.default_targets`,
        found from the data by a fit), not at the old targets' positions.
        """
        new = tuple(changes.get("targets", self.targets)) != self.targets
        if new and "target_positions" not in changes:
            unplaced = np.zeros((0, 3))
            changes.update(target_positions=unplaced, target_turns=unplaced, known_targets=False)
        return replace(self, **changes)

    @cached_property
    def layout(self) -> SpatialLayout:
        return SpatialLayout(self.chain.kinds, self.targets, self.oriented)

    @cached_property
    def nominal(self) -> np.ndarray:
        """The nominal parameters ``(p,)``: base pose, zero errors, nominal targets."""
        out = np.zeros(self.layout.n_params)
        out[:6] = self.base_pose
        out[self.layout.target_start :] = self._target_block(
            self.target_positions, self.target_turns
        )
        return out

    def _target_block(self, positions: np.ndarray, turns: np.ndarray) -> np.ndarray:
        """The targets' parameters ``(k * size,)`` from their positions and orientations."""
        blocks = [positions, turns] if self.oriented else [positions]
        return np.concatenate(blocks, axis=-1).ravel()

    def _params(self, params: np.ndarray | None) -> np.ndarray:
        return self.nominal if params is None else np.asarray(params, dtype=float)

    def params_of(
        self,
        chain: SerialChain,
        base_pose: np.ndarray,
        targets: np.ndarray,
        turns: np.ndarray | None = None,
    ) -> np.ndarray:
        """This arm's parameters ``(p,)`` for the arm ``chain`` (same joints) with its base
        at ``base_pose`` (mm, rad) and its targets at ``targets`` ``(k, 3)`` in its tip frame,
        turned by ``turns`` ``(k, 3)`` there (rotation vectors; default none): exact,
        whatever the two descriptions' frames.

        Joint ``k``'s error is ``E_k = N_k^-1 T_k`` (nominal and true origins), split as
        ``T(x, y, z) Rx Ry Rz``; the turn about (or slide along) its axis is its zero.
        """
        if chain.kinds != self.chain.kinds:
            raise ValueError("the two descriptions must have the same joints")
        lay = self.layout
        out = np.zeros(lay.n_params)
        out[:6] = base_pose
        zero_u = np.zeros(self.n_joints)
        for k, kind in enumerate(chain.kinds):
            error = np.linalg.solve(self.chain.origins[k], chain.origins[k])
            rot, shift = error[:3, :3], error[:3, 3]
            ry = np.arcsin(np.clip(rot[0, 2], -1.0, 1.0))
            rx = np.arctan2(-rot[1, 2], rot[2, 2])
            rz = np.arctan2(-rot[0, 1], rot[0, 0])
            start = 6 + 5 * k
            if kind == "R":
                out[start : start + 5] = [*shift, rx, ry]
                zero_u[k] = rz
            else:  # slide the origin along the axis until its z is 0: that is the zero
                slide = shift[2] / rot[2, 2]
                moved = shift - rot[:, 2] * slide
                out[start : start + 5] = [moved[0], moved[1], rx, ry, rz]
                zero_u[k] = slide
        out[lay.zero_start : lay.target_start] = np.linalg.solve(self.joint_map, zero_u)
        tip = np.linalg.solve(self.chain.tip, chain.tip)
        local = np.asarray(targets, dtype=float) @ tip[:3, :3].T + tip[:3, 3]
        turned = np.zeros_like(local) if turns is None else np.asarray(turns, dtype=float)
        local_turns = rotation_vector(tip[:3, :3] @ vector_rotation(turned))
        out[lay.target_start :] = self._target_block(local, local_turns)
        return out

    def calibrated_chain(self, params: np.ndarray) -> SerialChain:
        """The chain whose joint origins carry ``params``' errors and zeros: its nominal
        kinematics are this arm's at ``params`` (base pose and targets aside)."""
        lay = self.layout
        errors = lay.placement_errors(np.asarray(params, dtype=float))
        zero_u = (
            self.joint_map @ np.asarray(params, dtype=float)[lay.zero_start : lay.target_start]
        )
        origins = np.empty_like(self.chain.origins)
        for k, kind in enumerate(self.chain.kinds):
            x, y, z, rx, ry, rz = errors[k]
            rot = elementary(0, rx) @ elementary(1, ry) @ elementary(2, rz)
            error = transform(rot, [x, y, z]) @ joint_motion(kind, zero_u[k])
            origins[k] = self.chain.origins[k] @ error
        return SerialChain(
            origins,
            self.chain.kinds,
            self.chain.tip,
            self.chain.joint_names,
            self.chain.joint_limits,
        )

    # -- what is identified ----------------------------------------------------------

    @property
    def param_names(self) -> tuple[str, ...]:
        return self.layout.names

    @property
    def param_units(self) -> tuple[str, ...]:
        return self.layout.units

    @property
    def display_scale(self) -> np.ndarray:
        return self.layout.display_scale

    @property
    def fixed(self) -> tuple[str, ...]:
        return tuple(n for n in self.layout.names if n in self.user_fixed or n in self.held)

    @cached_property
    def free(self) -> np.ndarray:
        held = set(self.fixed)
        return np.array([n not in held for n in self.layout.names])

    @property
    def free_names(self) -> tuple[str, ...]:
        return tuple(n for n, f in zip(self.layout.names, self.free, strict=True) if f)

    @property
    def n_params(self) -> int:
        return self.layout.n_params

    @property
    def n_free(self) -> int:
        return int(np.sum(self.free))

    @property
    def angle_params(self) -> np.ndarray:
        return self.layout.angles

    @property
    def instrument_params(self) -> np.ndarray:
        return self.layout.instrument

    @property
    def registration_params(self) -> np.ndarray:
        """The base pose and the targets (:attr:`instrument_params`)."""
        return self.layout.instrument

    @property
    def n_joints(self) -> int:
        return self.chain.n_joints

    @property
    def joint_kinds(self) -> tuple[str, ...]:
        """Every reading's kind: ``"R"`` (an angle, rad) or ``"P"`` (a slide, mm).

        A reading feeds joints of its own kind only (the robot file's ``joint_map``
        is checked for it), so reading ``j`` is of the kind of the chain's joint ``j``.
        """
        return self.chain.kinds

    @property
    def joint_limits(self) -> np.ndarray:
        return self.limits

    def within_limits(self, q: np.ndarray, *, tol: float = 1e-9) -> np.ndarray:
        """Every reading within its limit and every joint value ``M q`` within the chain's."""
        q = np.asarray(q, dtype=float)
        ok = (q >= self.limits[:, 0] - tol) & (q <= self.limits[:, 1] + tol)
        u = q @ self.joint_map.T
        lo, hi = self.chain.joint_limits[:, 0], self.chain.joint_limits[:, 1]
        return ok & (u >= lo - tol) & (u <= hi + tol)

    @property
    def point_dim(self) -> int:
        return 6 if self.oriented else 3

    @property
    def position_dim(self) -> int:
        return 3

    @property
    def sigma(self) -> float | None:
        """Reference instrument noise (1 std, mm) of :attr:`noise`, or None."""
        return None if self.noise is None else self.noise.sigma_mm

    @cached_property
    def reach_mm(self) -> float:
        """The sum of the joint origins' and the tip's offsets (an upper bound of the reach)."""
        offsets = np.linalg.norm(self.chain.origins[:, :3, 3], axis=1)
        return float(np.sum(offsets) + np.linalg.norm(self.chain.tip[:3, 3]) + 1.0)

    @property
    def deviation_bounds(self) -> DeviationBounds:
        """Every joint's placement and zero (:func:`~armcal.models.spatial.kinematics.\
deviation_bounds`); the base pose and the targets are the instrument's."""
        return deviation_bounds(self.layout, self.reach_mm)

    @property
    def base_offset(self) -> bool:
        """True: the base pose in the instrument's frame is always identified."""
        return True

    @property
    def tip_reach_mm(self) -> float:
        """How far from the base a measured point can lie: the reach and a target 0.5 m out
        (targets found from the data may sit on a long tool)."""
        targets = float(np.max(np.linalg.norm(self.target_positions, axis=1)))
        return self.reach_mm + max(targets, 500.0)

    @property
    def target_labels(self) -> tuple[str, ...]:
        return () if self.targets == (SINGLE_TARGET,) else self.targets

    @property
    def arm(self) -> SpatialArm:
        return self

    def with_noise(self, noise: NoiseModel | None) -> SpatialArm:
        return replace(self, noise=noise)

    def with_fixed(self, fixed: Sequence[str]) -> SpatialArm:
        """The user's fixed set replaced; the rule's set is chosen again (:meth:`prepared`)."""
        return replace(self, user_fixed=tuple(fixed), held=(), merges=())

    def target_index(self, labels: Sequence[str]) -> np.ndarray:
        """Indices of ``labels`` among the targets (ValueError for an unknown one)."""
        lookup = {label: i for i, label in enumerate(self.targets)}
        missing = sorted({str(x) for x in labels} - lookup.keys())
        if missing:
            raise ValueError(f"unknown targets {missing}; {self.name} has {list(self.targets)}")
        return np.array([lookup[str(x)] for x in labels], dtype=int)

    # -- measurement -------------------------------------------------------------------

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
        index = target_indices(target, self.targets, q.shape[-2])
        if index is None and len(self.targets) > 1:
            raise targets_missing(self.name, self.targets)
        refuse_feature(self.name, feature)
        return Conditions(q, index, None, sigma_mm)

    def chain_kinematics(
        self,
        conditions: Conditions,
        params: np.ndarray | None,
        *,
        derivatives: bool = False,
        keep: bool = False,
        parameters: bool = True,
    ) -> ChainKinematics:
        """The kinematics of the rows at ``params``; what it finds is kept on the conditions
        (:meth:`~armcal.models.interface.Conditions.latest`), so that the positions and
        weights a fit needs at the parameters of its Jacobian's pass take no pass of their
        own: the points and rotations always, the derivatives too with ``keep`` (a tool's
        angular Jacobian, whose point's Jacobian is usually asked for next) for a block of
        rows at most (:data:`~armcal.models.interface.ROW_BLOCK`), until the points alone
        are asked for (their last use).  ``parameters=False``: the joints' derivatives
        alone (:func:`~armcal.models.spatial.kinematics.kinematics`)."""
        params = self._params(params)
        key = (self.chain, self.joint_map, self.layout, params.shape, params.tobytes())
        kept = conditions.latest(_KINEMATICS, key)
        enough = kept is not None and (
            not derivatives
            or (kept.joint_jacobian is not None and (kept.jacobian is not None or not parameters))
        )
        if enough:
            if not derivatives and kept.jacobian is not None:
                conditions.keep(_KINEMATICS, key, _copied(kept, derivatives=False))
            return _copied(kept, derivatives=derivatives)
        found = kinematics(
            self.chain,
            self.joint_map,
            self.layout,
            conditions.q,
            conditions.target,
            params,
            derivatives=derivatives,
            parameters=parameters,
        )
        whole = derivatives and keep and found.points.size <= 3 * ROW_BLOCK  # rows x sets
        conditions.keep(_KINEMATICS, key, _copied(found, derivatives=whole))
        return found

    def positions(self, conditions: Conditions, params: np.ndarray | None = None) -> np.ndarray:
        """The targets' positions ``(..., m, 3)`` (mm); for a 6-DoF instrument also their
        orientations' turns from the rows' frames (rotation vectors, rad): ``(..., m, 6)``."""
        kin = self.chain_kinematics(conditions, params)
        if not self.oriented:
            return kin.points
        assert kin.target_rotation is not None
        turn = spatial_pose.turns(kin.target_rotation, conditions.frames)
        return np.concatenate([kin.points, turn], axis=-1)

    def _stacked(
        self,
        kin: ChainKinematics,
        conditions: Conditions,
        position: np.ndarray | None,
        angular: np.ndarray | None,
    ) -> np.ndarray:
        """A Jacobian of the points: its position rows and, for a 6-DoF instrument, the turns'
        rows from the target's angular velocities (:mod:`~armcal.models.spatial.pose`)."""
        assert position is not None
        if not self.oriented:
            return position
        assert angular is not None and kin.target_rotation is not None
        turn = spatial_pose.turns(kin.target_rotation, conditions.frames)
        return np.concatenate([position, spatial_pose.turn_rows(angular, turn)], axis=-2)

    def derivative(
        self, conditions: Conditions, params: np.ndarray | None, name: str
    ) -> np.ndarray:
        """One of the derivatives of :class:`ChainKinematics` (``jacobian``, ...); the tool
        role's, so the pass is kept for the point's Jacobian (:meth:`chain_kinematics`)."""
        joints = name in _JOINT_DERIVATIVES
        kin = self.chain_kinematics(
            conditions, params, derivatives=True, keep=True, parameters=not joints
        )
        found = getattr(kin, name)
        assert found is not None
        return found

    def jacobian(self, conditions: Conditions, params: np.ndarray | None = None) -> np.ndarray:
        kin = self.chain_kinematics(conditions, params, derivatives=True)
        return self._stacked(kin, conditions, kin.jacobian, kin.target_angular)

    def columns_jacobian(
        self, conditions: Conditions, params: np.ndarray | None, columns: np.ndarray
    ) -> np.ndarray | None:
        """:meth:`jacobian`'s ``columns`` ``(..., m, 3, c)`` where they are all the
        instrument's (the base pose and the targets' positions, as registering the nominal
        arm fits): from the points and the tip's rotation alone, a pass of the kinematics
        without derivatives (about a sixth of the cost).  None for other columns, or a
        6-DoF instrument (:func:`~armcal.models.interface.columns_jacobian`).

        The base's translations move every point alike; a turn of the base about its
        axis ``w`` (roll about the turned x axis, pitch about the yawed y axis, yaw
        about z: the base's screws of :mod:`~armcal.models.spatial.kinematics`) moves a
        point ``x`` at ``w x (x - t)``; a target's position moves its point by the tip's
        rotation.
        """
        columns = np.asarray(columns, dtype=bool)
        if self.oriented or not bool(np.all(self.layout.instrument[columns])):
            return None
        kin = self.chain_kinematics(conditions, params)
        base = self._params(params)[..., None, :6]  # (..., 1, 6)
        points = kin.points
        out = np.zeros((*points.shape[:-1], 3, self.layout.n_params))
        out[..., :, 0:3] = np.eye(3)
        offset = points - base[..., :3]
        for c, w in enumerate(base_turn_axes(base)):
            out[..., :, 3 + c] = cross(np.broadcast_to(w, offset.shape), offset)
        index = conditions.target
        index = np.zeros(conditions.m, dtype=int) if index is None else index
        target_columns_into(out, self.layout, index, kin.rotation)
        return out[..., columns]

    def joint_jacobian(
        self, conditions: Conditions, params: np.ndarray | None = None
    ) -> np.ndarray:
        kin = self.chain_kinematics(conditions, params, derivatives=True, parameters=False)
        return self._stacked(kin, conditions, kin.joint_jacobian, kin.tip_angular)

    def jacobians(
        self, conditions: Conditions, params: np.ndarray | None = None
    ) -> tuple[np.ndarray, np.ndarray]:
        """:meth:`jacobian` and :meth:`joint_jacobian` from one pass of the kinematics."""
        kin = self.chain_kinematics(conditions, params, derivatives=True)
        return (
            self._stacked(kin, conditions, kin.jacobian, kin.target_angular),
            self._stacked(kin, conditions, kin.joint_jacobian, kin.tip_angular),
        )

    def anchor(self, conditions: Conditions, points: np.ndarray) -> tuple[Conditions, np.ndarray]:
        """A 6-DoF instrument's measured orientations become the rows' frames
        (:func:`~armcal.models.spatial.pose.anchor`)."""
        points = np.asarray(points, dtype=float)
        return spatial_pose.anchor(conditions, points) if self.oriented else (conditions, points)

    def unanchor(self, conditions: Conditions, points: np.ndarray) -> np.ndarray:
        """Orientations as rotation vectors in the instrument's frame again."""
        points = np.asarray(points, dtype=float)
        return spatial_pose.unanchor(conditions, points) if self.oriented else points

    def pose_covariances(
        self,
        conditions: Conditions,
        params: np.ndarray | None = None,
        *,
        noise: NoiseModel | None = None,
    ) -> np.ndarray:
        noise = self.noise_of(noise)
        return noise.pose_covariances(**self._row_noise(conditions, params, noise))

    def noise_of(self, noise: NoiseModel | None) -> NoiseModel:
        """The 3-D noise model: ``noise``, else the arm's, else unit."""
        return relative_noise(self.noise if noise is None else noise).for_dim(3)

    def _row_noise(
        self, conditions: Conditions, params: np.ndarray | None, noise: NoiseModel
    ) -> dict[str, Any]:
        """What ``noise`` needs of the rows: their shape over parameter stacks, the joint
        Jacobian where encoder noise needs it, the rows' own sigmas, and the measured
        points where a laser tracker's noise depends on them."""
        kin = joint = None
        if noise.joint_sigma is not None or noise.tracker is not None:
            kin = self.chain_kinematics(
                conditions, params, derivatives=noise.joint_sigma is not None
            )
            if kin.joint_jacobian is not None:
                joint = self._stacked(kin, conditions, kin.joint_jacobian, kin.tip_angular)
        shape = np.broadcast_shapes(
            np.shape(conditions.q)[:-1], () if params is None else (*np.shape(params)[:-1], 1)
        )
        return {
            "shape": shape,
            "joint_jacobian": joint,
            "row_sigma": conditions.sigma_mm,
            "points": None if kin is None else kin.points,
            "oriented": self.oriented,
        }

    def whitening(
        self, conditions: Conditions, params: np.ndarray | None = None
    ) -> np.ndarray | None:
        plain = self.noise is None or self.noise.isotropic_iid
        if plain and conditions.sigma_mm is None and not self.oriented:
            return None
        noise = self.noise_of(None)
        return noise.whitening(**self._row_noise(conditions, params, noise))

    # -- fitting -----------------------------------------------------------------------

    def registration(
        self, conditions: Conditions, points: np.ndarray, weights: np.ndarray | None = None
    ) -> np.ndarray:
        """Parameters ``(p,)``: the nominal arm with its base pose and targets registered to
        one point set ``(m, 3)`` (:mod:`~armcal.models.spatial.registration`)."""
        at_tip = self.chain_kinematics(conditions, self._at_tip())  # targets at the tip frame
        frames, tips = at_tip.rotation, at_tip.points
        target = (
            np.zeros(conditions.m, dtype=int) if conditions.target is None else conditions.target
        )
        nominal = self.target_positions
        points = np.asarray(points, dtype=float)
        rotation, translation, found = register(
            frames, tips, target, points[:, :3], nominal, weights
        )
        out = self.nominal.copy()
        out[:3] = translation
        out[3:6] = matrix_rpy(rotation)
        positions, turns = registered_targets(
            rotation @ frames, target, points, found, nominal, self.target_turns,
            known=self.known_targets, oriented=self.oriented, row_frames=conditions.frames,
        )  # fmt: skip
        out[self.layout.target_start :] = self._target_block(positions, turns)
        return out

    def _at_tip(self) -> np.ndarray:
        """The nominal arm in its own base frame with every target at the tip frame's origin."""
        out = self.nominal.copy()
        out[:6] = 0.0
        out[self.layout.target_start :] = 0.0
        return out

    def start(
        self, conditions: Conditions, points: np.ndarray, weights: np.ndarray | None = None
    ) -> np.ndarray:
        """Every set's registration (module notes), the robot's errors at 0."""
        points = np.asarray(points, dtype=float)
        sets = points.reshape(-1, *points.shape[-2:])
        w = None if weights is None else np.broadcast_to(weights, sets.shape[:2])
        if w is None:  # sets of one experiment (Monte Carlo): their mean is registered once
            mean = sets.mean(axis=0)
            known = known_start(self, conditions, mean)  # prepared for them
            found = self.registration(conditions, mean) if known is None else known[0]
            out = np.tile(found, (sets.shape[0], 1))
        else:
            out = np.array(
                [self.registration(conditions, s, wi) for s, wi in zip(sets, w, strict=True)]
            )
        held = ~self.free
        out[:, held] = self.nominal[held]  # what is held stays at its nominal value
        return out

    def canonical(self, params: np.ndarray) -> np.ndarray:
        """Angles wrapped into ``(-pi, pi]``; a target's orientation to a turn of at most
        half a turn."""
        params = np.array(params, dtype=float)
        turns = self.layout.turns
        angles = self.layout.angles & ~turns
        params[..., angles] = np.pi - np.mod(np.pi - params[..., angles], 2 * np.pi)
        if turns.any():
            vectors = params[..., turns].reshape(*params.shape[:-1], -1, 3)
            params[..., turns] = rotation_vector(vector_rotation(vectors)).reshape(
                *params.shape[:-1], -1
            )
        return params

    def step_scale(self, conditions: Conditions) -> np.ndarray:
        """A millimetre per mm; the reach per radian."""
        return np.where(self.layout.angles, self.reach_mm, 1.0)

    # -- the identifiable set ------------------------------------------------------------

    @property
    def rank_bound(self) -> int:
        """``4R + 2P + 3k`` for point targets, ``4R + 2P + 6k`` in full pose: the parameters
        a complete, minimal model has (:mod:`~armcal.models.spatial.selection`)."""
        revolute = int(np.count_nonzero(self.chain.revolute))
        per = 6 if self.oriented else 3
        return 4 * revolute + 2 * (self.n_joints - revolute) + per * len(self.targets)

    def prepared(self, conditions: Conditions, points: np.ndarray | None = None) -> SpatialArm:
        """The arm for these rows: registered to ``points`` (when given) and reduced to the
        parameters they identify, by the fixed rule of :mod:`~armcal.models.spatial.selection`.
        """
        arm = self
        if points is not None:
            points = np.asarray(points, dtype=float)
            registered = self.registration(conditions, points)
            arm = replace(
                self,
                base_pose=registered[:6],
                target_positions=self.layout.target_points(registered),
                target_turns=self.layout.target_turns(registered),
            )
        # The columns in the robot's own frame: about the instrument's far-away origin a base
        # turn looks like a shift, and the rule's tolerance would see a dependence there.
        turn = rpy_matrix(arm.base_pose[3:])
        local = conditions
        if conditions.frames is not None:  # the frames turned back with the base
            local = conditions.with_frames(turn.T @ conditions.frames)
        at_base = replace(arm, base_pose=np.zeros(6))
        back = np.kron(np.eye(arm.point_dim // 3), turn)
        p = arm.layout.n_params
        rows = RowTriangle(p)  # the rule needs their column space only
        plain = True  # the whitening is the identity: then the rows are also the fit's
        for block, part in conditions.blocks():
            jac = at_base.jacobian(block if local is conditions else local.take(part))
            w = arm.whitening(block)
            plain = plain and w is None
            if w is not None:
                rows.add((w @ back @ jac).reshape(-1, p))
            elif points is None:
                rows.add(jac.reshape(-1, p))
            else:  # beside them, the registered arm's residuals in its own frame
                miss = (points[part] - arm.base_pose[:3]) @ turn - at_base.positions(block)
                rows.add(jac.reshape(-1, p), miss.reshape(-1))
        u = np.asarray(conditions.q) @ arm.joint_map.T
        held, merges = select_from_rows(arm.layout, arm.chain, rows.triangle(), u, arm.user_fixed)
        out = replace(arm, held=held, merges=merges)
        if plain:  # the rank analysis, the covariance at nominal and the fit's first step
            at_nominal = rows.transformed(_from_base(arm.base_pose, turn, p)[:, out.free])
            nominal_triangle_known(out, conditions, at_nominal)
            if points is not None:  # the fit starts at the registration
                start_known(out, conditions, points, out.nominal, at_nominal)
        return out

    def selected_by(
        self, rows: np.ndarray, conditions: Conditions, first: Sequence[str] = ()
    ) -> SpatialArm:
        """The arm with what ``rows`` cannot separate held, by the rule of
        :mod:`~armcal.models.spatial.selection` (its :attr:`user_fixed` held first, the
        columns of ``first`` kept first)."""
        u = np.asarray(conditions.q) @ self.joint_map.T
        held, merges = select_from_rows(
            self.layout, self.chain, rows, u, self.user_fixed, tuple(first)
        )
        return replace(self, held=held, merges=merges)

    def expressed(self, conditions: Conditions, params: np.ndarray) -> np.ndarray:
        """The free parameters that reproduce ``params``' points at these rows, the held
        ones at their nominal values: Gauss-Newton from ``params`` (each merge is an exact
        symmetry of the kinematics, so the points are reproduced to round-off)."""
        return refit_free(self, conditions, params)

    @property
    def held_values(self) -> np.ndarray:
        """The nominal parameters: held errors at 0, a held base or target where it is."""
        return self.nominal

    @property
    def held_reasons(self) -> tuple[Held, ...]:
        return self.merges

    def fit_details(self, conditions: Conditions, params: np.ndarray) -> dict[str, np.ndarray]:
        return {}

    def linear_positions(self, conditions: Conditions) -> LinearPositions | None:
        return None

    def plan_conditions(self, q: np.ndarray, loads: Loads | None = None) -> Conditions:
        """Every target measured at every pose; a 6-DoF instrument's orientations about
        where the nominal arm puts them."""
        q = np.asarray(q, dtype=float)
        k = len(self.targets)
        if k == 1:
            rows = self.conditions(q)
        else:
            rows = self.conditions(
                np.repeat(q, k, axis=-2), target=np.tile(np.arange(k), q.shape[-2])
            )
        if not self.oriented:
            return rows
        frames = self.chain_kinematics(rows, None).target_rotation
        return rows.with_frames(frames)


#: The derivatives of :class:`ChainKinematics` by the joints: a pass without the
#: parameters' Jacobians gives them.
_JOINT_DERIVATIVES = frozenset({"joint_jacobian", "tip_angular", "joint_axes", "joint_velocities"})

#: The slot of :meth:`SpatialArm.chain_kinematics` on the conditions.
_KINEMATICS = "spatial chain kinematics"


def _copied(kin: ChainKinematics, *, derivatives: bool) -> ChainKinematics:
    """A copy of ``kin``'s arrays, its derivatives or only its points and rotations (what
    is kept, and what is handed out from it: a caller may change its arrays in place)."""
    if not derivatives:
        target = None if kin.target_rotation is None else kin.target_rotation.copy()
        return ChainKinematics(kin.points.copy(), kin.rotation.copy(), target_rotation=target)
    copies: dict[str, Any] = {f.name: _copy(getattr(kin, f.name)) for f in fields(kin)}
    return ChainKinematics(**copies)


def _copy(array: np.ndarray | None) -> np.ndarray | None:
    return None if array is None else array.copy()


def _from_base(base: np.ndarray, turn: np.ndarray, p: int) -> np.ndarray:
    """``A`` ``(p, p)`` with ``J_T = (I x R) J_0 A``: the Jacobian at the base pose ``base``
    ``(6,)`` (its turn ``R``, ``turn``) from the one with the base at the origin, its rows
    turned.

    Every column but the base's six is only turned.  A shift ``t`` of the base moves a
    point by ``t = R (R^T t)``; a turn about ``w`` (:func:`base_turn_axes`) moves the
    point ``R x_0 + t`` by ``w x R x_0 = R ((R^T w) x x_0)``, the base-at-origin turns'
    columns ``e_c x x_0`` combined by ``R^T w``.  A 6-DoF point's orientation turns by
    ``w = R (R^T w)`` alike.
    """
    out = np.eye(p)
    out[0:3, 0:3] = turn.T
    out[3:6, 3:6] = turn.T @ np.stack(np.broadcast_arrays(*base_turn_axes(base)), axis=-1)
    return out
