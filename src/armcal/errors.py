"""Exceptions raised by armcal.

Every problem a user can fix (a malformed file, a plan that cannot identify the
parameters, an option out of range) raises :class:`ArmcalError` or one of its
subclasses.  The command line turns these into exit status 2 and a single line
``armcal: error: ...``; anything else is a bug and keeps its traceback.

A result that is computed but suspicious carries :class:`ArmcalWarning` records
(code and message); the command line prints each as ``armcal: warning: ...``
and the JSON lists them under ``warnings``.

A warning or an error says what to try in neutral words: "try a robust fit".
Where such advice is an option of the library or a flag of the command line,
the text holds a reference to an *action* (:func:`action`), which the library
renders in its own words (:data:`ACTIONS`) and the command line in its flags
(:meth:`ArmcalWarning.render`, :meth:`ArmcalError.render`).  An action may carry
values (``action("method", "optimize")``), which each vocabulary places in its own
way: ``method="optimize"`` here, ``--method optimize`` on the command line.

An error built from another's text takes that text as raised (:func:`unrendered`),
not ``str(exc)``, so that its actions still reach the command line unrendered.
"""

from __future__ import annotations

import re
import string
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from urllib.parse import quote, unquote

__all__ = [
    "ACTIONS",
    "ArmcalError",
    "ArmcalWarning",
    "InputError",
    "NotIdentifiableError",
    "action",
    "render",
    "unique_warnings",
    "unrendered",
]

#: What a warning or an error can advise, by key, in the library's words (the command
#: line has its flags for the same, :mod:`armcal.cli`).
ACTIONS: dict[str, str] = {
    "refit-robust": "fit robustly (identify(..., robust=True)) to leave them out",
    "try-robust": "try a robust fit (robust=True)",
    "try-closed-form": 'try the closed form (method="closed-form")',
    "geometry-alone": "fit the geometry alone (the model without compliance)",
    "geometry-only": "a fit without compliance (compliance=False) fits the geometry only",
    "hold-terms": "fixed = [...] in the robot file's [identify] table, or calibrate(..., "
    "fixed=...)",
    "design": "(armcal.design)",
    "own-urdf": 'export its own URDF (export(cal, "urdf") without original)',
    "choose-tip": "name the tip link (tip_link in a robot TOML, or load_spatial_robot(..., "
    "tip_link=LINK))",
    "choose-base": "name the base link (base_link in a robot TOML, or load_spatial_robot(..., "
    "base_link=LINK))",
    # Options named in an error or a note; ``{}`` is the action's values joined by
    # commas, ``{:q}`` each in double quotes, joined by ", " (:func:`action`).
    "method": "method={:q}",
    "poses": "m = {}",
    "test-poses": "test_q",
    "sigma": "sigma",
    "isotropic-noise": "NoiseModel.isotropic(sigma_mm)",
    "hold": "fixed=[{:q}]",
    "fixed": "fixed",
    "free-held": "calibrate(..., fixed=...) or the robot file's [identify]",
    "trials": "trials={}",
    "cross-validate": "cross_validate",
    "target": "target",
    "target-label": "target=LABEL",
    "payload-kg": "payload_kg",
    "payload-given": "payload_kg (given or the program's column)",
    "design-defaults": "criterion and method at their defaults",
    "candidates": "candidates",
    "position-requirement": 'the requirement "position_rms_mm"',
    "distinct": "distinct=True",
    "payloads": "payloads",
    "robot-file": "load_robot",
    "measurements-file": "read_measurements",
    "plan-file": "read_plan",
    "calibration-file": "read_calibration",
    "truth-file": "load_truth",
    "robot-arm": "arm",
}

_ACTION = re.compile(r"\u27e6([a-z][a-z-]*)(?::([^\u27e6\u27e7]*))?\u27e7")
#: What a value keeps as it is inside a reference: all but ``%``, ``|`` and non-ASCII.
_PLAIN = " " + "".join(c for c in string.punctuation if c not in "%|")


class _Values(tuple):
    """An action's values, as its words' ``{}`` (comma-joined) or ``{:q}`` (quoted) say."""

    def __format__(self, spec: str) -> str:
        if spec == "q":
            return ", ".join(f'"{value}"' for value in self)
        if spec:
            raise ValueError(f"unknown format {spec!r} for an action's values")
        return ",".join(self)


