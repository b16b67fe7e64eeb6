"""Unit mistakes in a spatial robot file: angles in radians, lengths in metres, a URDF in mm.

A robot file has no measurements to fit, so its own numbers are the evidence.
Each check compares them with what a real arm looks like, and is an error where
no real arm could look like that, a warning where a strange arm might.

* **Modified DH angles in radians** (error).  The twists ``alpha_deg`` of a real
  arm are 0, +-90, 180 or a design angle such as 30 or 45 degrees, and its zeros
  ``theta_deg`` are about as round.  A key whose every angle lies within +-pi (plus
  :data:`RADIAN_MATCH`) while one of them is within :data:`RADIAN_MATCH` of +-pi/2
  or +-pi (1.5708, 3.1416, or the two-decimal 1.57 and 3.14) is in radians: a twist
  or a zero of 1.57 degrees with none beyond 3.14 degrees is no arm's.  Each of
  ``alpha_deg``, ``theta_deg``, ``base_rpy_deg`` and ``tip_rpy_deg`` is judged on
  its own (a table may have only its twists in radians); Hayati's ``beta_deg`` is
  not (it is a small angle, in radians as in degrees).
* **Joint limits in radians** (``limits-radians`` warning, as for planar arms).
  Every revolute joint's limit in ``joint_limits_deg`` within
  :data:`~armcal.files.robots.RADIAN_LIMIT_BOUND` (6.3, 2 pi rounded up): no real
  arm turns every joint through +-6 degrees only, while radians of any joint lie
  within +-2 pi.  A warning, not an error: an arm with one small tilting joint
  among slides could.
* **A slide's limits in metres** (``limits-metres`` warning).  A prismatic joint
  whose travel in ``joint_limits_deg`` (mm) is shorter than
  :data:`~armcal.files.robots.METRE_REACH_MM` (10 mm) and whose limits lie within
  +-10: a linear axis of a robot travels tens of mm at the least.
* **A URDF's limits in degrees** (``urdf-limits-degrees`` warning).  A revolute
  joint of the chain whose URDF limit is beyond :data:`URDF_LIMIT_BOUND_RAD` (4 pi:
  two turns each way; the widest wrists turn about +-2 turns): URDF limits are
  radians, and degrees read as radians give tens of turns.
* **Lengths in metres** (``lengths-in-metres`` warning, as for planar arms): the
  chain's offsets from its first joint on (the first joint's origin places the arm
  in its root link's frame, which may be a cell's) and the tip's add up to less
  than :data:`~armcal.files.robots.METRE_REACH_MM`.
* **A URDF in millimetres** (error): those offsets add up to more than
  :data:`MAX_REACH_MM` (20 m).  The largest serial arms reach about 17.6 m (the
  space station's Canadarm2; industrial arms 4.7 m at most): a URDF written in mm
  (``xyz="0 0 425"`` for 425 mm) makes a 1 m arm reach 1 km.  Where a few origins
  are each beyond that reach alone while the others make an arm, those origins are
  named: millimetres among metres.
* **rpy in degrees** (error, read with the URDF: :data:`~armcal.files.urdf.RPY_BOUND_RAD`):
  an origin's angle beyond 2 pi.
"""

from __future__ import annotations

import math
import os
from collections.abc import Mapping, Sequence

import numpy as np

from ..errors import ArmcalWarning
from ..models import SerialChain
from .common import fail
from .robots import METRE_REACH_MM, RADIAN_LIMIT_BOUND

__all__ = [
    "MAX_REACH_MM",
    "RADIAN_MATCH",
    "URDF_LIMIT_BOUND_RAD",
    "check_mdh_angles",
    "check_reach",
    "limit_warnings",
    "urdf_limit_warning",
]

#: How close (in the file's "degrees") an angle must be to +-pi/2 or +-pi to be read as
#: radians: 2e-3 takes 1.5708 and 3.1416 as well as the two-decimal 1.57 and 3.14.
RADIAN_MATCH = 2e-3

#: An arm whose joint origins and tip add up to more than this (mm) is no arm: the
#: largest serial arms reach 17.6 m (Canadarm2); industrial ones 4.7 m at most.
MAX_REACH_MM = 20_000.0

#: A URDF revolute limit beyond this (rad: two turns each way) is degrees read as radians.
URDF_LIMIT_BOUND_RAD = 4 * math.pi

_RADIAN_MARKS = np.array([math.pi / 2, math.pi])


