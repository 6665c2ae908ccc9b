"""What one call of a generated function costs, counted rather than timed: instructions, first-level
instruction-cache misses and bytes of distinct code run, under valgrind's callgrind.

The counts do not depend on the machine's load or clock and, for the same binary, are the same on every run.
A function is called on fixed inputs (the same path every call) by a program linked statically and without
PIE, so that the addresses callgrind reports are those ``objdump`` disassembles. Only the inside of the
function is counted (``--toggle-collect``: its callees included, the harness's loop not), once with
``LOW_CALLS`` and once with ``HIGH_CALLS`` calls; the difference divided by the difference of the call counts
is the cost of one call in steady state (the first call's cold cache misses cancel). The cache simulated is
fixed (``CACHE``: a 32 kB, 8-way L1 with 64-byte lines, as on current x86-64 and Arm cores), not detected from
the host, so the misses are the same on every machine. Code bytes are the summed sizes of the distinct
instructions executed in one call (``objdump``), libm's included.
"""

from __future__ import annotations

import dataclasses
import functools
import platform
import re
import shutil
import subprocess
import tempfile
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import casadi as ca

from quadruped_dyn.bench.harnesses import HARNESSES
from quadruped_dyn.checks.check_program_values import generate_checked, reference_header_name
from quadruped_dyn.codegen.emit import codegen_functions
from quadruped_dyn.codegen.library import C_FLAGS, cached_object, run_tool
from quadruped_dyn.errors import InputError
from quadruped_dyn.model.robot import Robot

#: Calls of the two counted runs: their difference is the cost of (HIGH_CALLS - LOW_CALLS) steady-state calls.
LOW_CALLS, HIGH_CALLS = 1, 3
#: The simulated caches (size, associativity, line bytes): fixed, so the counts do not depend on the host.
CACHE = ("--I1=32768,8,64", "--D1=32768,8,64", "--LL=1048576,16,64")
#: The code one call may run and still fit a 32 kB first-level instruction cache.
CODE_BUDGET_BYTES = 32 * 1024
NOT_MEASURED = "not measured: valgrind is not installed (Debian: apt-get install valgrind)"


@dataclass(frozen=True)
class CallCost:
    """The steady-state cost of one call of ``function`` (its C name), counted by callgrind."""

    function: str
    instructions: int  # instructions executed per call, callees (libm) included
    i1_misses: int  # first-level instruction-cache misses per call (CACHE)
    code_bytes: int  # bytes of the distinct instructions executed in one call
    over_budget: bool  # code_bytes > CODE_BUDGET_BYTES
    operations: int | None = None  # arithmetic operations of the CasADi graph (timing.arithmetic_operations)


def arithmetic_operations(f: ca.Function) -> int:
    """Operations of an SX Function's generated C: its instructions less inputs, outputs and
    constants (constants are literals in the C; equal ones are shared or not by round-off)."""
    skip = (ca.OP_CONST, ca.OP_INPUT, ca.OP_OUTPUT)
    return sum(f.instruction_id(k) not in skip for k in range(f.n_instructions()))


def valgrind_available() -> bool:
    return shutil.which("valgrind") is not None


def cpu_model() -> str:
    """The CPU's model name (/proc/cpuinfo), or the platform's processor string."""
    try:
        text = Path("/proc/cpuinfo").read_text()
    except OSError:
        return platform.processor() or "unknown"
    found = re.search(r"^model name\s*:\s*(.+)$", text, flags=re.M)
    return found.group(1).strip() if found else platform.processor() or "unknown"


def instruction_sizes(binary: Path) -> dict[int, int]:
    """Address -> size in bytes of every instruction ``objdump -d`` disassembles in ``binary``."""
    text = run_tool(["objdump", "-d", "--insn-width=16", str(binary)])
    sizes = {}
    for line in text.splitlines():
        found = re.match(r"^\s*([0-9a-f]+):\t((?:[0-9a-f]{2} )+)", line)
        if found:
            sizes[int(found.group(1), 16)] = len(found.group(2).split())
    return sizes


def callgrind_counts(command: list[str], symbol: str, out_file: Path) -> tuple[int, int, set[int]]:
    """Run ``command`` under callgrind counting only inside ``symbol``: (instructions, I1 misses, addresses of
    the instructions executed)."""
    run_tool(["valgrind", "--tool=callgrind", f"--callgrind-out-file={out_file}", f"--toggle-collect={symbol}",
              "--dump-instr=yes", "--compress-pos=no", "--compress-strings=no", "--cache-sim=yes", *CACHE,
              *command])
    lines = out_file.read_text().splitlines()
    events = next(line.split()[1:] for line in lines if line.startswith("events:"))
    totals = next(line.split()[1:] for line in lines if line.startswith(("totals:", "summary:")))
    total = dict(zip(events, map(int, totals)))
    addresses, after_call = set(), False
    for line in lines:
        if line.startswith("calls="):
            after_call = True  # the next line is the call's inclusive cost, at the call site
        elif line.startswith("0x"):
            if not after_call and int(line.split()[2]) > 0:  # positions: instr line; then Ir first
                addresses.add(int(line.split()[0], 16))
            after_call = False
    return total.get("Ir", 0), total.get("I1mr", 0), addresses


