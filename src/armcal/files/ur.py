"""Universal Robots' kinematics: the built-in nominal DH tables and the controller's
calibration file.

A UR controller describes the arm by a standard DH table (``Rz(q + theta) Tz(d)
Tx(a) Rx(alpha)`` per joint, metres and radians).  The nominal table of each
model is fixed (``urcontrol.conf``'s ``[DH]``; Universal Robots publishes it);
each robot's factory calibration is kept apart as *deltas* added element-wise
(``calibration.conf``, section ``[mounting]``: ``delta_theta``, ``delta_a``,
``delta_d``, ``delta_alpha``, six values each, one line each)::

    [mounting]
    delta_theta = [ -1.4e-07, 0.673081443308028327, ...]
    delta_d = [ 0.000247971363099203, 681.734313237237868, -696.406678436933362, ...]

The controller's real kinematics -- what it reports as its DH table -- are
nominal plus deltas.  The controller stores the twist ``pi/2`` as
``1.570796327`` (:data:`UR_QUARTER_TURN`), and so does this table.

**The trap.**  Joints 2, 3 and 4 of a UR are parallel by design; with real,
slightly tilted axes the standard DH common normals run off to where the axes
nearly meet, so ``delta_d`` of joints 2-4 holds hundreds or thousands of metres
of opposite sign that cancel.  They are exact, not wrong: armcal builds the chain
from the rows' transforms (:meth:`~armcal.models.SerialChain.from_dh`), where they
cancel to 1e-10 mm, and identifies errors in its own continuous parametrization,
never in ``d``.  A file whose calibrated flange lies far from the nominal model's
(:data:`FAR_FROM_NOMINAL_MM`) is flagged: another model, or values not in
metres and radians.
"""

from __future__ import annotations

import os
import re
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from ..errors import ArmcalError, ArmcalWarning, unrendered
from ..models import CalibratedArm, SpatialArm
from ..models.spatial.chain import SerialChain, elementary, transform
from ..models.spatial.dh import PARALLEL_COS, DhTable, dh_table
from ..numerics import wrap_angle
from .common import fail, read_text

__all__ = [
    "FAR_FROM_NOMINAL_MM",
    "UR_JOINTS",
    "UR_MODELS",
    "UR_QUARTER_TURN",
    "UrDh",
    "UrFrames",
    "format_ur_calibration",
    "format_ur_kinematics",
    "read_ur_calibration",
    "read_ur_kinematics",
    "ur_calibration_warning",
    "ur_chain",
    "ur_deltas",
    "ur_frames",
    "ur_model_of",
    "ur_nominal",
]

#: ``pi/2`` as the controller stores it (its twists and the ROS driver's defaults).
UR_QUARTER_TURN = 1.570796327

#: The joints, base to wrist, as the ROS driver names them.
UR_JOINTS = ("shoulder_pan", "shoulder_lift", "elbow", "wrist_1", "wrist_2", "wrist_3")

#: Nominal ``(d1, a2, a3, d4, d5, d6)`` (m) of each model: the published DH tables of
#: Universal Robots (the same values as the ROS description's ``default_kinematics``);
#: every other ``d`` and ``a`` and every ``theta`` is 0, and the twists are
#: ``[q, 0, 0, q, -q, 0]`` with ``q`` = :data:`UR_QUARTER_TURN`.
UR_MODELS: dict[str, tuple[float, float, float, float, float, float]] = {
    "ur3": (0.1519, -0.24365, -0.21325, 0.11235, 0.08535, 0.0819),
    "ur5": (0.089159, -0.425, -0.39225, 0.10915, 0.09465, 0.0823),
    "ur10": (0.1273, -0.612, -0.5723, 0.163941, 0.1157, 0.0922),
    "ur3e": (0.15185, -0.24355, -0.2132, 0.13105, 0.08535, 0.0921),
    "ur5e": (0.1625, -0.425, -0.3922, 0.1333, 0.0997, 0.0996),
    "ur10e": (0.1807, -0.6127, -0.57155, 0.17415, 0.11985, 0.11655),
    "ur16e": (0.1807, -0.4784, -0.36, 0.17415, 0.11985, 0.11655),
}

#: A calibration that moves the flange farther than this from the nominal model's (over
#: random poses) is not of this model, or not in metres and radians: real ones move it a
#: few millimetres.
FAR_FROM_NOMINAL_MM = 20.0

