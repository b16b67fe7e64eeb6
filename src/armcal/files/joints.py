"""The joint columns of every CSV armcal reads and writes, in each joint's own unit.

A revolute joint's column is ``q{j}_deg`` (the model's radians written in
degrees), a prismatic joint's ``q{j}_mm`` (a slide, in mm, as the model takes it):
PRODUCT.md, "Joint columns and units of joints".  A column in the other unit is
an error that names the joint's kind and the right column, never a conversion:
a prismatic reading of 200 under ``q3_deg`` read as degrees would move the slide
3.49 mm.  Which kind a reading is comes from the arm (``arm.joint_kinds``); a
joint map moves joints of a reading's own kind only, so reading ``j`` is of the
kind of joint ``j``.

A file may instead name its joint columns as the robot publishes them
(:func:`named_joint_columns`): by the URDF's joint names, in the units of ROS's
``/joint_states`` (radians, metres) or with a unit suffix (``joint_1_deg``,
``slide_mm``).  They are mapped to the joints by name, never by position.
"""

from __future__ import annotations

import math
import re
from collections.abc import Sequence

import numpy as np

from ..models import FitModel
from .common import fail, shown
from .csv_text import WIDTH, Column, degree_cells, degrees, float_cells
from .robots import RADIAN_LIMIT_BOUND

__all__ = [
    "JOINT_COLUMN",
    "JOINT_UNITS",
    "RADIAN_MIN_POSES",
    "SAME_POSE",
    "check_joint_units",
    "check_joint_values",
    "check_pose_labels",
    "file_limits",
    "joint_names",
    "joint_values",
    "limit_slack",
    "model_units",
    "named_joint_columns",
    "radians_message",
    "refuse_radians",
    "revolute",
    "wrapped_into",
]

#: The unit of a joint's column by the joint's kind: an angle in degrees, a slide in mm.
JOINT_UNITS = {"R": "deg", "P": "mm"}

#: A joint column of either unit (``q3_deg``, ``q3_mm``); up to 9999 joints.
JOINT_COLUMN = re.compile(r"^q([1-9][0-9]{0,3})_(deg|mm)$")

#: The largest difference of two rows' joint readings (deg, or mm for a slide) under one
#: ``pose`` label: ten times an industrial joint encoder's reading resolution (about
#: 0.001 deg) and far above a CSV's printing round-off.  Farther apart, the rows are two
#: poses.
SAME_POSE = 0.01


def _kinds(kinds: int | Sequence[str]) -> tuple[str, ...]:
    """``kinds`` as a tuple; a count ``n`` stands for ``n`` revolute joints."""
    if isinstance(kinds, int):
        return ("R",) * kinds
    return tuple(kinds)


def revolute(kinds: int | Sequence[str]) -> np.ndarray:
    """Boolean ``(n,)``: the revolute joints of ``kinds`` (a count: all of them)."""
    return np.array([kind == "R" for kind in _kinds(kinds)], dtype=bool)


def joint_names(kinds: int | Sequence[str]) -> list[str]:
    """The joint columns of an arm whose joints are ``kinds`` (``"R"``/``"P"`` each, or a
    count of revolute joints).

    >>> joint_names(["R", "R", "P"])
    ['q1_deg', 'q2_deg', 'q3_mm']
    >>> joint_names(2)
    ['q1_deg', 'q2_deg']
    """
    return [f"q{j}_{JOINT_UNITS[kind]}" for j, kind in enumerate(_kinds(kinds), start=1)]


def joint_values(q: np.ndarray, kinds: int | Sequence[str] | None = None) -> Column:
    """The joint values ``q`` ``(m, n)`` (rad, mm) as their columns' text: a revolute
    joint's in degrees (:func:`~armcal.files.csv_text.degree_cells`), a prismatic one's
    in mm with full round-trip precision; without ``kinds`` every joint is revolute."""
    q = np.asarray(q, dtype=float)
    turns = revolute(q.shape[1] if kinds is None else kinds)
    if turns.size != q.shape[1]:
        raise ValueError(f"q has {q.shape[1]} joints but kinds gives {turns.size}")
    if turns.all():
        return degrees(q)

    def cells(block: np.ndarray) -> np.ndarray:
        out = np.zeros((*block.shape, WIDTH), dtype=np.uint8)
        out[:, turns] = degree_cells(block[:, turns])
        out[:, ~turns] = float_cells(block[:, ~turns])
        return out

    return Column(q, cells)


