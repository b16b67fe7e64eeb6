"""A spatial serial arm's parameters, its measured points and their analytic Jacobians.

**Parameters** (:class:`SpatialLayout`), over-complete, in this order:

* the base pose in the instrument's frame, ``base.x, base.y, base.z`` (mm) and
  ``base.rx, base.ry, base.rz`` (URDF's roll, pitch, yaw: ``Rz Ry Rx``);
* every joint's placement error, a small transform
  ``E = T(x, y, z) Rx(rx) Ry(ry) Rz(rz)`` right after its nominal origin, in its
  own frame (z = its axis): ``j{k}.x, .y, .z, .rx, .ry`` for a revolute joint
  (a turn about its own axis is its zero) and ``j{k}.x, .y, .rx, .ry, .rz`` for a
  prismatic one (a slide along its axis is its zero);
* the zero error of every controller reading, ``dq{k}``: ``u = M (q + dq)``;
* every target's position in the tip frame, ``{label}.x, .y, .z`` (mm), and for
  data of a 6-DoF instrument its orientation there, ``{label}.rx, .ry, .rz``: a
  rotation vector (axis times angle), whose Jacobian (SO(3)'s left Jacobian) is
  regular at every orientation, where roll, pitch and yaw are not at a pitch of
  90 degrees (a probe turned square to the flange).

Every parameter acts at a point of the chain as a small screw, so the
parametrization has no singularity where consecutive axes are parallel (a plain
DH model's ``d`` runs off to infinity there).  Which of these the measurements
identify is :mod:`~armcal.models.spatial.selection`'s job.

**Kinematics** (:func:`kinematics`): batched over parameter stacks ``(..., p)``
and rows ``(m,)``.  A parameter's column of the Jacobian is that of a screw with
axis ``w`` through ``c`` or a translation ``v``: ``dp = w x (p - c) + v``,
accumulated along the chain in one pass.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np

from ..defaults import LARGE_ANGLE_DEG
from ..interface import DeviationBounds
from .chain import SerialChain, elementary, left_jacobian, rpy_matrix, vector_rotation

__all__ = [
    "BASE_NAMES",
    "LARGE_PLACEMENT_FRACTION",
    "ChainKinematics",
    "SpatialLayout",
    "cross",
    "default_targets",
    "deviation_bounds",
    "kinematics",
]

#: The base pose's parameter names: translation (mm), then roll, pitch, yaw.
BASE_NAMES = ("base.x", "base.y", "base.z", "base.rx", "base.ry", "base.rz")

#: The placement error components of a joint by kind: indices into (x, y, z, rx, ry, rz).
_PLACEMENT = {"R": (0, 1, 2, 3, 4), "P": (0, 1, 3, 4, 5)}
_COMPONENT = ("x", "y", "z", "rx", "ry", "rz")


@dataclass(frozen=True)
class SpatialLayout:
    """Where each parameter of a spatial arm lives in the parameter vector.

    Attributes
    ----------
    kinds : tuple of str
        The joints' kinds (``"R"``, ``"P"``).
    targets : tuple of str
        The targets' labels (``("tool",)`` for one unlabelled target).
    oriented : bool
        Whether the targets' orientations are measured (and so are parameters).
    """

    kinds: tuple[str, ...]
    targets: tuple[str, ...]
    oriented: bool = False

    @property
    def n_joints(self) -> int:
        return len(self.kinds)

    @property
    def placement_start(self) -> int:
        return 6

    @property
    def zero_start(self) -> int:
        return 6 + 5 * self.n_joints

    @property
    def target_start(self) -> int:
        return 6 + 6 * self.n_joints

    @property
    def target_size(self) -> int:
        """Parameters per target: its position, and its orientation when measured."""
        return 6 if self.oriented else 3

    @property
    def n_params(self) -> int:
        return self.target_start + self.target_size * len(self.targets)

    @cached_property
    def names(self) -> tuple[str, ...]:
        joints = [
            f"j{k + 1}.{_COMPONENT[c]}"
            for k, kind in enumerate(self.kinds)
            for c in _PLACEMENT[kind]
        ]
        zeros = [f"dq{k + 1}" for k in range(self.n_joints)]
        axes = _COMPONENT[: self.target_size]
        targets = [f"{label}.{axis}" for label in self.targets for axis in axes]
        return (*BASE_NAMES, *joints, *zeros, *targets)

    @cached_property
    def angles(self) -> np.ndarray:
        """Boolean ``(p,)``: parameters that are angles (rad inside, deg shown)."""
        out = np.zeros(self.n_params, dtype=bool)
        out[3:6] = True
        for k, kind in enumerate(self.kinds):
            start = 6 + 5 * k
            for slot, c in enumerate(_PLACEMENT[kind]):
                out[start + slot] = c >= 3
            out[self.zero_start + k] = kind == "R"
        return out | self.turns

    @cached_property
    def units(self) -> tuple[str, ...]:
        return tuple("deg" if a else "mm" for a in self.angles)

    @cached_property
    def display_scale(self) -> np.ndarray:
        return np.where(self.angles, 180.0 / np.pi, 1.0)

    @cached_property
    def instrument(self) -> np.ndarray:
        """Boolean ``(p,)``: the base pose and the targets, not the robot's geometry."""
        out = np.zeros(self.n_params, dtype=bool)
        out[:6] = True
        out[self.target_start :] = True
        return out

    @cached_property
    def turns(self) -> np.ndarray:
        """Boolean ``(p,)``: the targets' orientations (rotation vectors), where measured."""
        out = np.zeros(self.n_params, dtype=bool)
        if self.oriented:
            out[self.target_start :] = np.tile([False] * 3 + [True] * 3, len(self.targets))
        return out

    def joint_of(self, index: int) -> int | None:
        """The 0-based joint a parameter belongs to (placement or zero), None otherwise."""
        if self.placement_start <= index < self.zero_start:
            return (index - self.placement_start) // 5
        if self.zero_start <= index < self.target_start:
            return index - self.zero_start
        return None

    def placement_errors(self, params: np.ndarray) -> np.ndarray:
        """Every joint's error ``(x, y, z, rx, ry, rz)`` ``(..., n, 6)`` in ``params``."""
        out = np.zeros((*params.shape[:-1], self.n_joints, 6))
        for k, kind in enumerate(self.kinds):
            start = 6 + 5 * k
            out[..., k, list(_PLACEMENT[kind])] = params[..., start : start + 5]
        return out

    def target_points(self, params: np.ndarray) -> np.ndarray:
        """The targets' positions ``(..., k, 3)`` in the tip frame (mm)."""
        blocks = params[..., self.target_start :].reshape(*params.shape[:-1], -1, self.target_size)
        return blocks[..., :3]

    def target_turns(self, params: np.ndarray) -> np.ndarray:
        """The targets' orientations ``(..., k, 3)`` in the tip frame (rotation vectors, rad);
        zero where they are not measured."""
        if not self.oriented:
            return np.zeros((*params.shape[:-1], len(self.targets), 3))
        blocks = params[..., self.target_start :].reshape(*params.shape[:-1], -1, 6)
        return blocks[..., 3:]

    def target_columns(self, t: int) -> tuple[slice, slice | None]:
        """Target ``t``'s position columns and, when measured, its orientation columns."""
        start = self.target_start + self.target_size * t
        turn = slice(start + 3, start + 6) if self.oriented else None
        return slice(start, start + 3), turn


