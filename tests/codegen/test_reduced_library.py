"""The reduced model's generated C (docs/formulation.md §6.2, §11), compiled and loaded back: equal to its
CasADi graph and to the Pinocchio-built reference on every built-in robot, every stance set of
two, three or four feet; fd_r solves M_r qdd_r = tau_ext - C_r - G_r; singular configurations
are reported by the return code; the float build agrees with the double one."""

from __future__ import annotations

import re

import numpy as np
import pinocchio as pin
import pytest

from quadruped_dyn.checks.check_program_values import (
    float_bound,
    pinocchio_outputs,
    reduced_inputs,
    reference_state,
    tolerance_scale,
)
from quadruped_dyn.codegen.emit import REDUCED_NAMES, REDUCED_STANCE_SETS, reduced_functions, reduced_symbol
from quadruped_dyn.codegen.library import QD_DEGENERATE, RETURN_CODES, CompiledFunction, compiled_library
from quadruped_dyn.codegen.reduced_library import CompiledReducedDynamics
from quadruped_dyn.dynamics.reduced import reduced_model
from quadruped_dyn.errors import InputError, NumericalError
from quadruped_dyn.experiment.gait import GAITS, gait_plan
from quadruped_dyn.experiment.plan_ik import ik_target
from quadruped_dyn.model.stance import stance_set
from quadruped_dyn.tolerances import FLOAT_MAX_BOUND, FLOAT_REL_TOL, REL_TOL_GRAPH, REL_TOL_TERMS, TRUNK_PITCH_DEG_MARGIN
from tests.conftest import assert_close
from tests.dynamics.test_singular_and_types import QUAT, _collinear_joints

#: fd_r's backward error: the LU solve with partial pivoting leaves a residual of a few
#: n * eps relative to |M_r| |qdd_r| + |rhs| (n = 13): far below 1e-12.
REL_TOL_RESIDUAL = 1e-12

#: As check_qd.c's QD_MAX_TOL: a float case whose conditioning-scaled tolerance exceeds this
#: could only fail on NaN, so it is not checked in float (the double build checks it).
FLOAT_MAX_TOL = 1e-2


def _inputs(s, n):
    return {k: (v if k == "quat" else v[:n]) for k, v in reduced_inputs(s).items()}


def test_compiled_reduced_equal_graph_and_pinocchio(robot, ref, library):
    s = reference_state(robot)
    for stance in REDUCED_STANCE_SETS:
        graphs = {f.name(): f for f in reduced_functions(robot, stance)}
        n = 13 if len(stance.feet) == 2 else 12
        x = _inputs(s, n)
        out = {}
        for kind in REDUCED_NAMES:
            name = reduced_symbol(kind, stance)
            f = CompiledFunction(library, name)
            (out[kind],) = f(*[x[k] for k in f.names_in])
            scale = tolerance_scale(ref, name, s)
            expected = pinocchio_outputs(robot, ref, name, s)[0]
            assert_close(out[kind], expected, rel=REL_TOL_TERMS * scale, what=f"{name} vs Pinocchio")
            if kind != "fd_r":  # fd_r's graph is a signature; its body is the C solve
                graph = np.array(graphs["qd_" + name](*[x[k] for k in f.names_in]))
                assert_close(out[kind], graph.reshape(out[kind].shape), rel=REL_TOL_GRAPH, what=f"{name} vs graph")
        rhs = x["tau_ext"] - out["CG_r"]
        residual = out["M_r"] @ out["fd_r"] - rhs
        bound = np.abs(out["M_r"]) @ np.abs(out["fd_r"]) + np.abs(rhs)
        assert np.all(np.abs(residual) <= REL_TOL_RESIDUAL * bound), f"fd_r {stance.name}: backward error"
        assert_close(out["M_r"] @ x["qdd_r"] + out["CG_r"], out["id_r"], what=f"id_r = M_r qdd + CG_r, {stance.name}")


