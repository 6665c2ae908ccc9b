"""The one C printer of the generated evaluation functions: an SX ``casadi.Function`` printed from its instruction
list (``n_instructions``, ``instruction_id``, ``instruction_input``, ``instruction_output``,
``instruction_constant``), structured data, never CasADi's output text.

With the default ``PrintOptions`` the function prints as CasADi's ``CodeGenerator`` prints its static evaluation
function (casadi/core/sx_function.cpp ``codegen_body``, code_generator.cpp ``constant`` and ``scope_exit``), byte for
byte (tests/codegen/test_printer.py): ``static int NAME(const casadi_real** arg, casadi_real** res, casadi_int* iw,
casadi_real* w, int mem)``, one local ``aK`` per work value, one statement per instruction. The options are this
project's forms of it: no test of the argument pointers where the caller passes them all, products with a shared
denominator's reciprocal, the elementary functions in casadi_real's precision, the unused parameters cast to void.

``lanes`` L > 1 evaluates L states per call (the batch functions): nonzero k of input i for state l is
``arg[i][k*L+l]``, outputs alike, and the body is one loop over the states with scalar locals (the states side by
side, so a compiler can vectorise across them). ``parameters`` names inputs every state shares (a robot's masses and
lengths as symbolic inputs of the graph, for the parametric functions): read at ``arg[i][k]`` whatever the lanes. A
parameter enters the graph as a symbol, never as a literal matched by value (a mass of 1 kg is not every ``1.``)."""

from __future__ import annotations

import math
from dataclasses import dataclass

import casadi as ca

from quadruped_dyn.codegen.precision_math import PRECISION_MATH

SIGNATURE = "(const casadi_real** arg, casadi_real** res, casadi_int* iw, casadi_real* w, int mem)"
#: CasADi's ``max_declarations_per_line``
_DECLARATIONS_PER_LINE = 12
_UNUSED = "(void)arg; (void)res; (void)iw; (void)w; (void)mem;"

#: op -> (before, between, after) of its operands, as casadi_math<double>::pre/sep/post and CodeGenerator::print_op
_OPERATORS: dict[int, tuple[str, str, str]] = {
    ca.OP_ASSIGN: ("", "", ""), ca.OP_ADD: ("(", "+", ")"), ca.OP_SUB: ("(", "-", ")"), ca.OP_MUL: ("(", "*", ")"),
    ca.OP_DIV: ("(", "/", ")"), ca.OP_NEG: ("(-", "", ")"), ca.OP_TWICE: ("(2.*", "", ")"), ca.OP_INV: ("(1./", "", ")"),
    ca.OP_LT: ("(", "<", ")"), ca.OP_LE: ("(", "<=", ")"), ca.OP_EQ: ("(", "==", ")"), ca.OP_NE: ("(", "!=", ")"),
    ca.OP_NOT: ("(!", "", ")"), ca.OP_AND: ("(", "&&", ")"), ca.OP_OR: ("(", "||", ")"),
    ca.OP_IF_ELSE_ZERO: ("(", "?", ":0)"),
    ca.OP_FABS: ("casadi_fabs(", "", ")"), ca.OP_SQ: ("casadi_sq(", "", ")"), ca.OP_SIGN: ("casadi_sign(", "", ")"),
    ca.OP_FMIN: ("casadi_fmin(", ",", ")"), ca.OP_FMAX: ("casadi_fmax(", ",", ")"),
    ca.OP_HYPOT: ("casadi_hypot(", ",", ")"),
    **{op: (f"{name}(", ",", ")") for op, name in (
        (ca.OP_SIN, "sin"), (ca.OP_COS, "cos"), (ca.OP_TAN, "tan"), (ca.OP_SQRT, "sqrt"), (ca.OP_EXP, "exp"),
        (ca.OP_LOG, "log"), (ca.OP_ASIN, "asin"), (ca.OP_ACOS, "acos"), (ca.OP_ATAN, "atan"), (ca.OP_ATAN2, "atan2"),
        (ca.OP_POW, "pow"), (ca.OP_CONSTPOW, "pow"), (ca.OP_SINH, "sinh"), (ca.OP_COSH, "cosh"),
        (ca.OP_TANH, "tanh"), (ca.OP_FLOOR, "floor"), (ca.OP_CEIL, "ceil"), (ca.OP_FMOD, "fmod"),
        (ca.OP_COPYSIGN, "copysign"), (ca.OP_ERF, "erf"))},
}
#: The CasADi helpers an op's C calls (the file the function goes into defines them)
_HELPERS = {ca.OP_FABS: "casadi_fabs", ca.OP_SQ: "casadi_sq", ca.OP_SIGN: "casadi_sign", ca.OP_FMIN: "casadi_fmin",
            ca.OP_FMAX: "casadi_fmax", ca.OP_HYPOT: "casadi_hypot"}


