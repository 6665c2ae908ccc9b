"""State conventions: project <-> Pinocchio conversions, classical vs spatial acceleration."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

from quadruped_dyn.errors import InputError
from quadruped_dyn.model.state import classical_from_spatial, full_q, random_state, rotation, spatial_from_classical
from quadruped_dyn.references.pinocchio import PinocchioReference
from tests.conftest import SEEDS, assert_close


@pytest.mark.parametrize("seed", SEEDS)
def test_round_trip(robot, seed):
    ref = PinocchioReference(robot)
    s = random_state(robot.lower, robot.upper, np.random.default_rng(seed))
    assert_close(ref.project_q(ref.pin_q(s.q)), s.q)
    assert_close(ref.project_v(ref.pin_v(s.v)), s.v)
    # joints land where Pinocchio's own name lookup says
    qp = ref.pin_q(s.q)
    for k, name in enumerate(robot.joint_names):
        assert qp[robot.model.joints[robot.model.getJointId(name)].idx_q] == s.q[7 + k]
    assert_close(rotation(s.q), pin.Quaternion(qp[3:7]).toRotationMatrix())


@pytest.mark.parametrize("seed", SEEDS)
def test_classical_body_acceleration_matches_pinocchio(robot, seed):
    """a_b = R^T pddot: Pinocchio's classical acceleration of the trunk frame, from v and the
    spatial vdot. Feeding the classical a_b as if it were Pinocchio's a fails this test."""
    ref = PinocchioReference(robot)
    rng = np.random.default_rng(seed)
    s = random_state(robot.lower, robot.upper, rng)
    a_b = rng.normal(size=3)
    v_b, omega_b = s.v[:3], s.v[3:6]
    a = s.a.copy()
    a[:3] = spatial_from_classical(omega_b, v_b, a_b)
    pin.forwardKinematics(robot.model, ref.data, ref.pin_q(s.q), ref.pin_v(s.v), ref.pin_v(a))
    classical = pin.getClassicalAcceleration(robot.model, ref.data, 1, pin.ReferenceFrame.LOCAL).linear
    assert_close(classical, a_b)
    assert_close(classical_from_spatial(omega_b, v_b, a[:3]), a_b)
    spatial = pin.getAcceleration(robot.model, ref.data, 1, pin.ReferenceFrame.LOCAL).linear
    assert np.abs(spatial - a_b).max() > 1e-3, "classical and spatial coincide: test state too tame"


def test_full_q_rejects_bad_input():
    with pytest.raises(InputError, match="rotation"):
        full_q(np.diag([1.0, 1.0, -1.0]), np.zeros(3), np.zeros(12))
    with pytest.raises(InputError, match="shape"):
        full_q(np.eye(3), np.zeros(2), np.zeros(12))
    with pytest.raises(InputError, match="NaN"):
        full_q(np.eye(3), np.zeros(3), np.full(12, np.nan))
