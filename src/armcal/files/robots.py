"""Robot and truth files: a robot TOML (or a built-in name) as the arm armcal fits.

Units: files use mm and degrees with the unit in every key name
(``link_lengths_mm``, ``joint_limits_deg``); everything returned to the library
is in mm and rad.  Every key lives in one catalogue (:mod:`armcal.formats`), so
a misspelled or misplaced key gets a hint that names its table.
"""

from __future__ import annotations

import math
import os
from collections.abc import Sequence
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import numpy as np

from ..choices import BUILTIN_ROBOTS, DEFAULT_ROBOT, SIGMA_RANGE_MM
from ..errors import ArmcalError, ArmcalWarning, InputError, action, unrendered
from ..families.registry import RobotSpec, builtin_robots
from ..formats import SPATIAL_TRUTH_KEYS, TRUTH_KEYS, allowed_keys
from ..models import (
    Annulus,
    Box,
    CompliantArm,
    Elastostatic,
    FitModel,
    PlanarArm,
    Region,
    Target,
    TermChoice,
    checked_joint_map,
)
from ..noise import NoiseModel
from ..paper import paper_arm
from .common import (
    STDIO,
    check_keys,
    check_truth_keys,
    fail,
    load_toml,
    number,
    number_within,
    numbers,
    read_text,
    suggest,
)

__all__ = [
    "BUILTIN_ROBOTS",
    "COMPLIANCE_TRUTH_KEYS",
    "DEFAULT_ROBOT",
    "JOINT_SIGMA_MAX_DEG",
    "LINK_LENGTH_RANGE_MM",
    "RADIAN_LIMIT_BOUND",
    "SIGMA_RANGE_MM",
    "SPATIAL_ROBOT_KEYS",
    "RobotSpec",
    "fixed_parameters",
    "held_terms",
    "load_compliance_truth",
    "load_planar_robot",
    "load_truth",
    "parse_region",
    "planar_truth",
    "read_joint_map",
    "refuse_unknown_robot",
    "rigid_truth_message",
    "unknown_parameter",
]

#: Link lengths accepted (mm): from a micrometre to 10 km.
LINK_LENGTH_RANGE_MM = (1e-3, 1e7)

#: A robot arm whose links add up to less than this (mm) was almost surely written in
#: metres (a 0.66 m arm as 0.66 mm): the smallest desktop arms reach about 10 cm.
METRE_REACH_MM = 10.0

#: Encoder noise accepted (1 std, deg): 0 to 10 deg.  An encoder that reads a joint
#: worse than 10 deg is no encoder; such a value is a unit mistake (mdeg, arcsec).
JOINT_SIGMA_MAX_DEG = 10.0

#: Joint limits whose every value lies within this many "degrees" (2 pi, rounded up so
#: that written-out radians such as 6.2832 count) look like radians: a real joint
#: confined to +-6.3 deg cannot move enough to be calibrated, while radians limits of
#: any revolute joint lie within +-2 pi.  Such limits give a ``limits-radians`` warning.
RADIAN_LIMIT_BOUND = 6.3


# --------------------------------------------------------------------------- robots


def _builtin(name: str) -> RobotSpec[PlanarArm]:
    arm, truth = paper_arm(BUILTIN_ROBOTS[name])
    return RobotSpec(arm, name, truth)


def parse_region(path, region: Any) -> Region:
    key = "measurement.region"
    if not isinstance(region, dict):
        raise fail(path, f"key '{key}': expected a table such as {{ kind = \"annulus\", ... }}")
    kind = region.get("kind")
    if kind == "annulus":
        check_keys(path, region, ["kind", "center_mm", "r_min_mm", "r_max_mm"], f"{key}.")
        center = numbers(path, region.get("center_mm", [0.0, 0.0]), f"{key}.center_mm", 2)
        r_min = number(path, region.get("r_min_mm", 0.0), f"{key}.r_min_mm")
        if "r_max_mm" not in region:
            raise fail(path, f"key '{key}': an annulus needs r_max_mm")
        r_max = number(path, region["r_max_mm"], f"{key}.r_max_mm")
        if not 0 <= r_min < r_max:
            raise fail(path, f"key '{key}': need 0 <= r_min_mm < r_max_mm, got {r_min}, {r_max}")
        return Annulus((center[0], center[1]), r_min, r_max)
    if kind == "box":
        check_keys(path, region, ["kind", "x_mm", "y_mm"], f"{key}.")
        bounds = []
        for axis in ("x_mm", "y_mm"):
            if axis not in region:
                raise fail(path, f"key '{key}': a box needs {axis} = [lo, hi]")
            lo, hi = numbers(path, region[axis], f"{key}.{axis}", 2)
            if not lo < hi:
                raise fail(path, f"key '{key}.{axis}': need lo < hi, got [{lo}, {hi}]")
            bounds.append((lo, hi))
        return Box(bounds[0], bounds[1])
    raise fail(path, f'key \'{key}.kind\': expected "annulus" or "box", got {kind!r}')


