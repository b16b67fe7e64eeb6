"""Files in and out: robot and truth TOML, plan and measurement CSV, calibration JSON.

Every reader validates strictly and raises :class:`~armcal.errors.InputError`
with a message that names the file, the row (data row and file line) and the
column or key, and says how to fix it.  Every writer writes a temporary file
next to the target and renames it, so a failed run never leaves half a file;
:func:`check_outputs` refuses, before any work, an output that is an input, a
directory or a special file, and :func:`write_folder` makes an output folder
only once all its files are complete.

Units: files use mm and degrees with the unit in every column or key name
(``q1_deg``, ``x_mm``); everything returned to the library is in mm and rad.
"""

from __future__ import annotations

import csv
import difflib
import errno
import json
import math
import os
import re
import shutil
import stat
import sys
import tempfile
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any, BinaryIO

import numpy as np

from .errors import ArmcalError, ArmcalWarning, InputError
from .formats import TRUTH_KEYS, allowed_keys, reader_columns, table_of
from .models import (
    Annulus,
    Box,
    CalibratedArm,
    CompliantArm,
    Elastostatic,
    FitModel,
    Loads,
    PlanarArm,
    Plane,
    Region,
    Target,
)
from .noise import NoiseModel
from .paper import BUILTIN_ROBOTS, paper_arm

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover - exercised on Python 3.10 only
    import tomli as tomllib

__all__ = [
    "BUILTIN_ROBOTS",
    "CALIBRATION_FORMAT",
    "DEFAULT_ROBOT",
    "INSTRUMENT_RANGE",
    "JOINT_SIGMA_MAX_DEG",
    "LIMIT_TOLERANCE_DEG",
    "LINK_LENGTH_RANGE_MM",
    "RADIAN_LIMIT_BOUND",
    "REACH_MARGIN",
    "SIGMA_RANGE_MM",
    "STDIO",
    "Measurements",
    "OutputFolder",
    "Program",
    "RobotSpec",
    "arm_for_measurements",
    "atomic_write",
    "check_outputs",
    "format_measurements_csv",
    "format_plan_csv",
    "format_program_csv",
    "load_robot",
    "load_truth",
    "read_calibration",
    "read_measurements",
    "read_plan",
    "read_program",
    "robot_to_dict",
    "unknown_parameter",
    "write_folder",
]

#: Instrument noise accepted (1 std, mm): from a nanometre to a metre.  Beyond it the
#: value is a unit mistake, and its square under- or overflows in the covariance.
SIGMA_RANGE_MM = (1e-6, 1e3)

#: Link lengths accepted (mm): from a micrometre to 10 km.
LINK_LENGTH_RANGE_MM = (1e-3, 1e7)

#: Encoder noise accepted (1 std, deg): 0 to 10 deg.  An encoder that reads a joint
#: worse than 10 deg is no encoder; such a value is a unit mistake (mdeg, arcsec).
JOINT_SIGMA_MAX_DEG = 10.0

#: Joint limits whose every value lies within this many "degrees" (2 pi, rounded up so
#: that written-out radians such as 6.2832 count) look like radians: a real joint
#: confined to +-6.3 deg cannot move enough to be calibrated, while radians limits of
#: any revolute joint lie within +-2 pi.  Such limits give a ``limits-radians`` warning.
RADIAN_LIMIT_BOUND = 6.3

#: How far (deg) a *measured* joint angle may lie beyond a joint limit and still be
#: accepted, with a ``beyond-limits`` warning.  Limits constrain plans, not what the
#: arm really did: a reading past a limit by encoder noise, overshoot or a soft limit
#: set inside the hard stop is a few tenths of a degree.  Beyond 2 deg (twice the
#: largest joint offset PRODUCT.md expects, about a degree) the file or the robot's
#: limits are wrong, and the reading stays an error.
LIMIT_TOLERANCE_DEG = 2.0

#: A measured tip farther than ``(1 + REACH_MARGIN)`` times the arm's reach (the sum of
#: its link lengths) from the base is an error: no arm whose links deviate by less than
#: 10 % (the ``large-deviation`` bound of :mod:`armcal.plausibility`) gets there.
REACH_MARGIN = 0.1

#: An instrument sees an arm from at most this many reaches away (a laser tracker a
#: few metres from a sub-metre arm): a point beyond the reach but within it may be
#: instrument-frame data without a base offset, one farther is a wrong value or unit.
INSTRUMENT_RANGE = 100.0

#: The robot used when a command is given none.
DEFAULT_ROBOT = "paper-4link"

#: Largest magnitude accepted in a CSV field (1000 km in mm): larger values are unit
#: mistakes or corrupt data, and their squares would overflow in the least squares.
MAX_ABS_VALUE = 1e9

#: A file path as the functions here take it.
PathArg = str | os.PathLike[str]


_JOINT_COLUMN = re.compile(r"^q([1-9][0-9]{0,3})_deg$")  # up to 9999 joints
#: A column with a known stem and another unit suffix (``q1_rad``, ``x_m``).
_UNIT_COLUMN = re.compile(r"^(q[1-9][0-9]{0,3}|x|y|z|sigma)_([A-Za-z]+)$")

#: Units a column may be written in that armcal does not read (a unit hint, not a typo).
_OTHER_UNITS = frozenset(
    ("m", "cm", "um", "in", "inch", "inches", "ft", "rad", "mrad", "urad", "grad", "rev")
)

#: The path that means stdin for an input and stdout for an output file.
STDIO = "-"
#: stdin's text, once read (a second reader of ``-`` gets the same text).
_stdin_text: list[str] = []


@dataclass(frozen=True, eq=False)
class RobotSpec:
    """A robot as loaded from a built-in name or a TOML file.

    Attributes
    ----------
    arm : PlanarArm
        The arm, with the file's noise model (``[measurement]``) and fixed
        parameters (``[identify]``).
    default_truth : ndarray, shape (p,), or None
        Deviations (mm, rad) of the built-in virtual robot; None for robot files.
    source : str
        The built-in name or the file path it came from.
    warnings : tuple of ArmcalWarning
        What in the file is accepted but suspicious (``limits-radians``); every
        command prints these.
    elastic : Elastostatic or None
        The ``[elastostatic]`` table: gravity, masses and payload that twist the
        joints (:mod:`armcal.elastostatic`); None for a rigid arm.
    gravity_3d : ndarray, shape (3,), or None
        ``[measurement] gravity``: gravity's direction in the instrument frame,
        for 3-D data.
    """

    arm: PlanarArm
    default_truth: np.ndarray | None
    source: str
    warnings: tuple[ArmcalWarning, ...] = ()
    elastic: Elastostatic | None = None
    gravity_3d: np.ndarray | None = None


