"""The IK reference of a gait plan: joint angles, rates and accelerations (docs/formulation.md §9.2).

The trunk follows ``Plan.trunk`` with R = I, so each foot's position relative to the trunk,
in the trunk frame, is r = P - p, with rate Pd - pd and classical acceleration Pdd - pdd. Leg
IK by what the leg is: the closed form for a leg of the paper's DH form (``dh_form``),
damped Gauss-Newton otherwise, polished by Newton steps to the round-off of the leg's FK.
Then qd = J^-1 rd and qdd = J^-1 (rdd - Jdot qd).
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cache

import casadi as ca
import numpy as np

from quadruped_dyn.dynamics.kinematics import robot_feet, robot_kinematics
from quadruped_dyn.experiment.gait import Plan, gait_posture
from quadruped_dyn.experiment.ik import analytic_ik, numeric_ik
from quadruped_dyn.model.paper_robot import PaperRobotParams, dh_form
from quadruped_dyn.model.robot import Robot

#: Newton steps after numeric IK has converged to IK_POSITION_TOL: each squares the relative
#: error, so two take 1e-12 m to the FK's own round-off (~1e-17 m).
POLISH_STEPS = 2


@dataclass(frozen=True)
class ReferenceSample:
    """The reference at one time: reduced coordinates (12 joints in FL, FR, BL, BR x HAA, HFE,
    KFE order, + the roll phi = 0 for a gait with two-feet phases), rad, rad/s, rad/s^2."""

    q_r: np.ndarray
    qd_r: np.ndarray
    qdd_r: np.ndarray
    stance: tuple[int, ...]


@cache
def leg_dh_forms(robot: Robot) -> tuple[PaperRobotParams | None, ...]:
    """``dh_form`` of each leg, decided once per robot (it compares placements: far costlier
    than the IK it selects, which runs at every right-hand-side evaluation)."""
    return tuple(dh_form(leg) for leg in robot.legs)


def leg_ik(robot: Robot, i: int, r: np.ndarray, guess: np.ndarray) -> np.ndarray:
    """Joint angles (3,) putting foot i at r (trunk frame, m)."""
    params = leg_dh_forms(robot)[i]
    if params is not None:
        return analytic_ik(robot.legs[i].label, r, params)
    q = numeric_ik(robot, i, r, guess)
    kin = robot_kinematics(robot)[i]
    for _ in range(POLISH_STEPS):
        q = q + np.linalg.solve(np.asarray(kin.foot_jacobian(q)), r - np.asarray(kin.foot_position(q)).ravel())
    return q


@cache
def robot_bias_accelerations(robot: Robot) -> ca.Function:
    """q, qd (12,) -> Jdot qd (3, 4): each leg's ``foot_bias_acceleration`` in one call."""
    kin = robot_kinematics(robot)
    q, qd = ca.SX.sym("q", 12), ca.SX.sym("qd", 12)
    return ca.Function("bias", [q, qd], [ca.horzcat(*[kin[i].foot_bias_acceleration(q[3 * i : 3 * i + 3],
                                                                                       qd[3 * i : 3 * i + 3])
                                                      for i in range(4)])])


def reference(plan: Plan, t: float, q_guess: np.ndarray | None = None) -> ReferenceSample:
    """IK of the plan at time t (``q_guess``: joint angles (12,) near the answer, for numeric IK)."""
    robot = plan.robot
    guess = gait_posture(robot) if q_guess is None else q_guess
    p, pd, pdd = plan.trunk(t)
    q = np.zeros(12)
    rd, rdd = np.zeros((4, 3)), np.zeros((4, 3))
    for i in range(4):
        P, Pd, Pdd = plan.foot(i, t)
        rd[i], rdd[i] = Pd - pd, Pdd - pdd  # trunk frame = world orientation (R = I)
        q[3 * i : 3 * i + 3] = leg_ik(robot, i, P - p, guess[3 * i : 3 * i + 3])
    J = np.asarray(robot_feet(robot)(q)[1]).reshape(3, 4, 3).transpose(1, 0, 2)  # (leg, row, joint)
    qd = np.linalg.solve(J, rd[:, :, None]).ravel()
    bias = np.asarray(robot_bias_accelerations(robot)(q, qd)).T
    qdd = np.linalg.solve(J, (rdd - bias)[:, :, None]).ravel()
    extra = np.zeros(plan.gait.n_coords - 12)  # roll, its rate and acceleration: 0 with R = I
    return ReferenceSample(np.append(q, extra), np.append(qd, extra), np.append(qdd, extra), plan.stance(t))