def _sigma_value(path, value: Any, key: str) -> float:
    """An instrument noise (1 std, mm) within :data:`SIGMA_RANGE_MM`."""
    return number_within(path, value, key, SIGMA_RANGE_MM, "mm")


def _instrument_covariance(path, meas: dict) -> np.ndarray | None:
    """``[measurement] sigma_mm`` (a number or ``[sx, sy]``) or ``covariance_mm2``, in mm^2."""
    if "sigma_mm" in meas and "covariance_mm2" in meas:
        raise fail(
            path,
            "keys 'measurement.sigma_mm' and 'measurement.covariance_mm2' both give the "
            "instrument noise; keep one",
        )
    if "sigma_mm" in meas:
        key = "measurement.sigma_mm"
        raw = meas["sigma_mm"]
        if isinstance(raw, list):
            if len(raw) != 2:
                raise fail(
                    path,
                    f"key '{key}': expected one number or two [sx, sy] (per instrument axis), "
                    f"got {len(raw)} numbers",
                )
            sx, sy = (_sigma_value(path, v, f"{key}[{i}]") for i, v in enumerate(raw))
            return np.diag([sx**2, sy**2])
        return np.eye(2) * _sigma_value(path, raw, key) ** 2
    if "covariance_mm2" in meas:
        key = "measurement.covariance_mm2"
        raw = meas["covariance_mm2"]
        square = isinstance(raw, list) and len(raw) == 2
        if not square or not all(isinstance(row, list) and len(row) == 2 for row in raw):
            raise fail(
                path, f"key '{key}': expected a 2 x 2 matrix [[a, b], [b, c]] in mm^2, got {raw!r}"
            )
        cov = np.array([numbers(path, row, f"{key}[{i}]", 2) for i, row in enumerate(raw)])
        a, b, c, d = cov[0, 0], cov[0, 1], cov[1, 0], cov[1, 1]
        if b != c:
            raise fail(
                path,
                f"key '{key}': must be symmetric (b = c), got [[{a:g}, {b:g}], [{c:g}, {d:g}]]",
            )
        if not (a > 0 and d > 0 and a * d - b * c > 0):
            raise fail(
                path,
                f"key '{key}': must be positive definite (a > 0, c > 0, a c > b^2), got "
                f"[[{a:g}, {b:g}], [{c:g}, {d:g}]]",
            )
        low, high = SIGMA_RANGE_MM
        for i in (0, 1):
            if not low <= math.sqrt(cov[i, i]) <= high:
                raise fail(
                    path,
                    f"key '{key}[{i}][{i}]': the std of axis {'xy'[i]} must be between {low:g} "
                    f"and {high:g} mm, got {math.sqrt(cov[i, i]):g}; check the unit (mm^2)",
                )
        return cov
    return None


def _joint_sigma(path, meas: dict, n: int) -> np.ndarray | None:
    """``[measurement] joint_sigma_deg``: one number or ``n``, in rad (None when absent)."""
    if "joint_sigma_deg" not in meas:
        return None
    key = "measurement.joint_sigma_deg"
    raw = meas["joint_sigma_deg"]
    if isinstance(raw, list):
        if len(raw) != n:
            raise fail(
                path, f"key '{key}': expected one number or {n} (one per joint), got {len(raw)}"
            )
        values = [number(path, v, f"{key}[{j}]") for j, v in enumerate(raw)]
        names = [f"{key}[{j}]" for j in range(n)]
    else:
        values, names = [number(path, raw, key)], [key]
    for name, value in zip(names, values, strict=True):
        if not 0 <= value <= JOINT_SIGMA_MAX_DEG:
            raise fail(
                path,
                f"key '{name}': encoder noise must be between 0 and {JOINT_SIGMA_MAX_DEG:g} deg, "
                f"got {value:g}; check the unit (deg)",
            )
    return np.radians(values)


