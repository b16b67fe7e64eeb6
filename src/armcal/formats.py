"""The files armcal reads, as data: every robot-file key and every CSV column.

One catalogue serves three readers: :mod:`armcal.files` takes the allowed keys
of each robot-file table from it (so a key cannot be accepted without being
documented) and its hints for a key written in the wrong table; ``armcal
formats`` prints it; and each command's ``--help`` names the columns of the
files it reads.

The CSV columns are :mod:`armcal.columns`'s, named here too.

Examples
--------
>>> [key.name for key in ROBOT_KEYS if key.table == "identify"]
['fixed', 'free']
>>> table_of("sigma_mm")
'measurement'
"""

from __future__ import annotations

import textwrap
from collections.abc import Sequence

from .columns import COLUMNS, Column, columns_line, reader_columns
from .keys import INSTRUMENT_KEYS, Key

__all__ = [
    "COLUMNS",
    "FIGURE_FORMATS",
    "FILE_KINDS",
    "ROBOT_KEYS",
    "SPATIAL_KEYS",
    "SPATIAL_TRUTH_KEYS",
    "TRUTH_KEYS",
    "Column",
    "Key",
    "allowed_keys",
    "columns_line",
    "format_reference",
    "reader_columns",
    "table_of",
]


ROBOT_KEYS: tuple[Key, ...] = (
    Key("", "name", "text", "the file's stem", "name shown in reports and exports"),
    Key("", "link_lengths_mm", "mm, one per link", "required", "nominal link lengths l1..ln"),
    Key(
        "",
        "joint_limits_deg",
        "deg, [lo, hi] per joint",
        "[-180, 180] each",
        "joint limits; every designed pose stays inside them",
    ),
    Key(
        "",
        "base_offset",
        "true/false",
        "false",
        "data in the instrument's frame: also identify the base position x0, y0 (3-D data "
        "add the base rotation phi0 in the fitted plane)",
    ),
    Key(
        "",
        "joint_map",
        "n x n matrix",
        "lower-triangular ones (each reading is a relative joint angle, as in the paper)",
        "coupled joints: link angles theta = M q from the controller's commands q",
    ),
    Key(
        "",
        "joint_offsets_deg",
        "deg, one per joint",
        "0 each",
        "known zero offsets already in the controller (an exported calibration)",
    ),
    Key(
        "measurement",
        "sigma_mm",
        "mm, one number or [sx, sy]",
        "estimated from the residuals",
        "instrument noise, 1 std per axis",
    ),
    Key(
        "measurement",
        "covariance_mm2",
        "mm^2, [[a, b], [b, c]]",
        "none",
        "instrument noise as a full 2 x 2 covariance (instead of sigma_mm)",
    ),
    Key(
        "measurement",
        "joint_sigma_deg",
        "deg, one number or one per joint",
        "0",
        "encoder noise, propagated through the Jacobian (needs sigma_mm)",
    ),
    Key(
        "measurement",
        "region",
        'inline table: kind = "annulus" or "box"',
        "none: anywhere",
        "where the instrument sees the tool (annulus: center_mm, r_min_mm, r_max_mm; "
        "box: x_mm = [lo, hi], y_mm = [lo, hi])",
    ),
    Key(
        "measurement",
        "gravity",
        "direction [gx, gy, gz] in the instrument frame",
        "none",
        "gravity for 3-D data and [elastostatic]; projected into the fitted plane",
    ),
    Key(
        "identify",
        "fixed",
        "list of parameter names",
        "none: all free",
        "parameters held at nominal (e.g. ['dl4', 'dq1']); with [elastostatic] also "
        "compliance terms, held at zero (e.g. 'k3')",
    ),
    Key(
        "identify",
        "free",
        "list of parameter names",
        "all",
        "the only parameters identified (instead of fixed); geometry and compliance "
        "terms are each governed only when the list names one of their kind",
    ),
    Key(
        "targets",
        "LABEL",
        "inline table: length_mm (mm), angle_deg (deg)",
        "no targets: the tool point at the end of the last link",
        "a reflector or tool point per label: distance from the last joint and angle from "
        "the last link; measurements name it in a target column",
    ),
    Key(
        "elastostatic",
        "gravity_xy",
        "direction [gx, gy] in the base frame",
        "none: a horizontal arm",
        "gravity in the plane of motion (size 9.80665 m/s^2)",
    ),
    Key(
        "elastostatic",
        "link_masses_kg",
        "kg, one per link",
        "none: the lumped mode (c1..cn)",
        "link masses; with them the compliances k1..kn are identified",
    ),
    Key(
        "elastostatic",
        "com_fraction",
        "0..1, one or one per link",
        "0.5",
        "centre of mass along each link (0 at its joint, 1 at the next)",
    ),
    Key(
        "elastostatic",
        "payload_kg",
        "kg",
        "0",
        "payload at the tip for rows without a payload_kg column",
    ),
)