def _looks_like_radians(values: Sequence[float]) -> float | None:
    """The value of ``values`` that is +-pi/2 or +-pi (to :data:`RADIAN_MATCH`) when every
    value lies within +-(pi + :data:`RADIAN_MATCH`), else None."""
    size = np.abs(np.asarray(values, dtype=float))
    if size.size == 0 or np.any(size > math.pi + RADIAN_MATCH):
        return None
    hit = np.abs(size[:, None] - _RADIAN_MARKS).min(axis=1) <= RADIAN_MATCH
    if not hit.any():
        return None
    return float(np.asarray(values, dtype=float)[np.argmax(hit)])


def check_mdh_angles(
    path: str | os.PathLike, angles: Mapping[str, Sequence[float]], table: str = "mdh"
) -> None:
    """Refuse a DH table (modified or standard) whose angles are radians (module notes).

    Parameters
    ----------
    path : str or path
        The robot file, for the message.
    angles : mapping
        ``alpha_deg``, ``theta_deg``, ``base_rpy_deg`` and ``tip_rpy_deg`` (those
        given) to the file's values, each judged on its own; the keys are named
        ``<table>.<key>`` in the message.
    table : str
        The table the file wrote them under: ``mdh`` or ``dh`` (standard DH).

    Raises
    ------
    InputError
        Naming the key and the value that gives the radians away.

    Examples
    --------
    >>> check_mdh_angles("a.toml", {"alpha_deg": [0, -90, 0], "theta_deg": [0, -90, 0]})
    >>> check_mdh_angles("a.toml", {"alpha_deg": [0, -1.5708, 0], "theta_deg": [0, 0, 0]})
    Traceback (most recent call last):
    ...
    armcal.errors.InputError: a.toml: key 'mdh.alpha_deg': every angle is within +-pi ...
    """
    for key in ("alpha_deg", "theta_deg", "base_rpy_deg", "tip_rpy_deg"):
        found = _looks_like_radians(angles.get(key, ()))
        if found is None:
            continue
        raise fail(
            path,
            f"key '{table}.{key}': every angle is within +-pi and "
            f"{found:g} is {'' if found > 0 else '-'}pi{'/2' if abs(found) < 2 else ''}, "
            f"which looks like radians; give degrees (e.g. {math.degrees(found):.4g} for "
            f"{found:g}; deg = rad x 57.29578)",
        )


def limit_warnings(
    path: str | os.PathLike, pairs: np.ndarray, kinds: Sequence[str], key: str
) -> list[ArmcalWarning]:
    """``limits-radians`` and ``limits-metres`` for the limits ``pairs`` ``(n, 2)`` (deg; mm
    for a prismatic joint) of a spatial robot file's key ``key`` (module notes)."""
    revolute = np.array([kind == "R" for kind in kinds])
    out = []
    angles = pairs[revolute]
    if angles.size and np.all(np.abs(angles) <= RADIAN_LIMIT_BOUND):
        lo, hi = angles[0]
        out.append(
            ArmcalWarning(
                "limits-radians",
                f"{os.fspath(path)}: key '{key}': every revolute joint's limit is "
                f"within +-{RADIAN_LIMIT_BOUND:g}, which looks like radians; give the limits in "
                f"degrees (e.g. [{math.degrees(lo):.1f}, {math.degrees(hi):.1f}] for "
                f"[{lo:g}, {hi:g}] rad): as written, every joint turns through a few degrees "
                "only",
            )
        )
    travel = pairs[:, 1] - pairs[:, 0]
    short = (~revolute) & (travel < METRE_REACH_MM) & np.all(np.abs(pairs) <= METRE_REACH_MM, 1)
    for j in np.flatnonzero(short):
        lo, hi = pairs[j]
        out.append(
            ArmcalWarning(
                "limits-metres",
                f"{os.fspath(path)}: key '{key}[{j}]': prismatic joint {j + 1} "
                f"travels {hi - lo:g} mm ([{lo:g}, {hi:g}]), which looks like metres; a "
                f"slide's limits are in mm (e.g. [{1000 * lo:g}, {1000 * hi:g}])",
            )
        )
    return out


