"""C of a function evaluated leg by leg (``codegen.forms.leg_template.LegPieces``; docs/derivatives.md, "dfd_r and dgrf as
generated C").

The head, each template's leg function and the tail become static C functions (``static_c``); the function itself
calls the head, then each leg's template function once per leg (the legs of one template one after the other, so
that its machine code stays in the instruction cache), then the tail, which writes the outputs. Each leg's
parameters are a static table; a leg whose joints turn the other way than its template's (sigma = -1) gets its joint
inputs and their sines negated into a local array first (cos is even)."""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca

from quadruped_dyn.codegen.c_facts import prelude_c
from quadruped_dyn.codegen.forms.leg_template import LegPieces
from quadruped_dyn.codegen.joint_trig import trig_as_inputs
from quadruped_dyn.codegen.print_settings import static_c
from quadruped_dyn.model.leg import LEG_LABELS

_SIGNATURE = "(const casadi_real** arg, casadi_real** res, casadi_int* iw, casadi_real* w, int mem)"

#: A leg function's input before its parameters: ("arg", i, offset) the trunk's entries at arg[i] + offset; ("head",
#: j) the head's output j; ("joint", i, first) the leg's three joint entries at arg[i][first + 3 k ...] (times sigma);
#: ("leg", i, first) the leg's three entries at arg[i] + first + 3 k (a foot force: not turned).
LegInput = tuple[str, int] | tuple[str, int, int]


@dataclass(frozen=True)
class LegCall:
    """Where the pieces' inputs come from in the function's arg (its signature's inputs, then sin and cos of the 12
    joint angles at ``sin_arg`` and ``sin_arg`` + 1)."""

    head_args: tuple[int, ...]
    leg_inputs: tuple[LegInput, ...]  # the leg function's inputs before p, sin, cos
    sin_arg: int
    tail_args: tuple[int, ...]  # the tail's inputs before L_0..L_3


def legs_reals(pieces: LegPieces) -> int:
    """Reals of the legs' outputs L_0..L_3 ``by_leg_c``'s function keeps between the legs and the tail."""
    return 4 * max(f.nnz_out(0) for f in pieces.legs)


def by_leg_c(c_name: str, pieces: LegPieces, call: LegCall, host_helpers: frozenset[str],
             test_outputs: bool = False, export_in: bool = False) -> str:
    """Static C functions of ``pieces``, ``{c_name}_in(arg, res, L, iw, w, mem)`` calling them with the legs' outputs in
    L (``legs_reals``: the caller's memory; exported with ``export_in``, for a caller short of stack) and
    ``int c_name(arg, res, iw, w, mem)``, which keeps L on its stack. The tail writes every output (the callers pass all) or,
    with ``test_outputs``, tests each output pointer as CasADi
    does (its inputs all given)."""
    joints = [i for i, x in enumerate(call.leg_inputs) if x[0] == "joint"]
    if not joints:
        raise AssertionError(f"{c_name}: a leg function reads no joint angle")
    q_input = joints[0]  # the angles: the first joint input
    if any(f.n_in() != len(call.leg_inputs) + 1 for f in pieces.legs) or pieces.tail.n_in() != len(call.tail_args) + 4:
        raise AssertionError(f"{c_name}: the pieces' inputs are not as the call reads them")
    text = [prelude_c()]
    if pieces.head is not None:
        text.append(static_c(f"{c_name}_head", pieces.head, host_helpers, all_io=True))
    for i, leg in enumerate(pieces.legs):  # one copy of its code for every leg of its template
        text.append("QD_NOINLINE " + static_c(f"{c_name}_leg{i}", trig_as_inputs(leg, q_input), host_helpers,
                                              all_io=True))
    for k in range(4):
        values = pieces.leg_values(k)
        text.append(f"static const casadi_real {c_name}_p{k}[{max(len(values), 1)}] = "
                    f"{{{', '.join(repr(x) for x in values) if values else '0'}}}; /* {LEG_LABELS[k]}'s parameters */\n")
    text.append(static_c(f"{c_name}_tail", pieces.tail, host_helpers, all_io=not test_outputs, inputs_given=True))
    nl = legs_reals(pieces) // 4
    body = [f"{'' if export_in else 'static '}int {c_name}_in(const casadi_real** arg, casadi_real** res, casadi_real* L, "
            "casadi_int* iw, casadi_real* w, int mem) {\n"]
    if pieces.head is not None:
        heads = [f"h{j}" for j in range(pieces.head.n_out())]
        body.append("".join(f"  casadi_real h{j}[{pieces.head.nnz_out(j)}];\n" for j in range(pieces.head.n_out())))
        body.append(f"  const casadi_real* h_arg[{len(call.head_args)}] = {{{', '.join(f'arg[{i}]' for i in call.head_args)}}};\n"
                    f"  casadi_real* h_res[{len(heads)}] = {{{', '.join(heads)}}};\n"
                    f"  {c_name}_head(h_arg, h_res, iw, w, mem);\n")
    for k in sorted(range(4), key=lambda k: pieces.template_of[k]):
        body.append(_leg_call(c_name, pieces, call, k, nl))
    t_arg = [f"arg[{i}]" for i in call.tail_args] + [f"L + {nl * k}" for k in range(4)]
    body.append(f"  const casadi_real* t_arg[{len(t_arg)}] = {{{', '.join(t_arg)}}};\n"
                f"  return {c_name}_tail(t_arg, res, iw, w, mem);\n}}\n\n")
    body.append(f"int {c_name}{_SIGNATURE} {{\n  casadi_real L[{4 * nl}];\n"
                f"  return {c_name}_in(arg, res, L, iw, w, mem);\n}}\n")
    return "\n".join(text) + "\n" + "".join(body)