_KEYS = ("delta_theta", "delta_a", "delta_d", "delta_alpha")


@dataclass(frozen=True, eq=False)
class UrDh:
    """A standard DH table, or the deltas to one (metres and radians, six values each)."""

    theta: np.ndarray
    a: np.ndarray
    d: np.ndarray
    alpha: np.ndarray

    def __add__(self, other: UrDh) -> UrDh:
        return UrDh(
            self.theta + other.theta, self.a + other.a, self.d + other.d, self.alpha + other.alpha
        )

    def table(self) -> DhTable:
        """The same table in armcal's units (mm, rad)."""
        return DhTable(self.theta, 1000.0 * self.d, 1000.0 * self.a, self.alpha)


def ur_nominal(model: str) -> UrDh:
    """The nominal DH table of a UR model (a key of :data:`UR_MODELS`)."""
    d1, a2, a3, d4, d5, d6 = UR_MODELS[model]
    q = UR_QUARTER_TURN
    return UrDh(
        np.zeros(6),
        np.array([0.0, a2, a3, 0.0, 0.0, 0.0]),
        np.array([d1, 0.0, 0.0, d4, d5, d6]),
        np.array([q, 0.0, 0.0, q, -q, 0.0]),
    )


def ur_chain(dh: UrDh) -> SerialChain:
    """The chain of a UR's DH table (mm): the DH base frame to the flange."""
    return dh.table().chain(UR_JOINTS)


def ur_deltas(chain: SerialChain, model: str) -> UrDh:
    """The deltas to ``model``'s nominal table that give ``chain`` (the DH base frame to the
    flange, mm): its exact standard DH table (:func:`~armcal.models.spatial.dh.dh_table`,
    on the nominal table's branch) minus the nominal, in metres and radians, every angle
    within half a turn.  Nearly parallel axes give ``d`` deltas of metres that cancel, as
    the controller's own do."""
    nominal = ur_nominal(model)
    table = dh_table(chain, nominal.table())
    return UrDh(
        wrap_angle(table.theta - nominal.theta),
        table.a / 1000.0 - nominal.a,
        table.d / 1000.0 - nominal.d,
        wrap_angle(table.alpha - nominal.alpha),
    )


def _farthest_mm(chain: SerialChain, model: str, poses: int) -> float:
    """The largest distance (mm) between ``chain``'s flange and ``model``'s nominal one over
    ``poses`` random readings (seeded: the same figure every run)."""
    q = np.random.default_rng(0).uniform(-np.pi, np.pi, (poses, 6))
    moved = chain.forward(q)[..., :3, 3] - ur_chain(ur_nominal(model)).forward(q)[..., :3, 3]
    return float(np.max(np.linalg.norm(moved, axis=-1)))


@dataclass(frozen=True, eq=False)
class UrFrames:
    """Where a chain's base and tip frames lie from a UR model's DH frames.

    ``base @ chain.forward(q) @ tip`` is the model's kinematics from its DH base frame
    to its flange (:func:`ur_chain`) for a ``chain`` that is the model in other frames:
    Universal Robots' ROS description has ``base_link`` turned by half a turn about z
    from the controller's base frame, and ``tool0`` (or ``flange``, ``wrist_3_link``)
    at or about its flange.

    Attributes
    ----------
    model : str
        The UR model (a key of :data:`UR_MODELS`) nearest the chain.
    base, tip : ndarray, shape (4, 4)
        The chain's base frame in the DH base frame, and the DH flange in the chain's
        tip frame (the identity for a chain in the DH frames).
    distance_mm : float
        The largest distance left between the flanges over random poses.
    """

    model: str
    base: np.ndarray
    tip: np.ndarray
    distance_mm: float

    def apply(self, chain: SerialChain) -> SerialChain:
        """``chain`` (the same arm, calibrated or not) from the DH base frame to the flange."""
        origins = chain.origins.copy()
        origins[0] = self.base @ origins[0]
        return replace(chain, origins=origins, tip=chain.tip @ self.tip)


def _foot(line: np.ndarray) -> float:
    """Where on the z axis the common normal to the line of ``line``'s z axis (a frame
    ``(4, 4)`` in the z axis's frame, not parallel to it) meets the z axis."""
    z, p = line[:3, 2], line[:3, 3]
    return float((p[2] - z[2] * (p @ z)) / (1.0 - z[2] ** 2))


