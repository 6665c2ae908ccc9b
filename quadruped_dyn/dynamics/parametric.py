"""The full-coordinate terms with the robot's numbers as an input: one graph per family (``model/parameters.py``).

The robot of ``parameters.parametric_robot`` (its masses, CoMs, inertias, joint positions and foot points entries of
an SX p) goes through the same algorithms as a loaded robot: ``crba`` for M and G, ``newton_euler`` for the rest;
they take each body's first moment m c and inertia about its origin as p has them (``LinkInertia.origin``).
Each Function takes p (N_PARAMETERS,) as its last input, named "p"; the fixed library's inputs come first, in its
order. The dynamics are linear in the inertial part pi = p[:N_INERTIAL]:
``regressor_full(q, v, a, p)`` = Y (18, 130) with id_full(q, v, a, 0, p) = Y pi (Pinocchio's
``computeJointTorqueRegressor``, in the project's order and conventions), the Jacobian of the same graph.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cache

import casadi as ca

from quadruped_dyn.dynamics.crba import generalized_gravity, mass_matrix_crba
from quadruped_dyn.dynamics.newton_euler import gravity_in_trunk, inverse_dynamics
from quadruped_dyn.model.parameters import N_INERTIAL, N_PARAMETERS, Family, parametric_robot
from quadruped_dyn.model.state import NQ_FULL, NV_FULL


@dataclass(frozen=True)
class ParametricDynamics:
    """Named CasADi Functions of a family; each takes p last (module docstring)."""

    M_full: ca.Function  # q, p -> M (18, 18), composite rigid bodies
    C_full: ca.Function  # q, v, p -> C (18,) velocity terms
    G_full: ca.Function  # q, p -> G (18,)
    nle_full: ca.Function  # q, v, p -> C + G (18,)
    id_full: ca.Function  # q, v, a, f, p -> (w_res (6,), tau (12,))
    regressor_full: ca.Function  # q, v, a, p -> Y (18, N_INERTIAL)

    def functions(self) -> tuple[ca.Function, ...]:
        return (self.M_full, self.C_full, self.G_full, self.nle_full, self.id_full, self.regressor_full)


@cache
def parametric_dynamics(family: Family) -> ParametricDynamics:
    """The family's parametric Functions (built once per family)."""
    q, v, a, f = ca.SX.sym("q", NQ_FULL), ca.SX.sym("v", NV_FULL), ca.SX.sym("a", NV_FULL), ca.SX.sym("f", 12)
    p = ca.SX.sym("p", N_PARAMETERS)
    robot = parametric_robot(family, p)
    qj, g_b = q[7:], gravity_in_trunk(q)
    zero_v, zero_f, zero_g = ca.SX.zeros(NV_FULL), ca.SX.zeros(12), ca.SX.zeros(3)
    tau = inverse_dynamics(robot, qj, g_b, v, a, f)
    Y = ca.jacobian(inverse_dynamics(robot, qj, g_b, v, a, zero_f), p[:N_INERTIAL])
    opts = {"cse": True}

    def function(name: str, inputs: dict[str, ca.SX], outputs: dict[str, ca.SX]) -> ca.Function:
        named = {**inputs, "p": p}
        return ca.Function(name, list(named.values()), list(outputs.values()), list(named), list(outputs), opts)

    return ParametricDynamics(
        M_full=function("M_full", {"q": q}, {"M": mass_matrix_crba(robot, qj)}),
        C_full=function("C_full", {"q": q, "v": v}, {"C": inverse_dynamics(robot, qj, zero_g, v, zero_v, zero_f)}),
        G_full=function("G_full", {"q": q}, {"G": generalized_gravity(robot, qj, g_b)}),
        nle_full=function("nle_full", {"q": q, "v": v}, {"nle": inverse_dynamics(robot, qj, g_b, v, zero_v, zero_f)}),
        id_full=function("id_full", {"q": q, "v": v, "a": a, "f": f}, {"w_res": tau[:6], "tau": tau[6:]}),
        regressor_full=function("regressor_full", {"q": q, "v": v, "a": a}, {"Y": ca.sparsify(Y)}),
    )
