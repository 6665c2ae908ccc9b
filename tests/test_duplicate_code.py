"""No two places in the package hold the same logic: pylint's duplicate-code finder (``Symilar``, what
``pylint --enable=duplicate-code`` runs) over every module of ``quadruped_dyn``.

A run of ``MIN_SIMILARITY_LINES`` lines that are the same in two places (comments, docstrings and imports aside)
fails the test: one function should serve both. The import statements are blanked here with ``ast`` (pylint's own
``ignore-imports`` parses every module with astroid: 30x slower, the same findings).
"""

from __future__ import annotations

import ast
import io
import re
from contextlib import redirect_stdout
from pathlib import Path

import pytest

PACKAGE = Path(__file__).resolve().parents[1] / "quadruped_dyn"

#: The shortest run of equal lines that counts as a duplicate: 6, the length at which a copied piece of logic (a loop
#: with its body, a Function built the same way) shows; the package has none at 5 either.
MIN_SIMILARITY_LINES = 6


def _without_imports(text: str) -> str:
    """The module's text with its import statements' lines blank (line numbers kept)."""
    lines = text.split("\n")
    for node in ast.walk(ast.parse(text)):
        if isinstance(node, ast.Import | ast.ImportFrom):
            end = node.end_lineno or node.lineno
            lines[node.lineno - 1 : end] = [""] * (end - node.lineno + 1)
    return "\n".join(lines)


def test_no_duplicate_code_in_the_package() -> None:
    symilar = pytest.importorskip("pylint.checkers.symilar", reason="pylint is not installed (pip install '.[test]')")
    finder = symilar.Symilar(min_lines=MIN_SIMILARITY_LINES, ignore_comments=True, ignore_docstrings=True)
    modules = sorted(PACKAGE.rglob("*.py"))
    for path in modules:
        finder.append_stream(str(path.relative_to(PACKAGE.parent)), io.StringIO(_without_imports(path.read_text())))
    out = io.StringIO()
    with redirect_stdout(out):
        finder.run()
    total = re.search(r"TOTAL lines=(\d+) duplicates=(\d+)", out.getvalue())
    assert total, "pylint's report has no TOTAL line: " + out.getvalue()[-500:]
    assert len(modules) > 100 and int(total.group(1)) > 10_000, "the finder did not read the package"
    assert int(total.group(2)) == 0, out.getvalue()
