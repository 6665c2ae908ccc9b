"""The names of the files ``codegen`` writes, and the check that two robots in one folder never write the same file.

A robot's own files are ``qd_<name>.<ext>`` and ``qd_<name>-<role>.<ext>`` (``-d`` its derivatives, ``-r-<feet>``
a stance set's reduced model, ``-reference`` the check program's values); a robot's name never holds a ``-``
(``files.names.safe_name``), so the text before the first ``-`` or ``.`` is the robot's stem, whatever the name.
The files every robot's folder shares (``SHARED_FILES``: the Makefile, the check programs, the reduced templates,
the Cortex-M start-up) do not start with ``qd_``, so no robot's file is named as one of them; they are the same bytes
for every robot (the Makefile builds the robot ``ROBOT=<name>`` names, by default the one whose header is there).
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from pathlib import Path

from quadruped_dyn.errors import InputError
from quadruped_dyn.files.names import is_safe_name, printable, safe_name
from quadruped_dyn.model.stance import STANCE_SETS, StanceSet

#: What every stance set's name joins its feet with in file and C names ('FL+BR' -> 'FL_BR').
FEET_JOIN = "_"
#: Stance sets with a reduced model (docs/formulation.md §5-§6): four feet, the four triples, the six pairs.
REDUCED_STANCE_SETS: tuple[StanceSet, ...] = tuple(st for st in STANCE_SETS if len(st.feet) >= 2)
#: Between a robot's stem and a file's role: no robot name holds it.
ROLE_SEPARATOR = "-"

CHECK_PROGRAM = "check_qd.c"
MAKEFILE = "Makefile"
#: The hand-written templates of the reduced files (checks, fd_r's solve, dfd_r's solve), one header every reduced
#: file includes (not one copy per stance file: ~28 kB each); robot-independent.
REDUCED_TEMPLATES = "reduced_templates.h"
#: start-up and memory map of the check program on QEMU's MPS2 Cortex-M boards (the Makefile's cross builds)
CORTEX_M_FILES = ("cortex_m_startup.c", "cortex_m.ld")
#: the thread-safety check program (`make check-threads`)
THREADS_FILE = "check_threads.c"
#: The files of a generated folder that are no robot's: the same bytes whichever robot wrote them.
SHARED_FILES = (CHECK_PROGRAM, MAKEFILE, REDUCED_TEMPLATES, *CORTEX_M_FILES, THREADS_FILE)


def feet_suffix(stance: StanceSet) -> str:
    """'FL_BR' for the stance set FL+BR: the feet as C names and file names carry them."""
    return stance.name.replace("+", FEET_JOIN)


def robot_stem(name: str) -> str:
    """``qd_<name>``: the start of every file of the robot named ``name`` (made safe if it is not:
    ``files.names.safe_name``, injective)."""
    return f"qd_{name if is_safe_name(name) else safe_name(name)}"


def family_stem(key: str) -> str:
    """``qdp_<key>``: the files of a family's parametric library (``codegen.parametric_library``); no robot's file
    (those start with ``qd_``) is named as one of them."""
    return f"qdp_{key}"


def robot_file(name: str, role: str | None, suffix: str) -> str:
    """The file of robot ``name`` with ``role`` (None: its main source or header) and ``suffix`` ('.c', '.h')."""
    return robot_stem(name) + (f"{ROLE_SEPARATOR}{role}" if role else "") + suffix


def casadi_name(path: Path) -> str:
    """The name CasADi's CodeGenerator is given for the generated file ``path`` (a C identifier: the file's stem,
    its role separator as '_'); its static symbols carry it."""
    return path.stem.replace(ROLE_SEPARATOR, "_")


def reference_header_name(name: str) -> str:
    """The check program's reference values of robot ``name``: ``qd_<name>-reference.h``."""
    return robot_file(name, "reference", ".h")


