"""The ``[instrument]`` table of an instrument other than a tracker: where it roughly is.

A robot file's ``[instrument]`` names its ``kind`` (PRODUCT.md, "Instruments"):
absent, ``tracker`` or ``probe``, the instrument reports points (or poses) and
the table's keys say where it stands for plans (:mod:`armcal.files.spatial`);
``plane``, ``point`` or ``distance``, it is an instrument of
:mod:`armcal.instruments`, read here:

* ``plane``: ``planes = { LABEL = { normal = [x, y, z], offset_mm = d } }``, every
  plane ``normal . p = d`` in the robot's base frame;
* ``point``: ``points = { LABEL = { xyz_mm = [x, y, z] } }``;
* ``distance``: ``pivot_mm = [x, y, z]`` and ``range_mm = [least, greatest]``, the
  distances from the pivot it reads (a truth file may give the reading's
  ``offset_mm`` too);
* ``partial``: ``reads = ["z"]`` (what it reads in its frame, some of x, y, z and of
  the tool's turn rx, ry, rz, at least one coordinate), ``xyz_mm = [x, y, z]`` and
  ``rpy_deg = [r, p, y]``, its frame in the base's; where it reads turns, optionally
  ``tool_rpy_deg`` (the tool's axes in the tip frame, default none turned) and
  ``max_turn_deg`` (the largest turn of the tool from the instrument's axes a plan
  keeps to, default 150);
* ``camera``: ``camera = "cam.yaml"`` (its ``camera_info``, relative to the robot
  file; a calibration file holds the mapping itself), ``mount`` (``eye-in-hand`` or
  ``eye-to-hand``), ``camera_in_tool`` (eye-in-hand) or ``camera_in_base``
  (eye-to-hand) ``= { xyz_mm, rpy_deg }``, and ``board = { rows, cols, square_mm,
  xyz_mm, rpy_deg }``, the board's corners and where it is (in the base frame for
  eye-in-hand, in the tool's for eye-to-hand).

The same table, written back by :func:`instrument_section`, is a calibration
file's ``instrument`` section and a truth file's ``[instrument]`` (where the
virtual lab's instrument really is).
"""

from __future__ import annotations

import os
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import InputError
from ..families.registry import RobotSpec, family_of
from ..instruments import (
    Board,
    Camera,
    Coordinates,
    Distance,
    FixedPoints,
    Instrument,
    Plane,
    Planes,
)
from ..instruments.camera import MOUNTS
from ..instruments.partial import AXES, COMPONENTS, TURNS
from ..models.instrumented import InstrumentedArm
from .camera_info import camera_info_table, intrinsics_of, read_camera_info
from .common import check_keys, fail, load_toml, number, numbers, shown, suggest

__all__ = [
    "EQUATION_KINDS",
    "INSTRUMENT_KINDS",
    "TRACKER_KINDS",
    "instrument_kind",
    "instrument_section",
    "instrumented_arm",
    "instrumented_truth",
    "read_instrument",
    "true_instrument",
]

#: Kinds whose rows report points (or poses): the table says where they stand for plans.
TRACKER_KINDS = ("tracker", "probe")
#: Kinds of :mod:`armcal.instruments`, read here.
EQUATION_KINDS = ("plane", "point", "distance", "partial", "camera")
#: Every kind PRODUCT.md names, in its order.
INSTRUMENT_KINDS = ("tracker", "probe", "plane", "point", "distance", "partial", "camera")

#: The keys each kind's table takes (with ``kind``); a truth file's distance adds the offset.
_KEYS = {
    "plane": ("kind", "planes"),
    "point": ("kind", "points", "known_distances_mm"),
    "distance": ("kind", "pivot_mm", "range_mm"),
    "partial": ("kind", "reads", "xyz_mm", "rpy_deg", "tool_rpy_deg", "max_turn_deg"),
    "camera": (
        "kind",
        "camera",
        "mount",
        "camera_in_tool",
        "camera_in_base",
        "board",
        "margin_px",
        "min_depth_mm",
        "max_tilt_deg",
    ),
}