@dataclass(frozen=True, eq=False)
class Measurements:
    """Measured poses read from a CSV file.

    Attributes
    ----------
    q : ndarray, shape (m, n)
        Commanded joint angles in rad.
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


# --------------------------------------------------------------------------- helpers


def _fail(path: str | os.PathLike, message: str) -> InputError:
    name = os.fspath(path)
    return InputError(f"{'<stdin>' if name == STDIO else name}: {message}")


def _read_stdin(what: str) -> str:
    if not _stdin_text:
        if sys.stdin is None or sys.stdin.isatty():
            raise _fail(STDIO, f"no {what} piped in; give a file name or pipe one into armcal")
        data = sys.stdin.buffer.read()
        try:
            _stdin_text.append(data.decode("utf-8-sig"))
        except UnicodeDecodeError:
            raise _fail(STDIO, f"is not UTF-8 text; expected a {what} file") from None
    return _stdin_text[0]


def _read_text(path: str | os.PathLike, what: str) -> str:
    if os.fspath(path) == STDIO:
        return _read_stdin(what)
    try:
        return Path(path).read_text(encoding="utf-8-sig")
    except FileNotFoundError:
        raise _fail(path, f"{what} file not found") from None
    except IsADirectoryError:
        raise _fail(path, f"is a directory, expected a {what} file") from None
    except UnicodeDecodeError:
        raise _fail(path, f"is not UTF-8 text; expected a {what} file") from None
    except OSError as exc:
        raise _fail(path, f"cannot read: {exc.strerror}") from None


def _umask() -> int:
    umask = os.umask(0o022)  # the only portable way to read the umask
    os.umask(umask)
    return umask


def _file_mode(target: Path) -> int:
    """Permissions for ``target``: kept if it exists, else what ``open()`` would give.

    ``mkstemp`` creates files readable by the owner only (0600).
    """
    if target.exists():
        return target.stat().st_mode & 0o7777
    return 0o666 & ~_umask()


#: File kinds an output must never replace, with the ``stat`` test that finds them.
_SPECIAL_FILES = (
    (stat.S_ISFIFO, "a FIFO (named pipe)"),
    (stat.S_ISCHR, "a character device"),
    (stat.S_ISBLK, "a block device"),
    (stat.S_ISSOCK, "a socket"),
)


def _can_write_in(folder: Path) -> bool:
    return os.access(folder, os.W_OK | os.X_OK)


def _stat(path: Path) -> os.stat_result | None:
    """``os.stat`` (through links), or None when nothing is there."""
    try:
        return path.stat()
    except (FileNotFoundError, NotADirectoryError):
        return None


def _check_output_file(path: PathArg, fix: str = "give another path") -> Path:
    """The regular file a write to ``path`` replaces or makes; InputError if it must not.

    A symbolic link is followed to the file it points to (see :func:`atomic_write`).
    ``fix`` says what to do about a directory or a special file in the way.
    """
    if not os.fspath(path):
        raise InputError("an output file name is empty; give a file name")
    if os.fspath(path).endswith(("/", os.sep)):  # realpath would drop the slash
        raise _fail(path, f"names a folder (it ends with a slash), expected a file; {fix}")
    real = Path(os.path.realpath(path))
    try:
        info = _stat(real)
    except OSError as exc:  # a link loop, a folder without search permission
        raise _fail(path, f"cannot write: {exc.strerror}; {fix}") from None
    if info is not None:
        if stat.S_ISDIR(info.st_mode):
            raise _fail(path, f"is a directory, expected a file; {fix}")
        for test, kind in _SPECIAL_FILES:
            if test(info.st_mode):
                raise _fail(
                    path, f"is {kind}, not a regular file; armcal writes only regular files, {fix}"
                )
    folder = real.parent
    shown = f"folder {os.path.dirname(path) or '.'}"
    if os.path.islink(path):
        shown = f"folder {folder} of the link target"
    if not folder.exists():
        raise _fail(path, f"cannot write: {shown} does not exist; create it first")
    if not folder.is_dir():
        raise _fail(path, f"cannot write: {shown} is not a folder; give another path")
    if not _can_write_in(folder):
        raise _fail(path, f"cannot write: {shown} is not writable; give another path")
    return real


def _check_output_folder(path: PathArg) -> Path:
    """The folder ``path`` (through links), if files can be written into it or it can be made."""
    if not os.fspath(path):
        raise InputError("an output folder name is empty; give a folder name")
    real = Path(os.path.realpath(path))
    try:
        info = _stat(real)
    except OSError as exc:
        raise _fail(path, f"cannot use as the output folder: {exc.strerror}") from None
    if info is not None:
        if not stat.S_ISDIR(info.st_mode):
            raise _fail(path, "is a file, expected a folder; give a folder name (made if missing)")
        if not _can_write_in(real):
            raise _fail(path, "cannot write into the folder: not writable; give another folder")
        return real
    # The nearest existing folder as the user wrote it (through links, as the OS would).
    ancestor = next(parent for parent in Path(path).parents if os.path.lexists(parent))
    if not ancestor.is_dir():
        raise _fail(path, f"cannot make the folder: {ancestor} is a file, not a folder")
    if not _can_write_in(ancestor):
        raise _fail(path, f"cannot make the folder: {ancestor} is not writable")
    return real


def _same_file(real: Path, other: PathArg) -> bool:
    """Whether ``other`` names the file at the resolved path ``real`` (links and ./ included)."""
    if Path(os.path.realpath(other)) == real:
        return True
    try:
        return os.path.samefile(real, other)  # hard links, bind mounts
    except OSError:
        return False


@dataclass(frozen=True)
class OutputFolder:
    """An output folder and the names of the files a command writes into it.

    Attributes
    ----------
    path : str or path
        The folder; made (with its missing parents) when the files are written.
    files : tuple of str
        Names of the files written inside it.
    """

    path: PathArg
    files: tuple[str, ...]


def check_outputs(
    outputs: Mapping[str, PathArg | OutputFolder | None],
    inputs: Mapping[str, PathArg | None] | None = None,
) -> None:
    """Refuse, before any work, outputs that cannot or must not be written.

    A command calls this first, so that a bad output path costs no computing
    and leaves nothing behind.

    Parameters
    ----------
    outputs : mapping
        Option (``"-o"``, ``"--plot"``) to the file it writes, or to an
        :class:`OutputFolder`; None (an option not given) is skipped.
    inputs : mapping, optional
        Option (``"--plan"``) to the file the command reads; None is skipped.

    Raises
    ------
    InputError
        Naming the path, if an output file is a directory or a special file
        (FIFO, device, socket), is in a folder that is missing or not writable,
        is the same file as an input (compared through links, ``./`` and hard
        links), or is given for two outputs; or if an output folder is a file
        or cannot be made.

    Examples
    --------
    >>> check_outputs({"-o": "."})
    Traceback (most recent call last):
    ...
    armcal.errors.InputError: .: is a directory, expected a file; give -o another file name
    """
    # (option that writes it, path as given, resolved path, what to do if it clashes)
    files: list[tuple[str, str, Path, str]] = []
    for option, output in outputs.items():
        if isinstance(output, OutputFolder):
            folder = _check_output_folder(output.path)
            if folder.is_dir():  # files already there must be replaceable
                fix = f"move it away or give {option} another folder"
                for name in output.files:
                    path = os.path.join(os.fspath(output.path), name)
                    files.append((option, path, _check_output_file(path, fix), fix))
        elif output is not None and os.fspath(output) == STDIO:
            continue  # stdout: the command checks that it is the only one
        elif output is not None:
            fix = f"give {option} another file name"
            files.append((option, os.fspath(output), _check_output_file(output, fix), fix))
    for k, (option, path, real, fix) in enumerate(files):
        for input_option, source in (inputs or {}).items():
            if source is not None and _same_file(real, source):
                raise _fail(
                    path,
                    f"is the input {input_option} {os.fspath(source)}; writing it would "
                    f"destroy the input; {fix}",
                )
        for other_option, other, other_real, _ in files[:k]:
            if other_real == real:
                raise _fail(
                    path,
                    f"given for two outputs ({other_option} {other} and {option} {path}); "
                    "give each its own file name",
                )


def atomic_write(path: PathArg, content: str | bytes | Callable[[BinaryIO], None]) -> None:
    """Write ``content`` to ``path`` through a temporary file and a rename.

    The temporary file is made next to the file it replaces and renamed over it
    only once complete, so a failed or interrupted write leaves the old file
    (or nothing) and no temporary file.  An existing file keeps its
    permissions; a new one gets ``0666`` minus the umask.

    A symbolic link is written through, as a shell's ``>`` would: the file it
    points to (at the end of the chain of links; made if missing) is replaced
    atomically and the link is kept.  A directory or a special file (FIFO,
    character or block device, socket) is never replaced.

    Parameters
    ----------
    path : str or path
        Target file; its folder must exist.  An existing file is replaced.
        :data:`STDIO` (``-``) writes to stdout instead.
    content : str, bytes or callable
        UTF-8 text, bytes, or a function that writes bytes to the open binary
        handle (e.g. ``lambda handle: fig.savefig(handle, format="png")``).

    Raises
    ------
    InputError
        If the folder does not exist or is not writable, or ``path`` is a
        directory or a special file.
    """
    if os.fspath(path) == STDIO:
        if isinstance(content, str):
            sys.stdout.write(content)
        elif isinstance(content, bytes):
            sys.stdout.flush()
            sys.stdout.buffer.write(content)
        else:
            sys.stdout.flush()
            content(sys.stdout.buffer)
        sys.stdout.flush()
        return
    target = _check_output_file(path)
    try:
        fd, tmp = tempfile.mkstemp(prefix=f".{target.name}.", suffix=".tmp", dir=target.parent)
    except OSError as exc:
        raise _fail(path, f"cannot write: {exc.strerror}") from None
    try:
        with os.fdopen(fd, "wb") as handle:
            if isinstance(content, str):
                handle.write(content.encode("utf-8"))
            elif isinstance(content, bytes):
                handle.write(content)
            else:
                content(handle)
        os.chmod(tmp, _file_mode(target))
        os.replace(tmp, target)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise


def _move_into_place(staged: Path, path: Path) -> None:
    """Replace ``path`` (through links) by the complete file ``staged``, keeping its mode."""
    target = _check_output_file(path)
    os.chmod(staged, _file_mode(target))
    try:
        os.replace(staged, target)
    except OSError as exc:
        if exc.errno != errno.EXDEV:
            raise
        atomic_write(target, staged.read_bytes())  # a link into another file system


def write_folder(path: PathArg, files: Mapping[str, str | Callable[[Path], None]]) -> Path:
    """Write ``files`` into the folder ``path``: every file complete, or nothing new.

    Every file is first written into a hidden temporary folder.  A new folder
    (with any missing parent) then appears by one rename, once every file is
    complete; in an existing folder the files are renamed into place one by one
    (as :func:`atomic_write`: through links, keeping modes) and other files
    there are left alone.  On a failure or an interrupt before that, the
    temporary folder is removed and nothing is left behind.

    Parameters
    ----------
    path : str or path
        The output folder; links are followed.
    files : mapping
        File name to UTF-8 text, or to a function that writes the file at the
        path it is given (e.g. ``lambda target: save_figure(fig, target)``).

    Returns
    -------
    Path
        ``path``.

    Raises
    ------
    InputError
        If ``path`` is a file or cannot be made, or holds a file of one of the
        names that must not be replaced (see :func:`check_outputs`).
    """
    folder = _check_output_folder(path)
    exists = folder.is_dir()
    top = folder  # the outermost folder to make
    while not exists and not os.path.lexists(top.parent):
        top = top.parent
    stage = Path(
        tempfile.mkdtemp(
            prefix=".armcal-" if exists else f".{top.name}.",
            suffix=".tmp",
            dir=folder if exists else top.parent,
        )
    )
    try:
        inner = stage if exists else stage / folder.relative_to(top)
        inner.mkdir(parents=True, exist_ok=True)
        for name, content in files.items():
            if isinstance(content, str):
                atomic_write(inner / name, content)
            else:
                content(inner / name)
        if exists:
            for name in files:
                _move_into_place(inner / name, folder / name)
        else:
            os.chmod(stage, 0o777 & ~_umask())  # mkdtemp makes it 0700
            if os.path.lexists(top):
                raise _fail(path, f"cannot make the folder: {top} appeared while armcal ran")
            os.rename(stage, top)
    except BaseException:
        shutil.rmtree(stage, ignore_errors=True)
        raise
    if exists:
        shutil.rmtree(stage, ignore_errors=True)
    return Path(path)


def _suggest(key: str, allowed: Sequence[str]) -> str:
    """``did you mean 'X'? `` for the closest of ``allowed`` (case aside), else ``""``."""
    lower = {name.lower(): name for name in allowed}
    close = difflib.get_close_matches(key.lower(), list(lower), n=1)
    return f"did you mean '{lower[close[0]]}'? " if close else ""


def _check_keys(
    path, table: dict, allowed: Sequence[str], where: str = "", *, robot: bool = True
) -> None:
    """Refuse a key of ``table`` not in ``allowed``; a robot file's hint names its table."""
    for key in table:
        if key not in allowed:
            hint = (_misplaced(key, where) if robot else "") or _suggest(key, allowed)
            raise _fail(
                path, f"unknown key '{where}{key}': {hint}allowed keys are {', '.join(allowed)}"
            )