def _stance_args(robot, stance_name):
    stance = stance_set(stance_name)
    n = 13 if len(stance.feet) == 2 else 12
    x = _inputs(reference_state(robot), n)
    return stance, x


def test_singular_configurations_are_reported(paper):
    """The C return codes, through the Python layer: QD_NONFINITE for a zero quaternion and a NaN input
    (through ``raw``: ``__call__`` refuses those inputs before the C sees them,
    tests/codegen/test_library.py). A stretched stance leg is NOT singular: the reduced model never
    inverts the leg's Jacobian (cond(M_r) 1e3 -> 3e4). (QD_SINGULAR: the float build's bound, checked by
    the check program; no regular double state of a built-in robot is known to reach it since the trunk
    pitched near 90 deg is degenerate, test_trunk_pitched_near_90_deg_is_degenerate_for_two_feet.)"""
    library = compiled_library(paper)
    stance, x = _stance_args(paper, "FL+BR")
    for name in ("M_r", "fd_r"):
        f = CompiledFunction(library, reduced_symbol(name, stance))
        args = {"q_r": x["q_r"], "qd_r": x["qd_r"], "tau_ext": x["tau_ext"], "quat": np.zeros(4)}
        with pytest.raises(InputError, match="not finite"):
            f.raw(*[args[k] for k in f.names_in])
    f = CompiledFunction(library, reduced_symbol("id_r", stance))
    with pytest.raises(InputError, match="not finite"):
        f.raw(np.full(13, np.nan), x["qd_r"], x["qdd_r"], x["quat"])
    for feet in ("FL+FR+BL", "FL+FR+BL+BR"):  # M_r of three or four feet does not read quat (the header says so)
        stance, x = _stance_args(paper, feet)
        f = CompiledFunction(library, reduced_symbol("M_r", stance))
        zero, given = (np.asarray(f.raw(x["q_r"], quat)) for quat in (np.zeros(4), x["quat"]))
        assert np.all(np.isfinite(given)) and np.array_equal(zero, given), feet
    stance, x = _stance_args(paper, "FR+BL+BR")
    q = x["q_r"].copy()
    q[3 * 3 + 2] = 0.0  # BR knee straight
    qdd = CompiledReducedDynamics(paper).fd_r(stance, q, x["qd_r"], x["tau_ext"], x["quat"])
    assert np.all(np.isfinite(qdd))


def test_trunk_pitched_near_90_deg_is_degenerate_for_two_feet(paper):
    """Two feet with the trunk pitched to within TRUNK_PITCH_DEG_MARGIN (2 deg) of 90 deg: every
    generated function of the pair returns QD_DEGENERATE, as the Python model raises (their error
    grows as eps / cos(pitch)^3: 0.1 relative at 1e-5 rad, returned as success before); 1 deg
    outside the margin they agree with the paper's recipe (``reduced_model``) within REL_TOL_TERMS."""
    library = compiled_library(paper)
    stance = stance_set("FL+BR")
    rng = np.random.default_rng(3)
    q_r = np.r_[paper.standing_q, 0.1]
    x = {"q_r": q_r, "qd_r": 0.3 * rng.standard_normal(13), "qdd_r": rng.standard_normal(13),
         "tau_ext": rng.standard_normal(13)}
    model = reduced_model(paper, stance.name)
    code = re.escape(RETURN_CODES[QD_DEGENERATE])
    compiled = {kind: CompiledFunction(library, reduced_symbol(kind, stance)) for kind in REDUCED_NAMES}
    for margin in (1e-13, 1e-5, np.radians(TRUNK_PITCH_DEG_MARGIN) - 1e-3):
        quat = pin.Quaternion(pin.rpy.rpyToMatrix(0.1, np.pi / 2 - margin, 0.2)).coeffs()
        for kind, f in compiled.items():
            with pytest.raises(NumericalError, match=code):
                f(*[{**x, "quat": quat}[k] for k in f.names_in])
                pytest.fail(f"{kind} returned {margin:.0e} rad from a 90 deg pitch")
        with pytest.raises(NumericalError, match="pitched within 2.0 deg of 90 deg"):
            model.M_r(q_r, quat)
    quat = pin.Quaternion(pin.rpy.rpyToMatrix(0.1, np.pi / 2 - np.radians(TRUNK_PITCH_DEG_MARGIN + 1), 0.2)).coeffs()
    expected = {"M_r": np.asarray(model.M_r(q_r, quat)),
                "CG_r": np.asarray(model.C_r(q_r, x["qd_r"], quat)).ravel() + np.asarray(model.G_r(q_r, quat)).ravel(),
                "id_r": np.asarray(model.id_r(q_r, x["qd_r"], x["qdd_r"], quat)).ravel(),
                "fd_r": model.forward_dynamics(q_r, x["qd_r"], x["tau_ext"], quat)[0]}
    for kind, value in expected.items():
        f = compiled[kind]
        assert_close(f(*[{**x, "quat": quat}[k] for k in f.names_in])[0], value, rel=REL_TOL_TERMS,
                     what=f"{kind} 1 deg outside the pitch margin")


