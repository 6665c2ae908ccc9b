"""The repository speaks of the project only: no work-log labels (numbered sessions or rounds of work, who
did them, this project's issue numbers) and no dates, anywhere but in CHANGELOG.md.

Every file git tracks is read: docs, code, tests, notebooks, generated
files, the README. Another project's tracker is cited as ``owner/repo#N``. A hit fails naming file:line.
"""

from __future__ import annotations

import re
import shutil
import subprocess
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
THIS = Path(__file__).resolve().relative_to(ROOT).as_posix()
#: The one place dates and versions' history belong.
ALLOWED = {"CHANGELOG.md", THIS}

#: Dates that are data: the measured-results page's header says when each section was measured.
DATED_HEADERS = {"docs/results.md": re.compile(r"<!-- header -->.*?<!-- /header -->", re.S)}

#: TEMPORARY: folders whose hits are being fixed by the code generator's rework (and casadi_gen/ regenerated
#: from it). The lead empties this list at merge; it must not grow.
TEMPORARY_EXCLUSIONS: tuple[str, ...] = ()

_MONTHS = "January|February|March|April|May|June|July|August|September|October|November|December"
LABELS: dict[str, re.Pattern[str]] = {
    "a numbered session": re.compile(r"\bsessions? \d+", re.IGNORECASE),
    "a numbered round of work": re.compile(r"\brounds? \d+|\b(first|second|third|fourth|fifth|sixth) round\b",
                                           re.IGNORECASE),
    "who did the work": re.compile(r"\bhelper (session|review|h?\d+)", re.IGNORECASE),
    "an issue number": re.compile(r"\bissues? #?\d+", re.IGNORECASE),
    # '#N' not in owner/repo#N form (nor a CSS colour such as '#222;')
    "a '#N' reference": re.compile(r"(?<![\w/.-])#\d+\b(?!;)"),
    "a date": re.compile(rf"\b(19|20)\d\d-(0[1-9]|1[0-2])-([0-2]\d|3[01])\b|\b({_MONTHS}) (19|20)\d\d\b"),
}


def repository_files() -> list[str]:
    """The files git tracks, relative to the root (a command's outputs in the checkout, e.g. ``gen/``, are not the
    repository's)."""
    if shutil.which("git") is None or not (ROOT / ".git").exists():
        pytest.skip("not a git checkout: the files of the repository are not known")
    out = subprocess.run(["git", "ls-files", "-z"], cwd=ROOT,
                         capture_output=True, check=True).stdout.decode()
    return sorted({f for f in out.split("\0") if f and (ROOT / f).is_file()})


def text_of(path: Path) -> str | None:
    data = path.read_bytes()
    if b"\0" in data:
        return None
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError:
        return None


def hits(relative: str, text: str) -> list[str]:
    """``file:line: what (the matched text)`` for every label in ``text``."""
    found = []
    for number, line in enumerate(text.splitlines(), 1):
        for what, pattern in LABELS.items():
            for m in pattern.finditer(line):
                found.append(f"{relative}:{number}: {what} ({m.group(0)!r})")
    return found


def test_the_patterns_find_labels_and_pass_plain_text() -> None:
    for text in ("session 12", "round 3 of reliability", "the third round of review",
                 "helper review", "issue 51", "issues #7", "(#18 item 5)", "since 2026-12-02", "December 2026"):
        assert hits("x", text), text
    for text in ("casadi/casadi#2959", "color: #222;", "round(x, 3)", "a scalar helper", "<h2>", "h10 * h", "the 2,000 lines",
                 "version 0.1.0", "1e-10", "rounds of x", "#include <math.h>"):
        assert not hits("x", text), text


def test_no_work_log_labels_or_dates() -> None:
    found = []
    for relative in repository_files():
        if relative in ALLOWED or relative.startswith(TEMPORARY_EXCLUSIONS):
            continue
        text = text_of(ROOT / relative)
        if relative in DATED_HEADERS and text is not None:
            text = DATED_HEADERS[relative].sub(lambda m: "\n" * m.group(0).count("\n"), text)
        if text is not None:
            found += hits(relative, text)
    assert not found, f"{len(found)} work-log labels or dates:\n" + "\n".join(found[:200])
