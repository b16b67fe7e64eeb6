"""What kind of armcal file a text looks like, to name a file given to the wrong option.

A plan given where measurements are expected, a calibration JSON given as a robot,
a URDF given as a truth file: the reader's error then says what the file looks
like and which option takes it (``this looks like a plan file (joint columns, no
x_mm): --plan takes it``) instead of the first thing its own format finds wrong.
"""

from __future__ import annotations

import re

import tomllib

from ..errors import action

__all__ = [
    "ROBOT_KEYS_SEEN",
    "TRUTH_KEYS_SEEN",
    "field_count_fix",
    "looks_like",
    "not_a_table",
    "toml_kind",
    "wrong_toml",
]

#: Top-level keys that only a robot file has (planar: link_lengths_mm; spatial: a URDF,
#: a DH table or a UR model).
ROBOT_KEYS_SEEN = ("link_lengths_mm", "urdf", "mdh", "dh", "ur", "measurement", "elastostatic")

#: Top-level keys that only a truth file has (planar and spatial).
TRUTH_KEYS_SEEN = (
    "dl_mm",
    "dq_deg",
    "base_mm",
    "k_urad_per_Nm",
    "c_mdeg_per_m",
    "base",
    "errors",
    "compliance",
)

#: A first line of TOML: ``key = value`` or ``[table]``.
_TOML_LINE = re.compile(r"^\s*(\[[\w.\"' -]+\]|[\w.\"'-]+\s*=)")

#: A joint column of a CSV header (``q1_deg``, ``q4_mm``).
_JOINT = re.compile(r"^q\d+_(deg|mm)$")


def toml_kind(data: dict) -> str | None:
    """``"robot"`` or ``"truth"`` for a TOML table with only that file's keys, else None."""
    robot = [key for key in ROBOT_KEYS_SEEN if key in data]
    truth = [key for key in TRUTH_KEYS_SEEN if key in data]
    if robot and not truth:
        return "robot"
    if truth and not robot:
        return "truth"
    return None


def _first_line(text: str) -> str:
    """The first line that is neither blank nor a ``#`` comment (read line by line: a
    file may hold 10^5 rows)."""
    start = 0
    while start < len(text):
        end = text.find("\n", start)
        end = len(text) if end < 0 else end
        raw = text[start:end].strip().lstrip("\ufeff")
        if raw and not raw.startswith("#"):
            return raw
        start = end + 1
    return ""


def not_a_table(text: str) -> bool:
    """Whether ``text`` starts as JSON, XML or TOML does, which no CSV header does."""
    first = _first_line(text)
    return first[:1] in ("{", "<", "[") or bool(_TOML_LINE.match(first) and "=" in first)


def _kind(text: str) -> tuple[str, str] | None:
    """What ``text`` looks like and the action that takes it: (``"a plan file (...)"``,
    ``"plan-file"``), or None when it looks like no armcal file."""
    first = _first_line(text)
    if first.startswith("{"):
        if "armcal-calibration" in text[:200]:
            return "a calibration file (JSON, written by identify)", "calibration-file"
        return None
    if first.startswith("<") and "<robot" in text[:5000]:
        return "a URDF (XML with a <robot> element)", "robot-file"
    if _TOML_LINE.match(first):
        try:
            kind = toml_kind(tomllib.loads(text))
        except (ValueError, RecursionError):
            return None
        return None if kind is None else _TOML_KINDS[kind]
    header = [name.strip() for name in re.split(r"[,;\t]", first)]
    if not any(_JOINT.match(name) for name in header):
        return None
    if "x_mm" in header:
        return "a measurements file (joint columns and x_mm)", "measurements-file"
    return "a plan file (joint columns, no x_mm)", "plan-file"


def wrong_toml(data: dict, expected: str) -> str:
    """``"this looks like a truth file (...): --truth takes it; "`` for a TOML table
    ``data`` read as the ``expected`` kind (``"robot"`` or ``"truth"``) that has only the
    other kind's keys, else ``""``."""
    kind = toml_kind(data)
    if kind is None or kind == expected:
        return ""
    what = _TOML_KINDS[kind]
    return f"this looks like {what[0]}: {action(what[1])} takes it; "


#: What a robot and a truth TOML look like, and the action that takes each.
_TOML_KINDS = {
    "robot": ("a robot file (TOML with the arm's geometry)", "robot-file"),
    "truth": ("a truth file (TOML with deviations such as dl_mm)", "truth-file"),
}


def looks_like(text: str, expected: str) -> str:
    """``"this looks like a plan file (...): --plan takes it; "`` when ``text`` looks like
    another kind of armcal file than the action ``expected`` takes (``"plan-file"``,
    ``"measurements-file"``, ``"robot-file"``, ...), else ``""``.

    Examples
    --------
    >>> "a plan file (joint columns, no x_mm)" in looks_like("q1_deg\\n1\\n", "measurements-file")
    True
    >>> looks_like("q1_deg,q2_deg\\n1,2\\n", "plan-file")
    ''
    """
    found = _kind(text)
    if found is None or found[1] == expected:
        return ""
    if found[1] == "plan-file" and expected == "program-file":  # the same columns
        return ""
    what, option = found
    return f"this looks like {what}: {action(option)} takes it; "


#: A field that is digits only, maybe signed: what a comma-separated row's numbers split into
#: when they were written with decimal commas ("-159,93" gives "-159" and "93").
_DIGITS = re.compile(r"\s*[-+]?\d+\s*")

#: Two fields that are one number with a thousands separator ("1,234.5"): 1 to 3 digits, then
#: 3 digits and a decimal part.
_THOUSANDS = re.compile(r"\s*[-+]?\d{1,3},\d{3}\.\d*\s*")


def field_count_fix(row: list[str], width: int, delimiter: str, header_end: str = "x") -> str:
    """The fix for a row of ``row`` fields where the header has ``width`` (its last field
    ``header_end``): one more field, empty, or one less beside an empty last header field,
    is a separator that ends the line (Excel writes one); a comma-separated
    row of whole numbers only, up to twice as many as the header's, seems written with
    decimal commas (each number split in two; a whole number, in one); a pair of fields
    like ``1`` and ``234.5``, with a thousands separator; else every column needs a value."""
    trailing = f"remove the trailing separator ({delimiter!r}) at the end of each line"
    if len(row) == width + 1 and not row[-1].strip():
        return f"the row ends with a separator: {trailing}"
    if len(row) == width - 1 and not header_end.strip():
        return f"the header ends with a separator: {trailing}"
    if delimiter != "," or len(row) <= width:
        return "give every column a value"
    if len(row) <= 2 * width and all(map(_DIGITS.fullmatch, row)):
        return (
            f"every field is a whole number, as when numbers are written with decimal commas "
            f"({','.join(row[:2])} for {'.'.join(row[:2])}): the file seems to use decimal "
            "commas; write a point as the decimal separator, or separate the columns with ';'"
        )
    pairs = (",".join(row[k : k + 2]) for k in range(len(row) - 1))
    split = next((pair for pair in pairs if _THOUSANDS.fullmatch(pair)), None)
    if split is not None:
        return (
            f"{split.strip()} looks like one number with a thousands separator: write numbers "
            f"without one ({split.strip().replace(',', '')})"
        )
    return "give every column a value"