def urdf_limit_warning(path: str | os.PathLike, chain: SerialChain) -> ArmcalWarning | None:
    """``urdf-limits-degrees`` when a revolute joint's URDF limit is beyond
    :data:`URDF_LIMIT_BOUND_RAD` (module notes)."""
    limits = chain.joint_limits
    wide = chain.revolute & np.any(
        np.isfinite(limits) & (np.abs(limits) > URDF_LIMIT_BOUND_RAD), axis=1
    )
    if not wide.any():
        return None
    shown = ", ".join(
        f"{chain.joint_names[j]} [{limits[j, 0]:g}, {limits[j, 1]:g}]"
        for j in np.flatnonzero(wide)
    )
    return ArmcalWarning(
        "urdf-limits-degrees",
        f"{os.fspath(path)}: the URDF's limits of {shown} are beyond +-{URDF_LIMIT_BOUND_RAD:.4g} "
        "rad (two turns each way), which looks like degrees; a URDF's revolute limits are in "
        "radians: convert them (rad = deg / 57.29578), or give joint_limits_deg in the robot "
        "TOML",
    )


def _offsets_in_mm(chain: SerialChain, offsets: np.ndarray) -> str | None:
    """What to say of a URDF whose reach is beyond :data:`MAX_REACH_MM` because of a few
    joint origins (``offsets``: joints 2 to n, mm), each beyond it alone, while the others
    make an arm: those origins, in mm among metres (None when the whole file is in mm)."""
    big = offsets > MAX_REACH_MM
    rest = float(np.sum(offsets[~big]) + np.linalg.norm(chain.tip[:3, 3]))
    if not big.any() or rest > MAX_REACH_MM or rest < METRE_REACH_MM:
        return None
    joints = np.flatnonzero(big) + 1  # offsets start at the second joint
    written = [" ".join(f"{v / 1000:g}" for v in chain.origins[j, :3, 3]) for j in joints]
    shown = ", ".join(
        f'joint {chain.joint_names[j]!r} (xyz="{xyz}")'
        for j, xyz in zip(joints, written, strict=True)
    )
    which = "that xyz" if joints.size == 1 else "those xyz"
    return (
        f"the origin of {shown} is beyond any arm's reach ({MAX_REACH_MM / 1000:g} m) alone, "
        f"while the arm's other offsets add up to {rest / 1000:.3g} m: it looks written in "
        f"millimetres among metres; a URDF's lengths are metres: divide {which} by 1000"
    )


def check_reach(
    path: str | os.PathLike, chain: SerialChain, *, urdf: bool, table: str = "mdh"
) -> ArmcalWarning | None:
    """Refuse an arm that reaches beyond :data:`MAX_REACH_MM`; ``lengths-in-metres`` when
    its offsets add up to less than :data:`~armcal.files.robots.METRE_REACH_MM`.

    ``urdf`` says whether the lengths came from a URDF (metres) or a modified DH table
    (``a_mm``, ``d_mm`` of the ``table``, ``mdh`` or ``dh``), for the fix the message gives.
    """
    # From the first joint on: the first joint's origin places the arm in its root link's
    # frame, which may be a cell's world frame metres away.
    offsets = np.linalg.norm(chain.origins[1:, :3, 3], axis=1)
    reach = float(np.sum(offsets) + np.linalg.norm(chain.tip[:3, 3]))
    if reach > MAX_REACH_MM:
        alone = _offsets_in_mm(chain, offsets) if urdf else None
        if alone is not None:
            raise fail(path, alone)
        fix = (
            'the URDF looks written in millimetres (xyz="0 0 425" for 425 mm), but a URDF\'s '
            "lengths are metres: divide its xyz and its prismatic limits by 1000"
            if urdf
            else f"check the unit of {table}.a_mm, {table}.d_mm and the frames' xyz (mm)"
        )
        raise fail(
            path,
            f"the arm's joint offsets from joint 1 add up to {reach:.4g} mm ({reach / 1e6:.3g} "
            "km), beyond "
            f"any arm's reach ({MAX_REACH_MM / 1000:g} m); {fix}",
        )
    if reach >= METRE_REACH_MM:
        return None
    where = (
        "the URDF's xyz are read in metres" if urdf else f"{table}.a_mm and {table}.d_mm are in mm"
    )
    return ArmcalWarning(
        "lengths-in-metres",
        f"{os.fspath(path)}: the arm's joint offsets from joint 1 add up to {reach:g} mm, which "
        "looks like "
        f"the wrong unit ({where}): as written, the arm reaches {reach:g} mm and every "
        "measured point in mm lies far beyond it",
    )
