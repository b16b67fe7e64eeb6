"""The nominal geometry of a spatial serial arm: :class:`SerialChain`.

A chain of ``n`` moving joints, each revolute (``"R"``: a turn about its axis)
or prismatic (``"P"``: a slide along it).  Every joint has a frame whose z axis
is its axis; ``origins[j]`` places joint ``j``'s frame in the frame of the link
before it (after the previous joint's motion), and ``tip`` places the tip
(flange) frame in the last joint's frame.  A joint value ``u_j`` (rad, or mm
for a slide) moves by ``Rz(u_j)`` or ``Tz(u_j)``:

``T(u) = origins[0] J_0(u_0) origins[1] J_1(u_1) ... J_{n-1}(u_{n-1}) tip``.

Descriptions of other forms reduce to this one:

* a URDF chain (:meth:`SerialChain.from_joints`): a joint's ``<origin>`` and
  ``<axis>``; the frame is turned so that its z axis is the joint's axis, and
  fixed joints fold into their neighbours;
* a modified DH table (Craig, :meth:`SerialChain.from_mdh`):
  ``Rx(alpha) Tx(a) Rz(theta) Tz(d)`` per joint, the joint value added to
  ``theta`` (revolute) or ``d`` (prismatic);
* a standard DH table (Denavit and Hartenberg's distal convention,
  :meth:`SerialChain.from_dh`): ``Rz(theta) Tz(d) Tx(a) Rx(alpha)`` per joint,
  the joint value added to ``theta`` or ``d`` likewise.

The controller's readings ``q`` need not be these joint values: with a joint
map ``M`` (coupled axes, a joint counted the other way round) ``u = M q``.  The
joint limits hold for ``q``.  Units: mm and rad.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

__all__ = [
    "JOINT_KINDS",
    "SerialChain",
    "UrdfJoint",
    "axis_frame",
    "elementary",
    "joint_motion",
    "left_jacobian",
    "left_jacobian_inverse",
    "matrix_rpy",
    "rotation_vector",
    "rpy_matrix",
    "skew",
    "transform",
    "vector_rotation",
]

#: The kinds of moving joint: revolute (an angle, rad) and prismatic (a length, mm).
JOINT_KINDS = ("R", "P")


def elementary(axis: int, angle: ArrayLike) -> np.ndarray:
    """Rotation matrices ``(..., 3, 3)`` about the coordinate axis ``axis`` (0, 1, 2).

    Examples
    --------
    >>> np.round(elementary(2, np.pi / 2) @ [1.0, 0.0, 0.0], 12).tolist()
    [0.0, 1.0, 0.0]
    """
    angle = np.asarray(angle, dtype=float)
    c, s = np.cos(angle), np.sin(angle)
    out = np.zeros((*angle.shape, 3, 3))
    i, j = (axis + 1) % 3, (axis + 2) % 3
    out[..., axis, axis] = 1.0
    out[..., i, i] = c
    out[..., j, j] = c
    out[..., j, i] = s
    out[..., i, j] = -s
    return out


def rpy_matrix(rpy: ArrayLike) -> np.ndarray:
    """``Rz(yaw) Ry(pitch) Rx(roll)`` ``(..., 3, 3)`` of ``(..., 3)`` angles (URDF's ``rpy``)."""
    rpy = np.asarray(rpy, dtype=float)
    return elementary(2, rpy[..., 2]) @ elementary(1, rpy[..., 1]) @ elementary(0, rpy[..., 0])


def matrix_rpy(rotation: np.ndarray) -> np.ndarray:
    """Roll, pitch, yaw ``(..., 3)`` of rotations ``(..., 3, 3)``: :func:`rpy_matrix` undone.

    Pitch lies in ``[-pi/2, pi/2]``; at pitch ``+-pi/2`` (where roll and yaw turn
    about one axis) the roll is 0.

    Examples
    --------
    >>> np.round(matrix_rpy(rpy_matrix([0.1, -0.2, 3.0])), 12).tolist()
    [0.1, -0.2, 3.0]
    """
    r = np.asarray(rotation, dtype=float)
    pitch = np.arcsin(np.clip(-r[..., 2, 0], -1.0, 1.0))
    cos_pitch = np.hypot(r[..., 0, 0], r[..., 1, 0])
    regular = cos_pitch > 1e-12
    roll = np.where(regular, np.arctan2(r[..., 2, 1], r[..., 2, 2]), 0.0)
    yaw = np.where(
        regular, np.arctan2(r[..., 1, 0], r[..., 0, 0]), np.arctan2(-r[..., 0, 1], r[..., 1, 1])
    )
    return np.stack([roll, pitch, yaw], axis=-1)


def vector_rotation(vector: ArrayLike) -> np.ndarray:
    """Rotations ``(..., 3, 3)`` of rotation vectors ``(..., 3)`` (axis times angle, rad):
    Rodrigues' formula.

    Examples
    --------
    >>> np.round(vector_rotation([0.0, 0.0, np.pi / 2]) @ [1.0, 0.0, 0.0], 12).tolist()
    [0.0, 1.0, 0.0]
    """
    v = np.asarray(vector, dtype=float)
    x, y, z = v[..., 0], v[..., 1], v[..., 2]
    angle2 = x * x + y * y + z * z
    angle = np.sqrt(angle2)
    small = angle < 1e-8  # the series to second order: exact to round-off there
    safe = np.where(small, 1.0, angle)
    a = np.where(small, 1.0 - angle2 / 6, np.sin(safe) / safe)
    b = np.where(small, 0.5 - angle2 / 24, (1.0 - np.cos(safe)) / safe**2)
    # I + a [v] + b [v]^2, with [v]^2 = v v^T - |v|^2 I: entry by entry, not a batch of
    # 3x3 products.
    out = np.empty((*v.shape[:-1], 3, 3))
    c, bx, by = 1.0 - b * angle2, b * x, b * y
    ax, ay, az = a * x, a * y, a * z
    out[..., 0, 0], out[..., 1, 1], out[..., 2, 2] = c + bx * x, c + by * y, c + b * z * z
    out[..., 0, 1], out[..., 1, 0] = bx * y - az, bx * y + az
    out[..., 0, 2], out[..., 2, 0] = bx * z + ay, bx * z - ay
    out[..., 1, 2], out[..., 2, 1] = by * z - ax, by * z + ax
    return out


def rotation_vector(rotation: np.ndarray) -> np.ndarray:
    """Rotation vectors ``(..., 3)`` (axis times angle in ``[0, pi]``) of rotations
    ``(..., 3, 3)``: :func:`vector_rotation` undone.

    Near a half turn the axis comes from the symmetric part (the skew part
    vanishes there), so the result is accurate at every angle.

    Examples
    --------
    >>> np.round(rotation_vector(vector_rotation([0.3, -0.2, 0.1])), 12).tolist()
    [0.3, -0.2, 0.1]
    """
    r = np.asarray(rotation, dtype=float)
    skew = np.stack(
        [r[..., 2, 1] - r[..., 1, 2], r[..., 0, 2] - r[..., 2, 0], r[..., 1, 0] - r[..., 0, 1]],
        axis=-1,
    )
    sin2 = np.linalg.norm(skew, axis=-1)  # 2 sin(angle)
    cos = np.clip((np.trace(r, axis1=-2, axis2=-1) - 1.0) / 2, -1.0, 1.0)
    angle = np.arctan2(sin2 / 2, cos)
    small = sin2 < 1e-12
    scale = np.where(small, 0.5, angle / np.where(small, 1.0, sin2))
    out = skew * scale[..., None]
    wide = cos < -0.9  # beyond about 154 degrees: the axis from R + R^T
    if np.any(wide):
        sym = (r[wide] + np.swapaxes(r[wide], -1, -2)) / 2 - cos[wide][:, None, None] * np.eye(3)
        column = np.argmax(np.diagonal(sym, axis1=-2, axis2=-1), axis=-1)
        axis = np.take_along_axis(sym, column[:, None, None], axis=-1)[..., 0]
        axis /= np.linalg.norm(axis, axis=-1, keepdims=True)
        sign = np.where(np.einsum("...i,...i->...", axis, skew[wide]) < 0, -1.0, 1.0)
        out[wide] = axis * (sign * angle[wide])[:, None]
    return out


def skew(v: np.ndarray) -> np.ndarray:
    """``[v]_x`` ``(..., 3, 3)`` of vectors ``(..., 3)``."""
    k = np.zeros((*v.shape[:-1], 3, 3))
    k[..., 0, 1], k[..., 0, 2], k[..., 1, 2] = -v[..., 2], v[..., 1], -v[..., 0]
    return k - np.swapaxes(k, -1, -2)


def left_jacobian(vector: ArrayLike) -> np.ndarray:
    """SO(3)'s left Jacobian ``J_l(v)`` ``(..., 3, 3)``: ``exp(v + dv) = exp(J_l dv) exp(v)``
    to first order, so a rotation ``exp(v)`` turns with angular velocity ``J_l(v) dv``.

    ``J_l = I + (1 - cos t)/t^2 [v] + (t - sin t)/t^3 [v]^2``, ``t = |v|`` (Chirikjian,
    *Stochastic Models, Information Theory, and Lie Groups*, vol. 2, 2012, 10.6).

    Examples
    --------
    >>> v, dv = np.array([0.4, -1.1, 0.7]), np.array([1e-7, 2e-7, -1e-7])
    >>> turn = vector_rotation(v + dv) @ vector_rotation(v).T
    >>> bool(np.allclose(rotation_vector(turn), left_jacobian(v) @ dv, atol=1e-13))
    True
    """
    v = np.asarray(vector, dtype=float)
    t = np.linalg.norm(v, axis=-1)[..., None, None]
    k = skew(v)
    small = t < 1e-4  # the series to t^4: exact to round-off there
    safe = np.where(small, 1.0, t)
    a = np.where(small, 0.5 - t**2 / 24 + t**4 / 720, (1.0 - np.cos(safe)) / safe**2)
    b = np.where(small, 1 / 6 - t**2 / 120 + t**4 / 5040, (safe - np.sin(safe)) / safe**3)
    return np.eye(3) + a * k + b * (k @ k)


def left_jacobian_inverse(vector: ArrayLike) -> np.ndarray:
    """``J_l(v)^-1`` ``(..., 3, 3)``: how a rotation vector ``v`` changes when its rotation
    turns by a small ``w``: ``dv = J_l(v)^-1 w``.

    ``J_l^-1 = I - [v]/2 + (1/t^2 - (1 + cos t)/(2 t sin t)) [v]^2`` (same source as
    :func:`left_jacobian`); singular at a full turn only, ``|v| < pi`` here.

    Examples
    --------
    >>> v = np.array([0.4, -1.1, 2.7])
    >>> bool(np.allclose(left_jacobian_inverse(v) @ left_jacobian(v), np.eye(3)))
    True
    """
    v = np.asarray(vector, dtype=float)
    t = np.linalg.norm(v, axis=-1)[..., None, None]
    k = skew(v)
    small = t < 1e-4
    safe = np.where(small, 1.0, t)
    c = np.where(
        small,
        1 / 12 + t**2 / 720 + t**4 / 30240,
        1.0 / safe**2 - (1.0 + np.cos(safe)) / (2.0 * safe * np.sin(safe)),
    )
    return np.eye(3) - 0.5 * k + c * (k @ k)


def transform(
    rotation: ArrayLike | None = None, translation: ArrayLike | None = None
) -> np.ndarray:
    """The homogeneous transform ``(4, 4)`` of a rotation and a translation (mm)."""
    out = np.eye(4)
    if rotation is not None:
        out[:3, :3] = rotation
    if translation is not None:
        out[:3, 3] = translation
    return out


def axis_frame(axis: ArrayLike) -> np.ndarray:
    """A rotation ``R`` ``(3, 3)`` with ``R e_z = axis / |axis|``, the identity for ``+z``.

    The x axis is the old x axis made perpendicular to ``axis`` (the old y axis
    when ``axis`` is along x), so a URDF joint about ``y`` keeps its frame's x.
    """
    z = np.asarray(axis, dtype=float)
    z = z / np.linalg.norm(z)
    if np.allclose(z, [0.0, 0.0, 1.0], rtol=0.0, atol=1e-15):
        return np.eye(3)
    ref = np.array([1.0, 0.0, 0.0]) if abs(z[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    x = ref - z * (ref @ z)
    x /= np.linalg.norm(x)
    return np.column_stack([x, np.cross(z, x), z])


@dataclass(frozen=True)
class UrdfJoint:
    """One joint of a URDF chain, as read (lengths in mm, angles in rad).

    Attributes
    ----------
    name : str
    kind : str
        ``"revolute"``, ``"continuous"``, ``"prismatic"`` or ``"fixed"``.
    xyz : tuple of float
        ``<origin xyz>`` (mm).
    rpy : tuple of float
        ``<origin rpy>`` (rad).
    axis : tuple of float
        ``<axis xyz>`` (unit vector; URDF's default ``(1, 0, 0)``).
    limits : tuple of float or None
        ``<limit lower upper>`` (rad, or mm for a slide); None for a
        continuous joint or one without limits.
    """

    name: str
    kind: str
    xyz: tuple[float, float, float]
    rpy: tuple[float, float, float]
    axis: tuple[float, float, float] = (1.0, 0.0, 0.0)
    limits: tuple[float, float] | None = None


@dataclass(frozen=True, eq=False)
class SerialChain:
    """The nominal kinematics of a serial arm (module notes).

    Attributes
    ----------
    origins : ndarray, shape (n, 4, 4)
        Joint ``j``'s frame (z = its axis) in the frame before it, mm.
    kinds : tuple of str
        ``"R"`` or ``"P"`` per joint.
    tip : ndarray, shape (4, 4)
        The tip (flange) frame in the last joint's frame.
    joint_names : tuple of str
        For reports (URDF joint names, or ``"joint 1"``...).
    joint_limits : ndarray, shape (n, 2)
        Limits of the joint values ``u`` as the description gives them (rad,
        mm), or infinite.
    """

    origins: np.ndarray
    kinds: tuple[str, ...]
    tip: np.ndarray
    joint_names: tuple[str, ...]
    joint_limits: np.ndarray

    def __post_init__(self) -> None:
        n = len(self.kinds)
        if n == 0:
            raise ValueError("a serial arm needs at least one moving joint")
        if self.origins.shape != (n, 4, 4) or self.tip.shape != (4, 4):
            raise ValueError(f"origins must have shape ({n}, 4, 4) and tip (4, 4)")
        if any(k not in JOINT_KINDS for k in self.kinds):
            raise ValueError(f"joint kinds must be 'R' or 'P', got {self.kinds}")
        if len(self.joint_names) != n or self.joint_limits.shape != (n, 2):
            raise ValueError("one name and one [lo, hi] limit per joint")
        if not (np.all(np.isfinite(self.origins)) and np.all(np.isfinite(self.tip))):
            raise ValueError("joint origins must be finite")

    @property
    def n_joints(self) -> int:
        return len(self.kinds)

    @property
    def revolute(self) -> np.ndarray:
        """Boolean ``(n,)``: the revolute joints."""
        return np.array([k == "R" for k in self.kinds])

    @classmethod
    def from_mdh(
        cls,
        alpha: ArrayLike,
        a: ArrayLike,
        theta: ArrayLike,
        d: ArrayLike,
        kinds: Sequence[str] | None = None,
        *,
        tip: np.ndarray | None = None,
    ) -> SerialChain:
        """A chain from a modified DH table (Craig): ``Rx(alpha) Tx(a) Rz(theta) Tz(d)``.

        ``alpha``, ``theta`` in rad, ``a``, ``d`` in mm, one entry per joint; the
        joint value adds to ``theta`` (revolute) or ``d`` (prismatic).

        Examples
        --------
        >>> chain = SerialChain.from_mdh([0, 0], [0, 100.0], [0, 0], [0, 0])
        >>> chain.n_joints, chain.origins[1, :3, 3].tolist()
        (2, [100.0, 0.0, 0.0])
        """
        alpha, a, theta, d = (np.asarray(v, dtype=float).ravel() for v in (alpha, a, theta, d))
        n = alpha.size
        if not (a.size == theta.size == d.size == n):
            raise ValueError("alpha, a, theta and d need one entry per joint")
        kinds = tuple(kinds) if kinds is not None else ("R",) * n
        origins = np.empty((n, 4, 4))
        for j in range(n):
            rot_x = transform(elementary(0, alpha[j]))
            slide_x = transform(translation=[a[j], 0.0, 0.0])
            turn_z = transform(elementary(2, theta[j]))
            slide_z = transform(translation=[0.0, 0.0, d[j]])
            origins[j] = rot_x @ slide_x @ turn_z @ slide_z
        tip = np.eye(4) if tip is None else tip
        names = tuple(f"joint {j + 1}" for j in range(n))
        limits = np.tile([-np.inf, np.inf], (n, 1))
        return cls(origins, kinds, tip, names, limits)

    @classmethod
    def from_dh(
        cls,
        theta: ArrayLike,
        d: ArrayLike,
        a: ArrayLike,
        alpha: ArrayLike,
        names: Sequence[str] | None = None,
        *,
        kinds: Sequence[str] | None = None,
    ) -> SerialChain:
        """A chain from a standard (distal) DH table, as controllers give it: joint ``k``
        moves the frame by ``Rz(q_k + theta_k) Tz(d_k) Tx(a_k) Rx(alpha_k)`` (rad, mm), or
        for a prismatic joint (``kinds``, default every joint revolute) by
        ``Rz(theta_k) Tz(q_k + d_k) Tx(a_k) Rx(alpha_k)``.  Joint 1's axis is the base
        frame's z; each row after its joint's motion becomes the next joint's origin, the
        last row the tip, and each joint's frame then slides along its own axis to the
        point nearest the frame before (the same kinematics), so the metres of ``d`` of
        near-parallel axes (a controller's) cancel here, to round-off of their size
        (``1e-16`` of 1e6 mm is 1e-10 mm), and nowhere else.

        Examples
        --------
        >>> chain = SerialChain.from_dh([0, 0], [0, 0], [100.0, 50.0], [0, 0])
        >>> np.round(chain.forward([np.pi / 2, 0.0])[:3, 3], 9).tolist()
        [0.0, 150.0, 0.0]
        """
        theta, d, a, alpha = (np.asarray(v, dtype=float).ravel() for v in (theta, d, a, alpha))
        n = theta.size
        if not (d.size == a.size == alpha.size == n):
            raise ValueError("theta, d, a and alpha need one entry per joint")
        rows = np.array([dh_row(theta[j], d[j], a[j], alpha[j]) for j in range(n)])
        origins = np.concatenate([np.eye(4)[None], rows[:-1], rows[-1:]])
        # Slide every joint's frame along its own axis to the point nearest the frame
        # before it (a slide along the axis commutes with the joint's motion: the same
        # kinematics), so no frame sits the metres away where near-parallel axes' common
        # normals meet them, and errors are placed at the joints themselves.
        for j in range(1, n):
            along = origins[j][:3, 2] @ origins[j][:3, 3]
            slide = transform(translation=[0.0, 0.0, -along])
            origins[j] = origins[j] @ slide
            origins[j + 1] = np.linalg.inv(slide) @ origins[j + 1]
        names = tuple(names) if names is not None else tuple(f"joint {j + 1}" for j in range(n))
        limits = np.tile([-np.inf, np.inf], (n, 1))
        kinds = tuple(kinds) if kinds is not None else ("R",) * n
        return cls(origins[:n], kinds, origins[n], names, limits)

    @classmethod
    def from_joints(cls, joints: Sequence[UrdfJoint]) -> SerialChain:
        """A chain from a URDF's joints from the base link to the tip link, in order.

        Fixed joints fold into the next moving joint's origin (or the tip); each
        moving joint's frame is turned so that its z axis is its ``<axis>``.
        """
        pending = np.eye(4)
        origins, kinds, names, limits = [], [], [], []
        for joint in joints:
            placed = pending @ transform(rpy_matrix(joint.rpy), joint.xyz)
            if joint.kind == "fixed":
                pending = placed
                continue
            turn = axis_frame(joint.axis)
            origins.append(placed @ transform(turn))
            kinds.append("P" if joint.kind == "prismatic" else "R")
            names.append(joint.name)
            limits.append(joint.limits if joint.limits is not None else (-np.inf, np.inf))
            pending = transform(turn.T)
        if not origins:
            raise ValueError("the chain has no moving joint")
        return cls(np.array(origins), tuple(kinds), pending, tuple(names), np.array(limits))

    def zero_frames(self) -> np.ndarray:
        """Every joint's frame ``(n, 4, 4)`` in the base frame at zero joint values (z its
        axis); the tip's is ``zero_frames()[-1] @ tip``."""
        frames = [self.origins[0]]
        for origin in self.origins[1:]:
            frames.append(frames[-1] @ origin)
        return np.array(frames)

    def forward(self, u: ArrayLike) -> np.ndarray:
        """The tip frames ``(..., 4, 4)`` at joint values ``u`` ``(..., n)`` (rad, mm).

        Examples
        --------
        >>> chain = SerialChain.from_mdh([0, 0], [0, 100.0], [0, 0], [0, 0])
        >>> np.round(chain.forward([np.pi / 2, 0.0])[:3, 3], 9).tolist()
        [0.0, 100.0, 0.0]
        """
        u = np.asarray(u, dtype=float)
        frame = np.broadcast_to(np.eye(4), (*u.shape[:-1], 4, 4))
        for j, kind in enumerate(self.kinds):
            frame = frame @ self.origins[j] @ joint_motion(kind, u[..., j])
        return frame @ self.tip


def dh_row(theta: float, d: float, a: float, alpha: float) -> np.ndarray:
    """``Rz(theta) Tz(d) Tx(a) Rx(alpha)`` ``(4, 4)``: a standard DH row (rad, mm)."""
    rotation = elementary(2, theta) @ elementary(0, alpha)
    return transform(rotation, [a * np.cos(theta), a * np.sin(theta), d])


def joint_motion(kind: str, value: np.ndarray) -> np.ndarray:
    """The motion ``(..., 4, 4)`` of a joint of ``kind`` by ``value``: ``Rz`` or ``Tz``."""
    value = np.asarray(value, dtype=float)
    out = np.zeros((*value.shape, 4, 4))
    out[..., 3, 3] = 1.0
    if kind == "R":
        out[..., :3, :3] = elementary(2, value)
    else:
        out[..., :3, :3] = np.eye(3)
        out[..., 2, 3] = value
    return out