#: A joint's placement error (or a prismatic joint's zero) beyond this fraction of the
#: arm's reach is implausible for a calibration.  Calibration-sized placement errors are
#: tenths of a mm to a few mm, about 0.1 % of a 1-3 m reach; a unit mistake gives
#: deviations as large as the links (tens of percent of the reach), and another variant
#: of the arm (a longer upper arm, an offset wrist) tens to hundreds of mm, 3-10 % of it.
#: 1 % (29 mm on the industrial-6r, whose reach_mm is 2.9 m; 12 mm on the cobot-6r)
#: leaves a factor of 3 to 10 on either side.
LARGE_PLACEMENT_FRACTION = 0.01


def deviation_bounds(layout: SpatialLayout, reach_mm: float) -> DeviationBounds:
    """How large a spatial arm's deviations may be (:class:`DeviationBounds`): every joint's
    placement and zero, lengths beyond :data:`LARGE_PLACEMENT_FRACTION` of ``reach_mm``,
    angles beyond :data:`~armcal.models.defaults.LARGE_ANGLE_DEG`; the base pose and the
    targets are the instrument's, not the robot's.

    Examples
    --------
    >>> bounds = deviation_bounds(SpatialLayout(("R",), ("tool",)), 1000.0)
    >>> bounds.bounds[[0, 6, 11]].tolist(), round(float(np.degrees(bounds.bounds[9])), 9)
    ([inf, 10.0, 0.17453292519943295], 10.0)
    """
    length = LARGE_PLACEMENT_FRACTION * reach_mm
    bounds = np.where(layout.angles, np.radians(LARGE_ANGLE_DEG), length)
    bounds[layout.instrument] = np.inf
    p = layout.n_params
    return DeviationBounds(
        bounds,
        np.full(p, np.nan),
        ("",) * p,
        "placement",
        LARGE_PLACEMENT_FRACTION,
        LARGE_ANGLE_DEG,
        "variant",
        np.zeros(p),
        length,
    )