def _leg_call(c_name: str, pieces: LegPieces, call: LegCall, k: int, nl: int) -> str:
    """The call of robot leg k's template function, its outputs at L + nl k."""
    sigma = pieces.leg_signs(k)
    turned = any(x < 0 for x in sigma)
    local: list[str] = []
    inputs: list[str] = []
    for x in call.leg_inputs:
        if x[0] == "arg":
            inputs.append(f"arg[{x[1]}] + {x[2]}")  # type: ignore[misc]
        elif x[0] == "head":
            inputs.append(f"h{x[1]}")
        elif x[0] == "leg":
            inputs.append(f"arg[{x[1]}] + {x[2] + 3 * k}")  # type: ignore[misc]
        elif turned:
            inputs.append(f"x + {len(local)}")
            local += [f"{'-' if s < 0 else ''}arg[{x[1]}][{x[2] + 3 * k + j}]" for j, s in enumerate(sigma)]  # type: ignore[misc]
        else:
            inputs.append(f"arg[{x[1]}] + {x[2] + 3 * k}")  # type: ignore[misc]
    sin = f"arg[{call.sin_arg}] + {3 * k}"
    if turned:
        sin = f"x + {len(local)}"
        local += [f"{'-' if s < 0 else ''}arg[{call.sin_arg}][{3 * k + j}]" for j, s in enumerate(sigma)]
    prologue = f"    const casadi_real x[{len(local)}] = {{{', '.join(local)}}}; /* sigma times */\n" if turned else ""
    l_arg = [*inputs, f"{c_name}_p{k}", sin, f"arg[{call.sin_arg + 1}] + {3 * k}"]
    return (f"  {{ /* leg {k} */\n{prologue}    const casadi_real* l_arg[{len(l_arg)}] = {{{', '.join(l_arg)}}};\n"
            f"    casadi_real* l_res[1] = {{L + {nl * k}}};\n"
            f"    {c_name}_leg{pieces.template_of[k]}(l_arg, l_res, iw, w, mem);\n  }}\n")


