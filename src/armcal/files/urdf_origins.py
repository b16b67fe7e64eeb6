"""A calibration written into the user's own URDF: the chain's joint origins, nothing else.

A calibrated spatial arm differs from its URDF only in where each joint of the
chain sits: the identified placement error ``E_k`` of joint ``k`` and its zero
offset (a turn about its own axis, or a slide along it) are one transform in
armcal's joint frame, whose z axis is the joint's axis.  In the URDF's own
joint frame, where the axis is ``<axis xyz>`` (the frame ``A_k`` turns z onto
it), that transform is ``A_k E_k A_k^T``, and the joint's new origin is

    ``O_k' = O_k A_k E_k A_k^T``.

Every link frame then moves with its joint as the calibration says, so meshes,
inertials, collision geometry and the tool frames beyond the tip, all given in
link frames, follow the calibrated arm.  The file is rewritten as text: only the
``<origin>`` element of each moving joint of the chain changes (one is added to
a joint that had none), and everything else -- names, limits, comments, off-chain
joints, transmissions, formatting -- is the original's, byte for byte.

The base pose of the calibration is the instrument's, not the robot's, and is
not written; a URDF whose chain does not match the calibration's (another
robot, another variant) is refused.  For a xacro, which cannot be expanded
without ROS, the same origins are written as a YAML file a macro can load
(:meth:`CalibratedOrigins.yaml`; docs/six-axis.md).
"""

from __future__ import annotations

import re
import xml.etree.ElementTree as ET
from collections.abc import Iterator, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..errors import InputError
from ..export_text import num
from ..models import CalibratedArm, SerialChain, SpatialArm, UrdfJoint, matrix_rpy
from ..models.spatial.chain import axis_frame, rpy_matrix, transform
from .urdf import parse_urdf, urdf_joint, urdf_tree

__all__ = ["CalibratedOrigins", "calibrated_origins", "rpy_near"]

#: A URDF is in metres, armcal in mm.
_MM_PER_M = 1000.0

#: The calibration's chain and the URDF's agree when every origin is within this many mm
#: and this many radians: the same file read twice agrees exactly, a copy whose numbers
#: were printed with 9 digits (``1.57079632679``) within 1e-11 rad and 1e-9 mm.
_SAME_MM, _SAME_RAD = 1e-6, 1e-9

#: An origin that moves less than this (mm, rad) is left as the file wrote it.
_UNCHANGED = 1e-12

_TAG = re.compile(r"<(/?)([A-Za-z_][\w:.-]*)((?:[^>\"']|\"[^\"]*\"|'[^']*')*?)(/?)>")
_NAME = re.compile(r"\bname\s*=\s*([\"'])(.*?)\1")


@dataclass(frozen=True, eq=False)
class _Element:
    """Where an element of the file's text starts and ends, and its opening tag's end."""

    tag: str
    name: str
    start: int
    open_end: int
    end: int
    depth: int


def _elements(text: str) -> list[_Element]:
    """Every element of ``text`` with its span, comments, CDATA and declarations skipped."""
    masked = re.sub(
        r"<!--.*?-->|<!\[CDATA\[.*?\]\]>|<\?.*?\?>|<!DOCTYPE[^>]*>",
        lambda m: " " * len(m.group()),
        text,
        flags=re.S,
    )
    out: list[_Element] = []
    stack: list[tuple[str, str, int, int]] = []
    for match in _TAG.finditer(masked):
        closing, tag, attrs, empty = match.groups()
        if closing:
            if stack and stack[-1][0] == tag:
                tag, name, start, open_end = stack.pop()
                out.append(_Element(tag, name, start, open_end, match.end(), len(stack)))
            continue
        found = _NAME.search(attrs)
        name = found.group(2) if found else ""
        if empty:
            out.append(_Element(tag, name, match.start(), match.end(), match.end(), len(stack)))
        else:
            stack.append((tag, name, match.start(), match.end()))
    return out