#: Where targets without a nominal position are thought to be before any data: this
#: far beyond the flange (mm), on a circle of this radius about the last joint's axis
#: (a target on that axis would not see the joint turn).
DEFAULT_TARGET_OFFSET_MM = (100.0, 50.0)


def default_targets(count: int) -> np.ndarray:
    """Nominal positions ``(count, 3)`` of targets the robot file does not place.

    Examples
    --------
    >>> default_targets(1).tolist()
    [[50.0, 0.0, 100.0]]
    """
    beyond, radius = DEFAULT_TARGET_OFFSET_MM
    angle = 2 * np.pi * np.arange(count) / count
    return np.column_stack(
        [radius * np.cos(angle), radius * np.sin(angle), np.full(count, beyond)]
    )


def cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """``a x b`` ``(..., 3)`` of broadcast vectors: ``numpy.cross`` without its general
    axis handling, which costs more than the products on the small arrays here."""
    a0, a1, a2 = a[..., 0], a[..., 1], a[..., 2]
    b0, b1, b2 = b[..., 0], b[..., 1], b[..., 2]
    out = np.empty(np.broadcast_shapes(a.shape, b.shape))
    # Written into one array, not stacked: a copy of the result less.
    np.subtract(a1 * b2, a2 * b1, out=out[..., 0])
    np.subtract(a2 * b0, a0 * b2, out=out[..., 1])
    np.subtract(a0 * b1, a1 * b0, out=out[..., 2])
    return out


def _turned(rot: np.ndarray, axis: int, angle: np.ndarray) -> np.ndarray:
    """``rot @ elementary(axis, angle)`` ``(..., 3, 3)``, as two columns mixed: no matrix
    of every row built and multiplied."""
    c, s = np.cos(angle)[..., None], np.sin(angle)[..., None]
    i, j = (axis + 1) % 3, (axis + 2) % 3
    ri, rj = rot[..., :, i], rot[..., :, j]
    out = np.empty(np.broadcast_shapes(rot.shape, (*c.shape[:-1], 3, 3)))
    out[..., :, axis] = rot[..., :, axis]
    out[..., :, i] = ri * c + rj * s
    out[..., :, j] = rj * c - ri * s
    return out


@dataclass(frozen=True, eq=False)
class ChainKinematics:
    """The measured points of rows and what the kinematics gives with them.

    Attributes
    ----------
    points : ndarray, shape (..., m, 3)
        Target positions in the instrument's frame, mm.
    rotation : ndarray, shape (..., m, 3, 3)
        The tip frame's orientation in the instrument's frame.
    jacobian : ndarray, shape (..., m, 3, p), or None
        ``d points / d params`` (mm per mm or rad).
    joint_jacobian : ndarray, shape (..., m, 3, n), or None
        ``d points / d q`` (mm per rad of the controller's readings).
    tip_angular : ndarray, shape (..., m, 3, n), or None
        The tip frame's angular velocity per unit of every reading.
    angular : ndarray, shape (..., m, 3, p), or None
        The tip frame's angular velocity per unit of every parameter.
    target_rotation : ndarray, shape (..., m, 3, 3), or None
        The row's target's orientation in the instrument's frame, where measured.
    target_angular : ndarray, shape (..., m, 3, p), or None
        Its angular velocity per unit of every parameter.
    joint_axes : ndarray, shape (..., m, n, 3), or None
        Every joint's axis (0 for a prismatic joint) in the instrument's frame.
    joint_velocities : ndarray, shape (..., m, n, 3), or None
        The point's velocity per unit of every joint value ``u`` (not the readings).
    """

    points: np.ndarray
    rotation: np.ndarray
    jacobian: np.ndarray | None = None
    joint_jacobian: np.ndarray | None = None
    tip_angular: np.ndarray | None = None
    angular: np.ndarray | None = None
    target_rotation: np.ndarray | None = None
    target_angular: np.ndarray | None = None
    joint_axes: np.ndarray | None = None
    joint_velocities: np.ndarray | None = None


