"""Derivatives of the dynamics (dynamics/derivatives.py) against Pinocchio's analytical
derivatives (computeRNEADerivatives, computeABADerivatives) and, for the tangent convention,
against finite differences along pinocchio.integrate."""

from __future__ import annotations

import numpy as np
import pytest

from quadruped_dyn.checks.finite_differences import ReducedFiniteDifferences, central, grf_derivatives_by_differences
from quadruped_dyn.dynamics.derivatives import full_derivatives, grf_derivatives, reduced_derivatives
from quadruped_dyn.errors import InputError, NumericalError
from quadruped_dyn.model.registry import ROBOT_NAMES
from quadruped_dyn.model.robot import load_robot
from quadruped_dyn.model.stance import stance_set
from quadruped_dyn.model.state import random_state, rotation
from quadruped_dyn.references.pinocchio import PinocchioDerivatives, PinocchioReference
from quadruped_dyn.tolerances import REL_TOL_DERIVATIVES, REL_TOL_FD_DERIVATIVES
from tests.conftest import SEEDS, assert_close

FAST_ROBOTS = ["paper", "solo12"]


def _check_full(robot, seeds=SEEDS):
    d, pd = full_derivatives(robot), PinocchioDerivatives(PinocchioReference(robot))
    for seed in seeds:
        rng = np.random.default_rng(seed)
        s = random_state(robot.lower, robot.upper, rng)
        names = ("dtau_dq", "dtau_dv", "dtau_da")
        for name, ours, theirs in zip(names, d.did_full(s.q, s.v, s.a), pd.rnea_derivatives(s.q, s.v, s.a)):
            assert_close(np.array(ours), theirs, REL_TOL_DERIVATIVES, f"{robot.name} did_full {name}")
        tau = rng.normal(scale=10.0, size=18)
        names = ("da_dq", "da_dv", "da_dtau")
        for name, ours, theirs in zip(names, d.dfd_full(s.q, s.v, tau), pd.aba_derivatives(s.q, s.v, tau)):
            assert_close(np.array(ours), theirs, REL_TOL_DERIVATIVES, f"{robot.name} dfd_full {name}")


@pytest.mark.parametrize("name", FAST_ROBOTS)
def test_full_derivatives_match_pinocchio(name):
    _check_full(load_robot(name))


def test_full_derivatives_match_pinocchio_b1_by_path(erd):
    _check_full(load_robot(str(erd / "b1_description/urdf/b1.urdf")), seeds=(0,))


@pytest.mark.slow
@pytest.mark.parametrize("name", ROBOT_NAMES)
def test_full_derivatives_match_pinocchio_every_robot(name):
    _check_full(load_robot(name))


def test_q_derivative_is_along_pinocchio_integrate(paper):
    """The convention itself, without Pinocchio's derivatives: central differences of the project's
    rnea along pinocchio.integrate(q, h e_k) equal did_full's column k (18 columns, body-frame trunk
    increment); differences along the quaternion's entries do not (they are a different thing)."""
    ref = PinocchioReference(paper)
    pd = PinocchioDerivatives(ref)
    d = full_derivatives(paper)
    s = random_state(paper.lower, paper.upper, np.random.default_rng(3))
    dq = np.array(d.did_full(s.q, s.v, s.a)[0])
    fd = central(lambda x: ref.rnea(pd.integrate(s.q, x), s.v, s.a), np.zeros(18))
    assert_close(dq, fd, REL_TOL_FD_DERIVATIVES, "did_full dtau_dq vs differences along integrate")
    assert np.all(dq[:, :3] == 0.0)  # no dependence on the trunk position
    # a world-frame rotation increment (R -> exp([dw]x) R) gives other columns: the convention matters
    R = rotation(s.q)
    world = dq[:, 3:6] @ R.T  # the columns a world-frame increment would have
    assert np.abs(world - dq[:, 3:6]).max() > 1e-3 * np.abs(dq).max()


@pytest.mark.parametrize("name", FAST_ROBOTS)
def test_did_full_equals_the_literal_tangent_jacobian(name):
    """did_full's shortcuts (rotation columns -M[:, 0:3] [g_b]x, no position columns) against CasADi's
    Jacobian of the whole rnea with respect to q times d q / d dq of pinocchio.integrate (did_full_ad)."""
    robot = load_robot(name)
    d = full_derivatives(robot)
    for seed in (0, 1):
        s = random_state(robot.lower, robot.upper, np.random.default_rng(seed))
        for k, (ours, literal) in enumerate(zip(d.did_full(s.q, s.v, s.a), d.did_full_ad(s.q, s.v, s.a))):
            assert_close(np.array(ours), np.array(literal), REL_TOL_DERIVATIVES, f"{name} did_full output {k}")


@pytest.mark.parametrize("bad", ["nan", "shape", "zero_quat"])
def test_bad_input_is_input_error(paper, bad):
    d = full_derivatives(paper)
    s = random_state(paper.lower, paper.upper, np.random.default_rng(0))
    q = s.q.copy()
    if bad == "nan":
        q[8] = np.nan
    elif bad == "shape":
        q = q[:18]
    else:
        q[3:7] = 0.0
    with pytest.raises(InputError):
        d.did_full(q, s.v, s.a)
    with pytest.raises(InputError):
        d.dfd_full(q, s.v, s.a)