def fixed_parameters(
    path, table: Any, names: Sequence[str], arm_name: str, terms: Sequence[str] = ()
) -> list[str]:
    """``[identify] fixed = [...]`` or ``free = [...]`` as the list of fixed names of the
    arm's parameters ``names``.

    ``terms`` are an effect's (joint compliance's, :func:`held_terms`), which the
    lists may name too.  With them, ``free`` governs each group apart: a list that
    names no parameter of the arm leaves every one free.
    """
    if not isinstance(table, dict):
        raise fail(path, "key 'identify': expected a table [identify]")
    if "fixed" in table and "free" in table:
        raise fail(
            path,
            "keys 'identify.fixed' and 'identify.free' both say what is identified; keep one "
            "(free = [...] fixes every other parameter)",
        )
    if not table:
        return []
    key = "fixed" if "fixed" in table else "free"
    raw = table[key]
    if not isinstance(raw, list) or not all(isinstance(v, str) for v in raw):
        raise fail(path, f"key 'identify.{key}': expected a list of parameter names, got {raw!r}")
    known = [*names, *terms]
    for name in raw:
        if name == "phi0":  # a policy: the robot file describes the robot, not a set-up
            raise fail(
                path,
                f"key 'identify.{key}': phi0 is the base's turn in the instrument's axes, "
                "which exists only with 3-D data and belongs to the set-up, not the robot; "
                "leave it out (held, it would put the instrument's turn into the joint "
                f"offsets); to hold it for one fit, use {action('hold', 'phi0')}",
            )
        if name not in known:
            raise fail(path, f"key 'identify.{key}': {unknown_parameter(name, known, arm_name)}")
    chosen = set(raw)
    if key == "free" and chosen and not chosen & set(names):
        return []  # only the effect's terms listed: the arm's parameters stay free
    fixed = [nm for nm in names if (nm in chosen) == (key == "fixed")]
    if len(fixed) == len(names):
        raise fail(
            path,
            f"key 'identify.{key}': every parameter would be fixed; leave at least one free",
        )
    return fixed


def held_terms(table: Any, terms: Sequence[str]) -> TermChoice:
    """The effect's ``terms`` the ``[identify]`` table (checked by :func:`fixed_parameters`)
    holds: those ``fixed`` lists, or, where ``free`` lists any, every one it does not."""
    if not isinstance(table, dict):
        return TermChoice()
    if "free" in table:
        free = tuple(n for n in table["free"] if n in terms)
        return TermChoice(free=free) if free else TermChoice()
    return TermChoice(fixed=tuple(n for n in table.get("fixed", []) if n in terms))


def unknown_parameter(name: str, names: Sequence[str], arm_name: str) -> str:
    """The message for a parameter name the arm does not have: the valid names, and a hint.

    Examples
    --------
    >>> unknown_parameter("x0", ("dl1", "dq1"), "arm")
    "unknown parameter 'x0'; the parameters of arm are dl1, dq1 (x0 and y0 exist only with base_offset = true)"
    """  # noqa: E501
    per_target = [n for n in names if n.startswith(f"{name}@")]
    if per_target:  # the last link's parameter, which targets split into one per target
        hint = (
            f"with targets it is one per target ({', '.join(per_target)}): the last link and "
            f"each target are one vector; hold them all with {action('hold', *per_target)}; "
        )
    else:
        hint = suggest(name, names)
    message = (
        f"unknown parameter '{name}'; {hint}the parameters of {arm_name} are {', '.join(names)}"
    )
    if name in ("x0", "y0"):
        message += " (x0 and y0 exist only with base_offset = true)"
    return message


