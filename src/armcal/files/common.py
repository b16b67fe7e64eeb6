"""What every file reader shares: one error form, text from a file or stdin, TOML, keys, numbers.

Every reader validates strictly and raises :class:`~armcal.errors.InputError`
with a message that names the file, the row (data row and file line) and the
column or key, and says how to fix it (:func:`fail`).
"""

from __future__ import annotations

import difflib
import json
import math
import os
import re
import sys
from collections.abc import Iterator, Sequence
from operator import itemgetter
from pathlib import Path
from typing import Any, BinaryIO

from ..errors import InputError, action
from ..formats import table_of
from .kinds import looks_like, wrong_toml

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover - exercised on Python 3.10 only
    import tomli as tomllib

__all__ = [
    "MAX_ABS_VALUE",
    "STDIO",
    "PathArg",
    "check_keys",
    "fail",
    "forget_stdin",
    "load_toml",
    "number",
    "number_within",
    "numbers",
    "parse_number",
    "read_text",
    "shown",
    "suggest",
    "to_json",
    "write_json",
]


#: Largest magnitude accepted in a CSV field (1000 km in mm): larger values are unit
#: mistakes or corrupt data, and their squares would overflow in the least squares.
MAX_ABS_VALUE = 1e9

#: A file path as the functions here take it.
PathArg = str | os.PathLike[str]


#: The path that means stdin for an input and stdout for an output file.
STDIO = "-"
#: stdin's text, once read (a second reader of ``-`` gets the same text).
_stdin_text: list[str] = []


def fail(path: str | os.PathLike, message: str) -> InputError:
    name = os.fspath(path)
    return InputError(f"{'<stdin>' if name == STDIO else name}: {message}")


def forget_stdin() -> None:
    """Forget what :func:`read_stdin` read: a new run of the program reads its own stdin
    (several runs in one process, as tests and notebooks make)."""
    _stdin_text.clear()


def _is_utf16(data: bytes) -> bool:
    """Whether ``data`` look like UTF-16: a byte-order mark, or ASCII text with a NUL beside
    every character (UTF-16 without a mark) in its first bytes."""
    if data.startswith((b"\xff\xfe", b"\xfe\xff")):
        return True
    head = data[:64]
    half = len(head) // 2
    return half >= 2 and (head[1::2] == b"\0" * half or head[0::2] == b"\0" * half)


def _decoded(path: str | os.PathLike, data: bytes, what: str) -> str:
    """``data`` as UTF-8 text (a byte-order mark dropped), or the error that names the
    encoding: UTF-16 (Excel's "Unicode text") gets its own fix."""
    if _is_utf16(data):
        raise fail(
            path,
            "is UTF-16 text (as Excel's 'Unicode text' writes it); save it as UTF-8 (in "
            f"Excel: CSV UTF-8); expected a {what} file",
        )
    try:
        return data.decode("utf-8-sig")
    except UnicodeDecodeError:
        raise fail(path, f"is not UTF-8 text; expected a {what} file") from None


def read_stdin(what: str) -> str:
    if not _stdin_text:
        if sys.stdin is None or sys.stdin.isatty():
            raise fail(STDIO, f"no {what} piped in; give a file name or pipe one into armcal")
        _stdin_text.append(_decoded(STDIO, sys.stdin.buffer.read(), what))
    return _stdin_text[0]


def read_text(path: str | os.PathLike, what: str) -> str:
    if os.fspath(path) == STDIO:
        return read_stdin(what)
    try:
        data = Path(path).read_bytes()
    except FileNotFoundError:
        raise fail(path, f"{what} file not found") from None
    except IsADirectoryError:
        raise fail(path, f"is a directory, expected a {what} file") from None
    except OSError as exc:
        raise fail(path, f"cannot read: {exc.strerror}") from None
    # universal newlines, as reading in text mode gives: \r\n and \r end a line too
    text = _decoded(path, data, what)
    return text.replace("\r\n", "\n").replace("\r", "\n") if "\r" in text else text


def shown(text: str, limit: int = 40) -> str:
    """``text`` quoted for a message, cut to ``limit`` characters (a cell may be huge).

    Examples
    --------
    >>> shown("1" * 50, limit=5)
    "'11111...'"
    """
    return repr(text if len(text) <= limit else text[:limit] + "...")


#: What an empty numeric cell should hold, by column (else a number in the column's unit).
_EMPTY_FIX = {
    "payload_kg": "write the payload in kg (0 for none)",
    "fx_N": "write the tip force in N (0 for none)",
    "fy_N": "write the tip force in N (0 for none)",
}