TRUTH_KEYS: tuple[Key, ...] = (
    Key("", "dl_mm", "mm, one per link", "required", "true length deviations"),
    Key("", "dq_deg", "deg, one per joint", "required", "true joint zero offsets"),
    Key(
        "",
        "base_mm",
        "[x0 mm, y0 mm]",
        "0, 0",
        "true base pose (robots with base_offset)",
    ),
    Key(
        "",
        "k_urad_per_Nm",
        "urad/(N*m), one per joint",
        "0",
        "true joint compliances (robots with link masses)",
    ),
    Key(
        "",
        "c_mdeg_per_m",
        "mdeg/m, one per joint",
        "0",
        "true lumped compliances (robots without link masses)",
    ),
)


#: A spatial serial arm's robot TOML: from a URDF, a modified DH table (``[mdh]``), a
#: standard one (``[dh]``) or a UR model (``[ur]``).
SPATIAL_KEYS: tuple[Key, ...] = (
    Key("", "name", "text", "the file's stem", "name shown in reports and exports"),
    Key(
        "",
        "urdf",
        "path, relative to this file",
        "none: give [mdh], [dh] or [ur]",
        "the arm's URDF",
    ),
    Key("", "base_link", "URDF link name", "the URDF's root", "where the chain starts"),
    Key("", "tip_link", "URDF link name", "the one leaf of the chain", "where the chain ends"),
    Key(
        "",
        "joint_map",
        "n x n matrix",
        "identity",
        "coupled joints: the URDF's joint values u = M q from the controller's readings q",
    ),
    Key(
        "",
        "joint_limits_deg",
        "deg (mm for a prismatic joint), [lo, hi] per joint",
        "the URDF's (on u); a full turn each way for continuous joints",
        "limits on the controller's readings q; they replace the URDF's (not an [mdh] "
        "table's own)",
    ),
    Key("mdh", "alpha_deg", "deg, one per joint", "required", "Craig's alpha: Rx(alpha)"),
    Key("mdh", "a_mm", "mm, one per joint", "required", "Craig's a: Tx(a)"),
    Key("mdh", "theta_deg", "deg, one per joint", "required", "the joint's zero: Rz(theta)"),
    Key("mdh", "d_mm", "mm, one per joint", "required", "Craig's d: Tz(d)"),
    Key(
        "mdh",
        "beta_deg",
        "deg, one per joint",
        "0 each",
        "Hayati's beta, Ry(beta) after Tx(a): nearly parallel consecutive axes",
    ),
    Key(
        "mdh",
        "joint_types",
        '"R" or "P" per joint',
        '"R" each',
        "revolute or prismatic (then d is the reading, in mm: its columns are q{j}_mm)",
    ),
    Key(
        "mdh",
        "joint_limits_deg",
        "deg (mm for a prismatic joint), [lo, hi] per joint",
        "none",
        "the table's own limits, on its joint values u = M q as a URDF's <limit> (export "
        "writes them for a coupled joint_map); kept beside the top-level joint_limits_deg",
    ),
    Key("mdh", "base_xyz_mm", "mm, [x, y, z]", "0", "a base frame before the first row"),
    Key("mdh", "base_rpy_deg", "deg, [roll, pitch, yaw]", "0", "its orientation"),
    Key("mdh", "tip_xyz_mm", "mm, [x, y, z]", "0", "the flange after the last row"),
    Key("mdh", "tip_rpy_deg", "deg, [roll, pitch, yaw]", "0", "its orientation"),
    Key("dh", "alpha_deg", "deg, one per joint", "required", "the DH twist: Rx(alpha)"),
    Key("dh", "a_mm", "mm, one per joint", "required", "the DH length: Tx(a)"),
    Key("dh", "theta_deg", "deg, one per joint", "required", "the joint's zero: Rz(theta)"),
    Key("dh", "d_mm", "mm, one per joint", "required", "the DH offset: Tz(d)"),
    Key("dh", "joint_types", '"R" or "P" per joint', '"R" each', "revolute or prismatic"),
    Key("dh", "base_xyz_mm", "mm, [x, y, z]", "0", "a base frame before the first row"),
    Key("dh", "base_rpy_deg", "deg, [roll, pitch, yaw]", "0", "its orientation"),
    Key("dh", "tip_xyz_mm", "mm, [x, y, z]", "0", "a tip frame after the last row"),
    Key("dh", "tip_rpy_deg", "deg, [roll, pitch, yaw]", "0", "its orientation"),
    Key(
        "measurement",
        "sigma_mm",
        "mm, one number or [sx, sy, sz]",
        "estimated from the residuals",
        "instrument noise, 1 std per axis of the instrument's frame",
    ),
    Key(
        "measurement",
        "covariance_mm2",
        "mm^2, 3 x 3",
        "none",
        "instrument noise as a full covariance (instead of sigma_mm)",
    ),
    Key(
        "measurement",
        "tracker",
        "table: range_mm, range_mm_per_m, transverse_mm, transverse_mm_per_m",
        "none",
        "a laser tracker's noise (1 std): along the line of sight and across it, each a "
        "constant plus a term per metre of distance from the tracker (instead of sigma_mm)",
    ),
    Key(
        "measurement",
        "orientation_sigma_deg",
        "deg",
        "none",
        "a 6-DoF instrument's orientation noise (1 std about each axis): needed for "
        "measurements with rx_deg, ry_deg, rz_deg; plans are then evaluated for full poses "
        "(partial coordinates that read a turn: a turn's component's noise)",
    ),
    Key(
        "measurement",
        "sigma_px",
        "px",
        "none",
        "a camera's noise (1 std per pixel coordinate of a corner), instead of sigma_mm",
    ),
    *INSTRUMENT_KEYS,
    Key(
        "targets",
        "LABEL",
        "inline table: xyz_mm (mm, tip frame), normal (a direction, tip frame)",
        "none: found from the data",
        "a reflector's nominal position, and the way it faces (for acceptance_deg); "
        "measurements name it in a target column",
    ),
    Key(
        "identify",
        "fixed",
        "list of parameter names",
        "none",
        "parameters held at nominal; with [elastostatic] also compliance terms "
        "(c2.j3, k4), held at zero",
    ),
    Key(
        "identify",
        "free",
        "list of parameter names",
        "all",
        "the only parameters identified; geometry and compliance terms are each governed "
        "only when the list names one of their kind, and a term the rows cannot identify "
        "is refused",
    ),
    Key(
        "ur",
        "model",
        "ur3, ur5, ur10, ur3e, ur5e, ur10e or ur16e",
        "none: give urdf, [mdh] or [dh]",
        "a Universal Robots arm: its nominal DH table, built in (metres and radians as the "
        "controller's)",
    ),
    Key(
        "ur",
        "calibration",
        "path, relative to this file",
        "the nominal table",
        "the controller's calibration.conf, whose [mounting] deltas are added to the nominal "
        "table as the controller does, or the ROS driver's calibration YAML (.yaml): the "
        "arm's own joint frames",
    ),
    Key(
        "elastostatic",
        "gravity",
        "a direction [gx, gy, gz] in the robot's base frame",
        "[0, 0, -1]: a floor-mounted arm",
        "gravity, scaled to 9.80665 m/s^2; the table makes the revolute joints compliant",
    ),
    Key(
        "elastostatic",
        "link_masses_kg",
        "kg, one per joint",
        "the URDF's <inertial> tags, else the lumped mode",
        "what each joint moves up to the next joint; compliance k1..kn [urad/(N*m)]",
    ),
    Key(
        "elastostatic",
        "link_com_mm",
        "mm, [x, y, z] per joint, in armcal's frame of the joint after its motion (z along "
        "its axis; a URDF child link's frame turned so, the same for a joint about z)",
        "the joint's origin",
        "every link's centre of mass (the URDF's <inertial> tags are turned into this frame "
        "when the table gives no masses)",
    ),
    Key(
        "elastostatic",
        "lumped",
        "true/false",
        "true when no masses are known",
        "masses unknown: c{j}.{s} [mdeg/m], joint j's twist per metre of horizontal lever "
        "arm to station s (the joints beyond it and the tip), and with payloads that vary k{j}",
    ),
    Key(
        "elastostatic", "payload_kg", "kg", "0", "the payload of rows without a payload_kg column"
    ),
    Key(
        "elastostatic",
        "payload_com_mm",
        "mm, [x, y, z] in the tip (flange) frame",
        "[0, 0, 0]",
        "the payload's centre of mass",
    ),
)