def _metre_lengths_warning(path, lengths: list[float]) -> ArmcalWarning | None:
    """``lengths-in-metres`` when the links add up to less than :data:`METRE_REACH_MM`."""
    reach = sum(lengths)
    if reach >= METRE_REACH_MM:
        return None
    shown = ", ".join(f"{1000 * v:g}" for v in lengths)
    return ArmcalWarning(
        "lengths-in-metres",
        f"{os.fspath(path)}: key 'link_lengths_mm': the links add up to {reach:g} mm, which "
        f"looks like metres; give the lengths in mm (e.g. [{shown}]): as written, the arm "
        f"reaches {reach:g} mm and every measured point in mm lies far beyond it",
    )


def _radian_limits_warning(path, raw_limits: list[tuple[float, float]]) -> ArmcalWarning | None:
    """``limits-radians`` when every joint limit lies within :data:`RADIAN_LIMIT_BOUND`."""
    if not all(abs(v) <= RADIAN_LIMIT_BOUND for pair in raw_limits for v in pair):
        return None
    shown = ", ".join(f"[{lo:g}, {hi:g}]" for lo, hi in raw_limits)
    lo, hi = raw_limits[0]
    return ArmcalWarning(
        "limits-radians",
        f"{os.fspath(path)}: key 'joint_limits_deg': every limit is within "
        f"+-{RADIAN_LIMIT_BOUND:g} "
        f"({shown}), which looks like radians; give the limits in degrees (e.g. "
        f"[{math.degrees(lo):.1f}, {math.degrees(hi):.1f}] for [{lo:g}, {hi:g}] rad): as "
        "written, every joint turns through a few degrees only",
    )


#: The keys that describe a spatial arm in a robot TOML (a URDF, a DH table or a UR
#: model; exactly one of them), which planar robot files lack.
SPATIAL_ROBOT_KEYS = ("urdf", "mdh", "dh", "ur")

_PIPED_SPATIAL = (
    "{what} is read from a file, not piped in (only a planar robot file may be): give its path"
)


def refuse_unknown_robot(key: str) -> None:
    """Refuse a robot that is no file and no built-in, listing every family's built-ins
    and the closest to ``key`` (a typo of a name)."""
    builtins = builtin_robots()
    if key == STDIO or key in builtins or Path(key).exists():
        return
    by_family: dict[str, list[str]] = {}
    for name, family in builtins.items():
        by_family.setdefault(family.name, []).append(name)
    listed = "; ".join(f"{family}: {', '.join(names)}" for family, names in by_family.items())
    raise InputError(
        f"{key}: robot is neither a built-in ({listed}) nor an existing file; "
        f"{suggest(key, list(builtins))}"
        "give a built-in's name or the path of a robot TOML file or a URDF"
    )


