"""The parametric library: one compiled C library per family (``model/parameters.py``) that serves every robot of it.

Its functions are ``dynamics/parametric.py``'s, each ``qd_p_<name>(arg, res, iw, w, mem)`` with the robot's
parameters p as its last input, read once per call (``PrintOptions.parameters``): M_full, C_full, G_full, nle_full,
id_full (the fixed library's inputs, then p) and regressor_full (q, v, a, p -> Y (18, 130), id_full = Y p[:130] with
f = 0). Every input must be given (none NULL). Each takes the joints' sines and cosines once per call (``qd_sincos``,
docs/embedded.md "The joints' sines and cosines"), as the fixed library's full terms do. The header opens with p's
layout, from ``PARAMETER_NAMES``; p is filled in Python (``parameters_of``; no C filler: a C user writes the 178
numbers in that order). Compiled once per family and cached under a key of the family (its rotations and axes, not a
robot's numbers), the generator's source, CasADi, precision, flags and compiler: a new robot of a known family, or a
variant, loads it with no compile.
"""

from __future__ import annotations

import hashlib
import shutil
import sys
import tempfile
from dataclasses import dataclass, replace
from pathlib import Path

import casadi as ca
import numpy as np

from quadruped_dyn.codegen.c_file import Entry, FileOptions, c_file
from quadruped_dyn.codegen.file_names import family_stem
from quadruped_dyn.codegen.joint_trig import trig_as_inputs
from quadruped_dyn.codegen.library import (
    C_FLAGS,
    PACKAGE,
    CompiledFunction,
    CompiledLibrary,
    compile_sources,
    compiler_version,
    generator_sources,
)
from quadruped_dyn.codegen.precision_math import template_c
from quadruped_dyn.codegen.print_settings import EVALUATION, PREFIX, SINCOS
from quadruped_dyn.codegen.printer import print_function
from quadruped_dyn.dynamics.parametric import parametric_dynamics
from quadruped_dyn.errors import InputError
from quadruped_dyn.files.cache import cached_build
from quadruped_dyn.model.leg import LEG_LABELS
from quadruped_dyn.model.parameters import (
    BODIES,
    FOOT_POINTS,
    INERTIAL_NAMES,
    JOINT_POSITIONS,
    JOINTS,
    N_PARAMETERS,
    Family,
    check_family,
    check_parameters,
    family_of,
    parameters_of,
)
from quadruped_dyn.model.robot import Robot
from quadruped_dyn.model.state import JOINT_ANGLES

#: The C names of the parametric functions: qd_p_M_full, ...
PARAMETRIC_PREFIX = PREFIX + "p_"
PARAMETRIC_NAMES = ("M_full", "C_full", "G_full", "nle_full", "id_full", "regressor_full")


def layout_comment(family: Family) -> str:
    """p's layout as a C comment (``model/parameters.py``)."""
    inertial = ", ".join(INERTIAL_NAMES)
    lines = [f"p ({N_PARAMETERS} reals, SI units) of the family {family.key} (the structure of {family.robot.name}):"]
    lines += [f"  p[{10 * b}..{10 * b + 9}] {body}: {inertial} (kg, kg m, kg m^2 at its frame's origin)"
              for b, body in enumerate(BODIES)]
    lines += [f"  p[{JOINT_POSITIONS.start + 3 * k}..{JOINT_POSITIONS.start + 3 * k + 2}] {joint}: its origin in its "
              "parent's frame (m)" for k, joint in enumerate(JOINTS)]
    lines += [f"  p[{FOOT_POINTS.start + 3 * n}..{FOOT_POINTS.start + 3 * n + 2}] {leg} foot: in its KFE frame (m)"
              for n, leg in enumerate(LEG_LABELS)]
    return "/* " + "\n   ".join(lines) + " */\n"


def shared_inputs(n_in: int) -> tuple[int, ...]:
    """The inputs a batch's states share (``Entry.shared``; ``CompiledFunction.shared``): p, the last."""
    return (n_in - 1,)


def c_named(f: ca.Function) -> ca.Function:
    """Parametric function ``f`` under its C name (``PARAMETRIC_PREFIX``), the same graph, subexpressions shared."""
    args = f.sx_in()
    return ca.Function(PARAMETRIC_PREFIX + f.name(), args, f.call(args), f.name_in(), f.name_out(), {"cse": True})


def _entry(f: ca.Function) -> tuple[Entry, str]:
    """The entry of parametric function ``f`` and the static C it calls: f's graph with the joints' sines and cosines
    as inputs (``joint_trig``), taken once per call by ``qd_sincos`` as the fixed library's full terms do."""
    renamed = c_named(f)
    evaluation = f"qdp_{f.name()}_eval"
    trig = trig_as_inputs(f, 0, JOINT_ANGLES)  # inputs (..., p, sin, cos)
    # p read once per call whatever the lanes; every input given (none NULL): no test of its pointer at each read
    static = print_function(trig, replace(EVALUATION, name=evaluation, parameters=(f.n_in() - 1,), guard_inputs=False))
    n = len(JOINT_ANGLES)
    inputs = ", ".join([*(f"arg[{i}]" for i in range(f.n_in())), "s", "c"])
    body = (f"  casadi_real c[{n}], s[{n}]; /* the joints' cosines and sines, once */\n"
            f"  const casadi_real* a[{f.n_in() + 2}] = {{{inputs}}};\n"
            f"  qd_sincos({n}, arg[0] + {JOINT_ANGLES.start}, c, s);\n"
            f"  return {evaluation}(a, res, iw, w, mem);\n")
    return Entry(renamed, None, body, shared=shared_inputs(f.n_in())), static.text


