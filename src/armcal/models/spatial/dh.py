"""A serial chain as a modified DH table, exactly, even where consecutive axes are parallel.

A row of the table (Craig's modified DH, with Hayati's extra angle ``beta``)
places joint ``k``'s frame in joint ``k - 1``'s::

    Rx(alpha) Tx(a) Ry(beta) Rz(theta) Tz(d)

With ``beta = 0`` this is Craig's row.  For two axes far from parallel the x
axis of joint ``k - 1``'s frame runs along their common normal and ``beta`` is 0.
For nearly parallel axes the common normal runs off to infinity (a controller's
DH ``d`` of hundreds of metres, and a table that rounds badly); there the
frame's origin stays where it is, its x axis points to where the next axis
crosses its xy plane, and ``beta`` takes the small tilt about y (Hayati and
Mirmirani, "Improving the absolute positioning accuracy of robot manipulators",
J. Robotic Systems 2(4), 1985).  So every row stays finite and well conditioned.

A joint's frame may turn about and slide along its own axis without changing the
kinematics (those commute with the joint's own turn or slide), which is the
freedom the table uses: :func:`mdh_table` picks each frame's x axis and origin,
and the first row and the tip absorb what is left (``base``, ``tip``), so
:meth:`MdhTable.chain` gives back the same kinematics to round-off.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from ...numerics import wrap_angle
from .chain import SerialChain, dh_row, elementary, joint_motion, transform

__all__ = [
    "CONVENTIONS",
    "PARALLEL_COS",
    "DhTable",
    "MdhTable",
    "convention_mistake",
    "degeneracy",
    "dh_table",
    "mdh_table",
    "mdh_transform",
    "table_chain",
]

#: Consecutive axes closer to parallel than 45 degrees get Hayati's row (module notes).
PARALLEL_COS = np.cos(np.pi / 4)


def mdh_transform(alpha: float, a: float, beta: float, theta: float, d: float) -> np.ndarray:
    """``Rx(alpha) Tx(a) Ry(beta) Rz(theta) Tz(d)`` ``(4, 4)`` (rad, mm).

    Examples
    --------
    >>> np.round(mdh_transform(0.0, 100.0, 0.0, np.pi / 2, 5.0)[:3, 3], 12).tolist()
    [100.0, 0.0, 5.0]
    """
    rot = elementary(0, alpha) @ elementary(1, beta) @ elementary(2, theta)
    return transform(rot, elementary(0, alpha) @ [a, 0.0, 0.0] + rot @ [0.0, 0.0, d])


@dataclass(frozen=True)
class MdhTable:
    """A modified DH table (rad, mm), one entry per joint, with a base and a tip transform.

    Attributes
    ----------
    alpha, a, beta, theta, d : ndarray, shape (n,)
    kinds : tuple of str
    base : ndarray, shape (4, 4)
        Before the first row (the identity when the first axis is placed by a row).
    tip : ndarray, shape (4, 4)
        The tip frame in the last joint's frame.
    """

    alpha: np.ndarray
    a: np.ndarray
    beta: np.ndarray
    theta: np.ndarray
    d: np.ndarray
    kinds: tuple[str, ...]
    base: np.ndarray
    tip: np.ndarray

    def chain(self, joint_names: tuple[str, ...] | None = None) -> SerialChain:
        """The chain of this table (joint values add to ``theta`` or ``d``)."""
        n = len(self.kinds)
        origins = np.array(
            [
                mdh_transform(self.alpha[k], self.a[k], self.beta[k], self.theta[k], self.d[k])
                for k in range(n)
            ]
        )
        origins[0] = self.base @ origins[0]
        names = joint_names or tuple(f"joint {k + 1}" for k in range(n))
        limits = np.tile([-np.inf, np.inf], (n, 1))
        return SerialChain(origins, self.kinds, self.tip, names, limits)


def _row(origin: np.ndarray) -> tuple[float, float, float, float, float, float]:
    """``(alpha, a, beta, theta, d, miss)`` of a transform meant to be a row; ``miss`` is how
    far (mm, rad) the row's transform is from it (0 for a transform of the row's form)."""
    rot, t = origin[:3, :3], origin[:3, 3]
    z = rot[:, 2]
    beta = float(np.arcsin(np.clip(z[0], -1.0, 1.0)))
    alpha = float(np.arctan2(-z[1], z[2]))
    rest = (elementary(0, alpha) @ elementary(1, beta)).T @ rot
    theta = float(np.arctan2(rest[1, 0], rest[0, 0]))
    d = float((t[1] * z[1] + t[2] * z[2]) / max(z[1] ** 2 + z[2] ** 2, 1e-300))
    a = float(t[0] - d * z[0])
    miss = float(np.max(np.abs(mdh_transform(alpha, a, beta, theta, d) - origin)))
    return alpha, a, beta, theta, d, miss


def _screw(phi: float, s: float) -> np.ndarray:
    """``Rz(phi) Tz(s)``: a turn about and a slide along a frame's own z axis."""
    return transform(elementary(2, phi), [0.0, 0.0, s])