def _screw_part(frame: np.ndarray) -> np.ndarray:
    """``Rz(phi) Tz(s)``: the turn about and the slide along z of a ``frame`` that nearly
    keeps the z axis (the rest is the round-off of two descriptions of one arm)."""
    return transform(elementary(2, np.arctan2(frame[1, 0], frame[0, 0])), [0, 0, frame[2, 3]])


def _snapped(frame: np.ndarray) -> np.ndarray:
    """``frame`` with its rotation rounded to the nearest quarter turns and every coordinate
    of its translation within :data:`FAR_FROM_NOMINAL_MM` of 0 set to 0: the frames of a
    description differ from the DH ones by such (a calibration moves them by less)."""
    rotation = np.round(frame[:3, :3])
    if np.max(np.abs(frame[:3, :3] - rotation)) > 0.1 or not np.allclose(
        rotation @ rotation.T, np.eye(3)
    ):
        rotation = frame[:3, :3]
    shift = np.where(np.abs(frame[:3, 3]) < FAR_FROM_NOMINAL_MM, 0.0, frame[:3, 3])
    return transform(rotation, shift)


def _on_axis(frame: np.ndarray) -> bool:
    """Whether ``frame`` (in a joint's frame) has its z axis on the joint's axis."""
    return bool(np.linalg.norm(frame[:2, 2]) < 1e-12 and np.linalg.norm(frame[:2, 3]) < 1e-9)


def _frames_to(chain: SerialChain, model: str, poses: int) -> UrFrames:
    """:class:`UrFrames` of ``chain`` to ``model``'s DH frames.

    Joint 1's axis goes exactly onto the DH base frame's z axis (a DH table starts
    there), turned about and slid along it so that the first axis not parallel to it
    (a UR's joint 2) lies where the model's does; the flange sits on the last joint's
    axis, turned about and slid along it as the model's.  Axis lines do not depend on
    where a description puts a joint's frame along or about its axis.  Those frames,
    rounded to quarter turns and to no offset where that keeps joint 1's axis and the
    flange where a DH table needs them (:func:`_snapped`), are a description's own: a
    calibrated description (a UR's calibration file, or the ROS description with the
    robot's calibration YAML) gives the same frames as the nominal one, and its
    calibration stays in the chain.
    """
    nominal = ur_chain(ur_nominal(model))
    mine, theirs = chain.zero_frames(), nominal.zero_frames()
    rel_mine = np.linalg.solve(mine[0], mine)
    rel_theirs = np.linalg.solve(theirs[0], theirs)
    k = next((k for k in range(1, 6) if abs(rel_mine[k, 2, 2]) < PARALLEL_COS), None)
    turn = slide = 0.0
    if k is not None:  # a UR's joint 2
        turn = np.arctan2(rel_theirs[k, 1, 2], rel_theirs[k, 0, 2]) - np.arctan2(
            rel_mine[k, 1, 2], rel_mine[k, 0, 2]
        )
        slide = _foot(rel_theirs[k]) - _foot(rel_mine[k])
    base = theirs[0] @ transform(elementary(2, turn), [0, 0, slide]) @ np.linalg.inv(mine[0])
    last = _screw_part(np.linalg.solve(base @ mine[-1], theirs[-1]))
    tip = np.linalg.solve(chain.tip, last @ nominal.tip)
    rounded = _snapped(base)
    if _on_axis(rounded @ chain.origins[0]):
        base = rounded
    rounded = _snapped(tip)
    if _on_axis(chain.tip @ rounded):
        tip = rounded
    frames = UrFrames(model, base, tip, 0.0)
    return replace(frames, distance_mm=_farthest_mm(frames.apply(chain), model, poses))


def ur_frames(chain: SerialChain, *, poses: int = 200) -> UrFrames:
    """The UR model that ``chain`` (six revolute joints) is in some base and tip frames, and
    those frames (:class:`UrFrames`): the model whose flange, in them, lies nearest the
    chain's over ``poses`` random readings.  ``chain`` is a nominal one: its frames then
    hold for every calibration of it (:meth:`UrFrames.apply`).

    Examples
    --------
    >>> turned = transform(elementary(2, np.pi))  # ROS's base_link from the DH base frame
    >>> chain = ur_chain(ur_nominal("ur5"))
    >>> origins = chain.origins.copy()
    >>> origins[0] = turned @ origins[0]
    >>> found = ur_frames(replace(chain, origins=origins))
    >>> found.model, bool(found.distance_mm < 1e-9)
    ('ur5', True)
    """
    found = [_frames_to(chain, model, poses) for model in UR_MODELS]
    return min(found, key=lambda frames: frames.distance_mm)