def parse_number(path, where: str, name: str, field: str, decimal_comma: bool = False) -> float:
    """A CSV cell ``field`` (stripped) of column ``name`` at ``where`` (row and line) as a
    finite number within :data:`MAX_ABS_VALUE`, or the error that says what is wrong with
    it and what to write: an empty cell, digits grouped with '_', not a number, not finite,
    too large.  The cell is shown cut (:func:`shown`); a semicolon file may write 1,5."""
    if not field:
        fix = _EMPTY_FIX.get(name, "write its value, a number")
        raise fail(path, f"{where}, column {name}: the cell is empty; {fix}")
    if "_" in field:  # Python's float() reads 1_249.3 as 1249.3; no instrument writes it
        raise fail(
            path,
            f"{where}, column {name}: {shown(field)} is not a number: digits are not grouped "
            f"with '_'; write {shown(field.replace('_', ''))}",
        )
    try:
        value = float(field.replace(",", ".", 1) if decimal_comma else field)
    except ValueError:
        raise fail(path, f"{where}, column {name}: {shown(field)} is not a number") from None
    if not math.isfinite(value):
        raise fail(path, f"{where}, column {name}: {shown(field)} is not a finite number")
    if abs(value) > MAX_ABS_VALUE:
        raise fail(
            path,
            f"{where}, column {name}: {shown(field)} is beyond ±{MAX_ABS_VALUE:g}; "
            "check the unit (mm, deg)",
        )
    return value


def suggest(key: str, allowed: Sequence[str]) -> str:
    """``did you mean 'X'? `` for the closest of ``allowed`` (case aside), else ``""``."""
    lower = {name.lower(): name for name in allowed}
    close = difflib.get_close_matches(key.lower(), list(lower), n=1)
    return f"did you mean '{lower[close[0]]}'? " if close else ""


def check_keys(
    path, table: dict, allowed: Sequence[str], where: str = "", *, robot: bool = True
) -> None:
    """Refuse a key of ``table`` not in ``allowed``; a robot file's hint names its table."""
    for key in table:
        if key not in allowed:
            hint = (misplaced(key, where) if robot else "") or suggest(key, allowed)
            raise fail(
                path, f"unknown key '{where}{key}': {hint}allowed keys are {', '.join(allowed)}"
            )


#: How a truth file of the other family writes what a key of this family holds: a planar
#: arm's (lists, one per joint) and a spatial arm's (a table of parameters).
_TRUTH_FAMILIES = {
    "planar": (
        "a planar arm's truth file: deviations as lists, one per joint (dl_mm = [...] in mm, "
        "dq_deg = [...] in deg, base_mm = [x0, y0])"
    ),
    "spatial": (
        "a spatial arm's truth file: the deviations as a table of parameters ([errors] with "
        "dq1 = ... in deg, j2.x = ... in mm), the base as base = { xyz_mm = [x, y, z], "
        "rpy_deg = [r, p, y] }, the compliance as [compliance]"
    ),
}


#: A spatial arm's parameter (dq3, j2.x), which a truth file gives under [errors].
_PARAMETER = re.compile(r"^(dq\d+|j\d+\.\w+)$")


def check_truth_keys(
    path, data: dict, allowed: Sequence[str], other: Sequence[str], family: str
) -> None:
    """Refuse a key of a truth file that the ``other`` family's truth file takes (a planar
    arm's ``dq_deg`` for a spatial arm), saying how the arm's ``family`` (``"planar"`` or
    ``"spatial"``) writes it; the other keys :func:`check_keys` judges."""
    for key in data:
        if family == "spatial" and _PARAMETER.match(key):
            raise fail(
                path,
                f"unknown key '{key}': a parameter's error belongs in the [errors] table (write "
                f"it under an [errors] line); allowed keys are {', '.join(allowed)}",
            )
        if key not in allowed and key in other:
            theirs = "spatial" if family == "planar" else "planar"
            raise fail(
                path,
                f"unknown key '{key}': it belongs in a {theirs} arm's truth file, but the robot "
                f"is {family}; write {_TRUTH_FAMILIES[family]}; allowed keys are "
                f"{', '.join(allowed)}",
            )


def misplaced(key: str, where: str) -> str:
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


def number(path, value: Any, key: str) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise fail(path, f"key '{key}': expected a number, got {value!r}")
    try:
        number = float(value)
    except OverflowError:
        number = math.inf
    if not math.isfinite(number) or abs(number) > MAX_ABS_VALUE:
        raise fail(path, f"key '{key}': expected a finite number within ±{MAX_ABS_VALUE:g}")
    return number


