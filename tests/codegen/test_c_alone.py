"""Every hand-written C file of the generated code compiles alone: it includes what it uses (codegen/c_alone.py's
header, the templates before it), in double and in float."""

from __future__ import annotations

import subprocess

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
