"""Small HTML tables for a notebook: what a result's ``_repr_html_`` shows.

A notebook (Jupyter, VS Code) displays a result by its ``_repr_html_`` where it
has one: its one-line ``repr`` as a caption over a table of what a reader looks
up (a calibration's parameters with their std, a validation's errors before and
after).  Every text is escaped; numbers are written as the text reports write
them (4 significant digits, a std to 3).
"""

from __future__ import annotations

from collections.abc import Sequence
from html import escape

__all__ = [
    "html_table",
    "number",
]


def number(value: float, digits: int = 4) -> str:
    """``value`` to ``digits`` significant digits (``g`` format), as the reports write it.

    Examples
    --------
    >>> number(0.0123456), number(1234567.0), number(0.5, 3)
    ('0.01235', '1.235e+06', '0.5')
    """
    return f"{value:.{digits}g}"


def html_table(
    caption: str,
    header: Sequence[str],
    rows: Sequence[Sequence[str]],
    *,
    notes: Sequence[str] = (),
) -> str:
    """An HTML table: ``caption`` above, ``header`` and ``rows`` of text (escaped), and
    ``notes`` (warnings, say) as lines below it.

    Examples
    --------
    >>> print(html_table("R", ["a", "b"], [["1", "<2>"]]))
    <div><p><code>R</code></p><table><thead><tr><th>a</th><th>b</th></tr></thead><tbody><tr><td>1</td><td>&lt;2&gt;</td></tr></tbody></table></div>
    """
    head = "".join(f"<th>{escape(text)}</th>" for text in header)
    body = "".join(
        "<tr>" + "".join(f"<td>{escape(text)}</td>" for text in row) + "</tr>" for row in rows
    )
    below = "".join(f"<p>{escape(text)}</p>" for text in notes)
    return (
        f"<div><p><code>{escape(caption)}</code></p><table><thead><tr>{head}</tr></thead>"
        f"<tbody>{body}</tbody></table>{below}</div>"
    )
