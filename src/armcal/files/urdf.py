"""A URDF file as the serial chain armcal calibrates.

Read with the standard library's XML parser: armcal needs a URDF's links and
joints only (names, parents, ``<origin>``, ``<axis>``, ``<limit>``, ``<mimic>``),
not its meshes, materials or transmissions, and the URDF libraries that parse
those (urdfpy, yourdfpy) pull in trimesh, lxml and network-fetching resolvers
for ``package://`` meshes.  Errors name the file, the line and the element.

Units: a URDF is in metres and radians; the chain returned is in mm and rad
(a prismatic joint's limits in mm).
"""

from __future__ import annotations

import os
import xml.etree.ElementTree as ET
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..errors import InputError
from ..models import LinkMasses, SerialChain, UrdfJoint
from ..models.spatial_chain import axis_frame, rpy_matrix, transform
from .common import suggest

__all__ = [
    "UrdfChain",
    "read_urdf",
]

_MOVING = ("revolute", "continuous", "prismatic")
_KINDS = (*_MOVING, "fixed")


@dataclass(frozen=True, eq=False)
class UrdfChain:
    """The chain of a URDF from a base link to a tip link.

    Attributes
    ----------
    chain : SerialChain
    robot : str
        The URDF's ``<robot name>``.
    base_link, tip_link : str
    masses : LinkMasses or None
        Every moving link's mass and centre of mass (in armcal's joint frame, mm)
        from the ``<inertial>`` tags of the links each joint moves (through fixed
        joints, side branches included, a side branch that moves at its zero; a
        link without the tag weighs nothing); None when no such link has one.
    """

    chain: SerialChain
    robot: str
    base_link: str
    tip_link: str
    masses: LinkMasses | None = None


def _line_of(text: str, tag: str, name: str) -> int:
    """The line of ``<tag name="name"`` in ``text`` (1-based; 0 when not found)."""
    for quote in ('"', "'"):
        at = text.find(f"name={quote}{name}{quote}")
        while at >= 0:
            start = text.rfind("<", 0, at)
            if text[start + 1 : start + 1 + len(tag)] == tag:
                return text.count("\n", 0, at) + 1
            at = text.find(f"name={quote}{name}{quote}", at + 1)
    return 0


def _floats(path: Path, text: str, element: ET.Element, attr: str, count: int, where: str):
    raw = element.get(attr)
    if raw is None:
        return None
    parts = raw.split()
    try:
        values = tuple(float(v) for v in parts)
    except ValueError:
        values = ()
    if len(values) != count or not all(abs(v) < float("inf") for v in values):
        raise InputError(
            f"{path}: {where}: {attr}={raw!r} is not {count} numbers; write "
            f"{count} numbers separated by spaces (metres and radians)"
        )
    return values