@dataclass(frozen=True, eq=False)
class _Screws:
    """Every parameter and joint value as a screw at the tip: axis ``w`` and moment
    ``v - w x c`` (a translation's axis 0), column by column: shapes ``(..., m, 3, p)``
    and ``(..., m, 3, n)``, the layout of the Jacobians they become."""

    axis: np.ndarray | None  # None: the joints' screws alone
    moment: np.ndarray | None
    joint_axis: np.ndarray
    joint_moment: np.ndarray


def _cross_columns(axis: np.ndarray, point: np.ndarray, out: np.ndarray) -> np.ndarray:
    """``out += w x x`` for every column ``w`` of ``axis`` ``(..., 3, c)`` and the point
    ``point`` ``(..., 3)`` of its row, into the columns ``out`` ``(..., 3, c)`` in place:
    ``w x x = [x]^T w`` with ``[x]`` the row's cross-product matrix, one stacked product
    of every row's ``3 x 3`` by its ``3 x c`` (a few times faster than six products of
    the columns' components, and the same to round-off)."""
    x0, x1, x2 = point[..., 0], point[..., 1], point[..., 2]
    turn = np.zeros((*point.shape, 3))
    turn[..., 0, 1], turn[..., 0, 2] = x2, -x1
    turn[..., 1, 0], turn[..., 1, 2] = -x2, x0
    turn[..., 2, 0], turn[..., 2, 1] = x1, -x0
    out += turn @ axis
    return out


def _base_screws(
    base: np.ndarray,
    rot: np.ndarray,
    pos: np.ndarray,
    lead: tuple[int, ...],
    n: int,
    p: int,
    parameters: bool,
) -> _Screws:
    """The screws of the base pose's six parameters; every other one 0 until the chain
    walk reaches it.  Without ``parameters``, the joints' screws alone."""
    joint_axis = np.zeros((*lead, 3, n))
    joint_moment = np.zeros((*lead, 3, n))
    if not parameters:
        return _Screws(None, None, joint_axis, joint_moment)
    axis = np.zeros((*lead, 3, p))
    moment = np.zeros((*lead, 3, p))
    moment[..., 0:3] = np.eye(3)
    for c, w in enumerate(base_turn_axes(base)):
        axis[..., :, 3 + c] = w
        moment[..., :, 3 + c] = -cross(w, pos)
    return _Screws(axis, moment, joint_axis, joint_moment)


def base_turn_axes(base: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The axes ``(..., 3)`` of the base pose's three turns (``base`` ``(..., 6)``: x, y,
    z, roll, pitch, yaw): roll about the turned x axis, pitch about the yawed y axis, yaw
    about z; each moves a point ``x`` at ``w x (x - t)``."""
    return (
        rpy_matrix(base[..., 3:6])[..., :, 0],
        elementary(2, base[..., 5])[..., :, 1],
        np.array([0.0, 0.0, 1.0]),
    )


def target_columns_into(
    out: np.ndarray, layout: SpatialLayout, index: np.ndarray, rot: np.ndarray
) -> None:
    """Every target's position columns of ``out`` ``(..., m, 3, p)``, in place: the tip's
    rotation ``rot`` ``(..., m, 3, 3)`` on the rows of that target (``index`` ``(m,)``), 0
    on the others."""
    for t in range(len(layout.targets)):
        cols, _ = layout.target_columns(t)
        out[..., cols] = np.where((index == t)[:, None, None], rot, 0.0)


def _apply(rot: np.ndarray, other: np.ndarray) -> np.ndarray:
    """``rot @ other`` of rotations ``(..., m, 3, 3)`` and a vector ``(3,)``, a matrix
    ``(3, b)`` or matrices ``(..., 1, 3, b)`` the same for every row: one BLAS product
    of the stacked rows where ``other`` is one (one parameter set), a batched product
    otherwise."""
    if other.ndim <= 2:
        flat = rot.reshape(-1, 3) @ other
        return flat.reshape(*rot.shape[:-1], *other.shape[1:])
    if all(size == 1 for size in other.shape[:-2]):
        flat = rot.reshape(-1, 3) @ other.reshape(3, -1)
        return flat.reshape(*rot.shape[:-1], other.shape[-1])
    sets = np.broadcast_shapes(rot.shape[:-3], other.shape[:-3])
    out = np.empty((*sets, rot.shape[-3], 3, other.shape[-1]))
    if np.prod(sets) > _SETS_LOOPED:
        np.matmul(rot, other, out=out)
        return out
    rot = np.broadcast_to(rot, (*sets, *rot.shape[-3:]))
    other = np.broadcast_to(other, (*sets, *other.shape[-3:]))
    for at in np.ndindex(sets):  # a BLAS product per set beats numpy's per-row 3 x 3 ones
        out[at] = _apply(rot[at], other[at])
    return out


#: Parameter sets up to which :func:`_apply` takes one BLAS product per set.
_SETS_LOOPED = 64


def _joint_frame(
    origin: np.ndarray, err: np.ndarray, kind: str
) -> tuple[np.ndarray, np.ndarray, list[tuple[int, np.ndarray]]]:
    """A joint's constant frame before its value: the nominal origin's rotation turned by
    the placement's angle errors ``(..., 1, 3, 3)``, its shift in the frame before
    ``(..., 1, 3, 1)`` (the origin's and the placement's), and for each angle error its
    axis in that frame ``(slot component, (..., 1, 3, 1))``: a walk takes the whole turn in
    one product, not one per error, and every screw's axis from one product too."""
    turn = np.broadcast_to(origin[:3, :3], (*err.shape[:-1], 3, 3))
    shift = origin[:3, 3, None] + turn @ err[..., :3, None]  # (a missing slot's error is 0)
    axes: list[tuple[int, np.ndarray]] = []
    for c in (3, 4, 5):
        if c in _PLACEMENT[kind]:
            axes.append((c, turn[..., :, c - 3 : c - 2]))
            turn = _turned(turn, c - 3, err[..., c])
    return turn, shift, axes


