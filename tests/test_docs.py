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
        modules = ({p.stem for p in (ROOT / "quadruped_dyn" / package).glob("*.py")} - {"__init__", "__main__"}) | {
            p.parent.name for p in (ROOT / "quadruped_dyn" / package).glob("*/__init__.py")}  # a subpackage of modules
        listed = set(re.findall(rf"^::: quadruped_dyn\.{package}\.(\w+)$", (ROOT / "docs" / "api" / f"{package}.md").read_text(),
                                flags=re.M))
        assert modules == listed, f"docs/api/{package}.md lists {sorted(listed)}, the package has {sorted(modules)}"


def test_code_cites_docs_not_spec():
    """Code cites docs/ sections, nothing outside the repository."""
    offenders = [f"{p.relative_to(ROOT)}:{i}" for folder in ("quadruped_dyn", "tests", "notebooks")
                 for p in (ROOT / folder).rglob("*") if p.suffix in (".py", ".ipynb", ".c", ".h") and p.name != "test_docs.py"
                 for i, line in enumerate(p.read_text().splitlines(), 1) if re.search(r"\bSPEC\b", line)]
    assert not offenders, offenders


#: A citation of a docs section in the package: ``docs/<page>.md, "<heading>"``, ``docs/<page>.md "<heading>"``,
#: ``docs/<page>.md §N`` (ranges ``§1-§3``, lists ``§6.2, §11``), the heading possibly after the section number.
CITATION = re.compile(r'(?:docs/)?([a-z_]+)\.md((?:[ ,]+§[\d.]+(?:\s*[-–]\s*§?[\d.]+)?)*)((?:(?:,\s+(?:[*#]\s*)?| )"[^"]+")*)')


def _headings(page: Path) -> list[str]:
    return [line.lstrip("#").strip() for line in page.read_text().splitlines() if line.startswith("#")]


def _stale_citations(text: str) -> tuple[int, list[str]]:
    """(citations found in ``text``, those whose page, heading or section number does not exist in docs/). A cited
    heading is a heading's text or its start; comment markers and line breaks inside it are ignored."""
    found, stale = 0, []
    for m in CITATION.finditer(text):
        page, sections, headings = ROOT / "docs" / f"{m.group(1)}.md", m.group(2), m.group(3)
        if not (sections or headings):
            continue
        found += 1
        if not page.is_file():
            stale.append(m.group(0))
            continue
        have = _headings(page)
        for cited in re.findall(r'"([^"]+)"', headings):
            cited = " ".join(re.sub(r"^\s*(?:\*|#|//)?\s*", "", line) for line in cited.splitlines()).strip()
            if not any(h.startswith(cited) for h in have):
                stale.append(f'{m.group(1)}.md "{cited}"')
        for number in re.findall(r"§([\d.]+)", sections):
            if not any(re.match(re.escape(number.rstrip(".")) + r"[.\s–]", h) for h in have):
                stale.append(f"{m.group(1)}.md §{number}")
    return found, stale


def test_a_stale_citation_is_found():
    assert _stale_citations('(docs/derivatives.md, "did_full by leg")') == (1, ['derivatives.md "did_full by leg"'])
    assert _stale_citations('docs/formulation.md §6.9 and docs/nowhere.md §1') == (2, ["formulation.md §6.9",
                                                                                      "docs/nowhere.md §1"])
    assert _stale_citations('(docs/embedded.md,\n * "The joints\' sines\n * and cosines")') == (1, [])


def test_docs_citations_in_the_package_name_existing_headings():
    """Every docs section the package's code, comments and C cite exists (a renamed or moved heading is caught)."""
    found, stale = 0, []
    for path in sorted((ROOT / "quadruped_dyn").rglob("*")):
        if path.suffix in (".py", ".c", ".h"):
            n, bad = _stale_citations(path.read_text())
            found += n
            stale += [f"{path.relative_to(ROOT)}: {b}" for b in bad]
    assert found > 30, "the citation pattern no longer matches the package's citations"
    assert not stale, stale
