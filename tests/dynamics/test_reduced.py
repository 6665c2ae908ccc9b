"""Reduced coordinates (docs/formulation.md §5-§6): id_r against a Pinocchio-built reference, Walker-Orin
vs AD, id_r = M_r qdd + C_r + G_r, forward dynamics, and the physics check against
Pinocchio-quantity constrained dynamics with the stance feet as rigid point contacts."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

from quadruped_dyn.dynamics.guarded import guarded_call
from quadruped_dyn.dynamics.reduced import reduced_maps, reduced_model
from quadruped_dyn.errors import InputError, NumericalError
from quadruped_dyn.model.robot import load_robot
from quadruped_dyn.references.pinocchio import PinocchioReference, roll_rates
from quadruped_dyn.tolerances import COND_ERR_FACTOR, REL_TOL_TERMS
from tests.conftest import assert_close

STANCES = ["FR+BL+BR", "FL+FR+BL+BR", "FL+BR", "FL+BL"]  # walk, stand, trot, pace
ROBOTS = ["paper", "solo12", "anymal_c"]
#: bent-knee postures (rad) for robots whose neutral pose has straight, singular legs
POSTURE = {"solo12": [0.0, 0.8, -1.6], "anymal_c": [0.0, 0.6, -1.2]}


def _near_standing(robot, rng):
    base = np.tile(POSTURE[robot.name], 4) if robot.name in POSTURE else robot.standing_q
    qj = np.clip(base + rng.normal(scale=0.1, size=12), robot.lower, robot.upper)
    R = pin.rpy.rpyToMatrix(*rng.normal(scale=0.2, size=3))
    return qj, R, pin.Quaternion(R).coeffs()


def _reduced(robot, stance, rng):
    m = reduced_model(robot, stance)
    qj, R, quat = _near_standing(robot, rng)
    q_r = np.concatenate([qj, [pin.rpy.matrixToRpy(R)[0]]])[: m.n]
    return m, q_r, rng.normal(size=m.n), rng.normal(size=m.n), quat


@pytest.mark.parametrize("name", ROBOTS)
@pytest.mark.parametrize("stance", STANCES)
def test_id_r_against_pinocchio_reference(name, stance):
    robot = load_robot(name)
    m, q_r, qd, qdd, quat = _reduced(robot, stance, np.random.default_rng(0))
    ours = guarded_call(m.id_r, q_r, qd, qdd, quat)[0]
    theirs = PinocchioReference(robot).reduced_inverse_dynamics(m.stance.feet, m.stance.selection("paper"), q_r, qd, qdd, quat)
    assert_close(ours, theirs, what=f"id_r {stance}")


@pytest.mark.parametrize("stance", STANCES)
def test_maps_alone_against_pinocchio_reference(paper, stance):
    """``reduced_maps`` (the maps without the dynamics' graph) gives Pinocchio's v and a."""
    rng = np.random.default_rng(3)
    qj, R, quat = _near_standing(paper, rng)
    n = 13 if stance.count("+") == 1 else 12
    q_r = np.concatenate([qj, [pin.rpy.matrixToRpy(R)[0]]])[:n]
    qd, qdd = rng.normal(size=n), rng.normal(size=n)
    v, a = guarded_call(reduced_maps(paper, stance), q_r, qd, qdd, quat)
    feet = tuple(["FL", "FR", "BL", "BR"].index(x) for x in stance.split("+"))
    _, v_ref, a_ref = PinocchioReference(paper).reduced_motion(feet, q_r, qd, qdd, quat)
    assert_close(v, v_ref, what=f"v {stance}")
    assert_close(a, a_ref, what=f"a {stance}")


@pytest.mark.parametrize("stance", STANCES)
def test_terms_and_identities(paper, stance):
    m, q_r, qd, qdd, quat = _reduced(paper, stance, np.random.default_rng(1))
    (M,) = guarded_call(m.M_r, q_r, quat)
    assert_close(guarded_call(m.M_r_ad, q_r, quat)[0], M, what="Walker-Orin M_r = AD M_r")
    (C,), (G,) = guarded_call(m.C_r, q_r, qd, quat), guarded_call(m.G_r, q_r, quat)
    (tau_r,) = guarded_call(m.id_r, q_r, qd, qdd, quat)
    assert_close(M @ qdd + C + G, tau_r, what="id_r = M_r qdd + C_r + G_r")
    tau_ext = np.concatenate([tau_r[:12], np.zeros(m.n - 12)])
    (qdd_fd,) = guarded_call(m.fd_r, q_r, qd, tau_ext, quat)
    assert_close(M @ qdd_fd + C + G, tau_ext, what="fd_r solves M_r qdd = tau_ext - C_r - G_r")
    if m.n == 12:
        allowed = COND_ERR_FACTOR * np.linalg.cond(M) * np.finfo(float).eps  # a solve's forward error
        assert_close(qdd_fd, qdd, rel=allowed, what="fd_r(id_r(qdd)) = qdd")
    assert np.abs(M - M.T).max() > 1e-6, "M_r is expected not to be symmetric"


def _physical_motion(robot, ref, stance, rng):
    """A motion the robot really makes: consistent velocities, accelerations from Pinocchio-
    quantity constrained dynamics under random joint torques."""
    m = reduced_model(robot, stance)
    qj, R, quat = _near_standing(robot, rng)
    q = np.concatenate([np.zeros(3), quat, qj])
    xi = rng.normal(scale=0.3, size=6)
    qd = rng.normal(size=12)
    r, J = ref.foot_positions(q), ref.foot_jacobians(q)
    for i in m.stance.feet:
        qd[3 * i : 3 * i + 3] = np.linalg.solve(J[i], -(xi[:3] + np.cross(xi[3:], r[i])))
    v = np.concatenate([xi, qd])
    a, _ = ref.constrained_forward_dynamics(q, v, rng.normal(scale=3.0, size=12), m.stance.feet)
    q_r, qd_r, qdd_r = qj, qd, a[6:]
    if m.n == 13:
        phid, phidd = roll_rates(R, xi[3:], a[3:6])
        q_r = np.append(qj, pin.rpy.matrixToRpy(R)[0])
        qd_r, qdd_r = np.append(qd, phid), np.append(a[6:], phidd)
    return m, q, v, a, q_r, qd_r, qdd_r, quat


@pytest.mark.parametrize("stance", ["FR+BL+BR", "FL+BR", "FR+BL"])
def test_torques_of_a_real_motion_reproduce_it_under_constrained_dynamics(paper, stance):
    """Stance sets whose paper model balances any realisable wrench (3 feet: rank 6; 2 feet:
    the residual is only the roll moment, zero for a real motion): the maps recover the full
    motion, the roll entry vanishes, and id_r's torques drive the constrained dynamics to it."""
    ref = PinocchioReference(paper)
    m, q, v, a, q_r, qd_r, qdd_r, quat = _physical_motion(paper, ref, stance, np.random.default_rng(2))
    v_map, a_map = guarded_call(m.maps, q_r, qd_r, qdd_r, quat)
    assert_close(v_map, v, what="velocity map") and assert_close(a_map, a, what="acceleration map")
    (tau_r,) = guarded_call(m.id_r, q_r, qd_r, qdd_r, quat)
    if m.n == 13:
        assert abs(tau_r[12]) <= REL_TOL_TERMS * np.abs(tau_r[:12]).max(), "a real motion leaves no roll moment"
    a_again, _ = ref.constrained_forward_dynamics(q, v, tau_r[:12], m.stance.feet)
    assert_close(a_again, a, what="constrained dynamics reproduce the motion")


def test_reduced_model_needs_two_to_four_feet(paper):
    with pytest.raises(InputError, match="needs 2, 3 or 4 stance feet"):
        reduced_model(paper, "FL")


def test_forward_dynamics_reports_condition_and_refuses_singular_stances(paper):
    from quadruped_dyn.experiment.ik import analytic_ik

    m, q_r, qd, qdd, quat = _reduced(paper, "FL+FR+BL", np.random.default_rng(5))
    (tau_r,) = guarded_call(m.id_r, q_r, qd, qdd, quat)
    qdd_fd, cond = m.forward_dynamics(q_r, qd, tau_r, quat)
    assert_close(qdd_fd, qdd, rel=COND_ERR_FACTOR * cond * np.finfo(float).eps)
    coincident = q_r.copy()  # FL and FR feet on one point: three feet on a line, GRF rank 5
    target = np.array([0.19, 0.0, -0.25])
    coincident[0:3], coincident[3:6] = analytic_ik("FL", target), analytic_ik("FR", target)
    with pytest.raises(NumericalError, match="singular"):
        m.forward_dynamics(coincident, qd, tau_r, quat)


@pytest.mark.parametrize("name", ["paper", "go2"])
def test_projection_forms_equal_walker_orin(name):
    """The generated forms (reduced_projection: S M_full T, one-pass C_r + G_r, closed-form maps)
    against the paper's recipe (reduced: Walker-Orin columns, Householder least squares), every
    stance set of two, three or four feet."""
    import casadi as ca

    from quadruped_dyn.codegen.emit import REDUCED_STANCE_SETS, reduced_functions
    from quadruped_dyn.dynamics.reduced_projection import reduced_projection

    robot = load_robot(name)
    rng = np.random.default_rng(5)
    for stance in REDUCED_STANCE_SETS:
        m, q_r, qd, qdd, quat = _reduced(robot, stance.name, rng)
        M_r, CG_r, G_r, id_r, *_ = reduced_functions(robot, stance)  # fd_r, dfd_r follow
        (M,) = guarded_call(m.M_r, q_r, quat)
        assert_close(np.array(M_r(q_r, quat)), M, what=f"M_r {stance.name}")
        expected = guarded_call(m.C_r, q_r, qd, quat)[0] + guarded_call(m.G_r, q_r, quat)[0]
        assert_close(np.array(CG_r(q_r, qd, quat)).ravel(), expected,
                     what=f"CG_r {stance.name}")
        assert_close(np.array(G_r(q_r, quat)).ravel(), guarded_call(m.G_r, q_r, quat)[0], what=f"G_r {stance.name}")
        assert_close(np.array(id_r(q_r, qd, qdd, quat)).ravel(), guarded_call(m.id_r, q_r, qd, qdd, quat)[0],
                     what=f"id_r {stance.name}")
        assert isinstance(M_r, ca.Function)
        # dfd_r's lift: v and a = T qdd_r + k in one pass, against the paper's maps (Householder least squares)
        syms = [ca.SX.sym(k, len(x)) for k, x in (("q_r", q_r), ("qd", qd), ("qdd", qdd), ("quat", quat))]
        v, a = reduced_projection(robot, stance, syms[0], syms[3]).velocity_and_acceleration(syms[1], syms[2])
        ours = ca.Function("motion", syms, [v, a])(q_r, qd, qdd, quat)
        for name, o, e in zip(("v", "a"), ours, guarded_call(reduced_maps(robot, stance.name), q_r, qd, qdd, quat)):
            assert_close(np.array(o).ravel(), e, what=f"{name} {stance.name}")
