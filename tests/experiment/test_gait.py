"""Gait plans (trot, statically stable walk) and the IK plan."""

from __future__ import annotations

import shutil

import numpy as np
import pytest

from quadruped_dyn.dynamics.kinematics import robot_kinematics
from quadruped_dyn.errors import InputError
from quadruped_dyn.experiment.gait import TROT, WALK, deepest_point, gait_plan, gait_posture, support_margin
from quadruped_dyn.experiment.paper_experiment import static_stability
from quadruped_dyn.experiment.plan_ik import feet_ik, ik_target, ik_targets
from quadruped_dyn.experiment.simulate import CasadiReducedDynamics, IkTorques
from quadruped_dyn.model.paper_robot import dh_form
from quadruped_dyn.model.registry import ROBOT_NAMES
from quadruped_dyn.model.robot import load_robot
from tests.conftest import assert_close

#: Central differences of the IK trajectory with step H: O(H^2) truncation on signals whose
#: third derivative is ~1e3 rad/s^3, plus round-off eps / H.
H = 1e-5
REL_TOL_DIFF = 1e-5

#: Position, velocity, acceleration jumps allowed across a switch sampled 2 EPS apart: the
#: next derivative (velocity <= 1 m/s, acceleration <= 1e2 m/s^2, jerk <= 1e4 m/s^3) times 2 EPS.
EPS = 1e-9
C2_TOL = (2e-9, 2e-7, 2e-5)

#: The walk's static-stability targets (docs/experiment.md §2): the CoM at least this far inside the
#: support triangle (m) at all times, and no stance foot pulling on the ground.
MIN_COM_MARGIN_M = 0.02
#: Static-stability samples in the tests, s (the CLI uses 5 ms; 20 ms keeps the sweep short).
STABILITY_DT_TEST = 0.02


@pytest.mark.parametrize("gait", [TROT, WALK], ids=["trot", "walk"])
@pytest.mark.parametrize("k", [1, 2, 3, 4, 5])
def test_feet_and_trunk_are_c2_at_lift_off_and_touch_down(paper, gait, k):
    plan = gait_plan(paper, gait)
    t = k * gait.phase_duration
    for i in range(4):
        before, after = plan.foot(i, t - EPS), plan.foot(i, t + EPS)
        for order, (a, b, tol) in enumerate(zip(before, after, C2_TOL)):
            assert np.abs(a - b).max() <= tol, f"foot {i}, derivative {order} jumps at t = {t}"
    for order, (a, b, tol) in enumerate(zip(plan.trunk(t - EPS), plan.trunk(t + EPS), C2_TOL)):
        assert np.abs(a - b).max() <= tol, f"trunk derivative {order} jumps at t = {t}"


def test_trunk_rate_and_acceleration_are_derivatives_of_its_position(paper):
    plan = gait_plan(paper, WALK)
    for t in (0.13, 0.52, 1.01):
        p, pd, pdd = plan.trunk(t)
        (pp, pdp, _), (pm, pdm, _) = plan.trunk(t + H), plan.trunk(t - H)
        assert_close(pd, (pp - pm) / (2 * H), rel=REL_TOL_DIFF, what="trunk velocity")
        assert_close(pdd, (pdp - pdm) / (2 * H), rel=REL_TOL_DIFF, what="trunk acceleration")


def test_walk_swings_one_leg_at_a_time_and_advances_each_foot_one_stride(paper):
    plan = gait_plan(paper, WALK)
    for k, stance in enumerate(WALK.phases):
        assert len(stance) == 3
        t = (k + 0.5) * WALK.phase_duration
        moving = [i for i in range(4) if np.abs(plan.foot(i, t)[1]).max() > 0]
        assert moving == [i for i in range(4) if i not in stance]
    for i in range(4):  # a full cycle later each foot stands one stride further on
        a, b = plan.foot(i, 0.01)[0], plan.foot(i, 0.01 + WALK.period)[0]
        assert_close(b - a, [WALK.speed * WALK.period, 0, 0])


def test_consecutive_swing_legs_share_a_side_or_an_end():
    """Around the foot rectangle: the support triangles before and after a switch overlap in
    a triangle, not only along a diagonal (where the CoM would have no margin)."""
    from quadruped_dyn.model.leg import LEG_LABELS

    swings = [WALK.swing_phase(i) for i in range(4)]
    order = [LEG_LABELS[swings.index(k)] for k in range(4)]
    for a, b in zip(order, order[1:] + order[:1]):
        assert a[0] == b[0] or a[1] == b[1], f"{a} then {b} is a diagonal switch"


def test_support_margin_and_deepest_point():
    square = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]])
    assert support_margin(np.array([0.5, 0.5]), square) == pytest.approx(0.5)
    assert support_margin(np.array([1.5, 0.5]), square) == pytest.approx(-0.5)
    tri_a, tri_b = square[[0, 1, 2]], square[[0, 1, 3]]  # overlap: triangle (0,0), (1,0), (0.5,0.5)
    point, depth = deepest_point(tri_a, tri_b)
    r = 0.5 / (1 + np.sqrt(2))  # inradius of that right isosceles triangle (legs 1/sqrt(2))
    assert depth == pytest.approx(r)
    assert_close(point, [0.5, r])


#: Every built-in robot and b1 by path; all but paper and solo12 only in the slow suite (20-160 s each
#: on a loaded 2-core machine: anymal_c 161 s, b1 ~100 s).
STABILITY_ROBOTS = [pytest.param(n, marks=pytest.mark.slow) if n not in ("paper", "solo12") else n
                    for n in (*ROBOT_NAMES, "b1")]