@dataclass(frozen=True, eq=False)
class CalibratedOrigins:
    """The calibrated origins of a URDF's chain joints, and the file they go into.

    Attributes
    ----------
    path : Path
        The original URDF.
    text : str
        Its text.
    joints : tuple of str
        The chain's moving joints, base to tip.
    xyz_m : ndarray, shape (n, 3)
        Every joint's calibrated ``<origin xyz>`` (m).
    rpy : ndarray, shape (n, 3)
        Its ``<origin rpy>`` (rad).
    changed : ndarray of bool, shape (n,)
        The joints whose origin the calibration moves (the others are left as written).
    """

    path: Path
    text: str
    joints: tuple[str, ...]
    xyz_m: np.ndarray
    rpy: np.ndarray
    changed: np.ndarray

    def _origin(self, k: int) -> str:
        xyz = " ".join(num(v) for v in self.xyz_m[k])
        rpy = " ".join(num(v) for v in self.rpy[k])
        return f'<origin xyz="{xyz}" rpy="{rpy}"/>'

    def urdf(self) -> str:
        """The original file with the calibrated origins: every other byte as it was."""
        text = self.text
        elements = _elements(text)
        joints = {e.name: e for e in elements if e.tag == "joint" and e.depth == 1}
        # the robot's joints (a transmission's <joint> is deeper), and their <origin>s
        origins = {e.start: e for e in elements if e.tag == "origin" and e.depth == 2}
        edits: list[tuple[int, int, str]] = []
        for k, name in enumerate(self.joints):
            if not self.changed[k]:
                continue
            joint = joints[name]
            inside = [e for start, e in origins.items() if joint.open_end <= start < joint.end]
            if inside:
                edits.append((inside[0].start, inside[0].end, self._origin(k)))
            else:
                line_start = text.rfind("\n", 0, joint.start) + 1
                indent = text[line_start : joint.start]
                sep = f"\n{indent}  " if "\n" in text[joint.open_end : joint.end] else ""
                edits.append((joint.open_end, joint.open_end, sep + self._origin(k)))
        for start, end, new in sorted(edits, reverse=True):
            text = text[:start] + new + text[end:]
        return text

    def yaml(self) -> str:
        """The calibrated origins as YAML, one mapping per joint (metres, radians), for a
        xacro macro that takes its joints' origins as properties."""
        lines = [
            f"# Calibrated joint origins of {self.path.name}'s chain, written by armcal:",
            '# <origin xyz="x y z" rpy="roll pitch yaw"/> of each joint (m, rad).',
        ]
        for k, name in enumerate(self.joints):
            values = (*self.xyz_m[k], *self.rpy[k])
            lines.append(f"{name}:")
            lines += [
                f"  {key}: {num(v)}"
                for key, v in zip(("x", "y", "z", "roll", "pitch", "yaw"), values, strict=True)
            ]
        return "\n".join(lines) + "\n"


def _clean(values: np.ndarray) -> np.ndarray:
    """``values`` with magnitudes below 1e-15 (round-off of a zero) set to 0."""
    return np.where(np.abs(values) < 1e-15, 0.0, values)


def rpy_near(rotation: np.ndarray, start: Sequence[float]) -> np.ndarray:
    """The roll, pitch and yaw of ``rotation`` nearest ``start`` (rad).

    Near a pitch of +-90 deg (a URDF's joint turned onto another axis, common) only
    roll - yaw or roll + yaw is fixed, and :func:`matrix_rpy` picks one solution of
    many; a calibrated origin written that way would look nothing like the original.
    Gauss-Newton from the original's angles, with the minimum-norm step where the
    Jacobian loses rank, reaches the rotation by the smallest change of the angles.

    Examples
    --------
    >>> start = [0.0, -np.pi / 2, -np.pi / 2]
    >>> turned = rpy_matrix(start) @ rpy_matrix([1e-3, 0.0, 0.0])
    >>> near = rpy_near(turned, start)
    >>> bool(np.allclose(rpy_matrix(near), turned, rtol=0, atol=1e-15))
    True
    >>> bool(np.max(np.abs(near - start)) < 2e-3)
    True
    """
    axes = np.eye(3)
    rpy = np.array(start, dtype=float)
    for _ in range(50):
        miss = (rpy_matrix(rpy) - rotation).ravel()
        if np.max(np.abs(miss)) <= 1e-16:
            break
        rz, ry, rx = (rpy_matrix(a) for a in ([0, 0, rpy[2]], [0, rpy[1], 0], [rpy[0], 0, 0]))
        turns = [np.cross(np.eye(3), axes[i]) for i in range(3)]  # K e_i: skew of each axis
        jac = np.stack(
            [
                (rz @ ry @ rx @ turns[0]).ravel(),
                (rz @ ry @ turns[1] @ rx).ravel(),
                (rz @ turns[2] @ ry @ rx).ravel(),
            ],
            axis=1,
        )
        rpy -= np.linalg.lstsq(jac, miss, rcond=1e-10)[0]
    if np.max(np.abs(rpy_matrix(rpy) - rotation)) > 1e-14:
        return matrix_rpy(rotation)  # a large turn: the closed form's angles
    return rpy