def _choice(frame: np.ndarray, after: np.ndarray) -> tuple[np.ndarray, bool]:
    """The turn and slide of ``frame`` (world, z its axis) that put its x axis along the
    common normal to the axis of ``after`` (Craig), or, for nearly parallel axes, towards
    where that axis crosses the frame's xy plane (Hayati); the x axis keeps the sign of
    the frame's own.  Returns the screw and whether the row is Hayati's."""
    rel = np.linalg.solve(frame, after)  # the next frame in this one
    z, p = rel[:3, 2], rel[:3, 3]
    if abs(z[2]) >= PARALLEL_COS:  # Hayati: origin stays, x towards the crossing point
        crossing = p - z * (p[2] / z[2])
        direction = crossing[:2]
        slide = 0.0
        hayati = True
    else:  # Craig: the common normal, from the foot of it on this axis
        normal = np.cross([0.0, 0.0, 1.0], z)
        direction = normal[:2]
        # The foot on this axis: the point (0, 0, s) closest to the line p + t z.
        w = z[2]
        denom = 1.0 - w**2
        slide = float((p[2] - w * (p @ z)) / denom)
        hayati = False
    norm = np.linalg.norm(direction)
    phi = 0.0 if norm < 1e-12 else float(np.arctan2(direction[1], direction[0]))
    if np.cos(phi) < 0 or (np.cos(phi) == 0 and np.sin(phi) < 0):  # keep the frame's x side
        phi = phi - np.pi if phi > 0 else phi + np.pi
    return _screw(phi, slide), hayati


def mdh_table(chain: SerialChain) -> MdhTable:
    """The modified DH table of ``chain``, exact to round-off (module notes).

    Examples
    --------
    >>> chain = SerialChain.from_mdh([0, -np.pi / 2, 0], [0, 100.0, 400.0], [0, 0.1, 0],
    ...                              [300.0, 0, 20.0])
    >>> table = mdh_table(chain)
    >>> np.round(table.a, 9).tolist(), np.round(table.d, 9).tolist()
    ([0.0, 100.0, 400.0], [300.0, 0.0, 20.0])
    >>> u = np.array([0.3, -0.5, 1.1])
    >>> bool(np.allclose(table.chain().forward(u), chain.forward(u), atol=1e-12))
    True
    """
    n = chain.n_joints
    world = chain.zero_frames()
    screws = [np.eye(4)] * n
    hayati = [True] * n  # row k + 1's kind
    for k in range(n - 1):
        screws[k], hayati[k] = _choice(world[k], world[k + 1])
    rows = np.zeros((n, 5))
    base = np.eye(4)
    for k in range(n):
        before = np.eye(4) if k == 0 else np.linalg.inv(screws[k - 1])
        origin = before @ chain.origins[k] @ screws[k]
        *values, miss = _row(origin)
        if k > 0 and not hayati[k - 1]:
            values[2] = 0.0  # Craig's row: beta is 0 but for round-off
        if k == 0 and miss > 1e-9:  # the first axis is placed by a base transform
            base, values = origin, [0.0] * 5
        rows[k] = values
    tip = np.linalg.inv(screws[-1]) @ chain.tip
    alpha, a, beta, theta, d = (rows[:, i].copy() for i in range(5))
    return MdhTable(alpha, a, beta, theta, d, chain.kinds, base, tip)


