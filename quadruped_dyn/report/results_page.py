"""``docs/results.md``, written by a command: every measured number on it comes with the command that measures it,
and the machine and date of each section's run in one header.

``python -m quadruped_dyn.report.results_page [--sections terms] [--robots paper,solo12] [--samples 200]
[--page docs/results.md]`` reruns the sections named (``SECTIONS``) and rewrites their text and their row of the
header; the other sections keep the text and the header row of their last run. A section is the text between
``<!-- section: NAME -->`` and ``<!-- /section -->``; the header is the table between ``<!-- header -->`` and
``<!-- /header -->``.
"""

from __future__ import annotations

import argparse
import re
import sys
from collections.abc import Callable, Sequence
from datetime import datetime, timezone
from pathlib import Path

from quadruped_dyn.errors import InputError
from quadruped_dyn.report.results_sections import (
    against_section,
    conditioning_section,
    experiment_section,
    operations_section,
    terms_section,
)

#: The robots of the default run: the built-in ones and example-robot-data's b1, by path.
DEFAULT_ROBOTS: tuple[str, ...] = ("paper", "solo12", "go2", "go1", "a1", "anymal_c", "hyq", "b1")
TITLE = "# Measured results"
INTRO = ("Every number here was measured by the command its section names; the header says on which machine and when\n"
         "each section was last run (`python -m quadruped_dyn.report.results_page --sections NAME` reruns one).\n"
         "Errors are relative (max |ours − reference| / max |reference|, worst over the states); timings are to be\n"
         "read as ratios, absolute times drift with the machine's load.")
HEADER_COLUMNS = ("section", "command", "machine", "date (UTC)")
_SECTION = re.compile(r"<!-- section: (?P<name>[\w-]+) -->\n(?P<body>.*?)<!-- /section -->", re.S)
_HEADER = re.compile(r"<!-- header -->\n(?P<body>.*?)<!-- /header -->", re.S)


def machine() -> str:
    """The CPU model, its cores and the compiler, in one cell."""
    from quadruped_dyn.report.gather import versions

    m = versions()["machine"]
    words = str(m["compiler"]).split()
    compiler = f"{words[0]} {words[-1]}" if words else "no gcc"  # "gcc (Debian 12.2.0-14) 12.2.0" -> "gcc 12.2.0"
    return f"{m['cpu']}, {m['cores']} cores, {compiler}, Python {m['python']}"


#: Section name -> (title, what reruns it): a function of (robots, samples) returning (command, Markdown).
SECTIONS: dict[str, tuple[str, Callable[[Sequence[str], int], tuple[str, str]]]] = {
    "terms": ("Every term against Pinocchio", terms_section),
    "conditioning": ("The reduced model's conditioning", conditioning_section),
    "against": ("Other libraries as references", against_section),
    "experiment": ("The paper's experiment", experiment_section),
    "generated-c": ("Generated C", operations_section),
}


def parse_page(text: str) -> tuple[dict[str, str], dict[str, list[str]]]:
    """(section name -> its text, section name -> its header row's cells) of a page this module wrote."""
    sections = {m["name"]: m["body"] for m in _SECTION.finditer(text)}
    header: dict[str, list[str]] = {}
    found = _HEADER.search(text)
    for line in (found["body"].splitlines() if found else []):
        cells = [c.strip() for c in re.split(r"(?<!\\)\|", line.strip().strip("|"))]
        if len(cells) == len(HEADER_COLUMNS) and cells[0] not in (HEADER_COLUMNS[0], "") and set(cells[0]) != {"-"}:
            header[cells[0]] = cells
    return sections, header


def render(sections: dict[str, str], header: dict[str, list[str]], titles: dict[str, str]) -> str:
    """The page: title, introduction, the header table, then every section under its title, in ``titles``' order."""
    rows = ["| " + " | ".join(HEADER_COLUMNS) + " |", "|" + "---|" * len(HEADER_COLUMNS)]
    rows += ["| " + " | ".join(header[name]) + " |" for name in titles if name in header]
    parts = [TITLE, "", INTRO, "", "<!-- header -->", *rows, "<!-- /header -->", ""]
    for name, title in titles.items():
        if name in sections:
            parts += [f"## {title}", "", f"<!-- section: {name} -->", sections[name].rstrip("\n"), "<!-- /section -->", ""]
    return "\n".join(parts)


def section_titles(text: str) -> dict[str, str]:
    """Section name -> title, in the page's order (a section's title is the heading just above its marker)."""
    titles = {m["name"]: m["title"] for m in re.finditer(r"^## (?P<title>.+)\n\n<!-- section: (?P<name>[\w-]+) -->",
                                                         text, re.M)}
    return {**titles, **{n: t for n, (t, _) in SECTIONS.items() if n not in titles}}


def update_page(page: Path, names: Sequence[str], robots: Sequence[str], samples: int, now: datetime | None = None) -> str:
    """Rerun the sections ``names`` and rewrite ``page``; return its new text."""
    unknown = [n for n in names if n not in SECTIONS]
    if unknown:
        raise InputError(f"unknown section {', '.join(unknown)}; expected some of {', '.join(SECTIONS)}")
    old = page.read_text() if page.exists() else ""
    sections, header = parse_page(old)
    stamp = (now or datetime.now(timezone.utc)).strftime("%Y-%m-%d %H:%M")
    where = machine()
    for name in names:
        command, sections[name] = SECTIONS[name][1](robots, samples)
        header[name] = [name, command.replace("|", "\\|"), where, stamp]
    text = render(sections, header, section_titles(old))
    page.write_text(text)
    return text


def main(argv: Sequence[str] | None = None) -> None:
    parser = argparse.ArgumentParser(prog="python -m quadruped_dyn.report.results_page", description=__doc__)
    parser.add_argument("--sections", default=",".join(SECTIONS), help="comma-separated: " + ", ".join(SECTIONS))
    parser.add_argument("--robots", default=",".join(DEFAULT_ROBOTS))
    parser.add_argument("--samples", type=int, default=200)
    parser.add_argument("--page", type=Path, default=Path("docs/results.md"))
    args = parser.parse_args(argv)
    if args.samples < 1:
        parser.error("--samples must be at least 1")
    try:
        update_page(args.page, [s for s in args.sections.split(",") if s], [r for r in args.robots.split(",") if r],
                    args.samples)
    except InputError as e:
        print(f"error: {e}", file=sys.stderr)
        sys.exit(2)


if __name__ == "__main__":
    main()
