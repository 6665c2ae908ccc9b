"""Symbolic terms a person can read: CasADi SX -> SymPy, simplified and typeset (MathML / LaTeX),
and the size and structure of every term (operation counts, sparsity patterns).

``to_sympy`` replays a CasADi SX Function's instruction list in SymPy: each constant becomes
a rational (the shortest decimal that reads back as the same double: 0.2 stays 1/5), each
input entry a given symbol. Simplification runs on 17-digit coefficients; display rounds them
to ``DISPLAY_DIGITS``.

``paper_formulas`` (the DH robot's front-left leg; trunk frame b, x forward, y left, z up, m;
joint angles theta_1..3 = HAA, HFE, KFE, rad; trunk level, R = I): foot position r(theta),
its Jacobian J = dr/dtheta, and the leg's gravity torques G (N m), the joint rows of G_full.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import casadi as ca
import numpy as np
import sympy as sp

from quadruped_dyn.dynamics.grf import grf_solve
from quadruped_dyn.dynamics.kinematics import robot_kinematics
from quadruped_dyn.dynamics.newton_euler import full_dynamics
from quadruped_dyn.dynamics.reduced import reduced_model
from quadruped_dyn.model.robot import Robot

#: Significant digits of the coefficients shown in typeset formulas (checks use the 17-digit ones).
DISPLAY_DIGITS = 4

_UNARY: dict[int, Callable[[sp.Expr], sp.Expr]] = {
    ca.OP_ASSIGN: lambda x: x,
    ca.OP_NEG: lambda x: -x,
    ca.OP_SQ: lambda x: x**2,
    ca.OP_TWICE: lambda x: 2 * x,
    ca.OP_INV: lambda x: 1 / x,
    ca.OP_SQRT: sp.sqrt,
    ca.OP_SIN: sp.sin,
    ca.OP_COS: sp.cos,
    ca.OP_TAN: sp.tan,
    ca.OP_ASIN: sp.asin,
    ca.OP_ACOS: sp.acos,
    ca.OP_ATAN: sp.atan,
    ca.OP_EXP: sp.exp,
    ca.OP_LOG: sp.log,
    ca.OP_FABS: sp.Abs,
    ca.OP_SIGN: sp.sign,
}
_BINARY: dict[int, Callable[[sp.Expr, sp.Expr], sp.Expr]] = {
    ca.OP_ADD: lambda x, y: x + y,
    ca.OP_SUB: lambda x, y: x - y,
    ca.OP_MUL: lambda x, y: x * y,
    ca.OP_DIV: lambda x, y: x / y,
    ca.OP_POW: lambda x, y: x**y,
    ca.OP_CONSTPOW: lambda x, y: x**y,
    ca.OP_ATAN2: sp.atan2,
    ca.OP_HYPOT: lambda x, y: sp.sqrt(x**2 + y**2),
}


def to_sympy(f: ca.Function, inputs: list[sp.Matrix]) -> list[sp.Matrix]:
    """The outputs of SX Function ``f`` as SymPy matrices, for dense symbolic ``inputs``
    (one column matrix per input, in ``f``'s input order)."""
    outputs = [sp.zeros(f.size1_out(i), f.size2_out(i)) for i in range(f.n_out())]
    work: dict[int, sp.Expr] = {}
    for k in range(f.n_instructions()):
        op, ins, outs = f.instruction_id(k), f.instruction_input(k), f.instruction_output(k)
        if op == ca.OP_CONST:
            work[outs[0]] = sp.Rational(repr(f.instruction_constant(k)))
        elif op == ca.OP_INPUT:
            work[outs[0]] = inputs[ins[0]][ins[1]]
        elif op == ca.OP_OUTPUT:
            rows, cols = f.sparsity_out(outs[0]).get_triplet()
            outputs[outs[0]][rows[outs[1]], cols[outs[1]]] = work[ins[0]]
        elif op in _UNARY:
            work[outs[0]] = _UNARY[op](work[ins[0]])
        elif op in _BINARY:
            work[outs[0]] = _BINARY[op](work[ins[0]], work[ins[1]])
        else:
            raise ValueError(f"{f.name()}: CasADi operation {op} has no SymPy translation here")
    return outputs


def rounded(expr: sp.Basic, digits: int = DISPLAY_DIGITS) -> sp.Basic:
    """``expr`` with every number shown to ``digits`` significant digits (integers kept)."""
    numbers = {n: sp.Float(n, digits) for n in expr.atoms(sp.Number) if not n.is_Integer}
    return expr.xreplace(numbers)


@dataclass(frozen=True)
class Formula:
    """A typeset term: ``expr`` (simplified, coefficients to double precision) for checks,
    ``latex`` and ``mathml`` (coefficients rounded to DISPLAY_DIGITS) for reading."""

    title: str
    symbol: str  # left-hand side, SymPy's naming (G_FL is G with subscript FL)
    expr: sp.Matrix
    variables: tuple[sp.Symbol, ...]

    @property
    def latex(self) -> str:
        return f"{sp.latex(sp.Symbol(self.symbol))} = {sp.latex(rounded(self.expr))}"

    @property
    def mathml(self) -> str:
        """Presentation MathML (MathML Core: browsers render it without scripts)."""
        lhs = sp.mathml(sp.Symbol(self.symbol), printer="presentation")
        rhs = sp.mathml(rounded(self.expr), printer="presentation")
        return f'<math display="block"><mrow>{lhs}<mo>=</mo>{rhs}</mrow></math>'

    def evaluate(self, values: np.ndarray) -> np.ndarray:
        """The formula (double-precision coefficients) at numeric values of ``variables``."""
        return np.array(sp.lambdify(self.variables, self.expr, "numpy")(*values), dtype=float)


def _simplified(m: sp.Matrix) -> sp.Matrix:
    """trigsimp with double-precision coefficients (exact rationals make it factor out
    their common divisor, 2e-16 (8338500000000001 cos ...), which nobody can read)."""
    def shortest(e: sp.Expr) -> sp.Expr:
        e = rounded(e, 17)
        return min((sp.trigsimp(e), sp.fu(e)), key=sp.count_ops)

    return m.applyfunc(shortest)


def paper_formulas(robot: Robot) -> list[Formula]:
    """Foot position, foot Jacobian and gravity torques of the front-left leg (see module doc)."""
    theta = sp.Matrix(sp.symbols("theta_1:4", real=True))
    kin = robot_kinematics(robot)[0]
    (r,) = to_sympy(kin.foot_position, [theta])
    (J,) = to_sympy(kin.foot_jacobian, [theta])
    th = ca.SX.sym("theta", 3)
    level = ca.vertcat(ca.SX.zeros(6), 1, th, ca.SX.zeros(9))  # p = 0, quaternion (0, 0, 0, 1): R = I
    g_leg = ca.Function("G_FL", [th], [full_dynamics(robot).G_full_newton_euler(level)[6:9]])
    (G,) = to_sympy(g_leg, [theta])
    variables = tuple(theta)
    return [
        Formula("foot position of FL, trunk frame (m)", "r_FL", _simplified(r), variables),
        Formula("foot Jacobian of FL, dr/dθ (m/rad)", "J_FL", _simplified(J), variables),
        Formula("gravity torques of FL's HAA, HFE, KFE, trunk level (N m)", "G_FL", _simplified(G), variables),
    ]


@dataclass(frozen=True)
class TermSize:
    name: str
    instructions: int  # CasADi algorithm length after common-subexpression elimination
    inputs: str  # e.g. "q[19], v[18]"
    outputs: str
    pattern: np.ndarray  # bool: the first output's sparsity (matrix) or its Jacobian's w.r.t. all inputs (vector)


def sparsity_pattern(f: ca.Function) -> np.ndarray:
    """The first output's structural nonzeros (a matrix), or those of its Jacobian w.r.t. all
    inputs side by side (a vector)."""
    if f.size2_out(0) > 1:
        sp_out = f.sparsity_out(0)
    else:
        return np.hstack([np.array(ca.DM(f.jac_sparsity(0, i), 1)) for i in range(f.n_in())]).astype(bool)
    return np.array(ca.DM(sp_out, 1)).astype(bool)


def term_functions(robot: Robot) -> dict[str, ca.Function]:
    """The terms whose size and structure the report shows: full coordinates, one GRF solve
    per stance kind (paper model), and the reduced model of standing, a walk triple, a trot pair."""
    fd = full_dynamics(robot)
    terms = {name: getattr(fd, name) for name in ("M_full_walker_orin", "M_full_ad", "M_full_crba", "C_full",
                                                   "G_full_newton_euler", "nle_full", "coriolis", "id_full")}
    terms["foot Jacobian (FL)"] = robot_kinematics(robot)[0].foot_jacobian
    for stance in ("FL+FR+BL+BR", "FR+BL+BR", "FL+BR"):
        terms[f"grf {stance}"] = grf_solve(robot, stance).function
    for stance in ("FL+FR+BL+BR", "FR+BL+BR", "FL+BR"):
        m = reduced_model(robot, stance)
        for name in ("id_r", "M_r", "C_r", "G_r", "fd_r"):
            terms[f"{name} {stance}"] = getattr(m, name)
    return terms


def term_sizes(robot: Robot) -> list[TermSize]:
    return [TermSize(name, f.n_instructions(), shapes(f), shapes(f, outputs=True), sparsity_pattern(f))
            for name, f in term_functions(robot).items()]


def shapes(f: ca.Function, outputs: bool = False) -> str:
    """Names and shapes of a Function's inputs (or outputs), e.g. 'q[19], v[18]' or 'M[18x18]'."""
    n, name, sparsity = (f.n_out(), f.name_out, f.sparsity_out) if outputs else (f.n_in(), f.name_in, f.sparsity_in)
    return ", ".join(f"{name(i)}[{sparsity(i).size1()}" + (f"x{sparsity(i).size2()}" if sparsity(i).size2() > 1 else "")
                     + "]" for i in range(n))