@dataclass(frozen=True, eq=False)
class DhTable:
    """A standard (distal) DH table, as controllers give it (rad, mm): joint ``k`` moves the
    frame by ``Rz(q_k + theta_k) Tz(d_k) Tx(a_k) Rx(alpha_k)`` (:meth:`SerialChain.from_dh`)."""

    theta: np.ndarray
    d: np.ndarray
    a: np.ndarray
    alpha: np.ndarray

    def chain(self, joint_names: tuple[str, ...] | None = None) -> SerialChain:
        return SerialChain.from_dh(self.theta, self.d, self.a, self.alpha, joint_names)


def dh_table(chain: SerialChain, reference: DhTable, *, tol: float = 1e-9) -> DhTable:
    """The standard DH table of a revolute ``chain``, exact to round-off, on the branch of
    ``reference`` (its nominal table: every ``x`` axis on the side that keeps ``theta``
    within a quarter turn of the reference's, so a calibration's table differs from the
    nominal by small deltas).

    Frame ``k`` has its z axis on joint ``k + 1``'s axis and its x axis along the common
    normal from the axis before; for parallel axes the normal through the previous
    frame's origin (``d = 0``), for nearly parallel ones the unique normal, far away (a
    ``d`` of hundreds of metres, as controllers report).  Frame 0 is the chain's base,
    whose z axis must be joint 1's; the last frame is the tip, whose x axis must cross
    the last joint's axis at a right angle (a row's ``Tx(a) Rx(alpha)``).

    Raises
    ------
    ValueError
        For a prismatic joint, a first axis off the base's z, or a tip off the last axis:
        no standard DH table holds them.
    """
    if any(kind != "R" for kind in chain.kinds):
        raise ValueError("a standard DH table of revolute joints cannot hold a prismatic joint")
    n = chain.n_joints
    frames = chain.zero_frames()
    lines = [*frames, frames[-1] @ chain.tip]  # the tip: its z and x axes are the last row's
    first = lines[0]
    reach = max(1.0, float(np.linalg.norm(first[:3, 3])))
    if np.linalg.norm(first[:2, 2]) > tol or np.linalg.norm(first[:2, 3]) > tol * reach:
        raise ValueError("joint 1's axis is not the base frame's z axis")
    frame = np.eye(4)
    rows = np.zeros((n, 4))
    for k in range(n):
        target = np.linalg.solve(frame, lines[k + 1])  # the next axis (or the tip) here
        rows[k] = _dh_row_of(target, k == n - 1, reference.theta[k], tol)
        frame = frame @ dh_row(*rows[k])
    if np.max(np.abs(frame - lines[n])) > tol * max(1.0, np.max(np.abs(lines[n]))):
        raise ValueError("the tip's x axis does not cross the last joint's axis at a right angle")
    return DhTable(rows[:, 0], rows[:, 1], rows[:, 2], rows[:, 3])