def _misplaced(key: str, where: str) -> str:
    """A hint when a robot-file ``key`` belongs in another table than ``where``."""
    home = table_of(key)
    if home is None or home == where.rstrip("."):
        return ""
    if home:
        return f"it belongs in the [{home}] table (write it under a [{home}] line); "
    return (
        f"it belongs at the top level: move it above the first [table] line (a key after "
        f"[{where.rstrip('.')}] is part of that table); "
    )


def _number(path, value: Any, key: str) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise _fail(path, f"key '{key}': expected a number, got {value!r}")
    try:
        number = float(value)
    except OverflowError:
        number = math.inf
    if not math.isfinite(number) or abs(number) > MAX_ABS_VALUE:
        raise _fail(path, f"key '{key}': expected a finite number within ±{MAX_ABS_VALUE:g}")
    return number


def _numbers(path, value: Any, key: str, count: int | None = None) -> list[float]:
    if not isinstance(value, list):
        raise _fail(path, f"key '{key}': expected a list of numbers, got {value!r}")
    if count is not None and len(value) != count:
        raise _fail(path, f"key '{key}': expected {count} numbers, got {len(value)}")
    return [_number(path, v, f"{key}[{i}]") for i, v in enumerate(value)]


def _load_toml(path, what: str) -> dict:
    text = _read_text(path, what)
    try:
        return tomllib.loads(text)
    except (ValueError, RecursionError) as exc:  # TOMLDecodeError, or digits/nesting limits
        raise _fail(path, f"invalid TOML: {exc}") from None


# --------------------------------------------------------------------------- robots


def _builtin(name: str) -> RobotSpec:
    arm, truth = paper_arm(BUILTIN_ROBOTS[name])
    return RobotSpec(arm, truth, name)


def _parse_region(path, region: Any) -> Region:
    key = "measurement.region"
    if not isinstance(region, dict):
        raise _fail(path, f"key '{key}': expected a table such as {{ kind = \"annulus\", ... }}")
    kind = region.get("kind")
    if kind == "annulus":
        _check_keys(path, region, ["kind", "center_mm", "r_min_mm", "r_max_mm"], f"{key}.")
        center = _numbers(path, region.get("center_mm", [0.0, 0.0]), f"{key}.center_mm", 2)
        r_min = _number(path, region.get("r_min_mm", 0.0), f"{key}.r_min_mm")
        if "r_max_mm" not in region:
            raise _fail(path, f"key '{key}': an annulus needs r_max_mm")
        r_max = _number(path, region["r_max_mm"], f"{key}.r_max_mm")
        if not 0 <= r_min < r_max:
            raise _fail(path, f"key '{key}': need 0 <= r_min_mm < r_max_mm, got {r_min}, {r_max}")
        return Annulus((center[0], center[1]), r_min, r_max)
    if kind == "box":
        _check_keys(path, region, ["kind", "x_mm", "y_mm"], f"{key}.")
        bounds = []
        for axis in ("x_mm", "y_mm"):
            if axis not in region:
                raise _fail(path, f"key '{key}': a box needs {axis} = [lo, hi]")
            lo, hi = _numbers(path, region[axis], f"{key}.{axis}", 2)
            if not lo < hi:
                raise _fail(path, f"key '{key}.{axis}': need lo < hi, got [{lo}, {hi}]")
            bounds.append((lo, hi))
        return Box(bounds[0], bounds[1])
    raise _fail(path, f'key \'{key}.kind\': expected "annulus" or "box", got {kind!r}')


def _sigma_value(path, value: Any, key: str) -> float:
    """An instrument noise (1 std, mm) within :data:`SIGMA_RANGE_MM`."""
    sigma = _number(path, value, key)
    low, high = SIGMA_RANGE_MM
    if not low <= sigma <= high:
        raise _fail(
            path,
            f"key '{key}': must be between {low:g} and {high:g} mm, got {sigma:g}; "
            "check the unit (mm)",
        )
    return sigma


