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

import codecs
import math
import os
import re
import xml.etree.ElementTree as ET
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..errors import ArmcalWarning, InputError, action, unrendered
from ..models import LinkMasses, SerialChain, UrdfJoint
from ..models.spatial.chain import axis_frame, rpy_matrix, transform
from .common import suggest

__all__ = [
    "GRIPPER_WORDS",
    "RPY_BOUND_RAD",
    "UrdfChain",
    "UrdfTree",
    "parse_urdf",
    "read_urdf",
    "urdf_joint",
    "urdf_tree",
]

_MOVING = ("revolute", "continuous", "prismatic")
_KINDS = (*_MOVING, "fixed")
#: Every joint type of the URDF format; floating and planar ones only off the chain.
_URDF_KINDS = (*_KINDS, "floating", "planar")

#: The largest rpy angle (rad) of a URDF origin: any orientation has angles within +-pi,
#: and a file may write 2 pi (with the last digits of a rounding); beyond it the angles
#: are degrees (rpy="90 0 0" read as radians turns by 90 rad = 5157 deg).
RPY_BOUND_RAD = 2 * math.pi + 2e-3


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
    warnings : tuple of ArmcalWarning
        What the chain warns of (:func:`read_urdf`).
    """

    chain: SerialChain
    robot: str
    base_link: str
    tip_link: str
    masses: LinkMasses | None = None
    warnings: tuple[ArmcalWarning, ...] = ()


def _lines_of(text: str, tag: str, name: str) -> list[int]:
    """Every line of ``<tag name="name"`` in ``text`` (1-based), in order."""
    lines = []
    for quote in ('"', "'"):
        at = text.find(f"name={quote}{name}{quote}")
        while at >= 0:
            start = text.rfind("<", 0, at)
            if text[start + 1 : start + 1 + len(tag)] == tag:
                lines.append(text.count("\n", 0, at) + 1)
            at = text.find(f"name={quote}{name}{quote}", at + 1)
    return sorted(lines)


def _line_of(text: str, tag: str, name: str) -> int:
    """The line of ``<tag name="name"`` in ``text`` (1-based; 0 when not found)."""
    lines = _lines_of(text, tag, name)
    return lines[0] if lines else 0


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
        xacro = (
            " (a xacro expression: expand the xacro file into a URDF first)" if "$" in raw else ""
        )
        raise InputError(
            f"{path}: {where}: {attr}={raw!r} is not {count} numbers{xacro}; write "
            f"{count} numbers separated by spaces (metres and radians)"
        )
    return values


#: xacro's namespaces (a xacro file declares one of them for its ``<xacro:...>`` elements).
_XACRO = ("{http://www.ros.org/wiki/xacro}", "{http://ros.org/wiki/xacro}")

#: What xacro, ROS's macro language for URDF, asks of a user who gives its source.
_EXPAND = "expand it into a URDF first (ROS's xacro: xacro robot.urdf.xacro > robot.urdf)"


def _text(data: bytes) -> str:
    """The file's text, decoded as the XML parser decodes it (its byte order mark or its
    declared encoding, else UTF-8), for the lines of elements in messages."""
    for bom, codec in ((codecs.BOM_UTF8, "utf-8-sig"), (codecs.BOM_UTF16_LE, "utf-16"),
                       (codecs.BOM_UTF16_BE, "utf-16")):  # fmt: skip
        if data.startswith(bom):
            return data.decode(codec, errors="replace")
    declared = re.match(rb"<\?xml[^>]*encoding\s*=\s*[\"']([A-Za-z0-9._-]+)[\"']", data)
    try:
        return data.decode(declared.group(1).decode() if declared else "utf-8", errors="replace")
    except LookupError:  # an encoding the parser knows and Python does not
        return data.decode("utf-8", errors="replace")


def parse_urdf(path: Path) -> tuple[ET.Element, str]:
    """The root element of the URDF at ``path`` and its text.

    The parser gets the bytes, so it honours the file's declared encoding (a Latin-1
    URDF that says so reads as it should).
    """
    try:
        data = path.read_bytes()
    except FileNotFoundError:
        raise InputError(f"{path}: no such URDF file; check the path") from None
    except OSError as exc:
        raise InputError(f"{path}: cannot read the URDF ({exc})") from None
    if not data.strip():
        raise InputError(f"{path}: the file is empty; give the robot's URDF")
    try:
        root = ET.fromstring(data)
    except LookupError as exc:  # a declared encoding Python does not know
        raise InputError(
            f"{path}: {exc}: declare an encoding the XML parser knows (UTF-8, ISO-8859-1) or "
            "save the file as UTF-8"
        ) from None
    except ET.ParseError as exc:
        line, column = exc.position
        fix = "fix the URDF"
        if b"xacro:" in data or b"${" in data:
            fix = f"it is a xacro file, not a URDF: {_EXPAND}"
        elif not data.lstrip().startswith(b"<"):
            fix = "a URDF is XML (<robot name=...>); is this the robot's URDF?"
        elif not _declares_encoding(data) and not _is_utf8(data):
            fix = (
                "its bytes are not UTF-8 and it declares no encoding: save it as UTF-8, or "
                'declare its encoding (<?xml version="1.0" encoding="ISO-8859-1"?>)'
            )
        raise InputError(
            f"{path}: line {line}, column {column + 1}: not well-formed XML; {fix}"
        ) from None
    text = _text(data)
    if root.tag != "robot":
        raise InputError(f"{path}: the root element is <{root.tag}>, not <robot>; is it a URDF?")
    for element in root.iter():
        if element.tag.startswith(_XACRO) or any("${" in v for v in element.attrib.values()):
            raise InputError(
                f"{path}: a xacro file (<xacro:...> elements or ${{...}} expressions), not a "
                f"URDF: {_EXPAND}"
            )
    return root, text


def _declares_encoding(data: bytes) -> bool:
    return re.match(rb"<\?xml[^>]*encoding\s*=", data.lstrip()) is not None


def _is_utf8(data: bytes) -> bool:
    try:
        data.decode("utf-8")
    except UnicodeDecodeError:
        return False
    return True


def _unique(path: Path, text: str, root: ET.Element, tag: str) -> list[str]:
    """The names of ``root``'s ``<tag>`` elements, refusing a name given twice."""
    names = [element.get("name", "") for element in root.findall(tag)]
    seen: set[str] = set()
    for name in names:
        if name in seen:
            lines = _lines_of(text, tag, name)
            where = f" (lines {lines[0]} and {lines[1]})" if len(lines) > 1 else ""
            also = " (and the joints that name it)" if tag == "link" else ""
            raise InputError(
                f"{path}: {tag} {name!r} is declared twice{where}; a URDF's {tag} names are "
                f"unique: rename one of them{also}"
            )
        seen.add(name)
    return names