# ----------------------------------------------------------------------------- reduced model, GRF

def reduced_point(robot, n, rng):
    import pinocchio as pin

    qj = np.clip(robot.standing_q + rng.normal(scale=0.05, size=12), robot.lower, robot.upper)
    R = pin.rpy.rpyToMatrix(*rng.normal(scale=0.1, size=3))
    quat = pin.Quaternion(R).coeffs()
    q_r = np.append(qj, pin.rpy.matrixToRpy(R)[0])[:n]
    return q_r, rng.normal(size=n), rng.normal(scale=5.0, size=n), quat


def _check_reduced(robot, stance_name, seed=0):
    d = reduced_derivatives(robot, stance_name)
    q_r, qd, tau, quat = reduced_point(robot, d.n, np.random.default_rng(seed))
    ours = d.dfd_r(q_r, qd, tau, quat)
    expected = ReducedFiniteDifferences(PinocchioReference(robot), d.stance).dfd_r(q_r, qd, tau, quat)
    assert np.all(ours[0][:, 12:] == 0.0)  # the roll is read from quat
    for name, o, e, tol in zip(("dqdd_dq", "dqdd_dqd", "M_r^-1", "dqdd_dtheta"), ours, expected,
                               (REL_TOL_FD_DERIVATIVES, REL_TOL_FD_DERIVATIVES, REL_TOL_DERIVATIVES, REL_TOL_FD_DERIVATIVES)):
        assert_close(o, e, tol, f"{robot.name} {stance_name} {name}")


@pytest.mark.parametrize("stance", ["FR+BL+BR", "FL+BR"])
def test_reduced_derivatives_match_reference_differences(paper, stance):
    _check_reduced(paper, stance)


def grf_point(robot, rng):
    """A random state with the joints near standing (every GRF system well conditioned)."""
    s = random_state(robot.lower, robot.upper, rng)
    q = s.q.copy()
    q[7:] = np.clip(robot.standing_q + rng.normal(scale=0.05, size=12), robot.lower, robot.upper)
    return q, s.v, s.a


def _check_grf(robot, stance_name, seed=0):
    q, v, a = grf_point(robot, np.random.default_rng(seed))
    ours = [np.array(x) for x in grf_derivatives(robot, stance_name)(q, v, a)]
    expected = grf_derivatives_by_differences(PinocchioReference(robot), stance_set(stance_name), q, v, a)
    for name, o, e in zip(("dlambda_dq", "dlambda_dv", "dlambda_da"), ours, expected):
        assert_close(o, e, REL_TOL_FD_DERIVATIVES, f"{robot.name} dgrf_{stance_name} {name}")


@pytest.mark.parametrize("stance", ["FL+FR+BL+BR", "FR+BL+BR", "FL+BR"])
def test_grf_derivatives_match_reference_differences(paper, stance):
    _check_grf(paper, stance)


@pytest.mark.slow
@pytest.mark.parametrize("name", ROBOT_NAMES)
def test_reduced_and_grf_derivatives_every_robot(name):
    robot = load_robot(name)
    for stance in ("FL+FR+BL+BR", "FR+BL+BR", "FL+BR", "FL+BL"):
        _check_reduced(robot, stance)
        _check_grf(robot, stance)


def test_reduced_derivatives_bad_input(paper):
    d = reduced_derivatives(paper, "FL+BR")
    q_r, qd, tau, quat = reduced_point(paper, 13, np.random.default_rng(0))
    with pytest.raises(InputError):
        d.dfd_r(q_r[:12], qd, tau, quat)
    with pytest.raises(InputError):
        d.dfd_r(q_r, qd, np.full(13, np.inf), quat)
    with pytest.raises(InputError):
        d.dfd_r(q_r, qd, tau, np.zeros(4))
    with pytest.raises(InputError):
        reduced_derivatives(paper, "FL")


def test_reduced_derivatives_numerical_outcomes_are_numerical_errors(paper):
    """As ReducedModel (docs/reliability.md §6-§7): the front pair at a level trunk (degenerate) and
    a trot pair with the trunk pitched 90 deg were InputErrors ('gives a non-finite ...'), and a
    singular M_r too, from dfd_r's own copy of the condition check."""
    front, trot = reduced_derivatives(paper, "FL+FR"), reduced_derivatives(paper, "FL+BR")
    q_r, z = np.r_[paper.standing_q, 0.0], np.zeros(13)
    level = np.array([0.0, 0.0, 0.0, 1.0])
    pitched = np.array([0.0, np.sin(np.pi / 4), 0.0, np.cos(np.pi / 4)])
    for call in (lambda: front.dfd_r(q_r, z, z, level), lambda: front.did_r(q_r, z, z, level),
                 lambda: front.velocity_map(q_r, level), lambda: trot.dfd_r(q_r, z, z, pitched)):
        with pytest.raises(NumericalError, match="degenerate"):
            call()
    assert all(np.all(np.isfinite(x)) for x in trot.dfd_r(q_r, z, z, level))

