"""docs/results.md is written by ``report.results_page``: a section rerun rewrites its text and its header row
(machine and date), the other sections keep theirs, and the page round-trips."""

from __future__ import annotations

from datetime import datetime, timezone
from pathlib import Path

import pytest

from quadruped_dyn.errors import InputError
from quadruped_dyn.report import results_page

DOCS_PAGE = Path(__file__).resolve().parents[2] / "docs" / "results.md"
WHEN = datetime(2030, 1, 2, 3, 4, tzinfo=timezone.utc)
STAMP = WHEN.strftime("%Y-%m-%d %H:%M")


def test_the_committed_page_round_trips() -> None:
    """The committed page is in the module's format: parsed and rendered again, it is the same text."""
    text = DOCS_PAGE.read_text()
    sections, header = results_page.parse_page(text)
    assert set(sections) == set(header), "every section has its header row (machine and date)"
    assert "terms" in sections
    assert results_page.render(sections, header, results_page.section_titles(text)) == text


def test_a_rerun_section_gets_todays_machine_and_date(tmp_path, monkeypatch) -> None:
    page = tmp_path / "results.md"
    page.write_text(DOCS_PAGE.read_text())
    kept_before = results_page.parse_page(page.read_text())[0]["against"]
    monkeypatch.setitem(results_page.SECTIONS, "terms",
                        ("Every term against Pinocchio", lambda robots, samples: ("`cmd`", f"{robots} {samples}\n")))
    text = results_page.update_page(page, ["terms"], ["paper"], 3, now=WHEN)
    sections, header = results_page.parse_page(text)
    assert sections["terms"] == "['paper'] 3\n"
    assert header["terms"][1:] == ["`cmd`", results_page.machine(), STAMP]
    assert sections["against"] == kept_before and header["against"][3] != STAMP
    with pytest.raises(InputError, match="unknown section"):
        results_page.update_page(page, ["nonsense"], ["paper"], 1)


def test_the_terms_section_of_one_robot(tmp_path) -> None:
    """The real measurement on a small case: the paper robot, two states; a fresh page gets the header too."""
    page = tmp_path / "results.md"
    text = results_page.update_page(page, ["terms"], ["paper"], 2, now=WHEN)
    sections, header = results_page.parse_page(text)
    assert header["terms"][3] == STAMP and header["terms"][2] == results_page.machine()
    row = next(line for line in sections["terms"].splitlines() if line.startswith("| paper"))
    cells = [c.strip() for c in row.strip("|").split("|")]
    assert cells[1] == "pass"
    errors = [float(c.split()[0]) for c in cells[2:7]]
    assert all(0 <= e < 1e-9 for e in errors), row


def test_the_against_section_of_one_robot() -> None:
    """The same URDF through MuJoCo and iDynTree, on the paper robot: a row that passes, with both errors small."""
    pytest.importorskip("mujoco")
    pytest.importorskip("idyntree")
    command, text = results_page.against_section(["paper"], 2)
    assert "--samples 2" in command
    row = next(line for line in text.splitlines() if line.startswith("| paper"))
    cells = [c.strip() for c in row.strip("|").split("|")]
    assert cells[1] == "pass" and all(0 <= float(c) < 1e-12 for c in cells[2:4]), row