def number_within(path, value: Any, key: str, bounds: tuple[float, float], unit: str) -> float:
    """A number of ``unit`` within ``bounds``; outside them, most likely another unit."""
    found = number(path, value, key)
    low, high = bounds
    if not low <= found <= high:
        raise fail(
            path,
            f"key '{key}': must be between {low:g} and {high:g} {unit}, got {found:g}; "
            f"check the unit ({unit})",
        )
    return found


def numbers(path, value: Any, key: str, count: int | None = None) -> list[float]:
    if not isinstance(value, list):
        raise fail(path, f"key '{key}': expected a list of numbers, got {value!r}")
    if count is not None and len(value) != count:
        raise fail(path, f"key '{key}': expected {count} numbers, got {len(value)}")
    return [number(path, v, f"{key}[{i}]") for i, v in enumerate(value)]


def load_toml(path, what: str, text: str | None = None) -> dict:
    """A TOML file's table (of its ``text`` where already read); an error names the line,
    shows it and says how to fix it."""
    text = read_text(path, what) if text is None else text
    try:
        data = tomllib.loads(text)
    except (ValueError, RecursionError) as exc:  # TOMLDecodeError, or digits/nesting limits
        other = looks_like(text, f"{what}-file")
        if other:  # a file of another kind: say which, not what TOML finds wrong in it
            raise fail(path, f"not a {what} TOML file: {other.removesuffix('; ')}") from None
        raise fail(path, f"invalid TOML: {_toml_advice(text, str(exc), what)}") from None
    other = wrong_toml(data, what)
    if other:
        raise fail(path, f"not a {what} file: {other.removesuffix('; ')}")
    return data


_TOML_AT = re.compile(r"^(?P<what>.*) \(at line (?P<line>\d+), column (?P<column>\d+)\)$")
_BARE_DECIMAL = re.compile(r"(?<![\w.])[-+]?(\.\d+)")
_BARE_KEY = re.compile(r"^\s*\[*\s*(?P<key>[^=\[\]]*?)\s*(=|\]|$)")


def _toml_advice(text: str, message: str, what: str) -> str:
    """The TOML parser's ``message`` with the line it names and a fix for the common cases."""
    lines = text.splitlines()
    found = _TOML_AT.match(message)
    if found is None:
        if message.endswith("(at end of document)"):
            return f"{message}; the file ends inside a bracket or a quote: close it"
        return f"{message}; check the brackets and quotes"
    number = int(found["line"])
    shown = lines[number - 1].strip() if 0 < number <= len(lines) else ""
    if len(shown) > 60:
        shown = shown[:57] + "..."
    where = f"line {number}, column {found['column']}: {shown!r}: {found['what']}"
    first = lines[0] if lines else ""
    if first.count(",") >= 1 and "=" not in first:
        return f"{where}; this looks like a CSV table, not a {what} TOML file; " + (
            f"{action('robot-file')} takes a built-in robot's name or a robot .toml file"
            if what == "robot"
            else f"pass the {what} .toml file"
        )
    key = _BARE_KEY.match(shown)
    name = "" if key is None else key["key"]
    if found["what"].startswith("Cannot overwrite a value") or found["what"].startswith(
        "Cannot declare"
    ):
        headers = [i for i in range(number - 1) if lines[i].lstrip().startswith("[")]
        table = shown.startswith("[")
        # A table's first declaration is a header; a key's is within the same table.
        look = headers if table else range(headers[-1] + 1 if headers else 0, number - 1)
        before = [
            i + 1
            for i in look
            if (m := _BARE_KEY.match(lines[i].strip())) is not None and m["key"] == name
        ]
        again = f" (first on line {before[0]})" if before and name else ""
        if table:
            return f"{where}; table [{name}] is declared twice{again}: merge the two"
        return f"{where}; key {name!r} is given twice{again}: keep one"
    if name and not name.isascii() and not name.startswith(('"', "'")):
        return (
            f"{where}; a key with characters beyond A-Z, a-z, 0-9, '_' and '-' must be "
            f'quoted ("{name}" = ...)'
        )
    bare = _BARE_DECIMAL.search(shown)
    if found["what"] == "Invalid value" and bare is not None:
        return f"{where}; TOML numbers need a digit before the point: write 0{bare[1]}"
    return f"{where}; check the brackets, quotes and '=' on that line"


def to_json(document: dict) -> str:
    """Serialize a result document; refuses NaN and infinity rather than writing them.

    Objects are indented, one key per line, to any depth; a list of objects has
    one object per line (indented in turn if it holds objects or lists); any
    other value (a number, a string, a list of numbers or of lists: residuals,
    a covariance) is one line.  ``json.dumps`` with
    ``indent`` would put every number of a 10^5-row residual table on a line of
    its own and switch off the C encoder, three times slower than this (issue
    20); the text parses to the same document.  A list of flat objects with the
    same keys (a residual table) is encoded a column at a time
    (:func:`_record_lines`), the same text as one ``json.dumps`` per object in a
    tenth of the time.  :func:`write_json` writes the same text to a file
    without holding it.
    """
    return "".join(_json_pieces(document, "")) + "\n"