@dataclass(frozen=True, eq=False)
class UrdfTree:
    """A URDF's links and joints as a tree: every link's parent joint, every link's
    children, and the joints other joints mimic."""

    links: list[str]
    parent_joint: dict[str, ET.Element]
    children: dict[str, list[str]]
    mimicked: set[str]


def urdf_tree(path: Path, text: str, root: ET.Element) -> UrdfTree:
    """The URDF's tree, every joint checked: a known type, a parent and a child that are
    links, no link the child of two joints (a loop)."""
    links = _unique(path, text, root, "link")
    _unique(path, text, root, "joint")
    parent_joint: dict[str, ET.Element] = {}
    children: dict[str, list[str]] = {name: [] for name in links}
    mimicked: set[str] = set()
    for joint in root.findall("joint"):
        name = joint.get("name", "")
        line = _line_of(text, "joint", name)
        where = f"line {line}, joint {name!r}"
        kind = joint.get("type", "")
        if kind not in _URDF_KINDS:
            raise InputError(
                f"{path}: {where}: type {kind!r} is not a URDF joint's; a serial arm's joints "
                f"are {', '.join(_KINDS)}"
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
        mimic = joint.find("mimic")
        if mimic is not None:
            mimicked.add(mimic.get("joint", ""))
    return UrdfTree(links, parent_joint, children, mimicked)


def _ends(
    path: Path, tree: UrdfTree, base_link: str | None, tip_link: str | None
) -> tuple[str, str]:
    """The chain's base link (default: the one root) and tip link (default: the one leaf
    beyond the base), each checked to be a link of the URDF."""
    links, children = tree.links, tree.children
    roots = [name for name in links if name not in tree.parent_joint]
    if not roots:
        raise InputError(
            f"{path}: every link is the child of a joint, so the joints form a loop; a URDF "
            "is one tree from one root link"
        )
    if len(roots) > 1:
        raise InputError(
            f"{path}: the URDF has {len(roots)} root links ({', '.join(roots)}): links that "
            "no joint connects to the others; a URDF is one tree: join them with a joint or "
            "remove them"
        )
    base = roots[0] if base_link is None else base_link
    ends: list[tuple[str, str | None]] = [("base_link", base), ("tip_link", tip_link)]
    for role, end in ends:
        if end is not None and end not in children:
            raise InputError(
                f"{path}: {role} {end!r} is not a link of the URDF; {suggest(end, links)}"
                f"its links are {', '.join(links)}"
            )
    if tip_link is not None:
        return base, tip_link
    leaves, stack = [], [base]
    while stack:
        link = stack.pop()
        stack.extend(children[link])
        if not children[link]:
            leaves.append(link)
    if len(leaves) != 1:
        counted = ", ".join(
            f"{leaf}: {_moving_to(leaf, base, tree.parent_joint)} joints"
            for leaf in sorted(leaves)
        )
        raise InputError(
            f"{path}: {len(leaves)} links end chains beyond {base!r} ({counted}); say "
            f"which is the tip: {action('choose-tip')}"
        )
    return base, leaves[0]


def _chain_joints(path: Path, tree: UrdfTree, base: str, tip_link: str) -> list[ET.Element]:
    """The joints from ``base`` to ``tip_link``, base first; refused when the tip does not
    lie beyond the base."""
    chain: list[ET.Element] = []
    link = tip_link
    while link != base:
        if link not in tree.parent_joint:
            raise InputError(
                f"{path}: tip_link {tip_link!r} does not lie beyond base_link {base!r}; "
                "choose links on one chain"
            )
        joint = tree.parent_joint[link]
        chain.append(joint)
        parent = joint.find("parent")
        assert parent is not None
        link = parent.get("link", "")
    chain.reverse()
    return chain


def read_urdf(
    path: str | os.PathLike, base_link: str | None = None, tip_link: str | None = None
) -> UrdfChain:
    """The chain of the URDF at ``path`` from ``base_link`` (default: the root) to
    ``tip_link`` (default: the one leaf beyond the base).

    Joints off the chain (a gripper's fingers, a camera's mount) are ignored, of any
    kind.  The chain's warnings (:attr:`UrdfChain.warnings`): ``gripper-joint`` when it
    ends in a joint that looks like a gripper's.

    Raises
    ------
    InputError
        Naming the file (and line): a missing, empty or malformed file, or a xacro
        file; a link or joint name declared twice; a link that is the child of two
        joints or a loop; an unknown base or tip link; several leaves and no tip link;
        a mimic, floating or planar joint on the chain; a joint of an unknown type or
        without a parent or child.
    """
    path = Path(path)
    root, text = parse_urdf(path)
    tree = urdf_tree(path, text, root)
    base, tip_link = _ends(path, tree, base_link, tip_link)
    chain = _chain_joints(path, tree, base, tip_link)
    _check_chain(path, text, chain, base, tip_link)
    joints = [urdf_joint(path, text, element) for element in chain]
    if all(joint.kind == "fixed" for joint in joints):
        raise InputError(
            f"{path}: no moving joint (revolute, continuous or prismatic) from base_link "
            f"{base!r} to tip_link {tip_link!r}; choose links with the arm's joints between them"
        )
    try:
        serial = SerialChain.from_joints(joints)
    except ValueError as exc:
        raise InputError(
            f"{path}: the chain from {base!r} to {tip_link!r}: {unrendered(exc)}"
        ) from None
    moving = [(element, joint) for element, joint in zip(chain, joints, strict=True)]
    masses = _link_masses(path, text, root, moving, tree.parent_joint, tree.children)
    gripper = _gripper_warning(path, text, chain, tree.mimicked)
    warnings = () if gripper is None else (gripper,)
    return UrdfChain(serial, root.get("name", path.stem), base, tip_link, masses, warnings)


def _moving_to(link: str, base: str, parent_joint: dict[str, ET.Element]) -> int:
    """How many moving joints lie between ``base`` and ``link`` (beyond it)."""
    count = 0
    while link != base:
        joint = parent_joint[link]
        count += joint.get("type") != "fixed"
        parent = joint.find("parent")
        assert parent is not None
        link = parent.get("link", "")
    return count


def _check_chain(path: Path, text: str, chain: list[ET.Element], base: str, tip: str) -> None:
    """Refuse a joint on the chain that armcal cannot calibrate: a floating or planar one (no
    reading of its own), or a mimic joint (its value follows another's)."""
    for element in chain:
        name, kind = element.get("name", ""), element.get("type", "")
        where = f"line {_line_of(text, 'joint', name)}, joint {name!r}"
        parent = element.find("parent")
        child = element.find("child")
        assert parent is not None and child is not None
        if kind not in _KINDS:
            raise InputError(
                f"{path}: {where}: a {kind} joint on the chain from {base!r} to {tip!r} (it "
                "moves in several directions, with no reading of its own: a mobile base, "
                f"say); start the chain beyond it, at link {child.get('link')!r}: "
                f"{action('choose-base')}"
            )
        mimic = element.find("mimic")
        if mimic is not None and kind != "fixed":
            raise InputError(
                f"{path}: {where}: a mimic joint on the chain (its value follows joint "
                f"{mimic.get('joint', '')!r}), which armcal does not model: the controller "
                "reads no value of its own for it; if it is a gripper's, end the chain before "
                f"it, at link {parent.get('link')!r}: {action('choose-tip')}"
            )


#: Words in a joint's or its link's name that say it is a gripper's, not the arm's.
GRIPPER_WORDS = ("finger", "gripper", "jaw", "hand", "claw")


def _gripper_warning(
    path: Path, text: str, chain: list[ET.Element], mimicked: set[str]
) -> ArmcalWarning | None:
    """``gripper-joint`` when the chain ends in moving joints that look like a gripper's
    (a name of :data:`GRIPPER_WORDS`, or a joint other joints mimic), with the link before
    them as the tip to choose."""
    moving = [element for element in chain if element.get("type") != "fixed"]
    trailing: list[tuple[ET.Element, str]] = []
    for element in reversed(moving):
        name = element.get("name", "")
        child = element.find("child")
        link = "" if child is None else child.get("link", "")
        words = [w for w in GRIPPER_WORDS if w in name.lower() or w in link.lower()]
        if name in mimicked:
            reason = "other joints mimic it"
        elif words:
            reason = f"its name or its link's says {words[0]}"
        else:
            break
        trailing.append((element, reason))
    if not trailing:
        return None
    last, reason = trailing[0]
    first = trailing[-1][0]
    parent = first.find("parent")
    assert parent is not None
    name = last.get("name", "")
    count = f"the last {len(trailing)} of them" if len(trailing) > 1 else "the last of them"
    return ArmcalWarning(
        "gripper-joint",
        f"{path.name}: the chain ends in joint {name!r} ({last.get('type')}, line "
        f"{_line_of(text, 'joint', name)}), which looks like a gripper's ({reason}): the arm "
        f"is read with {len(moving)} joints, {count} the gripper's; if the gripper is not "
        f"part of the arm, end the chain at link {parent.get('link')!r}: {action('choose-tip')}",
    )


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
    if rpy is not None and max(abs(v) for v in rpy) > RPY_BOUND_RAD:
        shown = " ".join(f"{v:g}" for v in rpy)
        raise InputError(
            f'{path}: {where}: rpy="{shown}" has an angle beyond 2 pi ({2 * math.pi:.4g} rad), '
            "which looks like degrees; a URDF's rpy is in radians: convert it (rad = deg / "
            "57.29578)"
        )
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


def urdf_joint(path: Path, text: str, element: ET.Element) -> UrdfJoint:
    """One joint of the chain in mm and rad."""
    name = element.get("name", "")
    where = f"line {_line_of(text, 'joint', name)}, joint {name!r}"
    kind = element.get("type", "")
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
