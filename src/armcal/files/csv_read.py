"""CSV text split into a header and rows, strictly: NumPy's reader for plain numbers,
the general reader for the rest, and every numeric field checked where it is.

What instruments and armcal write (a header, then rows of numbers) is parsed by
NumPy in one call; anything else -- ``#`` comments, quotes, blank lines, ``;``
with a decimal comma, tabs -- goes through the general reader, which names the
file, row and column of the first problem.  What the columns mean is the
caller's (:mod:`armcal.files.tables`).
"""

from __future__ import annotations

import csv
import io
import re
import warnings
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

from .common import MAX_ABS_VALUE, fail, parse_number
from .kinds import field_count_fix

__all__ = [
    "ParsedCsv",
    "column_numbers",
    "general_split",
    "parse_csv",
]


@dataclass(frozen=True, eq=False)
class ParsedCsv:
    """A CSV split into its header and rows, not yet checked.

    ``block`` holds every data row's numbers where the file is plain numbers (read
    by NumPy in one call), and ``fields(c)`` lists column ``c``'s fields otherwise.
    """

    header_line: int  # file line of the header
    header_raw: str  # the header line as written
    header: list[str]  # its column names, stripped
    lines: list[int]  # file line of every data row
    delimiter: str
    block: np.ndarray | None = None
    fields: Callable[[int], list[str]] | None = None


def parse_csv(path, text: str, text_columns: Sequence[str], layout: str) -> ParsedCsv:
    """Split ``text`` into header and rows: NumPy's reader for a file of plain numbers,
    else the general reader (comments, quotes, a decimal comma, or a column of
    ``text_columns``); ``layout`` is the header expected, for the errors."""
    numeric_file = _numeric_file(text, text_columns)
    if numeric_file is not None:
        header_line, header_raw, block = numeric_file
        delimiter = _delimiter(header_raw)
        lines = list(range(header_line + 1, header_line + 1 + block.shape[0]))
        header = [h.strip() for h in header_raw.split(delimiter)]
        return ParsedCsv(header_line, header_raw, header, lines, delimiter, block=block)
    plain = _plain_fields(text)
    return plain if plain is not None else general_split(path, text, layout)


def general_split(path, text: str, layout: str) -> ParsedCsv:
    """:func:`parse_csv`'s general reader: comments, quotes, blank lines, any delimiter."""
    # Lines that start with '#' are comments (instrument exports often begin with some).
    numbered = enumerate(text.splitlines(), start=1)
    kept = (
        [(line, raw) for line, raw in numbered if not raw.lstrip().startswith("#")]
        if "#" in text
        else list(numbered)
    )
    if not any(raw.strip() for _, raw in kept):
        raise fail(path, f"file is empty; expected a header line {layout}")
    header_raw = next(raw for _, raw in kept if raw.strip())
    delimiter = _delimiter(header_raw)
    header_line, fields_header, lines, fields = _split(path, kept, delimiter, layout)
    header = [h.strip() for h in fields_header]
    return ParsedCsv(header_line, header_raw, header, lines, delimiter, fields=fields)


def _split(
    path, kept: list[tuple[int, str]], delimiter: str, layout: str
) -> tuple[int, list[str], list[int], Callable[[int], list[str]]]:
    """A CSV's header (its file line and fields), its data rows' file lines, and its columns.

    Returns ``(header_line, header, lines, fields)`` where ``fields(c)`` lists
    column ``c`` of every data row.  A row of empty fields only is skipped, and
    every data row must have the header's number of fields.  A file without
    quotes (what instruments and armcal write) is split as one string, so that a
    10^5-row file makes no Python object per row; a quoted field (which may hold
    the separator or span lines) goes through the ``csv`` module.
    """
    if any('"' in raw for _, raw in kept):
        records = _records(path, kept, delimiter)
        rows = [(line, row) for line, row in records if "".join(row).strip()]
    else:
        texts = [(line, raw) for line, raw in kept if raw.replace(delimiter, "").strip()]
        rows = [(line, raw.split(delimiter)) for line, raw in texts[:1]]
        flat = delimiter.join(raw for _, raw in texts[1:]).split(delimiter)
        width = len(rows[0][1]) if rows else 0
        if len(flat) == width * (len(texts) - 1):  # every row as wide as the header
            lines = [line for line, _ in texts[1:]]
            return rows[0][0], rows[0][1], lines, lambda c: flat[c::width]
        rows += [(line, raw.split(delimiter)) for line, raw in texts[1:]]
    if not rows:
        raise fail(path, f"file has no header, only empty fields; expected {layout}")
    (header_line, header), data = rows[0], rows[1:]
    for r, (line, row) in enumerate(data, start=1):
        if len(row) != len(header):
            raise fail(
                path,
                f"row {r} (line {line}) has {len(row)} fields but the header has "
                f"{len(header)}; {field_count_fix(row, len(header), delimiter, header[-1])}",
            )
    return header_line, header, [line for line, _ in data], lambda c: [row[c] for _, row in data]


