"""The memory a caller provides to one generated function (deterministic: from CasADi's work
sizes and the signature only, so it is stated in the generated header; docs/embedded.md)."""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca

from quadruped_dyn.tolerances import FLOAT_FD_R_PER_COND, FLOAT_REL_TOL, FLOAT_USABLE_REL_ERR

POINTER_BYTES = 4  # Cortex-M (ILP32)
CASADI_INT_BYTES = 8  # the generated code's casadi_int is long long int


@dataclass(frozen=True)
class WorkMemory:
    """What a caller of one generated function provides, in bytes for a 32-bit target."""

    sz_arg: int
    sz_res: int
    sz_iw: int
    sz_w: int
    n_in: int  # reals of all inputs
    n_out: int  # reals (nonzeros) of all outputs

    def bytes(self, real_bytes: int) -> int:
        return (POINTER_BYTES * (self.sz_arg + self.sz_res) + CASADI_INT_BYTES * self.sz_iw
                + real_bytes * (self.sz_w + self.n_in + self.n_out))


def work_memory(f: ca.Function, iw: int, w: int) -> WorkMemory:
    """``iw``, ``w``: the generated code's sizes (its header's _SZ_IW, _SZ_W: CasADi keeps the SX
    work on the stack, so these are not ``f.sz_w()`` of the virtual machine)."""
    return WorkMemory(f.sz_arg(), f.sz_res(), iw, w, sum(f.nnz_in(i) for i in range(f.n_in())),
                      sum(f.nnz_out(i) for i in range(f.n_out())))



def memory_doc(functions: list[ca.Function], work: dict[str, tuple[int, int]]) -> list[str]:
    """Header comment lines: each function's caller memory in bytes, double / float."""
    lines = [
        " *",
        " * Embedded use (docs/embedded.md): memory the caller provides per call, in bytes on a 32-bit",
        f" * target: arg and res pointer arrays ({POINTER_BYTES} B each), iw ({CASADI_INT_BYTES} B casadi_int), w, and the",
        " * inputs and outputs themselves; double / float. Code size and worst-case stack depend on the",
        " * compiler and its flags: measured by `quadruped-dyn codegen ROBOT --out DIR --json` (cross",
        " * builds, docs/embedded.md), not stated here.",
    ]
    lines += [
        " *",
        " * Float build (-Dcasadi_real=float) against the double build, relative to the largest output",
        " * (measured at 300 states near standing, docs/embedded.md): the full-coordinate terms within",
        f" * {FLOAT_REL_TOL:g}; the GRF solves and reduced terms lose the digits of the stance set's GRF system",
        " * and velocity map conditioning (front or back pair: float can leave no correct digit; use",
        f" * double there); fd_r within {FLOAT_FD_R_PER_COND:g} x FLT_EPSILON x cond_1(M_r) (QD_SINGULAR flags the",
        " * worst cases by its pivot test; measured: no float fd_r result returned as 0 was off by more",
        f" * than {FLOAT_USABLE_REL_ERR:g}).",
        " *",
        " * Caller memory per function, bytes, double/float:",
    ]
    memory = {f.name(): work_memory(f, *work[f.name()]) for f in functions}
    cells = [f"{n} {m.bytes(8)}/{m.bytes(4)}" for n, m in memory.items()]
    row = " *  "
    for c in cells:
        if len(row) + len(c) + 2 > 100:
            lines.append(row.rstrip())
            row = " *  "
        row += " " + c + ";"
    lines.append(row.rstrip())
    return lines