def ur_model_of(chain: SerialChain, *, poses: int = 200) -> tuple[str, float]:
    """The UR model whose nominal flange lies nearest ``chain``'s over random poses, and
    that largest distance (mm): models differ by centimetres, a calibration by millimetres."""
    distance = {model: _farthest_mm(chain, model, poses) for model in UR_MODELS}
    model = min(distance, key=distance.__getitem__)
    return model, distance[model]


_LIST = re.compile(r"^\[(.*)\]$")


def read_ur_calibration(path: str | os.PathLike) -> UrDh:
    """The deltas of a UR controller's ``calibration.conf`` (module notes).

    The other keys of the file (checksums, the calibration status, raw offsets)
    are the controller's own and are not read.

    Raises
    ------
    InputError
        Naming the file, the line and the key, for a missing ``[mounting]``
        section or delta, or a value that is not six numbers.
    """
    text = read_text(path, "UR calibration")
    section, found, mounted = None, {}, False
    for number, raw in enumerate(text.splitlines(), start=1):
        line = raw.split("#", 1)[0].strip()
        if not line:
            continue
        if line.startswith("[") and line.endswith("]") and "=" not in line:
            section = line[1:-1].strip()
            mounted = mounted or section == "mounting"
            continue
        if section != "mounting" or "=" not in line:
            continue
        key, value = (part.strip() for part in line.split("=", 1))
        if key not in _KEYS:
            continue
        match = _LIST.match(value)
        values = [] if match is None else [v.strip() for v in match.group(1).split(",")]
        try:
            numbers = [float(v) for v in values]
        except ValueError:
            numbers = []
        if len(numbers) != 6 or not all(np.isfinite(numbers)):
            raise fail(
                path,
                f"line {number}: key '{key}': expected six numbers as [ v1, ..., v6] (metres "
                f"and radians, as the controller writes them), got {value!r}",
            )
        found[key] = np.array(numbers)
    missing = [key for key in _KEYS if key not in found]
    if missing:
        where = "" if mounted else " and no [mounting] section"
        raise fail(
            path,
            f"has no '{missing[0]}'{where}: a UR controller's calibration.conf has a "
            f"[mounting] section with {', '.join(_KEYS)}; give that file",
        )
    return UrDh(found["delta_theta"], found["delta_a"], found["delta_d"], found["delta_alpha"])


def format_ur_calibration(deltas: UrDh) -> str:
    """The ``[mounting]`` deltas in the controller's text form: ``%.18g`` numbers, which
    read back exactly (:func:`read_ur_calibration`)."""

    def listed(values: np.ndarray) -> str:
        return "[ " + ", ".join(format(float(v), ".18g") for v in values) + "]"

    rows = [f"{key} = {listed(getattr(deltas, key[6:]))}" for key in _KEYS]
    return "\n".join(["[mounting]", *rows]) + "\n"


def ur_calibration_warning(
    path: str | os.PathLike, model: str, calibrated: SerialChain, *, poses: int = 1000
) -> ArmcalWarning | None:
    """``ur-calibration-far`` when the ``calibrated`` chain's flange lies farther than
    :data:`FAR_FROM_NOMINAL_MM` from the nominal model's at ``poses`` random poses."""
    largest = _farthest_mm(calibrated, model, poses)
    if largest <= FAR_FROM_NOMINAL_MM:
        return None
    return ArmcalWarning(
        "ur-calibration-far",
        f"{Path(path).name}: it moves the flange up to {largest:.4g} mm from the "
        f"nominal {model}'s (a factory calibration moves it a few mm): check that the file is "
        f"this {model}'s, and that its values are in metres and radians",
    )


#: The ROS driver's names of the six joint frames in its calibration YAML, base to wrist.
ROS_FRAMES = ("shoulder", "upper_arm", "forearm", "wrist_1", "wrist_2", "wrist_3")
_POSE_KEYS = ("x", "y", "z", "roll", "pitch", "yaw")


