"""``codegen.printer``: with no options it prints every generated function's evaluation byte for byte as CasADi's
``CodeGenerator`` does (the printer is faithful; reading CasADi's text here is the reference, nothing edits it), and
each option changes only what it names. The options' values in the shipped C are checked by ``codegen --check``
(casadi_gen byte-identical) and test_emit's compiled comparisons."""

from __future__ import annotations

import ctypes
import os
import re
import tempfile
from pathlib import Path

import casadi as ca
import numpy as np
import pytest

from quadruped_dyn.codegen.emit import codegen_functions, reduced_functions
from quadruped_dyn.codegen.emit_derivatives import derivative_functions
from quadruped_dyn.codegen.file_names import REDUCED_STANCE_SETS
from quadruped_dyn.codegen.library import C_FLAGS, run_tool
from quadruped_dyn.codegen.printer import PrintOptions, c_constant, print_function
from quadruped_dyn.model.robot import load_robot


def casadi_evaluation(f: ca.Function) -> str:
    """CasADi's static evaluation function of ``f`` (casadi_f0), as its CodeGenerator writes it."""
    cg = ca.CodeGenerator("f.c")
    cg.add(f)
    with tempfile.TemporaryDirectory() as tmp:
        cg.generate(tmp + os.sep)
        text = (Path(tmp) / "f.c").read_text()
    found = re.search(r"static int casadi_f0\(.*?\n\}\n", text, re.S)
    assert found, f"{f.name()}: no evaluation function in CasADi's output"
    return found.group(0)


def _small() -> ca.Function:
    x, y = ca.SX.sym("x", 3), ca.SX.sym("y", 2)
    out = ca.vertcat(2 * ca.sin(x[0]) / x[1], x[2] / x[1] + 1e-20, -1.0, ca.fabs(x[0]) / 3, 1 / y[0], ca.cos(y[1]) ** 2)
    return ca.Function("f", [x, y], [out, ca.SX(ca.Sparsity.lower(2)) + x[0]], {"cse": True})


def test_constants_print_as_casadi():
    assert [c_constant(v) for v in (2.0, -1.0, 0.0, -0.0, 1e-20, 1 / 3)] == [
        "2.", "-1.", "0.", "0.", "9.9999999999999995e-21", "3.3333333333333331e-01"]


def test_small_function_prints_as_casadi():
    assert print_function(_small()).text == casadi_evaluation(_small())


def test_options_change_only_what_they_name():
    f = _small()
    plain = print_function(f).text
    text = print_function(f, PrintOptions(name="qd_x", guard_inputs=False, guard_outputs=False, reciprocals=True,
                                          precision_math=True, void_unused=True)).text
    assert text.startswith("static int qd_x(") and "  (void)arg; (void)res; (void)iw; (void)w; (void)mem;\n" in text
    assert "?" not in text and "!=0" not in text and "qd_sin(" in text and "qd_cos(" in text and "(2*" in text
    assert "  casadi_real rcp0, rcp1;\n" in text  # x[1] divides twice, 3 is a constant; 1 / y[0] is an inverse
    assert text.count("*rcp0)") == 2 and text.count("*rcp1)") == 1 and "(1/a" in text
    assert len(text.splitlines()) == len(plain.splitlines()) + 1 + 1 + 2  # the casts, the declaration, two reciprocals
    x = ca.SX.sym("x")
    with pytest.raises(ValueError, match="exp has no wrapper"):  # a function without a precision wrapper
        print_function(ca.Function("e", [x], [ca.exp(x)]), PrintOptions(precision_math=True))


_LANES = 4
#: the reciprocals' products against CasADi's quotients: x * fl(1/d) against fl(x / d), two roundings for one, twice
RECIPROCAL_REL_TOL = 4 * np.finfo(float).eps
_HOST = """#include <math.h>
#define casadi_real double
#define casadi_int long long int
static casadi_real casadi_sq(casadi_real x) { return x*x; }
static casadi_real casadi_fabs(casadi_real x) { return fabs(x); }
"""


@pytest.mark.parametrize("parameters", [(), (1,)], ids=["states", "shared-y"])
def test_lanes_evaluate_states_side_by_side_as_one_call_each(tmp_path, parameters):
    """With lanes the compiled function gives each state's outputs bit for bit as one call per state of the function
    printed without (the same operations in the same order), which agrees with CasADi's evaluation; an input named
    in ``parameters`` is one value every state reads."""
    f = _small()
    one = print_function(f, PrintOptions(name="one", reciprocals=True)).text
    many = print_function(f, PrintOptions(name="many", reciprocals=True, lanes=_LANES, parameters=parameters)).text
    exported = "".join(f"int {n}_call(const double** arg, double** res) {{ return {n}(arg, res, 0, 0, 0); }}\n"
                       for n in ("one", "many"))
    (tmp_path / "lanes.c").write_text(_HOST + one + many + exported)
    run_tool(["gcc", *C_FLAGS, "-Wno-unused-parameter", "-shared", str(tmp_path / "lanes.c"), "-o", str(tmp_path / "lanes.so")])
    lib = ctypes.CDLL(str(tmp_path / "lanes.so"))
    rng = np.random.default_rng(3)
    x, y = rng.uniform(0.5, 2.0, (_LANES, 3)), rng.uniform(0.5, 2.0, (_LANES, 2))
    if parameters:
        y[:] = y[0]  # every state's y is the parameters' one value
    sizes = [f.nnz_out(i) for i in range(f.n_out())]

    def call(name: str, inputs: list[np.ndarray], lanes: int) -> list[np.ndarray]:
        outs = [np.zeros(n * lanes) for n in sizes]
        args = [np.ascontiguousarray(v, dtype=float) for v in inputs]
        arg = (ctypes.c_void_p * 2)(*(a.ctypes.data for a in args))
        res = (ctypes.c_void_p * 2)(*(o.ctypes.data for o in outs))
        assert getattr(lib, f"{name}_call")(arg, res) == 0
        return outs

    batch = call("many", [x.T.ravel(), y[0] if parameters else y.T.ravel()], _LANES)  # nonzero k of state l at k L + l
    for l in range(_LANES):
        single = call("one", [x[l], y[l]], 1)
        for out, got, want in zip(single, batch, f(x[l], y[l]), strict=True):
            assert np.all(np.isfinite(got)) and np.array_equal(got.reshape(-1, _LANES)[:, l], out)
            assert np.allclose(out, np.asarray(ca.DM(want).nonzeros()), rtol=RECIPROCAL_REL_TOL, atol=0.0)


def _functions(name: str, everything: bool) -> list[ca.Function]:
    robot = load_robot(name)
    functions = codegen_functions(robot) + derivative_functions(robot)
    stances = REDUCED_STANCE_SETS if everything else REDUCED_STANCE_SETS[:1]
    return functions + [f for stance in stances for f in reduced_functions(robot, stance)]


def test_every_generated_function_of_the_paper_robot_prints_as_casadi():
    for f in _functions("paper", everything=False):
        assert print_function(f).text == casadi_evaluation(f), f.name()


@pytest.mark.slow
@pytest.mark.parametrize("name", ["paper", "go2"])
def test_every_generated_function_prints_as_casadi(name):
    for f in _functions(name, everything=True):
        assert print_function(f).text == casadi_evaluation(f), f.name()
