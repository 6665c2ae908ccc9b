"""Inverse kinematics round-trips forward kinematics; unreachable targets are clear errors."""

from __future__ import annotations

import numpy as np
import pytest

from quadruped_dyn import paper_robot
from quadruped_dyn.errors import InputError
from quadruped_dyn.kinematics import analytic_ik, numeric_ik
from quadruped_dyn.leg import LEG_LABELS

from .conftest import assert_close


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
