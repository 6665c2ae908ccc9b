"""``codegen.c_file``: with CasADi's options the file and header it prints are CasADi's ``CodeGenerator`` output for
the same Functions, byte for byte (reading CasADi's text is the reference here; nothing edits it), and each entry's
options change only what they name."""

from __future__ import annotations

import os
import tempfile
from pathlib import Path

import casadi as ca
import pytest

from quadruped_dyn.codegen.c_file import Entry, FileOptions, c_file
from quadruped_dyn.codegen.emit import codegen_functions, reduced_functions
from quadruped_dyn.codegen.emit_derivatives import derivative_functions
from quadruped_dyn.codegen.file_names import REDUCED_STANCE_SETS
from quadruped_dyn.model.robot import load_robot

CASADI = FileOptions(project=False)


def casadi_file(stem: str, functions: list[ca.Function]) -> tuple[str, str]:
    """(C source, header) CasADi's CodeGenerator writes for ``functions`` in ``stem``.c."""
    cg = ca.CodeGenerator(f"{stem}.c", {"with_header": True, "casadi_real": "double"})
    for f in functions:
        cg.add(f)
    with tempfile.TemporaryDirectory() as tmp:
        cg.generate(tmp + os.sep)
        return (Path(tmp) / f"{stem}.c").read_text(), (Path(tmp) / f"{stem}.h").read_text()


def _small() -> list[ca.Function]:
    x, y = ca.SX.sym("x", 3), ca.SX.sym("y", 2)
    f = ca.Function("f", [x, y], [ca.vertcat(2 * ca.sin(x[0]) / x[1], ca.fabs(x[2]), -1.0),
                                   ca.SX(ca.Sparsity.lower(2)) + x[0]], ["x", "y"], ["u", "v"], {"cse": True})
    g = ca.Function("g", [x], [x**2, ca.SX(ca.Sparsity.lower(3)) * x[1]])  # a sparse output, another helper first
    return [f, g]


def test_small_file_prints_as_casadi():
    assert c_file("small", [Entry(f) for f in _small()], CASADI) == casadi_file("small", _small())


def test_entries_change_only_what_they_name():
    f, g = _small()
    plain, _ = c_file("small", [Entry(f), Entry(g)], CASADI)
    text, header = c_file("small", [Entry(f, evaluation=None, body="  return qd_template(arg, res);\n", sz_w=7),
                                    Entry(g)], FileOptions(project=True, preamble="/* the templates */\n"))
    assert "static int casadi_f0(" in plain and "static int casadi_f0(" not in text and "casadi_f0" not in text
    assert "  return qd_template(arg, res);\n" in text and "  if (sz_w) *sz_w = 7;\n" in text
    assert "#define f_SZ_W 7\n" in header and "\nstatic inline casadi_real casadi_sq(" in text
    assert "/* the templates */\nCASADI_SYMBOL_EXPORT int f(" in text and "void f_release(int mem) {\n  (void)mem;\n}" in text


def _files(name: str) -> list[tuple[str, list[ca.Function]]]:
    robot = load_robot(name)
    return [("d", derivative_functions(robot)), ("full", codegen_functions(robot)),
            *((f"r{k}", reduced_functions(robot, stance)) for k, stance in enumerate(REDUCED_STANCE_SETS))]


@pytest.mark.slow
@pytest.mark.parametrize("name", ["paper", "go2"])
def test_every_generated_file_prints_as_casadi(name):
    for stem, functions in _files(name):
        assert c_file(stem, [Entry(f) for f in functions], CASADI) == casadi_file(stem, functions), stem
