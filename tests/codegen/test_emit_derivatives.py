"""Generated C of the derivatives against Pinocchio's analytical derivatives (did_full, dfd_full) and
central differences of the Pinocchio-built references (dfd_r, dgrf), in double and float, and the
return codes on bad input and a singular M."""

from __future__ import annotations

import subprocess

import casadi as ca
import numpy as np
import pytest

from quadruped_dyn.checks.finite_differences import ReducedFiniteDifferences, grf_derivatives_by_differences
from quadruped_dyn.codegen.c_alone import ALONE_HEADER, alone_header_c
from quadruped_dyn.codegen.c_facts import DERIVATIVE_SZ_W
from quadruped_dyn.codegen.emit import REDUCED_STANCE_SETS, TEMPLATES, reduced_symbol
from quadruped_dyn.codegen.emit_derivatives import (
    GRF_DERIVATIVE_STANCE_SETS,
    derivative_functions,
    derivative_source,
    dfd_r_lift,
    dfd_r_pieces,
    lift_seeds,
)
from quadruped_dyn.codegen.forms.did_full_pieces import did_full_pieces
from quadruped_dyn.codegen.joint_trig import trig_as_inputs
from quadruped_dyn.codegen.library import C_FLAGS, CompiledFunction, compiled_library
from quadruped_dyn.codegen.print_settings import PREFIX
from quadruped_dyn.dynamics.derivatives import full_derivatives
from quadruped_dyn.errors import InputError
from quadruped_dyn.math.compare import relative_error
from quadruped_dyn.model.registry import ROBOT_NAMES
from quadruped_dyn.model.robot import load_robot
from quadruped_dyn.model.stance import stance_set
from quadruped_dyn.model.state import random_state
from quadruped_dyn.references.pinocchio import PinocchioDerivatives, PinocchioReference
from quadruped_dyn.tolerances import FLOAT_REL_TOL, LIFT_COLUMNS_REL_TOL, REL_TOL_DERIVATIVES, REL_TOL_FD_DERIVATIVES
from tests.codegen.forms.test_leg_template import turned_robot
from tests.conftest import assert_close
from tests.dynamics.test_derivatives import grf_point, reduced_point


def _check_compiled_full(robot, library) -> None:
    """The C did_full and dfd_full against Pinocchio's analytical derivatives at two random states."""
    pd = PinocchioDerivatives(PinocchioReference(robot))
    did, dfd = CompiledFunction(library, "did_full"), CompiledFunction(library, "dfd_full")
    for seed in (0, 1):
        rng = np.random.default_rng(seed)
        s = random_state(robot.lower, robot.upper, rng)
        for name, ours, theirs in zip(("dtau_dq", "dtau_dv", "M"), did(s.q, s.v, s.a), pd.rnea_derivatives(s.q, s.v, s.a)):
            assert_close(ours, theirs, REL_TOL_DERIVATIVES, f"{robot.name} C did_full {name}")
        tau = rng.normal(scale=10.0, size=18)
        for name, ours, theirs in zip(("da_dq", "da_dv", "Minv"), dfd(s.q, s.v, tau), pd.aba_derivatives(s.q, s.v, tau)):
            assert_close(ours, theirs, REL_TOL_DERIVATIVES, f"{robot.name} C dfd_full {name}")


def test_compiled_derivatives_match_pinocchio(paper):
    _check_compiled_full(paper, compiled_library(paper))


def test_float_derivatives_match_double(paper):
    s = random_state(paper.lower, paper.upper, np.random.default_rng(5))
    tau = 5.0 * s.a
    d = CompiledFunction(compiled_library(paper, "double"), "dfd_full")(s.q, s.v, tau)
    x = CompiledFunction(compiled_library(paper, "float"), "dfd_full")(s.q, s.v, tau)
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
    with pytest.raises(InputError, match="not finite"):  # the C's QD_NONFINITE (raw: __call__ refuses it first)
        dfd.raw(q, s.v, s.a)
    with pytest.raises(InputError, match="NaN" if bad == "nan" else "zero quaternion"):
        dfd(q, s.v, s.a)
    with pytest.raises(InputError, match="shape"):
        dfd(q[:18], s.v, s.a)


