"""The paper's Newton-Euler in full coordinates: every term against Pinocchio, and identities."""

from __future__ import annotations

import dataclasses

import casadi as ca
import numpy as np
import pytest

from quadruped_dyn.checks.terms import run_check
from quadruped_dyn.dynamics.kinematics import joint_frames, robot_kinematics
from quadruped_dyn.dynamics.newton_euler import full_dynamics, hip_reaction_split, leg_newton_euler
from quadruped_dyn.math.rigid import LinkInertia
from quadruped_dyn.model.state import random_state, rotation
from quadruped_dyn.tolerances import FD_STEP, REL_TOL_FD
from tests.conftest import SEEDS, assert_close


def _np(x: object) -> np.ndarray:
    """Numeric array from a DM, or from an SX expression without free symbols."""
    if isinstance(x, ca.SX):
        x = ca.evalf(x)
    return np.asarray(x, dtype=float).squeeze()


@pytest.fixture(scope="module")
def fd(robot):
    return full_dynamics(robot)


@pytest.mark.parametrize("seed", SEEDS)
def test_terms_against_pinocchio(robot, ref, fd, seed):
    s = random_state(robot.lower, robot.upper, np.random.default_rng(seed))
    M, G = ref.mass_matrix(s.q), ref.gravity(s.q)
    assert_close(_np(fd.M_full_walker_orin(s.q)), M, what="M_full")
    assert_close(_np(fd.M_full_crba(s.q)), M, what="M_full by CRBA")
    assert_close(_np(fd.G_full_newton_euler(s.q)), G, what="G_full")
    assert_close(_np(fd.G_full_crb(s.q)), G, what="G_full by composite first moments")
    assert_close(_np(fd.C_full(s.q, s.v)), ref.nonlinear_effects(s.q, s.v) - G, what="C_full")
    assert_close(_np(fd.coriolis(s.q, s.v)), ref.coriolis_matrix(s.q, s.v), what="Coriolis matrix")
    R = rotation(s.q)
    expected = ref.rnea(s.q, s.v, s.a) - ref.contact_jacobian(s.q, (0, 1, 2, 3)).T @ np.concatenate([R @ f for f in s.f])
    w_res, tau = fd.id_full(s.q, s.v, s.a, s.f.ravel())
    assert_close(_np(tau), expected[6:], what="tau")
    assert_close(_np(w_res), expected[:6], what="base residual")


@pytest.mark.parametrize("seed", SEEDS)
def test_identities(robot, fd, seed):
    s = random_state(robot.lower, robot.upper, np.random.default_rng(seed))
    M = _np(fd.M_full_walker_orin(s.q))
    assert_close(_np(fd.M_full_ad(s.q)), M, what="Walker-Orin M = AD M")
    assert_close(_np(fd.M_full_crba(s.q)), M, what="Walker-Orin M = CRBA M")
    assert_close(M, M.T, what="M symmetric")
    assert np.linalg.eigvalsh(M).min() > 0
    w, tau = fd.id_full(s.q, s.v, s.a, np.zeros(12))
    lhs = np.concatenate([_np(w), _np(tau)])
    assert_close(lhs, M @ s.a + _np(fd.C_full(s.q, s.v)) + _np(fd.G_full_newton_euler(s.q)), what="id = M a + C + G")
    assert_close(_np(fd.coriolis(s.q, s.v)) @ s.v, _np(fd.C_full(s.q, s.v)), what="C(q, v) v = C_full")


@pytest.mark.parametrize("seed", SEEDS)
def test_mdot_minus_2c_skew(robot, fd, seed):
    """M depends on the joint angles only (body-frame coordinates): Mdot = dM/dq_j . qd_j."""
    s = random_state(robot.lower, robot.upper, np.random.default_rng(seed))
    dq = np.concatenate([np.zeros(7), s.v[6:]]) * FD_STEP
    Mdot = (_np(fd.M_full_walker_orin(s.q + dq)) - _np(fd.M_full_walker_orin(s.q - dq))) / (2 * FD_STEP)
    N = Mdot - 2 * _np(fd.coriolis(s.q, s.v))
    assert_close(N + N.T, np.zeros_like(N), rel=REL_TOL_FD * np.abs(Mdot).max(), what="Mdot - 2C skew")


@pytest.mark.parametrize("seed", SEEDS)
def test_jacobians_against_finite_differences(robot, seed):
    rng = np.random.default_rng(seed)
    q = rng.uniform(robot.lower, robot.upper)
    qd = rng.normal(size=12)
    for i, kin in enumerate(robot_kinematics(robot)):
        qi, qdi = q[3 * i : 3 * i + 3], qd[3 * i : 3 * i + 3]
        J = _np(kin.foot_jacobian(qi))
        J_fd = np.column_stack([
            (_np(kin.foot_position(qi + FD_STEP * e)) - _np(kin.foot_position(qi - FD_STEP * e))) / (2 * FD_STEP)
            for e in np.eye(3)
        ])
        assert_close(J, J_fd, rel=REL_TOL_FD, what="J vs finite differences")
        Jdot = (_np(kin.foot_jacobian(qi + FD_STEP * qdi)) - _np(kin.foot_jacobian(qi - FD_STEP * qdi))) / (2 * FD_STEP)
        assert_close(_np(kin.foot_bias_acceleration(qi, qdi)), Jdot @ qdi, rel=REL_TOL_FD, what="Jdot qdot")


def test_paper_split_of_the_hip_reaction(paper):
    """Eq. (1)-(2): suspended part + ground-force part = the recursion with the foot force, and
    the ground-force part of the torques is -J^T f (the paper's second inward pass)."""
    leg = paper.legs[3]
    syms = [ca.SX.sym(n, 3) for n in ("q", "qd", "qdd", "omega_b", "alpha_b", "a0", "f")]
    full = leg_newton_euler(leg, *syms)
    bar, hat = hip_reaction_split(leg, *syms)
    outputs = [x for forces in (full, bar, hat) for x in (forces.tau, forces.f1, forces.n1)]
    vals = [np.random.default_rng(5).normal(size=3) for _ in syms]
    out = [_np(x) for x in ca.Function("split", syms, outputs)(*vals)]
    for k, name in enumerate(("tau", "f1", "n1")):
        assert_close(out[3 + k] + out[6 + k], out[k], what=name)
    J = _np(robot_kinematics(paper)[3].foot_jacobian(vals[0]))
    assert_close(out[6], -J.T @ vals[6], what="tau from GRF")


@pytest.mark.parametrize("urdf", ["laikago_description/urdf/laikago.urdf", "b1_description/urdf/b1.urdf"])
def test_check_passes_on_other_quadrupeds(erd, urdf):
    from quadruped_dyn.model.robot import load_robot

    report = run_check(load_robot(str(erd / urdf)), samples=5)
    assert report.passed, report.table()


def test_joint_frames_are_rotations(paper):
    for R, _ in joint_frames(paper.legs[0], ca.DM([0.3, -0.2, 1.0])):
        R = _np(R)
        assert_close(R.T @ R, np.eye(3))


def test_check_fails_when_the_model_is_wrong():
    """A 1 % heavier trunk in the symbolic model must make the report fail (exit code 1 path)."""
    from quadruped_dyn.model.robot import load_robot

    good = load_robot("solo12")
    heavier = LinkInertia(good.trunk.mass * 1.01, good.trunk.com, good.trunk.inertia)
    report = run_check(dataclasses.replace(good, trunk=heavier), samples=2)
    assert not report.passed
    failed = {t.name for t in report.terms if not t.passed}
    assert {"M_full (Walker-Orin)", "G_full"} <= failed and "foot positions" not in failed