def load_planar_robot(
    name_or_path: str | os.PathLike,
    *,
    base_link: str | None = None,
    tip_link: str | None = None,
) -> RobotSpec[PlanarArm]:
    """Load a built-in planar robot by name or a planar robot TOML file.

    Parameters
    ----------
    name_or_path : str or path
        ``paper-2link``, ``paper-3link``, ``paper-4link``, or a TOML file with
        ``link_lengths_mm`` and the optional ``name``, ``joint_limits_deg``,
        ``base_offset``, ``[measurement]`` (``sigma_mm`` as one number or per
        axis ``[sx, sy]``, or ``covariance_mm2``; ``joint_sigma_deg``;
        ``region``) and ``[identify]`` (``fixed`` or ``free``: lists of
        parameter names).

    Returns
    -------
    RobotSpec
        The arm carries the noise model (:class:`~armcal.noise.NoiseModel`) and
        the fixed parameters; ``warnings`` holds ``limits-radians`` when every
        joint limit looks like radians.

    Raises
    ------
    InputError
        For a missing file, invalid TOML, an unknown key or parameter name, or an
        invalid value; the message names the file and the key.

    Examples
    --------
    >>> load_planar_robot("paper-4link").arm.link_lengths.tolist()
    [260.0, 180.0, 120.0, 100.0]
    """
    key = os.fspath(name_or_path)
    refuse_unknown_robot(key)
    if base_link is not None or tip_link is not None:
        raise ArmcalError(
            f"{key}: a base or tip link was given, but this is a planar robot, not one from a "
            "URDF: links choose a URDF's chain; drop them"
        )
    if key in BUILTIN_ROBOTS:
        return _builtin(key)
    path = Path(key)
    data = _planar_data(path)
    lengths = _link_lengths(path, data)
    n = len(lengths)
    name = data.get("name", "robot" if key == STDIO else path.stem)
    if not isinstance(name, str) or not name.strip():
        raise fail(path, f"key 'name': expected a non-empty string, got {name!r}")
    metres = _metre_lengths_warning(path, lengths)
    warnings: list[ArmcalWarning] = [] if metres is None else [metres]
    limits = None
    if "joint_limits_deg" in data:
        limits, radians = _joint_limits(path, data["joint_limits_deg"], n)
        warnings += [] if radians is None else [radians]
    base_offset = data.get("base_offset", False)
    if not isinstance(base_offset, bool):
        raise fail(path, f"key 'base_offset': expected true or false, got {base_offset!r}")
    measurement = _Measurement(None, None, None)
    if "measurement" in data:
        measurement = _measurement(path, data["measurement"], n)
    mapping = None
    if "joint_map" in data:
        mapping = read_joint_map(path, data["joint_map"], ("R",) * n)
    offsets = None
    if "joint_offsets_deg" in data:
        offsets = np.radians(numbers(path, data["joint_offsets_deg"], "joint_offsets_deg", n))
    targets = _targets(path, data["targets"], lengths[-1]) if "targets" in data else ()
    try:
        structure = PlanarArm(lengths, base_offset=base_offset, joint_map=mapping, targets=targets)
    except ValueError as exc:
        raise fail(path, unrendered(exc)) from None
    fixed, elastic = _fixed_and_elastic(path, data, structure, name)
    try:
        arm = PlanarArm(
            lengths,
            limits,
            base_offset=base_offset,
            name=name,
            noise=measurement.noise,
            region=measurement.region,
            fixed=fixed,
            joint_map=mapping,
            targets=targets,
            joint_offsets=offsets,
        )
    except ValueError as exc:  # every value was checked above; this names what is left
        raise fail(path, unrendered(exc)) from None
    return RobotSpec(arm, key, None, tuple(warnings), elastic, measurement.gravity_3d)


def _planar_data(path: Path) -> dict[str, Any]:
    """The table of a planar robot TOML (``-``: stdin, which must be neither a URDF nor a
    spatial robot file), its keys and its tables' keys checked."""
    if os.fspath(path) == STDIO:
        text = read_text(path, "robot")
        if text.lstrip().startswith("<"):
            raise fail(path, _PIPED_SPATIAL.format(what="a URDF"))
        data = load_toml(path, "robot", text)
        if any(key in data for key in SPATIAL_ROBOT_KEYS):
            raise fail(path, _PIPED_SPATIAL.format(what="a six-axis robot file"))
    else:
        data = load_toml(path, "robot")
    check_keys(path, data, allowed_keys(""))
    for table in ("measurement", "identify", "elastostatic"):  # [targets] holds labels
        if isinstance(data.get(table), dict):
            check_keys(path, data[table], allowed_keys(table), f"{table}.")
    return data


def _link_lengths(path: Path, data: dict[str, Any]) -> list[float]:
    """``link_lengths_mm``: at least one, each within :data:`LINK_LENGTH_RANGE_MM`."""
    if "link_lengths_mm" not in data:
        raise fail(path, "missing key 'link_lengths_mm' (a list of link lengths in mm)")
    lengths = numbers(path, data["link_lengths_mm"], "link_lengths_mm")
    if not lengths:
        raise fail(path, "key 'link_lengths_mm': needs at least one link")
    low, high = LINK_LENGTH_RANGE_MM
    for i, length in enumerate(lengths):
        if not low <= length <= high:
            raise fail(
                path,
                f"key 'link_lengths_mm[{i}]': link {i + 1} length must be between {low:g} and "
                f"{high:g} mm, got {length:g}; check the unit (mm)",
            )
    return lengths


def _joint_limits(
    path: Path, raw: Any, n: int
) -> tuple[list[tuple[float, float]], ArmcalWarning | None]:
    """``joint_limits_deg``: a pair ``[lo, hi]`` per joint, in rad, and the
    ``limits-radians`` warning where they look like radians already."""
    if not isinstance(raw, list) or len(raw) != n:
        raise fail(
            path,
            f"key 'joint_limits_deg': expected {n} pairs [lo, hi], one per joint, got {raw!r}",
        )
    pairs = []
    for j, pair in enumerate(raw):
        lo, hi = numbers(path, pair, f"joint_limits_deg[{j}]", 2)
        if not lo < hi:
            raise fail(path, f"key 'joint_limits_deg[{j}]': need lo < hi, got [{lo}, {hi}]")
        pairs.append((lo, hi))
    limits = [(math.radians(lo), math.radians(hi)) for lo, hi in pairs]
    return limits, _radian_limits_warning(path, pairs)