@pytest.mark.parametrize("name", STABILITY_ROBOTS)
def test_walk_is_statically_stable(name, erd):
    """Along a full cycle: the CoM (Pinocchio's, of the actual IK configuration) stays at least
    MIN_COM_MARGIN_M inside the support triangle and the paper's GRF model gives f_z >= 0."""
    robot = load_robot(str(erd / "b1_description/urdf/b1.urdf") if name == "b1" else name)
    plan = gait_plan(robot, WALK)
    result = static_stability(plan, IkTorques(plan, CasadiReducedDynamics(robot)), WALK.period, STABILITY_DT_TEST)
    assert result["min_com_margin_m"] >= MIN_COM_MARGIN_M, result
    assert result["min_fz_N"] >= 0.0, result


@pytest.mark.parametrize("name", ["paper", "solo12", "go1"])  # analytic IK, numeric IK
@pytest.mark.parametrize("gait", [TROT, WALK], ids=["trot", "walk"])
def test_ik_target_is_consistent(name, gait):
    """FK(q(t)) puts each foot where the plan says relative to the trunk; qd, qdd are the
    derivatives of q."""
    robot = load_robot(name)
    plan = gait_plan(robot, gait)
    kin = robot_kinematics(robot)
    t = 0.37
    r = ik_target(plan, t)
    for i in range(4):
        foot = np.asarray(kin[i].foot_position(r.q_r[3 * i : 3 * i + 3])).ravel()
        assert_close(foot, plan.foot(i, t)[0] - plan.trunk(t)[0])
    rp, rm = ik_target(plan, t + H, r.q_r[:12]), ik_target(plan, t - H, r.q_r[:12])
    assert_close(r.qd_r, (rp.q_r - rm.q_r) / (2 * H), rel=REL_TOL_DIFF, what="qd = dq/dt")
    assert_close(r.qdd_r, (rp.qd_r - rm.qd_r) / (2 * H), rel=REL_TOL_DIFF, what="qdd = dqd/dt")


#: The batched target against the one-at-a-time one: both polish Newton's solution to the FK's
#: round-off from different starting points, so they differ by a few ulp of the signal's scale
#: times the legs' Jacobian condition number (~10): measured <= 4 eps on solo12, go2, anymal_c.
BATCH_REL_TOL = 64 * np.finfo(float).eps


@pytest.mark.parametrize("name", ["paper", "solo12", "anymal_c"])  # analytic IK, numeric IK (two leg forms)
def test_batched_ik_targets_equal_one_at_a_time(name):
    """``ik_targets`` (every target in one Gauss-Newton batch from the posture) gives what
    ``ik_target`` gives sample by sample from the previous sample's angles."""
    plan = gait_plan(load_robot(name), WALK)
    ts = np.linspace(0.0, plan.gait.period, 40)
    batch, guess = ik_targets(plan, ts), None
    for t, b in zip(ts, batch):
        one = ik_target(plan, float(t), guess)
        guess = one.q_r[:12]
        assert b.stance == one.stance
        for x, y, what in ((b.q_r, one.q_r, "q"), (b.qd_r, one.qd_r, "qd"), (b.qdd_r, one.qdd_r, "qdd")):
            assert np.all(np.isfinite(x)), what
            assert np.abs(x - y).max() <= BATCH_REL_TOL * np.abs(y).max(), (t, what)


def test_unreachable_target_in_a_batch_names_the_leg():
    """One foot out of reach among reachable ones: InputError naming that leg, not a wrong answer."""
    robot = load_robot("solo12")
    q = np.tile(gait_posture(robot), (3, 1))
    r = np.array([[robot_kinematics(robot)[i].foot_position(q[k, 3 * i : 3 * i + 3]).full().ravel() for i in range(4)]
                  for k in range(3)])
    np.testing.assert_allclose(feet_ik(robot, r, q), q, atol=1e-12)
    r[1, 2] += [0.0, 0.0, -1.0]  # BL one metre below its reach
    with pytest.raises(InputError, match="numeric IK for leg BL did not reach"):
        feet_ik(robot, r, q)


def test_closed_form_ik_is_chosen_by_the_leg_not_the_file(paper, tmp_path):
    """A copy of the paper's URDF is the same robot: its legs have the DH form, so it gets the
    closed-form IK and the same target; a URDF robot of another form does not."""
    copy = tmp_path / "copy.urdf"
    shutil.copy(paper.urdf, copy)
    robot = load_robot(str(copy))
    assert all(dh_form(leg) is not None for leg in robot.legs)
    assert not any(dh_form(leg) is not None for leg in load_robot("solo12").legs)
    a, b = ik_target(gait_plan(paper, WALK), 0.41), ik_target(gait_plan(robot, WALK), 0.41)
    np.testing.assert_array_equal(a.q_r, b.q_r)


@pytest.mark.parametrize("ts", [[0.1, np.nan], [np.inf], [], [[0.1]], [-0.1], [0.1 + 1j], ["0.1"]])
def test_ik_targets_refuse_times_that_are_not_times(ts):
    """NaN, inf, negative, complex, empty or 2-D times: InputError naming ts, not a ValueError deep in the plan."""
    with pytest.raises(InputError, match="ts has shape .*; expected a non-empty 1-D array of finite times >= 0"):
        ik_targets(gait_plan(load_robot("solo12"), TROT), np.array(ts, dtype=object if ts == ["0.1"] else None))


def test_ik_targets_refuse_a_non_finite_guess():
    with pytest.raises(InputError, match="q_guess"):
        ik_targets(gait_plan(load_robot("solo12"), TROT), np.array([0.1]), np.full(12, np.nan))
