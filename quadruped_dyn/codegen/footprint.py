"""Flash, RAM and stack of the generated C on a Cortex-M target (docs/embedded.md).

Measured on the objects the generated Makefile's cross builds leave in ``build/<target>/``
(``make cortex-m7`` / ``cortex-m4f``, -ffunction-sections, -fstack-usage, -fcallgraph-info=su):

- **code** of a function: the bytes of its own symbol and of every function of the generated
  code it calls (transitively, each counted once; ``nm --size-sort``), machine code and
  constants. The C library's elementary functions it calls (sin, cos, sqrt and what they call)
  are shared by all functions and counted once, in ``libm``.
- **stack** (worst case): its own frame plus the deepest chain of calls below it, from the
  compiler's call graph (.ci: each function's frame as -fstack-usage reports it and its callees);
  a library function's frame comes from its disassembly in the linked check program (``push``,
  ``vpush``, ``sub sp``).
- **work memory** the caller provides: CasADi's sz_arg / sz_res pointers, sz_iw integers and
  sz_w reals, plus the inputs and outputs themselves (``work_memory``; deterministic, in the
  generated header).

The numbers depend on the compiler version and flags; they are measured, reported (``codegen
--json``, the report, docs/embedded.md) and never written into the committed generated files.
"""

from __future__ import annotations

import hashlib
import json
import re
import subprocess
import tempfile
from collections.abc import Iterable
from dataclasses import asdict, dataclass, field
from pathlib import Path

from quadruped_dyn.codegen.file_names import ROLE_SEPARATOR
from quadruped_dyn.codegen.targets import TARGETS, Target, make, skip_reason
from quadruped_dyn.codegen.work_memory import WorkMemory, work_memory  # noqa: F401 -- re-exported
from quadruped_dyn.files.cache import cached_build

#: Targets of the issue's budget (docs/embedded.md), bytes.
BUDGET_FULL_CODE = 64 * 1024  # M_full + nle_full (C + G) + id_full at -Os
BUDGET_REDUCED_CODE = 48 * 1024  # M_r + CG_r + fd_r of one stance set
BUDGET_STACK = 8 * 1024  # any function
BUDGET_ROBOT = 1024 * 1024  # every function of a robot: the flash of a common Cortex-M4 part

@dataclass
class FunctionFootprint:
    code: int  # bytes: the function and the generated functions it calls
    stack: int  # bytes, worst case including the C library functions it calls
    stack_bounded: bool  # False if a frame in the chain is dynamic (none in the generated code)


@dataclass
class Footprint:
    target: str
    cflags: str
    compiler: str
    functions: dict[str, FunctionFootprint]
    objects: dict[str, int]  # object file -> code + read-only + initialised data (bytes)
    libm: int  # the C library's elementary functions the code calls, counted once
    libm_functions: list[str] = field(default_factory=list)

    @property
    def total(self) -> int:
        """Every function of the robot (all objects) and the library functions they need."""
        return sum(self.objects.values()) + self.libm

    def group_code(self, names: Iterable[str]) -> int:
        """Code of several functions together (shared callees once): a sum over their closures."""
        return sum(self._closure_sizes(names).values())

    def _closure_sizes(self, names: Iterable[str]) -> dict[str, int]:
        out: dict[str, int] = {}
        for n in names:
            out.update(self._sizes[n])
        return out

    _sizes: dict[str, dict[str, int]] = field(default_factory=dict, repr=False)

    def as_json(self) -> dict[str, object]:
        d = asdict(self)
        d.pop("_sizes")
        d["total"] = self.total
        return d


_NODE = re.compile(r'node: \{ title: "([^"]+)" label: "[^"]*?(?:\\n(\d+) bytes \(([a-z,]+)\))?" ?(?:shape|\})')
_EDGE = re.compile(r'edge: \{ sourcename: "([^"]+)" targetname: "([^"]+)"')