def model_units(q_file: np.ndarray, kinds: Sequence[str]) -> np.ndarray:
    """Joint values ``(m, n)`` in the files' units (deg; mm) in the model's (rad; mm)."""
    return np.where(revolute(kinds), np.radians(q_file), q_file)


def file_limits(arm: FitModel) -> np.ndarray:
    """The arm's reading limits ``(n, 2)`` in the files' units (deg; mm)."""
    turns = revolute(arm.joint_kinds)[:, None]
    return np.where(turns, np.degrees(arm.joint_limits), arm.joint_limits)


def limit_slack(kinds: Sequence[str]) -> np.ndarray:
    """``(n,)``: the 1e-9 (rad, mm) slack of ``within_limits`` in deg (mm)."""
    return np.where(revolute(kinds), math.degrees(1e-9), 1e-9)


def check_joint_units(
    path, header: Sequence[str], header_line: int, arm: FitModel
) -> list[tuple[int, str]]:
    """The header's joint columns as ``(joint number, name)``, sorted, each in its joint's
    unit, without gaps or a joint twice; else InputError naming the column and the fix."""
    found = sorted((int(m.group(1)), h) for h in header if (m := JOINT_COLUMN.match(h)))
    joints = [j for j, _ in found]
    if len(set(joints)) < len(joints):
        j = next(j for j in joints if joints.count(j) > 1)
        raise fail(
            path,
            f"line {header_line}: joint {j} has two columns "
            f"({', '.join(h for i, h in found if i == j)}); keep the one in its unit",
        )
    if joints and joints != list(range(1, len(joints) + 1)):
        raise fail(
            path,
            f"line {header_line}: joint columns must be q1_deg..qN_deg without gaps, got "
            f"{', '.join(h for _, h in found)}",
        )
    names = joint_names(arm.joint_kinds)
    for j, name in found:
        if j <= len(names) and name != names[j - 1]:
            kind = "prismatic" if arm.joint_kinds[j - 1] == "P" else "revolute"
            what, fix = (
                ("a slide in mm, not an angle", "millimetres")
                if kind == "prismatic"
                else ("an angle, not a length", "degrees")
            )
            raise fail(
                path,
                f"line {header_line}, column {name}: joint {j} of {arm.name} is {kind}: its "
                f"reading is {what}; name the column {names[j - 1]} and give {fix}",
            )
    return found


def check_joint_values(
    path, what: str, arm: FitModel, q: np.ndarray, lines: Sequence[int]
) -> None:
    """Refuse a plan's or program's pose ``q`` ``(m, n)`` (rad, mm) whose readings are within
    their limits but whose joint values ``u = M q`` leave the limits of the arm's
    description (a URDF's ``<limit>``, which hold for ``u`` under a coupled joint map):
    the arm cannot go there, so designing, synthesizing or correcting it would be fiction.
    """
    bad = np.flatnonzero(~np.all(arm.within_limits(q), axis=1))
    limits = arm.value_limits
    if not bad.size or limits is None:
        return
    r = int(bad[0])
    u = arm.joint_map @ q[r]
    k = int(np.flatnonzero((u < limits[:, 0] - 1e-9) | (u > limits[:, 1] + 1e-9))[0])
    turns = arm.joint_kinds[k] == "R"
    unit = "deg" if turns else "mm"
    lo, hi = np.degrees(limits[k]) if turns else limits[k]
    value = math.degrees(u[k]) if turns else u[k]
    raise fail(
        path,
        f"{what} row {r + 1} (line {lines[r]}): its readings are within their limits, but "
        f"joint {k + 1} of the arm's description ({arm.joint_names[k]}, u = M q by "
        f"joint_map) would be at {value:.6g} {unit}, outside its limits [{lo:g}, {hi:g}] "
        f"{unit} (the URDF's, on u): the arm cannot reach this pose; remove or change it",
    )