@dataclass(frozen=True)
class _Measurement:
    """A planar robot file's ``[measurement]``: the instrument's noise model, the region it
    measures and gravity's direction in its frame (each None where not given)."""

    noise: NoiseModel | None
    region: Region | None
    gravity_3d: np.ndarray | None


def _measurement(path: Path, meas: Any, n: int) -> _Measurement:
    """``[measurement]``: ``gravity``, the instrument's noise (``sigma_mm`` or
    ``covariance_mm2``), the encoders' (``joint_sigma_deg``) and ``region``."""
    if not isinstance(meas, dict):
        raise fail(path, "key 'measurement': expected a table [measurement]")
    gravity_3d = None
    if "gravity" in meas:
        gravity_3d = np.array(numbers(path, meas["gravity"], "measurement.gravity", 3))
        if not np.any(gravity_3d):
            raise fail(
                path,
                "key 'measurement.gravity': needs a non-zero direction in the instrument "
                "frame, e.g. [0, 0, -1] for a levelled tracker",
            )
    covariance = _instrument_covariance(path, meas)
    joint_sigma = _joint_sigma(path, meas, n)
    if joint_sigma is not None and covariance is None:
        raise fail(
            path,
            "key 'measurement.joint_sigma_deg': encoder noise needs the instrument noise "
            "too; add sigma_mm (or covariance_mm2) to [measurement]",
        )
    noise = None if covariance is None else NoiseModel(covariance, joint_sigma)
    region = parse_region(path, meas["region"]) if "region" in meas else None
    return _Measurement(noise, region, gravity_3d)


def _fixed_and_elastic(
    path: Path, data: dict[str, Any], structure: PlanarArm, name: str
) -> tuple[list[str], Elastostatic | None]:
    """The parameters ``[identify]`` holds, among the arm's and its ``[elastostatic]``
    compliance terms, and that table (the terms it holds chosen), None for a rigid arm."""
    n = structure.n_joints
    elastic = _elastostatic(path, data["elastostatic"], n) if "elastostatic" in data else None
    terms = () if elastic is None else elastic.term_names(structure)
    fixed: list[str] = []
    if "identify" in data:
        fixed = fixed_parameters(path, data["identify"], structure.param_names, name, terms)
        if elastic is not None:
            elastic = replace(elastic, terms=held_terms(data["identify"], terms))
    return fixed, elastic


def _elastostatic(path, table: Any, n: int) -> Elastostatic:
    """``[elastostatic]``: ``gravity_xy``, ``link_masses_kg``, ``com_fraction``, ``payload_kg``."""
    if not isinstance(table, dict):
        raise fail(path, "key 'elastostatic': expected a table [elastostatic]")
    gravity = None
    if "gravity_xy" in table:
        gravity = numbers(path, table["gravity_xy"], "elastostatic.gravity_xy", 2)
    masses = None
    if "link_masses_kg" in table:
        masses = numbers(path, table["link_masses_kg"], "elastostatic.link_masses_kg", n)
    fraction: float | list[float] = 0.5
    if "com_fraction" in table:
        raw = table["com_fraction"]
        key = "elastostatic.com_fraction"
        fraction = numbers(path, raw, key, n) if isinstance(raw, list) else number(path, raw, key)
    payload = 0.0
    if "payload_kg" in table:
        payload = number(path, table["payload_kg"], "elastostatic.payload_kg")
    try:
        return Elastostatic.create(
            n, gravity_xy=gravity, link_masses_kg=masses, com_fraction=fraction, payload_kg=payload
        )
    except ArmcalError as exc:
        raise fail(path, f"[elastostatic]: {unrendered(exc)}") from None