def _dh_row_of(target: np.ndarray, last: bool, theta_ref: float, tol: float) -> np.ndarray:
    """``(theta, d, a, alpha)`` of the row that puts a frame's z axis on ``target``'s (the
    next joint's frame, or the tip's when ``last``), in the current frame (module notes
    of :func:`dh_table`)."""
    z, p = target[:3, 2], target[:3, 3]
    w = float(z[2])
    normal = np.array([-z[1], z[0], 0.0])  # z_prev x z
    if last:  # the tip's own x axis (a row's: across the last axis), no common normal
        d, x, point = float(p[2]), target[:3, 0].copy(), p
    elif np.linalg.norm(normal) > tol:  # the common normal, between its feet
        # t = (p_z w - p.z) / (1 - w^2), written without cancellation for nearly parallel
        # axes (where the feet lie metres away and d is large).
        t = -(p[0] * z[0] + p[1] * z[1]) / (z[0] ** 2 + z[1] ** 2)
        d = float(p[2] + t * w)
        point = p + t * z
        x = point - [0.0, 0.0, d]
        if np.linalg.norm(x) <= tol * max(1.0, abs(d)):  # intersecting axes
            x = normal
    else:  # parallel axes: the normal through this frame's origin (d = 0)
        d = 0.0
        point = p - z * (p[2] / w)
        x = point.copy()
        if np.linalg.norm(x) <= tol:  # the same axis: keep the reference's x
            x = np.array([np.cos(theta_ref), np.sin(theta_ref), 0.0])
    x = x / np.linalg.norm(x)
    theta = float(np.arctan2(x[1], x[0]))
    if not last and abs(wrap_angle(theta - theta_ref)) > np.pi / 2:  # the reference's side
        x, theta = -x, float(wrap_angle(theta + np.pi))
    y = np.cross([0.0, 0.0, 1.0], x)
    alpha = float(np.arctan2(-(z @ y), z[2]))
    a = float((point - [0.0, 0.0, d]) @ x)
    return np.array([theta, d, a, alpha])


def degeneracy(chain: SerialChain) -> str | None:
    """Why the joints of ``chain`` cannot move its tip in ``min(n, 6)`` independent ways,
    in words ("makes joints 5 and 6 turn about one axis, ..."), or None for a regular arm.

    Two consecutive revolute joints about one axis (or prismatic ones along one
    direction) are named; the rank of the tip's twists over the joints (lengths over
    the arm's size) is taken at three generic joint values (seeded: the same answer
    every run), so a rank lost only at a singular pose does not count.  A DH table read
    in the other convention usually shows here: the row of zeros ``(alpha, a) = (0, 0)``
    that a standard table has at its end and a modified one at its start moves between
    two joints, whose axes then coincide.

    Examples
    --------
    >>> degeneracy(SerialChain.from_mdh([0, 0], [0, 0], [0, 0], [0, 100.0]))
    'makes joints 1 and 2 turn about one axis, so its tip moves in 1 independent way, not 2'
    >>> degeneracy(SerialChain.from_mdh([0, 0], [0, 300.0], [0, 0], [0, 0])) is None
    True
    """
    n = chain.n_joints
    zero = chain.zero_frames()
    size = max(1.0, float(np.sum(np.linalg.norm(chain.origins[:, :3, 3], axis=1))))
    size += float(np.linalg.norm(chain.tip[:3, 3]))
    pair = None
    for k in range(n - 1):
        z, z_next = zero[k][:3, 2], zero[k + 1][:3, 2]
        if np.linalg.norm(np.cross(z, z_next)) > 1e-9:
            continue
        offset = np.linalg.norm(np.cross(z, zero[k + 1][:3, 3] - zero[k][:3, 3]))
        if chain.kinds[k] == chain.kinds[k + 1] == "R" and offset <= 1e-9 * size:
            pair = f"makes joints {k + 1} and {k + 2} turn about one axis"
        elif chain.kinds[k] == chain.kinds[k + 1] == "P":
            pair = f"makes joints {k + 1} and {k + 2} slide along one direction"
        if pair is not None:
            break
    full = min(n, 6)
    rank = 0
    for q in np.random.default_rng(0).uniform(-np.pi, np.pi, (3, n)):
        frame, columns = np.eye(4), []
        for k, kind in enumerate(chain.kinds):
            frame = frame @ chain.origins[k]
            z, p = frame[:3, 2], frame[:3, 3]
            line = np.cross(p, z) / size
            columns.append(np.concatenate([z, line]) if kind == "R" else np.r_[0, 0, 0, z])
            frame = frame @ joint_motion(kind, q[k])
        values = np.linalg.svd(np.array(columns).T, compute_uv=False)
        rank = max(rank, int(np.sum(values > 1e-9 * values[0])))
    ways = f"{rank} independent way{'s' if rank != 1 else ''}, not {full}"
    if rank < full:
        return f"{pair}, so its tip moves in {ways}" if pair else f"moves its tip in {ways}"
    return None if pair is None else f"{pair}: two of its joints do the work of one"