def check_pose_labels(
    path, labels: Sequence[str], q_file: np.ndarray, kinds: Sequence[str], lines: Sequence[int]
) -> None:
    """Refuse a ``pose`` label given to two different joint readings.

    A pose label names one pose: the rows measured at its joint readings (one per
    target, load or cycle).  What groups rows by it (the check of swapped targets, the
    ISO 9283 cycles, the report's count of poses) would mix two poses.

    Parameters
    ----------
    path : str or path
        The file, for the message.
    labels : sequence of str
        Every row's ``pose`` label.
    q_file : ndarray, shape (m, n)
        Every row's joint readings in the file's units (deg, mm for a slide).
    kinds : sequence of str
        Every joint's kind, ``"R"`` or ``"P"``.
    lines : sequence of int
        Every row's line in the file.

    Raises
    ------
    InputError
        Naming the label, its two rows and the joint that differs by more than
        :data:`SAME_POSE`.
    """
    _, first, group = np.unique(np.asarray(labels), return_index=True, return_inverse=True)
    group = group.reshape(-1)
    spread = np.abs(q_file - q_file[first[group]])
    named = np.array([bool(label) for label in labels], dtype=bool)  # an empty cell: no label
    moved = np.flatnonzero(named & (np.max(spread, axis=1, initial=0.0) > SAME_POSE))
    if not moved.size:
        return
    r = int(moved[0])
    a = int(first[group[r]])
    j = int(np.argmax(spread[r]))
    name = joint_names(kinds)[j]
    unit = JOINT_UNITS[_kinds(kinds)[j]]
    raise fail(
        path,
        f"rows {a + 1} and {r + 1} (lines {lines[a]} and {lines[r]}), column pose: the label "
        f"{shown(labels[r])} is given to two different joint readings ({name} {q_file[a, j]:g} "
        f"and {q_file[r, j]:g} {unit}); a pose label names one pose (the rows measured at "
        "its joint readings, one per target, load or cycle): give the other pose a label "
        "of its own",
    )


def wrapped_into(q_deg: np.ndarray, lo: float, hi: float) -> float | None:
    """The turn (-360 or +360) that brings every one of a column's angles within [lo, hi].

    None when no single turn does.
    """
    for turn in (-360.0, 360.0):
        shifted = np.where((q_deg < lo) | (q_deg > hi), q_deg + turn, q_deg)
        if np.all((shifted >= lo) & (shifted <= hi)):
            return turn
    return None


#: Fewest poses whose angles all lie within :data:`RADIAN_LIMIT_BOUND` before a
#: plan or a program is refused as radians: one or two poses near zero are a
#: home position, not a unit mistake.
RADIAN_MIN_POSES = 3


def refuse_radians(path, what: str, q_deg: np.ndarray, limits_deg: np.ndarray) -> None:
    """InputError when a plan's or program's angles look like radians (:func:`radians_message`)."""
    found = radians_message(what, q_deg, limits_deg)
    if found is not None:
        raise fail(path, found)


def radians_message(what: str, q_deg: np.ndarray, limits_deg: np.ndarray) -> str | None:
    """What says that a file's angles ``q_deg`` look like radians under ``q*_deg``, with
    the fix; None when they do not.

    Every angle within :data:`RADIAN_LIMIT_BOUND` (2 pi, rounded up) over at
    least :data:`RADIAN_MIN_POSES` poses, while the joints may turn farther: an
    arm calibrated or corrected there would move a few degrees in all, whereas
    radians of any pose lie within 2 pi.  ``identify`` catches the same mistake
    by fitting both readings (:mod:`armcal.plausibility`); a plan or a program
    has no positions to fit, so its range is the evidence.
    """
    span = np.abs(q_deg).max(initial=0.0)
    may_turn = np.maximum(-limits_deg[:, 0], limits_deg[:, 1]).max() > RADIAN_LIMIT_BOUND
    if len(q_deg) < RADIAN_MIN_POSES or span == 0.0 or span > RADIAN_LIMIT_BOUND or not may_turn:
        return None
    return (
        f"every joint angle of the {len(q_deg)} {what} rows is within +-{span:.3g}, which "
        f"looks like radians under the q*_deg columns (the joints may turn to "
        f"{np.abs(limits_deg).max():g} deg); convert the angles to degrees (x 180/pi)"
    )


