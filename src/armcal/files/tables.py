"""CSV tables: plans, measurements and robot programs, read strictly and written exactly.

A plan or program has a column per joint (``q1_deg..qn_deg``; a prismatic joint's
is ``q{j}_mm``, its reading a slide in mm); measurements add
the measured point (``x_mm, y_mm[, z_mm]``) and optional columns (``pose``,
``target``, ``sigma_mm``, ``payload_kg``, ``fx_N``, ``fy_N``).  Readers accept
the variants spreadsheets and instruments write (``#`` comments, ``;`` with a
decimal comma, tabs) and name the file, row and column of any bad value.
"""

from __future__ import annotations

import difflib
import os
import re
from collections.abc import Sequence
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from ..errors import ArmcalWarning, action
from ..formats import reader_columns
from ..models import FitModel, Loads
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
from .robots import METRE_REACH_MM, SIGMA_RANGE_MM
from .writers import ORIENTATION_COLUMNS

__all__ = [
    "INSTRUMENT_RANGE",
    "LIMIT_TOLERANCE_DEG",
    "LIMIT_TOLERANCE_MM",
    "REACH_MARGIN",
    "Measurements",
    "Program",
    "read_labelled_plan",
    "read_loaded_plan",
    "read_measurements",
    "read_plan",
    "read_program",
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

#: A measured tip farther than ``(1 + REACH_MARGIN)`` times the arm's reach (the sum of
#: its link lengths) from the base is an error: no arm whose links deviate by less than
#: 10 % (the ``large-deviation`` bound of :mod:`armcal.plausibility`) gets there.
REACH_MARGIN = 0.1

#: An instrument sees an arm from at most this many reaches away (a laser tracker a
#: few metres from a sub-metre arm): a point beyond the reach but within it may be
#: instrument-frame data without a base offset, one farther is a wrong value or unit.
INSTRUMENT_RANGE = 100.0


#: A column with a known stem and another unit suffix (``q1_rad``, ``x_m``).
_UNIT_COLUMN = re.compile(r"^(q[1-9][0-9]{0,3}|x|y|z|rx|ry|rz|sigma)_([A-Za-z]+)$")

#: A rotation vector's angle is at most half a turn; up to a full turn is accepted (an
#: instrument may not reduce it), beyond that the column is not degrees of a rotation vector.
MAX_TURN_DEG = 360.0

#: Units a column may be written in that armcal does not read (a unit hint, not a typo).
_OTHER_UNITS = frozenset(
    ("m", "cm", "um", "in", "inch", "inches", "ft", "rad", "mrad", "urad", "grad", "rev")
)


@dataclass(frozen=True, eq=False)
class Measurements:
    """Measured poses read from a CSV file.

    Attributes
    ----------
    q : ndarray, shape (m, n)
        Commanded joint values: rad (mm for a prismatic joint).
    xy : ndarray, shape (m, 2)
        Measured positions in mm.
    labels : tuple of str
        The ``pose`` column, or ``"1".."m"`` when the file has none.
    rows : tuple of int
        The 1-based data row of every pose (blank lines and the header not counted),
        as error and warning messages name them.
    row_sigma : ndarray, shape (m,), or None
        The optional ``sigma_mm`` column: each point's instrument uncertainty
        (1 std, mm), for instruments that report it.
    warnings : tuple of ArmcalWarning
        What is accepted but suspicious: ``beyond-limits`` (measured angles
        slightly beyond a joint limit).
    targets : tuple of str, or None
        The optional ``target`` column: which target every row measured.
    z : ndarray, shape (m,), or None
        The optional ``z_mm`` column of 3-D instrument data; then ``xy`` are the
        instrument's x and y, not yet in the plane of motion.
    payload_kg : ndarray, shape (m,), or None
        The optional ``payload_kg`` column: the payload carried in every row.
    force_n : ndarray, shape (m, 2), or None
        The optional ``fx_N``, ``fy_N`` columns: a force applied at the tip (N).
    orientation : ndarray, shape (m, 3), or None
        The optional ``rx_deg, ry_deg, rz_deg`` columns of a 6-DoF instrument: the
        target's orientation as a rotation vector in the instrument's frame (rad).
    feature : tuple of str, or None
        A plane, point or distance instrument's rows: the feature every row touches
        (its ``plane`` or ``point`` column, else the instrument's one feature).
    readings : ndarray, shape (m, d), or None
        What such an instrument read (mm): its ``distance_mm`` column, or 0 for a row
        that touches a plane or sits in a point (``d`` the instrument's numbers a row).
    """

    q: np.ndarray
    xy: np.ndarray
    labels: tuple[str, ...]
    rows: tuple[int, ...] = ()
    row_sigma: np.ndarray | None = None
    warnings: tuple[ArmcalWarning, ...] = ()
    targets: tuple[str, ...] | None = None
    z: np.ndarray | None = None
    payload_kg: np.ndarray | None = None
    force_n: np.ndarray | None = None
    orientation: np.ndarray | None = None
    feature: tuple[str, ...] | None = None
    readings: np.ndarray | None = None

    def loads(self, default_payload_kg: float = 0.0) -> Loads:
        """Every row's payload (the file's default where there is no column) and tip force."""
        m = self.q.shape[0]
        payload = default_payload_kg if self.payload_kg is None else self.payload_kg
        return Loads.create(m, payload, self.force_n)

    @property
    def has_loads(self) -> bool:
        """Whether the file has a payload or force column."""
        return self.payload_kg is not None or self.force_n is not None

    @property
    def xyz(self) -> np.ndarray:
        """The 3-D points ``(m, 3)`` in mm (requires :attr:`z`)."""
        if self.z is None:
            raise ValueError("the measurements are 2-D: no z_mm column")
        return np.column_stack([self.xy, self.z])

    @property
    def instrument_points(self) -> np.ndarray:
        """What the instrument read ``(m, 3)`` or ``(m, 6)``: the 3-D point (mm) and, from a
        6-DoF instrument, the orientation's rotation vector (rad); a plane's, a point's or
        a distance's readings (:attr:`readings`)."""
        if self.readings is not None:
            return self.readings
        if self.orientation is None:
            return self.xyz
        return np.column_stack([self.xyz, self.orientation])


# --------------------------------------------------------------------------- CSV


@dataclass(frozen=True, eq=False)
class _Table:
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


def _read_csv(
    path,
    arm: FitModel,
    what: str,
    measured: bool = False,
    arm_from: str | None = None,
    columns: tuple[list[str], list[str], list[str]] | None = None,
) -> _Table:
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
    return _Table(values, texts, numbers, lines, beyond, parsed.header_line)


def read_plan(path: str | os.PathLike, arm: FitModel) -> np.ndarray:
    """Read a plan CSV (header ``q1_deg,...,qn_deg``) for ``arm``.

    Returns
    -------
    ndarray, shape (m, n)
        Joint values in rad (mm for a prismatic joint), each within the joint limits.
    """
    return read_labelled_plan(path, arm)[0]


def read_labelled_plan(
    path: str | os.PathLike, arm: FitModel
) -> tuple[np.ndarray, tuple[str, ...] | None]:
    """:func:`read_plan` and its optional ``pose`` labels (None without the column)."""
    q, payload, labels = read_loaded_plan(path, arm)
    if payload is not None:
        raise fail(
            path,
            f"has a payload_kg column but robot {arm.name} has no [elastostatic] table; "
            "remove the column or add the table to the robot file",
        )
    return q, labels


def read_loaded_plan(
    path: str | os.PathLike, arm: FitModel
) -> tuple[np.ndarray, np.ndarray | None, tuple[str, ...] | None]:
    """Read a plan CSV with its optional ``payload_kg`` (designs with compliance) and
    ``pose`` columns.

    Returns
    -------
    q : ndarray, shape (m, n)
        Joint values in rad (mm for a prismatic joint).
    payload : ndarray, shape (m,), or None
        The payload of every pose (kg), when the column is there.
    labels : tuple of str, or None
        The ``pose`` column, when it is there.
    """
    table = _read_csv(path, arm, "plan")
    payload, _ = _load_columns(path, table)
    labels = table.texts.get("pose")
    q = model_units(table.values, arm.joint_kinds)
    return q, payload, None if labels is None else tuple(labels)


@dataclass(frozen=True, eq=False)
class Program:
    """A robot program's joint commands read from a CSV file.

    Attributes
    ----------
    q : ndarray, shape (m, n)
        Joint commands in rad (mm for a prismatic joint), within the joint limits.
    labels : tuple of str, or None
        The optional ``pose`` column.
    targets : tuple of str, or None
        The optional ``target`` column: the tool point each command is for.
    """

    q: np.ndarray
    labels: tuple[str, ...] | None = None
    targets: tuple[str, ...] | None = None
    payload_kg: np.ndarray | None = None
    force_n: np.ndarray | None = None


def read_program(
    path: str | os.PathLike, arm: FitModel, *, arm_from: str | None = None
) -> Program:
    """Read a program CSV: ``q1_deg..qn_deg``; optional ``pose``, ``target`` and load columns.

    ``arm_from`` names where ``arm`` came from when not from ``--robot`` (``"the
    calibration cal.json"``), for the errors that blame a wrong robot.

    Raises
    ------
    InputError
        For a malformed file, a command outside the joint limits or an unknown target.
    """
    table = _read_csv(path, arm, "program", arm_from=arm_from)
    targets = table.texts.get("target")
    if targets is not None:
        if not arm.target_labels:
            raise fail(
                path,
                f"has a target column but {arm.name} has no targets; remove the column",
            )
        _check_target_labels(path, arm, targets, table.lines)
    labels = table.texts.get("pose")
    payload, force = _load_columns(path, table)
    return Program(
        model_units(table.values, arm.joint_kinds),
        None if labels is None else tuple(labels),
        None if targets is None else tuple(targets),
        payload,
        force,
    )


def _beyond_limits_warning(path, arm: FitModel, beyond) -> ArmcalWarning:
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


def _check_reach(
    path, arm: FitModel, xy: np.ndarray, lines: list[int], arm_from: str | None
) -> None:
    """Refuse a measured point no arm of this geometry can reach (see :data:`REACH_MARGIN`).

    Without a base offset the base is the instrument's origin, and every tip lies
    within ``reach`` of it.  With one, the base is unknown, but every tip lies
    within ``reach`` of it, so within ``2 reach`` of the data's centroid.
    """
    reach = arm.tip_reach_mm
    limit = (1 + REACH_MARGIN) * reach
    if arm.base_offset or xy.shape[1] == 3:
        center = np.mean(xy, axis=0)
        limit *= 2
        where = "from the centroid of the measured points"
    else:
        center = np.zeros(2)
        where = "from the base (the instrument's origin; base_offset = false)"
    distance = np.linalg.norm(xy - center, axis=1)
    r = int(np.argmax(distance))
    if distance[r] <= limit:
        return
    c = int(np.argmax(np.abs(xy[r] - center)))
    column = ("x_mm", "y_mm", "z_mm")[c]
    fix = "check the value and the unit (mm)"
    if arm_from is not None:
        fix = (
            f"{arm_from} belongs to {arm.name}: if the measurements are of another arm, pass "
            f"that arm's calibration; else {fix}"
        )
    elif distance[r] <= 1000 * limit and reach < METRE_REACH_MM:
        fix = (
            f"the robot's links add up to {reach:g} mm: if the robot file's link_lengths_mm "
            "are in metres, write them in mm"
        )
    elif not arm.base_offset and distance[r] <= INSTRUMENT_RANGE * reach:
        fix += (
            "; if the instrument's origin is not at the arm's base (a laser tracker, a camera), "
            "set base_offset = true in the robot file"
        )
    raise fail(
        path,
        f"row {r + 1} (line {lines[r]}), column {column}: {xy[r, c]:g} puts the tip "
        f"{distance[r]:.4g} mm {where}, beyond the reach of {arm.name} ("
        f"{'2 x ' if arm.base_offset else ''}{reach:g} mm, +{100 * REACH_MARGIN:g} % for "
        f"deviations: {limit:.4g} mm); {fix}",
    )


def read_measurements(
    path: str | os.PathLike, arm: FitModel, *, arm_from: str | None = None
) -> Measurements:
    """Read a measurements CSV: ``q1_deg..qn_deg,x_mm,y_mm``, optional ``pose`` and ``sigma_mm``.

    Parameters
    ----------
    path : str or path
    arm : PlanarArm
        The robot measured: its joint count, limits, link lengths, base offset.
    arm_from : str, optional
        Where ``arm`` came from when not from ``--robot`` (``"the calibration
        cal.json"``), for the errors that blame a wrong robot.

    Returns
    -------
    Measurements
        Joint values in rad (mm for a slide), positions in mm, the data rows, the
        ``sigma_mm`` column (per-row instrument noise, mm) and the ``beyond-limits``
        warning.

    Raises
    ------
    InputError
        Naming the file, row and column: a malformed file; a joint angle more
        than :data:`LIMIT_TOLERANCE_DEG` beyond its limit; a ``sigma_mm`` outside
        :data:`SIGMA_RANGE_MM`; a point no arm of this geometry can reach
        (:data:`REACH_MARGIN`).
    """
    instrument = getattr(arm, "instrument", None)  # a plane's, a point's, a distance's
    if instrument is not None:
        return _read_readings(path, arm, instrument, arm_from)
    table = _read_csv(path, arm, "measurements", measured=True, arm_from=arm_from)
    n = arm.n_joints
    values = table.values
    m = values.shape[0]
    labels = table.texts.get("pose") or [str(i) for i in range(1, m + 1)]
    row_sigma = _row_sigma(path, table)
    xy = values[:, n:]
    z = table.numbers.get("z_mm")
    targets = table.texts.get("target")
    if targets is not None:
        _check_target_labels(path, arm, targets, table.lines)
    if z is None:
        _check_reach(path, arm, xy, table.lines, arm_from)
    else:
        _check_reach(path, arm, np.column_stack([xy, z]), table.lines, arm_from)
    warnings = []
    if table.beyond:
        warnings.append(_beyond_limits_warning(path, arm, table.beyond))
    payload, force = _load_columns(path, table)
    orientation = _orientation_columns(path, arm, table)
    return Measurements(
        model_units(values[:, :n], arm.joint_kinds),
        xy,
        tuple(labels),
        rows=tuple(range(1, m + 1)),
        row_sigma=row_sigma,
        warnings=tuple(warnings),
        targets=None if targets is None else tuple(targets),
        z=z,
        payload_kg=payload,
        force_n=force,
        orientation=orientation,
    )


def _row_sigma(path, table: _Table) -> np.ndarray | None:
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


def _read_readings(path, arm: FitModel, instrument: Any, arm_from: str | None) -> Measurements:
    """The measurements of a plane, point or distance instrument (``readings`` columns):
    every row's feature (its label column, required with several features) and what it
    read (0 for a touch or a seating)."""
    label = instrument.label_column
    text = ["pose", "target", *([label] if label else [])]
    table = _read_csv(
        path,
        arm,
        "measurements",
        measured=True,
        arm_from=arm_from,
        columns=(list(instrument.reading_columns), text, ["sigma_mm"]),
    )
    n = arm.n_joints
    m = table.values.shape[0]
    labels = table.texts.get("pose") or [str(i) for i in range(1, m + 1)]
    features = _feature_labels(path, instrument, table)
    targets = table.texts.get("target")
    if targets is not None:
        _check_target_labels(path, arm, targets, table.lines)
    readings = table.values[:, n:]
    if not instrument.reading_columns:
        readings = np.zeros((m, instrument.dim))
    warnings = [] if not table.beyond else [_beyond_limits_warning(path, arm, table.beyond)]
    return Measurements(
        model_units(table.values[:, :n], arm.joint_kinds),
        np.zeros((m, 2)),
        tuple(labels),
        rows=tuple(range(1, m + 1)),
        row_sigma=_row_sigma(path, table),
        warnings=tuple(warnings),
        targets=None if targets is None else tuple(targets),
        feature=features,
        readings=readings,
    )


def _feature_labels(path, instrument: Any, table: _Table) -> tuple[str, ...]:
    """Every row's feature: its label column's, each one of the instrument's; the one
    feature's where the column is absent (an error with several)."""
    known = tuple(instrument.labels)
    column = instrument.label_column
    m = table.values.shape[0]
    found = None if column is None else table.texts.get(column)
    if found is None:
        if len(known) > 1:
            raise fail(
                path,
                f"line {table.header_line}: missing column '{column}': the robot file's "
                f"[instrument] has {len(known)} {column}s ({', '.join(known)}); add a column "
                f"'{column}' naming the {column} of every row",
            )
        return (known[0],) * m
    for r, label in enumerate(found):
        if label not in known:
            said = shown(label) if label else "empty"
            raise fail(
                path,
                f"row {r + 1} (line {table.lines[r]}), column {column}: {said} "
                f"is not a {column} of the robot file's [instrument]: {suggest(label, known)}"
                f"its {column}s are {', '.join(known)}",
            )
    return tuple(found)


def _orientation_columns(path, arm: FitModel, table: _Table) -> np.ndarray | None:
    """The rotation vectors ``(m, 3)`` (rad) of ``rx_deg, ry_deg, rz_deg``: all three or none,
    of a spatial arm, each of at most :data:`MAX_TURN_DEG`."""
    found = [table.numbers.get(name) for name in ORIENTATION_COLUMNS]
    given = [
        name for name, column in zip(ORIENTATION_COLUMNS, found, strict=True) if column is not None
    ]
    if not given:
        return None
    if len(given) < 3:
        missing = [name for name in ORIENTATION_COLUMNS if name not in given]
        raise fail(
            path,
            f"line {table.header_line}: has {', '.join(given)} but not {', '.join(missing)}: "
            "a 6-DoF instrument's "
            "orientation is a rotation vector rx_deg, ry_deg, rz_deg; add the missing "
            "columns or remove the orientation",
        )
    if arm.orientation_dim < 3:
        raise fail(
            path,
            f"has orientation columns ({', '.join(given)}) but {arm.name} is a {arm.family} arm, "
            "whose tool orientation is not measured; remove them",
        )
    degrees_ = np.column_stack([column for column in found if column is not None])
    angle = np.linalg.norm(degrees_, axis=1)
    bad = np.flatnonzero(angle > MAX_TURN_DEG)
    if bad.size:
        r = int(bad[0])
        raise fail(
            path,
            f"row {r + 1} (line {table.lines[r]}), columns rx_deg, ry_deg, rz_deg: a turn of "
            f"{angle[r]:.6g} deg is more than {MAX_TURN_DEG:g}; give the orientation as a "
            "rotation vector (axis times angle) in degrees",
        )
    return np.radians(degrees_)


def _load_columns(path, table: _Table) -> tuple[np.ndarray | None, np.ndarray | None]:
    """The ``payload_kg`` column (not negative) and the tip force ``(m, 2)`` (a missing axis 0)."""
    payload = table.numbers.get("payload_kg")
    if payload is not None and np.any(payload < 0):
        r = int(np.flatnonzero(payload < 0)[0])
        raise fail(
            path,
            f"row {r + 1} (line {table.lines[r]}), column payload_kg: {payload[r]:g} kg is "
            "negative; give the mass carried (0 for none)",
        )
    fx, fy = table.numbers.get("fx_N"), table.numbers.get("fy_N")
    force = None
    if fx is not None or fy is not None:
        m = table.values.shape[0]
        force = np.column_stack(
            [np.zeros(m) if fx is None else fx, np.zeros(m) if fy is None else fy]
        )
    return payload, force


def _check_target_labels(path, arm: FitModel, labels: list[str], lines: list[int]) -> None:
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
