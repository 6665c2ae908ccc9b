"""Accuracy of the generated C's float build against its double build (docs/embedded.md).

Every generated function is called in both builds (the x86-64 libraries of ``compiled_library``:
the same source as on a target) at a few hundred seeded random states near standing; its error
is max |float - double| / max |double| over all its outputs. The reduced forward dynamics fd_r
amplifies rounding by the conditioning of M_r, so its error is also stated per unit of
eps_float * cond_1(M_r) (cond_1 from the double build's M_r at the same state). The bounds the
generated header states (``tolerances.FLOAT_ERROR_BOUNDS``) are checked against these
measurements by the tests.
"""

from __future__ import annotations

import ctypes
from dataclasses import dataclass, field

import numpy as np
import pinocchio as pin

from quadruped_dyn.codegen.emit import CODEGEN_FUNCTIONS, PREFIX, REDUCED_NAMES, REDUCED_STANCE_SETS, reduced_symbol
from quadruped_dyn.codegen.library import compiled_library
from quadruped_dyn.model.robot import Robot
from quadruped_dyn.model.state import NV_FULL, full_q

EPS_FLOAT = float(np.finfo(np.float32).eps)


class _Caller:
    """One generated function of a library, called through ctypes in its precision."""

    def __init__(self, lib: ctypes.CDLL, name: str, real: type) -> None:
        self.real = real
        self.ctype = ctypes.c_float if real is np.float32 else ctypes.c_double
        self.fn = getattr(lib, PREFIX + name)
        sp = ctypes.POINTER(ctypes.c_longlong)

        def nnz(kind: str, i: int) -> int:
            f = getattr(lib, f"{PREFIX}{name}_sparsity_{kind}")
            f.restype = sp
            s = f(i)
            # compressed column: nrow, ncol, colind[ncol + 1], row[nnz]; CasADi's compact form of a
            # dense pattern is nrow, ncol, 1 (a real colind starts at 0)
            return int(s[0] * s[1]) if s[2] == 1 else int(s[2 + int(s[1])])

        n_in, n_out = getattr(lib, f"{PREFIX}{name}_n_in")(), getattr(lib, f"{PREFIX}{name}_n_out")()
        self.nnz_in = [nnz("in", i) for i in range(n_in)]
        self.nnz_out = [nnz("out", i) for i in range(n_out)]
        self.work: np.ndarray = np.zeros(4096, dtype=real)

    def __call__(self, args: list[np.ndarray]) -> tuple[int, np.ndarray]:
        ptr = ctypes.POINTER(self.ctype)
        ins: list[np.ndarray] = [np.ascontiguousarray(a[:n], dtype=self.real) for a, n in zip(args, self.nnz_in)]
        outs: list[np.ndarray] = [np.zeros(n, dtype=self.real) for n in self.nnz_out]
        arg = (ptr * len(ins))(*[a.ctypes.data_as(ptr) for a in ins])
        res = (ptr * len(outs))(*[o.ctypes.data_as(ptr) for o in outs])
        flag = self.fn(arg, res, None, self.work.ctypes.data_as(ptr), 0)
        return flag, np.concatenate(outs).astype(float)


def function_names() -> list[str]:
    """Every generated function, without the prefix."""
    return list(CODEGEN_FUNCTIONS) + [reduced_symbol(k, s) for s in REDUCED_STANCE_SETS for k in REDUCED_NAMES]


def near_standing_inputs(robot: Robot, rng: np.random.Generator) -> dict[str, np.ndarray]:
    """Inputs of every generated function at a random state near standing: joints 0.2 rad
    around standing (inside the limits), trunk roll/pitch/yaw 0.2 rad, unit-scale rates."""
    joints = np.clip(robot.standing_q + rng.normal(scale=0.2, size=12), robot.lower, robot.upper)
    rpy = rng.normal(scale=0.2, size=3)
    q = full_q(pin.rpy.rpyToMatrix(*rpy), rng.normal(scale=0.5, size=3), joints)
    v, a = rng.normal(size=NV_FULL), rng.normal(size=NV_FULL)
    return {"q": q, "v": v, "a": a, "f": rng.normal(scale=20.0, size=12), "q_r": np.append(joints, rpy[0]),
            "qd_r": np.append(v[6:], v[3]), "qdd_r": np.append(a[6:], a[3]), "quat": q[3:7], "tau_ext": 10.0 * a[5:]}


#: The signal names of each function's inputs, in order (the header's signatures).
_SIGNATURES = {"M_full": ("q",), "C_full": ("q", "v"), "G_full": ("q",), "nle_full": ("q", "v"),
               "id_full": ("q", "v", "a", "f"), "grf": ("q", "v", "a"), "M_r": ("q_r", "quat"),
               "CG_r": ("q_r", "qd_r", "quat"), "G_r": ("q_r", "quat"), "id_r": ("q_r", "qd_r", "qdd_r", "quat"),
               "fd_r": ("q_r", "qd_r", "tau_ext", "quat")}


def _kind(name: str) -> str:
    if name.startswith("grf_"):
        return "grf"
    return next((k for k in REDUCED_NAMES if name.startswith(k + "_")), name)


@dataclass
class FloatAccuracy:
    """Per function: the largest float error seen, and for fd_r that error per eps_float * cond_1(M_r)."""

    states: int
    max_error: dict[str, float] = field(default_factory=dict)
    per_cond: dict[str, float] = field(default_factory=dict)  # fd_r: max err / (eps_float cond_1(M_r))
    max_cond: dict[str, float] = field(default_factory=dict)  # fd_r: largest cond_1(M_r) seen
    flagged: dict[str, int] = field(default_factory=dict)  # states where a build returned non-zero


def measure(robot: Robot, n_states: int = 300, seed: int = 0) -> FloatAccuracy:
    double = ctypes.CDLL(str(compiled_library(robot, "double").path))
    single = ctypes.CDLL(str(compiled_library(robot, "float").path))
    names = function_names()
    callers = {n: (_Caller(double, n, np.float64), _Caller(single, n, np.float32)) for n in names}
    rng = np.random.default_rng(seed)
    out = FloatAccuracy(n_states)
    for _ in range(n_states):
        x = near_standing_inputs(robot, rng)
        m_r: dict[str, np.ndarray] = {}
        for name in names:
            d_call, f_call = callers[name]
            args = [x[s] for s in _SIGNATURES[_kind(name)]]
            (fd, d), (ff, f) = d_call(args), f_call(args)
            if _kind(name) == "M_r":
                m_r[name[len("M_r_"):]] = d
            if fd != 0 or ff != 0:
                out.flagged[name] = out.flagged.get(name, 0) + 1
                continue
            err = float(np.abs(f - d).max() / (np.abs(d).max() or 1.0))
            out.max_error[name] = max(out.max_error.get(name, 0.0), err)
            if _kind(name) == "fd_r":
                M = m_r[name[len("fd_r_"):]]
                n = int(round(np.sqrt(M.size)))
                cond = float(np.linalg.cond(M.reshape(n, n, order="F"), 1))
                out.per_cond[name] = max(out.per_cond.get(name, 0.0), err / (EPS_FLOAT * cond))
                out.max_cond[name] = max(out.max_cond.get(name, 0.0), cond)
    return out
