"""No function of the package is longer than ``MAX_FUNCTION_LINES``: counted with ``ast`` from its ``def``
(decorators aside) to its last line, docstring and comments included. The package holds no generated Python (the
generated code is C, written under an output directory), so every module is counted."""

from __future__ import annotations

import ast
from pathlib import Path

PACKAGE = Path(__file__).resolve().parents[1] / "quadruped_dyn"
#: The longest a function may be: one concept that reads on one screen; a longer one is split by concept.
MAX_FUNCTION_LINES = 80


def _long_functions(text: str) -> list[tuple[str, int]]:
    """(name, lines) of every function or method in ``text`` longer than MAX_FUNCTION_LINES."""
    return [(node.name, node.end_lineno - node.lineno + 1) for node in ast.walk(ast.parse(text))
            if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef) and node.end_lineno is not None
            and node.end_lineno - node.lineno + 1 > MAX_FUNCTION_LINES]


def test_the_count_sees_a_long_function():
    lines = [f"x{i} = {i}\n" for i in range(MAX_FUNCTION_LINES)]
    assert _long_functions("def f():\n" + "".join("    " + line for line in lines)) == [("f", MAX_FUNCTION_LINES + 1)]
    method = "class C:\n    async def g(self):\n" + "".join("        " + line for line in lines)
    assert _long_functions(method) == [("g", MAX_FUNCTION_LINES + 1)]
    assert _long_functions("def f():\n" + "".join("    " + line for line in lines[:-1])) == []


def test_no_function_is_longer_than_the_limit():
    modules = sorted(PACKAGE.rglob("*.py"))
    assert len(modules) > 50
    long = {f"{path.relative_to(PACKAGE.parent)}:{name}": lines for path in modules
            for name, lines in _long_functions(path.read_text())}
    assert not long, long
