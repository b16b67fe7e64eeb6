"""The robot file's keys as data: :class:`Key`, and the ``[instrument]`` table's.

:mod:`armcal.formats` holds every key of every file (and ``armcal formats`` prints
them); the instrument's, one table of many kinds (PRODUCT.md, "Instruments"), are
kept here, where a new instrument's keys are added.
"""

from __future__ import annotations

from dataclasses import dataclass

__all__ = ["INSTRUMENT_KEYS", "Key"]


@dataclass(frozen=True)
class Key:
    """One key of the robot TOML file.

    Attributes
    ----------
    table : str
        ``""`` for the top level, else the table (``measurement``, ...).
    name : str
        The key.
    unit : str
        Its unit or type.
    default : str
        What applies when it is absent.
    meaning : str
        What it sets.
    """

    table: str
    name: str
    unit: str
    default: str
    meaning: str


#: The ``[instrument]`` table of a spatial robot file: its kind, and where each kind's
#: instrument roughly is (a tracker's keys say where it stands for plans).
INSTRUMENT_KEYS: tuple[Key, ...] = (
    Key(
        "instrument",
        "kind",
        "tracker, probe, plane, point, distance, partial or camera",
        "tracker",
        "what the instrument reports: points (tracker), poses (probe), touches of planes, "
        "seatings in fixed points, distances from a pivot (a ballbar, a draw-wire sensor), "
        "or some coordinates of the tool point (partial: dial indicators, a displacement "
        "sensor, a CMM), or a board's corners in a camera's image (camera)",
    ),
    Key(
        "instrument",
        "camera",
        "path of a camera_info YAML or JSON file (relative to this file)",
        "required for kind camera",
        "the camera's intrinsics: image_width, image_height, camera_matrix, "
        "distortion_model plumb_bob, distortion_coefficients (k1 k2 p1 p2 k3)",
    ),
    Key(
        "instrument",
        "mount",
        '"eye-in-hand" or "eye-to-hand"',
        "required for kind camera",
        "the camera on the tool (the board fixed in the cell), or fixed in the cell (the "
        "board on the tool)",
    ),
    Key(
        "instrument",
        "camera_in_tool",
        "{ xyz_mm = [x, y, z], rpy_deg = [r, p, y] } in the flange's frame",
        "required for an eye-in-hand camera",
        "where the camera roughly is on the flange (its z along the view, x right, y down)",
    ),
    Key(
        "instrument",
        "camera_in_base",
        "{ xyz_mm = [x, y, z], rpy_deg = [r, p, y] } in the robot's base frame",
        "required for an eye-to-hand camera",
        "where the fixed camera roughly is",
    ),
    Key(
        "instrument",
        "board",
        "{ rows, cols, square_mm, xyz_mm = [x, y, z], rpy_deg = [r, p, y] }",
        "required for kind camera",
        "the board's corners (rows x cols, square_mm apart; corner i cols + j at (j s, i s, "
        "0)) and where it roughly is: in the base frame (eye-in-hand) or the flange's",
    ),
    Key(
        "instrument",
        "margin_px",
        "number (px)",
        "optional for kind camera, default 10",
        "how far inside the image's edges a plan's photo keeps every corner",
    ),
    Key(
        "instrument",
        "min_depth_mm",
        "number (mm)",
        "optional for kind camera, default 150",
        "how far in front of the lens a plan's photo keeps every corner (its nearest focus)",
    ),
    Key(
        "instrument",
        "max_tilt_deg",
        "number (degrees)",
        "optional for kind camera, default 60",
        "the largest angle between the board's normal and a corner's line of sight in a "
        "plan's photo (an oblique corner is found poorly)",
    ),
    Key(
        "instrument",
        "reads",
        'list of "x", "y", "z", "rx", "ry", "rz"',
        "required for kind partial",
        "what partial coordinates read in their own frame: some of its axes (a dial "
        "indicator: one) and of the tool's turn (its rotation vector's components, with a "
        "coordinate); rows give x_mm ... rz_deg, a cell empty where it read none",
    ),
    Key(
        "instrument",
        "tool_rpy_deg",
        "deg, [roll, pitch, yaw] as in URDF (Rz Ry Rx), in the tip frame",
        "optional for kind partial that reads a turn, default [0, 0, 0]",
        "where the tool's axes roughly are (found with the arm: tool.rx, tool.ry, tool.rz)",
    ),
    Key(
        "instrument",
        "max_turn_deg",
        "number (degrees)",
        "optional for kind partial that reads a turn, default 150",
        "the largest turn of the tool from the instrument's axes a plan's pose keeps to "
        "(away from the rotation vector's jump at a half turn)",
    ),
    Key(
        "instrument",
        "xyz_mm",
        "mm, [x, y, z] in the robot's base frame",
        "required for kind partial",
        "where the frame of partial coordinates roughly has its origin",
    ),
    Key(
        "instrument",
        "rpy_deg",
        "deg, [roll, pitch, yaw] as in URDF (Rz Ry Rx), in the robot's base frame",
        "required for kind partial",
        "how the frame of partial coordinates is roughly turned",
    ),
    Key(
        "instrument",
        "planes",
        "table of LABEL = { normal = [x, y, z], offset_mm = d } in the robot's base frame",
        "required for kind plane",
        "every plane touched, normal . p = d, where it roughly is; rows name theirs in a "
        "plane column",
    ),
    Key(
        "instrument",
        "points",
        "table of LABEL = { xyz_mm = [x, y, z] } in the robot's base frame",
        "required for kind point",
        "every fixed point (a cone, a ball socket) the tool sits in, where it roughly is; "
        "rows name theirs in a point column",
    ),
    Key(
        "instrument",
        "known_distances_mm",
        'list of ["A", "B", mm]',
        "none",
        "kind point: calibrated bars between labelled points, each tying the second point to "
        "the first at that distance (a point is tied to at most one, itself free)",
    ),
    Key(
        "instrument",
        "pivot_mm",
        "mm, [x, y, z] in the robot's base frame",
        "required for kind distance",
        "where a distance instrument's pivot roughly is; rows give distance_mm, the "
        "distance from it less an unknown offset",
    ),
    Key(
        "instrument",
        "position_mm",
        "mm, [x, y, z] in the robot's base frame",
        "none",
        "where the instrument stands, for plans: its range and the reflectors' acceptance "
        "angle are seen from here",
    ),
    Key(
        "instrument",
        "range_mm",
        "mm, [least, greatest]",
        "none",
        "the distances from position_mm the instrument measures (kind distance: from "
        "pivot_mm); plans keep every target within them",
    ),
    Key(
        "instrument",
        "box_mm",
        "mm, [[x lo, x hi], [y lo, y hi], [z lo, z hi]] in the robot's base frame",
        "none",
        "a measuring volume (a camera's, a CMM's); plans keep every target inside",
    ),
    Key(
        "instrument",
        "acceptance_deg",
        "deg",
        "none",
        "a reflector's half acceptance angle (an SMR: about 30); plans keep every target's "
        "normal within it of the line to position_mm (needs every target's normal)",
    ),
    Key(
        "instrument",
        "floor_z_mm",
        "mm, in the robot's base frame",
        "none",
        "a floor: plans keep every target and the flange above it",
    ),
)