def _xyz_angles(rotation: np.ndarray) -> tuple[float, float, float]:
    """``(roll, pitch, yaw)`` with ``R = Rx(roll) Ry(pitch) Rz(yaw)``: the order the ROS
    driver's calibration tool writes (Eigen's ``eulerAngles(0, 1, 2)``)."""
    pitch = float(np.arcsin(np.clip(rotation[0, 2], -1.0, 1.0)))
    roll = float(np.arctan2(-rotation[1, 2], rotation[2, 2]))
    yaw = float(np.arctan2(-rotation[0, 1], rotation[0, 0]))
    return roll, pitch, yaw


def _xyz_rotation(roll: float, pitch: float, yaw: float) -> np.ndarray:
    return elementary(0, roll) @ elementary(1, pitch) @ elementary(2, yaw)


def _ros_frames(dh: UrDh) -> np.ndarray:
    """The joint frames ``(6, 4, 4)`` (mm, at zero readings) where the ROS description puts
    them: joint ``k``'s at the foot of its DH row's ``Rz(theta) Tz(d)``, the last at the
    flange."""
    frames, frame = [], np.eye(4)
    for k in range(6):
        if k:
            frame = frame @ transform(elementary(0, dh.alpha[k - 1]), [1000.0 * dh.a[k - 1], 0, 0])
        frame = frame @ transform(elementary(2, dh.theta[k]), [0.0, 0.0, 1000.0 * dh.d[k]])
        frames.append(frame)
    return np.array(frames)


def format_ur_kinematics(chain: SerialChain, model: str, label: str) -> str:
    """``chain`` (a UR ``model`` from its DH base frame, mm) as the ROS driver's calibration
    YAML: every joint frame in the one before, ``x, y, z`` in metres and ``roll, pitch,
    yaw`` in radians with ``R = Rx(roll) Ry(pitch) Rz(yaw)``, as the driver's calibration
    tool writes them.  Each joint frame slides along and turns about its own axis (the
    same kinematics) to where the ROS description has the model's (:func:`_ros_frames`),
    so its links' meshes hang where they belong; the last one is the flange.  ``hash`` is
    ``label``: the driver compares it with the controller's and warns when they differ,
    as they do for a calibration the controller does not hold.

    The ROS description puts these numbers into URDF ``rpy`` (``Rz Ry Rx``), which differs
    for angles that are not multiples of a quarter turn: for a calibration's milliradians,
    micrometres at the flange.  armcal's URDF export has no such difference.

    Raises
    ------
    ValueError
        If the flange is not on the last joint's axis (a UR joint frame is).
    """
    tip = chain.tip
    if np.linalg.norm(tip[:2, 2]) > 1e-12 or np.linalg.norm(tip[:2, 3]) > 1e-9:
        raise ValueError("the flange is not on the last joint's axis, where a UR's joint frame is")
    world = chain.zero_frames()
    world[5] = world[5] @ tip
    placed = []
    for k, (frame, where) in enumerate(zip(world, _ros_frames(ur_nominal(model)), strict=True)):
        if k < 5:  # slide along and turn about the joint's own axis
            z, x = frame[:3, 2], frame[:3, 0]
            slide = float((where[:3, 3] - frame[:3, 3]) @ z)
            aim = where[:3, 0] - (where[:3, 0] @ z) * z
            turn = float(np.arctan2(np.cross(x, aim) @ z, x @ aim))
            frame = frame @ transform(elementary(2, turn), [0.0, 0.0, slide])
        placed.append(frame)
    lines = ["kinematics:"]
    for k, name in enumerate(ROS_FRAMES):
        step = placed[0] if k == 0 else np.linalg.solve(placed[k - 1], placed[k])
        values = (*(step[:3, 3] / 1000.0), *_xyz_angles(step[:3, :3]))
        lines.append(f"  {name}:")
        lines += [f"    {key}: {float(v)!r}" for key, v in zip(_POSE_KEYS, values, strict=True)]
    lines.append(f"  hash: {label}")
    return "\n".join(lines) + "\n"


