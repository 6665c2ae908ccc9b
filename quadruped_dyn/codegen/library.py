"""Compiling the generated C, caching the libraries, and calling them from Python.

A library is built from ``codegen.generate``'s output with ``C_FLAGS`` and cached under
``generation_key`` (everything it depends on), so a stale library is never loaded;
``cache.cached_build`` verifies its bytes before it is loaded. ``load_external`` gives
a CasADi Function (convenient, ~20 us per call from Python); ``CompiledFunction`` calls
through ctypes (~2-4 us).
"""

from __future__ import annotations

import ctypes
import functools
import hashlib
import re
import shutil
import subprocess
import sys
import tempfile
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from pathlib import Path

import casadi as ca
import numpy as np

from quadruped_dyn.codegen import c_facts
from quadruped_dyn.codegen.emit import PREFIX, TEMPLATES, generate
from quadruped_dyn.codegen.file_names import robot_stem
from quadruped_dyn.errors import BuildError, InputError, NumericalError
from quadruped_dyn.files.cache import cached_build
from quadruped_dyn.model.robot import Robot
from quadruped_dyn.model.state import check_array, check_quaternion

C_FLAGS = ("-std=c99", "-pedantic", "-Wall", "-Wextra", "-Werror", "-O3", "-fPIC")
COMPILE_JOBS = 2  # this machine's cores
#: A compiler's or linker's error line ("file.c:3:5: error: ...", "ld: ...: undefined reference").
_DIAGNOSTIC = re.compile(r"(^|: )(fatal )?error:|undefined reference")


def run_tool(cmd: list[str], cwd: str | Path | None = None, env: dict[str, str] | None = None) -> str:
    """Run a compiler or harness (in ``cwd``, with ``env`` if given); its stdout, or a BuildError naming the command
    and its complaint (an InputError if the program is not installed)."""
    try:
        proc = subprocess.run(cmd, capture_output=True, text=True, cwd=cwd, env=env, check=False)
    except FileNotFoundError as e:  # the environment, not a failed check: bad input (exit 2)
        raise InputError(f"'{cmd[0]}' not found; expected it on PATH (a C/C++ compiler is needed here)") from e
    if proc.returncode != 0:
        lines = (proc.stderr or proc.stdout).strip().splitlines() or ["no output"]
        # the first diagnostic says what went wrong; the last is often only "cc1: all warnings being treated as errors"
        first = next((line for line in lines if _DIAGNOSTIC.search(line)), lines[-1])
        raise BuildError(f"'{Path(cmd[0]).name}' failed (exit {proc.returncode}): {first[:300]}")
    return proc.stdout


@functools.cache
def compiler_version(cc: str) -> str:
    """The first line of ``cc --version`` (part of every build cache key)."""
    return run_tool([cc, "--version"]).splitlines()[0]


@dataclass(frozen=True)
class CompiledLibrary:
    path: Path  # shared library
    source: Path  # the C file it was built from
    key: str  # hash of the C source, header, flags and compiler: a stale library is never reused
    precision: str = "double"  # casadi_real of the build: "double" or "float"


#: A ``#include`` of anything but a <system> header: the object depends on bytes outside the source.
_LOCAL_INCLUDE = re.compile(rb'^[ \t]*#[ \t]*include[ \t]*([^<\s].*)$', re.M)
#: ... of a file beside the source, by name (``"reduced_templates.h"``): its bytes go into the key.
_QUOTED_NAME = re.compile(rb'"([\w.]+)"')
#: The includes of a hand-written C file compiled alone (``codegen/c_alone.py``): dead where it is pasted into a
#: generated file, which defines CASADI_PREFIX first.
_ALONE_INCLUDES = re.compile(rb'^#ifndef CASADI_PREFIX\b.*?^#endif\b', re.M | re.S)


