"""Benchmark of the generated C against Pinocchio's native C++, measured in the same run.

Both sides are timed in compiled code (``c/bench_qd.c`` and ``c/bench_pinocchio.cpp``, and
with ``peer`` Pinocchio's CppADCodeGen code, ``cppadcg.py``): the median over ``reps`` runs of
``calls`` calls each, fewer for a function slower than 2 ms / ``calls`` (every harness stops a run
at about 2 ms: ``c/bench_median.h``, QD_RUN_BUDGET_NS), each harness's runs interleaved across its
functions (a few ms of disturbance spoil one run of a few functions, not all of one's); the harnesses alternate for ``rounds``
rounds, each round on fresh copies of the harnesses and the libraries they time (where code lands in memory moves the
generated C's time by up to 1.6x: placement.py), and a function's time is its median over the rounds. Ratios are what to
read; absolute times drift with the machine's load. By default the Pinocchio harness links the pin
wheel's libraries (built for generic x86-64) and the generated C is built with ``C_FLAGS``, so
neither side uses -march=native; ``native`` builds the generated C and the peer for this machine
(Pinocchio native stays the wheel's build: harnesses.py says why).
Pairs: M_full ~ crba, nle_full (C + G in one call) ~ nonLinearEffects, G_full ~
computeGeneralizedGravity, id_full ~ rnea (id_full also applies 4 foot forces), did_full ~ computeRNEADerivatives,
dfd_full ~ computeABADerivatives, fd_r_<feet> ~
constraintDynamics with those stance feet, dfd_r_<feet> ~ constraintDynamics + computeConstraintDynamicsDerivatives
with those feet (the analytical derivatives need the forward dynamics first; dfd_r also computes qdd_r).
The reduced terms M_r, CG_r, G_r, id_r are timed alone.
"""

from __future__ import annotations

import ctypes
import functools
import hashlib
import shutil
import sys
import tempfile
import time
import timeit
from dataclasses import asdict, dataclass, field
from pathlib import Path

import numpy as np
import pinocchio as pin

from quadruped_dyn.bench import cppadcg
from quadruped_dyn.bench.call_cost import (
    NOT_MEASURED,
    CallCost,
    arithmetic_operations,
    call_cost_table,
    cpu_model,
    generated_call_costs,
    valgrind_available,
)
from quadruped_dyn.bench.harnesses import HARNESSES, PINOCCHIO_CXX_FLAGS, cmeel_prefix, pinocchio_program, require_headers
from quadruped_dyn.bench.placement import TimedProgram, median_over_rounds
from quadruped_dyn.bench.timing_counts import check_counts
from quadruped_dyn.checks.check_program_values import generate_checked, reference_header_name
from quadruped_dyn.codegen.emit import PREFIX, GeneratedFiles, codegen_functions
from quadruped_dyn.codegen.library import (
    C_FLAGS,
    CompiledFunction,
    CompiledLibrary,
    compile_sources,
    compiled_library,
    compiler_version,
    run_tool,
    work_sizes_of,
)
from quadruped_dyn.files.cache import cache_dir, cached_build
from quadruped_dyn.model.robot import Robot
from quadruped_dyn.model.state import random_state
from quadruped_dyn.references.pinocchio import PinocchioReference

#: fd_r_<feet> is timed against Pinocchio's constraintDynamics with the same stance feet as rigid
#: point contacts (different physics: the paper's GRF model vs rigid contacts; the same job, a
#: forward dynamics step of a robot on those feet). Target ratio generated / Pinocchio.
FD_R_TARGET = 0.25
#: dfd_r_<feet> against constraintDynamics + computeConstraintDynamicsDerivatives with the same feet (docs/derivatives.md)
DFD_R_TARGET = 0.5

#: generated function -> (Pinocchio algorithm, target ratio generated / Pinocchio)
PAIRS = {
    "M_full": ("crba", 0.4),
    "nle_full": ("nonLinearEffects", 0.18),
    "G_full": ("computeGeneralizedGravity", 0.15),
    "id_full": ("rnea", 0.2),
    # derivatives (docs/derivatives.md): d/dq, d/dv, d/da (= M) of rnea; d/dq, d/dv, d/dtau (= M^-1) of aba
    "did_full": ("computeRNEADerivatives", 0.5),
    "dfd_full": ("computeABADerivatives", 0.5),
}


@dataclass
class BenchEntry:
    name: str
    generated_ns: float
    pinocchio: str | None = None
    pinocchio_ns: float | None = None
    ratio: float | None = None
    target: float | None = None
    python_generated_us: float | None = None
    python_pinocchio_us: float | None = None
    generated_spread: float | None = None  # max / min of generated_ns over the rounds' fresh copies (placement.py)
    pinocchio_spread: float | None = None  # the same of pinocchio_ns