@pytest.mark.parametrize("zero", [2, 7])
def test_singular_mass_matrix_returns_singular(tmp_path, zero):
    """The hand-written solve on its own, with a mass matrix that is not positive definite: a zero pivot in
    the trunk's block (2) or in a leg's (7: the legs are factorised first)."""
    program = tmp_path / "singular.c"
    (tmp_path / ALONE_HEADER).write_text(alone_header_c())  # what the template includes alone: prelude, qd_dense.c
    program.write_text(f"""#define casadi_real double
#define casadi_int long long int
#include "{TEMPLATES / 'qd_derivatives_solve.c'}"
#include <stdio.h>
static casadi_int sp_M[2 + 19 + 324] = {{18, 18}}; /* M dense, as a compressed-column pattern (filled in main) */
const casadi_int* qd_M_full_sparsity_out(casadi_int i) {{ (void)i; return sp_M; }}
int qd_M_full(const casadi_real** arg, casadi_real** res, casadi_int* iw, casadi_real* w, int mem) {{
  (void)arg; (void)iw; (void)w; (void)mem;
  for (int i = 0; i < 324; ++i) res[0][i] = 0;
  for (int i = 0; i < 18; ++i) res[0][i + 18 * i] = i == {zero} ? 0.0 : 1.0;
  return 0;
}}
int qd_nle_full(const casadi_real** arg, casadi_real** res, casadi_int* iw, casadi_real* w, int mem) {{
  (void)arg; (void)iw; (void)w; (void)mem;
  for (int i = 0; i < 18; ++i) res[0][i] = 0;
  return 0;
}}
static int did(const casadi_real** arg, casadi_real** res, casadi_int* iw, casadi_real* w, int mem) {{
  (void)arg; (void)res; (void)iw; (void)w; (void)mem; return 0;
}}
int main(void) {{
  static casadi_real w[QD_DFD_FULL_SZ_W];
  casadi_real q[19] = {{0}}, v[18] = {{0}}, tau[18] = {{0}}, out[3][324];
  const casadi_real* arg[3] = {{q, v, tau}};
  casadi_real* res[3] = {{out[0], out[1], out[2]}};
  static const casadi_int sp[2 + 19 + 1] = {{18, 18}};
  for (int j = 0; j <= 18; ++j) sp_M[2 + j] = 18 * j;
  for (int k = 0; k < 324; ++k) sp_M[2 + 19 + k] = k % 18;
  (void)qd_dgrf_solve; (void)qd_dfd_full_parts_eval; /* not exercised here */
  printf("%d\\n", qd_dfd_full_solve(did, sp, sp, arg, res, 0, w, 0));
  return 0;
}}
""")
    exe = tmp_path / "singular"
    subprocess.run(["gcc", *[f for f in C_FLAGS if f != "-fPIC"], "-I", str(tmp_path), str(program), "-lm", "-o", str(exe)],
                   check=True)
    assert subprocess.run([str(exe)], capture_output=True, text=True, check=True).stdout.strip() == "2"


def test_the_derivative_templates_temporaries_end_at_their_stated_work_size(tmp_path):
    """c_facts.DERIVATIVE_SZ_W (QD_<name>_SZ_W, the functions' _SZ_W) against the template's own pointer arithmetic:
    the w it passes on to qd_M_full (the first real past its temporaries) is w + QD_<name>_SZ_W."""
    (tmp_path / ALONE_HEADER).write_text(alone_header_c())
    program = tmp_path / "work_end.c"
    program.write_text(f"""#define casadi_real double
#define casadi_int long long int
#include "{TEMPLATES / 'qd_derivatives_solve.c'}"
#include <stdio.h>
static casadi_real* seen;
const casadi_int* qd_M_full_sparsity_out(casadi_int i) {{ (void)i; return 0; }}
int qd_M_full(const casadi_real** arg, casadi_real** res, casadi_int* iw, casadi_real* w, int mem) {{
  (void)arg; (void)res; (void)iw; (void)mem; seen = w; return 9;
}}
int qd_nle_full(const casadi_real** arg, casadi_real** res, casadi_int* iw, casadi_real* w, int mem) {{
  (void)arg; (void)res; (void)iw; (void)w; (void)mem; return 9;
}}
static int did(const casadi_real** arg, casadi_real** res, casadi_int* iw, casadi_real* w, int mem) {{
  (void)arg; (void)res; (void)iw; (void)w; (void)mem; return 0;
}}
int main(void) {{
  static casadi_real w[4096];
  (void)qd_dfd_full_parts_eval;
  qd_dfd_full_solve(did, 0, 0, 0, 0, 0, w, 0);
  printf("%ld %d ", (long)(seen - w), QD_DFD_FULL_SZ_W);
  qd_dgrf_solve(6, 15, did, did, 0, 0, 0, 0, 0, w, 0);
  printf("%ld %d\\n", (long)(seen - w), QD_DGRF_SZ_W);
  return 0;
}}
""")
    exe = tmp_path / "work_end"
    subprocess.run(["gcc", *[f for f in C_FLAGS if f != "-fPIC"], "-I", str(tmp_path), str(program), "-lm", "-o", str(exe)],
                   check=True)
    used_dfd, stated_dfd, used_dgrf, stated_dgrf = map(int, subprocess.run([str(exe)], capture_output=True, text=True,
                                                                           check=True).stdout.split())
    assert (stated_dfd, stated_dgrf) == (DERIVATIVE_SZ_W["DFD_FULL"][0], DERIVATIVE_SZ_W["DGRF"][0])
    assert (used_dfd, used_dgrf) == (stated_dfd, stated_dgrf)


