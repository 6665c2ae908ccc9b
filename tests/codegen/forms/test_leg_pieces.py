"""id_full and M leg by leg (codegen/forms/leg_pieces.py) against the whole-robot graphs they replace in the reduced files' C
(``newton_euler.full_dynamics``: the paper's recursion and the composite rigid bodies), on every built-in robot and on
a robot whose legs need two templates and a sign."""

from __future__ import annotations

import casadi as ca
import numpy as np
import pytest

from quadruped_dyn.codegen.forms.leg_pieces import id_full_pieces, mass_blocks, mass_matrix_pieces
from quadruped_dyn.codegen.forms.leg_template import LegPieces
from quadruped_dyn.dynamics.newton_euler import full_dynamics
from quadruped_dyn.model.registry import ROBOT_NAMES
from quadruped_dyn.model.robot import load_robot
from quadruped_dyn.model.state import random_state
from quadruped_dyn.tolerances import REL_TOL_GRAPH
from tests.codegen.forms.test_leg_template import turned_robot
from tests.conftest import assert_close


def _legs(pieces: LegPieces, k: int, head: list[np.ndarray] | None, q: np.ndarray, v: np.ndarray,
          a: np.ndarray) -> np.ndarray:
    """Leg k's function at the robot's state, as the C calls it: joint inputs times the leg's signs (M's legs: no
    head, the angles alone)."""
    s, sigma = slice(3 * k, 3 * k + 3), np.array(pieces.leg_signs(k))
    joints = [sigma * q[7:][s]] if head is None else [sigma * q[7:][s], sigma * v[6:][s], sigma * a[6:][s]]
    trunk = [] if head is None else [v[3:6], a[3:6], *head]
    return pieces.legs[pieces.template_of[k]](*trunk, *joints, np.array(pieces.leg_values(k)))


def _check(robot, seeds=(0, 1)) -> None:
    fd = full_dynamics(robot)
    id_pieces, m_pieces = id_full_pieces(robot), mass_matrix_pieces(robot)
    for seed in seeds:
        rng = np.random.default_rng(seed)
        s = random_state(robot.lower, robot.upper, rng)
        head = [np.asarray(x) for x in id_pieces.head.call([s.q, s.v, s.a])]
        ys = [_legs(id_pieces, k, head, s.q, s.v, s.a) for k in range(4)]
        no_force = np.zeros(12)  # the reduced terms' rnea: their foot forces are the GRF projection's
        for name, ours, whole in zip(("w_res", "tau"), id_pieces.tail(s.q, s.v, s.a, *ys),
                                     fd.id_full(s.q, s.v, s.a, no_force)):
            assert_close(np.array(ours), np.array(whole), REL_TOL_GRAPH, f"{robot.name} id_full {name} by leg")
        Ls = [_legs(m_pieces, k, None, s.q, s.v, s.a) for k in range(4)]
        M = np.array(ca.densify(fd.M_full_crba(s.q)))
        assert_close(np.array(m_pieces.tail(*Ls)), np.array(mass_blocks(ca.DM(M))), REL_TOL_GRAPH,
                     f"{robot.name} M's blocks by leg")
        legs = [slice(6 + 3 * k, 9 + 3 * k) for k in range(4)]  # the blocks are all of M: none between two legs
        assert all(not M[a, b].any() for a in legs for b in legs if a != b) and np.array_equal(M[6:, :6], M[:6, 6:].T)


@pytest.mark.parametrize("name", ROBOT_NAMES)
def test_id_full_and_m_by_leg_equal_the_whole_robot_graphs(name):
    _check(load_robot(name))


def test_by_leg_with_two_templates_and_a_sign():
    _check(turned_robot())