def read_joint_map(path, value: Any, kinds: Sequence[str]) -> np.ndarray:
    """A robot file's ``joint_map``, in every family's robot file: a row of numbers per
    joint, its readings' map to the angles the kinematics use (a planar arm's link angles
    ``theta = M q``, a spatial arm's URDF joint values ``u = M q``).

    Parameters
    ----------
    path : path
        The robot file, for the messages.
    value : object
        The key's value as read from the TOML.
    kinds : sequence of str
        The arm's joints, ``"R"`` (revolute) or ``"P"`` (prismatic).

    Returns
    -------
    ndarray, shape (n, n)

    Raises
    ------
    InputError
        Unless ``value`` is ``n`` rows of ``n`` finite numbers, invertible by the one
        check of every family (:func:`~armcal.models.checked_joint_map`), whose readings
        move joints of their own kind only.
    """
    n = len(kinds)
    if not isinstance(value, list) or len(value) != n:
        raise fail(
            path,
            f"key 'joint_map': expected {n} rows of {n} numbers (the arm has {n} joints), "
            f"got {value!r}",
        )
    rows = [numbers(path, row, f"joint_map[{i}]", n) for i, row in enumerate(value)]
    try:
        mapping = checked_joint_map(rows, n)
    except ValueError as exc:
        raise fail(path, str(exc)) from None
    _check_map_kinds(path, mapping, kinds)
    return mapping


def _check_map_kinds(path, mapping: np.ndarray, kinds: Sequence[str]) -> None:
    """Refuse a ``joint_map`` that makes a revolute joint's angle of a slide's reading (mm)
    or a slide of an angle: the units do not mix, and every reading's column unit follows
    the kind of the joints it moves (``q{j}_deg`` or ``q{j}_mm``)."""
    for i, j in np.argwhere(mapping != 0):
        if kinds[i] != kinds[j]:
            what = {"R": "revolute", "P": "prismatic"}
            raise fail(
                path,
                f"key 'joint_map': row {i + 1}, column {j + 1} is {mapping[i, j]:g}: it moves "
                f"{what[kinds[i]]} joint {i + 1} by reading {j + 1} of {what[kinds[j]]} joint "
                f"{j + 1}; a reading moves joints of its own kind only (degrees and mm do not "
                "mix): set it to 0",
            )


def _targets(path, table: Any, last_length: float) -> tuple[Target, ...]:
    """``[targets]``: ``label = { length_mm = ..., angle_deg = ... }`` per target."""
    if not isinstance(table, dict) or not table:
        raise fail(
            path,
            "key 'targets': expected a table [targets] with one entry per target, e.g. "
            "A = { length_mm = 100.0, angle_deg = 0.0 }",
        )
    targets = []
    for label, entry in table.items():
        key = f"targets.{label}"
        if not isinstance(entry, dict):
            raise fail(path, f"key '{key}': expected {{ length_mm = ..., angle_deg = ... }}")
        check_keys(path, entry, ["length_mm", "angle_deg"], f"{key}.")
        length = number(path, entry.get("length_mm", last_length), f"{key}.length_mm")
        angle = number(path, entry.get("angle_deg", 0.0), f"{key}.angle_deg")
        low, high = LINK_LENGTH_RANGE_MM
        if not low <= length <= high:
            raise fail(
                path,
                f"key '{key}.length_mm': the distance from the last joint to the target must be "
                f"between {low:g} and {high:g} mm, got {length:g}",
            )
        try:
            targets.append(Target(str(label), length, math.radians(angle)))
            PlanarArm([1.0], targets=targets)  # label rules
        except ValueError as exc:
            raise fail(path, f"key '{key}': {unrendered(exc)}") from None
    return tuple(targets)


