"""The documentation site builds offline with warnings as errors (``mkdocs build --strict``):
every page in the nav, every link and anchor between pages, and the API reference of every
public module (mkdocstrings), whose docstrings must not break a cross-reference."""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent


def test_site_builds_strict_and_offline(tmp_path):
    pytest.importorskip("mkdocstrings_handlers.python", reason="the docs extra is not installed (pip install '.[docs]')")
    site = tmp_path / "site"
    proc = subprocess.run([sys.executable, "-m", "mkdocs", "build", "--strict", "--site-dir", str(site)],
                          cwd=ROOT, capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr[-3000:]
    for page in ("formulation", "conventions", "reliability", "results", "architecture"):
        assert (site / page / "index.html").is_file(), page
    api = (site / "api" / "model" / "index.html").read_text()
    assert 'id="quadruped_dyn.model.robot.load_robot"' in api  # the API reference is there, not just its headings
    for html in site.rglob("*.html"):  # nothing the pages load comes from the network
        assert not re.search(r'<(?:script|link|img)[^>]+(?:src|href)="(?:https?:)?//', html.read_text()), html


def test_every_subpackage_has_an_api_page():
    pages = {p.stem for p in (ROOT / "docs" / "api").glob("*.md")}
    packages = {p.parent.name for p in (ROOT / "quadruped_dyn").glob("*/__init__.py")}
    assert packages <= pages, (f"no API page for {sorted(packages - pages)}: add docs/api/<package>.md with one "
                               "'::: quadruped_dyn.<package>.<module>' line per module, and its line in mkdocs.yml's nav")
    for package in packages:
        modules = {p.stem for p in (ROOT / "quadruped_dyn" / package).glob("*.py")} - {"__init__", "__main__"}
        listed = set(re.findall(rf"^::: quadruped_dyn\.{package}\.(\w+)$", (ROOT / "docs" / "api" / f"{package}.md").read_text(),
                                flags=re.M))
        assert modules == listed, f"docs/api/{package}.md lists {sorted(listed)}, the package has {sorted(modules)}"


def test_code_cites_docs_not_spec():
    """Code cites docs/ sections, nothing outside the repository."""
    offenders = [f"{p.relative_to(ROOT)}:{i}" for folder in ("quadruped_dyn", "tests", "notebooks")
                 for p in (ROOT / folder).rglob("*") if p.suffix in (".py", ".ipynb", ".c", ".h") and p.name != "test_docs.py"
                 for i, line in enumerate(p.read_text().splitlines(), 1) if re.search(r"\bSPEC\b", line)]
    assert not offenders, offenders