#: The two conventions of a DH table, by the robot TOML's key, in words.
CONVENTIONS = {
    "mdh": "modified DH (Craig: Rx(alpha) Tx(a) Rz(theta) Tz(d) per row)",
    "dh": "standard DH (Denavit-Hartenberg: Rz(theta) Tz(d) Tx(a) Rx(alpha) per row)",
}


def table_chain(
    convention: str,
    alpha: np.ndarray,
    a: np.ndarray,
    theta: np.ndarray,
    d: np.ndarray,
    kinds: tuple[str, ...],
    base: np.ndarray,
    tip: np.ndarray,
    *,
    beta: np.ndarray | None = None,
) -> SerialChain:
    """The chain of a DH table (rad, mm) read in ``convention`` (a key of
    :data:`CONVENTIONS`) between a ``base`` and a ``tip`` frame; ``beta`` (Hayati's) is
    modified DH's alone.

    Examples
    --------
    >>> row = (np.zeros(1), np.array([100.0]), np.zeros(1), np.zeros(1), ("R",))
    >>> np.round(table_chain("dh", *row, np.eye(4), np.eye(4)).forward([np.pi / 2])[:3, 3], 9)
    array([  0., 100.,   0.])
    """
    if convention == "mdh":
        beta = np.zeros_like(alpha) if beta is None else beta
        return MdhTable(alpha, a, beta, theta, d, kinds, base, tip).chain()
    chain = SerialChain.from_dh(theta, d, a, alpha, kinds=kinds)
    origins = chain.origins.copy()
    origins[0] = base @ origins[0]
    return replace(chain, origins=origins, tip=chain.tip @ tip)


def convention_mistake(
    convention: str,
    alpha: np.ndarray,
    a: np.ndarray,
    theta: np.ndarray,
    d: np.ndarray,
    kinds: tuple[str, ...],
    base: np.ndarray,
    tip: np.ndarray,
    *,
    beta: np.ndarray | None = None,
) -> str | None:
    """What to say of a table (:func:`table_chain`'s arguments) whose arm is degenerate in
    its ``convention`` and regular in the other (:func:`degeneracy`): the table of the
    other convention under the wrong name, the cheap and reliable sign of the mistake;
    None otherwise (a Hayati ``beta`` is modified DH's alone, so never a mistake).

    Examples
    --------
    >>> table = (np.radians([90, 0]), np.array([0, 0]), np.zeros(2), np.array([100, 50]),
    ...          ("R", "R"), np.eye(4), np.eye(4))
    >>> print(convention_mistake("mdh", *table))  # doctest: +NORMALIZE_WHITESPACE
    read as modified DH (Craig: Rx(alpha) Tx(a) Rz(theta) Tz(d) per row), the table makes
    joints 1 and 2 turn about one axis, so its tip moves in 1 independent way, not 2; read
    as standard DH (Denavit-Hartenberg: Rz(theta) Tz(d) Tx(a) Rx(alpha) per row), it is a
    regular arm: the table looks like standard DH; write it under [dh] (the same keys)
    """
    reason = degeneracy(table_chain(convention, alpha, a, theta, d, kinds, base, tip, beta=beta))
    if reason is None or (beta is not None and np.any(beta)):
        return None
    other = "dh" if convention == "mdh" else "mdh"
    if degeneracy(table_chain(other, alpha, a, theta, d, kinds, base, tip)) is not None:
        return None
    return (
        f"read as {CONVENTIONS[convention]}, the table {reason}; read as {CONVENTIONS[other]}, "
        f"it is a regular arm: the table looks like {CONVENTIONS[other].split(' (')[0]}; "
        f"write it under [{other}] (the same keys)"
    )
