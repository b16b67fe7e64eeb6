"""CSV text of whole columns at once, byte for byte what Python's ``round`` and ``repr`` write.

The tables armcal writes hold 10^5-10^6 rows: formatting them value by value
in Python (``repr(round(x, 12))``) took 8 of ``design --poses 1000000``'s 12 s
(issue 20).  Here every column becomes a block of bytes ``(m, k, width)`` in
NumPy, NUL bytes standing for nothing, and the file is its rows with the NULs
taken out (:func:`csv_text`).

**Angles** are written as ``repr(round(degrees, 12) + 0.0)`` (:func:`angle_text`:
an exact 90 deg reads ``90.0``, not ``89.99999999999999``; ``+ 0.0`` turns
``-0.0`` into ``0.0``).  For ``x = 0`` and ``1e-4 <= |x| < 4096`` the digits come
from integer arithmetic (:func:`degree_cells`):

* ``x 10^12`` exactly, as the rounded product ``p`` and its error ``e``
  (Dekker's two-product: ``10^12 = 2^12 5^12`` splits exactly, and nothing
  under- or overflows in this range).  Below ``2^52`` a unit in the last place
  of ``p`` is at most 1/2, so ``rint(p)`` is ``x 10^12`` correctly rounded,
  except where ``p`` itself is a tie (``p - rint(p) = +-1/2``): there ``e``
  decides, and ``e = 0`` is a true tie, which ``rint`` gave to the even side,
  as ``round`` does.
* Two numbers of 12 decimals below 4096 are farther apart (1e-12) than a unit
  in the last place there (2^-41), so the 12 decimals of that integer, trailing
  zeros dropped (one kept), are the shortest text that reads back as
  ``round(x, 12)``: what ``repr`` writes, in positional notation from 1e-4 up
  to 1e16.

Any other value (nonzero below 1e-4, from 4096 up, not finite) is formatted by
Python, as before.  **Other numbers** are ``repr(float)`` (the shortest text
that reads back as the same float), one C call per value (:func:`float_cells`);
**text** is UTF-8 (:func:`text_cells`).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

__all__ = [
    "Column",
    "angle_text",
    "csv_text",
    "degree_cells",
    "degrees",
    "float_cells",
    "floats",
    "text_cells",
]

#: Bytes of the longest number written (``repr`` of a float with an exponent: 24).
WIDTH = 24

#: Rows laid out at once: the byte blocks of a chunk stay a few MB.
CHUNK_ROWS = 1 << 15

_SPLIT = 134217729.0  # 2^27 + 1: Dekker's split of a double into two 26-bit halves
_SCALE = 1e12  # exact: 2^12 5^12
_SCALE_HIGH = _SPLIT * _SCALE - (_SPLIT * _SCALE - _SCALE)  # the upper half of 10^12 ...
_SCALE_LOW = _SCALE - _SCALE_HIGH  # ... and the lower
_ZERO, _POINT, _MINUS = ord("0"), ord("."), ord("-")

#: ``0000`` .. ``9999`` as bytes, and the same right-aligned without leading zeros.
_DIGITS = np.array([list(b"%04d" % v) for v in range(10_000)], dtype=np.uint8)
_INTEGERS = np.where((_DIGITS == _ZERO) & (np.cumsum(_DIGITS != _ZERO, axis=1) == 0), 0, _DIGITS)
_INTEGERS[:, -1] = _DIGITS[:, -1]  # the units digit, even 0


def angle_text(q_rad: float) -> str:
    """One angle (rad) as the file's degrees: the rule :func:`degree_cells` vectorizes."""
    return repr(round(math.degrees(q_rad), 12) + 0.0)


def degree_cells(q_rad: np.ndarray) -> np.ndarray:
    """:func:`angle_text` of every angle of ``q_rad`` ``(m, k)`` (rad): bytes ``(m, k, WIDTH)``."""
    degrees = np.degrees(np.asarray(q_rad, dtype=float))
    shape = degrees.shape
    degrees = degrees.reshape(-1)
    size = np.abs(degrees)
    fast = (degrees == 0) | ((size >= 1e-4) & (size < 4096))
    x = degrees[fast]
    product = x * _SCALE
    split = _SPLIT * x
    high = split - (split - x)
    low = x - high
    error = (high * _SCALE_HIGH - product) + high * _SCALE_LOW + low * _SCALE_HIGH
    error += low * _SCALE_LOW  # product + error = x 10^12 exactly
    nearest = np.rint(product)
    off = product - nearest
    scaled = nearest.astype(np.int64)
    scaled += (off == 0.5) & (error > 0)
    scaled -= (off == -0.5) & (error < 0)
    value = np.abs(scaled)
    units = value // 10**12  # < 4096
    rest = value - units * 10**12
    first = rest // 10**8
    rest -= first * 10**8
    second = rest // 10**4
    decimals = _DIGITS[np.stack([first, second, rest - second * 10**4], axis=1)].reshape(-1, 12)
    nonzero = decimals != _ZERO
    kept = np.where(nonzero.any(axis=1), 12 - np.argmax(nonzero[:, ::-1], axis=1), 1)
    decimals[np.arange(12) >= kept[:, None]] = 0
    text = np.zeros((x.size, WIDTH), dtype=np.uint8)
    text[:, 0] = np.where(scaled < 0, _MINUS, 0)
    text[:, 1:5] = _INTEGERS[units]
    text[:, 5] = _POINT
    text[:, 6:18] = decimals
    slow = np.flatnonzero(~fast)
    if not slow.size:
        return text.reshape(*shape, WIDTH)
    cells = np.zeros((degrees.size, WIDTH), dtype=np.uint8)
    cells[fast] = text
    # Nonzero below 1e-4, from 4096 up, not finite: Python's own rounding.
    texts = [repr(round(v, 12) + 0.0) for v in degrees[slow].tolist()]
    cells[slow] = np.array(texts, dtype=f"S{WIDTH}").view(np.uint8).reshape(-1, WIDTH)
    return cells.reshape(*shape, WIDTH)


