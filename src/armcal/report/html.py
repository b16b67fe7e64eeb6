"""A calibration or a validation as one self-contained HTML page, to hand over.

The page is what a manager or an auditor reads first: the verdict (what improved,
by how much, on poses the fit did not see, against the honest baseline), then the
data, what the data identify, the parameters with their std, the warnings, the
figures and the whole text report.  Everything is in the one file: the figures
are PNG images inlined as ``data:`` URIs, the style is in the page, and nothing
is fetched from a network.  Like the rest of :mod:`armcal.report`, it formats
results the commands computed (their JSON documents and text reports); the
figures arrive drawn, as PNG bytes.
"""

from __future__ import annotations

import base64
from collections.abc import Mapping, Sequence
from html import escape
from typing import Any

from .._version import __version__

__all__ = ["calibration_html", "validation_html"]

_STYLE = """
body { font: 15px/1.45 system-ui, sans-serif; max-width: 62rem; margin: 2rem auto;
       padding: 0 1rem; color: #1b1f24; }
h1 { font-size: 1.6rem; margin-bottom: .2rem; }
h2 { font-size: 1.2rem; border-bottom: 1px solid #d0d7de; padding-bottom: .2rem;
     margin-top: 2rem; }
.sub { color: #57606a; margin-top: 0; }
.verdict { font-size: 1.15rem; padding: .8rem 1rem; border-left: 6px solid #1a7f37;
           background: #f0fff4; }
.verdict.bad { border-color: #cf222e; background: #fff5f5; }
.verdict.open { border-color: #9a6700; background: #fff8e5; }
table { border-collapse: collapse; font-variant-numeric: tabular-nums; }
td, th { padding: .2rem .7rem; border-bottom: 1px solid #eaeef2; text-align: right; }
th { background: #f6f8fa; } td:first-child, th:first-child { text-align: left; }
tr.held td { color: #8c959f; }
.warn li { margin-bottom: .4rem; } .warn code { color: #9a6700; }
img { max-width: 100%; border: 1px solid #eaeef2; margin: .5rem 0; }
pre { background: #f6f8fa; padding: .8rem; overflow-x: auto; font-size: 12.5px; }
footer { margin-top: 2.5rem; color: #57606a; font-size: .85rem; }
"""


def _page(title: str, subtitle: str, sections: Sequence[tuple[str, str, str]]) -> str:
    """The page: ``sections`` of ``(id, heading, body HTML)`` under a title."""
    body = "\n".join(
        f'<section id="{sid}">\n<h2>{escape(heading)}</h2>\n{html}\n</section>'
        for sid, heading, html in sections
    )
    return (
        "<!DOCTYPE html>\n"
        '<html lang="en">\n<head>\n<meta charset="utf-8">\n'
        '<meta name="viewport" content="width=device-width, initial-scale=1">\n'
        f"<title>{escape(title)}</title>\n<style>{_STYLE}</style>\n</head>\n<body>\n"
        f'<h1>{escape(title)}</h1>\n<p class="sub">{escape(subtitle)}</p>\n'
        f"{body}\n<footer>Written by armcal {escape(__version__)}; self-contained, no "
        "network.</footer>\n</body>\n</html>\n"
    )


def _mm(value: float) -> str:
    return f"{value:.3g} mm"


def _change(before: float, after: float) -> str:
    """How much closer (or farther) ``after`` is than ``before``, in words."""
    if after < before:
        return f"{100 * (1 - after / before):.0f} % less error, {before / after:.3g} times closer"
    return f"WORSE: {100 * (after / before - 1):.0f} % more error than before"


def _verdict(text: str, kind: str = "") -> str:
    return f'<p class="verdict {kind}" id="verdict-text">{escape(text)}</p>'


def _warnings(warnings: Sequence[Mapping[str, Any]]) -> str:
    if not warnings:
        return "<p>None: nothing in the data or the fit calls for a caution.</p>"
    items = "".join(
        f"<li><code>{escape(str(w.get('code', '')))}</code> {escape(str(w.get('message', '')))}"
        "</li>"
        for w in warnings
    )
    return f'<ul class="warn">{items}</ul>'


def _figures(figures: Mapping[str, bytes]) -> str:
    if not figures:
        return "<p>No figures.</p>"
    return "\n".join(
        f'<figure><img alt="{escape(caption)}" src="data:image/png;base64,'
        f'{base64.b64encode(png).decode("ascii")}"><figcaption>{escape(caption)}</figcaption>'
        "</figure>"
        for caption, png in figures.items()
    )


def _parameters(parameters: Sequence[Mapping[str, Any]]) -> str:
    rows = []
    for p in parameters:
        held = bool(p.get("fixed"))
        std = "held" if held else f"{p['std']:.3g}"
        rows.append(
            f'<tr class="{"held" if held else ""}"><td>{escape(str(p["name"]))}</td>'
            f"<td>{p['value']:.6g}</td><td>{std}</td><td>{escape(str(p['unit']))}</td></tr>"
        )
    head = "<tr><th>parameter</th><th>value</th><th>std</th><th>unit</th></tr>"
    return f"<table>{head}{''.join(rows)}</table>"