def instrument_kind(path: str | os.PathLike, table: Any, where: str = "instrument") -> str:
    """The ``kind`` of an ``[instrument]`` table (``tracker`` where it has none)."""
    if table is None:
        return "tracker"
    if not isinstance(table, dict):
        raise fail(path, f"key '{where}': expected a table [{where}]")
    kind = table.get("kind", "tracker")
    if kind not in INSTRUMENT_KINDS:
        raise fail(
            path,
            f"key '{where}.kind': {shown(str(kind))} is not an instrument: "
            f"{suggest(str(kind), INSTRUMENT_KINDS)}the kinds are {', '.join(INSTRUMENT_KINDS)}",
        )
    return str(kind)


def read_instrument(
    path: str | os.PathLike, table: Any, where: str = "instrument", *, truth: bool = False
) -> Instrument | None:
    """The instrument of an ``[instrument]`` table (module notes); None for a tracker's.

    ``truth``: a truth file's table, whose distance may give its ``offset_mm``.

    Raises
    ------
    InputError
        Naming the file and the key: an unknown kind or key, a missing one, a normal
        of zero length, a range that is not ``0 <= least < greatest``.
    """
    kind = instrument_kind(path, table, where)
    if kind in TRACKER_KINDS:
        return None
    allowed = _KEYS[kind] + (("offset_mm",) if truth and kind == "distance" else ())
    check_keys(path, table, allowed, f"{where}.", robot=False)
    if kind == "plane":
        entries = _labelled(
            path, table, where, "planes", "{ normal = [0, 0, 1], offset_mm = 150 }"
        )
        planes = {}
        for label, entry in entries.items():
            key = f"{where}.planes.{label}"
            _entry_keys(path, entry, key, ("normal", "offset_mm"))
            normal = np.array(numbers(path, entry["normal"], f"{key}.normal", 3))
            if not np.linalg.norm(normal) > 0:  # an underflow too: 1e-320 has no direction
                raise fail(
                    path, f"key '{key}.normal': a normal of zero length; give its direction"
                )
            planes[label] = Plane(normal, number(path, entry["offset_mm"], f"{key}.offset_mm"))
        return Planes(planes)
    if kind == "partial":
        return _partial(path, table, where)
    if kind == "camera":
        return _camera(path, table, where)
    if kind == "point":
        entries = _labelled(path, table, where, "points", "{ xyz_mm = [900, 0, 200] }")
        points = {}
        for label, entry in entries.items():
            key = f"{where}.points.{label}"
            _entry_keys(path, entry, key, ("xyz_mm",))
            points[label] = np.array(numbers(path, entry["xyz_mm"], f"{key}.xyz_mm", 3))
        known = _known_distances(path, table.get("known_distances_mm", []), where)
        try:
            return FixedPoints(points, known)
        except ValueError as exc:
            raise fail(path, f"key '{where}.known_distances_mm': {exc}") from None
    for key in ("pivot_mm", "range_mm"):
        if key not in table:
            raise fail(path, f"key '{where}': a distance needs {key} ({_DISTANCE_EXAMPLE})")
    pivot = np.array(numbers(path, table["pivot_mm"], f"{where}.pivot_mm", 3))
    low, high = numbers(path, table["range_mm"], f"{where}.range_mm", 2)
    if not 0.0 <= low < high:
        raise fail(
            path,
            f"key '{where}.range_mm': need 0 <= least < greatest, got [{low:g}, {high:g}] "
            "(the distances from the pivot the instrument reads, mm)",
        )
    offset = number(path, table.get("offset_mm", 0.0), f"{where}.offset_mm")
    return Distance(pivot, (low, high), offset)


_DISTANCE_EXAMPLE = "pivot_mm = [800, 0, 0], range_mm = [95, 155]"
_PARTIAL_EXAMPLE = 'reads = ["z"], xyz_mm = [900, 0, 0], rpy_deg = [0, 0, 0]'


_CAMERA_EXAMPLE = (
    'camera = "cam.yaml", mount = "eye-in-hand", camera_in_tool = { xyz_mm = [0, 60, 100], '
    "rpy_deg = [0, 0, 0] }, board = { rows = 6, cols = 8, square_mm = 30, xyz_mm = [900, 0, 0], "
    "rpy_deg = [0, 0, 0] }"
)


