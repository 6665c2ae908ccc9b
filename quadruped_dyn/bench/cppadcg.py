"""Pinocchio's CppADCodeGen code as a peer of the generated C: ``bench``'s "pinocchio-cppadcodegen".

Pinocchio's code generators (``pinocchio/codegen/cppadcg-algo.hpp``: CodeGenCRBA, CodeGenRNEA,
CodeGenABA; nonLinearEffects and computeGeneralizedGravity recorded the same way,
``c/cppadcg_generate.cpp``) record each algorithm on CppAD's ``AD<CG<double>>`` for the robot's
free-flyer model (parsed from the URDF the Pinocchio harness parses, armature zeroed as in the
project's model) and write the C of its zero-order forward. That C is compiled with the project's
C flags (``library.C_FLAGS``: -std=c99 -O3 -fPIC; its warning flags are dropped, they change no
code and CppADCodeGen's C has unused variables), plus -march=native under ``bench --native``,
and timed by ``c/bench_cppadcg.c`` with the project's timing (``c/bench_median.h``).

Its functions take Pinocchio's coordinates and joint order: q = (p, quaternion x y z w, joints),
v = (v_b, omega_b in the trunk frame, joint rates), joints in the URDF's tree order (anymal_c: LF,
LH, RF, RH). Before it is timed, every function is evaluated at a random state and compared, mapped
to the project's order by joint name (``PinocchioReference``), with Pinocchio's native result:
NumericalError beyond REL_TOL_TERMS (a peer that computes something else is not a peer).

Generation (about a minute per robot, several under load) and compilation are cached under a hash
of everything they depend on (``cache.cached_build``): the URDF's bytes, the generator and harness
sources, the pin and CppADCodeGen versions, the flags and the compiler.
"""

from __future__ import annotations

import hashlib
import importlib.metadata
import shutil
import sys
import tempfile
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pinocchio as pin

from quadruped_dyn.bench.harnesses import HARNESSES, PINOCCHIO_CXX_FLAGS, pinocchio_program, require_headers
from quadruped_dyn.codegen.library import C_FLAGS, compiler_version, run_tool
from quadruped_dyn.errors import InputError, NumericalError
from quadruped_dyn.files.cache import cache_dir, cached_build
from quadruped_dyn.math.compare import relative_error, within
from quadruped_dyn.model.robot import Robot
from quadruped_dyn.model.state import random_state
from quadruped_dyn.references.pinocchio import PinocchioReference
from quadruped_dyn.tolerances import REL_TOL_TERMS

PEER = "pinocchio-cppadcodegen"

#: What to install for it: the optional extra ``bench`` (pyproject.toml), which ./run installs.
INSTALL_HINT = "pip install 'quadruped_dyn[bench]' (cmeel-cppadcodegen, cmeel-cppad)"

#: The headers it needs beyond the pin wheel's own.
HEADERS = ("cppad/cg.hpp", "cppad/cppad.hpp", "pinocchio/codegen/cppadcg-algo.hpp")

#: peer function -> (the generated function timed against it or None, target ratio generated / peer or None).
#: crba gives the upper triangle of M, M_full all of it; rnea applies no foot forces, id_full four.
PAIRS: dict[str, tuple[str | None, float | None]] = {
    "crba": ("M_full", 0.6),
    "nle": ("nle_full", None),
    "gravity": ("G_full", None),
    "rnea": ("id_full", 0.8),
    "aba": (None, None),  # no full-coordinate forward dynamics is generated: the peer against Pinocchio only
}

#: The Pinocchio native algorithm each peer function records (bench_pinocchio.cpp's names).
NATIVE = {"crba": "crba", "nle": "nonLinearEffects", "gravity": "computeGeneralizedGravity", "rnea": "rnea", "aba": "aba"}

#: The generator program and the timing program with what they include.
GENERATOR = "cppadcg_generate.cpp"
HARNESS = ("bench_cppadcg.c", "bench_median.h")


@dataclass
class PeerTiming:
    """One peer function timed in the same rounds as the generated C; ns are medians of CPU time."""

    name: str | None  # the generated function (None: the peer has no counterpart here)
    generated_ns: float | None
    peer: str
    peer_function: str
    peer_ns: float
    ratio: float | None  # generated / peer
    target: float | None
    pinocchio: str  # the native algorithm the peer records, timed in the same run
    pinocchio_ns: float
    peer_vs_pinocchio: float  # peer / native
    checked_rel_error: float  # peer vs Pinocchio native at a random state, before timing


def available() -> bool:
    """True when the headers of the ``bench`` extra are installed."""
    try:
        require_headers(HEADERS, INSTALL_HINT)
    except InputError:
        return False
    return True


def _versions() -> str:
    return " ".join(f"{d}={importlib.metadata.version(d)}" for d in ("pin", "cmeel-cppadcodegen", "cmeel-cppad"))


def generator(cxx: str = "g++") -> Path:
    """The compiled generator (c/cppadcg_generate.cpp), built once per source, versions and flags."""
    require_headers(HEADERS, INSTALL_HINT)
    source = HARNESSES / GENERATOR
    flags = (*PINOCCHIO_CXX_FLAGS, "-O1", "-w")  # -O1 after -O3: its run time is negligible, its build is not
    key = hashlib.sha256(source.read_bytes() + (_versions() + " ".join(flags) + compiler_version(cxx)).encode()).hexdigest()[:16]

    def build(exe: Path) -> None:
        print(f"building Pinocchio's CppADCodeGen generator once (several minutes) into {cache_dir()}", file=sys.stderr)
        run_tool(pinocchio_program([source], exe, flags, cxx))

    return cached_build(f"cppadcg-generator-{key}", "cppadcg_generate", build)


