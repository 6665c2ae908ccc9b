"""Inverse kinematics round-trips forward kinematics; unreachable targets are clear errors."""

from __future__ import annotations

import numpy as np
import pytest

from quadruped_dyn.errors import InputError
from quadruped_dyn.experiment.ik import analytic_ik, numeric_ik
from quadruped_dyn.model import paper_robot
from quadruped_dyn.model.leg import LEG_LABELS
from tests.conftest import assert_close


@pytest.mark.parametrize("label", LEG_LABELS)
def test_analytic_ik_round_trip(paper, label):
    rng = np.random.default_rng(0)
    leg = paper.legs[LEG_LABELS.index(label)]
    lower, upper = np.array([j.lower for j in leg.joints]), np.array([j.upper for j in leg.joints])
    for _ in range(20):
        q = rng.uniform(lower, upper)
        q_ik = analytic_ik(label, leg.foot_position(q))
        assert_close(q_ik, q, what="IK(FK(q))")


def test_analytic_ik_standing():
    for label in LEG_LABELS:
        target = paper_robot.hip_position(label) + [0, 0, -np.sqrt(2) * 0.2]
        assert_close(analytic_ik(label, target), paper_robot.STANDING_Q)


def test_numeric_ik_round_trip(robot):
    rng = np.random.default_rng(1)
    for i, leg in enumerate(robot.legs):
        q = np.clip(robot.standing_q[3 * i : 3 * i + 3] + rng.normal(scale=0.1, size=3),
                    [j.lower for j in leg.joints], [j.upper for j in leg.joints])
        target = leg.foot_position(q)
        assert_close(leg.foot_position(numeric_ik(robot, i, target)), target, what="FK(IK(r))")


def test_unreachable_targets(paper):
    with pytest.raises(InputError, match="reachable distances"):
        analytic_ik("FL", paper_robot.hip_position("FL") + [0, 0, -0.5])
    with pytest.raises(InputError, match="did not reach"):
        numeric_ik(paper, 0, paper_robot.hip_position("FL") + [0, 0, -0.5])
    with pytest.raises(InputError, match="shape"):
        analytic_ik("FL", np.zeros(2))


@pytest.mark.parametrize("k", [2, 3, 4])
def test_pose_from_feet_recovers_the_pose(k):
    import pinocchio as pin

    from quadruped_dyn.experiment.trunk_pose import pose_from_feet

    rng = np.random.default_rng(k)
    for _ in range(10):
        roll, pitch, yaw = rng.uniform(-0.5, 0.5, 3)
        R, p = pin.rpy.rpyToMatrix(roll, pitch, yaw), rng.normal(size=3)
        r_b = rng.normal(scale=0.3, size=(k, 3))
        hint = pitch + rng.normal(scale=0.05)  # two feet: two pitch solutions, the hint picks one
        R_fit, p_fit, closure = pose_from_feet(r_b, r_b @ R.T + p, roll if k == 2 else None, hint)
        assert_close(R_fit, R, what="R") and assert_close(p_fit, p, what="p")
        assert closure < 1e-12


def test_pose_from_feet_reports_closure():
    from quadruped_dyn.experiment.trunk_pose import pose_from_feet

    r_b = np.array([[0.2, 0.1, -0.3], [-0.2, 0.1, -0.3], [0.2, -0.1, -0.3]])
    P_w = r_b + [0.0, 0.0, 0.3]
    P_w[0, 0] += 0.03  # one foothold 3 cm away from where the leg reaches
    assert 0.005 < pose_from_feet(r_b, P_w)[2] < 0.03
    with pytest.raises(InputError, match="needs 3 or 4 stance feet, or 2 and the roll"):
        pose_from_feet(r_b[:2], P_w[:2])