@dataclass
class BenchReport:
    robot: str
    entries: list[BenchEntry] = field(default_factory=list)
    code_bytes: int = 0  # generated C: the library's sources and the headers they include
    source_files: int = 0  # generated C files
    library_bytes: int = 0  # compiled shared library (-O3)
    work_bytes: int = 0  # largest caller-provided work memory (iw + w) of any function; temporaries are locals
    generation_s: float | None = None  # None: the caller generated the C (``run_bench(checked_c=...)``)
    compile_s: float = 0.0  # compiling the objects not in the build cache (``compiled_objects``) and linking
    compiled_objects: int = 0  # of the generated C's files; the others had been compiled with these flags before
    pinocchio_version: str = pin.__version__
    native: bool = False  # both sides built with -march=native (``bench --native``)
    c_flags: list[str] = field(default_factory=list)  # of the generated C
    pinocchio_flags: list[str] = field(default_factory=list)  # of the Pinocchio harness
    peers: list[cppadcg.PeerTiming] = field(default_factory=list)  # Pinocchio's CppADCodeGen code, same rounds
    rounds: int = 0  # timing rounds, each on fresh copies of every harness and library timed (placement.py)
    cpu_model: str = field(default_factory=cpu_model)  # /proc/cpuinfo's model name
    compiler: str = ""  # the first line of ``cc --version``
    call_costs: list[CallCost] = field(default_factory=list)  # counted per call under callgrind (call_cost.py)
    call_cost_note: str | None = None  # why call_costs is empty (NOT_MEASURED), None when counted or not asked
    #: per term (parametric_timing.PAIRS): the parametric library's ns per call against the fixed library's and
    #: Pinocchio's, same run (``parametric_timings``); None when not asked (``bench --parametric``)
    parametric: dict[str, dict[str, float]] | None = None

    def as_dict(self) -> dict[str, object]:
        return asdict(self)

    def table(self) -> str:
        rows = [["function", "generated ns", "Pinocchio", "ratio", "target", "py gen us", "py pin us"]]
        for e in self.entries:
            rows.append([e.name, f"{e.generated_ns:.1f}", f"{e.pinocchio} {e.pinocchio_ns:.0f} ns" if e.pinocchio else "",
                         f"{e.ratio:.2f}" if e.ratio is not None else "",
                         f"<={e.target:.2f}" if e.target is not None else "",
                         f"{e.python_generated_us:.1f}" if e.python_generated_us is not None else "",
                         f"{e.python_pinocchio_us:.1f}" if e.python_pinocchio_us is not None else ""])
        lines = aligned(rows)
        lines.append(
            f"{self.robot}: C source {self.code_bytes / 1e3:.0f} kB, library {self.library_bytes / 1e3:.0f} kB, "
            f"max work memory {self.work_bytes} B, "
            + (f"generation {self.generation_s:.1f} s, " if self.generation_s is not None else "")
            + f"compile {self.compile_s:.1f} s "
            f"(Pinocchio {self.pinocchio_version}; {' '.join(self.c_flags)})"
        )
        if self.peers:
            peer_rows = [["peer function", "peer ns", "generated", "ratio", "target", "Pinocchio native", "peer/native",
                          "peer err"]]
            for p in self.peers:
                peer_rows.append([p.peer_function, f"{p.peer_ns:.0f}",
                                  f"{p.name} {p.generated_ns:.0f} ns" if p.name and p.generated_ns is not None else "",
                                  f"{p.ratio:.2f}" if p.ratio is not None else "",
                                  f"<={p.target:.2f}" if p.target is not None else "",
                                  f"{p.pinocchio} {p.pinocchio_ns:.0f} ns", f"{p.peer_vs_pinocchio:.2f}",
                                  f"{p.checked_rel_error:.0e}"])
            lines += aligned(peer_rows)
            lines.append(f"peer: {self.peers[0].peer}, same flags as the generated C, timed in the same rounds")
        if self.call_costs:
            lines += aligned(call_cost_table(self.call_costs))
            lines.append("per call, counted by callgrind (the same on any machine); I1: a simulated 32 kB 8-way cache")
        elif self.call_cost_note:
            lines.append(f"instructions and code per call: {self.call_cost_note}")
        if self.parametric:
            lines += aligned([["parametric term", "parametric ns", "fixed ns", "Pinocchio ns", "vs Pinocchio", "vs fixed"],
                              *([name, f"{t['parametric_ns']:.0f}", f"{t['fixed_ns']:.0f}", f"{t['pinocchio_ns']:.0f}",
                                 f"{t['vs_pinocchio']:.2f}", f"{t['vs_fixed']:.2f}"] for name, t in self.parametric.items())])
            lines.append("parametric: the family's library with p as an input (docs/embedded.md), default flags, own rounds")
        lines.append(f"CPU: {self.cpu_model}; compiler: {self.compiler}")
        return "\n".join(lines)


