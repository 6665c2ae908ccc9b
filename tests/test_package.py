"""The package's identity: its version in one place, the licence, the citation and the changelog."""

from __future__ import annotations

import importlib.metadata
import re
import subprocess
import sys
from pathlib import Path

import yaml
from click.testing import CliRunner

import quadruped_dyn
from quadruped_dyn.cli import main

ROOT = Path(__file__).resolve().parent.parent
PAPER_TITLE = "Kinematic and Dynamic Analysis of Quadruped Legged Robots: A New Formulation Approach"


def test_version_is_single_sourced() -> None:
    """pyproject.toml reads the version from ``quadruped_dyn.__version__`` (dynamic): the installed
    metadata says the same, and pyproject holds no literal version of its own."""
    assert re.fullmatch(r"\d+\.\d+\.\d+", quadruped_dyn.__version__)
    assert importlib.metadata.version("quadruped_dyn") == quadruped_dyn.__version__
    pyproject = (ROOT / "pyproject.toml").read_text()
    assert 'dynamic = ["version"]' in pyproject and 'attr = "quadruped_dyn.__version__"' in pyproject
    assert not re.search(r"^version\s*=", pyproject, re.MULTILINE)


def test_version_option() -> None:
    run = CliRunner().invoke(main, ["--version"])
    assert run.exit_code == 0 and run.output == f"quadruped-dyn {quadruped_dyn.__version__}\n"


def test_version_option_of_the_console_entry() -> None:
    """Through the entry point itself (``cli.entry``), as a user types it."""
    proc = subprocess.run([sys.executable, "-m", "quadruped_dyn.cli", "--version"], capture_output=True, text=True)
    assert proc.returncode == 0 and proc.stdout.strip() == f"quadruped-dyn {quadruped_dyn.__version__}"


def test_license_is_bsd_3_clause() -> None:
    text = (ROOT / "LICENSE").read_text()
    assert text.startswith("BSD 3-Clause License") and "quadruped_dyn developers" in text
    assert "Neither the name of the copyright holder" in text
    assert 'license = {text = "BSD-3-Clause"}' in (ROOT / "pyproject.toml").read_text()


def test_citation_names_the_paper_and_the_toolkit() -> None:
    cff = yaml.safe_load((ROOT / "CITATION.cff").read_text())
    assert cff["cff-version"] == "1.2.0" and cff["type"] == "software"
    assert cff["title"] == "quadruped_dyn" and cff["version"] == quadruped_dyn.__version__
    assert cff["license"] == "BSD-3-Clause"
    paper = cff["preferred-citation"]
    assert paper["title"] == PAPER_TITLE and paper["year"] == 2025
    assert [a["family-names"] for a in paper["authors"]] == ["Sureshkumar", "Harib", "Oseni"]
    assert PAPER_TITLE.split(":")[0] in (ROOT / "README.md").read_text().replace("\n", " ")


def test_changelog_has_an_entry_for_this_version() -> None:
    """Keep a Changelog: ``## [Unreleased]`` on top, then one ``## [X.Y.Z] - YYYY-MM-DD`` per version."""
    text = (ROOT / "CHANGELOG.md").read_text()
    headings = re.findall(r"^## \[([^\]]+)\]", text, re.MULTILINE)
    assert headings[0] == "Unreleased", headings
    assert quadruped_dyn.__version__ in headings
    assert re.search(rf"^## \[{re.escape(quadruped_dyn.__version__)}\] - \d{{4}}-\d{{2}}-\d{{2}}$", text, re.MULTILINE)
