"""Generated C of the derivatives of the full dynamics: ``qd_<robot>_d.c`` (docs/derivatives.md).

Functions (prefix ``qd_``), in one file beside the others, compiled into the same library:

* ``did_full(q, v, a) -> (dtau_dq, dtau_dv, dtau_da)``: CasADi's Jacobians of the full inverse
  dynamics (``dynamics/derivatives.py``), sparse outputs (leg rows do not depend on other legs);
* ``dfd_full_parts(q, v) -> (M, nle)``: M (dense) and C + G, what the forward-dynamics derivative needs;
* ``dfd_full(q, v, tau_full) -> (da_dq, da_dv, da_dtau)``: a signature only; its body is
  ``c/qd_derivatives_solve.c`` (Cholesky of M in plain C, then -M^-1 dtau/dx at a = fd).

d/dq is along ``pinocchio.integrate`` (a body-frame increment of the trunk pose; 18 columns).
The reduced model's and the GRF solve's derivatives are not generated: CasADi's Jacobians of one
stance set's id_r take 48-78k operations and of one GRF solve 18-21k (~20 bytes of C each), which
for the 10 reduced and 15 GRF stance sets would exceed the 6 MB budget of a robot's generated C;
they are Python/CasADi functions (``dynamics/derivatives.py``).
"""

from __future__ import annotations

import re

import casadi as ca

from quadruped_dyn.codegen.casadi_source import PREFIX, TEMPLATES, casadi_c, entry_point, work_sizes
from quadruped_dyn.dynamics.derivatives import full_derivatives
from quadruped_dyn.dynamics.newton_euler import full_dynamics
from quadruped_dyn.model.robot import Robot
from quadruped_dyn.model.state import NQ_FULL, NV_FULL

DERIVATIVE_NAMES = ("did_full", "dfd_full_parts", "dfd_full")


def derivative_functions(robot: Robot) -> list[ca.Function]:
    """The generated derivative Functions, named with the C prefix."""
    q, v, a, tau = ca.SX.sym("q", NQ_FULL), ca.SX.sym("v", NV_FULL), ca.SX.sym("a", NV_FULL), ca.SX.sym("tau_full", NV_FULL)
    d, fd = full_derivatives(robot), full_dynamics(robot)
    opts = {"cse": True}
    did = ca.Function(PREFIX + "did_full", [q, v, a], d.did_full.call([q, v, a]), ["q", "v", "a"],
                      ["dtau_dq", "dtau_dv", "dtau_da"], opts)
    parts = ca.Function(PREFIX + "dfd_full_parts", [q, v], [ca.densify(fd.M_full_crba(q)), fd.nle_full(q, v)],
                        ["q", "v"], ["M", "nle"], opts)
    placeholder = ca.repmat(tau, 1, NV_FULL) + ca.sum1(q) + ca.sum1(v)  # dense 18 x 18, depends on every input
    dfd = ca.Function(PREFIX + "dfd_full", [q, v, tau], [placeholder] * 3, ["q", "v", "tau_full"],
                      ["da_dq", "da_dv", "da_dtau"], opts)
    return [did, parts, dfd]


def derivative_source(file_stem: str, functions: list[ca.Function], precision: str) -> tuple[str, str]:
    """(C source, CasADi's header) of qd_<robot>_d.c: CasADi's code with c/qd_derivatives_solve.c
    inserted; every entry point returns QD_NONFINITE for a non-finite output, dfd_full solves."""
    c_text, h_text = casadi_c(file_stem, functions, precision)
    first = c_text.index(f"\n/* {functions[0].name()}:")
    c_text = c_text[:first] + "\n" + (TEMPLATES / "qd_derivatives_solve.c").read_text() + c_text[first:]
    work = work_sizes(h_text)
    raw = {}
    for f in functions:
        found = re.search(entry_point(f.name()), c_text)
        if not found or work[f.name()] != (0, 0):
            raise AssertionError(f"entry point of {f.name()} not found, or it needs work memory")
        raw[f.name()] = found.group(2)
    for f in functions:
        if f.name() == PREFIX + "dfd_full":
            did, parts = raw[PREFIX + "did_full"], raw[PREFIX + "dfd_full_parts"]
            body = (rf"\1  (void)\2;\n  return qd_dfd_full_solve({parts}, {did}, {PREFIX}did_full_sparsity_out(0), "
                    rf"{PREFIX}did_full_sparsity_out(1), arg, res, iw, w, mem);\n")
        else:
            nnz = ", ".join(str(f.nnz_out(i)) for i in range(f.n_out()))
            body = rf"\1  return qd_d_finite(\2(arg, res, iw, w, mem), res, {f.n_out()}, (const casadi_int[]){{{nnz}}});\n"
        c_text, count = re.subn(entry_point(f.name()), body, c_text)
        if count != 1:
            raise AssertionError(f"entry point of {f.name()} not found in CasADi's output")
    # dfd_full calls qd_did_full_sparsity_out, defined further down: declare it first
    declaration = f"CASADI_SYMBOL_EXPORT const casadi_int* {PREFIX}did_full_sparsity_out(casadi_int i);\n"
    first = c_text.index("\n/* quadruped_dyn: derivatives")
    return c_text[:first] + "\n" + declaration + c_text[first:], h_text