def read_urdf(
    path: str | os.PathLike, base_link: str | None = None, tip_link: str | None = None
) -> UrdfChain:
    """The chain of the URDF at ``path`` from ``base_link`` (default: the root) to
    ``tip_link`` (default: the one leaf beyond the base).

    Raises
    ------
    InputError
        Naming the file (and line): a missing or malformed file; a link that is
        the child of two joints or a loop; an unknown base or tip link; several
        leaves and no tip link; a mimic joint on the chain; a joint of an unknown
        type or without a parent or child.
    """
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise InputError(f"{path}: no such URDF file; check the path") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise InputError(f"{path}: cannot read the URDF ({exc})") from None
    try:
        root = ET.fromstring(text)
    except ET.ParseError as exc:
        line, column = exc.position
        raise InputError(
            f"{path}: line {line}, column {column + 1}: not well-formed XML; fix the URDF"
        ) from None
    if root.tag != "robot":
        raise InputError(f"{path}: the root element is <{root.tag}>, not <robot>; is it a URDF?")
    links = [link.get("name", "") for link in root.findall("link")]
    parent_joint: dict[str, ET.Element] = {}
    children: dict[str, list[str]] = {name: [] for name in links}
    for joint in root.findall("joint"):
        name = joint.get("name", "")
        line = _line_of(text, "joint", name)
        where = f"line {line}, joint {name!r}"
        kind = joint.get("type", "")
        if kind not in _KINDS:
            raise InputError(
                f"{path}: {where}: type {kind!r} is not one armcal calibrates; a serial arm's "
                f"joints are {', '.join(_KINDS)}"
            )
        parent, child = joint.find("parent"), joint.find("child")
        if parent is None or child is None or not parent.get("link") or not child.get("link"):
            raise InputError(f"{path}: {where}: needs <parent link=...> and <child link=...>")
        for link in (parent.get("link", ""), child.get("link", "")):
            if link not in children:
                raise InputError(
                    f"{path}: {where}: link {link!r} is not a <link> of the URDF; "
                    f"{suggest(link, links)}declare it or correct the name"
                )
        child_name = child.get("link", "")
        if child_name in parent_joint:
            other = parent_joint[child_name].get("name")
            raise InputError(
                f"{path}: {where}: link {child_name!r} is already the child of joint {other!r}: "
                "the URDF has a loop; a serial arm is a tree (close loops outside the URDF)"
            )
        parent_joint[child_name] = joint
        children[parent.get("link", "")].append(child_name)
    roots = [name for name in links if name not in parent_joint]
    if len(roots) != 1:
        raise InputError(
            f"{path}: the URDF has {len(roots)} root links ({', '.join(roots) or 'none'}): "
            "a loop or a detached link; a URDF is one tree"
        )
    base = roots[0] if base_link is None else base_link
    ends: list[tuple[str, str | None]] = [("base_link", base), ("tip_link", tip_link)]
    for role, end in ends:
        if end is not None and end not in children:
            raise InputError(
                f"{path}: {role} {end!r} is not a link of the URDF; {suggest(end, links)}"
                f"its links are {', '.join(links)}"
            )
    if tip_link is None:
        leaves, stack = [], [base]
        while stack:
            link = stack.pop()
            stack.extend(children[link])
            if not children[link]:
                leaves.append(link)
        if len(leaves) != 1:
            raise InputError(
                f"{path}: {len(leaves)} links end chains beyond {base!r} "
                f"({', '.join(sorted(leaves))}); "
                "say which is the tip with --tip-link or tip_link in a robot TOML"
            )
        tip_link = leaves[0]
    chain: list[ET.Element] = []
    link = tip_link
    while link != base:
        if link not in parent_joint:
            raise InputError(
                f"{path}: tip_link {tip_link!r} does not lie beyond base_link {base!r}; "
                "choose links on one chain"
            )
        joint = parent_joint[link]
        chain.append(joint)
        parent = joint.find("parent")
        assert parent is not None
        link = parent.get("link", "")
    joints = [_joint(path, text, element) for element in reversed(chain)]
    try:
        serial = SerialChain.from_joints(joints)
    except ValueError as exc:
        raise InputError(f"{path}: the chain from {base!r} to {tip_link!r}: {exc}") from None
    moving = [(element, joint) for element, joint in zip(reversed(chain), joints, strict=True)]
    masses = _link_masses(path, text, root, moving, parent_joint, children)
    return UrdfChain(serial, root.get("name", path.stem), base, tip_link, masses)


def _inertials(path: Path, text: str, root: ET.Element) -> dict[str, tuple[float, np.ndarray]]:
    """Every link's ``<inertial>``: its mass (kg) and centre of mass in its frame (mm)."""
    out = {}
    for link in root.findall("link"):
        inertial = link.find("inertial")
        if inertial is None:
            continue
        name = link.get("name", "")
        where = f"line {_line_of(text, 'link', name)}, link {name!r}"
        mass = inertial.find("mass")
        value = None if mass is None else _floats(path, text, mass, "value", 1, where)
        if value is None or value[0] < 0:
            raise InputError(
                f"{path}: {where}: <inertial> needs <mass value> >= 0 (kg); give the link's mass"
            )
        origin = inertial.find("origin")
        xyz = None if origin is None else _floats(path, text, origin, "xyz", 3, where)
        out[name] = (value[0], 1000.0 * np.array(xyz or (0.0, 0.0, 0.0)))
    return out