def measure(command_for_calls: Callable[[int], list[str]], symbol: str, binary: Path, work: Path,
            sizes: dict[int, int] | None = None) -> CallCost:
    """Cost of one call of ``symbol`` in ``binary`` (static, no PIE), whose calls ``command_for_calls(n)`` makes
    n of; ``sizes``: ``instruction_sizes(binary)`` if already known. InputError if a call's instructions differ
    between the two runs' steady state (not one path per call)."""
    low = callgrind_counts(command_for_calls(LOW_CALLS), symbol, work / f"{symbol}.low.out")
    high = callgrind_counts(command_for_calls(HIGH_CALLS), symbol, work / f"{symbol}.high.out")
    calls = HIGH_CALLS - LOW_CALLS
    instructions, remainder = divmod(high[0] - low[0], calls)
    if high[0] <= 0 or remainder or low[0] * calls != (high[0] - low[0]) * LOW_CALLS:
        raise InputError(f"{symbol}: instructions {low[0]} in {LOW_CALLS} calls, {high[0]} in {HIGH_CALLS}; "
                         "expected the same count every call (fixed inputs)")
    sizes = instruction_sizes(binary) if sizes is None else sizes
    code = sum(sizes.get(a, 0) for a in high[2])
    return CallCost(symbol, instructions, round((high[1] - low[1]) / calls), code, code > CODE_BUDGET_BYTES)


def static_program(sources: list[Path], flags: tuple[str, ...], main: list[str], exe: Path, cc: str = "gcc") -> None:
    """Link the generated ``sources`` (from the build cache, compiled with ``flags``) and the harness ``main``
    command-line part (source and -D/-I options) into a static, non-PIE ``exe``."""
    objects = [str(cached_object(s, flags, cc)[0]) for s in sources]
    run_tool([cc, *flags, "-no-pie", "-static", *main, *objects, "-lm", "-o", str(exe)])


def case_names(exe: Path) -> list[str]:
    """The C names of ``exe``'s cases, in order (call_cost.c without arguments prints them)."""
    return run_tool([str(exe)]).split()


def generated_call_costs(sources: list[Path], header: Path, reference: Path, flags: tuple[str, ...],
                         operations: dict[str, int] | None = None, cc: str = "gcc") -> list[CallCost]:
    """The cost of one call of every generated function of a checked package (``generate_checked``'s files),
    on its reference inputs; ``operations``: C name -> graph operations, reported beside."""
    with tempfile.TemporaryDirectory() as tmp:
        work = Path(tmp)
        exe = work / "call_cost"
        static_program(sources, flags, [f"-I{header.parent.resolve()}", f"-I{reference.parent.resolve()}",
                                        f"-DQD_HEADER=\"{header.name}\"", f"-DQD_REFERENCE=\"{reference.name}\"",
                                        str(HARNESSES / "call_cost.c")], exe, cc)
        costs, sizes = [], instruction_sizes(exe)
        for case, name in enumerate(case_names(exe)):
            cost = measure(functools.partial(_case_command, exe, case), name, exe, work, sizes)
            costs.append(dataclasses.replace(cost, operations=(operations or {}).get(name)))
    return costs


def robot_call_costs(robot: Robot, cc: str = "gcc") -> list[CallCost]:
    """``generated_call_costs`` of ``robot``'s generated C (double, ``C_FLAGS``, as ``bench`` builds it)."""
    with tempfile.TemporaryDirectory() as tmp:
        files = generate_checked(robot, Path(tmp))
        operations = {f.name(): arithmetic_operations(f) for f in codegen_functions(robot)}
        return generated_call_costs(files.c_sources, files.header, files.extra[reference_header_name(robot)],
                                    (*C_FLAGS, "-Dcasadi_real=double"), operations, cc)


def _case_command(exe: Path, case: int, calls: int) -> list[str]:
    return [str(exe), str(case), str(calls)]


def call_cost_table(costs: list[CallCost]) -> list[list[str]]:
    """Rows (header first) of the per-call counts, for ``timing.aligned``."""
    rows = [["function", "instructions", "I1 misses", "code bytes", "graph ops", f"> {CODE_BUDGET_BYTES // 1024} kB"]]
    for c in costs:
        rows.append([c.function, str(c.instructions), str(c.i1_misses), str(c.code_bytes),
                     "" if c.operations is None else str(c.operations), "yes" if c.over_budget else ""])
    return rows


def valgrind_version() -> str | None:
    """``valgrind --version``, or None without valgrind."""
    if not valgrind_available():
        return None
    return subprocess.run(["valgrind", "--version"], capture_output=True, text=True, check=False).stdout.strip()