def _walk_chain(
    chain: SerialChain,
    errors: np.ndarray,
    u: np.ndarray,
    pos: np.ndarray,
    rot: np.ndarray,
    screws: _Screws | None,
) -> tuple[np.ndarray, np.ndarray]:
    """The tip frame's position and rotation from the base's, joint by joint: nominal
    origin, placement error, joint value; with ``screws``, every placement parameter's
    and joint's screw is filled in on the way.

    The frames broadcast: until the first joint turns they are the same for every row
    (``(..., 1, 3)``, ``(..., 1, 3, 3)``).  A joint's constant frame (origin and placement
    errors, :func:`_joint_frame`) is one product of the stacked rows.
    """
    for k, kind in enumerate(chain.kinds):
        turn, shift, axes = _joint_frame(chain.origins[k], errors[..., k, :], kind)
        start = 6 + 5 * k
        slots = {c: start + slot for slot, c in enumerate(_PLACEMENT[kind])}
        if screws is not None and screws.moment is not None:  # the shifts' directions
            placed = _apply(rot, chain.origins[k][:3, :3])
            for c in (0, 1, 2):
                if c in slots:
                    screws.moment[..., :, slots[c]] = placed[..., :, c]
        pos = pos + _apply(rot, shift)[..., 0]
        if screws is not None and screws.axis is not None and screws.moment is not None:
            for c, axis in axes:
                w = _apply(rot, axis)[..., 0]
                screws.axis[..., :, slots[c]] = w
                screws.moment[..., :, slots[c]] = -cross(w, pos)
        rot = _apply(rot, turn)
        w = rot[..., :, 2]
        if kind == "R":
            if screws is not None:
                screws.joint_axis[..., :, k] = w
                screws.joint_moment[..., :, k] = -cross(w, pos)
            rot = _turned(rot, 2, u[..., k])
        else:
            if screws is not None:
                screws.joint_moment[..., :, k] = w
            pos = pos + w * u[..., k, None]
    pos = pos + _apply(rot, chain.tip[:3, 3])
    rot = _apply(rot, chain.tip[:3, :3])
    return pos, rot


