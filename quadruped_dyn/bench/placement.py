"""Timing rounds, each on fresh copies of the code it times: where a program's code lands in memory moves its time.

On this project's 2-core virtual machines (AMD EPYC Zen 5) byte-identical copies of the generated
library, each a new file (new page-cache pages), time differently and each copy keeps its time: over 12 copies of
a1's library ``qd_M_r_FL_FR_BL_BR`` took 687-1116 ns, ``qd_id_full`` 220-313 ns, ``qd_dfd_r_FL_BR`` 8.4-14.0 us
(median 707, 230, 8,666), while 8 copies of the pin wheel's ``libpinocchio_default.so`` moved
``constraintDynamics``, ``rnea`` and ``crba`` by 4 % at most (loops: a small hot footprint; the generated C is straight-line
code, tens of kB per call). One build timed in one place is one draw from that spread (docs/benchmark.md,
"Where the code lands"). So every round copies each harness and the libraries it times to a new directory and
runs the copy, and a function's time is the median over the rounds, for every side alike.
"""

from __future__ import annotations

import os
import shutil
import statistics
import tempfile
from dataclasses import dataclass
from pathlib import Path

from quadruped_dyn.codegen.library import run_tool


@dataclass(frozen=True)
class TimedProgram:
    """A timing harness: ``command[0]`` its executable, ``libraries`` the shared libraries whose code it times (copied
    beside it each round and found first: LD_LIBRARY_PATH, ahead of the harness's RUNPATH (linked --enable-new-dtags); their
    own dependencies from their original directories)."""

    command: list[str]
    libraries: tuple[Path, ...] = ()


def _run_copy(program: TimedProgram, directory: Path) -> str:
    exe = Path(shutil.copy(program.command[0], directory))
    for library in program.libraries:
        shutil.copy(library, directory)
    search = [str(directory), *dict.fromkeys(str(p.parent) for p in program.libraries)]
    env = {**os.environ, "LD_LIBRARY_PATH": os.pathsep.join([*search, os.environ.get("LD_LIBRARY_PATH", "")]).rstrip(os.pathsep)}
    return run_tool([str(exe), *program.command[1:]], env=env)


def parse_timings(output: str) -> dict[str, float]:
    """A harness's output, one "name ns" line per function (c/bench_median.h), as name -> ns."""
    return {name: float(value) for name, value in (line.split() for line in output.strip().splitlines())}


Timings = dict[str, dict[str, float]]  # side -> function name -> ns (or a ratio)


def median_over_rounds(programs: dict[str, TimedProgram], rounds: int) -> tuple[Timings, Timings]:
    """Run the programs in turn for ``rounds`` rounds, each run on fresh copies (``TimedProgram``). Returns per side
    (name -> median ns over the rounds, name -> max / min over them: the spread that placement and load gave)."""
    runs: dict[str, dict[str, list[float]]] = {side: {} for side in programs}
    for _ in range(rounds):
        for side, program in programs.items():
            with tempfile.TemporaryDirectory(prefix="qd-round-") as tmp:
                for name, ns in parse_timings(_run_copy(program, Path(tmp))).items():
                    runs[side].setdefault(name, []).append(ns)
    medians = {side: {n: statistics.median(v) for n, v in by.items()} for side, by in runs.items()}
    spreads = {side: {n: max(v) / min(v) if min(v) > 0 else float("inf") for n, v in by.items()} for side, by in runs.items()}
    return medians, spreads