def _included_bytes(source: Path, text: bytes) -> bytes:
    """The bytes of the files ``text`` includes by a quoted name, from ``source``'s directory (where the compiler
    looks first); BuildError for any other local include (a macro or a path: the key could miss its bytes)."""
    included = b""
    for target in _LOCAL_INCLUDE.findall(_ALONE_INCLUDES.sub(b"", text)):
        name = _QUOTED_NAME.fullmatch(target.strip())
        path = source.parent / name.group(1).decode() if name else None
        if path is None or not path.is_file() or _LOCAL_INCLUDE.search(_ALONE_INCLUDES.sub(b"", path.read_bytes())):
            raise BuildError(f"'{source.name}' includes {target.strip().decode(errors='replace')!s}; the object cache "
                             "takes C sources that include only <system> headers and self-contained files beside them")
        included += b"\0" + name.group(1) + b"\0" + path.read_bytes()  # type: ignore[union-attr]
    return included


def cached_object(source: Path, flags: tuple[str, ...], cc: str = "gcc") -> tuple[Path, bool]:
    """``source`` compiled with ``flags`` (``-c``), from the build cache: the key is the source's
    bytes and those of the files beside it that it includes (``_included_bytes``), the flags and the compiler,
    so the same file compiled the same way by the library, the benchmark or another robot's build is compiled
    once: (object path, True if compiled now)."""
    text = source.read_bytes()
    key = hashlib.sha256(text + _included_bytes(source, text) + "\0".join((cc, compiler_version(cc), *flags)).encode()
                         ).hexdigest()[:20]
    compiled = []

    def build(building: Path) -> None:
        run_tool([cc, *flags, "-c", str(source), "-o", str(building)])
        compiled.append(True)

    return cached_build(f"object-{key}", f"{source.stem}.o", build), bool(compiled)


def compile_sources(sources: list[Path], flags: tuple[str, ...], output: Path, cc: str = "gcc") -> int:
    """Compile C sources into one shared library: one object per source (``cached_object``:
    a file already compiled with the same flags is not compiled again), two compilers at a time
    (the generated files are large; this machine has two cores). Returns how many objects were
    compiled (the others came from the cache)."""
    with ThreadPoolExecutor(max_workers=COMPILE_JOBS) as pool:
        objects = list(pool.map(lambda source: cached_object(source, flags, cc), sources))
    run_tool([cc, "-shared", *(str(o) for o, _ in objects), "-o", str(output), "-lm"])
    return sum(compiled for _, compiled in objects)


PACKAGE = Path(__file__).resolve().parents[1]



def _module_file(dotted: str) -> Path | None:
    """The source file of ``quadruped_dyn.<dotted>`` (a module or a package's __init__), if any."""
    base = PACKAGE.joinpath(*dotted.split("."))
    for path in (base.with_suffix(".py"), base / "__init__.py"):
        if path.is_file():
            return path
    return None


def generator_sources(root: str = "codegen.emit") -> list[Path]:
    """``root`` (codegen/emit.py) and the package modules it imports, transitively, and the C templates:
    what the generated code depends on, and nothing else (editing the report or the experiment
    does not invalidate the compiled libraries)."""
    found: set[Path] = set()
    todo = [root]
    while todo:
        path = _module_file(todo.pop())
        if path is None or path in found:
            continue
        found.add(path)
        todo += re.findall(r"^\s*from quadruped_dyn\.([\w.]+) import", path.read_text(), flags=re.M)
    return sorted([*found, *TEMPLATES.glob("*")])


def generation_key(robot: Robot, precision: str, flags: tuple[str, ...], cc: str) -> str:
    """Hash of everything the compiled library depends on: the bytes ``robot``'s model was parsed
    from (``Robot.urdf_sha256``, recorded at load: not the file as it is now, which may have been
    edited since) and the foot frames chosen, the generator's source (``generator_sources``),
    CasADi's version, precision, flags and compiler."""
    if not robot.urdf_sha256:
        raise InputError(f"robot '{robot.name}' records no hash of its URDF; expected a Robot from load_robot")
    feet = ",".join(leg.foot_frame for leg in robot.legs)
    h = hashlib.sha256(f"{robot.name}\n{robot.urdf_sha256}\n{feet}\n".encode())
    for path in generator_sources():
        h.update(str(path.relative_to(PACKAGE)).encode() + path.read_bytes())
    h.update(f"{ca.CasadiMeta.version()} {precision} {' '.join(flags)} {compiler_version(cc)}".encode())
    return h.hexdigest()[:16]