def test_degenerate_stances_are_reported_by_every_function(paper):
    """QD_DEGENERATE from every generated reduced function where the Python model
    raises too: three collinear stance feet (put on a line by Pinocchio IK) and the front pair at zero
    pitch and roll (roll axis perpendicular to the feet's line); without it they return ~1e15 with
    code 0. A regular state of the same stance set next door still gets an answer."""
    library = compiled_library(paper)
    compiled = CompiledReducedDynamics(paper)
    cases = [("FL+FR+BL", _collinear_joints(paper, 1, (0, 2))), ("FR+BL+BR", _collinear_joints(paper, 2, (1, 3))),
             ("FL+FR", np.r_[paper.standing_q, 0.0])]
    for name, q in cases:
        stance, n = stance_set(name), q.size
        x = {"q_r": q, "qd_r": np.ones(n), "qdd_r": np.ones(n), "tau_ext": np.ones(n), "quat": QUAT}
        code = re.escape(RETURN_CODES[QD_DEGENERATE])
        for kind in REDUCED_NAMES:
            f = CompiledFunction(library, reduced_symbol(kind, stance))
            with pytest.raises(NumericalError, match=code):
                f(*[x[k] for k in f.names_in])
                pytest.fail(f"{kind} of {name} returned at a degenerate stance")
            with pytest.raises(NumericalError, match=code):  # the control loop's unchecked call: the same error
                f.raw(*[x[k] for k in f.names_in])
        ones = np.ones(n)
        calls = {"compiled id_r": (compiled.id_r, stance), "compiled fd_r": (compiled.fd_r, stance),
                 "Python id_r": (reduced_model(paper, name).id_r,)}  # the Python model agrees
        for what, (method, *first) in calls.items():
            with pytest.raises(NumericalError):
                method(*first, q, ones, ones, QUAT)
                pytest.fail(f"{what} of {name} returned at a degenerate stance")
        regular, quat = paper.standing_q, QUAT
        if n == 13:  # the front pair with the trunk rolled and pitched by 0.1 rad
            regular, quat = np.r_[paper.standing_q, 0.1], pin.Quaternion(pin.rpy.rpyToMatrix(0.1, 0.1, 0.0)).coeffs()
        assert np.all(np.isfinite(compiled.fd_r(stance, regular, x["qd_r"], x["tau_ext"], quat)))


