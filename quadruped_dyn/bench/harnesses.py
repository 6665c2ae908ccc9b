"""The benchmark's C and C++ programs (``c/``) and how the C++ ones are built against the pin wheel.

The pin wheel ships Pinocchio's headers and libraries under its cmeel prefix (with cmeel-eigen,
cmeel-boost, cmeel-urdfdom-headers, and cmeel-cppad / cmeel-cppadcodegen when the ``bench`` extra is
installed). A program built with ``PINOCCHIO_CXX_FLAGS`` links the wheel's libraries, whose
algorithms for ``double`` are compiled for generic x86-64 (SSE2; no AVX or FMA instruction in
``libpinocchio_default``). ``bench --native`` keeps it so: compiling the algorithms into the
harness with -march=native (header-only, Eigen's alignment held at the wheel's 16 bytes) built,
but crashed on the Model the wheel's URDF parser had built (the layouts differ).
"""

from __future__ import annotations

import importlib.metadata
from pathlib import Path

from quadruped_dyn.errors import InputError

HARNESSES = Path(__file__).resolve().parent / "c"

#: Flags of the C++ programs linked with the wheel's Pinocchio (its explicit template instantiations).
PINOCCHIO_CXX_FLAGS = (
    "-O3", "-DNDEBUG", "-std=c++17", "-DPINOCCHIO_ENABLE_TEMPLATE_INSTANTIATION",
    "-DBOOST_MPL_LIMIT_LIST_SIZE=30", "-DBOOST_MPL_LIMIT_VECTOR_SIZE=30",
    "-DBOOST_MPL_CFG_NO_PREPROCESSED_HEADERS", "-DBOOST_FUSION_INVOKE_MAX_ARITY=12",
)

PINOCCHIO_LIBS = ("-lpinocchio_default", "-lpinocchio_parsers", "-lurdfdom_model", "-lboost_serialization")


def cmeel_prefix() -> Path:
    """The pin wheel's install prefix (include/, lib/)."""
    return Path(str(importlib.metadata.distribution("pin").locate_file("cmeel.prefix")))


def require_headers(headers: tuple[str, ...], packages: str) -> Path:
    """The cmeel prefix, after checking that ``headers`` (relative to its include/) are there;
    InputError naming ``packages`` (what to install) otherwise."""
    prefix = cmeel_prefix()
    for header in headers:
        if not (prefix / "include" / header).is_file():
            raise InputError(f"missing {header} under {prefix}/include; expected {packages}")
    return prefix


def pinocchio_program(sources: list[Path], exe: Path, flags: tuple[str, ...], cxx: str = "g++") -> list[str]:
    """The command that builds ``sources`` into ``exe`` against the wheel's Pinocchio (a RUNPATH, not an RPATH: the
    benchmark's LD_LIBRARY_PATH finds its copies of the libraries first, placement.py)."""
    prefix = cmeel_prefix()
    include, lib = prefix / "include", prefix / "lib"
    return [cxx, *flags, f"-I{include}", f"-I{include / 'eigen3'}", f"-I{include / 'urdfdom_headers'}",
            *map(str, sources), f"-L{lib}", "-Wl,--enable-new-dtags", f"-Wl,-rpath,{lib}", *PINOCCHIO_LIBS, "-o", str(exe)]
