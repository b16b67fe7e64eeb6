"""The CSV files armcal reads, as data: every column of a plan, a measurement file and a
program, and what each reader takes of them.

One catalogue serves the readers (:mod:`armcal.files.tables` takes the columns of
each kind from it), ``armcal formats`` (:mod:`armcal.formats` prints it) and each
command's ``--help`` (:func:`columns_line`).
"""

from __future__ import annotations

from dataclasses import dataclass

__all__ = ["COLUMNS", "Column", "columns_line", "reader_columns"]


@dataclass(frozen=True)
class Column:
    """One column of a CSV file armcal reads.

    Attributes
    ----------
    name : str
        The header name (``q1_deg..qn_deg`` stands for one per joint).
    unit : str
        Its unit.
    required : bool
        Whether every file of that kind has it.
    meaning : str
        What it holds.
    """

    name: str
    unit: str
    required: bool
    meaning: str


_JOINTS = Column(
    "q1_deg..qn_deg",
    "deg (mm for a prismatic joint)",
    True,
    "joint commands, one column per joint: q{j}_deg for a revolute joint, q{j}_mm for a "
    "prismatic one (a slide, read in mm); a column in the other unit is an error. Or, for "
    "a robot described by a URDF, named by its joints as ROS publishes them: "
    "shoulder_pan_joint in radians (a slide in metres), shoulder_pan_joint_deg or _rad "
    "(_mm or _m), in any order, matched by name; every joint of the chain needs one and "
    "a joint off the chain is an error",
)
_POSE = Column(
    "pose", "text", False, "pose label: rows with the same label are one pose (same joint values)"
)
_TARGET = Column("target", "text", False, "the [targets] label of the point measured")
_PAYLOAD = Column("payload_kg", "kg", False, "payload at the tip ([elastostatic] robots)")
_FORCE = (
    Column("fx_N", "N", False, "force at the tip, x ([elastostatic] robots)"),
    Column("fy_N", "N", False, "force at the tip, y ([elastostatic] robots)"),
)
_MEASURED = (
    Column("x_mm", "mm", True, "measured position, instrument frame"),
    Column("y_mm", "mm", True, "measured position, instrument frame"),
    Column("z_mm", "mm", False, "3-D data: the plane of motion is fitted"),
    _POSE,
    _TARGET,
    Column("sigma_mm", "mm", False, "this row's instrument noise (1 std)"),
    Column(
        "rx_deg",
        "deg",
        False,
        "a 6-DoF instrument's orientation of the target: rotation vector (axis times angle, "
        "instrument frame), x; with ry_deg and rz_deg (spatial arms)",
    ),
    Column("ry_deg", "deg", False, "the rotation vector, y"),
    Column("rz_deg", "deg", False, "the rotation vector, z"),
    _PAYLOAD,
    *_FORCE,
)

#: What a plane, fixed point, distance or partial instrument reads: a row that touches or
#: sits reports nothing but its feature; a distance its reading; partial coordinates the
#: axes they read, a cell empty where they read none.
_READ = (
    Column(
        "plane",
        "text",
        False,
        "kind plane: the [instrument] planes label of the plane the tool point touches "
        "(required with several planes)",
    ),
    Column(
        "point",
        "text",
        False,
        "kind point: the [instrument] points label of the fixed point the tool point sits in "
        "(required with several points)",
    ),
    Column(
        "distance_mm",
        "mm",
        False,
        "kind distance (required there): the reading, the tool point's distance from the "
        "pivot less an unknown offset",
    ),
    Column(
        "corner",
        "text",
        False,
        "kind camera (required there): the board's corner, i cols + j (0 first), a row per "
        "corner of a photo",
    ),
    Column("u_px", "px", False, "kind camera (required there): the corner's image column"),
    Column("v_px", "px", False, "kind camera (required there): the corner's image row"),
    *(
        Column(
            f"{axis}_mm",
            "mm",
            False,
            f"kind partial, reading {axis}: the tool point's {axis} in the instrument's frame; "
            "empty where it read none (one of the reads columns required)",
        )
        for axis in ("x", "y", "z")
    ),
    *(
        Column(
            f"r{axis}_deg",
            "deg",
            False,
            f"kind partial, reading r{axis}: the {axis} component of the tool's turn in the "
            "instrument's frame (rotation vector, axis times angle); empty where it read none",
        )
        for axis in ("x", "y", "z")
    ),
    _POSE,
    Column("target", "text", False, "the [targets] label of the tool point (with several)"),
    Column(
        "sigma_mm",
        "mm",
        False,
        "this row's instrument noise (1 std; not with a turn's columns: give "
        "orientation_sigma_deg)",
    ),
)

#: Columns of each CSV file kind, joint columns first.
COLUMNS: dict[str, tuple[Column, ...]] = {
    "plan": (
        _JOINTS,
        Column(
            "pose",
            "text",
            False,
            "pose label, which synthesize copies into the measurements (repeat a label to "
            "measure a pose in several cycles: validate --iso9283)",
        ),
        _PAYLOAD,
    ),
    "measurements": (_JOINTS, *_MEASURED),
    "readings": (_JOINTS, *_READ),
    "program": (
        _JOINTS,
        _POSE,
        Column("target", "text", False, "the [targets] label the command is for"),
        _PAYLOAD,
        *_FORCE,
    ),
}


def reader_columns(kind: str) -> tuple[list[str], list[str], list[str]]:
    """The columns of a CSV ``kind`` besides the joints, as its reader takes them.

    Returns the required (numeric) ones, the optional text ones and the optional
    numeric ones.

    >>> reader_columns("program")
    ([], ['pose', 'target'], ['payload_kg', 'fx_N', 'fy_N'])
    """
    cols = COLUMNS[kind][1:]  # the joint columns first
    return (
        [c.name for c in cols if c.required],
        [c.name for c in cols if not c.required and c.unit == "text"],
        [c.name for c in cols if not c.required and c.unit != "text"],
    )


def columns_line(kind: str) -> str:
    """The columns of a CSV ``kind`` in one line: required ones, then ``[,optional]``.

    >>> columns_line("plan")
    'q1_deg..qn_deg [,pose] [,payload_kg]'
    """
    required, text, numeric = reader_columns(kind)
    return ",".join([COLUMNS[kind][0].name, *required]) + "".join(
        f" [,{name}]" for name in text + numeric
    )