# ----------------------------------------------------------------------------- reduced model and GRF solve


def _check_compiled_reduced(robot, library, stance_name, seed=0) -> float:
    """The C dfd_r_<feet> against central differences of the Pinocchio-built reduced forward dynamics;
    the largest relative error over its four outputs."""
    stance = stance_set(stance_name)
    n = 13 if len(stance.feet) == 2 else 12
    q_r, qd, tau, quat = reduced_point(robot, n, np.random.default_rng(seed))
    ours = CompiledFunction(library, reduced_symbol("dfd_r", stance))(q_r, qd, tau, quat)
    expected = ReducedFiniteDifferences(PinocchioReference(robot), stance).dfd_r(q_r, qd, tau, quat)
    assert np.all(np.asarray(ours[0])[:, 12:] == 0.0)  # the roll is read from quat
    for name, o, e in zip(("dqdd_dq", "dqdd_dqd", "dqdd_dtau", "dqdd_dtheta"), ours, expected):
        assert_close(o, e, REL_TOL_FD_DERIVATIVES, f"{robot.name} C dfd_r_{stance_name} {name}")
    return max(relative_error(np.asarray(o), e) for o, e in zip(ours, expected))


def _check_compiled_grf(robot, library, stance_name, seed=0) -> float:
    """The C dgrf_<feet> against central differences of Pinocchio's GRF solve (q along integrate)."""
    stance = stance_set(stance_name)
    q, v, a = grf_point(robot, np.random.default_rng(seed))
    ours = CompiledFunction(library, f"dgrf_{stance_name.replace('+', '_')}")(q, v, a)
    expected = grf_derivatives_by_differences(PinocchioReference(robot), stance, q, v, a)
    for name, o, e in zip(("dlambda_dq", "dlambda_dv", "dlambda_da"), ours, expected):
        assert_close(o, e, REL_TOL_FD_DERIVATIVES, f"{robot.name} C dgrf_{stance_name} {name}")
    return max(relative_error(np.asarray(o), e) for o, e in zip(ours, expected))


@pytest.mark.parametrize("stance", ["FR+BL+BR", "FL+BR"])
def test_compiled_reduced_derivatives_match_reference_differences(paper, stance):
    _check_compiled_reduced(paper, compiled_library(paper), stance)


@pytest.mark.parametrize("stance", ["FL+FR+BL+BR", "FR+BL+BR", "FL+BR", "FL"])
def test_compiled_grf_derivatives_match_reference_differences(paper, stance):
    _check_compiled_grf(paper, compiled_library(paper), stance)


def _every_stance_set(robot) -> dict[str, float]:
    library = compiled_library(robot)
    _check_compiled_full(robot, library)
    worst = {st.name: _check_compiled_reduced(robot, library, st.name) for st in REDUCED_STANCE_SETS}
    worst.update({f"grf {st.name}": _check_compiled_grf(robot, library, st.name) for st in GRF_DERIVATIVE_STANCE_SETS})
    print(f"{robot.name}: dfd_r max rel err {max(v for k, v in worst.items() if not k.startswith('grf')):.1e}, "
          f"dgrf {max(v for k, v in worst.items() if k.startswith('grf')):.1e}")
    return worst


@pytest.mark.slow
@pytest.mark.parametrize("name", ROBOT_NAMES)
def test_compiled_reduced_and_grf_derivatives_every_robot(name):
    """did_full, dfd_full, every reduced stance set's dfd_r and every GRF stance set's dgrf, compiled, on every
    built-in robot."""
    _every_stance_set(load_robot(name))


@pytest.mark.slow
def test_compiled_reduced_and_grf_derivatives_b1_by_path(erd):
    _every_stance_set(load_robot(str(erd / "b1_description/urdf/b1.urdf")))


def test_compiled_reduced_derivatives_bad_input(paper):
    """A NaN input or a zero quaternion: QD_NONFINITE from the C (raw), an InputError, refused by __call__
    before the C; a wrong length: InputError first."""
    stance = stance_set("FL+BR")
    dfd = CompiledFunction(compiled_library(paper), reduced_symbol("dfd_r", stance))
    q_r, qd, tau, quat = reduced_point(paper, 13, np.random.default_rng(0))
    for args, refused in (((q_r, np.full(13, np.nan), tau, quat), "NaN"), ((q_r, qd, tau, np.zeros(4)), "zero quaternion")):
        with pytest.raises(InputError, match="not finite"):
            dfd.raw(*args)
        with pytest.raises(InputError, match=refused):
            dfd(*args)
    with pytest.raises(InputError, match="shape"):
        dfd(q_r[:12], qd, tau, quat)


