"""Text that reads back exactly: numbers, TOML strings and keys, XML attributes and comments.

The pieces every exported file (:mod:`armcal.export_planar`, :mod:`armcal.export_spatial`)
is written with: every number with full round-trip precision, every name escaped
for where it goes.
"""

from __future__ import annotations

import json
import re

import numpy as np
from numpy.typing import ArrayLike

from .models import CalibratedArm
from .noise import NoiseModel

__all__ = [
    "deviations_text",
    "noise_toml",
    "num",
    "nums",
    "one_line",
    "pack",
    "quoteattr",
    "toml_key",
    "toml_string",
    "xml_comment",
    "xml_name",
]

_BARE_KEY = re.compile(r"^[A-Za-z0-9_-]+$")


def quoteattr(text: str) -> str:
    """``text`` as a double-quoted XML attribute value.

    The job of ``xml.sax.saxutils.quoteattr``, whose import pulls in urllib and
    http at every start of the program.

    >>> quoteattr('a "b" & <c>')
    '"a &quot;b&quot; &amp; &lt;c&gt;"'
    """
    for raw, entity in (("&", "&amp;"), ("<", "&lt;"), (">", "&gt;"), ('"', "&quot;")):
        text = text.replace(raw, entity)
    for raw, entity in (("\n", "&#10;"), ("\r", "&#13;"), ("\t", "&#9;")):
        text = text.replace(raw, entity)
    return f'"{text}"'


def num(value: float) -> str:
    """A float with full round-trip precision (``repr``), never ``-0.0``."""
    return repr(float(value) + 0.0)


def nums(values: ArrayLike) -> str:
    return "[" + ", ".join(num(v) for v in np.ravel(values)) + "]"


def toml_string(text: str) -> str:
    # A JSON string is a TOML basic string: the same escapes, \uXXXX for control characters
    # (TOML also refuses a raw DEL, which JSON leaves as it is).
    return json.dumps(text, ensure_ascii=False).replace("\x7f", "\\u007f")


def toml_key(key: str) -> str:
    return key if _BARE_KEY.match(key) else toml_string(key)


def one_line(text: str) -> str:
    """``text`` safe inside a one-line comment: no line breaks or other control characters."""
    return " ".join("".join(c if c.isprintable() else " " for c in text).split())


def noise_toml(noise: NoiseModel) -> list[str]:
    """The ``[measurement]`` lines of a noise model: ``sigma_mm`` (one value, or one per axis),
    ``covariance_mm2`` or a laser ``tracker``'s terms, ``joint_sigma_deg`` and a 6-DoF
    instrument's ``orientation_sigma_deg``."""
    cov = noise.covariance_mm2
    if noise.tracker is not None:
        terms = ", ".join(f"{k} = {num(v)}" for k, v in noise.tracker.to_dict().items())
        lines = [f"tracker = {{ {terms} }}"]
    elif np.count_nonzero(cov - np.diag(np.diagonal(cov))) == 0:
        sigma = np.sqrt(np.diagonal(cov))
        lines = [f"sigma_mm = {num(sigma[0]) if np.all(sigma == sigma[0]) else nums(sigma)}"]
    else:
        lines = ["covariance_mm2 = [" + ", ".join(nums(row) for row in cov) + "]"]
    if noise.joint_sigma is not None:
        sigma_q = np.degrees(noise.joint_sigma)
        shown = num(sigma_q[0]) if sigma_q.size == 1 else nums(sigma_q)
        lines.append(f"joint_sigma_deg = {shown}")
    if noise.orientation_sigma is not None:  # a 6-DoF instrument (spatial robot files)
        lines.append(f"orientation_sigma_deg = {num(np.degrees(noise.orientation_sigma))}")
    return lines


def pack(items: list[str], width: int = 90) -> list[str]:
    """``items`` joined by ``", "`` into lines of at most ``width`` characters (items whole)."""
    lines: list[str] = []
    for item in items:
        if lines and len(lines[-1]) + 2 + len(item) <= width:
            lines[-1] += ", " + item
        else:
            lines.append(item)
    return lines


def deviations_text(cal: CalibratedArm) -> list[str]:
    """``name = value unit`` of every robot parameter, in lines for a comment."""
    arm = cal.arm
    shown = [
        f"{name} = {num(value * scale)} {unit}"
        for name, value, scale, unit, instrument in zip(
            arm.param_names,
            cal.arm_params,
            arm.display_scale,
            arm.param_units,
            arm.instrument_params,
            strict=True,
        )
        if not instrument
    ]
    return pack(shown)


def xml_name(text: str) -> str:
    """``text`` for an XML attribute: control characters (most invalid in XML 1.0) as ``_``."""
    return "".join(c if c.isprintable() else "_" for c in text)


def xml_comment(text: str) -> str:
    """``text`` safe inside an XML comment (no ``--``, no trailing ``-``)."""
    while "--" in text:
        text = text.replace("--", "- -")
    return text + " " if text.endswith("-") else text
