"""The reduced model's generated C, called from Python: what the toolkit's own simulations use.

``CompiledReducedDynamics(robot)`` builds (once, cached and reused across processes by
``compiled``) the robot's shared library and calls its ``qd_id_r_<feet>`` / ``qd_fd_r_<feet>``
through ctypes. Same inputs and conventions as ``reduced.ReducedModel``: q_r, qd_r, qdd_r,
tau_ext (n,) with n = 12, or 13 for two stance feet (the 13th is the trunk roll), and quat the
trunk orientation (x, y, z, w). A degenerate stance (collinear feet, the front or back pair at zero pitch
or roll) and M_r singular to working precision raise NumericalError, a non-finite output InputError (the C
return codes: QD_DEGENERATE, QD_SINGULAR, QD_NONFINITE).
"""

from __future__ import annotations

import numpy as np

from quadruped_dyn.codegen.emit import reduced_symbol
from quadruped_dyn.codegen.library import CompiledFunction, compiled_library
from quadruped_dyn.errors import InputError
from quadruped_dyn.model.robot import Robot, check_robot
from quadruped_dyn.model.stance import StanceSet, stance_set
from quadruped_dyn.model.state import check_array


class CompiledReducedDynamics:
    """id_r and fd_r of every stance set of two, three or four feet, from the compiled C."""

    def __init__(self, robot: Robot) -> None:
        self.robot = check_robot(robot)
        self.library = compiled_library(robot)
        self._functions: dict[str, CompiledFunction] = {}

    def _call(self, name: str, stance: StanceSet | str, inputs: dict[str, np.ndarray]) -> np.ndarray:
        """Checked call: the stance (a StanceSet or a name like 'FL+BR'), shapes, finiteness and a
        non-zero quaternion here; singular configurations by the C function's return code
        (CompiledFunction raises NumericalError or InputError)."""
        stance = stance_set(stance)
        k = len(stance.feet)
        if k not in (2, 3, 4):
            raise InputError(f"stance {stance.name} has {k} feet; the reduced model needs 2, 3 or 4 distinct stance feet")
        n = 13 if k == 2 else 12
        args = [check_array(key, x, (4,) if key == "quat" else (n,)) for key, x in inputs.items()]  # quat: CompiledFunction
        symbol = reduced_symbol(name, stance)
        if symbol not in self._functions:
            self._functions[symbol] = CompiledFunction(self.library, symbol)
        return self._functions[symbol](*args)[0]

    def id_r(self, stance: StanceSet | str, q_r: np.ndarray, qd_r: np.ndarray, qdd_r: np.ndarray, quat: np.ndarray) -> np.ndarray:
        """tau_r (n,) [N m]: joint torques (and, for two feet, the moment about the support line)."""
        return self._call("id_r", stance, {"q_r": q_r, "qd_r": qd_r, "qdd_r": qdd_r, "quat": quat})

    def fd_r(
        self, stance: StanceSet | str, q_r: np.ndarray, qd_r: np.ndarray, tau_ext: np.ndarray, quat: np.ndarray
    ) -> np.ndarray:
        """qdd_r (n,) = M_r^-1 (tau_ext - C_r - G_r), the generated C's solve (c/qd_reduced_solve.c: the
        definition of ``dynamics.reduced.solve_forward_dynamics``, LU with a pivot check, in C);
        NumericalError where M_r is singular to working precision."""
        return self._call("fd_r", stance, {"q_r": q_r, "qd_r": qd_r, "tau_ext": tau_ext, "quat": quat})
