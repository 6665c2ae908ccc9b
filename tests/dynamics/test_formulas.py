"""Readable symbolic terms: SX -> SymPy is faithful, the DH leg's typeset formulas equal
Pinocchio's quantities, and the sparsity patterns show the structure physics predicts."""

from __future__ import annotations

import casadi as ca
import numpy as np
import pytest
import sympy as sp

from quadruped_dyn.dynamics.formulas import paper_formulas, rounded, sparsity_pattern, to_sympy
from quadruped_dyn.dynamics.newton_euler import full_dynamics
from quadruped_dyn.model.state import full_q
from quadruped_dyn.references.pinocchio import PinocchioReference
from quadruped_dyn.tolerances import FORMULA_DISPLAY_REL_TOL, REL_TOL_TERMS
from tests.conftest import assert_close


def test_to_sympy_replays_every_operation():
    x = ca.SX.sym("x", 3)
    exprs = [ca.sin(x[0]) * ca.cos(x[1]) / (2 + x[2] ** 2), ca.sqrt(1 + x[0] ** 2) - ca.atan2(x[1], x[2]),
             ca.tan(x[0] / 4) + 1 / (3 + x[1]) - ca.fabs(x[2]) + ca.exp(-x[0]) + ca.log(2 + x[1] ** 2), 2 * x[0] - x[1]]
    f = ca.Function("f", [x], [ca.vertcat(*exprs), ca.horzcat(x, 2 * x)])
    symbols = sp.Matrix(sp.symbols("x0:3", real=True))
    vec, mat = to_sympy(f, [symbols])
    rng = np.random.default_rng(0)
    for _ in range(5):
        values = rng.uniform(-1, 1, 3)
        subs = dict(zip(symbols, values))
        expected_vec, expected_mat = (np.array(y) for y in f(values))
        assert_close(np.array(vec.subs(subs), dtype=float), expected_vec, what="vector output")
        assert_close(np.array(mat.subs(subs), dtype=float), expected_mat, what="matrix output")


def test_unsupported_operation_is_named():
    x = ca.SX.sym("x")
    with pytest.raises(ValueError, match="no SymPy translation"):
        to_sympy(ca.Function("f", [x], [ca.floor(x)]), [sp.Matrix([sp.Symbol("x")])])


def test_paper_formulas_equal_pinocchio(paper):
    """Foot position, Jacobian and gravity torques of FL, as typeset (rounded) and at full
    precision, against Pinocchio's frame placement, getFrameJacobian, computeGeneralizedGravity."""
    ref = PinocchioReference(paper)
    formulas = paper_formulas(paper)
    references = [lambda q: ref.foot_positions(q)[0], lambda q: ref.foot_jacobians(q)[0], lambda q: ref.gravity(q)[6:9]]
    rng = np.random.default_rng(3)
    for _ in range(10):
        qj = rng.uniform(paper.lower, paper.upper)
        q = full_q(np.eye(3), np.zeros(3), qj)
        for formula, reference in zip(formulas, references):
            expected = np.asarray(reference(q))
            assert_close(formula.evaluate(qj[:3]).reshape(expected.shape), expected, what=formula.title)
            shown = sp.lambdify(formula.variables, rounded(formula.expr), "numpy")(*qj[:3])
            assert_close(np.array(shown, dtype=float).reshape(expected.shape), expected, rel=FORMULA_DISPLAY_REL_TOL,
                         what=f"{formula.title}, as shown")
    assert all("<math" in f.mathml and "\\theta" in f.latex for f in formulas)
    assert REL_TOL_TERMS < FORMULA_DISPLAY_REL_TOL


def test_mass_matrix_pattern_decouples_legs(robot):
    """In full coordinates each leg couples only to itself and the trunk: the leg-leg blocks
    of M are structurally zero, on every robot."""
    pattern = sparsity_pattern(full_dynamics(robot).M_full_crba)
    assert pattern.shape == (18, 18)
    for i in range(4):
        for j in range(4):
            block = pattern[6 + 3 * i : 9 + 3 * i, 6 + 3 * j : 9 + 3 * j]
            assert block.any() == (i == j), f"legs {i}, {j}"
