"""The reduced terms' parts from the stance's maps and the feet's kinematics (codegen/forms/stance_maps.py,
codegen/forms/leg_pieces.py ``foot_pieces``; docs/formulation.md §6.2, "The parts from the feet's maps"): the feet leg by leg
against ``kinematics.foot_position`` and its derivatives, and S_b, T_b, v and a assembled from the maps as the C
assembles them (c/qd_reduced_solve.c, qd_parts) against the generated forms' S_b, T_b (``ReducedProjection``) and
the paper's maps (``reduced.reduced_maps``: Householder least squares), every stance set of two to four feet."""

from __future__ import annotations

import casadi as ca
import numpy as np
import pytest

from quadruped_dyn.codegen.emit import REDUCED_STANCE_SETS
from quadruped_dyn.codegen.forms.leg_pieces import FOOT_PARTS, foot_kinematics, foot_pieces
from quadruped_dyn.codegen.forms.stance_maps import stance_maps
from quadruped_dyn.dynamics.guarded import guarded_call
from quadruped_dyn.dynamics.kinematics import foot_position
from quadruped_dyn.dynamics.reduced import reduced_maps
from quadruped_dyn.dynamics.reduced_projection import reduced_projection
from quadruped_dyn.math.spatial import unstacked
from quadruped_dyn.model.registry import ROBOT_NAMES
from quadruped_dyn.model.robot import load_robot
from quadruped_dyn.tolerances import REL_TOL_GRAPH, REL_TOL_TERMS
from tests.codegen.forms.test_leg_template import turned_robot
from tests.conftest import assert_close
from tests.dynamics.test_reduced import _reduced


def _feet(robot, q: np.ndarray, qd: np.ndarray) -> list[dict[str, np.ndarray]]:
    """Each leg's FOOT_PARTS by its template's function, as the C calls it (joint inputs times the leg's signs),
    turned back by the pieces' tail."""
    pieces = foot_pieces(robot)
    Ls = []
    for k in range(4):
        sigma = np.array(pieces.leg_signs(k))
        Ls.append(pieces.legs[pieces.template_of[k]](sigma * q[3 * k : 3 * k + 3], sigma * qd[3 * k : 3 * k + 3],
                                                    np.array(pieces.leg_values(k))))
    feet = np.array(pieces.tail(*Ls))
    return [{name: np.array(x) for name, x in unstacked(ca.DM(feet[:, k]), FOOT_PARTS).items()} for k in range(4)]


@pytest.mark.parametrize("name", [*ROBOT_NAMES, "turned"])
def test_feet_by_leg_equal_the_legs_kinematics(name):
    robot = load_robot(name) if name != "turned" else turned_robot()
    rng = np.random.default_rng(3)
    q, qd = rng.uniform(robot.lower, robot.upper), rng.normal(size=12)
    q_l, qd_l = ca.SX.sym("q_l", 3), ca.SX.sym("qd_l", 3)
    for k, foot in enumerate(_feet(robot, q, qd)):
        whole = ca.Function("foot", [q_l, qd_l], [foot_kinematics(foot_position(robot.legs[k], q_l), q_l, qd_l)])
        ours = np.concatenate([foot[n].ravel(order="F") for n, _, _ in FOOT_PARTS])
        assert_close(ours, np.array(whole(q[3 * k : 3 * k + 3], qd[3 * k : 3 * k + 3])).ravel(), REL_TOL_GRAPH,
                     f"{name} leg {k}'s foot by its template")


def _parts(robot, stance, q_r, qd, qdd, quat):
    """S_b, T_b, v, a from the maps and the feet, in the C's order of operations (qd_parts)."""
    n, feet = len(q_r), _feet(robot, q_r[:12], qd[:12])
    out = [np.array(x) for x in stance_maps(stance)(np.concatenate([feet[i]["r"].ravel() for i in stance.feet]), quat)]
    W_T, Y = out[1], out[2]
    S_b, T_b, vw, aw = np.zeros((n, 6)), np.zeros((6, n)), np.zeros(6), np.zeros(6)
    for j, i in enumerate(stance.feet):
        J, cols = feet[i]["J"], slice(3 * j, 3 * j + 3)
        S_b[3 * i : 3 * i + 3] = -(W_T[:, cols] @ J).T
        T_b[:, 3 * i : 3 * i + 3] = -Y[:, cols] @ J
        vw += Y[:, cols] @ -feet[i]["J_qd"].ravel()
    if n == 13:
        y_e, s_e, D = (x.reshape(shape) for x, shape in zip(out[3:], ((6,), (6,), (3, 3))))
        S_b[12], T_b[:, 12] = s_e, y_e
        vw += y_e * qd[12]
        aw += y_e * (qdd[12] - (D @ vw[3:]) @ vw[3:])
    omega = vw[3:]
    for j, i in enumerate(stance.feet):
        r, J_qd = feet[i]["r"].ravel(), feet[i]["J_qd"].ravel()
        b = -np.cross(omega, np.cross(omega, r) + 2 * J_qd) - feet[i]["Jdot_qd"].ravel() - feet[i]["J"] @ qdd[3 * i : 3 * i + 3]
        aw += Y[:, 3 * j : 3 * j + 3] @ b
    v = np.concatenate([vw, qd[:12]])
    a = np.concatenate([aw[:3] - np.cross(omega, vw[:3]), aw[3:], qdd[:12]])
    return S_b, T_b, v, a, out[0].item()


@pytest.mark.parametrize("name", ["paper", "go2", "turned"])
def test_parts_from_the_maps_equal_the_projection_and_the_papers_maps(name):
    robot = load_robot(name) if name != "turned" else turned_robot()
    rng = np.random.default_rng(7)
    for stance in REDUCED_STANCE_SETS:
        m, q_r, qd, qdd, quat = _reduced(load_robot("paper") if name == "turned" else robot, stance.name, rng)
        S_b, T_b, v, a, regularity = _parts(robot, stance, q_r, qd, qdd, quat)
        syms = [ca.SX.sym(k, len(x)) for k, x in (("q_r", q_r), ("quat", quat))]
        S_ref, T_ref, _ = reduced_projection(robot, stance, *syms).mass_matrix_factors()
        S_e, T_e = (np.array(ca.Function("f", syms, [x])(q_r, quat)) for x in (S_ref, T_ref))
        assert regularity > 0 and np.isfinite(regularity)
        assert_close(S_b, S_e, REL_TOL_TERMS, f"{name} {stance.name} S_b")
        assert_close(T_b, T_e, REL_TOL_TERMS, f"{name} {stance.name} T_b")
        for what, ours, paper in zip(("v", "a"), (v, a), guarded_call(reduced_maps(robot, stance.name), q_r, qd, qdd, quat)):
            assert_close(ours, paper, REL_TOL_TERMS, f"{name} {stance.name} {what} against the paper's maps")