def parametric_c(family: Family, precision: str = "double") -> tuple[str, str]:
    """(C source, header) of the family's parametric functions (module docstring)."""
    entries, statics = zip(*(_entry(f) for f in parametric_dynamics(family).functions()))
    preamble = template_c(SINCOS) + "\n".join(statics)
    source, header = c_file(family_stem(family.key), list(entries),
                            FileOptions(precision, preamble=preamble + "\n", precision_math=True))
    return source, layout_comment(family) + header


def _family_key(family: Family, precision: str, flags: tuple[str, ...], cc: str) -> str:
    h = hashlib.sha256(f"parametric {family.key}\n".encode())
    for path in generator_sources("codegen.parametric_library"):
        h.update(str(path.relative_to(PACKAGE)).encode() + path.read_bytes())
    h.update(f"{ca.CasadiMeta.version()} {precision} {' '.join(flags)} {compiler_version(cc)}".encode())
    return h.hexdigest()[:16]


class ParametricFunction(CompiledFunction):
    """A parametric function called from Python: its last input p goes through ``check_parameters`` (InputError, one
    line) once per distinct content -- the last checked p's bytes are kept, so a loop over states with one p pays a
    comparison of 178 numbers, in ``raw`` too."""

    def __init__(self, library: CompiledLibrary, name: str) -> None:
        super().__init__(library, name)
        self.shared = shared_inputs(len(self.sizes_in))
        self._checked: bytes | None = None

    def _check_p(self, args: tuple[np.ndarray, ...]) -> None:
        if len(args) != len(self.sizes_in):
            return  # CompiledFunction.__call__ says what is missing
        p = args[-1]
        key = p.tobytes() if isinstance(p, np.ndarray) and p.dtype == np.float64 and p.ndim == 1 else None
        if key is None or key != self._checked:
            check_parameters(p)
            self._checked = key

    def raw(self, *args: np.ndarray) -> list[np.ndarray]:
        self._check_p(args)
        return super().raw(*args)

    def batch(self, *arrays: np.ndarray, out: list[np.ndarray] | None = None,
              strict: bool = False) -> tuple[list[np.ndarray], np.ndarray]:
        """``CompiledFunction.batch`` with p one (178,) array, shared by every state, checked once."""
        if len(arrays) == len(self.sizes_in):  # a p of rows is refused as shared before its numbers are checked
            self._check_shared(self.names_in[-1], arrays[-1], self.sizes_in[-1])
        self._check_p(arrays)
        return super().batch(*arrays, out=out, strict=strict)

    def __call__(self, *args: np.ndarray) -> list[np.ndarray]:
        self._check_p(args)
        return super().__call__(*args)


@dataclass(frozen=True)
class ParametricLibrary:
    """A family's compiled parametric library; ``function(name)`` calls one with inputs (..., p)."""

    family: Family
    library: CompiledLibrary

    def function(self, name: str) -> ParametricFunction:
        """The compiled ``qd_p_<name>``; the p it is given is checked (``ParametricFunction``)."""
        if name not in PARAMETRIC_NAMES:
            raise InputError(f"'{name}' is not a parametric function; expected one of {', '.join(PARAMETRIC_NAMES)}")
        return ParametricFunction(self.library, "p_" + name)

    def parameters(self, robot: Robot) -> np.ndarray:
        """p of ``robot``, checked to be of this family (InputError naming the first difference) and physical."""
        check_family(self.family, robot)
        return check_parameters(parameters_of(robot))


def parametric_library(family_or_robot: Family | Robot, precision: str = "double", cc: str = "gcc") -> ParametricLibrary:
    """The family's parametric library (of a Family, or of a robot's family), compiled once into the cache."""
    if not isinstance(family_or_robot, Family | Robot):
        raise InputError(f"got {type(family_or_robot).__name__}; expected a Family or a Robot (load_robot)")
    family = family_or_robot if isinstance(family_or_robot, Family) else family_of(family_or_robot)
    flags = (*C_FLAGS, f"-Dcasadi_real={precision}")
    stem = family_stem(family.key)

    def build(building: Path) -> None:
        print(f"building the parametric C of family {family.key} ({family.robot.name}'s structure, {precision}) once "
              f"into the cache {building.parent.parent}", file=sys.stderr, flush=True)
        with tempfile.TemporaryDirectory() as tmp:
            source, header = parametric_c(family, precision)
            c_path, h_path = Path(tmp) / f"{stem}.c", Path(tmp) / f"{stem}.h"
            c_path.write_text(source)
            h_path.write_text(header)
            compile_sources([c_path], flags, building, cc)
            for p in (c_path, h_path):  # for reading; the library is what is verified
                shutil.copy(p, building.parent / p.name)

    key = _family_key(family, precision, flags, cc)
    lib = cached_build(key, f"lib{stem}.so", build)
    return ParametricLibrary(family, CompiledLibrary(lib, lib.parent / f"{stem}.c", key, precision))
