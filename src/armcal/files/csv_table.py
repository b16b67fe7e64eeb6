"""A CSV file read into a table for an arm: its header checked against the columns its
kind takes, its numbers and texts by column, and its joint values within the limits.

What every table of :mod:`armcal.files.tables` (plans, programs, measurements, an
instrument's readings) shares, and the checks of columns they have in common: a
row's ``sigma_mm``, its ``target`` labels, and the joint readings beyond a limit.
"""

from __future__ import annotations

import difflib
import os
import re
from collections.abc import Sequence
from dataclasses import dataclass, replace

import numpy as np

from ..errors import ArmcalWarning, action
from ..formats import reader_columns
from ..models import FitModel
from .common import fail, read_text, shown, suggest
from .csv_read import ParsedCsv, column_numbers, parse_csv
from .joints import (
    JOINT_COLUMN,
    JOINT_UNITS,
    check_joint_units,
    check_joint_values,
    check_pose_labels,
    file_limits,
    joint_names,
    limit_slack,
    model_units,
    named_joint_columns,
    radians_message,
    refuse_radians,
    revolute,
    wrapped_into,
)
from .kinds import looks_like, not_a_table
from .robots import SIGMA_RANGE_MM

__all__ = [
    "LIMIT_TOLERANCE_DEG",
    "LIMIT_TOLERANCE_MM",
    "Table",
    "beyond_limits_warning",
    "check_target_labels",
    "read_table",
    "row_sigma",
]


#: How far (deg) a *measured* joint angle may lie beyond a joint limit and still be
#: accepted, with a ``beyond-limits`` warning.  Limits constrain plans, not what the
#: arm really did: a reading past a limit by encoder noise, overshoot or a soft limit
#: set inside the hard stop is a few tenths of a degree.  Beyond 2 deg (twice the
#: largest joint offset PRODUCT.md expects, about a degree) the file or the robot's
#: limits are wrong, and the reading stays an error.
LIMIT_TOLERANCE_DEG = 2.0

#: The same for a prismatic joint's reading (mm): overshoot and encoder noise of a slide
#: are hundredths to tenths of a mm, and 2 mm is about the largest zero offset PRODUCT.md
#: expects of a joint ("up to a few mm").  Farther is an error.
LIMIT_TOLERANCE_MM = 2.0


#: A column with a known stem and another unit suffix (``q1_rad``, ``x_m``).
_UNIT_COLUMN = re.compile(r"^(q[1-9][0-9]{0,3}|x|y|z|rx|ry|rz|sigma)_([A-Za-z]+)$")


#: Units a column may be written in that armcal does not read (a unit hint, not a typo).
_OTHER_UNITS = frozenset(
    ("m", "cm", "um", "in", "inch", "inches", "ft", "rad", "mrad", "urad", "grad", "rev")
)


@dataclass(frozen=True, eq=False)
class Table:
    """A validated CSV: numbers in file units and the optional columns found."""

    values: np.ndarray  # (m, n + len(numeric)): joint columns (deg, mm), then the numeric ones
    texts: dict[str, list[str]]  # optional text columns present
    numbers: dict[str, np.ndarray]  # optional numeric columns present
    lines: list[int]  # file line of every data row
    beyond: list[tuple[int, int, float, float]]  # (row index, joint, value, by): deg or mm
    header_line: int = 1  # file line of the header


