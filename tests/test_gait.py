"""Gaits (trot, static walk) and the paper's validation experiment."""

from __future__ import annotations

import numpy as np
import pytest

from quadruped_dyn.gait import TROT, WALK, gait_posture, reference, simulate
from quadruped_dyn.kinematics import robot_kinematics
from quadruped_dyn.robot import load_robot

from .conftest import assert_close

GAIT = TROT
PAIRS = TROT.phases
#: Central differences of the IK trajectory with step H: O(H^2) truncation on signals whose
#: third derivative is ~1e3 rad/s^3, plus round-off eps / H.
H = 1e-5
REL_TOL_DIFF = 1e-5


def _standing(robot):
    return [leg.foot_position(q) for leg, q in zip(robot.legs, gait_posture(robot).reshape(4, 3))]


#: Position, velocity, acceleration jumps allowed across a switch sampled 2 EPS apart: the
#: next derivative (velocity <= 1 m/s, acceleration <= 1e2 m/s^2, jerk <= 1e4 m/s^3) times 2 EPS.
EPS = 1e-9
C2_TOL = (2e-9, 2e-7, 2e-5)


@pytest.mark.parametrize("gait", [TROT, WALK], ids=["trot", "walk"])
@pytest.mark.parametrize("k", [1, 2, 3, 4, 5])
def test_feet_are_c2_at_lift_off_and_touch_down(paper, gait, k):
    t = k * gait.phase_duration
    for i, standing in enumerate(_standing(paper)):
        before, after = gait.foot(i, t - EPS, standing), gait.foot(i, t + EPS, standing)
        for order, (a, b, tol) in enumerate(zip(before, after, C2_TOL)):
            assert np.abs(a - b).max() <= tol, f"foot {i}, derivative {order} jumps at t = {t}"


def test_walk_swings_one_leg_at_a_time_and_advances_each_foot_one_stride(paper):
    standing = _standing(paper)
    for k, stance in enumerate(WALK.phases):
        assert len(stance) == 3
        t = (k + 0.5) * WALK.phase_duration
        moving = [i for i in range(4) if np.abs(WALK.foot(i, t, standing[i])[1]).max() > 0]
        assert moving == [i for i in range(4) if i not in stance]
    for i in range(4):  # a full cycle later each foot stands one stride further on
        a, b = WALK.foot(i, 0.01, standing[i])[0], WALK.foot(i, 0.01 + WALK.period, standing[i])[0]
        assert_close(b - a, [WALK.speed * WALK.period, 0, 0])


def test_stance_feet_stay_on_their_footholds(paper):
    for t in np.linspace(0.01, 0.29, 5):
        for i in PAIRS[0]:
            P, Pd, _ = GAIT.foot(i, t, _standing(paper)[i])
            assert_close(Pd, np.zeros(3))
            assert_close(P, GAIT.foot(i, 0.0, _standing(paper)[i])[0])


@pytest.mark.parametrize("name", ["paper", "solo12", "go1"])  # analytic IK, numeric IK
def test_ik_reference_is_consistent(name):
    """FK(q(t)) puts each foot where the gait says; qd, qdd are the derivatives of q."""
    robot = load_robot(name)
    kin = robot_kinematics(robot)
    t = 0.37  # FR+BL stance, FL+BR swinging
    r = reference(robot, GAIT, t)
    for i in range(4):
        P = GAIT.foot(i, t, _standing(robot)[i])[0]
        assert_close(np.asarray(kin[i].foot_position(r.q_r[3 * i : 3 * i + 3])).ravel(), P - [GAIT.speed * t, 0, 0])
    rp, rm = reference(robot, GAIT, t + H, r.q_r[:12]), reference(robot, GAIT, t - H, r.q_r[:12])
    assert_close(r.qd_r, (rp.q_r - rm.q_r) / (2 * H), rel=REL_TOL_DIFF, what="qd = dq/dt")
    assert_close(r.qdd_r, (rp.qd_r - rm.qd_r) / (2 * H), rel=REL_TOL_DIFF, what="qdd = dqd/dt")


def test_forward_dynamics_reproduces_ik_with_the_roll_moment_applied(paper):
    """The paper's check over a tenth of a second (the error grows as dt^4 times the roll
    instability; see quadruped_dyn/gait.py)."""
    sim = simulate(paper, GAIT, horizon=0.1, dt=1e-3, roll_actuated=True)
    assert sim.diverged_at is None
    assert np.nanmax(sim.percent_error(sim.q, sim.q_ref)[:12]) < 1e-6
    assert np.nanmax(sim.percent_error(sim.qdd, sim.qdd_ref)[:12]) < 1e-4
    assert sim.closure_m.max() < 1e-9


def test_unactuated_roll_departs(paper):
    """With the roll unactuated the same torques do not make the trot: the centre of mass is
    off the diagonal support line (id_r's 13th entry is nonzero along the gait)."""
    sim = simulate(paper, GAIT, horizon=0.1, dt=1e-3, roll_actuated=False)
    assert np.abs(sim.roll_moment).max() > 0.1
    assert sim.departure_time(1.0) is not None


def test_forward_dynamics_reproduces_ik_in_the_static_walk(paper):
    """Three stance feet: no unactuated coordinate; over 0.1 s the reduced forward dynamics
    under id_r's torques stays on the IK motion (RK4 error only)."""
    sim = simulate(paper, WALK, horizon=0.1, dt=1e-3, roll_actuated=False)
    assert sim.q.shape[1] == 12 and sim.diverged_at is None
    assert np.nanmax(sim.percent_error(sim.q, sim.q_ref)) < 1e-6
    assert sim.closure_m.max() < 1e-9