def _camera(path, table: dict, where: str) -> Camera:
    """``kind = "camera"``: its intrinsics, its mount, where it and the board roughly are."""
    mount = table.get("mount")
    if mount not in MOUNTS:
        raise fail(
            path,
            f"key '{where}.mount': expected {' or '.join(repr(m) for m in MOUNTS)} (the camera on "
            f"the tool, or fixed in the cell), got {shown(str(mount))}",
        )
    own = "camera_in_tool" if mount == "eye-in-hand" else "camera_in_base"
    other = "camera_in_base" if own == "camera_in_tool" else "camera_in_tool"
    if other in table:
        raise fail(path, f"key '{where}.{other}': a camera {mount} is placed by {own}; rename it")
    for key in ("camera", own, "board"):
        if key not in table:
            raise fail(path, f"key '{where}': a camera needs {key} ({_CAMERA_EXAMPLE})")
    source = table["camera"]
    if isinstance(source, str):
        intrinsics = read_camera_info(Path(path).parent / source)
    else:
        intrinsics = intrinsics_of(path, source)
    placed = _pose(path, table[own], f"{where}.{own}")
    board = table["board"]
    key = f"{where}.board"
    _entry_keys(path, board, key, ("rows", "cols", "square_mm", "xyz_mm", "rpy_deg"))
    counts = []
    for name in ("rows", "cols"):
        value = board[name]
        if isinstance(value, bool) or not isinstance(value, int) or value < 2:
            raise fail(path, f"key '{key}.{name}': expected a whole number of corners, 2 or more")
        counts.append(value)
    square = number(path, board["square_mm"], f"{key}.square_mm")
    if not square > 0:
        raise fail(path, f"key '{key}.square_mm': expected the squares' side in mm, above 0")
    where_board = _pose(path, {k: board[k] for k in ("xyz_mm", "rpy_deg")}, key)
    view = _camera_view(path, table, where, intrinsics)
    return Camera(
        intrinsics, Board(counts[0], counts[1], square), mount, placed, where_board, **view
    )


#: A camera's optional view keys (the last of its keys in _KEYS): where a plan's photo
#: keeps its corners (the image less a margin, a nearest depth, a largest tilt).
VIEW_KEYS = _KEYS["camera"][-3:]


def _camera_view(path, table: dict, where: str, intrinsics: Any) -> dict[str, float]:
    """The view keys given, each checked: a margin of at least 0 px that leaves some of
    the image, a nearest depth above 0 mm, a largest tilt above 0 and below 90 deg."""
    found: dict[str, float] = {}
    half = min(intrinsics.width, intrinsics.height) / 2
    rules = {
        "margin_px": (lambda v: 0 <= v < half, f"at least 0 and below {half:g} (half the image)"),
        "min_depth_mm": (lambda v: v > 0, "above 0 (the lens's nearest focus)"),
        "max_tilt_deg": (lambda v: 0 < v < 90, "above 0 and below 90 degrees"),
    }
    for name, (holds, what) in rules.items():
        if name in table:
            value = number(path, table[name], f"{where}.{name}")
            if not holds(value):
                raise fail(path, f"key '{where}.{name}': expected {what}, got {value:g}")
            found[name] = value
    return found


def _pose(path, entry: Any, key: str) -> tuple[np.ndarray, np.ndarray]:
    """``{ xyz_mm = [..], rpy_deg = [..] }``."""
    _entry_keys(path, entry, key, ("xyz_mm", "rpy_deg"))
    return (
        np.array(numbers(path, entry["xyz_mm"], f"{key}.xyz_mm", 3)),
        np.array(numbers(path, entry["rpy_deg"], f"{key}.rpy_deg", 3)),
    )