def _unit_hint(name: str, allowed: Sequence[str]) -> str:
    """What to do about an ``allowed`` column in another unit (``q1_rad``, ``x_m``), else ``""``.

    A joint's right unit is the one its ``allowed`` column has (``q3_mm`` for a
    prismatic joint), else degrees.  A unit that is a typo of the right one
    (``q1_dge``) gets a did-you-mean instead.
    """
    match = _UNIT_COLUMN.match(name)
    if match is None:
        return ""
    stem, unit = match.groups()
    right = "mm"
    if stem.startswith("q"):
        right = "mm" if f"{stem}_mm" in allowed else "deg"
    fixed = f"{stem}_{right}"
    if fixed not in allowed and not (stem.startswith("q") and JOINT_COLUMN.match(fixed)):
        return ""
    unit = unit.lower()
    if unit not in _OTHER_UNITS and (
        unit in ("degree", "degrees") or difflib.get_close_matches(unit, [right])
    ):
        return f"did you mean '{fixed}'? "
    if right == "deg":
        return (
            f"joint angles are read in degrees: name the column {fixed} and give degrees "
            "(deg = rad x 57.29578); "
        )
    if stem.startswith("q"):
        return (
            f"joint {stem[1:]} is prismatic, its reading a slide in mm: name the column "
            f"{fixed} and give millimetres; "
        )
    return f"positions are read in mm: name the column {fixed} and give millimetres; "


def _check_header_names(
    path, text: str, parsed: ParsedCsv, allowed: list[str], kind: str, layout: str
) -> None:
    """Every column named, once, and known: one of ``allowed`` or a joint column."""
    header, header_line = parsed.header, parsed.header_line
    for col, name in enumerate(header, start=1):
        if not name and col == len(header) > 1:  # Excel's trailing separator
            raise fail(
                path,
                f"line {header_line}: header column {col} is empty: the header ends with a "
                f"separator: remove the trailing separator ({parsed.delimiter!r}) at "
                "the end of each line",
            )
        if not name:
            raise fail(path, f"line {header_line}: header column {col} is empty")
        if header.count(name) > 1:
            raise fail(path, f"line {header_line}: duplicate column '{name}'; keep one")
    for name in header:
        if name not in allowed and not JOINT_COLUMN.match(name):
            hint = _unit_hint(name, allowed) or looks_like(text, kind)
            raise fail(
                path,
                f"line {header_line}: unknown column {shown(name)}: "
                f"{hint or suggest(name, allowed)}expected {layout}",
            )


def _check_required(
    path,
    text: str,
    parsed: ParsedCsv,
    arm: FitModel,
    expected: list[str],
    what: str,
    arm_from: str | None,
    layout: str,
) -> None:
    """A joint column for every joint of ``arm`` in its unit, every ``expected`` column,
    and at least one row."""
    header, header_line = parsed.header, parsed.header_line
    found = check_joint_units(path, header, header_line, arm)
    if found and len(found) != arm.n_joints:
        has = f"has {len(found)} joint columns ({found[0][1]}..{found[-1][1]})"
        raise fail(
            path,
            f"{has} but robot {arm.name} has {arm.n_joints} joints; pass the matching "
            f"{action('robot-arm')} or fix the header"
            if arm_from is None
            else f"{has}, but {arm_from} belongs to {arm.name}, an arm of {arm.n_joints} "
            f"joints: the {what} and {arm_from} are of different arms; pass the calibration "
            f"of the same arm (or fix the header, if the file is of {arm.name})",
        )
    for name in expected:
        if name not in header:
            raise fail(
                path,
                f"line {header_line}: missing column '{name}'; "
                f"{looks_like(text, f'{what}-file')}expected {layout}",
            )
    if not parsed.lines:
        raise fail(
            path, f"has a header but no poses; add one row per pose after line {header_line}"
        )


def _columns(
    path,
    parsed: ParsedCsv,
    expected: list[str],
    optional: Sequence[str],
    optional_numeric: Sequence[str],
) -> tuple[np.ndarray, dict[str, np.ndarray], dict[str, list[str]]]:
    """The ``expected`` columns' numbers ``(m, len(expected))``, and the optional numeric
    and text columns present, by name."""
    header = parsed.header
    index = {name: header.index(name) for name in expected}
    present = [name for name in optional_numeric if name in header]
    columns = [index[name] for name in expected] + [header.index(name) for name in present]
    if parsed.block is None:
        assert parsed.fields is not None
        names = [*expected, *present]
        fields = [parsed.fields(c) for c in columns]
        block = column_numbers(path, parsed.lines, names, fields, parsed.delimiter)
    else:
        block = np.ascontiguousarray(parsed.block[:, columns])
    values = block[:, : len(expected)]
    numbers = {name: block[:, len(expected) + k] for k, name in enumerate(present)}
    texts = {}
    for name in optional:
        if name in header:  # never in a file of plain numbers (parse_csv's block)
            assert parsed.fields is not None
            texts[name] = [field.strip() for field in parsed.fields(header.index(name))]
    return values, numbers, texts


