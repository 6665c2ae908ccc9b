"""``codegen.joint_trig.trig_as_inputs`` on the generated full terms: the rewritten graph reads the joints' sines and
cosines from its two new inputs (no sin or cos of a joint angle left) and, given sin and cos of q's joint angles,
gives the original function's outputs to the bit, on every built-in robot."""

from __future__ import annotations

import casadi as ca
import numpy as np
import pytest

from quadruped_dyn.codegen.emit import codegen_functions
from quadruped_dyn.codegen.forms.did_full_pieces import did_full_pieces
from quadruped_dyn.codegen.forms.leg_pieces import id_full_pieces, mass_matrix_pieces
from quadruped_dyn.codegen.joint_trig import trig_as_inputs, trig_count
from quadruped_dyn.model.registry import ROBOT_NAMES
from quadruped_dyn.model.robot import load_robot
from quadruped_dyn.model.state import JOINT_ANGLES

NAMES = ("qd_M_full", "qd_G_full", "qd_nle_full", "qd_id_full")


def _dense(x: ca.DM) -> np.ndarray:
    return np.asarray(ca.densify(x))


@pytest.mark.parametrize("robot_name", ROBOT_NAMES)
def test_full_terms_read_the_joints_trig_and_agree_to_the_bit(robot_name):
    robot = load_robot(robot_name)
    functions = {f.name(): f for f in codegen_functions(robot)}
    rng = np.random.default_rng(11)
    for name in NAMES:
        f = functions[name]
        g = trig_as_inputs(f, 0, JOINT_ANGLES)
        assert trig_count(f) > 0 and trig_count(g) == 0, name
        args = [rng.uniform(-2.0, 2.0, f.nnz_in(i)) for i in range(f.n_in())]
        angles = args[0][JOINT_ANGLES.start:JOINT_ANGLES.stop]
        want = f.call([ca.DM(x) for x in args])
        got = g.call([*(ca.DM(x) for x in args), ca.DM(np.sin(angles)), ca.DM(np.cos(angles))])
        for w, o in zip(want, got):
            assert np.all(np.isfinite(_dense(w))) and np.array_equal(_dense(w), _dense(o)), name


@pytest.mark.parametrize("robot_name", ROBOT_NAMES)
def test_leg_functions_read_the_joints_trig_and_agree_to_the_bit(robot_name):
    """The leg functions of did_full, id_full and M (by_leg_c rewrites each, its joint angles the first joint input)."""
    robot = load_robot(robot_name)
    rng = np.random.default_rng(12)
    for pieces in (did_full_pieces(robot), id_full_pieces(robot), mass_matrix_pieces(robot)):
        for f in pieces.legs:
            i_q = 3 if f.n_in() > 2 else 0  # (w_b, alpha_b, a, q_l, ...) or (q_l, p)
            assert f.name_in(i_q) == "q_l"
            g = trig_as_inputs(f, i_q)
            assert trig_count(f) > 0 and trig_count(g) == 0, f.name()
            args = [rng.uniform(-2.0, 2.0, f.nnz_in(i)) for i in range(f.n_in())]
            want = f.call([ca.DM(x) for x in args])
            got = g.call([*(ca.DM(x) for x in args), ca.DM(np.sin(args[i_q])), ca.DM(np.cos(args[i_q]))])
            for w, o in zip(want, got):
                assert np.all(np.isfinite(_dense(w))) and np.array_equal(_dense(w), _dense(o)), f.name()


def test_other_entries_keep_their_trig():
    """Only the named entries are replaced: the sine of an entry outside them stays a sine."""
    x = ca.SX.sym("x", 3)
    f = ca.Function("f", [x], [ca.sin(x[0]) + ca.cos(x[1]) * ca.sin(x[2])])
    g = trig_as_inputs(f, 0, range(1, 3))
    assert trig_count(g) == 1
    assert float(g(ca.DM([0.3, 0.5, 0.7]), ca.DM([0.0, 0.2]), ca.DM([0.4, 0.0]))) == pytest.approx(np.sin(0.3) + 0.4 * 0.2)