def _partial(path, table: dict, where: str) -> Coordinates:
    """``kind = "partial"``: what it reads, where its frame roughly is, and for one that
    reads turns where the tool's axes are and the turns a plan keeps to."""
    for key in ("reads", "xyz_mm", "rpy_deg"):
        if key not in table:
            raise fail(path, f"key '{where}': partial coordinates need {key} ({_PARTIAL_EXAMPLE})")
    reads = table["reads"]
    if (
        not isinstance(reads, list)
        or not reads
        or not all(isinstance(a, str) and a in COMPONENTS for a in reads)
        or len(set(reads)) != len(reads)
    ):
        raise fail(
            path,
            f"key '{where}.reads': expected a list of what the instrument reads, some of "
            f'"x", "y", "z" and of the tool\'s turn "rx", "ry", "rz" (each once), as reads = '
            f'["z"] or ["x", "y", "rz"]; got {shown(str(reads))}',
        )
    if not set(reads) & set(AXES):
        raise fail(
            path,
            f"key '{where}.reads': turns alone ({', '.join(reads)}) see no length of the arm "
            'and no position of the tool; read a coordinate too (add "x", "y" or "z")',
        )
    turned = bool(set(reads) & set(TURNS))
    extra: dict[str, Any] = {}
    for key in ("tool_rpy_deg", "max_turn_deg"):
        if key in table and not turned:
            raise fail(path, f"key '{where}.{key}': the instrument reads no turn; remove the key")
    if "tool_rpy_deg" in table:
        extra["tool_rpy_deg"] = np.array(
            numbers(path, table["tool_rpy_deg"], f"{where}.tool_rpy_deg", 3)
        )
    if "max_turn_deg" in table:
        largest = number(path, table["max_turn_deg"], f"{where}.max_turn_deg")
        if not 0.0 < largest < 180.0:
            raise fail(
                path,
                f"key '{where}.max_turn_deg': expected the largest turn of the tool from the "
                f"instrument's axes, above 0 and below 180 degrees; got {largest:g}",
            )
        extra["max_turn_deg"] = largest
    xyz = numbers(path, table["xyz_mm"], f"{where}.xyz_mm", 3)
    rpy = numbers(path, table["rpy_deg"], f"{where}.rpy_deg", 3)
    return Coordinates(tuple(reads), np.array(xyz), np.array(rpy), **extra)


def _known_distances(path, value: Any, where: str) -> tuple[tuple[str, str, float], ...]:
    """``known_distances_mm = [["A", "B", 200.0], ...]``: bars between labelled points."""
    key = f"{where}.known_distances_mm"
    if not isinstance(value, list):
        raise fail(path, f'key \'{key}\': expected a list of [A, B, mm], as [["A", "B", 200.0]]')
    found = []
    for i, entry in enumerate(value):
        if (
            not isinstance(entry, list)
            or len(entry) != 3
            or not all(isinstance(label, str) for label in entry[:2])
        ):
            raise fail(path, f"key '{key}[{i}]': expected [A, B, mm]: two point labels and mm")
        found.append((entry[0], entry[1], number(path, entry[2], f"{key}[{i}][2]")))
    return tuple(found)


def _labelled(path, table: dict, where: str, key: str, example: str) -> dict[str, Any]:
    """A kind's table of features by label, at least one."""
    entries = table.get(key)
    if not isinstance(entries, dict) or not entries:
        raise fail(
            path,
            f"key '{where}.{key}': expected a table of features by label, as "
            f"{key} = {{ A = {example} }}",
        )
    for label in entries:
        if not label.strip() or label != label.strip():
            raise fail(path, f"key '{where}.{key}': a label {label!r} is empty or padded")
    return dict(entries)


def _entry_keys(path, entry: Any, key: str, needed: tuple[str, ...]) -> None:
    if not isinstance(entry, dict):
        raise fail(path, f"key '{key}': expected an inline table {{ {needed[0]} = ... }}")
    check_keys(path, entry, needed, f"{key}.", robot=False)
    for name in needed:
        if name not in entry:
            raise fail(path, f"key '{key}': missing {name}")


def true_instrument(path: str | os.PathLike, table: Any, instrument: Instrument) -> np.ndarray:
    """The parameters ``(t,)`` of ``instrument`` (the robot file's) where a truth file's
    ``[instrument]`` table says the virtual lab's really is; where it says nothing, the
    robot file's (its start: the user's guess is right)."""
    if table is None:
        return np.asarray(instrument.start, dtype=float)
    if isinstance(table, dict):  # what it leaves out is the robot file's (a range, a bar)
        section = instrument_section(instrument)
        table = {
            key: {**section[key], **value}
            if isinstance(value, dict) and isinstance(section.get(key), dict)
            else value
            for key, value in {**section, **table}.items()
        }
    true = read_instrument(path, table, truth=True)
    if true is None or true.kind != instrument.kind or true.labels != instrument.labels:
        found = "a tracker" if true is None else f"a {true.kind} ({', '.join(true.labels)})"
        raise fail(
            path,
            f"key 'instrument': the true instrument is {found}, but the robot file's is a "
            f"{instrument.kind} ({', '.join(instrument.labels)}); describe the same features",
        )
    try:
        return np.asarray(instrument.params_of(true), dtype=float)
    except ValueError as exc:
        raise InputError(f"{os.fspath(path)}: key 'instrument': {exc}") from None