@dataclass(frozen=True)
class GeneratedFiles:
    """The files ``generate`` writes, by what they are (callers never rely on an order)."""

    source: Path  # qd_<robot>.c: full-coordinate terms and GRF solves
    header: Path  # qd_<robot>.h: one header for all, documentation first
    extra: dict[str, Path]  # file name -> path of each of ``extra_files``' files (e.g. the reference values)
    check_program: Path  # check_qd.c
    makefile: Path
    reduced: tuple[Path, ...]  # qd_<robot>-r-<feet>.c: the reduced model of each stance set of 2-4 feet
    reduced_templates: Path  # reduced_templates.h: the hand-written templates every reduced file includes
    derivatives: tuple[Path, ...] = ()  # qd_<robot>-d.c: derivatives of the full dynamics
    embedded: tuple[Path, ...] = ()  # Cortex-M start-up and linker script, check_threads.c (docs/embedded.md)

    @property
    def c_sources(self) -> list[Path]:
        """The generated C files of the library (not the check program)."""
        return [self.source, *self.reduced, *self.derivatives]

    @property
    def library_sources(self) -> list[Path]:
        """What the library is compiled from: ``c_sources`` and the headers they include (its size is the
        generated C's size, docs/benchmark.md)."""
        return [*self.c_sources, self.header, self.reduced_templates]

    def all(self) -> list[Path]:
        """Every file, in the order they are written."""
        return [self.source, self.header, *self.extra.values(), self.check_program, *self.embedded, self.makefile,
                *self.reduced, self.reduced_templates, *self.derivatives]

    def own(self) -> set[str]:
        """The names of the files that are this robot's alone (not ``SHARED_FILES``)."""
        return {p.name for p in self.all()} - set(SHARED_FILES)


def file_layout(name: str, out_dir: Path, extra_names: tuple[str, ...] = ()) -> GeneratedFiles:
    """The files ``generate`` writes into ``out_dir`` for the robot ``name`` (with ``extra_names`` for its
    ``extra_files``), by role: the one place their names are made, known before the work (a command refuses a file
    it cannot write first)."""
    out_dir = Path(out_dir)
    return GeneratedFiles(source=out_dir / robot_file(name, None, ".c"), header=out_dir / robot_file(name, None, ".h"),
                          extra={f: out_dir / f for f in extra_names}, check_program=out_dir / CHECK_PROGRAM,
                          makefile=out_dir / MAKEFILE,
                          reduced=tuple(out_dir / robot_file(name, f"r-{feet_suffix(st)}", ".c")
                                        for st in REDUCED_STANCE_SETS),
                          reduced_templates=out_dir / REDUCED_TEMPLATES,
                          derivatives=(out_dir / robot_file(name, "d", ".c"),),
                          embedded=tuple(out_dir / f for f in (*CORTEX_M_FILES, THREADS_FILE)))


#: A robot's header in a generated folder: its name is the text between ``qd_`` and ``.h``.
_HEADER = re.compile(r"qd_([A-Za-z][A-Za-z0-9_]*)\.h")


def robots_in(out_dir: Path) -> list[str]:
    """The names of the robots whose generated header is in ``out_dir``."""
    if not Path(out_dir).is_dir():
        return []
    return sorted(m.group(1) for p in Path(out_dir).iterdir() if (m := _HEADER.fullmatch(p.name)))


def check_no_collision(layout: GeneratedFiles, name: str, out_dir: Path) -> None:
    """InputError if a file ``layout`` (robot ``name``'s) writes into ``out_dir`` is one that another robot there
    wrote (its files as ``file_layout`` names them), naming both robots and the first such file."""
    own = layout.own()
    for other in robots_in(out_dir):
        if other == name:
            continue
        shared = own & file_layout(other, out_dir, (reference_header_name(other),)).own()
        if shared:
            raise InputError(f"--out '{printable(str(out_dir))}' holds the generated C of '{other}', and '{name}' "
                             f"would write over its {sorted(shared)[0]}; expected another --out for '{name}'")
