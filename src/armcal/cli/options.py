"""The types of the command line's options: each turns one argument into a checked value.

A bad value is an :class:`argparse.ArgumentTypeError`, which the parser reports
as one ``armcal: error:`` line naming the option.
"""

from __future__ import annotations

import argparse
import math

from ..choices import SIGMA_RANGE_MM

__all__ = [
    "finite",
    "folds",
    "names",
    "not_negative",
    "payloads",
    "poses",
    "positive",
    "seed",
    "sigma",
    "sigma_or_zero",
    "trials",
]


def finite(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number, got {text!r}") from None
    if not math.isfinite(value):
        raise argparse.ArgumentTypeError(f"expected a finite number, got {text!r}")
    return value


def _above_zero(text: str, *, strict: bool) -> float:
    value = finite(text)
    if value < 0 or (strict and value == 0):
        bound = "> 0" if strict else ">= 0"
        raise argparse.ArgumentTypeError(f"expected a number {bound}, got {text!r}")
    return value


def positive(text: str) -> float:
    return _above_zero(text, strict=True)


def not_negative(text: str) -> float:
    return _above_zero(text, strict=False)


def payloads(text: str) -> tuple[float, ...]:
    values = tuple(not_negative(part) for part in text.split(",") if part.strip())
    if not values:
        raise argparse.ArgumentTypeError(f"expected payloads in kg like 0,10, got {text!r}")
    return values


def sigma(text: str) -> float:
    """Instrument noise in mm, within the range of any instrument (files.SIGMA_RANGE_MM)."""
    value = finite(text)
    low, high = SIGMA_RANGE_MM
    if not low <= value <= high:
        raise argparse.ArgumentTypeError(
            f"expected a noise std between {low:g} and {high:g} mm, got {text!r}"
        )
    return value


def sigma_or_zero(text: str) -> float:
    """Like :func:`sigma`, or 0 for noiseless synthetic data."""
    return 0.0 if finite(text) == 0 else sigma(text)


def seed(text: str) -> int:
    try:
        value = int(text)
    except ValueError:
        value = -1
    if value < 0:
        raise argparse.ArgumentTypeError(f"expected a whole number >= 0, got {text!r}")
    return value


def poses(text: str) -> int:
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a whole number, got {text!r}") from None
    if value < 1:
        raise argparse.ArgumentTypeError(f"expected at least 1 pose, got {value}")
    return value


def folds(text: str) -> int:
    """``--cross-validate K``: a whole number of folds >= 2."""
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"expected a whole number of folds, got {text!r}"
        ) from None
    if value < 2:
        raise argparse.ArgumentTypeError(f"needs at least 2 folds, got {value}")
    return value


def _at_least(text: str, smallest: int, what: str) -> int:
    """A whole number of ``what`` of at least ``smallest``, or the reason it is not."""
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"expected a whole number of {what}, got {text!r}"
        ) from None
    if value < smallest:
        raise argparse.ArgumentTypeError(f"expected at least {smallest} {what}, got {value}")
    return value


def trials(text: str) -> int:
    """``--trials N``: Monte Carlo trials, at least 2 (one has no spread to compare)."""
    return _at_least(text, 2, "trials")


def random_plans(text: str) -> int:
    """``--random-plans N``: random plans per study, at least 2."""
    return _at_least(text, 2, "random plans")


def names(text: str) -> tuple[str, ...]:
    """``--fix dl4,dq1``: parameter names, checked against the robot once it is loaded."""
    names = tuple(name.strip() for name in text.split(","))
    if not all(names):
        raise argparse.ArgumentTypeError(
            f"expected parameter names separated by commas (e.g. dl4,dq1), got {text!r}"
        )
    return names