#: A named joint column's unit suffix, and its factor to the file's canonical unit (deg or
#: mm) by the joint's kind; no suffix is ROS's ``/joint_states``: radians and metres.
_NAMED_UNITS = {
    "R": {"": math.degrees(1.0), "_rad": math.degrees(1.0), "_deg": 1.0},
    "P": {"": 1000.0, "_m": 1000.0, "_mm": 1.0},
}


def _named(column: str, names: Sequence[str]) -> tuple[int, str] | None:
    """``(joint index, suffix)`` of a column that names one of ``names``, else None."""
    for j, name in enumerate(names):
        if column == name:
            return j, ""
        if column.startswith(name) and column[len(name) :] in ("_rad", "_deg", "_m", "_mm"):
            return j, column[len(name) :]
    return None


def named_joint_columns(
    path, header: Sequence[str], header_line: int, arm: FitModel, allowed: Sequence[str]
) -> tuple[list[str], np.ndarray, bool]:
    """The header with joint columns named by ``arm``'s joints (its URDF's names) renamed to
    ``q{j}_deg`` / ``q{j}_mm``, every joint's factor ``(n,)`` to that unit (1 where the file
    already uses it), and whether the file names them so: the module notes' other way to
    name joints.  Named columns are the URDF's joint values ``u = M q`` (what ROS
    publishes), which the caller turns into the readings ``q`` under a coupled joint map.

    A file names all its joints one way.  Named, every joint of the chain needs a column
    and every other column must be one the file takes: a joint the chain does not have
    (``/joint_states`` lists a gripper's too) is an error naming it, as is a column in a
    unit that is not its joint's kind's.
    """
    names = list(arm.joint_names)
    kinds = arm.joint_kinds
    factors = np.ones(len(names))
    found = {  # a column the file takes itself (x_mm) is never a joint (a gantry's "x")
        c: hit
        for c, h in enumerate(header)
        if h not in allowed and (hit := _named(h, names)) is not None
    }
    if not found or any(JOINT_COLUMN.match(h) for h in header):
        return list(header), factors, False  # q{j}_deg columns (a mixture: their check names it)
    where = f"line {header_line}"
    out = list(header)
    for c, (j, suffix) in found.items():
        units = _NAMED_UNITS[kinds[j]]
        if suffix not in units:
            right = f"{names[j]}_deg" if kinds[j] == "R" else f"{names[j]}_mm"
            kind = "revolute" if kinds[j] == "R" else "prismatic"
            raise fail(
                path,
                f"{where}, column {header[c]}: {names[j]} is a {kind} joint; name the column "
                f"{names[j]} ({'radians' if kinds[j] == 'R' else 'metres'}) or {right}",
            )
        factors[j] = units[suffix]
        out[c] = f"q{j + 1}_{JOINT_UNITS[kinds[j]]}"
    hits = [j for j, _ in found.values()]
    for j in sorted({j for j in hits if hits.count(j) > 1}):
        both = ", ".join(header[c] for c, (i, _) in found.items() if i == j)
        raise fail(path, f"{where}: joint {names[j]} has two columns ({both}); keep one")
    missing = [names[j] for j in range(len(names)) if j not in hits]
    if missing:
        raise fail(
            path,
            f"{where}: the joint columns are named by {arm.name}'s joints, but "
            f"{', '.join(missing)} {'has' if len(missing) == 1 else 'have'} no column; add "
            f"{'it' if len(missing) == 1 else 'them'} (radians, or NAME_deg)",
        )
    for c, h in enumerate(header):
        if c not in found and h not in allowed:
            raise fail(
                path,
                f"{where}, column {h}: not a joint of {arm.name}'s chain "
                f"({', '.join(names)}) nor a column the file takes; drop it (a robot's "
                "/joint_states lists every joint, the calibrated chain only its own)",
            )
    return out, factors, True