@dataclass(frozen=True)
class PrintOptions:
    """How ``print_function`` prints; the defaults print CasADi's evaluation function."""

    name: str = "casadi_f0"  # the C function's name
    guard_inputs: bool = True  # read arg[i][k] as CasADi does, ``arg[i]? arg[i][k] : 0`` (False: the caller passes all)
    guard_outputs: bool = True  # write res[i][k] as CasADi does, ``if (res[i]!=0) ...`` (False: the caller passes all)
    #: a denominator dividing more than once, or a constant one: one reciprocal ``rcpK`` right after it is written, its
    #: quotients products with it (a division costs ~4 cycles of throughput, a product 0.5, and CasADi folds
    #: x * (1 / d) back into x / d in its graph). Each result moves by ~1 ulp (exact for a power of two); a zero or
    #: non-finite denominator still gives a non-finite result (docs/benchmark.md "Design choices")
    reciprocals: bool = False
    #: sin, cos, tan, sqrt as qd_sin, ... (``precision_math.PRECISION_MATH``) and CasADi's double literals in products and
    #: quotients as integers ((2.*x) -> (2*x), (1./x) -> (1/x): the same value in double, no promotion in float)
    precision_math: bool = False
    void_unused: bool = False  # cast the five parameters to void (-Wextra -Werror: some are unused)
    #: states per call, side by side in each input and output (batch evaluation; module docstring)
    lanes: int = 1
    #: the inputs holding parameters, the same for every state (parametric functions; module docstring)
    parameters: tuple[int, ...] = ()


@dataclass(frozen=True)
class Printed:
    """A printed function: its C text and the CasADi helpers it calls, in the order of their first call."""

    text: str
    helpers: tuple[str, ...]


def c_constant(value: float) -> str:
    """``value`` as CasADi's ``CodeGenerator::constant`` prints it: an integral value as ``2.``, ``-1.``, any other
    with 17 significant digits (``9.9999999999999995e-21``)."""
    if math.isnan(value) or math.isinf(value):
        raise ValueError(f"the constant {value} has no C literal here (CasADi prints casadi_nan / casadi_inf)")
    if abs(value) < 2.0**63 and float(int(value)) == value:
        return f"{int(value)}."
    return f"{value:.16e}"


def print_function(f: ca.Function, options: PrintOptions = PrintOptions()) -> Printed:
    """``f`` (an SX Function) as the C function ``options.name`` (module docstring)."""
    if options.lanes < 1:
        raise ValueError(f"lanes {options.lanes}: expected a positive number of states per call")
    if not f.is_a("SXFunction"):
        raise ValueError(f"{f.name()}: the printer prints SX Functions; this is a {f.class_name()}")
    return _Printer(f, options).function()