#: A spatial arm's truth TOML (virtual arms).
SPATIAL_TRUTH_KEYS: tuple[Key, ...] = (
    Key("", "robot", "path to a URDF or robot TOML", "the nominal arm", "the true arm"),
    Key(
        "",
        "base",
        "inline table: xyz_mm (mm), rpy_deg (deg)",
        "the identity",
        "the arm's base pose in the instrument's frame",
    ),
    Key(
        "",
        "errors",
        "table of parameter = value (mm, deg)",
        "none",
        "errors of the joints' placement and zeros (j2.x, dq3, ...)",
    ),
    Key(
        "",
        "targets",
        "table of LABEL = { xyz_mm = [x, y, z] }",
        "the robot file's",
        "the reflectors' true positions in the tip frame",
    ),
    Key(
        "",
        "instrument",
        "the robot file's [instrument] keys; a distance's offset_mm too",
        "the robot file's",
        "where a plane, fixed point, distance, partial or camera instrument really is",
    ),
    Key(
        "",
        "compliance",
        "table of parameter = value (urad/(N*m) for k2, mdeg/m for c2.j3)",
        "none: 0",
        "the true joint compliance of a robot with [elastostatic]",
    ),
)


#: Figure file suffix to the format written (matplotlib's name): the suffix
#: decides, so a ``.pdf`` file holds a PDF and never PNG bytes.
FIGURE_FORMATS: dict[str, str] = {".png": "png", ".pdf": "pdf", ".svg": "svg", ".eps": "eps"}