def write_json(document: dict, handle: BinaryIO) -> None:
    """Write :func:`to_json`'s text of ``document`` to a binary ``handle`` (UTF-8), in pieces.

    A 10^5-row calibration is tens of MB of text: written as it is made, it is
    never held whole (for :func:`~armcal.files.atomic_write`).
    """
    batch: list[str] = []
    size = 0
    for piece in _json_pieces(document, ""):
        batch.append(piece)
        size += len(piece)
        if size > WRITE_BATCH:
            handle.write("".join(batch).encode("utf-8"))
            batch, size = [], 0
    batch.append("\n")
    handle.write("".join(batch).encode("utf-8"))


#: Characters :func:`write_json` gathers before it encodes and writes them.
WRITE_BATCH = 1 << 20


def _json_pieces(value: Any, pad: str) -> Iterator[str]:
    """``value``'s JSON text in pieces, lines continued at ``pad`` (see :func:`to_json`)."""
    inner = pad + "  "
    if isinstance(value, dict) and value:
        yield "{\n"
        for i, (key, item) in enumerate(value.items()):
            yield (",\n" + inner if i else inner) + json.dumps(str(key)) + ": "
            yield from _json_pieces(item, inner)
        yield f"\n{pad}}}"
    elif isinstance(value, list | tuple) and any(isinstance(v, dict) for v in value):
        records = _record_lines(value)
        separator = ",\n" + inner
        yield "[\n" + inner
        if records is not None:
            for i, lines in enumerate(records):
                yield (separator if i else "") + separator.join(lines)
        else:
            for i, item in enumerate(value):
                if i:
                    yield separator
                if _nested(item):
                    yield from _json_pieces(item, inner)
                else:
                    yield _json_line(item)
        yield f"\n{pad}]"
    else:
        yield _json_line(value)


def _json_line(value: Any) -> str:
    return json.dumps(value, allow_nan=False, separators=(", ", ": "))


def _finite_floats(values: list[float]) -> list[str]:
    if not all(map(math.isfinite, values)):
        raise ValueError("Out of range float values are not JSON compliant")
    return list(map(float.__repr__, values))


#: JSON texts of a list of scalars of one exact type, as ``json.dumps`` writes each.
_SCALARS: dict[type, Any] = {
    float: _finite_floats,
    int: lambda values: list(map(int.__repr__, values)),
    bool: lambda values: ["true" if v else "false" for v in values],
    str: lambda values: list(map(json.encoder.encode_basestring_ascii, values)),
    type(None): lambda values: ["null"] * len(values),
}

#: Objects of a table whose texts are made at once (:func:`_record_lines`).
RECORD_CHUNK = 1 << 14


def _record_lines(rows: Sequence[Any]) -> Iterator[list[str]] | None:
    """The lines of ``rows``, chunk by chunk, if they are objects of scalars with the same keys.

    Each key's values are encoded together (one ``map`` of their type's
    encoder, value by value where a column mixes types); None for any other
    list.  Keys and types are checked before the first line is made.
    """
    first = rows[0]
    if type(first) is not dict or not first:
        return None
    keys = tuple(first)
    if set(map(type, rows)) != {dict} or set(map(tuple, rows)) != {keys}:
        return None
    if not all(set(map(type, map(itemgetter(key), rows))) <= _SCALARS.keys() for key in keys):
        return None
    names = (json.dumps(str(k)).replace("%", "%%") for k in keys)
    template = "{" + ", ".join(f"{name}: %s" for name in names) + "}"
    return _lines(rows, keys, template)


def _lines(rows: Sequence[dict], keys: tuple, template: str) -> Iterator[list[str]]:
    for start in range(0, len(rows), RECORD_CHUNK):
        chunk = rows[start : start + RECORD_CHUNK]
        columns = []
        for key in keys:
            values = list(map(itemgetter(key), chunk))
            kinds = set(map(type, values))
            if len(kinds) == 1:
                columns.append(_SCALARS[kinds.pop()](values))
            else:
                columns.append([_SCALARS[type(v)]([v])[0] for v in values])
        yield [template % fields for fields in zip(*columns, strict=True)]


def _nested(value: Any) -> bool:
    """Whether ``value`` is an object holding an object or a list (indented, not one line)."""
    return isinstance(value, dict) and any(isinstance(v, dict | list) for v in value.values())