def load_truth(path: str | os.PathLike, arm: PlanarArm, *, rigid: bool = False) -> np.ndarray:
    """Read a truth TOML (``dl_mm``, ``dq_deg``, optional ``base_mm``) for ``arm``.

    A model with joint compliance reads the truth's compliance on its own
    (:func:`load_compliance_truth`); a ``rigid`` model refuses it, as it cannot use it.

    Returns
    -------
    ndarray, shape (p,)
        User deviations in mm and rad.
    """
    data = load_toml(path, "truth")
    planar = allowed_keys("", TRUTH_KEYS)
    check_truth_keys(path, data, planar, allowed_keys("", SPATIAL_TRUTH_KEYS), "planar")
    check_keys(path, data, planar, robot=False)
    given = [key for key in COMPLIANCE_TRUTH_KEYS.values() if key in data]
    if rigid and given:
        raise fail(path, rigid_truth_message(given[0], arm.name))
    n, k = arm.n_joints, arm.n_links
    counts = f"{n} numbers, one per joint" + (
        f", or {k}: one per link vector (the last link once per target)" if k != n else ""
    )
    for key in ("dl_mm", "dq_deg"):
        if key not in data:
            raise fail(path, f"missing key '{key}' ({counts})")
    dl = numbers(path, data["dl_mm"], "dl_mm")
    dq = numbers(path, data["dq_deg"], "dq_deg")
    for key, values in (("dl_mm", dl), ("dq_deg", dq)):
        if len(values) not in (n, k):
            raise fail(path, f"key '{key}': expected {counts}, got {len(values)}")
    base = None
    if "base_mm" in data:
        if not arm.base_offset:
            raise fail(
                path,
                f"key 'base_mm': robot {arm.name} has base_offset = false; "
                "set base_offset = true in the robot file or remove base_mm",
            )
        base = numbers(path, data["base_mm"], "base_mm", 2)
    params = arm.params_from_display(dl, dq, base)
    for i, v in enumerate(params[:k]):
        if arm.link_nominal[i] + v <= 0:
            raise fail(path, f"key 'dl_mm': link {arm.link_names[i]} would have length <= 0")
    return params


#: Truth keys of the compliance parameters (:mod:`armcal.models.planar.compliance`), by kind.
COMPLIANCE_TRUTH_KEYS = {"k": "k_urad_per_Nm", "c": "c_mdeg_per_m"}


def rigid_truth_message(key: str, name: str, table: str | None = None) -> str:
    """Why a truth's compliance ``key`` (a ``table`` of keys, where given) is refused for
    the rigid model of robot ``name``."""
    return (
        f"key '{key}': the model of robot {name} has no joint compliance (its robot file has "
        "no [elastostatic] table, or the compliance is left out), so nothing twists its "
        f"joints; add the table to the robot file or remove {table or key}"
    )


def load_compliance_truth(path: str | os.PathLike, model: CompliantArm) -> np.ndarray:
    """The compliance of a truth TOML (``k_urad_per_Nm``, ``c_mdeg_per_m``), internal units.

    Returns
    -------
    ndarray, shape (P,)
        In the order of ``model.compliance_names``: rad/(N m) for ``k``, rad/m for ``c``.
    """
    data = load_toml(path, "truth")
    n = model.arm.n_joints
    values = []
    for kind in dict.fromkeys(model.kinds):
        key = COMPLIANCE_TRUTH_KEYS[kind]
        if key not in data:
            raise fail(
                path,
                f"missing key '{key}' ({n} numbers): the robot's [elastostatic] model has "
                f"parameters {', '.join(model.compliance_names)}",
            )
        values += numbers(path, data[key], key, n)
    return np.array(values) / model.compliance_scale


def planar_truth(
    robot: RobotSpec[PlanarArm],
    model: FitModel,
    path: str | os.PathLike | None,
    *,
    links: tuple[str | None, str | None] = (None, None),
    geometry_only: bool = False,
) -> np.ndarray:
    """The virtual robot's parameters of ``model``: a truth file's (``path``), with its
    compliance for a model of joint compliance, else the built-in robot's deviations.

    ``geometry_only`` (the demo's rigid arm) leaves a truth's compliance out.
    """
    if model.effect is not None:  # joint compliance: its terms follow the geometry's
        compliant: CompliantArm = model  # type: ignore[assignment]
        if path is None:
            keys = ", ".join(COMPLIANCE_TRUTH_KEYS[k] for k in dict.fromkeys(compliant.kinds))
            raise ArmcalError(
                f"{robot.source}: a robot with [elastostatic] needs a truth file with the "
                f"deviations and {keys}"
            )
        geometry = load_truth(path, compliant.arm)
        return np.concatenate([geometry, load_compliance_truth(path, compliant)])
    if path is not None:
        return load_truth(path, robot.arm, rigid=not geometry_only)
    assert isinstance(robot.default_truth, np.ndarray)
    return robot.default_truth