def float_cells(values: np.ndarray) -> np.ndarray:
    """``repr(float(v))`` of every value of ``values`` ``(m, k)``: bytes ``(m, k, WIDTH)``."""
    values = np.asarray(values, dtype=float)
    texts = np.array(list(map(float.__repr__, values.reshape(-1).tolist())), dtype=f"S{WIDTH}")
    return texts.view(np.uint8).reshape(*values.shape, WIDTH)


def text_cells(texts: Sequence[str]) -> np.ndarray | None:
    """``m`` texts as UTF-8 bytes ``(m, 1, width)``; None when one holds a NUL (see csv_text)."""
    encoded = [t.encode() for t in texts]
    if any(b"\0" in t for t in encoded):
        return None
    width = max(map(len, encoded), default=0) or 1
    return np.array(encoded, dtype=f"S{width}").view(np.uint8).reshape(len(encoded), 1, width)


@dataclass(frozen=True)
class Column:
    """Numbers to write, ``(m,)`` or ``(m, k)``, and the function that makes their bytes."""

    values: np.ndarray
    cells: Callable[[np.ndarray], np.ndarray]

    def __len__(self) -> int:
        return len(self.values)

    def block(self, rows: slice) -> np.ndarray:
        """The bytes ``(r, k, width)`` of a slice of rows."""
        part = self.values[rows]
        return self.cells(part.reshape(part.shape[0], -1))


def degrees(q_rad: np.ndarray) -> Column:
    """Angles (rad) written in degrees (:func:`degree_cells`)."""
    return Column(np.asarray(q_rad, dtype=float), degree_cells)


def floats(values: np.ndarray) -> Column:
    """Numbers written as ``repr(float)`` (:func:`float_cells`)."""
    return Column(np.asarray(values, dtype=float), float_cells)


def csv_text(header: Sequence[str], columns: Sequence[Column | Sequence[str]]) -> str:
    """The CSV of ``header`` and ``columns``, one row a line, the fields joined by commas.

    A column is numbers (:func:`degrees`, :func:`floats`) or ``m`` texts.  Chunk
    of rows by chunk, every column becomes a block of bytes ``(rows, k, width)``
    (NUL bytes are not written), the blocks are laid side by side and the NULs
    taken out; a text that holds a NUL of its own is written by joining the rows
    in Python instead.
    """
    texts = {i: text_cells(c) for i, c in enumerate(columns) if not isinstance(c, Column)}
    if any(block is None for block in texts.values()):
        return _joined(header, columns)
    parts = [(",".join(header) + "\n").encode()]
    m = len(columns[0]) if columns else 0
    for start in range(0, m, CHUNK_ROWS):
        rows = slice(start, start + CHUNK_ROWS)
        cells = [
            c.block(rows) if isinstance(c, Column) else texts[i][rows]  # type: ignore[index]
            for i, c in enumerate(columns)
        ]
        count = cells[0].shape[0]
        fields = [c[:, j] for c in cells for j in range(c.shape[1])]
        line = np.zeros((count, sum(f.shape[1] + 1 for f in fields)), dtype=np.uint8)
        at = 0
        for field in fields:
            width = field.shape[1]
            line[:, at : at + width] = field
            line[:, at + width] = ord(",")
            at += width + 1
        line[:, -1] = ord("\n")
        flat = line.reshape(-1)
        parts.append(flat[flat != 0].tobytes())
    return b"".join(parts).decode()


def _joined(header: Sequence[str], columns: Sequence[Column | Sequence[str]]) -> str:
    """:func:`csv_text` row by row in Python (a text holding a NUL)."""
    fields: list[list[str]] = []
    for column in columns:
        if isinstance(column, Column):
            block = column.block(slice(None))
            for j in range(block.shape[1]):
                fields.append([bytes(c).replace(b"\0", b"").decode() for c in block[:, j]])
        else:
            fields.append(list(column))
    rows = "".join(",".join(row) + "\n" for row in zip(*fields, strict=True))
    return ",".join(header) + "\n" + rows