def aligned(rows: list[list[str]]) -> list[str]:
    """Rows of cells as text lines: the first column left-aligned, the others right-aligned, each column as wide
    as its widest cell plus two spaces (so a long Pinocchio name never runs into the next column)."""
    widths = [max(len(row[i]) for row in rows) for i in range(len(rows[0]))]
    return [row[0].ljust(widths[0]) + "".join(cell.rjust(w + 2) for cell, w in zip(row[1:], widths[1:]))
            for row in rows]


def pinocchio_harness(cxx: str = "g++") -> Path:
    """The compiled Pinocchio benchmark, built once per (source, pin version, build command: flags, the wheel's
    paths, the link's RUNPATH that placement.py relies on), linked with the wheel's algorithms (harnesses.py)."""
    require_headers(("eigen3/Eigen/Core", "urdfdom_headers/urdf_model/model.h"),
                    "the cmeel-eigen and cmeel-urdfdom-headers packages (pip install cmeel-eigen cmeel-urdfdom-headers)")
    source = HARNESSES / "bench_pinocchio.cpp"
    flags = PINOCCHIO_CXX_FLAGS
    command = " ".join(pinocchio_program([Path(source.name)], Path("bench_pinocchio"), flags, cxx))
    key = hashlib.sha256(source.read_bytes() + pin.__version__.encode() + command.encode()).hexdigest()[:16]

    def build(exe: Path) -> None:
        print(f"building the Pinocchio benchmark harness once (about a minute) into {cache_dir()}", file=sys.stderr)
        run_tool(pinocchio_program([source], exe, flags, cxx))

    return cached_build(f"pinocchio-bench-{key}", "bench_pinocchio", build)