def foot_c(c_name: str, pieces: LegPieces, host_helpers: frozenset[str]) -> str:
    """Static C functions of ``pieces`` (``codegen.forms.leg_pieces.foot_pieces``: leg functions (q_l, qd_l, p) -> FOOT_PARTS,
    and each at qd_l = 0, without the rates' operations) and ``int c_name(int k, q_l, qd_l, s, c, y)``: robot leg k's
    foot kinematics y (18) at its joints' q_l, qd_l (3 each; null: at rest) and their sines s and cosines c, by its
    template's function and parameters; a leg whose joints turn the other
    way than its template's gets q_l, qd_l and s negated into a local array and J's columns negated after (r, J qd_l
    and Jdot qd_l are the template's at sigma q_l, sigma qd_l). The reduced files call it for their stance legs only
    (c/qd_reduced_solve.c, qd_parts)."""
    text = [prelude_c()]
    for i, leg in enumerate(pieces.legs):
        if leg.name_in() != ["q_l", "qd_l", "p"] or leg.nnz_out(0) != 18:
            raise AssertionError(f"{c_name}: a leg function is not (q_l, qd_l, p) -> FOOT_PARTS")
        q_l, p = ca.SX.sym("q_l", 3), ca.SX.sym("p", leg.sparsity_in(2))
        at_rest = ca.Function(f"{leg.name()}_at_rest", [q_l, p], leg.call([q_l, ca.SX.zeros(3), p]), {"cse": True})
        for name, f in ((f"{c_name}_leg{i}", leg), (f"{c_name}_at_rest_leg{i}", at_rest)):
            text.append("QD_NOINLINE " + static_c(name, trig_as_inputs(f, 0), host_helpers, all_io=True))
    cases = []
    for k in range(4):
        values = pieces.leg_values(k)
        text.append(f"static const casadi_real {c_name}_p{k}[{max(len(values), 1)}] = "
                    f"{{{', '.join(repr(x) for x in values) if values else '0'}}}; /* {LEG_LABELS[k]}'s parameters */\n")
        sigma = pieces.leg_signs(k)
        t = pieces.template_of[k]
        call = (f"qd_l ? {c_name}_leg{t}(a, r, 0, 0, 0) : {c_name}_at_rest_leg{t}(a_rest, r, 0, 0, 0)")
        if all(s > 0 for s in sigma):
            cases.append(f"  case {k}: {{\n    const casadi_real* a[5] = {{q_l, qd_l, {c_name}_p{k}, s, c}};\n"
                         f"    const casadi_real* a_rest[4] = {{q_l, {c_name}_p{k}, s, c}};\n"
                         f"    casadi_real* r[1] = {{y}};\n    return {call};\n  }}\n")
            continue
        turned = ", ".join(f"{'-' if sg < 0 else ''}{x}[{j}]" for x in ("q_l", "s") for j, sg in enumerate(sigma))
        turned_qd = ", ".join(f"qd_l ? {'-' if sg < 0 else ''}qd_l[{j}] : 0" for j, sg in enumerate(sigma))
        back = "".join(f"    for (int d = 0; d < 3; ++d) y[{3 + 3 * j} + d] = -y[{3 + 3 * j} + d];\n"
                       for j, sg in enumerate(sigma) if sg < 0)
        cases.append(f"  case {k}: {{ /* sigma = {tuple(int(x) for x in sigma)} */\n    const casadi_real x[6] = {{{turned}}};\n"
                     f"    const casadi_real x_d[3] = {{{turned_qd}}};\n"
                     f"    const casadi_real* a[5] = {{x, x_d, {c_name}_p{k}, x + 3, c}};\n"
                     f"    const casadi_real* a_rest[4] = {{x, {c_name}_p{k}, x + 3, c}};\n"
                     f"    casadi_real* r[1] = {{y}};\n    int flag = {call};\n{back}    return flag;\n  }}\n")
    text.append(f"int {c_name}(int k, const casadi_real* q_l, const casadi_real* qd_l, const casadi_real* s, "
                "const casadi_real* c, casadi_real* y) {\n  switch (k) {\n" + "".join(cases) + "  }\n  return 0;\n}\n")
    return "\n".join(text)