def compiled_library(robot: Robot, precision: str = "double", cc: str = "gcc") -> CompiledLibrary:
    """Generate, compile and cache the shared library of ``robot``'s functions (all of
    ``codegen.generate``'s C sources: full-coordinate terms, GRF solves, reduced models);
    ``cache.cached_build`` verifies its bytes before it is returned."""
    flags = (*C_FLAGS, f"-Dcasadi_real={precision}")
    key = generation_key(robot, precision, flags, cc)

    def build(building: Path) -> None:
        print(f"building {robot.name}'s generated C ({precision}) once into the cache {building.parent.parent} "
              "(a few minutes for a new robot)", file=sys.stderr, flush=True)
        with tempfile.TemporaryDirectory() as tmp:
            files = generate(robot, Path(tmp), precision)
            compile_sources(files.c_sources, flags, building, cc)
            for p in files.library_sources:  # for reading; the library is what is verified
                shutil.copy(p, building.parent / p.name)

    lib = cached_build(key, f"lib{robot_stem(robot.name)}.so", build)
    return CompiledLibrary(lib, lib.parent / f"{robot_stem(robot.name)}.c", key, precision)


def load_external(library: CompiledLibrary, name: str) -> ca.Function:
    """A generated function (double build) loaded back as a CasADi Function."""
    return ca.external(PREFIX + name, str(library.path))



#: The generated functions' return codes (``c_facts.RETURN_CODES``, from which the C macros are written): code -> meaning.
RETURN_CODES = {c.value: c.meaning for c in c_facts.RETURN_CODES}
QD_NONFINITE, QD_SINGULAR, QD_DEGENERATE, QD_NO_WORK = (c_facts.RETURN_CODE[n].value for n in (
    "QD_NONFINITE", "QD_SINGULAR", "QD_DEGENERATE", "QD_NO_WORK"))