def run_bench(robot: Robot, calls: int = 20000, reps: int = 9, rounds: int = 9, cc: str = "gcc", native: bool = False,
              peer: bool = False, checked_c: GeneratedFiles | None = None, call_cost: bool = False,
              parametric: bool = False) -> BenchReport:
    """Time every generated function and its Pinocchio counterpart in the same run; with ``peer``
    also Pinocchio's CppADCodeGen code (cppadcg.py, checked against Pinocchio first). ``native``:
    the generated C and the peer built with -march=native (Pinocchio native stays the wheel's).
    ``checked_c``: ``generate_checked``'s files of ``robot`` (double), already written (the
    report's own c/), timed as they are instead of generated again (``generation_s`` is then None).
    ``call_cost``: also count each function's instructions, I1 misses and code bytes per call (call_cost.py;
    ``call_cost_note`` says NOT_MEASURED without valgrind) beside the graphs' operations.
    ``parametric``: also the family's parametric library against the fixed library and Pinocchio
    (``parametric_timings``; its build, once per family, costs about a minute).
    InputError for counts outside ``timing_counts.check_counts``' bounds, before anything is built."""
    check_counts(calls, reps)
    flags = (*C_FLAGS, "-Dcasadi_real=double", *(("-march=native",) if native else ()))  # as library.compiled_library
    report = BenchReport(robot.name, native=native, c_flags=list(flags),
                         pinocchio_flags=list(PINOCCHIO_CXX_FLAGS),  # the wheel's algorithms, --native or not
                         compiler=compiler_version(cc))
    with tempfile.TemporaryDirectory() as tmp:
        files = checked_c
        if files is None or reference_header_name(robot) not in files.extra:
            start = time.perf_counter()
            codegen_functions(robot)  # symbolic build + generation, timed apart from compilation
            files = generate_checked(robot, Path(tmp))  # the check program's reference inputs drive the harness
            report.generation_s = time.perf_counter() - start
        c_path, h_path, ref_path = files.source, files.header, files.extra[reference_header_name(robot)]
        sources = files.c_sources
        report.code_bytes = sum(p.stat().st_size for p in files.library_sources)
        report.source_files = len(sources)
        for name in ("bench_qd.c", "bench_median.h"):
            shutil.copy(HARNESSES / name, tmp)
        exe, lib = Path(tmp) / "bench_qd", Path(tmp) / f"lib{c_path.stem}.so"
        start = time.perf_counter()
        report.compiled_objects = compile_sources(sources, flags, lib, cc)  # the library's objects, when cached
        report.compile_s = time.perf_counter() - start
        if call_cost and valgrind_available():
            operations = {f.name(): arithmetic_operations(f) for f in codegen_functions(robot)}
            report.call_costs = generated_call_costs(sources, h_path, ref_path, flags, operations, cc)
        elif call_cost:
            report.call_cost_note = NOT_MEASURED
        run_tool([cc, *flags, f"-I{h_path.parent.resolve()}",  # the headers beside the generated C (cwd is tmp)
                  f"-DQD_HEADER=\"{h_path.name}\"", f"-DQD_REFERENCE=\"{ref_path.name}\"", "bench_qd.c",
                  lib.name, "-Wl,--enable-new-dtags", f"-Wl,-rpath,{tmp}", "-lm", "-o", exe.name], cwd=tmp)
        harness = pinocchio_harness()
        feet = [robot.model.frames[i].name for i in robot.foot_frame_ids]
        commands = {"generated": [str(exe), str(calls), str(reps)],
                    "pinocchio": [str(harness), str(robot.urdf), str(calls), str(reps), *feet]}
        libraries = {"generated": (lib,), "pinocchio": (cmeel_prefix() / "lib" / "libpinocchio_default.so",)}
        if peer:
            peer_exe = cppadcg.harness(robot, native, cc)
            peer_errors = cppadcg.check(robot, peer_exe)  # NumericalError before any timing if it differs
            commands["peer"] = cppadcg.time_command(robot, peer_exe, calls, reps)
        programs = {side: TimedProgram(cmd, libraries.get(side, ())) for side, cmd in commands.items()}
        median, spread = median_over_rounds(programs, rounds)  # harnesses alternate, fresh copies each round
    generated, pinocchio = median["generated"], median["pinocchio"]
    report.rounds = rounds
    if peer:
        report.peers = cppadcg.timings({n[len(PREFIX):]: t for n, t in generated.items()}, median["peer"], pinocchio, peer_errors)
    library = compiled_library(robot, cc=cc)
    report.library_bytes = library.path.stat().st_size
    functions = ctypes.CDLL(str(library.path))  # each function's work sizes, as its _work entry states them
    report.work_bytes = max(8 * (iw + w) for _, _, iw, w in (work_sizes_of(functions, name) for name in generated))
    python_us = _python_call_times(robot, library)
    for name, ns in ((n[len(PREFIX):], t) for n, t in generated.items()):
        entry = BenchEntry(name, ns, python_generated_us=python_us.get(name), generated_spread=spread["generated"][PREFIX + name])
        if name in PAIRS or name.startswith(("fd_r_", "dfd_r_")):
            algo, target = PAIRS.get(name) or (
                (f"constraintDynamics_{name[len('fd_r_'):]}", FD_R_TARGET) if name.startswith("fd_r_")
                else (f"constraintDynamicsDerivatives_{name[len('dfd_r_'):]}", DFD_R_TARGET))
            entry.pinocchio, entry.pinocchio_ns, entry.target = algo, pinocchio[algo], target
            entry.ratio, entry.pinocchio_spread = ns / pinocchio[algo], spread["pinocchio"][algo]
            entry.python_pinocchio_us = python_us.get(algo)
        report.entries.append(entry)
    c_plus_g = generated[PREFIX + "C_full"] + generated[PREFIX + "G_full"]
    report.entries.append(BenchEntry("C_full + G_full", c_plus_g, "nonLinearEffects", pinocchio["nonLinearEffects"],
                                     c_plus_g / pinocchio["nonLinearEffects"], 0.25))
    if parametric:  # parametric_timing imports this module's harness: imported here
        from quadruped_dyn.bench.parametric_timing import parametric_timings
        report.parametric = parametric_timings(robot, calls, reps, max(3, rounds // 3), cc)
    return report


def _python_call_times(robot: Robot, library: CompiledLibrary, number: int = 2000) -> dict[str, float]:
    """Per-call time (us) through Python: the generated functions via ``CompiledFunction`` (ctypes)
    and Pinocchio's bindings."""
    ref = PinocchioReference(robot)
    s = random_state(robot.lower, robot.upper, np.random.default_rng(0))
    q, v, a = ref.pin_q(s.q), ref.pin_v(s.v), ref.pin_v(s.a)
    model, data = robot.model, ref.data
    inputs = {"q": s.q, "v": s.v, "a": s.a, "f": s.f.ravel(), "tau_full": 5.0 * s.a}
    out: dict[str, float] = {}
    for name in PAIRS:
        f = CompiledFunction(library, name)
        args = [inputs[n] for n in f.names_in]
        out[name] = 1e6 * min(timeit.repeat(functools.partial(f, *args), number=number, repeat=3)) / number
    pin_calls = {
        "crba": lambda: pin.crba(model, data, q),
        "nonLinearEffects": lambda: pin.nonLinearEffects(model, data, q, v),
        "computeGeneralizedGravity": lambda: pin.computeGeneralizedGravity(model, data, q),
        "rnea": lambda: pin.rnea(model, data, q, v, a),
        "computeRNEADerivatives": lambda: pin.computeRNEADerivatives(model, data, q, v, a),
        "computeABADerivatives": lambda: pin.computeABADerivatives(model, data, q, v, 5.0 * a),
    }
    for algo, call in pin_calls.items():
        out[algo] = 1e6 * min(timeit.repeat(call, number=number, repeat=3)) / number
    return out