def _origin(
    path: Path, text: str, element: ET.Element, where: str
) -> tuple[tuple[float, float, float], tuple[float, float, float]]:
    """A joint's ``<origin>``: ``xyz`` in mm and ``rpy`` in rad (zeros where absent)."""
    origin = element.find("origin")
    xyz = None if origin is None else _floats(path, text, origin, "xyz", 3, where)
    rpy = None if origin is None else _floats(path, text, origin, "rpy", 3, where)
    x, y, z = (1000.0 * v for v in (xyz or (0.0, 0.0, 0.0)))
    return (x, y, z), rpy or (0.0, 0.0, 0.0)


def _link_masses(
    path: Path,
    text: str,
    root: ET.Element,
    chain: list[tuple[ET.Element, UrdfJoint]],
    parent_joint: dict[str, ET.Element],
    children: dict[str, list[str]],
) -> LinkMasses | None:
    """What every moving joint of ``chain`` moves rigidly: mass and centre (module notes)."""
    inertial = _inertials(path, text, root)
    on_chain = {element for element, joint in chain if joint.kind != "fixed"}
    masses, centres, seen = [], [], False
    for element, joint in chain:
        if joint.kind == "fixed":
            continue
        child = element.find("child")
        assert child is not None
        total, moment = 0.0, np.zeros(3)
        stack = [(child.get("link", ""), np.eye(4))]
        while stack:
            link, frame = stack.pop()
            if link in inertial:
                mass, centre = inertial[link]
                total, moment = (
                    total + mass,
                    moment + mass * (frame[:3, :3] @ centre + frame[:3, 3]),
                )
                seen = True
            for below in children[link]:
                if parent_joint[below] in on_chain:
                    continue  # the next moving joint of the chain: its own link
                # a fixed joint, or a side branch that moves (a gripper's fingers) taken at
                # its zero: its weight loads the chain wherever it is
                side = parent_joint[below]
                where = f"line {_line_of(text, 'joint', side.get('name', ''))}"
                xyz, rpy = _origin(path, text, side, where)
                stack.append((below, frame @ transform(rpy_matrix(rpy), xyz)))
        centre = moment / total if total > 0 else np.zeros(3)
        masses.append(total)
        centres.append(axis_frame(joint.axis).T @ centre)  # armcal's frame: z along the axis
    return LinkMasses(np.array(masses), np.array(centres)) if seen else None


def _joint(path: Path, text: str, element: ET.Element) -> UrdfJoint:
    """One joint of the chain in mm and rad."""
    name = element.get("name", "")
    where = f"line {_line_of(text, 'joint', name)}, joint {name!r}"
    kind = element.get("type", "")
    if element.find("mimic") is not None and kind != "fixed":
        raise InputError(
            f"{path}: {where}: a mimic joint on the chain; armcal calibrates joints the "
            "controller reads: model the coupling with joint_map in a robot TOML"
        )
    xyz, rpy = _origin(path, text, element, where)
    axis_element = element.find("axis")
    axis = (1.0, 0.0, 0.0)
    if axis_element is not None:
        given = _floats(path, text, axis_element, "xyz", 3, where)
        if given is not None:
            axis = given
    if kind in _MOVING and sum(a * a for a in axis) < 1e-12:
        raise InputError(f"{path}: {where}: <axis xyz> is zero; give the joint's axis")
    limits = None
    limit = element.find("limit")
    if kind in ("revolute", "prismatic") and limit is not None:
        lo = _floats(path, text, limit, "lower", 1, where)
        hi = _floats(path, text, limit, "upper", 1, where)
        if lo is not None and hi is not None:
            scale = 1000.0 if kind == "prismatic" else 1.0
            if not lo[0] < hi[0]:
                raise InputError(f"{path}: {where}: <limit> needs lower < upper")
            limits = (lo[0] * scale, hi[0] * scale)
    return UrdfJoint(name, kind, xyz, rpy, (axis[0], axis[1], axis[2]), limits)
