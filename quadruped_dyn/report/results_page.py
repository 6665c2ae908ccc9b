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
import textwrap
from collections.abc import Callable, Sequence
from datetime import datetime, timezone
from pathlib import Path
from typing import TYPE_CHECKING

from quadruped_dyn.errors import InputError

if TYPE_CHECKING:
    from quadruped_dyn.references.interface import ModelChange

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


def robot_path(name: str) -> str:
    """A built-in robot's name as it is, ``b1`` as its example-robot-data URDF path."""
    if name != "b1":
        return name
    from quadruped_dyn.model import example_robot_data_dir

    return str(Path(example_robot_data_dir()) / "b1_description" / "urdf" / "b1.urdf")


def terms_section(robots: Sequence[str], samples: int) -> tuple[str, str]:
    """(command, Markdown) of every term against Pinocchio, one row per robot."""
    from quadruped_dyn.checks.terms import run_check
    from quadruped_dyn.model.robot import load_robot

    rows = []
    for name in robots:
        report = run_check(load_robot(robot_path(name)), samples, 0)
        full = [t for t in report.terms if not re.search(r"_r |^d", t.name)]
        reduced = [t for t in report.terms if "_r " in t.name]
        derivatives = [t for t in report.terms if t.name.startswith(("did_", "dfd_"))]
        worst_reduced = max(reduced, key=lambda t: t.max_rel_err)
        rows.append(f"| {name}{' (by path)' if name == 'b1' else ''} | {'pass' if report.passed else 'FAIL'} "
                    f"| {max(t.max_rel_err for t in full):.1e} "
                    f"| {worst_reduced.max_rel_err:.1e} ({worst_reduced.name}) "
                    f"| {max(t.max_rel_err for t in derivatives):.1e} "
                    f"| {max(g.max_err_vs_reference for g in report.grf):.1e} "
                    f"| {max(g.max_err_vs_pinocchio for g in report.grf):.1e} "
                    f"| {max(g.max_cond for g in report.grf):.1e} |")
    command = f"`quadruped-dyn check ROBOT --samples {samples} --json` (seed 0)"
    table = ["| robot | result | full-coordinate terms | reduced terms (worst) | derivatives | GRF vs SVD "
             "| GRF vs Pinocchio | largest cond(A) |", "|---|---|---|---|---|---|---|---|", *rows]
    prose = (f"{command}; tolerance 1e-10 for the terms, 1e-9 for the derivatives (`tolerances.py`). Worst relative "
             f"error over the {samples} states; the full-coordinate terms are M_full (three ways), C_full, G_full, the "
             "Coriolis matrix, id_full and the foot kinematics; the reduced ones id_r, M_r, C_r, G_r of four stance "
             "sets; the derivatives did_full and dfd_full against Pinocchio's analytical ones; the GRF columns cover 16 "
             "stance sets × 2 models. The reduced terms carry the conditioning of the maps and of the GRF solve, hence "
             "their larger errors; the GRF ranks are 5 / 6 / 5 with four / three / two feet.")
    text = "\n".join(textwrap.wrap(prose, 118, break_on_hyphens=False)) + "\n\n" + "\n".join(table) + "\n"
    return command, text


def _changes(changes: Sequence[ModelChange]) -> str:
    """What the libraries did to the model, one clause per change (``references.interface.ModelChange``)."""
    parts = []
    for c in changes:
        links = ", ".join(c.links[:3]) + (f" +{len(c.links) - 3}" if len(c.links) > 3 else "")
        size = f", M changes {c.size['M']:.1e}" if "M" in c.size else ""
        used = "" if c.in_comparison else ", not compared"
        parts.append(f"{c.library} {c.kind}{f' ({links})' if c.links else ''}{size}{used}")
    return "; ".join(parts) or "nothing"


def against_section(robots: Sequence[str], samples: int) -> tuple[str, str]:
    """(command, Markdown) of the same URDF through MuJoCo and iDynTree against Pinocchio, one row per robot."""
    from quadruped_dyn.checks.cross_library import parse_libraries, run_cross_library
    from quadruped_dyn.model.robot import load_robot

    libraries = parse_libraries("mujoco,idyntree")
    n = min(samples, 20)
    rows = []
    for name in robots:
        report = run_cross_library(load_robot(robot_path(name)), libraries, n, 0)
        worst = {lib: max((r.max_rel_err for r in report.results if r.library == lib), default=float("nan"))
                 for lib in libraries}
        rows.append(f"| {name}{' (by path)' if name == 'b1' else ''} | {'pass' if report.passed else 'FAIL'} | "
                    + " | ".join(f"{worst[lib]:.1e}" for lib in libraries) + f" | {_changes(report.changes).replace('|', '/')} |")
    command = f"`quadruped-dyn check ROBOT --against mujoco,idyntree --samples {n}` (seed 0)"
    prose = (f"{command}: M, C + G, G and the foot Jacobians of the same URDF through MuJoCo and iDynTree, largest "
             "relative error against Pinocchio over the terms; a difference the diagnosed model changes explain passes "
             "(conventions.md §10).")
    note = ("Errors of ~1e-12 where a URDF writes right angles with ten digits (1.5707963268: hyq, anymal_c) are the "
            "toolkit's snapping of placements (`SNAP_TOL` = 1e-9, moving the model by ~5e-12 rad); MuJoCo and iDynTree, "
            "both reading the raw numbers, agree with each other to round-off there. A change that is not compared "
            "(MuJoCo's own `balanceinertia` or `inertiafromgeom`) is what the library would do unasked, and its size.")
    table = ["| robot | result | MuJoCo | iDynTree | what the libraries did to the model |", "|---|---|---|---|---|", *rows]
    wrap = "\n".join
    return command, (wrap(textwrap.wrap(prose, 118, break_on_hyphens=False)) + "\n\n" + wrap(table) + "\n\n"
                     + wrap(textwrap.wrap(note, 118, break_on_hyphens=False)) + "\n")


#: Section name -> (title, what reruns it): a function of (robots, samples) returning (command, Markdown).
SECTIONS: dict[str, tuple[str, Callable[[Sequence[str], int], tuple[str, str]]]] = {
    "terms": ("Every term against Pinocchio", terms_section),
    "against": ("Other libraries as references", against_section),
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
