"""CSV tables: plans, measurements and robot programs, read strictly and written exactly.

A plan or program has a column per joint (``q1_deg..qn_deg``; a prismatic joint's
is ``q{j}_mm``, its reading a slide in mm); measurements add
the measured point (``x_mm, y_mm[, z_mm]``) and optional columns (``pose``,
``target``, ``sigma_mm``, ``payload_kg``, ``fx_N``, ``fy_N``).  Readers accept
the variants spreadsheets and instruments write (``#`` comments, ``;`` with a
decimal comma, tabs) and name the file, row and column of any bad value.
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..errors import ArmcalWarning
from ..models import FitModel, Loads
from .common import fail, shown, suggest
from .csv_table import (
    LIMIT_TOLERANCE_DEG,
    LIMIT_TOLERANCE_MM,
    Table,
    beyond_limits_warning,
    check_target_labels,
    read_table,
    row_sigma,
)
from .joints import (
    model_units,
)
from .robots import METRE_REACH_MM
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


#: A measured tip farther than ``(1 + REACH_MARGIN)`` times the arm's reach (the sum of
#: its link lengths) from the base is an error: no arm whose links deviate by less than
#: 10 % (the ``large-deviation`` bound of :mod:`armcal.plausibility`) gets there.
REACH_MARGIN = 0.1

#: An instrument sees an arm from at most this many reaches away (a laser tracker a
#: few metres from a sub-metre arm): a point beyond the reach but within it may be
#: instrument-frame data without a base offset, one farther is a wrong value or unit.
INSTRUMENT_RANGE = 100.0


#: A rotation vector's angle is at most half a turn; up to a full turn is accepted (an
#: instrument may not reduce it), beyond that the column is not degrees of a rotation vector.
MAX_TURN_DEG = 360.0


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
    table = read_table(path, arm, "plan")
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
    table = read_table(path, arm, "program", arm_from=arm_from)
    targets = table.texts.get("target")
    if targets is not None:
        if not arm.target_labels:
            raise fail(
                path,
                f"has a target column but {arm.name} has no targets; remove the column",
            )
        check_target_labels(path, arm, targets, table.lines)
    labels = table.texts.get("pose")
    payload, force = _load_columns(path, table)
    return Program(
        model_units(table.values, arm.joint_kinds),
        None if labels is None else tuple(labels),
        None if targets is None else tuple(targets),
        payload,
        force,
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
    table = read_table(path, arm, "measurements", measured=True, arm_from=arm_from)
    n = arm.n_joints
    values = table.values
    m = values.shape[0]
    labels = table.texts.get("pose") or [str(i) for i in range(1, m + 1)]
    sigma = row_sigma(path, table)
    xy = values[:, n:]
    z = table.numbers.get("z_mm")
    targets = table.texts.get("target")
    if targets is not None:
        check_target_labels(path, arm, targets, table.lines)
    if z is None:
        _check_reach(path, arm, xy, table.lines, arm_from)
    else:
        _check_reach(path, arm, np.column_stack([xy, z]), table.lines, arm_from)
    warnings = []
    if table.beyond:
        warnings.append(beyond_limits_warning(path, arm, table.beyond))
    payload, force = _load_columns(path, table)
    orientation = _orientation_columns(path, arm, table)
    return Measurements(
        model_units(values[:, :n], arm.joint_kinds),
        xy,
        tuple(labels),
        rows=tuple(range(1, m + 1)),
        row_sigma=sigma,
        warnings=tuple(warnings),
        targets=None if targets is None else tuple(targets),
        z=z,
        payload_kg=payload,
        force_n=force,
        orientation=orientation,
    )


def _read_readings(path, arm: FitModel, instrument: Any, arm_from: str | None) -> Measurements:
    """The measurements of a plane, point or distance instrument (``readings`` columns):
    every row's feature (its label column, required with several features) and what it
    read (0 for a touch or a seating).  Partial coordinates: :func:`_read_partial`."""
    if instrument.reads_every_feature and instrument.label_column is None:
        return _read_partial(path, arm, instrument, arm_from)
    label = instrument.label_column
    text = ["pose", "target", *([label] if label else [])]
    table = read_table(
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
        check_target_labels(path, arm, targets, table.lines)
    readings = table.values[:, n:]
    if not instrument.reading_columns:
        readings = np.zeros((m, instrument.dim))
    _check_bounds(path, instrument, readings, table.lines)
    warnings = [] if not table.beyond else [beyond_limits_warning(path, arm, table.beyond)]
    return Measurements(
        model_units(table.values[:, :n], arm.joint_kinds),
        np.zeros((m, 2)),
        tuple(labels),
        rows=tuple(range(1, m + 1)),
        row_sigma=row_sigma(path, table),
        warnings=tuple(warnings),
        targets=None if targets is None else tuple(targets),
        feature=features,
        readings=readings,
    )


def _check_bounds(path, instrument: Any, readings: np.ndarray, lines: list[int]) -> None:
    """InputError for a reading outside what the instrument can read (a camera's pixel
    outside its image)."""
    bounds = instrument.reading_bounds
    if bounds is None:
        return
    for k, (name, (low, high)) in enumerate(zip(instrument.reading_columns, bounds, strict=True)):
        bad = np.flatnonzero((readings[:, k] < low) | (readings[:, k] > high))
        if bad.size:
            r = int(bad[0])
            raise fail(
                path,
                f"row {r + 1} (line {lines[r]}), column {name}: {readings[r, k]:g} is outside "
                f"the image ({low:g} to {high:g} {instrument.unit}); check the camera file's "
                "image size and the column's unit",
            )


def _read_partial(path, arm: FitModel, instrument: Any, arm_from: str | None) -> Measurements:
    """The measurements of partial coordinates: a column per component the instrument
    reads (``x_mm``, ``y_mm``, ``z_mm``; a turn's ``rx_deg``, ``ry_deg``, ``rz_deg``, read
    in radians), at least one, each cell a reading or empty; every reading a row of its
    own (its component its feature), carrying its line's row number, pose, target and
    sigma (a line's ``sigma_mm`` is its coordinates', refused where it reads turns)."""
    names = list(instrument.reading_columns)
    axes = ["x_mm", "y_mm", "z_mm"]
    table = read_table(
        path,
        arm,
        "measurements",
        measured=True,
        arm_from=arm_from,
        columns=([], ["pose", "target", *axes, *ORIENTATION_COLUMNS], ["sigma_mm"]),
    )
    for name in (*axes, *ORIENTATION_COLUMNS):
        if name in table.texts and name not in names:
            component = name.split("_")[0]
            raise fail(
                path,
                f"line {table.header_line}: column {name}: the robot file's [instrument] reads "
                f'{", ".join(instrument.reads)} only; add "{component}" to [instrument] reads, '
                "or remove the column",
            )
    if instrument.turn_features and "sigma_mm" in table.numbers:
        raise fail(
            path,
            f"line {table.header_line}: column sigma_mm: a line's sigma in mm cannot be its "
            "turns'; give the sigmas in the robot file's [measurement] (sigma_mm, "
            "orientation_sigma_deg) and remove the column",
        )
    present = [name for name in names if name in table.texts]
    if not present:
        raise fail(
            path,
            f"line {table.header_line}: no column of a reading: the robot file's [instrument] "
            f"reads {', '.join(instrument.reads)}; add a column {' or '.join(names)}",
        )
    m = table.values.shape[0]
    cells = np.full((m, len(names)), np.nan)
    for k, name in enumerate(names):
        for r, text in enumerate(table.texts.get(name, ())):
            cells[r, k] = _reading(path, text, r, table.lines[r], name)
        if name.endswith("_deg"):  # a turn's component: radians inside
            cells[:, k] = np.radians(cells[:, k])
    found = ~np.isnan(cells)
    empty = np.flatnonzero(~found.any(axis=1))
    if empty.size:
        r = int(empty[0])
        raise fail(
            path,
            f"row {r + 1} (line {table.lines[r]}): no reading; give one in "
            f"{' or '.join(present)}, or remove the row",
        )
    line, feature = np.nonzero(found)  # every reading, row by row, axis by axis
    n = arm.n_joints
    labels = table.texts.get("pose") or [str(i) for i in range(1, m + 1)]
    targets = table.texts.get("target")
    if targets is not None:
        check_target_labels(path, arm, targets, table.lines)
    sigma = row_sigma(path, table)
    warnings = [] if not table.beyond else [beyond_limits_warning(path, arm, table.beyond)]
    return Measurements(
        model_units(table.values[line, :n], arm.joint_kinds),
        np.zeros((line.size, 2)),
        tuple(labels[r] for r in line),
        rows=tuple(int(r) + 1 for r in line),
        row_sigma=None if sigma is None else sigma[line],
        warnings=tuple(warnings),
        targets=None if targets is None else tuple(targets[r] for r in line),
        feature=tuple(instrument.labels[k] for k in feature),
        readings=cells[line, feature][:, None],
    )


def _reading(path, text: str, r: int, line: int, name: str) -> float:
    """A reading's cell: a finite number, or NaN where it is empty."""
    if not text:
        return float("nan")
    try:
        value = float(text)
    except ValueError:
        value = float("nan")
    unit = name.rsplit("_", 1)[1]
    if not np.isfinite(value):
        raise fail(
            path,
            f"row {r + 1} (line {line}), column {name}: {shown(text)} is not a finite number "
            f"({unit}); leave the cell empty where the instrument read nothing",
        )
    if unit == "deg" and abs(value) > _LARGEST_TURN_DEG:
        raise fail(
            path,
            f"row {r + 1} (line {line}), column {name}: {shown(text)} is beyond "
            f"±{_LARGEST_TURN_DEG:g} deg, which no component of a rotation vector (axis times "
            "angle, at most a half turn) reaches; check the unit (deg) and the convention",
        )
    if abs(value) > _FARTHEST_READING_MM:
        raise fail(
            path,
            f"row {r + 1} (line {line}), column {name}: {shown(text)} is beyond "
            f"±{_FARTHEST_READING_MM:g} mm; check the unit (mm)",
        )
    return value


#: A coordinate no instrument of a robot cell reads (mm): 1 km is a wrong unit or value.
_FARTHEST_READING_MM = 1e6
#: A turn's component is at most its angle, at most half a turn.
_LARGEST_TURN_DEG = 180.0


def _feature_labels(path, instrument: Any, table: Table) -> tuple[str, ...]:
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


def _orientation_columns(path, arm: FitModel, table: Table) -> np.ndarray | None:
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


def _load_columns(path, table: Table) -> tuple[np.ndarray | None, np.ndarray | None]:
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