class _Printer:
    def __init__(self, f: ca.Function, options: PrintOptions) -> None:
        self.f, self.o = f, options
        self.steps = [(f.instruction_id(k), f.instruction_input(k), f.instruction_output(k)) for k in range(f.n_instructions())]
        slots = [s for k, (op, a, r) in enumerate(self.steps) for s in self._slots(op, a, r)]
        self.width = len(str(max(slots))) if slots else 1  # CasADi pads aK to the width of the largest index
        self.declared = sorted(set(slots))
        self.helpers: list[str] = []

    @staticmethod
    def _slots(op: int, a: list[int], r: list[int]) -> list[int]:
        if op == ca.OP_OUTPUT:
            return [a[0]]
        if op in (ca.OP_INPUT, ca.OP_CONST):
            return [r[0]]
        return [r[0], *a]

    def work(self, slot: int) -> str:
        return f"a{slot:0{self.width}d}"

    def entry(self, k: int) -> str:
        """Nonzero ``k`` of an input or output: of this loop's state with lanes."""
        return f"{k * self.o.lanes}+l" if self.o.lanes > 1 else str(k)

    def read(self, i: int, k: int) -> str:
        entry = str(k) if i in self.o.parameters else self.entry(k)  # a parameter: one value for every state
        return f"arg[{i}]? arg[{i}][{entry}] : 0" if self.o.guard_inputs else f"arg[{i}][{entry}]"

    def constant(self, value: float) -> str:
        return c_constant(value)

    def operation(self, op: int, args: list[str]) -> str:
        if op not in _OPERATORS:
            raise ValueError(f"{self.f.name()}: operation {op} has no C form in the printer")
        before, between, after = _OPERATORS[op]
        if op in _HELPERS and _HELPERS[op] not in self.helpers:
            self.helpers.append(_HELPERS[op])
        if self.o.precision_math:
            before = {"(2.*": "(2*", "(1./": "(1/"}.get(before, before)
            if before[:-1] in PRECISION_MATH:
                before = "qd_" + before
            elif before[0].isalpha() and not before.startswith("casadi_"):
                raise ValueError(f"{self.f.name()}: {before[:-1]} has no wrapper in casadi_real's precision")
        return before + between.join(args) + after

    def statements(self) -> tuple[list[str], int]:
        """The body's statements and the number of reciprocals among them."""
        lines: list[str] = []
        written: dict[int, int] = {}  # slot -> the instruction that last wrote it
        constants: set[int] = set()  # the instructions writing a constant
        uses: dict[tuple[int, int], list[int]] = {}  # (denominator slot, its writer) -> the dividing instructions
        for k, (op, a, r) in enumerate(self.steps):
            if op == ca.OP_DIV and a[1] in written:
                uses.setdefault((a[1], written[a[1]]), []).append(k)
            if op == ca.OP_CONST:
                constants.add(k)
            if op != ca.OP_OUTPUT:
                written[r[0]] = k
        shared = {key: q for key, q in uses.items() if len(q) > 1 or key[1] in constants} if self.o.reciprocals else {}
        rcp = {}  # dividing instruction -> its reciprocal's number
        after: dict[int, list[int]] = {}  # writer -> the reciprocals printed after it
        for n, ((_, at), quotients) in enumerate(sorted(shared.items(), key=lambda item: item[0][1])):
            after.setdefault(at, []).append(n)
            rcp.update({k: n for k in quotients})
        for k, (op, a, r) in enumerate(self.steps):
            lines.append(self.statement(k, op, a, r, rcp))
            lines += [f"rcp{n}={self.operation(ca.OP_INV, [self.work(r[0])])};" for n in after.get(k, [])]
        return lines, len(shared)

    def statement(self, k: int, op: int, a: list[int], r: list[int], rcp: dict[int, int]) -> str:
        if op == ca.OP_OUTPUT:
            guard = f"if (res[{r[0]}]!=0) " if self.o.guard_outputs else ""
            return f"{guard}res[{r[0]}][{self.entry(r[1])}]={self.work(a[0])};"
        if op == ca.OP_INPUT:
            return f"{self.work(r[0])}={self.read(a[0], a[1])};"
        if op == ca.OP_CONST:
            return f"{self.work(r[0])}={self.constant(self.f.instruction_constant(k))};"
        if k in rcp:
            return f"{self.work(r[0])}=({self.work(a[0])}*rcp{rcp[k]});"
        return f"{self.work(r[0])}={self.operation(op, [self.work(x) for x in a])};"

    def function(self) -> Printed:
        statements, n_rcp = self.statements()
        lines = [f"static int {self.o.name}{SIGNATURE} {{"]
        if self.o.void_unused:
            lines.append(_UNUSED)
        names = [self.work(s) for s in self.declared]
        lines += ["casadi_real " + ", ".join(names[i:i + _DECLARATIONS_PER_LINE])
                  + ";" for i in range(0, len(names), _DECLARATIONS_PER_LINE)]
        if n_rcp:
            lines.append("casadi_real " + ", ".join(f"rcp{n}" for n in range(n_rcp)) + ";")
        if self.o.lanes > 1:  # one loop over the states, the locals scalars
            statements = [f"for (int l = 0; l < {self.o.lanes}; ++l) {{", *(f"  {x}" for x in statements), "}"]
        lines += [*statements, "return 0;"]
        return Printed("\n".join([lines[0], *(f"  {line}" for line in lines[1:]), "}"]) + "\n", tuple(self.helpers))