def instrumented_arm(
    path: str | os.PathLike,
    arm: Any,
    instrument: Instrument,
    elastic: bool,
    targets: bool,
    noise_keys: tuple[str, ...] = (),
) -> InstrumentedArm:
    """``arm`` (a spatial robot file's) measured by ``instrument`` (its ``[instrument]``),
    checked: no ``[elastostatic]``, no orientation, one tool point in ``[targets]`` (none
    for a camera, placed on the flange), labels that give no parameter the arm has, noise
    the instrument can read (a camera's in pixels, ``sigma_px``, the others' in mm), and
    an instrument some pose can meet.  ``elastic``: the file has ``[elastostatic]``;
    ``targets``: it has ``[targets]``; ``noise_keys``: the keys of its ``[measurement]``."""
    _check_noise_keys(path, instrument, noise_keys)
    if not instrument.tool_point:  # placed on the flange: the tool point is its origin
        if targets:
            raise fail(
                path,
                f"key 'targets': a {instrument.kind} on the tool is placed on the flange "
                "(camera_in_tool, board in the tool's frame); remove [targets]",
            )
        arm = arm.replace(target_positions=np.zeros((1, 3)), known_targets=True)
        held = tuple(n for n in arm.param_names if n.startswith(f"{arm.targets[0]}."))
        arm = arm.with_fixed((*arm.fixed, *held))
        targets = True
    if elastic:
        raise fail(
            path,
            f"key 'instrument.kind': a {instrument.kind} instrument with [elastostatic] is not "
            "supported yet; remove one of them (measure the arm's sag with a tracker)",
        )
    if instrument.turn_features:  # the turns are the instrument's readings, not the arm's
        arm = arm.replace(oriented=False)
    elif arm.oriented:
        what = (
            'the instrument reads no turn; add "rx", "ry" or "rz" to [instrument] reads, or '
            "remove the key"
            if instrument.reads_every_feature
            else f"a {instrument.kind} instrument reads no orientation; remove the key"
        )
        raise fail(path, f"key 'measurement.orientation_sigma_deg': {what}")
    if len(arm.targets) > 1:
        raise fail(
            path,
            f"key 'targets': a {instrument.kind} instrument measures one tool point; "
            f"give one in [targets], not {len(arm.targets)} ({', '.join(arm.targets)})",
        )
    if not targets:
        raise fail(
            path,
            f"key 'instrument.kind': a {instrument.kind} instrument measures the tool "
            "point: give it in [targets] (tool = { xyz_mm = [x, y, z] }, tip frame), where it "
            "roughly is",
        )
    clash = sorted(set(instrument.param_names) & set(arm.param_names))
    if clash:
        raise fail(
            path,
            f"key 'instrument': the labels of its {instrument.kind}s give parameters the arm "
            f"has already ({', '.join(clash)}); rename them (A, B, top, side, ...)",
        )
    _check_noise(path, arm.noise, instrument)
    far = instrument.out_of_reach(arm.tip_reach_mm)
    if far is not None:
        raise fail(path, f"key 'instrument': no pose can meet it: {far}; check [instrument]")
    return InstrumentedArm.of(arm, instrument)


def _check_noise_keys(path, instrument: Instrument, noise_keys: tuple[str, ...]) -> None:
    """A camera's noise in pixels (``sigma_px``), the others' in mm."""
    pixels = instrument.unit == "px"
    wrong = [k for k in noise_keys if k in ("sigma_mm", "covariance_mm2", "tracker")]
    if pixels and wrong:
        raise fail(
            path,
            f"key 'measurement.{wrong[0]}': a camera's noise is in pixels; give sigma_px "
            "(about 0.1 to 0.5 for a board's corners)",
        )
    if not pixels and "sigma_px" in noise_keys:
        raise fail(path, "key 'measurement.sigma_px': pixels are a camera's; give sigma_mm")