def _instrument_covariance(path, meas: dict) -> np.ndarray | None:
    """``[measurement] sigma_mm`` (a number or ``[sx, sy]``) or ``covariance_mm2``, in mm^2."""
    if "sigma_mm" in meas and "covariance_mm2" in meas:
        raise _fail(
            path,
            "keys 'measurement.sigma_mm' and 'measurement.covariance_mm2' both give the "
            "instrument noise; keep one",
        )
    if "sigma_mm" in meas:
        key = "measurement.sigma_mm"
        raw = meas["sigma_mm"]
        if isinstance(raw, list):
            if len(raw) != 2:
                raise _fail(
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
            raise _fail(
                path, f"key '{key}': expected a 2 x 2 matrix [[a, b], [b, c]] in mm^2, got {raw!r}"
            )
        cov = np.array([_numbers(path, row, f"{key}[{i}]", 2) for i, row in enumerate(raw)])
        a, b, c, d = cov[0, 0], cov[0, 1], cov[1, 0], cov[1, 1]
        if b != c:
            raise _fail(
                path,
                f"key '{key}': must be symmetric (b = c), got [[{a:g}, {b:g}], [{c:g}, {d:g}]]",
            )
        if not (a > 0 and d > 0 and a * d - b * c > 0):
            raise _fail(
                path,
                f"key '{key}': must be positive definite (a > 0, c > 0, a c > b^2), got "
                f"[[{a:g}, {b:g}], [{c:g}, {d:g}]]",
            )
        low, high = SIGMA_RANGE_MM
        for i in (0, 1):
            if not low <= math.sqrt(cov[i, i]) <= high:
                raise _fail(
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
            raise _fail(
                path, f"key '{key}': expected one number or {n} (one per joint), got {len(raw)}"
            )
        values = [_number(path, v, f"{key}[{j}]") for j, v in enumerate(raw)]
        names = [f"{key}[{j}]" for j in range(n)]
    else:
        values, names = [_number(path, raw, key)], [key]
    for name, value in zip(names, values, strict=True):
        if not 0 <= value <= JOINT_SIGMA_MAX_DEG:
            raise _fail(
                path,
                f"key '{name}': encoder noise must be between 0 and {JOINT_SIGMA_MAX_DEG:g} deg, "
                f"got {value:g}; check the unit (deg)",
            )
    return np.radians(values)


def _fixed_parameters(path, table: Any, names: Sequence[str], arm_name: str) -> list[str]:
    """``[identify] fixed = [...]`` or ``free = [...]`` as the list of fixed names."""
    if not isinstance(table, dict):
        raise _fail(path, "key 'identify': expected a table [identify]")
    if "fixed" in table and "free" in table:
        raise _fail(
            path,
            "keys 'identify.fixed' and 'identify.free' both say what is identified; keep one "
            "(free = [...] fixes every other parameter)",
        )
    if not table:
        return []
    key = "fixed" if "fixed" in table else "free"
    raw = table[key]
    if not isinstance(raw, list) or not all(isinstance(v, str) for v in raw):
        raise _fail(path, f"key 'identify.{key}': expected a list of parameter names, got {raw!r}")
    for name in raw:
        if name not in names:
            raise _fail(path, f"key 'identify.{key}': {unknown_parameter(name, names, arm_name)}")
    chosen = set(raw)
    fixed = [nm for nm in names if (nm in chosen) == (key == "fixed")]
    if len(fixed) == len(names):
        raise _fail(
            path,
            f"key 'identify.{key}': every parameter would be fixed; leave at least one free",
        )
    return fixed


def unknown_parameter(name: str, names: Sequence[str], arm_name: str) -> str:
    """The message for a parameter name the arm does not have: the valid names, and a hint.

    Examples
    --------
    >>> unknown_parameter("x0", ("dl1", "dq1"), "arm")
    "unknown parameter 'x0'; the parameters of arm are dl1, dq1 (x0 and y0 exist only with base_offset = true)"
    """  # noqa: E501
    hint = _suggest(name, names)
    message = (
        f"unknown parameter '{name}'; {hint}the parameters of {arm_name} are {', '.join(names)}"
    )
    if name in ("x0", "y0"):
        message += " (x0 and y0 exist only with base_offset = true)"
    return message


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


def load_robot(name_or_path: str | os.PathLike) -> RobotSpec:
    """Load a built-in robot by name or a robot TOML file.

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
    >>> load_robot("paper-4link").arm.link_lengths.tolist()
    [260.0, 180.0, 120.0, 100.0]
    """
    key = os.fspath(name_or_path)
    if key in BUILTIN_ROBOTS:
        return _builtin(key)
    path = Path(key)
    if key != STDIO and not path.exists():
        raise InputError(
            f"{key}: robot is neither a built-in ({', '.join(BUILTIN_ROBOTS)}) "
            f"nor an existing file; {_suggest(key, list(BUILTIN_ROBOTS))}"
            "give a built-in's name or the path of a robot TOML file"
        )
    data = _load_toml(path, "robot")
    _check_keys(path, data, allowed_keys(""))
    for table in ("measurement", "identify", "elastostatic"):  # [targets] holds labels
        if isinstance(data.get(table), dict):
            _check_keys(path, data[table], allowed_keys(table), f"{table}.")
    if "link_lengths_mm" not in data:
        raise _fail(path, "missing key 'link_lengths_mm' (a list of link lengths in mm)")
    lengths = _numbers(path, data["link_lengths_mm"], "link_lengths_mm")
    if not lengths:
        raise _fail(path, "key 'link_lengths_mm': needs at least one link")
    low, high = LINK_LENGTH_RANGE_MM
    for i, length in enumerate(lengths):
        if not low <= length <= high:
            raise _fail(
                path,
                f"key 'link_lengths_mm[{i}]': link {i + 1} length must be between {low:g} and "
                f"{high:g} mm, got {length:g}; check the unit (mm)",
            )
    n = len(lengths)
    name = data.get("name", "robot" if key == STDIO else path.stem)
    if not isinstance(name, str) or not name.strip():
        raise _fail(path, f"key 'name': expected a non-empty string, got {name!r}")
    warnings: list[ArmcalWarning] = []
    limits = None
    if "joint_limits_deg" in data:
        raw = data["joint_limits_deg"]
        if not isinstance(raw, list) or len(raw) != n:
            raise _fail(
                path,
                f"key 'joint_limits_deg': expected {n} pairs [lo, hi], one per joint, got {raw!r}",
            )
        pairs = []
        for j, pair in enumerate(raw):
            lo, hi = _numbers(path, pair, f"joint_limits_deg[{j}]", 2)
            if not lo < hi:
                raise _fail(path, f"key 'joint_limits_deg[{j}]': need lo < hi, got [{lo}, {hi}]")
            pairs.append((lo, hi))
        limits = [(math.radians(lo), math.radians(hi)) for lo, hi in pairs]
        radians = _radian_limits_warning(path, pairs)
        if radians is not None:
            warnings.append(radians)
    base_offset = data.get("base_offset", False)
    if not isinstance(base_offset, bool):
        raise _fail(path, f"key 'base_offset': expected true or false, got {base_offset!r}")
    noise, region, gravity_3d = None, None, None
    if "measurement" in data:
        meas = data["measurement"]
        if not isinstance(meas, dict):
            raise _fail(path, "key 'measurement': expected a table [measurement]")
        if "gravity" in meas:
            gravity_3d = np.array(_numbers(path, meas["gravity"], "measurement.gravity", 3))
            if not np.any(gravity_3d):
                raise _fail(
                    path,
                    "key 'measurement.gravity': needs a non-zero direction in the instrument "
                    "frame, e.g. [0, 0, -1] for a levelled tracker",
                )
        covariance = _instrument_covariance(path, meas)
        joint_sigma = _joint_sigma(path, meas, n)
        if joint_sigma is not None and covariance is None:
            raise _fail(
                path,
                "key 'measurement.joint_sigma_deg': encoder noise needs the instrument noise "
                "too; add sigma_mm (or covariance_mm2) to [measurement]",
            )
        if covariance is not None:
            noise = NoiseModel(covariance, joint_sigma)
        if "region" in meas:
            region = _parse_region(path, meas["region"])
    mapping = _joint_map(path, data["joint_map"], n) if "joint_map" in data else None
    offsets = None
    if "joint_offsets_deg" in data:
        offsets = np.radians(_numbers(path, data["joint_offsets_deg"], "joint_offsets_deg", n))
    targets = _targets(path, data["targets"], lengths[-1]) if "targets" in data else ()
    try:
        structure = PlanarArm(lengths, base_offset=base_offset, joint_map=mapping, targets=targets)
    except ValueError as exc:
        raise _fail(path, str(exc)) from None
    names = structure.param_names
    fixed = _fixed_parameters(path, data["identify"], names, name) if "identify" in data else []
    try:
        arm = PlanarArm(
            lengths,
            limits,
            base_offset=base_offset,
            name=name,
            noise=noise,
            region=region,
            fixed=fixed,
            joint_map=mapping,
            targets=targets,
            joint_offsets=offsets,
        )
    except ValueError as exc:  # every value was checked above; this names what is left
        raise _fail(path, str(exc)) from None
    elastic = _elastostatic(path, data["elastostatic"], n) if "elastostatic" in data else None
    return RobotSpec(arm, None, key, tuple(warnings), elastic, gravity_3d)


def _elastostatic(path, table: Any, n: int) -> Elastostatic:
    """``[elastostatic]``: ``gravity_xy``, ``link_masses_kg``, ``com_fraction``, ``payload_kg``."""
    if not isinstance(table, dict):
        raise _fail(path, "key 'elastostatic': expected a table [elastostatic]")
    gravity = None
    if "gravity_xy" in table:
        gravity = _numbers(path, table["gravity_xy"], "elastostatic.gravity_xy", 2)
    masses = None
    if "link_masses_kg" in table:
        masses = _numbers(path, table["link_masses_kg"], "elastostatic.link_masses_kg", n)
    fraction: float | list[float] = 0.5
    if "com_fraction" in table:
        raw = table["com_fraction"]
        key = "elastostatic.com_fraction"
        fraction = (
            _numbers(path, raw, key, n) if isinstance(raw, list) else _number(path, raw, key)
        )
    payload = 0.0
    if "payload_kg" in table:
        payload = _number(path, table["payload_kg"], "elastostatic.payload_kg")
    try:
        return Elastostatic.create(
            n, gravity_xy=gravity, link_masses_kg=masses, com_fraction=fraction, payload_kg=payload
        )
    except ArmcalError as exc:
        raise _fail(path, f"[elastostatic]: {exc}") from None


def _joint_map(path, value: Any, n: int) -> np.ndarray:
    """``joint_map``: ``n`` rows of ``n`` numbers, ``theta = M q``."""
    if not isinstance(value, list) or len(value) != n:
        raise _fail(
            path,
            f"key 'joint_map': expected {n} rows of {n} numbers (theta = M q), got {value!r}",
        )
    rows = [_numbers(path, row, f"joint_map[{i}]", n) for i, row in enumerate(value)]
    return np.array(rows)  # PlanarArm judges it (invertible; the last column with targets)


def _targets(path, table: Any, last_length: float) -> tuple[Target, ...]:
    """``[targets]``: ``label = { length_mm = ..., angle_deg = ... }`` per target."""
    if not isinstance(table, dict) or not table:
        raise _fail(
            path,
            "key 'targets': expected a table [targets] with one entry per target, e.g. "
            "A = { length_mm = 100.0, angle_deg = 0.0 }",
        )
    targets = []
    for label, entry in table.items():
        key = f"targets.{label}"
        if not isinstance(entry, dict):
            raise _fail(path, f"key '{key}': expected {{ length_mm = ..., angle_deg = ... }}")
        _check_keys(path, entry, ["length_mm", "angle_deg"], f"{key}.")
        length = _number(path, entry.get("length_mm", last_length), f"{key}.length_mm")
        angle = _number(path, entry.get("angle_deg", 0.0), f"{key}.angle_deg")
        low, high = LINK_LENGTH_RANGE_MM
        if not low <= length <= high:
            raise _fail(
                path,
                f"key '{key}.length_mm': the distance from the last joint to the target must be "
                f"between {low:g} and {high:g} mm, got {length:g}",
            )
        try:
            targets.append(Target(str(label), length, math.radians(angle)))
            PlanarArm([1.0], targets=targets)  # label rules
        except ValueError as exc:
            raise _fail(path, f"key '{key}': {exc}") from None
    return tuple(targets)


def load_truth(path: str | os.PathLike, arm: PlanarArm) -> np.ndarray:
    """Read a truth TOML (``dl_mm``, ``dq_deg``, optional ``base_mm``) for ``arm``.

    Returns
    -------
    ndarray, shape (p,)
        User deviations in mm and rad.
    """
    data = _load_toml(path, "truth")
    _check_keys(path, data, allowed_keys("", TRUTH_KEYS), robot=False)
    n, k = arm.n_joints, arm.n_links
    counts = f"{n} numbers, one per joint" + (
        f", or {k}: one per link vector (the last link once per target)" if k != n else ""
    )
    for key in ("dl_mm", "dq_deg"):
        if key not in data:
            raise _fail(path, f"missing key '{key}' ({counts})")
    dl = _numbers(path, data["dl_mm"], "dl_mm")
    dq = _numbers(path, data["dq_deg"], "dq_deg")
    for key, values in (("dl_mm", dl), ("dq_deg", dq)):
        if len(values) not in (n, k):
            raise _fail(path, f"key '{key}': expected {counts}, got {len(values)}")
    base = None
    if "base_mm" in data:
        if not arm.base_offset:
            raise _fail(
                path,
                f"key 'base_mm': robot {arm.name} has base_offset = false; "
                "set base_offset = true in the robot file or remove base_mm",
            )
        base = _numbers(path, data["base_mm"], "base_mm", 2)
    params = arm.params_from_display(dl, dq, base)
    for i, v in enumerate(params[:k]):
        if arm.link_nominal[i] + v <= 0:
            raise _fail(path, f"key 'dl_mm': link {arm.link_names[i]} would have length <= 0")
    return params


#: Truth keys of the compliance parameters (:mod:`armcal.elastostatic`), by kind.
COMPLIANCE_TRUTH_KEYS = {"k": "k_urad_per_Nm", "c": "c_mdeg_per_m"}


def load_compliance_truth(path: str | os.PathLike, model: CompliantArm) -> np.ndarray:
    """The compliance of a truth TOML (``k_urad_per_Nm``, ``c_mdeg_per_m``), internal units.

    Returns
    -------
    ndarray, shape (P,)
        In the order of ``model.compliance_names``: rad/(N m) for ``k``, rad/m for ``c``.
    """
    data = _load_toml(path, "truth")
    n = model.arm.n_joints
    values = []
    for kind in dict.fromkeys(model.kinds):
        key = COMPLIANCE_TRUTH_KEYS[kind]
        if key not in data:
            raise _fail(
                path,
                f"missing key '{key}' ({n} numbers): the robot's [elastostatic] model has "
                f"parameters {', '.join(model.compliance_names)}",
            )
        values += _numbers(path, data[key], key, n)
    return np.array(values) / model.compliance_scale


# --------------------------------------------------------------------------- CSV


def _joint_names(n: int) -> list[str]:
    return [f"q{j}_deg" for j in range(1, n + 1)]


@dataclass(frozen=True, eq=False)
class _Table:
    """A validated CSV: numbers in file units and the optional columns found."""

    values: np.ndarray  # (m, n + len(numeric)): joint columns (deg), then the numeric ones
    texts: dict[str, list[str]]  # optional text columns present
    numbers: dict[str, np.ndarray]  # optional numeric columns present
    lines: list[int]  # file line of every data row
    beyond: list[tuple[int, int, float, float]]  # (row index, joint, value deg, by deg)


def _parse_number(path, where: str, name: str, field: str, decimal_comma: bool = False) -> float:
    try:
        value = float(field.replace(",", ".", 1) if decimal_comma else field)
    except ValueError:
        raise _fail(path, f"{where}, column {name}: {field!r} is not a number") from None
    if not math.isfinite(value):
        raise _fail(path, f"{where}, column {name}: {field!r} is not a finite number")
    if abs(value) > MAX_ABS_VALUE:
        raise _fail(
            path,
            f"{where}, column {name}: {field} is beyond ±{MAX_ABS_VALUE:g}; "
            "check the unit (mm, deg)",
        )
    return value


def _records(path, kept: list[tuple[int, str]], delimiter: str) -> list[tuple[int, list[str]]]:
    """CSV records of the ``(file line, text)`` lines kept, each with the file line it starts on.

    A quoted field may span lines; a record is numbered by its first line.
    """
    reader = csv.reader((raw + "\n" for _, raw in kept), delimiter=delimiter)
    records = []
    start = 0  # index in ``kept`` of the next record's first line
    try:
        for row in reader:
            records.append((kept[start][0], row))
            start = reader.line_num
    except csv.Error as exc:  # a field beyond the csv module's size limit, a NUL byte
        line = kept[min(start, len(kept) - 1)][0]
        raise _fail(path, f"line {line}: not a CSV row ({exc}); check the file") from None
    return records


def _shown(text: str, limit: int = 40) -> str:
    """``text`` quoted for a message, cut to ``limit`` characters."""
    return repr(text if len(text) <= limit else text[:limit] + "...")


def _delimiter(header: str) -> str:
    """The separator of a CSV whose header line is ``header``: a comma, else ';' or a tab."""
    if "," not in header:
        for candidate in (";", "\t"):
            if candidate in header:
                return candidate
    return ","


def _unit_hint(name: str, allowed: Sequence[str]) -> str:
    """What to do about an ``allowed`` column in another unit (``q1_rad``, ``x_m``), else ``""``.

    A unit that is a typo of the right one (``q1_dge``) gets a did-you-mean instead.
    """
    match = _UNIT_COLUMN.match(name)
    if match is None:
        return ""
    stem, unit = match.groups()
    right = "deg" if stem.startswith("q") else "mm"
    fixed = f"{stem}_{right}"
    if fixed not in allowed and not (stem.startswith("q") and _JOINT_COLUMN.match(fixed)):
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
    return f"positions are read in mm: name the column {fixed} and give millimetres; "


def _read_csv(path, arm: PlanarArm, what: str, limit_tol_deg: float = 0.0) -> _Table:
    """Validate a CSV of kind ``what`` (a key of :data:`armcal.formats.COLUMNS`).

    Its joint columns and required columns must be there; its optional text and
    numeric columns may be.  A joint angle beyond its limit by at most
    ``limit_tol_deg`` is accepted and listed in ``beyond``; farther is an error.
    """
    numeric, optional, optional_numeric = reader_columns(what)
    expected = _joint_names(arm.n_joints) + list(numeric)
    extras = list(optional) + list(optional_numeric)
    layout = ",".join(expected) + "".join(f" [,{c}]" for c in extras)
    text = _read_text(path, what)
    # Lines that start with '#' are comments (instrument exports often begin with some).
    kept = [
        (line, raw)
        for line, raw in enumerate(text.splitlines(), start=1)
        if not raw.lstrip().startswith("#")
    ]
    if not any(raw.strip() for _, raw in kept):
        raise _fail(path, f"file is empty; expected a header line {layout}")
    header_raw = next(raw for _, raw in kept if raw.strip())
    delimiter = _delimiter(header_raw)
    rows = [
        (line, row) for line, row in _records(path, kept, delimiter) if any(f.strip() for f in row)
    ]
    if not rows:
        raise _fail(path, f"file has no header, only empty fields; expected {layout}")
    header_line, header = rows[0]
    header = [h.strip() for h in header]
    for col, name in enumerate(header, start=1):
        if not name:
            raise _fail(path, f"line {header_line}: header column {col} is empty")
        if header.count(name) > 1:
            raise _fail(path, f"line {header_line}: duplicate column '{name}'; keep one")
    for name in header:
        if name not in expected and name not in extras and not _JOINT_COLUMN.match(name):
            raise _fail(
                path,
                f"line {header_line}: unknown column {_shown(name)}: "
                f"{_unit_hint(name, expected + extras) or _suggest(name, expected + extras)}"
                f"expected {layout}",
            )
    joints = sorted(int(m.group(1)) for h in header if (m := _JOINT_COLUMN.match(h)))
    if joints and joints != list(range(1, len(joints) + 1)):
        raise _fail(
            path,
            f"line {header_line}: joint columns must be q1_deg..qN_deg without gaps, got "
            f"{', '.join(f'q{j}_deg' for j in joints)}",
        )
    if joints and len(joints) != arm.n_joints:
        raise _fail(
            path,
            f"has {len(joints)} joint columns (q1_deg..q{len(joints)}_deg) but robot "
            f"{arm.name} has {arm.n_joints} joints; pass the matching --robot or fix the header",
        )
    for name in expected:
        if name not in header:
            raise _fail(path, f"line {header_line}: missing column '{name}'; expected {layout}")
    data_rows = rows[1:]
    if not data_rows:
        raise _fail(
            path, f"has a header but no poses; add one row per pose after line {header_line}"
        )
    index = {name: header.index(name) for name in expected}
    values = np.empty((len(data_rows), len(expected)))
    texts: dict[str, list[str]] = {name: [] for name in optional if name in header}
    present = [name for name in optional_numeric if name in header]
    numbers = {name: np.empty(len(data_rows)) for name in present}
    for r, (line, row) in enumerate(data_rows, start=1):
        where = f"row {r} (line {line})"
        if len(row) != len(header):
            raise _fail(
                path,
                f"{where} has {len(row)} fields but the header has {len(header)}; "
                "give every column a value",
            )
        comma = delimiter == ";"  # a semicolon file may write 1,5 for 1.5
        for c, name in enumerate(expected):
            values[r - 1, c] = _parse_number(path, where, name, row[index[name]].strip(), comma)
        for name in present:
            numbers[name][r - 1] = _parse_number(
                path, where, name, row[header.index(name)].strip(), comma
            )
        for name in texts:
            texts[name].append(row[header.index(name)].strip())
    lines = [line for line, _ in data_rows]
    q_deg = values[:, : arm.n_joints]
    limits_deg = np.degrees(arm.joint_limits)
    # Distance beyond the nearer limit (deg), 0 inside; the 1e-9 rad slack of
    # PlanarArm.within_limits keeps a limit written out in the file inside.
    by = np.maximum(limits_deg[:, 0] - q_deg, q_deg - limits_deg[:, 1])
    outside = by > math.degrees(1e-9)
    far = outside & (by > limit_tol_deg)
    if far.any():
        r, j = map(int, np.argwhere(far)[0])
        lo, hi = limits_deg[j]
        fix = "fix the pose or the robot's joint_limits_deg"
        if limit_tol_deg > 0:
            fix = (
                f"readings up to {limit_tol_deg:g} deg beyond a limit are accepted; "
                "check the robot file (joint_limits_deg) and the column"
            )
        raise _fail(
            path,
            f"row {r + 1} (line {lines[r]}), column q{j + 1}_deg: "
            f"{values[r, j]:g} deg is outside joint {j + 1}'s limits [{lo:g}, {hi:g}] deg; {fix}",
        )
    beyond = [
        (int(r), int(j), float(values[r, j]), float(by[r, j])) for r, j in np.argwhere(outside)
    ]
    return _Table(values, texts, numbers, lines, beyond)


def read_plan(path: str | os.PathLike, arm: PlanarArm) -> np.ndarray:
    """Read a plan CSV (header ``q1_deg,...,qn_deg``) for ``arm``.

    Returns
    -------
    ndarray, shape (m, n)
        Joint angles in rad, each within the joint limits.
    """
    q, payload = read_loaded_plan(path, arm)
    if payload is not None:
        raise _fail(
            path,
            f"has a payload_kg column but robot {arm.name} has no [elastostatic] table; "
            "remove the column or add the table to the robot file",
        )
    return q


def read_loaded_plan(
    path: str | os.PathLike, arm: PlanarArm
) -> tuple[np.ndarray, np.ndarray | None]:
    """Read a plan CSV with an optional ``payload_kg`` column (designs with compliance).

    Returns
    -------
    q : ndarray, shape (m, n)
        Joint angles in rad.
    payload : ndarray, shape (m,), or None
        The payload of every pose (kg), when the column is there.
    """
    table = _read_csv(path, arm, "plan")
    payload, _ = _load_columns(path, table)
    return np.radians(table.values), payload


@dataclass(frozen=True, eq=False)
class Program:
    """A robot program's joint commands read from a CSV file.

    Attributes
    ----------
    q : ndarray, shape (m, n)
        Joint commands in rad, within the joint limits.
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


def read_program(path: str | os.PathLike, arm: PlanarArm) -> Program:
    """Read a program CSV: ``q1_deg..qn_deg``; optional ``pose``, ``target`` and load columns.

    Raises
    ------
    InputError
        For a malformed file, a command outside the joint limits or an unknown target.
    """
    table = _read_csv(path, arm, "program")
    targets = table.texts.get("target")
    if targets is not None:
        if not arm.targets:
            raise _fail(
                path,
                f"has a target column but {arm.name} has no targets; remove the column",
            )
        _check_target_labels(path, arm, targets, table.lines)
    labels = table.texts.get("pose")
    payload, force = _load_columns(path, table)
    return Program(
        np.radians(table.values),
        None if labels is None else tuple(labels),
        None if targets is None else tuple(targets),
        payload,
        force,
    )


def format_program_csv(
    q: np.ndarray,
    corrected: np.ndarray,
    labels: Sequence[str] | None = None,
    targets: Sequence[str] | None = None,
) -> str:
    """Program CSV text: ``[pose,]q1_deg..qn_deg[,target],corrected`` (1 or 0 per row)."""
    head = (["pose"] if labels is not None else []) + _joint_names(q.shape[1])
    head += (["target"] if targets is not None else []) + ["corrected"]
    lines = [",".join(head)]
    for i, row in enumerate(q):
        fields = [str(labels[i])] if labels is not None else []
        fields += [_angle_text(v) for v in row]
        fields += [str(targets[i])] if targets is not None else []
        lines.append(",".join([*fields, "1" if corrected[i] else "0"]))
    return "\n".join(lines) + "\n"


def _beyond_limits_warning(path, arm: PlanarArm, beyond) -> ArmcalWarning:
    limits_deg = np.degrees(arm.joint_limits)
    shown = [
        f"row {r + 1} q{j + 1}_deg = {value:g} "
        f"([{limits_deg[j, 0]:g}, {limits_deg[j, 1]:g}], {by:.3g} deg beyond)"
        for r, j, value, by in beyond[:5]
    ]
    more = f" and {len(beyond) - 5} more" if len(beyond) > 5 else ""
    return ArmcalWarning(
        "beyond-limits",
        f"{os.fspath(path)}: {len(beyond)} measured joint angle(s) beyond the robot's limits by "
        f"at most {LIMIT_TOLERANCE_DEG:g} deg, accepted (limits constrain plans, not what the "
        f"arm did): {'; '.join(shown)}{more}; if the arm cannot go there, check the robot "
        "file's joint_limits_deg",
    )


def _check_reach(path, arm: PlanarArm, xy: np.ndarray, lines: list[int]) -> None:
    """Refuse a measured point no arm of this geometry can reach (see :data:`REACH_MARGIN`).

    Without a base offset the base is the instrument's origin, and every tip lies
    within ``reach`` of it.  With one, the base is unknown, but every tip lies
    within ``reach`` of it, so within ``2 reach`` of the data's centroid.
    """
    reach = float(np.sum(arm.link_lengths[:-1]) + np.max(arm.link_nominal[arm.n_joints - 1 :]))
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
    if not arm.base_offset and distance[r] <= INSTRUMENT_RANGE * reach:
        fix += (
            "; if the instrument's origin is not at the arm's base (a laser tracker, a camera), "
            "set base_offset = true in the robot file"
        )
    raise _fail(
        path,
        f"row {r + 1} (line {lines[r]}), column {column}: {xy[r, c]:g} puts the tip "
        f"{distance[r]:.4g} mm {where}, beyond the reach of {arm.name} ("
        f"{'2 x ' if arm.base_offset else ''}{reach:g} mm, +{100 * REACH_MARGIN:g} % for "
        f"deviations: {limit:.4g} mm); {fix}",
    )


def read_measurements(path: str | os.PathLike, arm: PlanarArm) -> Measurements:
    """Read a measurements CSV: ``q1_deg..qn_deg,x_mm,y_mm``, optional ``pose`` and ``sigma_mm``.

    Parameters
    ----------
    path : str or path
    arm : PlanarArm
        The robot measured: its joint count, limits, link lengths, base offset.

    Returns
    -------
    Measurements
        Angles in rad, positions in mm, the data rows, the ``sigma_mm`` column
        (per-row instrument noise, mm) and the ``beyond-limits`` warning.

    Raises
    ------
    InputError
        Naming the file, row and column: a malformed file; a joint angle more
        than :data:`LIMIT_TOLERANCE_DEG` beyond its limit; a ``sigma_mm`` outside
        :data:`SIGMA_RANGE_MM`; a point no arm of this geometry can reach
        (:data:`REACH_MARGIN`).
    """
    table = _read_csv(path, arm, "measurements", limit_tol_deg=LIMIT_TOLERANCE_DEG)
    n = arm.n_joints
    values = table.values
    m = values.shape[0]
    labels = table.texts.get("pose") or [str(i) for i in range(1, m + 1)]
    row_sigma = table.numbers.get("sigma_mm")
    if row_sigma is not None:
        low, high = SIGMA_RANGE_MM
        bad = np.flatnonzero((row_sigma < low) | (row_sigma > high))
        if bad.size:
            r = int(bad[0])
            raise _fail(
                path,
                f"row {r + 1} (line {table.lines[r]}), column sigma_mm: {row_sigma[r]:g} is not "
                f"a noise std between {low:g} and {high:g} mm; check the unit (mm)",
            )
    xy = values[:, n:]
    z = table.numbers.get("z_mm")
    targets = table.texts.get("target")
    if targets is not None:
        _check_target_labels(path, arm, targets, table.lines)
    if z is None:
        _check_reach(path, arm, xy, table.lines)
    else:
        _check_reach(path, arm, np.column_stack([xy, z]), table.lines)
    warnings = []
    if table.beyond:
        warnings.append(_beyond_limits_warning(path, arm, table.beyond))
    payload, force = _load_columns(path, table)
    return Measurements(
        np.radians(values[:, :n]),
        xy,
        tuple(labels),
        rows=tuple(range(1, m + 1)),
        row_sigma=row_sigma,
        warnings=tuple(warnings),
        targets=None if targets is None else tuple(targets),
        z=z,
        payload_kg=payload,
        force_n=force,
    )


def _load_columns(path, table: _Table) -> tuple[np.ndarray | None, np.ndarray | None]:
    """The ``payload_kg`` column (not negative) and the tip force ``(m, 2)`` (a missing axis 0)."""
    payload = table.numbers.get("payload_kg")
    if payload is not None and np.any(payload < 0):
        r = int(np.flatnonzero(payload < 0)[0])
        raise _fail(
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


def _check_target_labels(path, arm: PlanarArm, labels: list[str], lines: list[int]) -> None:
    """Every row names a target, one of the robot file's ``[targets]`` when it has them."""
    known = arm.target_labels
    for r, label in enumerate(labels):
        if not label:
            raise _fail(
                path,
                f"row {r + 1} (line {lines[r]}), column target: empty; name the target "
                "(reflector, marker) every row measured",
            )
        if known and label not in known:
            raise _fail(
                path,
                f"row {r + 1} (line {lines[r]}), column target: {label!r} is not a target of "
                f"{arm.name}: {_suggest(label, known)}the robot file's [targets] has "
                f"{', '.join(known)}",
            )


def arm_for_measurements(arm: PlanarArm, meas: Measurements) -> PlanarArm:
    """The arm to identify from ``meas``: its targets are those measured.

    With a ``target`` column, the targets are the labels measured, in the order
    of the robot file's ``[targets]`` (nominal last link from there) or, without
    one, in the order they first appear (nominal: the last link's length, angle
    0).  With a ``z_mm`` column the base pose in the fitted plane is identified:
    base offset and base rotation (:mod:`armcal.instrument`).
    """
    changes: dict[str, Any] = {}
    if meas.targets is not None:
        seen = list(dict.fromkeys(meas.targets))
        if arm.targets:
            targets = tuple(t for t in arm.targets if t.label in seen)
        else:
            targets = tuple(Target(label, float(arm.link_lengths[-1])) for label in seen)
        if targets != arm.targets:
            changes["targets"] = targets
    elif arm.targets:
        raise InputError(
            f"{arm.name} has targets ({', '.join(arm.target_labels)}) but the measurements have "
            "no target column; add a column 'target' naming the target of every row"
        )
    if meas.z is not None:
        changes.update(base_offset=True, base_rotation=True)
    if not changes:
        return arm
    try:  # the fixed parameters that still exist are carried over
        return arm.replace(**changes)
    except ValueError as exc:
        raise InputError(f"{arm.name}: {exc}") from None


def _angle_text(q_rad: float) -> str:
    # Rounded to 1e-12 deg so an exact 90 deg is written "90.0", not "89.99999999999999".
    return repr(round(math.degrees(q_rad), 12) + 0.0)


def format_plan_csv(q: np.ndarray, payload_kg: np.ndarray | None = None) -> str:
    """Plan CSV text for joint angles ``q`` ``(m, n)`` in rad (and every pose's payload)."""
    head = _joint_names(q.shape[1]) + (["payload_kg"] if payload_kg is not None else [])
    lines = [",".join(head)]
    for i, row in enumerate(q):
        fields = [_angle_text(v) for v in row]
        if payload_kg is not None:
            fields.append(repr(float(payload_kg[i])))
        lines.append(",".join(fields))
    return "\n".join(lines) + "\n"


def format_measurements_csv(
    q: np.ndarray,
    xy: np.ndarray,
    labels: Sequence[str] | None = None,
    targets: Sequence[str] | None = None,
    payload_kg: np.ndarray | None = None,
) -> str:
    """Measurements CSV text; positions are written with full round-trip precision.

    ``xy`` of shape ``(m, 3)`` writes 3-D points (``z_mm``); ``targets`` adds the
    ``target`` column, ``payload_kg`` the payload of every row.
    """
    head = ["pose"] if labels is not None else []
    head += _joint_names(q.shape[1]) + ["x_mm", "y_mm", "z_mm"][: xy.shape[1]]
    head += ["target"] if targets is not None else []
    head += ["payload_kg"] if payload_kg is not None else []
    lines = [",".join(head)]
    for i, (row, point) in enumerate(zip(q, xy, strict=True)):
        fields = [str(labels[i])] if labels is not None else []
        fields += [_angle_text(v) for v in row] + [repr(float(v)) for v in point]
        fields += [str(targets[i])] if targets is not None else []
        fields += [repr(float(payload_kg[i]))] if payload_kg is not None else []
        lines.append(",".join(fields))
    return "\n".join(lines) + "\n"


# --------------------------------------------------------------------------- calibration JSON

#: The format tag of calibration files (PRODUCT.md); other formats are refused.
CALIBRATION_FORMAT = "armcal-calibration/1"


def _region_to_dict(region: Region | None) -> dict[str, Any] | None:
    if isinstance(region, Annulus):
        return {
            "kind": "annulus",
            "center_mm": list(region.center),
            "r_min_mm": region.r_min,
            "r_max_mm": region.r_max,
        }
    if isinstance(region, Box):
        return {"kind": "box", "x_mm": list(region.x), "y_mm": list(region.y)}
    return None


def robot_to_dict(arm: PlanarArm) -> dict[str, Any]:
    """The ``robot`` section of a calibration file: everything needed to rebuild the arm.

    ``name``, ``link_lengths_mm``, ``joint_limits_deg``, ``base_offset``,
    ``base_rotation``, ``joint_map``, ``joint_offsets_deg``, ``targets``
    (label to ``{length_mm, angle_deg}``) and ``region`` (or null); the noise
    model and the fixed parameters are top-level keys of the document.
    """
    return {
        "name": arm.name,
        "link_lengths_mm": arm.link_lengths.tolist(),
        "joint_limits_deg": arm.joint_limits_deg.tolist(),
        "base_offset": arm.base_offset,
        "base_rotation": arm.base_rotation,
        "joint_map": arm.joint_map.tolist(),
        "joint_offsets_deg": np.degrees(arm.joint_offsets).tolist(),
        "targets": {
            t.label: {"length_mm": t.length, "angle_deg": math.degrees(t.angle)}
            for t in arm.targets
        },
        "region": _region_to_dict(arm.region),
    }


def _arm_from_dict(data: dict[str, Any], noise: NoiseModel | None, fixed: list[str]) -> PlanarArm:
    region = None
    if data.get("region") is not None:
        region = _parse_region("", data["region"])
    targets = tuple(
        Target(label, float(entry["length_mm"]), math.radians(float(entry["angle_deg"])))
        for label, entry in data.get("targets", {}).items()
    )
    offsets = data.get("joint_offsets_deg")
    return PlanarArm(
        np.array(data["link_lengths_mm"], dtype=float),
        np.radians(np.array(data["joint_limits_deg"], dtype=float)),
        base_offset=bool(data["base_offset"]),
        name=str(data["name"]),
        noise=noise,
        region=region,
        fixed=fixed,
        joint_map=data.get("joint_map"),
        targets=targets,
        base_rotation=bool(data.get("base_rotation", False)),
        joint_offsets=None if offsets is None else np.radians(np.array(offsets, dtype=float)),
    )


def read_calibration(path: str | os.PathLike) -> CalibratedArm:
    """Read a calibration file written by ``armcal identify`` (``armcal-calibration/1``).

    Returns
    -------
    CalibratedArm
        The arm rebuilt from the file's ``robot`` section, noise and fixed
        parameters; the deviations and covariance in internal units (mm, rad);
        the plane of 3-D data.

    Raises
    ------
    InputError
        For a file that is not JSON, of another format or version, or whose
        parameters do not match its robot; the message names the file and key.
    """
    text = _read_text(path, "calibration")
    try:
        doc = json.loads(text)
    except (ValueError, RecursionError) as exc:  # JSONDecodeError, or digits/nesting limits
        raise _fail(path, f"not a calibration file: invalid JSON ({exc})") from None
    if not isinstance(doc, dict) or "format" not in doc:
        raise _fail(
            path, "not a calibration file: no 'format' key; write one with armcal identify -o"
        )
    if doc["format"] != CALIBRATION_FORMAT:
        raise _fail(
            path,
            f"format {doc['format']!r} is not {CALIBRATION_FORMAT!r}; write the calibration with "
            "this version of armcal identify -o",
        )
    key = "robot"
    try:
        noise = None
        if doc.get("noise") is not None:
            key = "noise"
            sigma_q = doc["noise"].get("joint_sigma_deg")
            noise = NoiseModel(
                np.array(doc["noise"]["covariance_mm2"], dtype=float),
                None if sigma_q is None else np.radians(np.array(sigma_q, dtype=float)),
            )
        key = "robot"
        arm = _arm_from_dict(doc["robot"], noise, list(doc.get("fixed", [])))
        model: FitModel = arm
        if doc.get("elastostatic") is not None:
            key = "elastostatic"
            model = _compliance_from_dict(arm, doc["elastostatic"])
        key = "parameters"
        names = [entry["name"] for entry in doc["parameters"]]
        expected = model.param_names
        if tuple(names) != expected:
            raise ValueError(
                f"parameters {', '.join(names)} do not match the robot's {', '.join(expected)}"
            )
        scale = model.display_scale
        values = np.array([float(entry["value"]) for entry in doc["parameters"]]) / scale
        key = "covariance"
        if list(doc["covariance"]["names"]) != names:
            raise ValueError("covariance names do not match the parameters")
        full = np.array(doc["covariance"]["matrix"], dtype=float) / np.outer(scale, scale)
        if full.shape != (len(names), len(names)):
            raise ValueError(f"expected a {len(names)} x {len(names)} matrix")
        key = "sigma_mm"
        sigma = float(doc["sigma_mm"])
        if not (sigma > 0 and math.isfinite(sigma)):
            raise ValueError(f"expected a positive noise std in mm, got {sigma}")
        key = "plane"
        plane = None if doc.get("plane") is None else Plane.from_dict(doc["plane"])
    except (KeyError, TypeError, ValueError, AttributeError, OverflowError, InputError) as exc:
        # AttributeError: a section of the wrong JSON type ("robot": [] has no .get)
        what = f"missing key {exc}" if isinstance(exc, KeyError) else str(exc)
        if isinstance(exc, AttributeError):
            what = "a section of the wrong type"
        raise _fail(
            path, f"key '{key}': {what}; write the calibration again with armcal identify -o"
        ) from None
    if not (np.all(np.isfinite(values)) and np.all(np.isfinite(full))):
        raise _fail(path, "key 'parameters': values must be finite numbers")
    if plane is None and arm.base_rotation:
        raise _fail(path, "key 'plane': a calibration from 3-D data must record its plane")
    return CalibratedArm(model, values, full, sigma, plane)


def _compliance_from_dict(arm: PlanarArm, data: dict[str, Any]) -> CompliantArm:
    """The compliance model of a calibration file's ``elastostatic`` section."""
    gravity = data["gravity_mps2"]
    masses = data["link_masses_kg"]
    elastic = Elastostatic(
        None if gravity is None else np.array(gravity, dtype=float).reshape(2),
        None if masses is None else np.array(masses, dtype=float).reshape(arm.n_joints),
        np.array(data["com_fraction"], dtype=float).reshape(arm.n_joints),
        float(data["payload_kg"]),
    )
    model = CompliantArm(arm, elastic, bool(data["known_loads"]))
    if list(data.get("parameters", model.compliance_names)) != list(model.compliance_names):
        raise ValueError(f"compliance parameters do not match {', '.join(model.compliance_names)}")
    return model