def _local(title: str) -> str:
    """A .ci title 'file.c:name' (a static function) or 'name' -> the symbol name."""
    return title.rsplit(":", 1)[-1]


def parse_callgraph(ci_text: str) -> tuple[dict[str, tuple[int, bool] | None], dict[str, set[str]]]:
    """(frame of each function: (bytes, bounded) or None for an external one, callees) from a .ci file."""
    frames: dict[str, tuple[int, bool] | None] = {}
    for title, size, kind in _NODE.findall(ci_text):
        frames[_local(title)] = (int(size), "dynamic" not in kind or "bounded" in kind) if size else None
    calls: dict[str, set[str]] = {}
    for src, dst in _EDGE.findall(ci_text):
        calls.setdefault(_local(src), set()).add(_local(dst))
    return frames, calls


def _tool(target: Target, name: str) -> str:
    return target.compiler[: -len("gcc")] + name


def _symbol_sizes(tool: str, path: Path) -> dict[str, int]:
    """Sizes of the defined code and data symbols of an object or program (``nm --size-sort``)."""
    out = subprocess.run([tool, "-S", "--size-sort", "-t", "d", str(path)], capture_output=True, text=True, check=True)
    sizes: dict[str, int] = {}
    for line in out.stdout.splitlines():
        parts = line.split()
        if len(parts) == 4 and parts[2] in "tTrRdD":
            sizes[parts[3]] = sizes.get(parts[3], 0) + int(parts[1])
    return sizes


_REGS = re.compile(r"\{([^}]*)\}")


def _register_count(regs: str) -> int:
    n = 0
    for part in regs.split(","):
        part = part.strip()
        if "-" in part:
            a, b = (int(re.sub(r"\D", "", x)) for x in part.split("-"))
            n += b - a + 1
        elif part:
            n += 1
    return n


def disassembly_frames(objdump: str, program: Path) -> tuple[dict[str, int], dict[str, set[str]]]:
    """Each function's frame (pushes, vpushes, ``sub sp``: bytes) and direct callees from a
    Thumb-2 program's disassembly: for the C library's functions, which have no .su file."""
    out = subprocess.run([objdump, "-d", "--no-show-raw-insn", str(program)], capture_output=True, text=True, check=True)
    frames: dict[str, int] = {}
    calls: dict[str, set[str]] = {}
    current = ""
    for line in out.stdout.splitlines():
        head = re.match(r"^[0-9a-f]+ <([^>]+)>:$", line)
        if head:
            current = head.group(1)
            frames[current], calls[current] = 0, set()
            continue
        if not current or "\t" not in line:
            continue
        insn = line.split("\t", 1)[1]
        op = insn.split()[0] if insn.split() else ""
        regs = _REGS.search(insn)
        if op in ("push", "push.w") and regs:
            frames[current] += 4 * _register_count(regs.group(1))
        elif op == "stmdb" and insn.split()[1].startswith("sp!") and regs:
            frames[current] += 4 * _register_count(regs.group(1))
        elif op == "vpush" and regs:
            frames[current] += (8 if "d" in regs.group(1) else 4) * _register_count(regs.group(1))
        elif op in ("sub", "sub.w", "subw") and re.match(r"sp, (sp, )?#", insn.split(None, 1)[1]):
            frames[current] += int(insn.rsplit("#", 1)[1].split()[0], 0)
        call = re.match(r"(bl|blx|b\.w|b)\s+[0-9a-f]+ <([^>+]+)>", insn)
        if call and call.group(2) != current:
            calls[current].add(call.group(2))
    return frames, calls


def _worst_stack(name: str, frames: dict[str, tuple[int, bool] | None], calls: dict[str, set[str]],
                 memo: dict[str, tuple[int, bool]], stack: tuple[str, ...] = ()) -> tuple[int, bool]:
    if name in memo:
        return memo[name]
    if name in stack:  # recursion: unbounded (none in the generated code or the libm functions it uses)
        return 0, False
    own = frames.get(name)
    size, bounded = own if own else (0, own is not None)
    deepest, ok = 0, True
    for callee in calls.get(name, ()):
        s, b = _worst_stack(callee, frames, calls, memo, stack + (name,))
        deepest, ok = max(deepest, s), ok and b
    memo[name] = (size + deepest, bounded and ok)
    return memo[name]


