"""Pinocchio's own identities through the reference layer (project order), as in Pinocchio's
unittest/python/bindings_rnea.py; a permutation or conversion slip breaks them."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

from quadruped_dyn.model.state import NV_FULL, random_state
from quadruped_dyn.tolerances import FD_STEP, REL_TOL_FD, REL_TOL_TERMS
from tests.conftest import SEEDS, assert_close

ZERO = np.zeros(NV_FULL)


@pytest.mark.parametrize("seed", SEEDS)
def test_rnea_identities(robot, ref, seed):
    s = random_state(robot.lower, robot.upper, np.random.default_rng(seed))
    M = ref.mass_matrix(s.q)
    nle, g = ref.nonlinear_effects(s.q, s.v), ref.gravity(s.q)
    assert_close(nle, ref.rnea(s.q, s.v, ZERO), what="nle = rnea(q, v, 0)")
    assert_close(g, ref.rnea(s.q, ZERO, ZERO), what="G = rnea(q, 0, 0)")
    assert_close(ref.coriolis_matrix(s.q, s.v) @ s.v, nle - g, what="C v = nle - G")
    assert_close(M @ s.a + nle, ref.rnea(s.q, s.v, s.a), what="M a + C + G = rnea")
    assert_close(M, M.T, what="M symmetric")
    assert np.linalg.eigvalsh(M).min() > 0, "M not positive definite"


@pytest.mark.parametrize("seed", SEEDS)
def test_mdot_minus_2c_is_skew(robot, ref, seed):
    s = random_state(robot.lower, robot.upper, np.random.default_rng(seed))
    qp = ref.pin_q(s.q)
    vp = ref.pin_v(s.v)
    Mp = pin.crba(robot.model, ref.data, pin.integrate(robot.model, qp, FD_STEP * vp)).copy()
    Mm = pin.crba(robot.model, ref.data, pin.integrate(robot.model, qp, -FD_STEP * vp)).copy()
    Mdot = ref.project_matrix((Mp - Mm) / (2 * FD_STEP))
    N = Mdot - 2 * ref.coriolis_matrix(s.q, s.v)
    assert_close(N + N.T, np.zeros_like(N), rel=REL_TOL_FD * np.abs(Mdot).max(), what="Mdot - 2C skew")


@pytest.mark.parametrize("stance", [(0, 1, 2, 3), (1, 2, 3), (0, 3), ()])
def test_constrained_forward_dynamics(robot, ref, stance):
    """The KKT solution satisfies what defines it, checked with Pinocchio's own algorithms:
    stance feet have zero classical world acceleration, and rnea(q, v, a) - Jc^T f = (0, tau)."""
    rng = np.random.default_rng(4)
    s = random_state(robot.lower, robot.upper, rng)
    tau = rng.normal(scale=5.0, size=12)
    a, f_world = ref.constrained_forward_dynamics(s.q, s.v, tau, stance)
    R = pin.Quaternion(ref.pin_q(s.q)[3:7]).toRotationMatrix()
    feet_acc = ref.foot_accelerations(s.q, s.v, a)[list(stance)] @ R.T  # world frame
    assert np.abs(feet_acc).max(initial=0.0) <= REL_TOL_TERMS * max(1.0, np.abs(a).max())
    generalized = ref.rnea(s.q, s.v, a) - ref.contact_jacobian(s.q, stance).T @ f_world.ravel()
    assert_close(generalized, np.concatenate([np.zeros(6), tau]), what="equations of motion")