def _check_noise(path, noise: Any, instrument: Instrument) -> None:
    """Noise the instrument can read: a sigma for each of its features (a turn's too, which
    has no default: a turn and a coordinate share no unit)."""
    if noise is None:
        if instrument.turn_features:
            raise fail(
                path,
                "key 'measurement': partial coordinates that read the tool's turn weigh "
                "coordinates and turns by their noise; give sigma_mm and orientation_sigma_deg",
            )
        return
    try:
        per_feature = instrument.feature_sigma(noise)
    except ValueError as exc:
        raise fail(path, f"key 'measurement': {exc}") from None
    try:
        if per_feature is None:
            noise.for_dim(instrument.dim)
    except ValueError as exc:
        raise fail(
            path,
            f"key 'measurement': a {instrument.kind} instrument reads {instrument.dim} "
            f"number{'s' if instrument.dim > 1 else ''} a row: {exc}",
        ) from None


def instrument_section(instrument: Instrument) -> dict[str, Any]:
    """The ``[instrument]`` table of ``instrument`` where the user said it is (its start),
    as :func:`read_instrument` reads it back (a calibration file's ``instrument``)."""
    if isinstance(instrument, Planes):
        planes = {
            label: {"normal": plane.normal.tolist(), "offset_mm": plane.offset_mm}
            for label, plane in instrument.planes.items()
        }
        return {"kind": "plane", "planes": planes}
    if isinstance(instrument, FixedPoints):
        points = {label: {"xyz_mm": xyz.tolist()} for label, xyz in instrument.points.items()}
        known = [[a, b, d] for a, b, d in instrument.known]
        return {
            "kind": "point",
            "points": points,
            **({"known_distances_mm": known} if known else {}),
        }
    if isinstance(instrument, Camera):
        own = "camera_in_tool" if instrument.mount == "eye-in-hand" else "camera_in_base"
        xyz, rpy = instrument.camera_pose
        board = instrument.board
        return {
            "kind": "camera",
            "camera": camera_info_table(instrument.intrinsics),
            "mount": instrument.mount,
            own: {"xyz_mm": xyz.tolist(), "rpy_deg": rpy.tolist()},
            "board": {
                "rows": board.rows,
                "cols": board.cols,
                "square_mm": board.square_mm,
                "xyz_mm": instrument.board_pose[0].tolist(),
                "rpy_deg": instrument.board_pose[1].tolist(),
            },
            **{name: float(getattr(instrument, name)) for name in VIEW_KEYS},
        }
    if isinstance(instrument, Coordinates):
        turned = (
            {
                "tool_rpy_deg": instrument.tool_rpy_deg.tolist(),
                "max_turn_deg": float(instrument.max_turn_deg),
            }
            if instrument.turns
            else {}
        )
        return {
            "kind": "partial",
            "reads": list(instrument.reads),
            "xyz_mm": instrument.xyz_mm.tolist(),
            "rpy_deg": instrument.rpy_deg.tolist(),
            **turned,
        }
    if isinstance(instrument, Distance):
        return {
            "kind": "distance",
            "pivot_mm": instrument.pivot_mm.tolist(),
            "range_mm": list(instrument.range_mm),
        }
    raise TypeError(f"no [instrument] table for {type(instrument).__name__}")


def instrumented_truth(
    robot: RobotSpec,
    model: Any,
    path: str | os.PathLike | None,
    *,
    links: tuple[str | None, str | None] = (None, None),
    geometry_only: bool = False,
) -> np.ndarray:
    """The virtual lab's parameters of ``model`` (an arm measured by an instrument): the
    arm's from the truth file as its own family reads it, its base at the origin of its
    frame (where the instrument is placed), then the instrument's where the file's
    ``[instrument]`` says it really is (:func:`true_instrument`)."""
    inner = model.inner
    found = path if path is not None else robot.default_truth
    arm = family_of(inner).role("truth")(
        replace(robot, arm=robot.arm.inner), inner, found, links=links, geometry_only=geometry_only
    )
    data = {} if found is None else load_toml(found, "truth")
    if "base" in data:
        raise fail(
            found,
            f"key 'base': the arm is measured by a {model.instrument.kind} instrument, placed "
            "in the robot's own base frame; remove base (say where the instrument really is "
            "in [instrument])",
        )
    theta = true_instrument(found or "truth", data.get("instrument"), model.instrument)
    return np.concatenate([np.asarray(arm, dtype=float), theta])
