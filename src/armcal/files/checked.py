"""Values of a hand-edited JSON file (a calibration file), checked key by key.

A key that is missing, of the wrong shape, or holds text, null, NaN or a
covariance no fit gives raises :class:`BadKey` naming the key and what it must
hold, so the reader's one line says that instead of numpy's text ("cannot
reshape array of size ...", "could not convert string to float").
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np

__all__ = [
    "COVARIANCE_RTOL",
    "STD_RTOL",
    "BadKey",
    "array_of",
    "check_covariance",
    "described",
    "list_of",
    "number_of",
]


class BadKey(ValueError):
    """A key of a JSON file that is missing or holds the wrong shape or values.

    Parameters
    ----------
    key : str
        The key as the file spells it, its section first (``robot.origins``).
    text : str
        What it must hold and what it holds.
    """

    def __init__(self, key: str, text: str) -> None:
        super().__init__(text)
        self.key = key


def described(value: Any) -> str:
    """What a JSON value is, for a message: null, a text, one number, a shape, or lists
    of unequal lengths."""
    if value is None:
        return "null"
    if isinstance(value, bool):
        return f"the value {str(value).lower()}"
    if isinstance(value, str):
        return f"the text {value[:20]!r}"
    if isinstance(value, dict):
        return "a section (an object)"
    if not _numbers_only(value):
        return "text or null among the numbers"
    try:
        shape = np.array(value, dtype=float).shape
    except ValueError:
        return "lists of unequal lengths"
    return "one number" if shape == () else f"shape {' x '.join(map(str, shape))}"


def _numbers_only(value: Any) -> bool:
    """Whether ``value`` is a JSON number or nested lists of them: numpy would read the
    text "1.5" as a number, and a boolean as 0 or 1."""
    if isinstance(value, list):
        return all(_numbers_only(item) for item in value)
    return isinstance(value, int | float) and not isinstance(value, bool)


def number_of(value: Any, key: str, what: str) -> float:
    """``value`` as a finite JSON number, else :class:`BadKey` naming ``key`` and ``what``
    it must hold (a number in quotes is refused: the file writes none)."""
    if not _numbers_only(value) or isinstance(value, list):
        raise BadKey(key, f"expected {what}, a number; got {described(value)}")
    if not math.isfinite(value):
        raise BadKey(key, f"expected {what}, a finite number; got {value}")
    return float(value)


def array_of(
    section: dict[str, Any],
    key: str,
    shape: tuple[int, ...],
    what: str,
    default: Any = None,
    where: str = "robot",
) -> np.ndarray:
    """``section[key]`` as finite numbers of ``shape`` (``-1``: any count).

    Raises
    ------
    BadKey
        Naming ``where.key``, ``what`` it must hold, the shape expected and the
        value found; for a missing key without ``default`` too.
    """
    name = f"{where}.{key}" if where else key
    if key not in section and default is None:
        raise BadKey(name, f"missing; expected {what}")
    raw = section.get(key, default)
    sized = " x ".join("k" if s == -1 else str(s) for s in shape)
    value = None
    if _numbers_only(raw):
        try:
            value = np.array(raw, dtype=float)
        except ValueError:  # lists of unequal lengths
            value = None
    if value is not None and -1 in shape and value.size == 0:
        value = value.reshape([0 if s == -1 else s for s in shape])
    if (
        value is None
        or value.ndim != len(shape)
        or any(s not in (-1, t) for s, t in zip(shape, value.shape, strict=True))
    ):
        raise BadKey(name, f"expected {what}: shape {sized}; got {described(raw)}")
    if not np.all(np.isfinite(value)):
        raise BadKey(name, f"expected finite numbers ({what}); got NaN or infinity")
    return value


def list_of(
    section: dict[str, Any], key: str, what: str, count: int | None = None, where: str = "robot"
) -> list:
    """``section[key]`` as a list (of ``count`` items where given), else :class:`BadKey`."""
    name = f"{where}.{key}" if where else key
    if key not in section:
        raise BadKey(name, f"missing; expected a list: {what}")
    raw = section[key]
    if not isinstance(raw, list) or (count is not None and len(raw) != count):
        many = "a list" if count is None else f"a list of {count}"
        got = f"{len(raw)} items" if isinstance(raw, list) else described(raw)
        raise BadKey(name, f"expected {many}: {what}; got {got}")
    return raw


#: How far a parameter's ``std`` may differ from the root of its variance (relative): the
#: file writes both from the same numbers, so they agree to the last digit unless edited.
STD_RTOL = 1e-6

#: Round-off allowed in a covariance, relative to the product of the two stds (asymmetry, a
#: correlation beyond +-1) or to the largest eigenvalue of the correlation matrix (a negative
#: one: every eigenvalue of a real covariance's is >= 0; computed ones come out at -1e-15
#: and above).
COVARIANCE_RTOL = 1e-9


def check_covariance(matrix: np.ndarray, names: Sequence[str], stds: Sequence[Any]) -> None:
    """Refuse a covariance ``(p, p)`` (display units) that no fit gives.

    Parameters
    ----------
    matrix : numpy.ndarray
        The file's ``covariance.matrix``, finite.
    names : sequence of str
        The parameters, one per row.
    stds : sequence
        Each parameter's ``std`` as the file gives it (``None``: not given).

    Raises
    ------
    BadKey
        For a std that is not a number >= 0 or not the root of its variance (key
        ``parameters``); a negative variance, asymmetry, a correlation beyond +-1 or
        a negative eigenvalue beyond round-off (key ``covariance``); each names the
        parameter(s).
    """
    variance = np.diag(matrix)
    for name, std, v in zip(names, stds, variance, strict=True):
        if std is None:
            continue  # the reader needs only the matrix
        std = number_of(std, "parameters", f"the std of {name}")
        if std < 0:
            raise BadKey("parameters", f"{name}: std {std:g} is negative; a std is >= 0")
        if v < 0:
            raise BadKey(
                "covariance",
                f"the variance of {name} is {v:g}, negative; a variance is a std squared "
                f"({std:g}^2 = {std * std:g} for the std the file gives)",
            )
        if abs(std - math.sqrt(v)) > STD_RTOL * max(std, math.sqrt(v)):
            raise BadKey(
                "parameters",
                f"{name}: std {std:g} is not the root of its variance in the covariance "
                f"({v:g}, whose root is {math.sqrt(v):g}); one of them was edited",
            )
    if np.any(variance < 0):
        i = int(np.argmin(variance))
        raise BadKey(
            "covariance",
            f"the variance of {names[i]} is {variance[i]:g}, negative; a variance is >= 0",
        )
    root = np.sqrt(variance)
    bound = np.outer(root, root)
    uneven = np.abs(matrix - matrix.T) > COVARIANCE_RTOL * bound
    beyond = np.abs(matrix) > (1 + COVARIANCE_RTOL) * bound  # |correlation| > 1
    for found, why in (
        (uneven, "is not symmetric"),
        (beyond, "has a correlation beyond +-1 (a covariance is at most the product of stds)"),
    ):
        if found.any():
            i, j = map(int, np.argwhere(found)[0])
            raise BadKey("covariance", f"the matrix {why}: row {names[i]}, column {names[j]}")
    seen = np.flatnonzero(root > 0)
    if seen.size == 0:
        return
    correlation = matrix[np.ix_(seen, seen)] / bound[np.ix_(seen, seen)]
    lam, vec = np.linalg.eigh((correlation + correlation.T) / 2)
    if lam[0] < -COVARIANCE_RTOL * lam[-1]:
        along = np.argsort(-np.abs(vec[:, 0]))[:2]
        raise BadKey(
            "covariance",
            f"the matrix is not positive semi-definite (its correlation matrix has eigenvalue "
            f"{lam[0]:.3g}, mostly along {' and '.join(names[seen[k]] for k in along)}): the "
            "correlations contradict each other, as no fit's do",
        )
