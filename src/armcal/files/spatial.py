"""Spatial robot files: a URDF, a robot TOML that points to one or gives a modified DH
table, the built-in spatial robots, and the truth of a virtual spatial arm.

A robot TOML of a spatial arm has ``urdf`` (a path relative to the file, with
optional ``base_link`` and ``tip_link``), an ``[mdh]`` table (``alpha_deg``,
``a_mm``, ``theta_deg``, ``d_mm``, optional ``joint_types``: Craig's modified DH)
or a ``[dh]`` table (the same keys: standard DH), and optionally
``name``, ``joint_map`` (URDF joint values ``u = M q`` from the controller's
readings ``q``), ``joint_limits_deg`` (on ``q``; they replace the URDF's, which
hold for ``u``), ``[measurement]`` (``sigma_mm``: one number or ``[sx, sy,
sz]``), ``[targets]`` (``LABEL = { xyz_mm = [x, y, z] }`` in the tip frame)
and ``[identify]`` (``fixed`` or ``free``).

A truth TOML (``--truth``) of a virtual spatial arm gives the instrument's pose
``base = { xyz_mm = [...], rpy_deg = [...] }``, ``[targets]`` as above, and the
true arm: ``robot = "true.urdf"`` (another description of it, joint for joint),
``[errors]`` (armcal's parameters in mm and deg: ``j2.x = 0.4``, ``dq3 = 0.05``),
or both (the errors on top of that description).
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np

from ..choices import BUILTIN_SPATIAL_ROBOTS, ROBOT_FOLDER
from ..errors import ArmcalError, ArmcalWarning, InputError, unrendered
from ..families.registry import RobotSpec
from ..formats import SPATIAL_KEYS, SPATIAL_TRUTH_KEYS, TRUTH_KEYS, allowed_keys
from ..models import (
    FitModel,
    LinkMasses,
    SerialChain,
    SpatialArm,
    SpatialElastics,
    SpatialView,
    rpy_matrix,
    transform,
)
from ..models.spatial.dh import convention_mistake, table_chain
from .common import (
    check_keys,
    check_truth_keys,
    fail,
    load_toml,
    number,
    number_within,
    numbers,
    suggest,
)
from .instrument_table import instrumented_arm, read_instrument
from .robot_units import check_mdh_angles, check_reach, limit_warnings, urdf_limit_warning
from .robots import (
    SPATIAL_ROBOT_KEYS,
    fixed_parameters,
    held_terms,
    read_joint_map,
    refuse_unknown_robot,
    rigid_truth_message,
)
from .spatial_noise import read_spatial_noise
from .ur import (
    UR_MODELS,
    read_ur_calibration,
    read_ur_kinematics,
    ur_calibration_warning,
    ur_chain,
    ur_nominal,
)
from .urdf import read_urdf

__all__ = [
    "BUILTIN_SPATIAL_ROBOTS",
    "ROBOT_FOLDER",
    "is_spatial_robot",
    "load_spatial_robot",
    "load_spatial_truth",
    "spatial_truth",
]

# The keys each table takes: the catalogue's (armcal formats prints it), so a key cannot be
# accepted without being documented.
_MDH_REQUIRED = ("alpha_deg", "a_mm", "theta_deg", "d_mm")


def is_spatial_robot(name_or_path: str | os.PathLike) -> bool:
    """Whether ``name_or_path`` names a spatial robot: a built-in one, a URDF, or a robot
    TOML with ``urdf``, ``[mdh]``, ``[dh]`` or ``[ur]``."""
    key = os.fspath(name_or_path)
    if key in BUILTIN_SPATIAL_ROBOTS or key.lower().endswith(_URDF_SUFFIXES):
        return True
    path = Path(key)
    if path.suffix.lower() != ".toml" or not path.is_file():
        return False
    try:
        data = load_toml(path, "robot")
    except InputError:  # the robot loader reports it
        return False
    return any(key in data for key in SPATIAL_ROBOT_KEYS)


#: A URDF's suffixes (a xacro file, ROS's macros for URDF, is read to say what it is).
_URDF_SUFFIXES = (".urdf", ".xacro")


def load_spatial_robot(
    name_or_path: str | os.PathLike,
    *,
    base_link: str | None = None,
    tip_link: str | None = None,
) -> RobotSpec[SpatialArm]:
    """A spatial robot from a built-in name, a URDF or a robot TOML (module notes).

    ``base_link`` and ``tip_link`` choose a URDF's chain (over a robot TOML's keys of
    the same names); a robot described otherwise refuses them.

    Raises
    ------
    InputError
        Naming the file and the key (or the URDF's line).
    """
    key = os.fspath(name_or_path)
    links = (base_link, tip_link)
    if key in BUILTIN_SPATIAL_ROBOTS:
        path = BUILTIN_SPATIAL_ROBOTS[key]
        truth = path.with_name(path.stem + "-truth.toml")
        spec = _from_toml(path, key, links)
        return replace(spec, default_truth=truth if truth.is_file() else None)
    path = Path(key)
    if path.suffix.lower() in _URDF_SUFFIXES:  # a missing one: the URDF reader says so
        found = read_urdf(path, base_link, tip_link)
        warnings = (*found.warnings, *_urdf_units(path, found.chain))
        return RobotSpec(SpatialArm(found.chain, found.robot), key, warnings=warnings)
    refuse_unknown_robot(key)
    return _from_toml(path, None, links)


def _urdf_units(path: Path, chain: SerialChain) -> tuple[ArmcalWarning, ...]:
    """A URDF's unit mistakes (:mod:`~armcal.files.robot_units`): an error for one in mm,
    warnings for lengths that look like another unit and limits that look like degrees."""
    found = [check_reach(path, chain, urdf=True), urdf_limit_warning(path, chain)]
    return tuple(w for w in found if w is not None)


def _relative_file(path: Path, value: Any, key: str, what: str) -> Path:
    """The existing file that ``key`` of the TOML ``path`` names, relative to ``path``."""
    if not isinstance(value, str):
        raise fail(path, f"key '{key}': expected a file name, got {value!r}")
    found = path.parent / value
    if not found.is_file():
        raise fail(
            path, f"key '{key}': {found} does not exist; give its path relative to the {what}"
        )
    return found


def _ur_chain(path: Path, table: Any) -> tuple[SerialChain, str, tuple[ArmcalWarning, ...]]:
    """``[ur]``: a UR model's nominal DH table plus its controller's calibration deltas
    (:mod:`~armcal.files.ur`), within the controller's +-360 degrees."""
    if not isinstance(table, dict):
        raise fail(path, "key 'ur': expected a table [ur] with 'model' (and 'calibration')")
    check_keys(path, table, allowed_keys("ur", SPATIAL_KEYS), "ur.")
    model = table.get("model")
    if model not in UR_MODELS:
        raise fail(path, f"key 'ur.model': expected one of {', '.join(UR_MODELS)}, got {model!r}")
    dh = ur_nominal(model)
    warnings: tuple[ArmcalWarning, ...] = ()
    if "calibration" in table:
        conf = _relative_file(path, table["calibration"], "ur.calibration", "robot file")
        if conf.suffix.lower() in (".yaml", ".yml"):  # the ROS driver's: the whole chain
            chain = read_ur_kinematics(conf)
        else:  # the controller's calibration.conf: deltas to the nominal table
            chain = ur_chain(dh + read_ur_calibration(conf))
        far = ur_calibration_warning(conf, model, chain)
        warnings = () if far is None else (far,)
    else:
        chain = ur_chain(dh)
    chain = replace(chain, joint_limits=np.tile([-2 * np.pi, 2 * np.pi], (6, 1)))
    return chain, model, warnings


def _chain(
    path: Path, data: dict, chosen: tuple[str | None, str | None]
) -> tuple[SerialChain, str, tuple[ArmcalWarning, ...], LinkMasses | None]:
    """The chain of a robot TOML: its URDF's (from the ``chosen`` base and tip links, else
    the file's), its ``[mdh]`` or ``[dh]`` table's or a UR's (``[ur]``), a default name,
    what reading it warns of, and its URDF's masses."""
    given = [key for key in SPATIAL_ROBOT_KEYS if key in data]
    if len(given) > 1:
        raise fail(path, f"keys {' and '.join(given)} all describe the arm; keep one")
    if given and given[0] != "urdf" and any(link is not None for link in chosen):
        raise fail(
            path,
            f"a base or tip link was given, but the file describes the arm by [{given[0]}], "
            "not by a URDF: links choose a URDF's chain; drop them",
        )
    if "ur" in data:
        return (*_ur_chain(path, data["ur"]), None)
    if "urdf" in data:
        return _urdf_chain(path, data, chosen)
    if not given:
        raise fail(
            path,
            "needs 'urdf' (a URDF file), an [mdh] or [dh] table or a [ur] model to describe "
            "the arm",
        )
    chain, warned = _table_chain(path, given[0], data[given[0]])
    return chain, path.stem, warned, None


def _urdf_chain(
    path: Path, data: dict, chosen: tuple[str | None, str | None]
) -> tuple[SerialChain, str, tuple[ArmcalWarning, ...], LinkMasses | None]:
    """The chain of the URDF a robot TOML names (``urdf``), between the ``chosen`` base and
    tip links, else the file's ``base_link`` and ``tip_link``: with the robot's name, what
    reading it warns of and its masses."""
    urdf = _relative_file(path, data["urdf"], "urdf", "robot file")
    links = {}
    for name in ("base_link", "tip_link"):
        if name in data and not isinstance(data[name], str):
            raise fail(path, f"key '{name}': expected a link name, got {data[name]!r}")
        links[name] = data.get(name)
    base_link, tip_link = chosen
    found = read_urdf(urdf, base_link or links["base_link"], tip_link or links["tip_link"])
    warned_urdf = (*found.warnings, *_urdf_units(urdf, found.chain))
    return found.chain, found.robot, warned_urdf, found.masses


def _table_chain(
    path: Path, key: str, table: Any
) -> tuple[SerialChain, tuple[ArmcalWarning, ...]]:
    """The chain of an ``[mdh]`` or ``[dh]`` table (``key``), checked for angles in radians,
    a table of the other convention and lengths in metres, and its own joint limits."""
    if not isinstance(table, dict):
        raise fail(path, f"key '{key}': expected a table [{key}]")
    check_keys(path, table, allowed_keys(key, SPATIAL_KEYS), f"{key}.")
    values = _table_columns(path, key, table)
    n = len(values["alpha_deg"])
    kinds = table.get("joint_types", ["R"] * n)
    if not isinstance(kinds, list) or len(kinds) != n or any(k not in ("R", "P") for k in kinds):
        raise fail(path, f'key \'{key}.joint_types\': expected {n} of "R" or "P", got {kinds!r}')
    frames = {}
    angles = {name: values[name] for name in ("alpha_deg", "theta_deg")}
    for where in ("base", "tip"):
        xyz = numbers(path, table.get(f"{where}_xyz_mm", [0, 0, 0]), f"{key}.{where}_xyz_mm", 3)
        rpy = numbers(path, table.get(f"{where}_rpy_deg", [0, 0, 0]), f"{key}.{where}_rpy_deg", 3)
        angles[f"{where}_rpy_deg"] = rpy
        frames[where] = transform(rpy_matrix(np.radians(rpy)), xyz)
    check_mdh_angles(path, angles, key)
    rows = (
        np.radians(values["alpha_deg"]),
        np.array(values["a_mm"]),
        np.radians(values["theta_deg"]),
        np.array(values["d_mm"]),
        tuple(kinds),
        frames["base"],
        frames["tip"],
    )
    beta = np.radians(values["beta_deg"])
    mistake = convention_mistake(key, *rows, beta=beta)
    if mistake is not None:
        raise fail(path, f"[{key}]: {mistake}")
    chain = table_chain(key, *rows, beta=beta)
    metres = check_reach(path, chain, urdf=False, table=key)
    warned: tuple[ArmcalWarning, ...] = () if metres is None else (metres,)
    if "joint_limits_deg" in table:  # limits on the table's joint values, as a URDF's
        limits = table["joint_limits_deg"]
        own, more = _limits(path, limits, chain.kinds, f"{key}.joint_limits_deg")
        chain = replace(chain, joint_limits=own)
        warned += more
    return chain, warned


def _table_columns(path: Path, key: str, table: dict) -> dict[str, list[float]]:
    """The columns of an ``[mdh]`` or ``[dh]`` table by key: ``alpha_deg``, ``a_mm``,
    ``theta_deg``, ``d_mm`` (required) and ``beta_deg`` (zeros by default), one value per
    joint each."""
    values = {}
    for name in _MDH_REQUIRED:
        if name not in table:
            raise fail(path, f"missing key '{key}.{name}': one value per joint")
        values[name] = numbers(path, table[name], f"{key}.{name}")
    n = len(values["alpha_deg"])
    values["beta_deg"] = numbers(path, table.get("beta_deg", [0.0] * n), f"{key}.beta_deg")
    for name, column in values.items():
        if len(column) != n or n == 0:
            raise fail(
                path,
                f"key '{key}.{name}': expected {n} values (one per joint, as alpha_deg), "
                f"got {len(column)}",
            )
    return values


def _from_toml(
    path: Path, builtin: str | None, links: tuple[str | None, str | None] = (None, None)
) -> RobotSpec[SpatialArm]:
    data = load_toml(path, "robot")
    check_keys(path, data, allowed_keys("", SPATIAL_KEYS))
    chain, default_name, read_warnings, masses = _chain(path, data, links)
    n = chain.n_joints
    name = data.get("name", default_name)
    if not isinstance(name, str) or not name.strip():
        raise fail(path, f"key 'name': expected a non-empty string, got {name!r}")
    mapping = np.eye(n)
    if "joint_map" in data:
        mapping = read_joint_map(path, data["joint_map"], chain.kinds)
    limits = np.zeros((0, 2))
    if "joint_limits_deg" in data:
        limits, warned = _limits(path, data["joint_limits_deg"], chain.kinds, "joint_limits_deg")
        read_warnings += warned
        if "mdh" not in data:
            # They replace the URDF's (or UR's) limits, which hold for the joint values M q;
            # an [mdh] table's own limits (mdh.joint_limits_deg) are the user's, and kept.
            chain = replace(chain, joint_limits=np.tile([-np.inf, np.inf], (n, 1)))
    noise = read_spatial_noise(path, data.get("measurement"))
    labels, positions, normals = _target_table(path, data.get("targets"))
    instrument = read_instrument(path, data.get("instrument"))
    view = None if instrument is not None else _view(path, data.get("instrument"), labels, normals)
    arm = SpatialArm(
        chain,
        name,
        mapping,
        limits,
        targets=labels or ("tool",),
        target_positions=positions,
        noise=noise,
        known_targets=bool(labels),
        oriented=noise is not None and noise.orientation_sigma is not None,
        view=view,
    )
    elastic = None
    if "elastostatic" in data:
        elastic = _elastostatic(path, data["elastostatic"], chain, masses)
    model: Any = arm
    if instrument is not None:
        measured = data.get("measurement")
        keys = tuple(measured) if isinstance(measured, dict) else ()
        model = instrumented_arm(path, arm, instrument, elastic is not None, bool(labels), keys)
    if "identify" in data:
        table = data["identify"]
        terms = () if elastic is None else elastic.term_names(arm)
        model = model.with_fixed(
            fixed_parameters(path, table, model.param_names, model.name, terms)
        )
        if elastic is not None:
            elastic = replace(elastic, terms=held_terms(table, terms))
    return RobotSpec(model, builtin or os.fspath(path), warnings=read_warnings, elastic=elastic)


def _limits(
    path: Path, raw: Any, kinds: Sequence[str], key: str
) -> tuple[np.ndarray, tuple[ArmcalWarning, ...]]:
    """Limits ``(n, 2)`` (rad; mm for a prismatic joint) of the key ``key``: a pair
    ``[lo, hi]`` per joint in deg (mm), and the unit warnings of
    :func:`~armcal.files.robot_units.limit_warnings`."""
    n = len(kinds)
    if not isinstance(raw, list) or len(raw) != n:
        raise fail(path, f"key '{key}': expected {n} pairs [lo, hi], one per joint")
    pairs = np.array([numbers(path, p, f"{key}[{j}]", 2) for j, p in enumerate(raw)])
    for j, (lo, hi) in enumerate(pairs):
        if not lo < hi:
            raise fail(path, f"key '{key}[{j}]': need lo < hi, got [{lo:g}, {hi:g}]")
    revolute = np.array([kind == "R" for kind in kinds])
    limits = np.where(revolute[:, None], np.radians(pairs), pairs)
    return limits, tuple(limit_warnings(path, pairs, kinds, key))


def _elastostatic(
    path: Path, table: Any, chain: SerialChain, masses: LinkMasses | None
) -> SpatialElastics:
    """``[elastostatic]`` of a spatial arm: gravity in the base frame, the links' masses
    (the table's, else the URDF's ``<inertial>``, else the lumped mode) and the payload."""
    if not isinstance(table, dict):
        raise fail(path, "key 'elastostatic': expected a table [elastostatic]")
    check_keys(path, table, allowed_keys("elastostatic", SPATIAL_KEYS), "elastostatic.")
    n = chain.n_joints
    key = "elastostatic.gravity"
    gravity = numbers(path, table.get("gravity", [0, 0, -1]), key, 3)
    lumped = table.get("lumped", False)
    if not isinstance(lumped, bool):
        raise fail(path, f"key 'elastostatic.lumped': expected true or false, got {lumped!r}")
    mass: Any = None
    com: Any = None
    if "link_masses_kg" in table:
        mass = numbers(path, table["link_masses_kg"], "elastostatic.link_masses_kg", n)
        raw = table.get("link_com_mm", [[0.0, 0.0, 0.0]] * n)
        if not isinstance(raw, list) or len(raw) != n:
            raise fail(path, f"key 'elastostatic.link_com_mm': expected {n} points [x, y, z]")
        com = [numbers(path, p, f"elastostatic.link_com_mm[{j}]", 3) for j, p in enumerate(raw)]
    elif "link_com_mm" in table:
        raise fail(path, "key 'elastostatic.link_com_mm': give link_masses_kg with it")
    elif masses is not None:
        mass, com = masses.mass_kg, masses.com_mm
    if lumped and "link_masses_kg" in table:
        raise fail(
            path,
            "[elastostatic]: lumped = true and link_masses_kg: the lumped mode is for "
            "masses unknown; remove one of them",
        )
    if table.get("lumped") is False and mass is None:
        raise fail(
            path,
            "[elastostatic]: lumped = false but no masses: give link_masses_kg (and "
            "link_com_mm), or <inertial> tags in the URDF",
        )
    payload = number(path, table.get("payload_kg", 0.0), "elastostatic.payload_kg")
    payload_at = numbers(
        path, table.get("payload_com_mm", [0, 0, 0]), "elastostatic.payload_com_mm", 3
    )
    try:
        return SpatialElastics.create(
            n,
            gravity=gravity,
            mass_kg=None if lumped else mass,
            com_mm=None if lumped else com,
            payload_kg=payload,
            payload_com_mm=payload_at,
        )
    except ArmcalError as exc:
        raise fail(path, f"[elastostatic]: {unrendered(exc)}") from None


def _targets(path: Path, table: Any) -> tuple[tuple[str, ...], np.ndarray]:
    labels, positions, _ = _target_table(path, table)
    return labels, positions


def _target_table(
    path: Path, table: Any
) -> tuple[tuple[str, ...], np.ndarray, list[np.ndarray | None]]:
    """``[targets]``: labels, positions ``(k, 3)`` and every target's unit normal (or None)."""
    if table is None:
        return (), np.zeros((0, 3)), []
    if not isinstance(table, dict) or not table:
        raise fail(
            path, "key 'targets': expected a table [targets] of LABEL = { xyz_mm = [x, y, z] }"
        )
    labels, positions, normals = [], [], []
    for label, entry in table.items():
        if (
            not isinstance(entry, dict)
            or "xyz_mm" not in entry
            or set(entry) - {"xyz_mm", "normal"}
        ):
            raise fail(
                path,
                f"key 'targets.{label}': expected {{ xyz_mm = [x, y, z] }} (mm, tip frame), "
                "and optionally normal = [x, y, z]",
            )
        labels.append(label)
        positions.append(numbers(path, entry["xyz_mm"], f"targets.{label}.xyz_mm", 3))
        normal = None
        if "normal" in entry:
            normal = np.array(numbers(path, entry["normal"], f"targets.{label}.normal", 3))
            length = float(np.linalg.norm(normal))
            if length == 0.0:
                raise fail(path, f"key 'targets.{label}.normal': give a direction, not 0")
            normal = normal / length
        normals.append(normal)
    return tuple(labels), np.array(positions), normals


#: ``[instrument]`` keys of the contact instruments (:mod:`armcal.files.instrument_table`).
_CONTACT_KEYS = ("planes", "points", "pivot_mm", "known_distances_mm")


def _view(path: Path, table: Any, labels: tuple[str, ...], normals: list) -> SpatialView | None:
    """``[instrument]``: where the instrument stands and what it reaches, for plans."""
    if table is None:
        return None
    if not isinstance(table, dict):
        raise fail(path, "key 'instrument': expected a table [instrument]")
    allowed = [k for k in allowed_keys("instrument", SPATIAL_KEYS) if k not in _CONTACT_KEYS]
    check_keys(path, table, allowed, "instrument.")
    if not set(table) - {"kind"}:  # a tracker (or a probe) said, nothing of where it stands
        return None
    needs_position = [key for key in ("range_mm", "acceptance_deg") if key in table]
    if needs_position and "position_mm" not in table:
        raise fail(
            path,
            f"key 'instrument.{needs_position[0]}': give instrument.position_mm too (mm, the "
            "robot's base frame), where it is seen from",
        )
    position = np.array(
        numbers(path, table.get("position_mm", [0, 0, 0]), "instrument.position_mm", 3)
    )
    reach = None
    if "range_mm" in table:
        low, high = numbers(path, table["range_mm"], "instrument.range_mm", 2)
        if not 0 <= low < high:
            raise fail(
                path,
                f"key 'instrument.range_mm': need 0 <= least < greatest, got [{low:g}, {high:g}]",
            )
        reach = (low, high)
    box = None
    if "box_mm" in table:
        raw = table["box_mm"]
        if not isinstance(raw, list) or len(raw) != 3:
            raise fail(
                path,
                "key 'instrument.box_mm': expected [[x lo, x hi], [y lo, y hi], [z lo, z hi]]",
            )
        box = np.array([numbers(path, r, f"instrument.box_mm[{i}]", 2) for i, r in enumerate(raw)])
        if not np.all(box[:, 0] < box[:, 1]):
            raise fail(path, "key 'instrument.box_mm': need lo < hi on every axis")
    acceptance = None
    if "acceptance_deg" in table:
        acceptance = number_within(
            path, table["acceptance_deg"], "instrument.acceptance_deg", (1.0, 90.0), "deg"
        )
        missing = [label for label, n in zip(labels, normals, strict=True) if n is None]
        if not labels or missing:
            raise fail(
                path,
                "key 'instrument.acceptance_deg': every target needs its normal "
                f"({', '.join(missing) or 'no [targets] given'}); add normal = [x, y, z] "
                "(tip frame) to each in [targets]",
            )
        acceptance = np.radians(acceptance)
    floor = None
    if "floor_z_mm" in table:
        floor = number(path, table["floor_z_mm"], "instrument.floor_z_mm")
    return SpatialView(
        position,
        reach,
        box,
        acceptance,
        None if acceptance is None else np.array(normals),
        floor,
    )


def load_spatial_truth(
    path: str | os.PathLike,
    model: FitModel,
    *,
    links: tuple[str | None, str | None] = (None, None),
    geometry_only: bool = False,
) -> np.ndarray:
    """The true parameters ``(p,)`` (mm, rad) of a virtual spatial arm (module notes), and
    for a model of joint compliance its ``[compliance]`` table's after them (display
    units urad/(N*m), mdeg/m; a parameter not given is 0).

    The true arm's description, when given, is turned into the arm's parameters
    exactly (:meth:`~armcal.models.SpatialArm.params_of`); a bare URDF's chain runs
    between the base and tip ``links`` (the robot's, where given).  A ``[compliance]``
    table needs a model of compliance (its robot file's ``[elastostatic]``), unless
    ``geometry_only``: then it is read for its keys and left out (the demo's rigid arm).
    """
    path = Path(path)
    data = load_toml(path, "truth")
    spatial = allowed_keys("", SPATIAL_TRUTH_KEYS)
    check_truth_keys(path, data, spatial, allowed_keys("", TRUTH_KEYS), "spatial")
    check_keys(path, data, spatial)
    arm: SpatialArm = model.arm
    if model.effect is None:  # a rigid arm
        if "compliance" in data and not geometry_only:
            raise fail(path, rigid_truth_message("compliance", arm.name, "[compliance]"))
        return _geometry_truth(path, data, arm, links)
    names = model.param_names[arm.n_params :]  # the compliance's, after the arm's
    compliance = np.zeros(len(names))
    if "compliance" in data:
        example, scale = f"{names[-1]} = 0.5", model.display_scale[arm.n_params :]
        table = data["compliance"]
        compliance = _named(path, table, "compliance", example, arm, names, names, scale)
    return np.concatenate([_geometry_truth(path, data, arm, links), compliance])


def _geometry_truth(
    path: Path, data: dict, arm: SpatialArm, links: tuple[str | None, str | None]
) -> np.ndarray:
    """The geometric truth of a truth TOML's ``data`` for ``arm``."""
    base = np.zeros(6)
    if "base" in data:
        entry = data["base"]
        if not isinstance(entry, dict) or not set(entry) <= {"xyz_mm", "rpy_deg"}:
            raise fail(path, "key 'base': expected { xyz_mm = [x, y, z], rpy_deg = [r, p, y] }")
        base[:3] = numbers(path, entry.get("xyz_mm", [0, 0, 0]), "base.xyz_mm", 3)
        base[3:] = np.radians(numbers(path, entry.get("rpy_deg", [0, 0, 0]), "base.rpy_deg", 3))
    labels, positions = _targets(path, data.get("targets"))
    chain = arm.chain
    if "robot" in data:
        other = _relative_file(path, data["robot"], "robot", "truth file")
        bare = other.suffix.lower() in _URDF_SUFFIXES  # a robot TOML says its own links
        chosen = dict(zip(("base_link", "tip_link"), links, strict=True)) if bare else {}
        chain = load_spatial_robot(other, **chosen).arm.chain
        if chain.kinds != arm.chain.kinds:
            raise fail(
                path,
                f"key 'robot': the true arm's joints ({''.join(chain.kinds)}) are not those of "
                f"{arm.name} ({''.join(arm.chain.kinds)}); describe the same arm",
            )
    truth_targets = arm.target_positions.copy()
    for label, position in zip(labels, positions, strict=True):
        if label not in arm.targets:
            raise fail(
                path,
                f"key 'targets.{label}': {label!r} is not a target of {arm.name}: "
                f"{suggest(label, arm.targets)}{_target_list(arm)}",
            )
        truth_targets[arm.targets.index(label)] = position
    params = arm.params_of(chain, base, truth_targets)
    if "errors" in data:
        params = params + _errors(path, data["errors"], arm)
    return params


def _target_list(arm: SpatialArm) -> str:
    """What a truth file's ``[targets]`` may name: the robot file's targets, or none."""
    if not arm.targets:
        return "the robot file has no [targets]; remove [targets] from the truth file"
    return (
        f"the robot file's [targets] has {', '.join(arm.targets)}; name one of them "
        "(a new target goes into the robot file first)"
    )


def _errors(path: Path, table: Any, arm: SpatialArm) -> np.ndarray:
    """``[errors]`` in display units as an internal parameter vector."""
    robot = ~arm.instrument_params
    names = [n for n, r in zip(arm.param_names, robot, strict=True) if r]
    return _named(path, table, "errors", "j2.x = 0.4, dq3 = 0.05", arm, names, arm.param_names)


def _named(
    path: Path,
    table: Any,
    key: str,
    example: str,
    arm: SpatialArm,
    names: Sequence[str],
    order: Sequence[str],
    scale: np.ndarray | None = None,
) -> np.ndarray:
    """A table of ``name = value`` in display units (dotted names nest in TOML) as a vector
    over ``order`` in internal units; only ``names`` may be given."""
    if not isinstance(table, dict):
        raise fail(path, f"key '{key}': expected a table [{key}] ({example}, ...)")
    flat: dict[str, Any] = {}
    for name, value in table.items():
        if isinstance(value, dict):
            flat.update({f"{name}.{k}": v for k, v in value.items()})
        else:
            flat[name] = value
    scale = arm.display_scale if scale is None else scale
    out = np.zeros(len(order))
    for name, value in flat.items():
        if name not in names:
            raise fail(
                path,
                f"key '{key}.{name}': not a parameter of {arm.name}'s [{key}]; "
                f"{suggest(name, names)}they are {', '.join(names)}",
            )
        i = list(order).index(name)
        out[i] = number(path, value, f"{key}.{name}") / scale[i]
    return out


def spatial_truth(
    robot: RobotSpec[SpatialArm],
    model: FitModel,
    path: str | os.PathLike | None,
    *,
    links: tuple[str | None, str | None] = (None, None),
    geometry_only: bool = False,
) -> np.ndarray:
    """The virtual robot's parameters of ``model`` from a truth file (``path``, else the
    built-in robot's own): :func:`armcal.files.spatial.load_spatial_truth`."""
    found = path if path is not None else robot.default_truth
    assert found is not None
    return load_spatial_truth(found, model, links=links, geometry_only=geometry_only)
