"""The per-phase interpolant of the target torques against the exact IK and id_r: at random
times, at the nodes and across a stance switch, and a short run driven by it against the same run
driven by the exact evaluation (their difference within what one ulp of initial state makes)."""

from __future__ import annotations

import numpy as np
import pytest

from quadruped_dyn.experiment.gait import TROT, WALK, gait_plan
from quadruped_dyn.experiment.simulate import IkTorques, TorqueLaw, reduced_dynamics, simulate_reduced
from quadruped_dyn.experiment.torque_table import IkTorqueTable, lobatto
from quadruped_dyn.tolerances import TABLE_REL_TOL

PAPER = TorqueLaw("paper", roll_applied=True)


def _stack(sample):
    ref, tau = sample
    return np.concatenate([ref.q_r, ref.qd_r, ref.qdd_r, tau])


@pytest.mark.parametrize("robot_name, gait", [("paper", WALK), pytest.param("go2", TROT, marks=pytest.mark.slow)],
                         ids=["paper-walk", "go2-trot"])
def test_interpolant_matches_the_exact_target(robot_name, gait):
    from quadruped_dyn.model.robot import load_robot

    robot = load_robot(robot_name)
    plan = gait_plan(robot, gait)
    table = IkTorqueTable(plan, reduced_dynamics(robot, "c"))
    h = gait.phase_duration
    rng = np.random.default_rng(0)
    n = gait.n_coords
    for k in range(2):
        stance = plan.stance((k + 0.5) * h)
        times = np.concatenate([[k * h, (k + 1) * h], rng.uniform(k * h, (k + 1) * h, 20)])
        approx = np.array([_stack(table(float(t), stance)) for t in times])
        exact = np.array([_stack(table.exact(float(t), stance)) for t in times])
        groups = [slice(0, n), slice(n, 2 * n), slice(2 * n, 3 * n), slice(3 * n, None)]
        for g in groups:
            scale = np.abs(exact[:, g]).max()
            err = np.abs(approx[:, g] - exact[:, g]).max()
            assert np.isfinite(err) and err <= 2 * TABLE_REL_TOL * scale, (k, g, err / scale)
        np.testing.assert_array_equal(approx[0], exact[0])  # a phase's start is a node: exact
    assert table.max_rel_error <= TABLE_REL_TOL


def test_step_ending_on_a_switch_keeps_its_phase():
    from quadruped_dyn.model.robot import load_robot

    robot = load_robot("paper")
    plan = gait_plan(robot, TROT)
    table = IkTorqueTable(plan, reduced_dynamics(robot, "c"))
    h = TROT.phase_duration
    first = plan.stance(0.5 * h)
    ref, tau = table(h, first)  # the end of phase 0, asked with phase 0's stance
    assert (0, first) in table._phases and tau.shape == (13,)
    exact_ref, exact_tau = table.exact(h, first)
    assert np.abs(tau - exact_tau).max() <= 2 * TABLE_REL_TOL * np.abs(exact_tau).max() + 1e-12


def test_lobatto_points_end_exactly_on_the_phase():
    nodes = lobatto(0.15, 0.3, 64)
    assert nodes[0] == 0.15 and nodes[-1] == 0.3 and np.all(np.diff(nodes) > 0)


@pytest.mark.slow
def test_run_on_the_interpolant_equals_the_exact_run_to_round_off(paper):
    """0.3 s of the paper trot (one phase and a switch): the table-driven run differs from the
    exact-driven one by no more than ~10x what a one-ulp change of the initial state makes."""
    plan = gait_plan(paper, TROT)
    dyn = reduced_dynamics(paper, "c")
    exact = IkTorques(plan, dyn)
    table = IkTorqueTable(plan, dyn)
    a = simulate_reduced(plan, dyn, PAPER, horizon=0.35, dt=5e-2, ik=exact)
    twin = simulate_reduced(plan, dyn, PAPER, horizon=0.35, dt=5e-2, ik=exact, initial_ulps=1)
    b = simulate_reduced(plan, dyn, PAPER, horizon=0.35, dt=5e-2, ik=table)
    assert a.stopped_at is None and b.stopped_at is None
    spread = max(np.abs(twin.q - a.q).max(), 1e-15)
    diff = np.abs(b.q - a.q).max()
    assert np.isfinite(diff) and diff <= 10 * spread + 1e-14, (diff, spread)


def test_all_feet_in_one_call_equal_the_per_leg_functions(paper):
    """``robot_feet`` (the simulations' one-call kinematics) gives the per-leg functions' values bit for bit."""
    from quadruped_dyn.dynamics.kinematics import robot_feet, robot_kinematics

    feet, kin = robot_feet(paper), robot_kinematics(paper)
    rng = np.random.default_rng(1)
    for _ in range(10):
        q = rng.normal(size=12)
        r, J = (np.asarray(x) for x in feet(q))
        for i in range(4):
            s = slice(3 * i, 3 * i + 3)
            np.testing.assert_array_equal(r[:, i], np.asarray(kin[i].foot_position(q[s])).ravel())
            np.testing.assert_array_equal(J[:, s], np.asarray(kin[i].foot_jacobian(q[s])))


def test_rigid_contact_fast_path_equals_the_kkt_solve_bit_for_bit(paper):
    """The physics check's per-evaluation KKT solve gives ``constrained_forward_dynamics``'s a exactly."""
    from quadruped_dyn.experiment.rigid_contact import _kkt_accelerations
    from quadruped_dyn.references.pinocchio import PinocchioReference

    ref = PinocchioReference(paper)
    rng = np.random.default_rng(2)
    for stance in [(0, 3), (0, 1, 3), (0, 1, 2, 3), ()]:
        quat = rng.normal(size=4)
        q = np.concatenate([rng.normal(size=3), quat / np.linalg.norm(quat), rng.normal(size=12) * 0.3])
        v, tau = rng.normal(size=18), rng.normal(size=12)
        expected, _ = ref.constrained_forward_dynamics(q, v, tau, stance)
        np.testing.assert_array_equal(_kkt_accelerations(ref, q, v, tau, stance), expected)