def read_ur_kinematics(path: str | os.PathLike) -> SerialChain:
    """The chain (mm) of the ROS driver's calibration YAML (:func:`format_ur_kinematics`'s
    layout, block or flow style, as the driver's calibration tool and the ROS description
    write it).

    Raises
    ------
    InputError
        Naming the file and the entry, for a missing frame or value.
    """
    text = read_text(path, "UR kinematics")
    frames: dict[str, dict[str, float]] = {}
    current = None
    for number, raw in enumerate(text.splitlines(), start=1):
        line = raw.split("#", 1)[0].rstrip()
        name, _, rest = line.strip().partition(":")
        if not line.strip() or name in ("kinematics", "hash"):
            continue
        rest = rest.strip()
        if name in ROS_FRAMES:
            current = frames.setdefault(name, {})
            pairs = [p.partition(":")[::2] for p in rest.strip("{}").split(",")] if rest else []
        elif current is not None and name in _POSE_KEYS:
            pairs = [(name, rest)]
        else:
            continue
        for key, value in pairs:
            try:
                current[key.strip()] = float(value)
            except ValueError:
                current[key.strip()] = np.nan
            if not np.isfinite(current[key.strip()]):
                raise fail(
                    path,
                    f"line {number}: {key.strip()!r}: expected a number, got {value.strip()!r}",
                )
    origins = []
    for name in ROS_FRAMES:
        entry = frames.get(name, {})
        missing = [key for key in _POSE_KEYS if key not in entry]
        if missing:
            raise fail(
                path,
                f"kinematics.{name}.{missing[0]} is missing: the ROS driver's calibration YAML "
                f"gives {', '.join(_POSE_KEYS)} for each of {', '.join(ROS_FRAMES)}",
            )
        rotation = _xyz_rotation(entry["roll"], entry["pitch"], entry["yaw"])
        origins.append(transform(rotation, 1000.0 * np.array([entry[k] for k in "xyz"])))
    limits = np.tile([-np.inf, np.inf], (6, 1))
    return SerialChain(np.array(origins), ("R",) * 6, np.eye(4), UR_JOINTS, limits)


def _ur_arm(cal: CalibratedArm, path: str) -> tuple[SerialChain, str, UrDh]:
    """The calibrated chain of a UR arm (DH base frame to flange, whatever frames its
    description used: :func:`armcal.files.ur.ur_frames`), its model
    (:func:`armcal.files.ur.ur_model_of`) and its deltas from that model's table, for a
    controller's file at ``path``."""
    arm: SpatialArm = cal.arm
    if arm.n_joints != 6 or set(arm.chain.kinds) != {"R"}:
        raise ArmcalError(f"{path}: a UR file needs a six-axis revolute arm; {arm.name} is not")
    frames = ur_frames(arm.chain)  # of the nominal: they hold for its calibration
    if frames.distance_mm > FAR_FROM_NOMINAL_MM:
        raise ArmcalError(
            f"{path}: {arm.name} is no UR model in any base and tip frames (nearest "
            f"{frames.model}, {frames.distance_mm:.4g} mm away); describe the arm with a robot "
            "file's [ur] table or Universal Robots' own URDF"
        )
    chain = frames.apply(arm.calibrated_chain(cal.arm_params))
    model, distance = ur_model_of(chain)
    if distance > FAR_FROM_NOMINAL_MM:
        raise ArmcalError(
            f"{path}: the calibrated {arm.name} moves the flange {distance:.4g} mm from the "
            f"nominal {model}'s (a calibration moves it a few mm); check the calibration"
        )
    try:
        deltas = ur_deltas(chain, model)
    except ValueError as exc:  # what a UR's DH table cannot hold, e.g. a tilted joint 1
        raise ArmcalError(
            f"{path}: the calibrated {arm.name} has no UR DH table: {unrendered(exc)}; a UR's "
            "table starts "
            "at joint 1's axis, so leave the base pose free (the joint's placement merges "
            "into it) rather than fixing base.* and identifying j1.*"
        ) from None
    return chain, model, deltas


def ur_texts(cal: CalibratedArm, ur_path: str | None, ros_path: str | None) -> dict[str, str]:
    """A UR controller's calibration.conf deltas and the ROS driver's calibration YAML."""
    texts: dict[str, str] = {}
    first = ur_path if ur_path is not None else ros_path
    if first is None:
        return texts
    chain, model, deltas = _ur_arm(cal, first)
    if ur_path is not None:
        texts[ur_path] = format_ur_calibration(deltas)
    if ros_path is not None:
        try:
            texts[ros_path] = format_ur_kinematics(chain, model, f"armcal_{cal.arm.name}_{model}")
        except ValueError as exc:
            raise ArmcalError(
                f"{ros_path}: the calibrated {cal.arm.name}: {unrendered(exc)}"
            ) from None
    return texts