def _closure(name: str, calls: dict[str, set[str]], within: set[str]) -> set[str]:
    seen, todo = set(), [name]
    while todo:
        n = todo.pop()
        if n in seen or n not in within:
            continue
        seen.add(n)
        todo.extend(calls.get(n, ()))
    return seen


def measure_build(build_dir: Path, target: Target, function_names: list[str], stem: str, cflags: str) -> Footprint:
    """Footprint of the generated functions from a finished cross build in ``build_dir``."""
    nm, objdump, size = _tool(target, "nm"), _tool(target, "objdump"), _tool(target, "size")
    tdir = Path(build_dir) / target.name
    functions: dict[str, FunctionFootprint] = {}
    objects: dict[str, int] = {}
    sizes_of: dict[str, dict[str, int]] = {}
    per_object: list[tuple[str, dict[str, int], dict[str, tuple[int, bool] | None], dict[str, set[str]]]] = []
    for obj in sorted([*tdir.glob(f"{stem}.o"), *tdir.glob(f"{stem}{ROLE_SEPARATOR}*.o")]):
        text = subprocess.run([size, "-A", str(obj)], capture_output=True, text=True, check=True).stdout
        objects[obj.name] = _section_bytes(text)
        f_frames, f_calls = parse_callgraph(obj.with_suffix(".ci").read_text())
        per_object.append((obj.name, _symbol_sizes(nm, obj), f_frames, f_calls))
    program = Path(build_dir) / target.programs[0]
    lib_frames, lib_calls = disassembly_frames(objdump, program)
    lib_sizes = _symbol_sizes(nm, program)
    externals: set[str] = set()
    for obj_name, sizes, f_frames, f_calls in per_object:
        local = set(sizes)
        for name in function_names:
            if name not in local:
                continue
            members = _closure(name, f_calls, local)
            sizes_of[name] = {f"{obj_name}:{m}": sizes[m] for m in members}
            externals |= {c for m in members for c in f_calls.get(m, ()) if c not in local}
            merged_frames: dict[str, tuple[int, bool] | None] = {k: (v, True) for k, v in lib_frames.items()}
            merged_frames.update({k: v for k, v in f_frames.items() if v})
            merged_calls = {**lib_calls, **f_calls}
            stack, bounded = _worst_stack(name, merged_frames, merged_calls, {})
            functions[name] = FunctionFootprint(sum(sizes_of[name].values()), stack, bounded)
    libm = set()
    todo = [e for e in externals if e in lib_sizes]
    while todo:
        n = todo.pop()
        if n in libm or n not in lib_sizes:
            continue
        libm.add(n)
        todo.extend(lib_calls.get(n, ()))
    compiler = subprocess.run([target.compiler, "--version"], capture_output=True, text=True, check=True).stdout.splitlines()[0]
    fp = Footprint(target.name, cflags, compiler, functions, objects, sum(lib_sizes[n] for n in libm), sorted(libm))
    fp._sizes = sizes_of
    return fp


def _section_bytes(size_a: str) -> int:
    """Code, read-only and initialised data of an object from ``size -A`` (what goes to flash)."""
    total = 0
    for line in size_a.splitlines():
        parts = line.split()
        if len(parts) >= 2 and parts[1].isdigit() and re.match(r"\.(text|rodata|data)", parts[0]):
            total += int(parts[1])
    return total