def _beyond_limits(
    path,
    arm: FitModel,
    what: str,
    values: np.ndarray,
    lines: list[int],
    expected: list[str],
    measured: bool,
) -> list[tuple[int, int, float, float]]:
    """Joint values beyond a limit: ``(row, joint, value, by)`` for those a ``measured``
    file may have (within the tolerance); an error for any other."""
    kinds = arm.joint_kinds
    q_file = values[:, : arm.n_joints]
    turns = revolute(kinds)
    units = [JOINT_UNITS[kind] for kind in kinds]
    limits = file_limits(arm)
    # Distance beyond the nearer limit (file units), 0 inside; the slack of within_limits
    # keeps a limit written out in the file inside.
    by = np.maximum(limits[:, 0] - q_file, q_file - limits[:, 1])
    outside = by > limit_slack(kinds)
    tolerance = np.where(turns, LIMIT_TOLERANCE_DEG, LIMIT_TOLERANCE_MM) * float(measured)
    far = outside & (by > tolerance)
    if far.any():
        r, j = map(int, np.argwhere(far)[0])
        lo, hi = limits[j]
        unit = units[j]
        fix = "fix the pose or the robot's joint_limits_deg"
        if measured:
            fix = (
                f"readings up to {tolerance[j]:g} {unit} beyond a limit are accepted; "
                "check the robot file (joint_limits_deg) and the column"
            )
        wrapped = wrapped_into(q_file[:, j], lo, hi) if turns[j] else None
        if wrapped is not None:  # a controller that reads 0..360
            fix = (
                f"{values[r, j]:g} is {values[r, j] + wrapped:g} {'+' if wrapped < 0 else '-'} "
                f"360: the column reads turns in 0..360 (or -360..0); subtract or add 360 "
                f"where a value exceeds the limit, or give joint_limits_deg in that range"
            )
        if turns[j]:  # radians blame no limit: say so before the limits
            fix = radians_message(what, q_file[:, turns], limits[turns]) or fix
        raise fail(
            path,
            f"row {r + 1} (line {lines[r]}), column {expected[j]}: {values[r, j]:g} {unit} is "
            f"outside joint {j + 1}'s limits [{lo:g}, {hi:g}] {unit}; {fix}",
        )
    return [
        (int(r), int(j), float(values[r, j]), float(by[r, j])) for r, j in np.argwhere(outside)
    ]