#: What each file kind is, for ``armcal formats``.
FILE_KINDS: dict[str, str] = {
    "robot": "robot TOML (--robot): the arm, its instrument and what to identify",
    "truth": "truth TOML (--truth): the deviations of a virtual robot",
    "spatial robot": "spatial robot TOML (--robot, or a URDF itself): a serial arm in 3-D",
    "spatial truth": "spatial truth TOML (--truth): the errors of a virtual spatial arm",
    "plan": "plan CSV (--plan, --candidates, --test-poses): poses to visit",
    "measurements": "measurements CSV (--measurements): poses and what the instrument read",
    "readings": (
        "measurements CSV of a plane, point, distance, partial or camera instrument "
        "(--measurements; [instrument] kind plane, point, distance, partial or camera): poses "
        "and what the instrument read"
    ),
    "program": "program CSV (--program): joint commands to correct",
    "calibration": "calibration JSON (--calibration): written by identify -o",
}

_CSV_RULES = (
    "CSV files: one header line, then one row per pose. Separators: comma; a semicolon "
    "(with a decimal comma allowed, as European spreadsheets write) or a tab when the header "
    "has no comma. Lines that start with # and blank lines are skipped; a UTF-8 byte-order "
    "mark and CRLF line ends are accepted. '-' reads the file from stdin."
)