def _with_jacobians(
    joint_map: np.ndarray,
    layout: SpatialLayout,
    screws: _Screws,
    points: np.ndarray,
    rot: np.ndarray,
    index: np.ndarray,
    turn: np.ndarray | None,
    target_rotation: np.ndarray | None,
) -> ChainKinematics:
    """The kinematics with its Jacobians, from the screws at the points: a screw moves a
    point ``x`` at ``w x x + moment``; a target's own columns are the tip's rotation."""
    axis, moment = screws.axis, screws.moment
    joint_axis, joint_moment = screws.joint_axis, screws.joint_moment
    # Zero errors: d/dq_i = sum_j M_ji d/du_j.
    n = joint_map.shape[0]  # one BLAS product of the stacked rows, (..., m, 3, n)
    zero_axis = (joint_axis.reshape(-1, n) @ joint_map).reshape(joint_axis.shape)
    zero_moment = (joint_moment.reshape(-1, n) @ joint_map).reshape(joint_moment.shape)
    jac = target_angular = None
    if axis is not None and moment is not None:  # the parameters' too
        axis[..., layout.zero_start : layout.target_start] = zero_axis
        moment[..., layout.zero_start : layout.target_start] = zero_moment
        jac = _cross_columns(axis, points, out=moment)  # (..., m, 3, p): the moments' array
        if turn is not None:  # a target's turn exp(v) moves at rot J_l(v) dv (chain.py)
            target_angular = axis.copy()
            turning = rot @ left_jacobian(turn)
        target_columns_into(jac, layout, index, rot)
        for t in range(len(layout.targets)):
            _, turn_cols = layout.target_columns(t)
            if target_angular is not None and turn_cols is not None:
                jac[..., turn_cols] = 0.0
                target_angular[..., turn_cols] = np.where(
                    (index == t)[:, None, None], turning, 0.0
                )
    joint_jac = _cross_columns(zero_axis, points, out=zero_moment)
    velocities = _cross_columns(joint_axis, points, out=joint_moment)
    return ChainKinematics(
        points,
        rot,
        jac,
        joint_jac,
        zero_axis,
        axis,
        target_rotation,
        target_angular,
        np.swapaxes(joint_axis, -1, -2),
        np.swapaxes(velocities, -1, -2),
    )


def kinematics(
    chain: SerialChain,
    joint_map: np.ndarray,
    layout: SpatialLayout,
    q: np.ndarray,
    target: np.ndarray | None,
    params: np.ndarray,
    *,
    derivatives: bool = False,
    parameters: bool = True,
) -> ChainKinematics:
    """Points (and, with ``derivatives``, Jacobians) of rows ``q`` ``(..., m, n)``.

    Parameters
    ----------
    chain : SerialChain
    joint_map : ndarray, shape (n, n)
        ``u = M (q + dq)``.
    layout : SpatialLayout
    q : ndarray, shape (..., m, n)
        Controller readings (rad, mm).
    target : ndarray of int, shape (m,), or None
        Every row's target (None: target 0).
    params : ndarray, shape (..., p)
        Internal units (mm, rad).
    derivatives : bool
        Also the parameter and joint Jacobians.
    parameters : bool
        With ``derivatives``: the parameters' Jacobians too (False: the joints' alone,
        ``jacobian``, ``angular`` and ``target_angular`` None; what a correction of
        joint commands needs, at a fraction of the cost).
    """
    params = np.asarray(params, dtype=float)[..., None, :]  # (..., 1, p)
    q = np.asarray(q, dtype=float)
    lead = np.broadcast_shapes(params.shape[:-1], q.shape[:-1])  # (..., m)
    n, p = layout.n_joints, layout.n_params
    zeros = params[..., layout.zero_start : layout.target_start]
    u = (q + zeros) @ joint_map.T
    errors = layout.placement_errors(params)  # (..., 1, n, 6)
    base = params[..., :6]
    rot = rpy_matrix(base[..., 3:6])  # (..., 1, 3, 3): every row's until a joint turns
    pos = base[..., :3]
    # Every parameter (and joint value) as a screw: axis w, moment v - w x c.
    screws = _base_screws(base, rot, pos, lead, n, p, parameters) if derivatives else None
    pos, rot = _walk_chain(chain, errors, u, pos, rot, screws)
    pos = np.broadcast_to(pos, (*lead, 3))  # a chain that never turns: the same frame
    rot = np.broadcast_to(rot, (*lead, 3, 3))
    points_tip = layout.target_points(params[..., 0, :])  # (..., k, 3)
    index = np.zeros(lead[-1], dtype=int) if target is None else np.asarray(target)
    local = np.take(points_tip, index, axis=-2)  # (..., m, 3)
    points = pos + np.einsum("...ij,...j->...i", rot, local)
    turn = target_rotation = None
    if layout.oriented:
        turn = np.take(layout.target_turns(params[..., 0, :]), index, axis=-2)  # (..., m, 3)
        target_rotation = rot @ vector_rotation(turn)
    if not derivatives:
        return ChainKinematics(points, rot, target_rotation=target_rotation)
    assert screws is not None
    return _with_jacobians(joint_map, layout, screws, points, rot, index, turn, target_rotation)