class CompiledFunction:
    """A generated function of a library, called through ctypes in the library's precision with
    preallocated buffers (every input and output, the work arrays its ``_work`` entry asks for):
    a few microseconds per call from Python, against ~20 us through ``casadi.external``. Inputs
    are checked as the symbolic functions' are (``model.state.check_array``: real, 1-D of the input's
    size, finite; a quaternion ``q`` (entries 3:7) or ``quat`` not zero); outputs are fresh dense
    float64 arrays (vectors 1-D, matrices 2-D)."""

    def __init__(self, library: CompiledLibrary, name: str) -> None:
        self._lib = ctypes.CDLL(str(library.path))
        self.name = PREFIX + name
        try:
            self._fn = getattr(self._lib, self.name)
        except AttributeError:
            raise InputError(f"{library.path.name} has no function {self.name}; expected a name its header "
                             f"{library.path.stem.removeprefix('lib')}.h declares (e.g. 'M_full')") from None
        graph = ca.external(self.name, str(library.path))  # only to read names and sparsity
        real, c_real = {"double": (np.float64, ctypes.c_double), "float": (np.float32, ctypes.c_float)}[library.precision]
        ptr = ctypes.POINTER(c_real)
        self._in = [np.zeros(graph.nnz_in(i), dtype=real) for i in range(graph.n_in())]
        self._out = [np.zeros(graph.nnz_out(i), dtype=real) for i in range(graph.n_out())]
        self._shapes = [(graph.size1_out(i), graph.size2_out(i)) for i in range(graph.n_out())]
        self._index = [
            np.ravel_multi_index(tuple(np.asarray(x, dtype=np.intp) for x in graph.sparsity_out(i).get_triplet()),
                                 self._shapes[i], order="F")
            for i in range(graph.n_out())
        ]
        self.names_in = graph.name_in()
        self.sizes_in = [x.size for x in self._in]
        n_arg, n_res, iw, w = work_sizes_of(self._lib, self.name)
        self._real, self._ptr = real, ptr
        self._n_arg, self._n_res = max(1, n_arg, len(self._in)), max(1, n_res, len(self._out))  # pointer arrays' lengths
        self._arg = (ptr * self._n_arg)(*[a.ctypes.data_as(ptr) for a in self._in])
        self._res = (ptr * self._n_res)(*[r.ctypes.data_as(ptr) for r in self._out])
        self._iw = (ctypes.c_longlong * max(1, iw))()
        self._w = (c_real * max(1, w))()
        self.shared: tuple[int, ...] = ()  # the inputs a batch's states share (``Entry.shared``): one (nnz,) array each
        self._batch = getattr(self._lib, self.name + "_batch")
        self._batch.argtypes = [ctypes.c_longlong, ctypes.POINTER(ptr), ctypes.POINTER(ptr), ctypes.POINTER(ctypes.c_int),
                                ptr]

    def raw(self, *args: np.ndarray) -> list[np.ndarray]:
        """The hot path of a control loop: inputs (arrays of the right sizes, not checked) copied
        into the preallocated buffers (in the library's precision), the C function called, its output buffers returned
        (the nonzeros, column-major; overwritten by the next call). A non-zero return code
        raises as ``__call__``'s does (``_raise_for``)."""
        for buf, x in zip(self._in, args):
            buf[:] = x
        flag = self._fn(self._arg, self._res, self._iw, self._w, 0)
        if flag != 0:
            self._raise_for(flag)
        return self._out

    def batch(self, *arrays: np.ndarray, out: list[np.ndarray] | None = None,
              strict: bool = False) -> tuple[list[np.ndarray], np.ndarray]:
        """N states in one C call (``qd_NAME_batch``): input i an (N, nnz_i) C-contiguous array in the library's
        precision (float64, float32 for a float library; anything else is refused, not copied: ``InputError``), but an
        input in ``shared`` (the parameters p of a parametric function) one (nnz_i,) array every state reads.
        Returns the outputs, (N, nnz) arrays of the nonzeros as ``raw`` gives them (``out``'s if given, checked
        likewise), each row equal to one call's to the bit, and each row's status: the scalar call's return code,
        or QD_NONFINITE where that is 0 but an input of the row is not finite. ``strict``: ``InputError`` naming the
        first bad row and its code instead."""
        if len(arrays) != len(self._in):
            raise InputError(f"{self.name}.batch takes inputs {self.names_in}; got {len(arrays)} arrays")
        per_state = [x for i, x in enumerate(arrays) if i not in self.shared]
        n = per_state[0].shape[0] if isinstance(per_state[0], np.ndarray) and per_state[0].ndim == 2 else -1
        for i, (x, size, name) in enumerate(zip(arrays, self.sizes_in, self.names_in)):
            if i in self.shared:
                self._check_shared(name, x, size)
            else:
                self._check_rows(f"input {name}", x, n, size)
        nnz_out = [buf.size for buf in self._out]
        if out is None:
            out = [np.empty((n, m), dtype=self._real) for m in nnz_out]
        elif len(out) != len(nnz_out):
            raise InputError(f"{self.name}.batch: out has {len(out)} arrays; expected {len(nnz_out)}")
        for i, (y, m) in enumerate(zip(out, nnz_out)):
            self._check_rows(f"output {i}", y, n, m)
        status = np.zeros(n, dtype=np.intc)
        arg = (self._ptr * self._n_arg)(*[x.ctypes.data_as(self._ptr) for x in arrays])
        res = (self._ptr * self._n_res)(*[y.ctypes.data_as(self._ptr) for y in out])
        self._batch(n, arg, res, status.ctypes.data_as(ctypes.POINTER(ctypes.c_int)), self._w)
        if not all(np.isfinite(np.sum(x)) for x in arrays):  # one pass each; a sum that overflowed is checked here
            finite = [np.isfinite(x).all(axis=-1) for x in arrays]  # a shared input's: one bool for every row
            status[(status == 0) & ~np.logical_and.reduce(np.broadcast_arrays(*finite))] = QD_NONFINITE
        if strict and status.any():
            row = int(np.flatnonzero(status)[0])
            raise InputError(f"{self.name}.batch: row {row}: {RETURN_CODES.get(int(status[row]), status[row])}")
        return out, status

    def _check_shared(self, name: str, x: object, size: int) -> None:
        """Shared input ``x`` one (size,) C-contiguous array in the library's precision, or InputError saying so."""
        if not isinstance(x, np.ndarray) or x.shape != (size,):
            got = f"shape {x.shape}" if isinstance(x, np.ndarray) else type(x).__name__
            raise InputError(f"{self.name}.batch input {name}: shared by every state (read once); expected one ({size},) "
                             f"array; got {got}")
        self._check_rows(f"input {name}", x[None, :], 1, size)

    def _check_rows(self, what: str, x: object, n: int, size: int) -> None:
        """``x`` an (n, size) C-contiguous array in the library's precision, or InputError saying what it is."""
        if not isinstance(x, np.ndarray) or x.ndim != 2 or x.shape != (n, size):
            got = f"shape {x.shape}" if isinstance(x, np.ndarray) else type(x).__name__
            raise InputError(f"{self.name}.batch {what}: expected an ({max(n, 0) if n >= 0 else 'N'}, {size}) array "
                             f"(rows: states); got {got}")
        writeable = " writeable" if what.startswith("output") else ""
        if x.dtype != self._real or not x.flags.c_contiguous or (writeable and not x.flags.writeable):
            raise InputError(f"{self.name}.batch {what}: expected a C-contiguous{writeable} "
                             f"{np.dtype(self._real).name} array (not copied); got {x.dtype}"
                             f"{'' if x.flags.c_contiguous else ', not C-contiguous'}")

    def _raise_for(self, flag: int) -> None:
        """QD_SINGULAR, QD_DEGENERATE are numerical (NumericalError); QD_NONFINITE cannot tell a bad input
        from a singular stance (InputError): docs/reliability.md §6."""
        known = {c.value: c for c in c_facts.RETURN_CODES}.get(flag)
        error = NumericalError if known is not None and known.numerical else InputError
        raise error(f"{self.name}: {RETURN_CODES.get(flag, f'error code {flag}')}")

    def __call__(self, *args: np.ndarray) -> list[np.ndarray]:
        if len(args) != len(self._in):
            raise InputError(f"{self.name} takes inputs {self.names_in}; got {len(args)} arrays")
        for buf, x, name in zip(self._in, args, self.names_in):
            x = check_array(name, x, buf.shape)
            if name in ("q", "quat"):
                check_quaternion(name, x[3:7] if name == "q" else x)
            buf[:] = x
        flag = self._fn(self._arg, self._res, self._iw, self._w, 0)
        if flag != 0:
            self._raise_for(flag)
        outs = []
        for buf, shape, index in zip(self._out, self._shapes, self._index):
            dense = np.zeros(shape[0] * shape[1])
            dense[index] = buf
            outs.append(dense if shape[1] == 1 else dense.reshape(shape, order="F"))
        return outs


def work_sizes_of(lib: ctypes.CDLL, name: str) -> tuple[int, int, int, int]:
    """(arg, res, iw, w): what a call of compiled function ``name`` needs from its caller, from its
    ``_work`` entry point. The arg and res arrays hold at least that many pointers -- CasADi uses
    the entries past the function's own inputs and outputs for the calls it makes --, iw and w at
    least that many entries."""
    sizes = [ctypes.c_longlong() for _ in range(4)]
    getattr(lib, f"{name}_work")(*[ctypes.byref(x) for x in sizes])
    n_arg, n_res, n_iw, n_w = (x.value for x in sizes)
    return n_arg, n_res, n_iw, n_w