def allowed_keys(table: str, keys: tuple[Key, ...] = ROBOT_KEYS) -> list[str]:
    """The keys allowed in ``table`` (``""`` the top level), tables included at the top."""
    names = [k.name for k in keys if k.table == table]
    if table == "":
        names += list(dict.fromkeys(k.table for k in keys if k.table))
    return names


def table_of(key: str) -> str | None:
    """The robot-file table that has ``key`` (``""`` the top level), or None.

    >>> table_of("link_lengths_mm")
    ''
    >>> table_of("nonsense") is None
    True
    """
    for entry in ROBOT_KEYS:
        if entry.name == key and entry.name != "LABEL":
            return entry.table
    return None


def _entries(rows: Sequence[tuple[str, str]], names: int = 0, width: int = 100) -> list[str]:
    """Two columns: a name (at least ``names`` wide), then its text wrapped beside it."""
    indent = 4 + max(names, *(len(name) for name, _ in rows))
    out = []
    for name, text in rows:
        wrapped = textwrap.wrap(text, width - indent) or [""]
        out.append(f"  {name:<{indent - 4}}  {wrapped[0]}")
        out.extend(" " * indent + more for more in wrapped[1:])
    return out


def _key_text(key: Key) -> str:
    return f"{key.meaning}. Unit: {key.unit}. Default: {key.default}."


def format_reference() -> str:
    """Every file armcal reads: keys and columns with unit, default and meaning."""
    lines = ["armcal file formats", "", FILE_KINDS["robot"] + ":"]
    for table in dict.fromkeys(k.table for k in ROBOT_KEYS):
        lines += ["", f"  [{table}]" if table else "  top level"]
        rows = [(k.name, _key_text(k)) for k in ROBOT_KEYS if k.table == table]
        lines += _entries(rows, max(len(k.name) for k in ROBOT_KEYS))
    lines += ["", FILE_KINDS["truth"] + ":"]
    lines += _entries([(k.name, _key_text(k)) for k in TRUTH_KEYS])
    lines += ["", FILE_KINDS["spatial robot"] + ":"]
    for table in dict.fromkeys(k.table for k in SPATIAL_KEYS):
        lines += ["", f"  [{table}]" if table else "  top level"]
        rows = [(k.name, _key_text(k)) for k in SPATIAL_KEYS if k.table == table]
        lines += _entries(rows, max(len(k.name) for k in SPATIAL_KEYS))
    lines += ["", FILE_KINDS["spatial truth"] + ":"]
    lines += _entries([(k.name, _key_text(k)) for k in SPATIAL_TRUTH_KEYS])
    for kind, columns in COLUMNS.items():
        lines += ["", FILE_KINDS[kind] + ":"]
        lines += _entries(
            [
                (c.name, f"{'required' if c.required else 'optional'}, {c.unit}: {c.meaning}")
                for c in columns
            ]
        )
    lines += ["", *textwrap.wrap(_CSV_RULES, 100)]
    lines += [
        "",
        *textwrap.wrap(
            FILE_KINDS["calibration"] + ": JSON of format armcal-calibration/1, read back by "
            "validate, compensate and export; its keys are in docs/reports.md.",
            100,
        ),
    ]
    return "\n".join(lines)
