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

from dataclasses import dataclass, field

import numpy as np
import pinocchio as pin

from quadruped_dyn.codegen.emit import CODEGEN_FUNCTIONS, REDUCED_NAMES, REDUCED_STANCE_SETS, reduced_parts, reduced_symbol
from quadruped_dyn.codegen.library import CompiledFunction, compiled_library
from quadruped_dyn.errors import InputError, NumericalError
from quadruped_dyn.model.robot import Robot
from quadruped_dyn.model.state import NV_FULL, full_q

EPS_FLOAT = float(np.finfo(np.float32).eps)


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


def _outputs(f: CompiledFunction, x: dict[str, np.ndarray]) -> np.ndarray | None:
    """f's outputs at the inputs x (by input name, the first entries of each: q_r has 13, a
    three-feet function takes 12), all in one float64 vector (column-major); None where the C
    function returned a non-zero code."""
    try:
        outs = f(*[x[name][:size] for name, size in zip(f.names_in, f.sizes_in)])
    except (InputError, NumericalError):
        return None
    return np.concatenate([o.ravel(order="F") for o in outs])


@dataclass
class FloatAccuracy:
    """Per function: the largest float error seen, and for fd_r that error per eps_float * cond_1(M_r)."""

    states: int
    max_error: dict[str, float] = field(default_factory=dict)
    per_cond: dict[str, float] = field(default_factory=dict)  # fd_r: max err / (eps_float cond_1(M_r))
    max_cond: dict[str, float] = field(default_factory=dict)  # fd_r: largest cond_1(M_r) seen
    flagged: dict[str, int] = field(default_factory=dict)  # states where a build returned non-zero


def measure(robot: Robot, n_states: int = 300, seed: int = 0) -> FloatAccuracy:
    double, single = compiled_library(robot, "double"), compiled_library(robot, "float")
    names = function_names()
    functions = {n: (CompiledFunction(double, n), CompiledFunction(single, n)) for n in names}
    rng = np.random.default_rng(seed)
    out = FloatAccuracy(n_states)
    for _ in range(n_states):
        x = near_standing_inputs(robot, rng)
        m_r: dict[str, np.ndarray] = {}  # stance name -> M_r (double build)
        for name in names:
            parts = reduced_parts(name)
            kind, stance = (parts[0], parts[1].name) if parts else (name, "")
            d, f = (_outputs(g, x) for g in functions[name])
            if kind == "M_r" and d is not None:
                m_r[stance] = d
            if d is None or f is None:
                out.flagged[name] = out.flagged.get(name, 0) + 1
                continue
            err = float(np.abs(f - d).max() / (np.abs(d).max() or 1.0))
            out.max_error[name] = max(out.max_error.get(name, 0.0), err)
            if kind == "fd_r" and stance in m_r:
                M = m_r[stance]
                n = int(round(np.sqrt(M.size)))
                cond = float(np.linalg.cond(M.reshape(n, n, order="F"), 1))
                out.per_cond[name] = max(out.per_cond.get(name, 0.0), err / (EPS_FLOAT * cond))
                out.max_cond[name] = max(out.max_cond.get(name, 0.0), cond)
    return out
