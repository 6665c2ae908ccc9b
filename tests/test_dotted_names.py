"""Every dotted name ``quadruped_dyn.x.y`` written in the repository's text resolves.

Imports inside strings (a child process's program, a notebook cell, a docs example) escape ruff and mypy: after
the layout move a slow test still imported ``quadruped_dyn.compiled`` and failed on import, not on what it tests."""
import importlib
import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
SEARCHED = ("quadruped_dyn", "tests", "notebooks", "docs")
SUFFIXES = {".py", ".md", ".ipynb", ".c", ".h", ".cpp", ".toml"}
DOTTED = re.compile(r"\bquadruped_dyn(?:\.[A-Za-z_][A-Za-z0-9_]*)+")


def _names() -> dict[str, str]:
    """Each dotted name -> one file that writes it."""
    found: dict[str, str] = {}
    files = [ROOT / "README.md", ROOT / "pyproject.toml"]
    for top in SEARCHED:
        files += [p for p in (ROOT / top).rglob("*") if p.suffix in SUFFIXES and ".ipynb_checkpoints" not in p.parts
                  and p != Path(__file__).resolve()]  # this file's own examples name stale modules on purpose
    for path in files:
        for name in DOTTED.findall(path.read_text(errors="replace")):
            found.setdefault(name.rstrip("."), str(path.relative_to(ROOT)))
    return found


def _resolves(name: str) -> bool:
    parts = name.split(".")
    for i in range(len(parts), 0, -1):
        try:
            obj = importlib.import_module(".".join(parts[:i]))
        except ModuleNotFoundError:
            continue
        for attr in parts[i:]:
            if not hasattr(obj, attr):
                return False
            obj = getattr(obj, attr)
        return True
    return False


def test_every_dotted_name_resolves():
    names = _names()
    assert len(names) > 20  # the scan found the package's names (a broken pattern would pass vacuously)
    missing = {name: where for name, where in names.items() if not _resolves(name)}
    assert not missing, f"names that do not resolve (name: a file writing it): {missing}"


def test_a_stale_name_is_caught():
    assert not _resolves("quadruped_dyn.compiled") and _resolves("quadruped_dyn.codegen.library.compiled_library")
