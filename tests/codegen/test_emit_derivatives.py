"""Generated C of the derivatives (qd_<robot>_d.c) against Pinocchio's analytical derivatives,
in double and float, and its return codes on bad input and a singular M."""

from __future__ import annotations

import subprocess

import numpy as np
import pytest

from quadruped_dyn.codegen.emit import TEMPLATES
from quadruped_dyn.codegen.library import C_FLAGS, CompiledFunction, compiled_library
from quadruped_dyn.errors import InputError
from quadruped_dyn.model.state import random_state
from quadruped_dyn.references.pinocchio import PinocchioDerivatives, PinocchioReference
from quadruped_dyn.tolerances import FLOAT_REL_TOL, REL_TOL_DERIVATIVES
from tests.codegen.test_emit import call_ctypes
from tests.conftest import assert_close


def test_compiled_derivatives_match_pinocchio(paper):
    library = compiled_library(paper)
    pd = PinocchioDerivatives(PinocchioReference(paper))
    did, dfd = CompiledFunction(library, "did_full"), CompiledFunction(library, "dfd_full")
    for seed in (0, 1):
        rng = np.random.default_rng(seed)
        s = random_state(paper.lower, paper.upper, rng)
        for name, ours, theirs in zip(("dtau_dq", "dtau_dv", "M"), did(s.q, s.v, s.a), pd.rnea_derivatives(s.q, s.v, s.a)):
            assert_close(ours, theirs, REL_TOL_DERIVATIVES, f"C did_full {name}")
        tau = rng.normal(scale=10.0, size=18)
        for name, ours, theirs in zip(("da_dq", "da_dv", "Minv"), dfd(s.q, s.v, tau), pd.aba_derivatives(s.q, s.v, tau)):
            assert_close(ours, theirs, REL_TOL_DERIVATIVES, f"C dfd_full {name}")


def test_float_derivatives_match_double(paper):
    double = compiled_library(paper, "double")
    single = compiled_library(paper, "float")
    import ctypes

    s = random_state(paper.lower, paper.upper, np.random.default_rng(5))
    tau = 5.0 * s.a
    d = call_ctypes(ctypes.CDLL(str(double.path)), "dfd_full", np.float64, [s.q, s.v, tau], [324] * 3)
    x = call_ctypes(ctypes.CDLL(str(single.path)), "dfd_full", np.float32, [s.q, s.v, tau], [324] * 3)
    cond = np.linalg.cond(PinocchioReference(paper).mass_matrix(s.q))
    for a, b in zip(x, d):  # M^-1 amplifies float's rounding by up to cond(M)
        assert_close(a, b, FLOAT_REL_TOL * max(1.0, cond / 100.0), "float dfd_full")


@pytest.mark.parametrize("bad", ["nan", "zero_quat"])
def test_bad_input_returns_nonfinite(paper, bad):
    dfd = CompiledFunction(compiled_library(paper), "dfd_full")
    s = random_state(paper.lower, paper.upper, np.random.default_rng(0))
    q = s.q.copy()
    if bad == "nan":
        q[9] = np.nan
    else:
        q[3:7] = 0.0
    with pytest.raises(InputError, match="not finite"):
        dfd(q, s.v, s.a)
    with pytest.raises(InputError, match="entries"):
        dfd(q[:18], s.v, s.a)


def test_singular_mass_matrix_returns_singular(tmp_path):
    """The hand-written solve on its own, with a mass matrix that is not positive definite."""
    program = tmp_path / "singular.c"
    program.write_text(f"""#define casadi_real double
#define casadi_int long long int
#include "{TEMPLATES / 'qd_derivatives_solve.c'}"
#include <stdio.h>
static int parts(const casadi_real** arg, casadi_real** res, casadi_int* iw, casadi_real* w, int mem) {{
  (void)arg; (void)iw; (void)w; (void)mem;
  for (int i = 0; i < 324; ++i) res[0][i] = 0;
  for (int i = 0; i < 18; ++i) {{ res[0][i + 18 * i] = i == 7 ? 0.0 : 1.0; res[1][i] = 0; }}
  return 0;
}}
static int did(const casadi_real** arg, casadi_real** res, casadi_int* iw, casadi_real* w, int mem) {{
  (void)arg; (void)res; (void)iw; (void)w; (void)mem; return 0;
}}
int main(void) {{
  casadi_real q[19] = {{0}}, v[18] = {{0}}, tau[18] = {{0}}, out[3][324];
  const casadi_real* arg[3] = {{q, v, tau}};
  casadi_real* res[3] = {{out[0], out[1], out[2]}};
  static const casadi_int sp[2 + 19 + 1] = {{18, 18}};
  printf("%d\\n", qd_dfd_full_solve(parts, did, sp, sp, arg, res, 0, 0, 0));
  return 0;
}}
""")
    exe = tmp_path / "singular"
    subprocess.run(["gcc", *[f for f in C_FLAGS if f != "-fPIC"], str(program), "-lm", "-o", str(exe)], check=True)
    assert subprocess.run([str(exe)], capture_output=True, text=True, check=True).stdout.strip() == "2"
