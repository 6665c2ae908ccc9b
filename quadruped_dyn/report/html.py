"""The report page: HTML building blocks and the page skeleton.

Escaping happens here, in one place: ``table`` escapes every header, caption and cell that is
not an ``Html`` value, and ``Html`` values are made only by the building blocks of this module
(``cell``, ``badge``, ...) from escaped parts. Text from input (robot, joint and frame names,
error messages, paths) therefore reaches the page only as text, never as markup: a cell that
merely starts with ``<td`` is text like any other.

Self-contained by construction: the style sheet is inline, images are data: URIs (base64 PNG),
formulas are MathML (rendered by the browser, no script); the page has no script and loads
nothing from the network.
"""

from __future__ import annotations

import base64
import html
import io
import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

#: Section verdicts. FAIL: a check against a reference failed (the command exits 1);
#: "result": measured, with no pass criterion (e.g. how far a simulation departs);
#: "skipped": not run on request (--fast); "not available": the data does not exist yet.
VERDICTS = ("pass", "FAIL", "result", "skipped", "not available")


@dataclass(frozen=True)
class Section:
    key: str  # anchor id
    title: str
    verdict: str  # one of VERDICTS
    headline: str  # one line: the section's headline number
    body: str  # HTML


class Html(str):
    """Markup made by this module's building blocks (a table cell, a badge): inserted as is."""


def esc(x: object) -> str:
    return html.escape(str(x))


def num(x: Any, fmt: str = ".2e") -> str:
    """A number for a table cell: 'n/a' for None, NaN or a missing value."""
    if x is None or (isinstance(x, float) and math.isnan(x)):
        return "n/a"
    try:
        return format(x, fmt)
    except (TypeError, ValueError):
        return esc(x)


def grade(err: float | None, tol: float | None) -> str:
    """CSS class of an error against its tolerance: 'good' (<= 1 % of tol), 'near' (<= tol),
    'bad' (> tol or not finite), '' (no tolerance)."""
    if err is None or tol is None:
        return ""
    if not (math.isfinite(err) and math.isfinite(tol)):
        return "bad"
    return "good" if err <= 0.01 * tol else "near" if err <= tol else "bad"


def cell(content: str, cls: str = "") -> str:
    """A table cell of ready HTML, with an optional CSS class."""
    return Html(f'<td class="{esc(cls)}">{content}</td>' if cls else f"<td>{content}</td>")


def table(header: Sequence[str], rows: Sequence[Sequence[str]], caption: str = "", cls: str = "") -> str:
    """Rows of cells: each cell either from ``cell`` (an ``Html`` value) or text (escaped here,
    whatever it looks like)."""
    head = "".join(f"<th>{esc(h)}</th>" for h in header)
    body = "".join("<tr>" + "".join(c if isinstance(c, Html) else f"<td>{esc(c)}</td>" for c in row) + "</tr>"
                   for row in rows)
    cap = f"<caption>{esc(caption)}</caption>" if caption else ""
    attr = f' class="{cls}"' if cls else ""
    return f"<table{attr}>{cap}<thead><tr>{head}</tr></thead><tbody>{body}</tbody></table>"


def badge(verdict: str) -> str:
    return f'<span class="verdict v-{esc(verdict.replace(" ", "-").lower())}">{esc(verdict)}</span>'


def png_image(data: bytes, alt: str, width: int | None = None) -> str:
    style = f' style="max-width:{width}px"' if width else ""
    return f'<img alt="{esc(alt)}"{style} src="data:image/png;base64,{base64.b64encode(data).decode()}">'


def figure(fig: Any, alt: str, caption: str = "", width: int | None = None, dpi: int = 100) -> str:
    """A matplotlib figure embedded as PNG (the figure is closed)."""
    import matplotlib.pyplot as plt

    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=dpi, bbox_inches="tight")
    plt.close(fig)
    cap = f"<figcaption>{esc(caption)}</figcaption>" if caption else ""
    return f"<figure>{png_image(buf.getvalue(), alt, width)}{cap}</figure>"


def not_available(what: str) -> str:
    return f'<p class="na">{esc(what)}: not available.</p>'


_CSS = """
body { font-family: system-ui, sans-serif; margin: 0 auto; max-width: 1100px; padding: 1em 2em; color: #222; }
h1 { margin-bottom: 0.2em; } h2 { border-bottom: 2px solid #ccc; padding-bottom: 0.2em; margin-top: 2em; }
h3 { margin-top: 1.4em; }
.sub { color: #666; margin-top: 0; }
table { border-collapse: collapse; margin: 0.6em 0; font-size: 0.88em; }
th, td { border: 1px solid #ddd; padding: 0.2em 0.55em; text-align: right; font-variant-numeric: tabular-nums; }
th { background: #f3f3f3; } td:first-child, th:first-child { text-align: left; }
table.summary td, table.summary th { text-align: left; }
caption { text-align: left; font-weight: 600; padding: 0.3em 0; }
td.good { background: #d9f2d9; } td.near { background: #fff0c2; } td.bad { background: #f8c9c9; font-weight: 600; }
.verdict { display: inline-block; padding: 0.05em 0.6em; border-radius: 0.8em; font-size: 0.85em; font-weight: 600; }
.v-pass { background: #2e7d32; color: white; } .v-fail { background: #c62828; color: white; }
.v-result { background: #1565c0; color: white; } .v-skipped, .v-not-available { background: #9e9e9e; color: white; }
figure { margin: 0.8em 0; } figure img { max-width: 100%; border: 1px solid #eee; }
figcaption { color: #555; font-size: 0.9em; }
pre { background: #f7f7f7; padding: 0.6em; overflow-x: auto; font-size: 0.82em; }
.na { color: #777; font-style: italic; }
.warn { color: #8a4b00; }
math { font-family: "STIX Two Math", "Cambria Math", "Latin Modern Math", "DejaVu Math TeX Gyre", math; }
math[display="block"] { margin: 0.6em 0; font-size: 1.1em; overflow-x: auto; }
.nb { border: 1px solid #ccc; padding: 0 1em; margin: 1em 0; }
.nb-in { border-left: 3px solid #1565c0; } .nb-out { border-left: 3px solid #999; background: #fcfcfc; }
.nb-err { border-left: 3px solid #c62828; background: #fdecea; }
details > summary { cursor: pointer; font-weight: 600; margin: 0.5em 0; }
"""


def page(title: str, subtitle: str, sections: Sequence[Section]) -> str:
    """The whole report: title, the summary table (linking to each section), the sections."""
    summary = table(
        ["section", "result", "headline"],
        [[cell(f'<a href="#{esc(s.key)}">{esc(s.title)}</a>'), cell(badge(s.verdict)), s.headline] for s in sections],
        cls="summary",
    )
    body = "\n".join(f'<section id="{esc(s.key)}"><h2>{esc(s.title)} {badge(s.verdict)}</h2>\n{s.body}\n</section>'
                     for s in sections)
    return (f'<!DOCTYPE html>\n<html lang="en"><head><meta charset="utf-8"><title>{esc(title)}</title>'
            f"<style>{_CSS}</style></head>\n<body><h1>{esc(title)}</h1><p class=\"sub\">{esc(subtitle)}</p>\n"
            f"<h2>Summary</h2>{summary}\n{body}\n</body></html>\n")
