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


def test_state_helpers_check_their_inputs():
    """rotation returned NaN for a zero quaternion and raised RuntimeError/ValueError for a short q;
    spatial_from_classical broadcast a (3, 1) a_b into a (3, 3) answer and passed NaN; random_state
    raised ValueError/OverflowError/AttributeError for swapped or NaN limits and an int seed."""
    q = full_q(np.eye(3), np.zeros(3), np.zeros(12))
    zero_quat = q.copy()
    zero_quat[3:7] = 0.0
    rng = np.random.default_rng(0)
    bad_calls = [
        (lambda: rotation(zero_quat), "zero quaternion"),
        (lambda: rotation(q[:5]), "shape"),
        (lambda: rotation("abc"), "string"),
        (lambda: rotation(np.full(19, np.nan)), "NaN"),
        (lambda: spatial_from_classical(np.ones(3), np.ones(3), np.ones((3, 1))), "shape"),
        (lambda: spatial_from_classical(np.full(3, np.nan), np.ones(3), np.ones(3)), "NaN"),
        (lambda: classical_from_spatial("abc", np.ones(3), np.ones(3)), "string"),
        (lambda: classical_from_spatial(np.ones(2), np.ones(2), np.ones(2)), "shape"),
        (lambda: random_state(np.ones(12), -np.ones(12), rng), "lower <= upper"),
        (lambda: random_state(np.full(12, -1e308), np.full(12, 1e308), rng), "finite"),
        (lambda: random_state(np.full(12, np.nan), np.ones(12), rng), "NaN"),
        (lambda: random_state(-np.ones(12), np.ones(12), 0), "Generator"),
    ]
    for call, match in bad_calls:
        with pytest.raises(InputError, match=match):
            call()
    assert_close(rotation(list(q)), np.eye(3))
    assert_close(spatial_from_classical([0, 0, 1], [1, 0, 0], [0, 0, 0]), np.array([0.0, -1.0, 0.0]))