def test_gait_states_are_regular(paper):
    """No return code at the walk's and the trot's reference states (every stance set they use):
    the regularity is >= 6e-2 there on every built-in robot and b1, 10^16.8 above QD_REGULARITY_MIN."""
    compiled = CompiledReducedDynamics(paper)
    for gait in GAITS.values():
        plan = gait_plan(paper, gait)
        for t in np.linspace(0.0, gait.period, 25)[:-1]:
            s = ik_target(plan, t)
            stance = stance_set("+".join(("FL", "FR", "BL", "BR")[i] for i in s.stance))
            n = 13 if len(stance.feet) == 2 else 12
            q, qd, qdd = s.q_r[:n], s.qd_r[:n], s.qdd_r[:n]
            tau = compiled.id_r(stance, q, qd, qdd, QUAT)
            assert np.all(np.isfinite(tau)) and np.all(np.isfinite(compiled.fd_r(stance, q, qd, tau, QUAT)))


def test_python_layer_checks_its_inputs(paper):
    d = CompiledReducedDynamics(paper)
    stance, x = _stance_args(paper, "FL+BR")
    with pytest.raises(InputError, match="quat"):
        d.fd_r(stance, x["q_r"], x["qd_r"], x["tau_ext"], np.zeros(4))
    with pytest.raises(InputError, match="q_r"):
        d.fd_r(stance, x["q_r"][:12], x["qd_r"], x["tau_ext"], x["quat"])
    with pytest.raises(InputError, match="tau_ext"):
        d.fd_r(stance, x["q_r"], x["qd_r"], np.full(13, np.inf), x["quat"])
    for bad in (stance_set("FL"), "FL", "FL+FL", "FL+XX", "none"):
        with pytest.raises(InputError, match="stance"):
            d.fd_r(bad, x["q_r"][:12], x["qd_r"][:12], x["tau_ext"][:12], x["quat"])


def test_float_build_matches_pinocchio(paper):
    """Every reduced term of the float build (REDUCED_NAMES; the derivatives are checked in
    tests/codegen/test_emit_derivatives.py) against Pinocchio's values, within the float tolerance
    scaled by the conditioning (tolerance_scale)."""
    from quadruped_dyn.references.pinocchio import PinocchioReference

    library = compiled_library(paper, "float")
    ref = PinocchioReference(paper)
    s = reference_state(paper)
    for stance in REDUCED_STANCE_SETS:
        x = _inputs(s, 13 if len(stance.feet) == 2 else 12)
        for kind in REDUCED_NAMES:
            name = reduced_symbol(kind, stance)
            f = CompiledFunction(library, name)
            bound = float_bound(ref, name, s)
            try:
                (out,) = f(*[x[k] for k in f.names_in])
            except NumericalError:  # refused only where its own error bound says so (a factor 2: it rounds in float)
                assert bound > FLOAT_MAX_BOUND / 2, f"{name} refused at a float error bound of {bound:.1e}"
                continue
            assert bound <= 2 * FLOAT_MAX_BOUND, f"{name} returned 0 at a float error bound of {bound:.1e}"
            tol = FLOAT_REL_TOL * tolerance_scale(ref, name, s)
            if tol > FLOAT_MAX_TOL:  # fd_r of BL+BR: cond(M_r) ~5e5 leaves float no digits to check
                continue
            expected = pinocchio_outputs(paper, ref, name, s)[0]
            assert_close(out, expected, rel=tol, what=name)


def test_python_layer_refuses_what_is_not_a_stance_or_a_robot(paper):
    """A stance that is None or a list raised AttributeError ('feet'), a robot given by name
    AttributeError ('urdf_sha256'), a quaternion whose |q|^2 underflows was 'zero' by one check
    and not by the other."""
    d = CompiledReducedDynamics(paper)
    stance, x = _stance_args(paper, "FL+BR")
    for bad in (None, ["FL", "BR"], 3):
        with pytest.raises(InputError, match="stance set"):
            d.fd_r(bad, x["q_r"], x["qd_r"], x["tau_ext"], x["quat"])
    with pytest.raises(InputError, match="zero quaternion"):
        d.id_r(stance, x["q_r"], x["qd_r"], x["qd_r"], np.array([0.0, 0.0, 0.0, 1e-200]))
    with pytest.raises(InputError, match="robot"):
        CompiledReducedDynamics("paper")