def peer_flags(native: bool) -> tuple[str, ...]:
    """The project's C flags less the warnings (-Werror: CppADCodeGen's C has unused variables)."""
    return tuple(f for f in C_FLAGS if not f.startswith("-W") and f != "-pedantic") + (("-march=native",) if native else ())


def harness(robot: Robot, native: bool = False, cc: str = "gcc") -> Path:
    """The timing program of the robot's CppADCodeGen functions, generated and compiled once (cached)."""
    gen = generator()
    flags = peer_flags(native)
    parts = [robot.urdf_sha256, gen.parent.name,  # the generator's cache entry: its source, versions and flags
             " ".join(flags), compiler_version(cc), *((HARNESSES / name).read_text() for name in HARNESS)]
    key = hashlib.sha256("\n".join(parts).encode()).hexdigest()[:16]

    def build(exe: Path) -> None:
        print(f"generating and compiling Pinocchio's CppADCodeGen code of {robot.name} (about a minute)", file=sys.stderr)
        with tempfile.TemporaryDirectory() as tmp:
            run_tool([str(gen), str(robot.urdf), tmp])
            sources = sorted(str(p) for p in Path(tmp).glob("*_forward_zero.c"))
            if len(sources) != len(PAIRS):
                raise NumericalError(f"the CppADCodeGen generator wrote {len(sources)} forward functions; expected {len(PAIRS)}")
            for name in HARNESS:
                shutil.copy(HARNESSES / name, tmp)
            run_tool([cc, *flags, *sources, "bench_cppadcg.c", "-lm", "-o", str(exe)], cwd=tmp)

    return cached_build(f"cppadcg-{robot.name}-{key}", "bench_cppadcg", build)


def state_args(robot: Robot, seed: int = 0) -> tuple[list[str], dict[str, np.ndarray]]:
    """A random state as the harness reads it (nq, nv, q, v, a, tau in Pinocchio's order) and in the project's order."""
    ref = PinocchioReference(robot)
    s = random_state(robot.lower, robot.upper, np.random.default_rng(seed))
    tau = 5.0 * s.a
    values = [ref.pin_q(s.q), ref.pin_v(s.v), ref.pin_v(s.a, "a"), ref.pin_v(tau, "tau")]
    args = [str(robot.model.nq), str(robot.model.nv), *(f"{x:.17g}" for vec in values for x in vec)]
    return args, {"q": s.q, "v": s.v, "a": s.a, "tau": tau}


def check(robot: Robot, exe: Path) -> dict[str, float]:
    """Relative error of each peer function against Pinocchio native at a random state (project
    order, mapped by joint name); NumericalError if any exceeds REL_TOL_TERMS."""
    args, x = state_args(robot)
    out = {}
    for line in run_tool([str(exe), "eval", *args]).strip().splitlines():
        name, *values = line.split()
        out[name] = np.array([float(v) for v in values])
    ref = PinocchioReference(robot)
    nv = robot.model.nv
    M_pin = np.zeros((nv, nv))
    M_pin[np.triu_indices(nv)] = out["crba"]  # row by row: the order of numpy's upper triangle
    M_pin = np.triu(M_pin) + np.triu(M_pin, 1).T
    q_pin, v_pin, tau_pin = ref.pin_q(x["q"]), ref.pin_v(x["v"]), ref.pin_v(x["tau"], "tau")
    pairs = {
        "crba": (ref.project_matrix(M_pin), ref.mass_matrix(x["q"])),
        "rnea": (ref.project_v(out["rnea"]), ref.rnea(x["q"], x["v"], x["a"])),
        "nle": (ref.project_v(out["nle"]), ref.nonlinear_effects(x["q"], x["v"])),
        "gravity": (ref.project_v(out["gravity"]), ref.gravity(x["q"])),
        "aba": (ref.project_v(out["aba"]), ref.project_v(pin.aba(robot.model, ref.data, q_pin, v_pin, tau_pin))),
    }
    errors = {name: relative_error(value, expected) for name, (value, expected) in pairs.items()}
    bad = {name: e for name, e in errors.items() if not within(e, REL_TOL_TERMS)}
    if bad:
        worst = ", ".join(f"{name} {e:.1e}" for name, e in bad.items())
        raise NumericalError(f"Pinocchio's CppADCodeGen code of {robot.name} differs from Pinocchio native ({worst} relative); "
                             f"expected <= {REL_TOL_TERMS:g} before timing it")
    return errors


def time_command(robot: Robot, exe: Path, calls: int, reps: int) -> list[str]:
    """The harness's timing command (at the state of ``check``)."""
    return [str(exe), "time", str(calls), str(reps), *state_args(robot)[0]]


def timings(generated: dict[str, float], peer: dict[str, float], native: dict[str, float],
            errors: dict[str, float]) -> list[PeerTiming]:
    """The entries of one robot from the medians of the same run (generated names without prefix)."""
    out = []
    for function, (name, target) in PAIRS.items():
        ours = generated[name] if name else None
        algo = NATIVE[function]
        out.append(PeerTiming(name, ours, PEER, function, peer[function], ours / peer[function] if ours else None, target,
                              algo, native[algo], peer[function] / native[algo], errors[function]))
    return out