def test_split_at_seeds_gives_the_lift_to_the_digit(paper):
    """dfd_r's lift split at its seeds (its primal once, the derivative over the tape) evaluates the same operations
    as the lift in one piece: equal outputs, bit for bit, at a random point and direction (FL+BR, FL+FR+BL)."""
    rng = np.random.default_rng(3)
    for name in ("FL+BR", "FL+FR+BL"):
        st = stance_set(name)
        n = 13 if len(st.feet) == 2 else 12
        q_r, qd, qdd = (rng.uniform(-0.8, 0.8, n) for _ in range(3))
        quat = rng.normal(size=4)
        quat /= np.linalg.norm(quat)
        F_b, dq, dth, dqd = rng.normal(size=6), rng.normal(size=n), rng.normal(size=3), rng.normal(size=n)
        whole = trig_as_inputs(dfd_r_lift(paper, st), 0)
        expected = [np.asarray(x) for x in whole(q_r, qd, qdd, quat, F_b, dq, dth, dqd, np.sin(q_r), np.cos(q_r))]
        pieces = dfd_r_pieces(paper, st)
        v_b, a_b, tape = pieces.lift(q_r, qd, qdd, quat, np.sin(q_r), np.cos(q_r))
        got = [np.asarray(x) for x in (v_b, a_b, *pieces.lift_dir(tape, F_b, dq, dth, dqd))]
        assert pieces.tape == tape.shape[0] > 0
        for i, (ours, theirs) in enumerate(zip(got, expected)):
            assert np.all(np.isfinite(ours)) and np.array_equal(ours, theirs), f"{name} output {i}"


def test_lift_columns_are_the_lift_direction_at_each_seed(paper):
    """qd_dfd_r_lift_columns' column c is qd_dfd_r_lift_dir along lift_seeds' seed c (the order the C template takes
    them in), to round-off (LIFT_COLUMNS_REL_TOL), at a random tape and F_b, for two (13 coordinates: the rotations,
    the roll rate's with the first, then the stance legs' joints), three and four feet."""
    rng = np.random.default_rng(4)
    for name in ("FL+BR", "FL+FR+BL", "FL+FR+BL+BR"):
        pieces = dfd_r_pieces(paper, stance_set(name))
        tape, F_b = rng.normal(size=pieces.tape), rng.normal(size=6)
        columns = [np.asarray(x) for x in pieces.lift_columns(tape, F_b)]
        seeds = lift_seeds(13 if name == "FL+BR" else 12, pieces.legs, pieces.lift_reads_quat)
        assert pieces.lift_reads_quat == (name == "FL+BR")
        assert len(seeds) == columns[0].shape[1] == 9 + 3 * (name == "FL+FR+BL+BR")
        for c, seed in enumerate(seeds):
            one = [np.asarray(x).ravel() for x in pieces.lift_dir(tape, F_b, *seed)]
            for k, (col, dir_k) in enumerate(zip(columns, one)):
                scale = np.max(np.abs(dir_k), initial=0.0)
                assert np.all(np.isfinite(col[:, c])) and np.all(np.isfinite(dir_k)), f"{name} column {c} output {k}"
                assert np.max(np.abs(col[:, c] - dir_k), initial=0.0) <= LIFT_COLUMNS_REL_TOL * scale, f"{name} {c} {k}"


def test_did_full_of_two_leg_templates_and_a_turned_hip_compiled(tmp_path):
    """qd_did_full of a robot whose legs need two templates (FR's knee turns about x: its own template) and a sign
    (FL's hip axis reversed: the others' template at -q), compiled with the library's flags, against CasADi's
    Jacobian of the whole rnea (did_full_ad), which has no templates."""
    robot = turned_robot()
    pieces = did_full_pieces(robot)
    assert pieces.template_of == (0, 1, 0, 0) and [pieces.leg_signs(k)[0] for k in (0, 2, 3)] == [1.0, -1.0, -1.0]
    c_text, _, _ = derivative_source(robot, "qd_turned_d", derivative_functions(robot), "double")
    source = tmp_path / "qd_turned_d.c"
    source.write_text(c_text)
    library = tmp_path / "libturned.so"
    subprocess.run(["gcc", *C_FLAGS, "-shared", str(source), "-o", str(library), "-lm"], check=True)  # qd_M_full: unused
    compiled = ca.external(PREFIX + "did_full", str(library))
    literal = full_derivatives(robot).did_full_ad
    for seed in (0, 1):
        s = random_state(robot.lower, robot.upper, np.random.default_rng(seed))
        for k, (ours, theirs) in enumerate(zip(compiled(s.q, s.v, s.a), literal(s.q, s.v, s.a))):
            assert_close(np.array(ca.densify(ours)), np.array(ca.densify(theirs)), REL_TOL_DERIVATIVES, f"output {k}")