def measure(source_dir: Path, build_dir: Path, target_name: str, function_names: list[str], stem: str,
            cflags: str = "-Os") -> Footprint:
    """Cross-build ``source_dir`` (a generated directory) for ``target_name`` with ``cflags`` and measure it."""
    target = TARGETS[target_name]
    make(Path(source_dir), [target.name], Path(build_dir), cflags=cflags, stem=stem)
    return measure_build(Path(build_dir), target, function_names, stem, cflags)


# ----------------------------------------------------------------------------- per robot, cached

#: What is measured for a robot: each Cortex-M target in its precision, at -Os and -O2.
MEASURED_BUILDS = (("cortex-m7", "-Os"), ("cortex-m7", "-O2"), ("cortex-m4f", "-Os"), ("cortex-m4f", "-O2"))
#: One build per target at -Os, the optimisation the budgets are stated at (the report's table:
#: half the cross compiling of MEASURED_BUILDS; ``codegen --json`` measures all four).
SIZE_BUILDS = (("cortex-m7", "-Os"), ("cortex-m4f", "-Os"))
FOOTPRINT_VERSION = "footprint-1"  # bump when the measurement changes


def summary(fp: Footprint, function_names: list[str], stances: list[str]) -> dict[str, object]:
    """JSON of one build: per function code and stack; the issue's budget groups; totals."""
    full = [n for n in ("qd_M_full", "qd_nle_full", "qd_id_full") if n in fp.functions]
    reduced = {s: fp.group_code([f"qd_{k}_{s}" for k in ("M_r", "CG_r", "fd_r")]) for s in stances}
    max_stack = max(f.stack for f in fp.functions.values())
    return {
        "target": fp.target, "cflags": fp.cflags, "compiler": fp.compiler,
        "functions": {n: {"code": fp.functions[n].code, "stack": fp.functions[n].stack,
                          "stack_bounded": fp.functions[n].stack_bounded} for n in function_names if n in fp.functions},
        "full_code": fp.group_code(full), "reduced_code": reduced, "max_stack": max_stack,
        "all_bounded": all(f.stack_bounded for f in fp.functions.values()),
        "objects": fp.objects, "libm": fp.libm, "libm_functions": fp.libm_functions, "total": fp.total,
        "budgets": {"full_code": BUDGET_FULL_CODE, "reduced_code": BUDGET_REDUCED_CODE, "stack": BUDGET_STACK,
                    "total": BUDGET_ROBOT},
    }


def _key(source_dir: Path, builds: tuple[tuple[str, str], ...]) -> str:
    digest = hashlib.sha256(f"{FOOTPRINT_VERSION} {builds}".encode())
    for path in sorted(Path(source_dir).iterdir()):
        if path.is_file() and path.suffix in (".c", ".h", ".ld") or path.name == "Makefile":
            digest.update(path.name.encode() + b"\0" + path.read_bytes())
    for target in {TARGETS[t] for t, _ in builds}:
        version = subprocess.run([target.compiler, "--version"], capture_output=True, text=True, check=True).stdout
        digest.update(version.encode())
    return "footprint-" + digest.hexdigest()[:16]


def robot_footprint(source_dir: Path, function_names: list[str], stem: str, stances: list[str],
                    builds: tuple[tuple[str, str], ...] = MEASURED_BUILDS) -> dict[str, object]:
    """Footprint of a generated directory on each (target, cflags) of ``builds`` (cached: the sources,
    Makefile, builds and compiler versions are the key), or ``{"skipped": reason}`` without the toolchain."""
    for target in {TARGETS[t] for t, _ in builds}:
        reason = skip_reason(target, run=False)
        if reason:
            return {"skipped": reason}

    def build(path: Path) -> None:
        measured = []
        with tempfile.TemporaryDirectory() as tmp:
            for target, cflags in builds:
                fp = measure(source_dir, Path(tmp) / f"{target}{cflags}", target, function_names, stem, cflags)
                measured.append(summary(fp, function_names, stances))
        path.write_text(json.dumps({"builds": measured}, indent=1))

    return dict(json.loads(cached_build(_key(source_dir, builds), "footprint.json", build).read_text()))
