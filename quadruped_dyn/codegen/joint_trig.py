"""A generated function with the sines and cosines of some of its inputs' entries as two more inputs
(docs/embedded.md, "The joints' sines and cosines"): its sin and cos of those entries read them instead, so a
caller takes them once — all twelve joint angles together at a C entry point (``c/qd_sincos.c``), or once for the
7-13 calls of dfd_r's lift at one point — instead of one libm call per angle inside each function."""

from __future__ import annotations

import casadi as ca


def trig_as_inputs(f: ca.Function, i_q: int, entries: range | None = None) -> ca.Function:
    """``f`` (an SX Function) with two more inputs after its own, sin and cos (one entry each per entry of input
    ``i_q`` in ``entries``, default all): every sin(x) / cos(x) whose x is such an entry reads sin[k] / cos[k]. The
    other operations are rebuilt one for one in f's order, so for sin, cos of those entries the outputs are f's to the
    bit. The entries themselves stay inputs (read where f reads them other than through sin and cos)."""
    if not f.is_a("SXFunction"):
        raise ValueError(f"{f.name()}: trig_as_inputs rewrites SX Functions, not {f.class_name()}")
    entries = range(f.nnz_in(i_q)) if entries is None else entries
    ins = [ca.SX.sym(f.name_in(i), f.sparsity_in(i)) for i in range(f.n_in())]
    sin, cos = (ca.SX.sym(x, len(entries)) for x in ("sin", "cos"))
    k_of = {e: k for k, e in enumerate(entries)}
    outs = [ca.SX(f.sparsity_out(i)) for i in range(f.n_out())]
    work: dict[int, ca.SX] = {}
    angle: dict[int, int] = {}  # work slot -> the entry of sin/cos its value's angle is
    for k in range(f.n_instructions()):
        op, a, r = f.instruction_id(k), f.instruction_input(k), f.instruction_output(k)
        if op == ca.OP_OUTPUT:
            outs[r[0]].nz[r[1]] = work[a[0]]
            continue
        read = angle.get(a[0]) if op in (ca.OP_SIN, ca.OP_COS) else None
        angle.pop(r[0], None)  # the slot is overwritten (CasADi reuses them, in place too)
        if op == ca.OP_INPUT:
            work[r[0]] = ins[a[0]].nz[a[1]]
            if a[0] == i_q and a[1] in k_of:
                angle[r[0]] = k_of[a[1]]
        elif op == ca.OP_CONST:
            work[r[0]] = ca.SX(f.instruction_constant(k))
        elif read is not None:
            work[r[0]] = (sin if op == ca.OP_SIN else cos)[read]
        elif len(a) == 1:
            work[r[0]] = ca.SX.unary(op, work[a[0]])
        else:
            work[r[0]] = ca.SX.binary(op, work[a[0]], work[a[1]])
    return ca.Function(f.name(), [*ins, sin, cos], outs, [*f.name_in(), "sin", "cos"], f.name_out(), {"cse": True})


def trig_count(f: ca.Function) -> int:
    """The number of sin and cos operations in ``f``'s graph."""
    return sum(f.instruction_id(k) in (ca.OP_SIN, ca.OP_COS) for k in range(f.n_instructions()))
