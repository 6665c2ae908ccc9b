"""The notebooks, executed and rendered to HTML for the report (offline: Markdown by
markdown-it-py, code by Pygments with inline styles, images as data: URIs). The repository
keeps them without outputs; executing happens on a copy in memory."""

from __future__ import annotations

import re
import subprocess
import time
from pathlib import Path
from typing import Any

from quadruped_dyn.report.html import esc

#: The notebooks of a source checkout (not installed with the package).
NOTEBOOK_DIR = Path(__file__).resolve().parents[2] / "notebooks"

#: Seconds a single cell may run.
CELL_TIMEOUT_S = 600

_ANSI = re.compile(r"\x1b\[[0-9;]*m")


def notebook_paths() -> list[Path]:
    return sorted(NOTEBOOK_DIR.glob("*.ipynb")) if NOTEBOOK_DIR.is_dir() else []


def execute(path: Path) -> tuple[Any, float]:
    """Run a notebook top to bottom (errors end up in its outputs); (notebook, seconds)."""
    import nbformat
    from nbclient import NotebookClient

    nb = nbformat.read(path, as_version=4)
    start = time.perf_counter()
    client = NotebookClient(nb, timeout=CELL_TIMEOUT_S, kernel_name="python3", allow_errors=True,
                            resources={"metadata": {"path": str(path.parent)}})
    client.execute(stderr=subprocess.DEVNULL)  # the kernel's own log lines are not the notebook's output
    return nb, time.perf_counter() - start


def _output_html(out: dict[str, Any]) -> str:
    kind = out.get("output_type")
    if kind == "stream":
        return f'<pre class="nb-out">{esc(out.get("text", ""))}</pre>'
    if kind == "error":
        trace = _ANSI.sub("", "\n".join(out.get("traceback", [])))
        return f'<pre class="nb-err">{esc(trace or out.get("ename", "error"))}</pre>'
    data = out.get("data", {})
    if "image/png" in data:
        return f'<img alt="notebook figure" src="data:image/png;base64,{"".join(data["image/png"].split())}">'
    if "text/html" in data:  # our own notebooks' HTML (formulas as MathML)
        return f'<div class="nb-out">{data["text/html"]}</div>'
    if "text/plain" in data:
        return f'<pre class="nb-out">{esc(data["text/plain"])}</pre>'
    return ""


def render(nb: Any) -> str:
    """Cells of an executed notebook as HTML."""
    from markdown_it import MarkdownIt
    from pygments import highlight
    from pygments.formatters import HtmlFormatter
    from pygments.lexers import PythonLexer

    md = MarkdownIt("commonmark").enable("table")
    formatter = HtmlFormatter(noclasses=True, nowrap=False)
    parts = []
    for c in nb.cells:
        if c.cell_type == "markdown":
            parts.append(md.render(c.source))
        elif c.cell_type == "code":
            parts.append(f'<div class="nb-in">{highlight(c.source, PythonLexer(), formatter)}</div>')
            parts += [_output_html(o) for o in c.get("outputs", [])]
    return '<div class="nb">' + "\n".join(parts) + "</div>"


def error_count(nb: Any) -> int:
    return sum(o.get("output_type") == "error" for c in nb.cells for o in c.get("outputs", []))
