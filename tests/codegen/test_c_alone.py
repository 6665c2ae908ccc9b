"""Every hand-written C file compiles alone: the templates of the generated code include what they use
(codegen/c_alone.py's header, the templates before it), in double and in float; the check and benchmark programs
against casadi_gen's committed header; the rest as they are (docs/embedded.md says how each is built)."""

from __future__ import annotations

import subprocess
from pathlib import Path

import casadi as ca
import pytest

from quadruped_dyn.codegen.c_alone import ALONE_HEADER, alone_header_c
from quadruped_dyn.codegen.c_facts import TEMPLATES

#: The templates pasted into the generated files (emit.py, emit_derivatives.py).
TEMPLATE_FILES = ("qd_sincos.c", "qd_dense.c", "qd_grf_solve.c", "qd_derivatives_solve.c", "qd_reduced_solve.c",
                  "qd_reduced_derivatives.c")
#: -Wno-unused-function: a template's functions are static, called by the generated file it is pasted into
FLAGS = ("-std=c99", "-Wall", "-Wextra", "-Werror", "-Wno-unused-function", "-Wdouble-promotion", "-c")


@pytest.mark.parametrize("real", ["double", "float"])
def test_each_template_compiles_alone(tmp_path, real):
    (tmp_path / ALONE_HEADER).write_text(alone_header_c())
    for name in TEMPLATE_FILES:
        done = subprocess.run(["cc", *FLAGS, f"-Dcasadi_real={real}", "-I", str(tmp_path), str(TEMPLATES / name),
                               "-o", str(tmp_path / "alone.o")], capture_output=True, text=True)
        assert done.returncode == 0, f"{name} ({real}) does not compile alone:\n{done.stderr}"


def test_template_calling_libm_by_name_is_refused(tmp_path, monkeypatch):
    from quadruped_dyn.codegen import precision_math
    (tmp_path / "t.c").write_text("static double f(double x) { return sqrt(x); }\n")
    monkeypatch.setattr(precision_math, "TEMPLATES", tmp_path)
    with pytest.raises(AssertionError, match="sqrt"):
        precision_math.template_c("t.c")


CASADI_GEN = Path(__file__).resolve().parents[2] / "casadi_gen"
PACKAGE = Path(__file__).resolve().parents[2] / "quadruped_dyn"
#: The programs that include a generated header (QD_HEADER) and the check program's reference values (QD_REFERENCE):
#: compiled against casadi_gen's committed ones
CHECK_PROGRAMS = ("codegen/c/check_qd.c", "codegen/c/check_threads.c", "bench/c/bench_qd.c", "bench/c/call_cost.c")
#: The C that includes nothing generated; qdx_native_run.c also in long double (experiment/native_run.py)
STANDALONE = (("codegen/c/cortex_m_startup.c", ()), ("bench/c/bench_cppadcg.c", ()),
              ("experiment/c/qdx_native_run.c", ()), ("experiment/c/qdx_native_run.c", ("-DQDX_LONG_DOUBLE",)))
PROGRAM_FLAGS = ("-std=c99", "-pedantic", "-Wall", "-Wextra", "-Werror", "-c")


def _compiles(tmp_path: Path, source: Path, *flags: str) -> None:
    done = subprocess.run(["cc", *PROGRAM_FLAGS, *flags, str(source), "-o", str(tmp_path / "alone.o")],
                          capture_output=True, text=True)
    assert done.returncode == 0, f"{source.name} {' '.join(flags)} does not compile alone:\n{done.stderr}"


@pytest.mark.parametrize("real", ["double", "float"])
def test_each_check_program_compiles_against_the_committed_header(tmp_path, real):
    for name in CHECK_PROGRAMS:
        _compiles(tmp_path, PACKAGE / name, f"-Dcasadi_real={real}", '-DQD_HEADER="qd_paper.h"',
                  '-DQD_REFERENCE="qd_paper-reference.h"', f"-I{CASADI_GEN}")


def test_each_standalone_c_file_compiles_alone(tmp_path):
    for name, flags in STANDALONE:
        _compiles(tmp_path, PACKAGE / name, *flags)


def test_peers_harness_compiles_with_casadis_header(tmp_path):
    """bench_peers.c with the header CasADi writes for the timed functions and their list (bench/peers.py)."""
    x = ca.SX.sym("x", 2)
    cg = ca.CodeGenerator("qd_peers.c", {"with_header": True})
    cg.add(ca.Function("qd_f", [x], [ca.sin(x)]))
    cg.generate(str(tmp_path) + "/")
    (tmp_path / "qd_peers_list.h").write_text("QD_FN(qd_f)\n")
    _compiles(tmp_path, PACKAGE / "bench/c/bench_peers.c", f"-I{tmp_path}", f"-I{PACKAGE / 'bench/c'}")