def action(key: str, *values: object) -> str:
    """A reference to the advice ``key`` of :data:`ACTIONS`, for a warning's or an error's
    text, with the ``values`` its words place (an option's value, parameter names).

    Examples
    --------
    >>> ArmcalWarning("outlier", f"2 outliers; {action('try-robust')}").message
    '2 outliers; try a robust fit (robust=True)'
    >>> error = ArmcalError(f"use {action('method', 'optimize')}")
    >>> str(error), error.render({"method": "--method {}"})
    ('use method="optimize"', 'use --method optimize')
    """
    if key not in ACTIONS:
        raise KeyError(f"unknown action {key!r}")
    if not values:
        if "{" in ACTIONS[key]:
            raise ValueError(f"action {key!r} needs its values")
        return f"\u27e6{key}\u27e7"
    encoded = "|".join(quote(str(value), safe=_PLAIN) for value in values)
    return f"\u27e6{key}:{encoded}\u27e7"


def render(text: str, words: Mapping[str, str] = ACTIONS) -> str:
    """``text`` with every action in ``words`` (the library's for keys ``words`` lacks).

    For a text that carries actions and is neither a warning nor an error: a note,
    a line of a report.
    """

    def said(found: re.Match[str]) -> str:
        key, encoded = found.group(1), found.group(2)
        template = words.get(key, ACTIONS[key])
        if encoded is None:
            return template
        return template.format(_Values(unquote(value) for value in encoded.split("|")))

    return _ACTION.sub(said, text)


def unrendered(exc: BaseException) -> str:
    """The text of ``exc`` as raised, its actions not yet rendered (an :class:`ArmcalError`'s),
    to build another error's text from; ``str(exc)`` for any other exception.

    Examples
    --------
    >>> inner = ArmcalError(f"too few; {action('try-robust')}")
    >>> ArmcalError(f"file.csv: {unrendered(inner)}").render({"try-robust": "try --robust"})
    'file.csv: too few; try --robust'
    """
    return exc.text if isinstance(exc, ArmcalError) else str(exc)


class ArmcalError(ValueError):
    """A problem with the user's input or request, with a message that says how to fix it.

    Its text may refer to an :func:`action`: ``str(error)`` says it in the library's
    words, :meth:`render` in another vocabulary (the command line's flags).

    Examples
    --------
    >>> error = ArmcalError(f"two leaves; {action('choose-tip')}")
    >>> str(error).startswith("two leaves; name the tip link (tip_link in a robot TOML")
    True
    >>> error.render({"choose-tip": "say which"})
    'two leaves; say which'
    """

    def __str__(self) -> str:
        return self.render(ACTIONS)

    @property
    def text(self) -> str:
        """The message as raised, its actions not rendered (:func:`unrendered`)."""
        return super().__str__()

    def render(self, words: Mapping[str, str]) -> str:
        """The message with every action in ``words`` (the library's for keys it lacks)."""
        return render(self.text, words)


class InputError(ArmcalError):
    """A file or option that cannot be read or does not validate.

    The message names the file and, where it applies, the row (1-based line of
    the file) and the column or key.
    """


class NotIdentifiableError(ArmcalError):
    """A plan whose Jacobian is rank deficient: some parameters cannot be identified.

    Attributes
    ----------
    combinations : list of str
        Human-readable parameter combinations that the plan cannot see, e.g.
        ``"dl3 - dl4"``.
    """

    def __init__(self, message: str, combinations: list[str] | None = None) -> None:
        super().__init__(message)
        self.combinations = list(combinations or [])


@dataclass(frozen=True)
class ArmcalWarning:
    """A result that is computed but suspicious: said on stderr and carried in the JSON.

    Attributes
    ----------
    code : str
        A stable, machine-readable key (``"ill-conditioned"``, ``"not-converged"``).
    text : str
        One line that says what is suspicious and what to try; advice that is an
        option refers to an :func:`action`, rendered by :attr:`message` (the
        library's words) or :meth:`render` (another vocabulary: the command line's).

    Examples
    --------
    >>> ArmcalWarning("not-converged", "gauss-newton did not converge").to_dict()
    {'code': 'not-converged', 'message': 'gauss-newton did not converge'}
    """

    code: str
    text: str

    @property
    def message(self) -> str:
        """The text in the library's words."""
        return self.render(ACTIONS)

    def render(self, words: Mapping[str, str]) -> str:
        """The text with every action in ``words`` (the library's for keys ``words`` lacks)."""
        return render(self.text, words)

    def to_dict(self, words: Mapping[str, str] | None = None) -> dict[str, str]:
        """The JSON form ``{code, message}`` (in ``words``, default the library's)."""
        return {"code": self.code, "message": self.render(words or ACTIONS)}


def unique_warnings(warnings: Sequence[ArmcalWarning]) -> list[ArmcalWarning]:
    """Each warning once, in order."""
    seen: set[tuple[str, str]] = set()
    kept = []
    for warning in warnings:
        if (warning.code, warning.text) not in seen:
            seen.add((warning.code, warning.text))
            kept.append(warning)
    return kept