def _numeric_file(text: str, text_columns: Sequence[str]) -> tuple[int, str, np.ndarray] | None:
    """The header's line and text, and every data row's numbers ``(m, width)``: a plain file.

    What instruments and armcal write -- a header, then rows of numbers only, no
    comment, quote, blank line or decimal comma -- is parsed by NumPy's C reader
    (about twice as fast as splitting it in Python at 10^5 rows, and without a
    Python string per field).  Anything else, and any row NumPy or the checks of
    :func:`column_numbers` would refuse, gives None: the general reader then reads the
    file and names the first problem.
    """
    plain = _plain_text(text)
    if plain is None:
        return None
    header_line, header_raw, delimiter, header, data = plain
    if delimiter == ";" or any(name.strip() in text_columns for name in header):
        return None
    rows = data.count("\n") + (not data.endswith("\n"))
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("error")  # e.g. loadtxt's "input contained no data"
            block = np.loadtxt(
                io.StringIO(data),
                delimiter=delimiter,
                comments=None,
                quotechar=None,
                ndmin=2,
                dtype=float,
            )
    except (ValueError, Warning):
        return None
    if block.shape != (rows, len(header)) or not np.all(np.abs(block) <= MAX_ABS_VALUE):
        return None
    return header_line, header_raw, block


def _plain_text(text: str) -> tuple[int, str, str, list[str], str] | None:
    """The header's line, text, delimiter and fields, and the data after it, of a file
    with no comment, quote, carriage return or blank line after its header (what
    instruments and armcal write); None for any other."""
    if any(c in text for c in '#"\r'):
        return None
    start, end = 0, _line_end(text, 0)
    while not text[start:end].strip():  # blank lines before the header
        if end == len(text):
            return None  # no header
        start, end = end + 1, _line_end(text, end + 1)
    data = text[end + 1 :]
    if not data.strip() or "\n\n" in data:
        return None
    header_raw = text[start:end]
    delimiter = _delimiter(header_raw)
    return text.count("\n", 0, start) + 1, header_raw, delimiter, header_raw.split(delimiter), data


def _plain_fields(text: str) -> ParsedCsv | None:
    """:func:`_plain_text`'s file split at its delimiter in one call (no Python object per
    line), where every row has the header's number of fields and none is blank or holds
    the delimiters alone; None otherwise."""
    plain = _plain_text(text)
    if plain is None:
        return None
    header_line, header_raw, delimiter, header, data = plain
    data = data[:-1] if data.endswith("\n") else data
    if re.search(f"^(?:[^\\S\n]|{re.escape(delimiter)})*$", data, re.MULTILINE):
        return None  # a line of spaces or delimiters only: the general reader skips it
    flat = data.replace("\n", delimiter).split(delimiter)
    rows, width = data.count("\n") + 1, len(header)
    if len(flat) != rows * width:
        return None
    lines = list(range(header_line + 1, header_line + 1 + rows))
    fields = [h.strip() for h in header]
    return ParsedCsv(
        header_line, header_raw, fields, lines, delimiter, fields=lambda c: flat[c::width]
    )


def _line_end(text: str, start: int) -> int:
    end = text.find("\n", start)
    return len(text) if end < 0 else end


def column_numbers(
    path, lines: list[int], names: list[str], columns: list[list[str]], delimiter: str
) -> np.ndarray:
    """The numeric ``columns`` (one list of fields each) as ``(m, len(columns))``, checked.

    NumPy parses each column at once (as ``float`` does, surrounding spaces
    allowed); only a block that fails -- a field that is not a number, not
    finite or beyond :data:`MAX_ABS_VALUE` -- is read again field by field, to
    name the first bad one in file order.  A semicolon file may write 1,5 for 1.5.
    """
    comma = delimiter == ";"
    # NumPy reads 1_249.3 as 1249.3, as float() does: a column with '_' is read field by field
    if not comma and not any("_" in "".join(column) for column in columns):
        try:
            # C order, as every reader gives: the fits' round-off follows the layout.
            values = np.ascontiguousarray(np.array(columns, dtype=float).reshape(-1, len(lines)).T)
        except ValueError:  # a field that is not a number: found below
            pass
        else:
            if np.all(np.abs(values) <= MAX_ABS_VALUE):  # NaN fails it too
                return values
    values = np.empty((len(lines), len(columns)))
    for r, line in enumerate(lines):  # row by row: the first bad field in file order
        where = f"row {r + 1} (line {line})"
        for c, name in enumerate(names):
            values[r, c] = parse_number(path, where, name, columns[c][r].strip(), comma)
    return values


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
        raise fail(path, f"line {line}: not a CSV row ({exc}); check the file") from None
    return records


def _delimiter(header: str) -> str:
    """The separator of a CSV whose header line is ``header``: a comma, else ';' or a tab."""
    if "," not in header:
        for candidate in (";", "\t"):
            if candidate in header:
                return candidate
    return ","