def _ancestors(
    path: Path, text: str, parent_joint: dict[str, ET.Element], link: str
) -> Iterator[tuple[str, np.ndarray]]:
    """``(link, F)`` from ``link`` up the tree while the joints are fixed: each link above
    and ``F``, the fixed joints' transform from it down to ``link``."""
    here, prefix = link, np.eye(4)
    yield here, prefix
    while here in parent_joint and parent_joint[here].get("type") == "fixed":
        joint = parent_joint[here]
        read = urdf_joint(path, text, joint)
        prefix = transform(rpy_matrix(read.rpy), read.xyz) @ prefix
        here = joint.find("parent").get("link", "")  # type: ignore[union-attr]  # checked
        yield here, prefix


def calibrated_origins(cal: CalibratedArm, original: str | Path) -> CalibratedOrigins:
    """The calibrated origins of ``cal`` (a spatial arm's calibration) in the URDF
    ``original`` it was made from (module notes).

    Raises
    ------
    InputError
        The file is not a URDF, lacks a joint of the calibration's chain, or its chain
        differs from the calibration's (another robot or variant): naming the joint and
        by how much.
    """
    path = Path(original)
    arm: SpatialArm = cal.arm  # the spatial family's role: given its calibrations
    root, text = parse_urdf(path)
    tree = urdf_tree(path, text, root)
    by_name = {j.get("name", ""): j for j in root.findall("joint")}
    chain = arm.chain
    calibrated = arm.calibrated_chain(cal.arm_params)
    reads: list[UrdfJoint] = []
    elements: list[ET.Element] = []
    for k, name in enumerate(chain.joint_names):
        element = by_name.get(name)
        if element is None or element.get("type") not in ("revolute", "continuous", "prismatic"):
            raise InputError(
                f"{path}: no moving joint {name!r}, joint {k + 1} of the calibration's chain "
                f"({', '.join(chain.joint_names)}); give the URDF of the calibrated robot"
            )
        elements.append(element)
        reads.append(urdf_joint(path, text, element))
    _check_same(path, text, tree.parent_joint, elements, chain, reads)
    xyz, rpy, changed = [], [], []
    for k, read in enumerate(reads):
        origin = transform(rpy_matrix(read.rpy), read.xyz)
        turn = transform(axis_frame(read.axis))
        error = np.linalg.solve(chain.origins[k], calibrated.origins[k])
        new = origin @ turn @ error @ np.linalg.inv(turn)
        # Round-off of exact zeros (1e-20 m) is written as 0: a reader's file stays clean.
        xyz.append(_clean(new[:3, 3] / _MM_PER_M))
        rpy.append(_clean(rpy_near(new[:3, :3], read.rpy)))
        moved = np.max(np.abs(new - origin)[:3, :3]) > _UNCHANGED
        changed.append(bool(moved or np.max(np.abs(new - origin)[:3, 3]) > _UNCHANGED))
    return CalibratedOrigins(
        path, text, tuple(chain.joint_names), np.array(xyz), np.array(rpy), np.array(changed)
    )


def _check_same(
    path: Path,
    text: str,
    parent_joint: dict[str, ET.Element],
    elements: list[ET.Element],
    chain: SerialChain,
    reads: list[UrdfJoint],
) -> None:
    """Refuse a URDF whose chain is not the calibration's: every joint where the chain has
    it in the frame of the joint before (through the fixed joints between), the first
    from some link above it (the calibration's base link)."""
    for k, read in enumerate(reads):
        own = transform(rpy_matrix(read.rpy), read.xyz) @ transform(axis_frame(read.axis))
        before = np.eye(4) if k == 0 else transform(axis_frame(reads[k - 1].axis)).T
        start = elements[k - 1].find("child") if k else None
        want = None if start is None else start.get("link", "")
        parent = elements[k].find("parent")
        link = "" if parent is None else parent.get("link", "")
        if not any(
            (want is None or above == want) and _same(before @ prefix @ own, chain.origins[k])
            for above, prefix in _ancestors(path, text, parent_joint, link)
        ):
            raise InputError(
                f"{path}: joint {read.name!r} (joint {k + 1} of the chain) is not where the "
                "calibration's robot has it: this URDF describes another robot or variant; "
                "give the URDF the calibration's robot file names"
            )


def _same(a: np.ndarray, b: np.ndarray) -> bool:
    """Two transforms alike within :data:`_SAME_MM` and :data:`_SAME_RAD`."""
    return bool(
        np.max(np.abs(a[:3, 3] - b[:3, 3])) <= _SAME_MM
        and np.max(np.abs(a[:3, :3] - b[:3, :3])) <= _SAME_RAD
    )