def read_table(
    path,
    arm: FitModel,
    what: str,
    measured: bool = False,
    arm_from: str | None = None,
    columns: tuple[list[str], list[str], list[str]] | None = None,
) -> Table:
    """Validate a CSV of kind ``what`` (a key of :data:`armcal.formats.COLUMNS`).

    ``arm_from`` names where the arm came from when not from ``--robot`` (``"the
    calibration cal.json"``), for the errors that blame a wrong robot.

    Its joint columns (in every joint's unit: :func:`~armcal.files.writers.joint_names`)
    and required columns must be there; its optional text and numeric columns may
    be.  A ``measured`` joint value beyond its limit by at most
    :data:`LIMIT_TOLERANCE_DEG` (:data:`LIMIT_TOLERANCE_MM` for a prismatic joint) is
    accepted and listed in ``beyond``; farther is an error, as any value beyond a
    limit of a plan or program is.  ``columns``: the required, optional text and
    optional numeric columns, where they are not those of ``what``.
    """
    numeric, optional, optional_numeric = reader_columns(what) if columns is None else columns
    kinds = arm.joint_kinds
    expected = joint_names(kinds) + list(numeric)
    extras = list(optional) + list(optional_numeric)
    layout = ",".join(expected) + "".join(f" [,{c}]" for c in extras)
    text = read_text(path, what)
    expected_kind = f"{what}-file"
    if not_a_table(text):  # JSON, XML or TOML
        other = looks_like(text, expected_kind)
        if other:
            raise fail(path, f"not a {what} CSV file: {other}expected a header line {layout}")
    parsed = parse_csv(path, text, optional, layout)
    header, factors, named = named_joint_columns(
        path, parsed.header, parsed.header_line, arm, expected[arm.n_joints :] + extras
    )
    parsed = replace(parsed, header=header)
    _check_header_names(path, text, parsed, expected + extras, expected_kind, layout)
    _check_required(path, text, parsed, arm, expected, what, arm_from, layout)
    lines = parsed.lines
    values, numbers, texts = _columns(path, parsed, expected, optional, optional_numeric)
    if named:  # the URDF's joint values u = M q, in radians or metres: the readings q
        u = values[:, : arm.n_joints] * factors
        values[:, : arm.n_joints] = np.linalg.solve(arm.joint_map, u.T).T
    beyond = _beyond_limits(path, arm, what, values, lines, expected, measured)
    q_file = values[:, : arm.n_joints]
    if what in ("plan", "program"):
        turns = revolute(kinds)
        if turns.any():
            refuse_radians(path, what, q_file[:, turns], file_limits(arm)[turns])
        check_joint_values(path, what, arm, model_units(q_file, kinds), lines)
    if "pose" in texts:
        check_pose_labels(path, texts["pose"], q_file, kinds, lines)
    return Table(values, texts, numbers, lines, beyond, parsed.header_line)


def beyond_limits_warning(path, arm: FitModel, beyond) -> ArmcalWarning:
    kinds = arm.joint_kinds
    limits = file_limits(arm)
    names = joint_names(kinds)
    shown = [
        f"row {r + 1} {names[j]} = {value:g} "
        f"([{limits[j, 0]:g}, {limits[j, 1]:g}], {by:.3g} {JOINT_UNITS[kinds[j]]} beyond)"
        for r, j, value, by in beyond[:5]
    ]
    more = f" and {len(beyond) - 5} more" if len(beyond) > 5 else ""
    slides = f" ({LIMIT_TOLERANCE_MM:g} mm for a slide)" if "P" in kinds else ""
    return ArmcalWarning(
        "beyond-limits",
        f"{os.fspath(path)}: {len(beyond)} measured joint {'value' if slides else 'angle'}(s) "
        f"beyond the robot's limits by at most {LIMIT_TOLERANCE_DEG:g} deg{slides}, accepted "
        f"(limits constrain plans, not what the arm did): {'; '.join(shown)}{more}; if the arm "
        "cannot go there, check the robot file's joint_limits_deg",
    )


def row_sigma(path, table: Table) -> np.ndarray | None:
    """The ``sigma_mm`` column, every value a noise std within :data:`SIGMA_RANGE_MM`."""
    row_sigma = table.numbers.get("sigma_mm")
    if row_sigma is not None:
        low, high = SIGMA_RANGE_MM
        bad = np.flatnonzero((row_sigma < low) | (row_sigma > high))
        if bad.size:
            r = int(bad[0])
            raise fail(
                path,
                f"row {r + 1} (line {table.lines[r]}), column sigma_mm: {row_sigma[r]:g} is not "
                f"a noise std between {low:g} and {high:g} mm; check the unit (mm)",
            )
    return row_sigma


def check_target_labels(path, arm: FitModel, labels: list[str], lines: list[int]) -> None:
    """Every row names a target, one of the robot file's ``[targets]`` when it has them."""
    known = arm.target_labels
    for r, label in enumerate(labels):
        if not label:
            raise fail(
                path,
                f"row {r + 1} (line {lines[r]}), column target: empty; name the target "
                "(reflector, marker) every row measured",
            )
        if known and label not in known:
            raise fail(
                path,
                f"row {r + 1} (line {lines[r]}), column target: {shown(label)} is not a target of "
                f"{arm.name}: {suggest(label, known)}the robot file's [targets] has "
                f"{', '.join(known)}",
            )