def calibration_verdict(document: Mapping[str, Any]) -> tuple[str, str]:
    """The verdict of ``identify``'s document and its kind (``""`` good, ``"open"`` not
    tested on held-out poses, ``"bad"`` worse than the nominal arm)."""
    fit = float(document["residual_rms_per_point_mm"])
    baseline = document.get("baseline") or {}
    nominal = baseline.get("rms_per_point_mm")
    cv = document.get("cross_validation")
    if cv is not None:
        held_out, before = float(cv["rms_per_point_mm"]), cv.get("nominal_rms_per_point_mm")
        if before is None:
            return (
                f"On held-out poses ({cv['folds']}-fold cross-validation) the calibrated arm "
                f"misses by {_mm(held_out)} RMS per point.",
                "",
            )
        kind = "bad" if held_out >= before else ""
        return (
            f"On held-out poses ({cv['folds']}-fold cross-validation) the calibrated arm "
            f"misses by {_mm(held_out)} RMS per point, against {_mm(before)} for the nominal "
            f"arm with its own instrument pose and targets: {_change(before, held_out)}. "
            f"Predicted: {_mm(float(cv['predicted_rms_per_point_mm']))}.",
            kind,
        )
    against = "" if nominal is None else f", against {_mm(float(nominal))} for the nominal arm"
    return (
        f"The calibration fits its own {document['poses']} rows within {_mm(fit)} RMS per "
        f"point{against} fitted the same way. Not yet tested on poses it did not see: "
        "validate it on fresh poses, or identify with cross-validation.",
        "open",
    )


def calibration_html(
    document: Mapping[str, Any],
    text: str,
    figures: Mapping[str, bytes],
    *,
    source: str,
    held: Sequence[str] = (),
) -> str:
    """``identify``'s report as a page: ``document`` its JSON (the calibration file's,
    with the warnings and any cross-validation), ``text`` its text report, ``figures``
    PNG bytes by caption, ``source`` the measurement file, ``held`` the sentences that
    say what the data cannot separate."""
    robot = document["robot"]
    verdict, kind = calibration_verdict(document)
    free = [p for p in document["parameters"] if not p.get("fixed")]
    gof = document.get("goodness_of_fit") or {}
    data = (
        f"<p>{document['poses']} rows from {escape(source)}, {document['poses_used']} in the "
        f"fit; noise sigma {document['sigma_mm']:.3g} mm ({escape(document['sigma_source'])})"
        + (
            f"; chi-square {gof['chi2']:.4g} on {gof['dof']} degrees of freedom"
            if gof.get("chi2") is not None
            else ""
        )
        + ".</p>"
    )
    identified = (
        f"<p>{len(free)} of {len(document['parameters'])} parameters identified; the others "
        "are held at their nominal values.</p>"
    )
    if held:
        identified += (
            "<p>Held because the measurements cannot separate them:</p><ul>"
            + "".join(f"<li>{escape(sentence)}</li>" for sentence in held)
            + "</ul>"
        )
    return _page(
        f"Calibration of {robot['name']}",
        f"armcal identify, {document['method']}, {len(document['parameters'])} parameters",
        [
            ("verdict", "Verdict", _verdict(verdict, kind)),
            ("data", "Data", data),
            ("identifiable", "What the data identify", identified),
            ("parameters", "Parameters", _parameters(document["parameters"])),
            ("warnings", "Warnings", _warnings(document.get("warnings", []))),
            ("figures", "Figures", _figures(figures)),
            ("report", "The whole report", f"<pre>{escape(text)}</pre>"),
        ],
    )


def validation_verdict(document: Mapping[str, Any]) -> tuple[str, str]:
    """The verdict of ``validate``'s document and its kind (see :func:`calibration_verdict`)."""
    before = float(document["rms_before_per_point_mm"])
    after = float(document["rms_after_per_point_mm"])
    kind = "bad" if after >= before else ""
    return (
        f"On {document['poses']} held-out rows the calibrated arm misses by {_mm(after)} RMS "
        f"per point, against {_mm(before)} before calibration ({document['baseline']} "
        f"baseline): {_change(before, after)}; worst {_mm(float(document['max_after_mm']))} "
        f"after, {_mm(float(document['max_before_mm']))} before. Predicted: "
        f"{_mm(float(document['predicted_rms_after_per_point_mm']))}.",
        kind,
    )


def validation_html(
    document: Mapping[str, Any],
    text: str,
    figures: Mapping[str, bytes],
    *,
    source: str,
    calibration: str,
) -> str:
    """``validate``'s report as a page: ``document`` its JSON, ``text`` its text report
    (with ISO 9283 where asked), ``figures`` PNG bytes by caption."""
    verdict, kind = validation_verdict(document)
    data = (
        f"<p>{document['poses']} rows from {escape(source)}, never seen by the calibration "
        f"{escape(calibration)}.</p>"
    )
    table = (
        "<table><tr><th>error per point</th><th>before</th><th>after</th></tr>"
        + "".join(
            f"<tr><td>{label}</td><td>{document[f'{key}_before_mm']:.4g} mm</td>"
            f"<td>{document[f'{key}_after_mm']:.4g} mm</td></tr>"
            for label, key in (("RMS", "rms"), ("95th percentile", "p95"), ("largest", "max"))
        )
        + "</table>"
    )
    return _page(
        "Validation on held-out poses",
        f"armcal validate of {calibration}",
        [
            ("verdict", "Verdict", _verdict(verdict, kind)),
            ("data", "Data", data + table),
            ("warnings", "Warnings", _warnings(document.get("warnings", []))),
            ("figures", "Figures", _figures(figures)),
            ("report", "The whole report", f"<pre>{escape(text)}</pre>"),
        ],
    )
