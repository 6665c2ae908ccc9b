"""Compiling the generated C, caching the libraries, and calling them from Python.

A library is built from ``codegen.generate``'s output with ``C_FLAGS`` and cached under a hash
of the C source, the header, the flags and the compiler version, so a stale library is never
loaded (``$QUADRUPED_DYN_CACHE``, else ``$XDG_CACHE_HOME/quadruped_dyn``, else
``~/.cache/quadruped_dyn``). ``load_external`` gives a CasADi Function (convenient, ~20 us per
call from Python); ``CompiledFunction`` calls through ctypes (~2-4 us).
"""

from __future__ import annotations

import ctypes
import hashlib
import os
import shutil
import subprocess
import tempfile
from dataclasses import dataclass
from pathlib import Path

import casadi as ca
import numpy as np

from .codegen import PREFIX, generate
from .errors import BuildError, InputError
from .robot import Robot

C_FLAGS = ("-std=c99", "-pedantic", "-Wall", "-Wextra", "-Werror", "-O3", "-fPIC")


def cache_dir() -> Path:
    """$QUADRUPED_DYN_CACHE, else $XDG_CACHE_HOME/quadruped_dyn, else ~/.cache/quadruped_dyn."""
    if "QUADRUPED_DYN_CACHE" in os.environ:
        return Path(os.environ["QUADRUPED_DYN_CACHE"])
    return Path(os.environ.get("XDG_CACHE_HOME", Path.home() / ".cache")) / "quadruped_dyn"


def run_tool(cmd: list[str], cwd: str | Path | None = None) -> str:
    """Run a compiler or harness; its stdout, or a BuildError naming the command and its complaint."""
    try:
        proc = subprocess.run(cmd, capture_output=True, text=True, cwd=cwd, check=False)
    except FileNotFoundError as e:
        raise BuildError(f"'{cmd[0]}' not found; expected it on PATH (a C/C++ compiler is needed here)") from e
    if proc.returncode != 0:
        tail = (proc.stderr or proc.stdout).strip().splitlines()[-1:] or ["no output"]
        raise BuildError(f"'{Path(cmd[0]).name}' failed (exit {proc.returncode}): {tail[0][:300]}")
    return proc.stdout


def _compiler_version(cc: str) -> str:
    return run_tool([cc, "--version"]).splitlines()[0]


@dataclass(frozen=True)
class CompiledLibrary:
    path: Path  # shared library
    source: Path  # the C file it was built from
    key: str  # hash of the C source, header, flags and compiler: a stale library is never reused


def compiled_library(robot: Robot, precision: str = "double", cc: str = "gcc") -> CompiledLibrary:
    """Generate, compile and cache the shared library of ``robot``'s functions."""
    with tempfile.TemporaryDirectory() as tmp:
        c_path, h_path = generate(robot, Path(tmp), precision)[:2]
        flags = (*C_FLAGS, f"-Dcasadi_real={precision}")
        key = hashlib.sha256(
            c_path.read_bytes() + h_path.read_bytes() + " ".join(flags).encode() + _compiler_version(cc).encode()
        ).hexdigest()[:16]
        target = cache_dir() / key
        lib = target / f"lib{c_path.stem}.so"
        if not lib.is_file():
            target.mkdir(parents=True, exist_ok=True)
            building = target / f".{lib.name}.{os.getpid()}"
            run_tool([cc, *flags, "-shared", str(c_path), "-o", str(building), "-lm"])
            shutil.copy(c_path, target / c_path.name)
            shutil.copy(h_path, target / h_path.name)
            building.replace(lib)  # atomic: a half-written library is never loaded
    return CompiledLibrary(lib, target / c_path.name, key)


def load_external(library: CompiledLibrary, name: str) -> ca.Function:
    """A generated function (double build) loaded back as a CasADi Function."""
    return ca.external(PREFIX + name, str(library.path))



class CompiledFunction:
    """A generated function of a double-precision library, called through ctypes with
    preallocated buffers: a few microseconds per call from Python, against ~20 us through
    ``casadi.external``. Inputs are checked for shape; outputs are fresh dense arrays
    (vectors 1-D, matrices 2-D)."""

    def __init__(self, library: CompiledLibrary, name: str) -> None:
        self._lib = ctypes.CDLL(str(library.path))
        self.name = PREFIX + name
        self._fn = getattr(self._lib, self.name)
        graph = ca.external(self.name, str(library.path))  # only to read names and sparsity
        dbl = ctypes.POINTER(ctypes.c_double)
        self._in = [np.zeros(graph.nnz_in(i)) for i in range(graph.n_in())]
        self._out = [np.zeros(graph.nnz_out(i)) for i in range(graph.n_out())]
        self._shapes = [(graph.size1_out(i), graph.size2_out(i)) for i in range(graph.n_out())]
        self._index = [
            np.ravel_multi_index(tuple(np.asarray(x, dtype=np.intp) for x in graph.sparsity_out(i).get_triplet()),
                                 self._shapes[i], order="F")
            for i in range(graph.n_out())
        ]
        self.names_in = graph.name_in()
        self._arg = (dbl * max(1, len(self._in)))(*[a.ctypes.data_as(dbl) for a in self._in])
        self._res = (dbl * max(1, len(self._out)))(*[r.ctypes.data_as(dbl) for r in self._out])
        iw, w = work_sizes_of(self._lib, self.name)
        self._iw = (ctypes.c_longlong * max(1, iw))()
        self._w = (ctypes.c_double * max(1, w))()

    def __call__(self, *args: np.ndarray) -> list[np.ndarray]:
        if len(args) != len(self._in):
            raise InputError(f"{self.name} takes inputs {self.names_in}; got {len(args)} arrays")
        for buf, x, name in zip(self._in, args, self.names_in):
            x = np.asarray(x, dtype=float).ravel()
            if x.shape != buf.shape:
                raise InputError(f"{name} has {x.size} entries; {self.name} expects {buf.size}")
            buf[:] = x
        if self._fn(self._arg, self._res, self._iw, self._w, 0) != 0:
            raise BuildError(f"{self.name} returned an error")
        outs = []
        for buf, shape, index in zip(self._out, self._shapes, self._index):
            dense = np.zeros(shape[0] * shape[1])
            dense[index] = buf
            outs.append(dense if shape[1] == 1 else dense.reshape(shape, order="F"))
        return outs


def work_sizes_of(lib: ctypes.CDLL, name: str) -> tuple[int, int]:
    """(iw, w) work sizes a compiled function asks for, from its ``_work`` entry point."""
    sizes = [ctypes.c_longlong() for _ in range(4)]
    getattr(lib, f"{name}_work")(*[ctypes.byref(x) for x in sizes])
    return sizes[2].value, sizes[3].value
