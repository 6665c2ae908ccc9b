"""The IK plan of a gait: joint angles, rates and accelerations (docs/experiment.md §3).

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
from quadruped_dyn.errors import InputError
from quadruped_dyn.experiment.gait import Plan, gait_posture
from quadruped_dyn.experiment.ik import IK_POSITION_TOL, analytic_ik, gauss_newton, not_reached
from quadruped_dyn.model.paper_robot import PaperRobotParams, dh_form
from quadruped_dyn.model.robot import Robot
from quadruped_dyn.model.state import check_array

#: Newton steps after numeric IK has converged to IK_POSITION_TOL: each squares the relative
#: error, so two take 1e-12 m to the FK's own round-off (~1e-17 m).
POLISH_STEPS = 2


@dataclass(frozen=True)
class IkTarget:
    """The target at one time: reduced coordinates (12 joints in FL, FR, BL, BR x HAA, HFE,
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


def feet_ik(robot: Robot, r: np.ndarray, guess: np.ndarray) -> np.ndarray:
    """Joint angles (N, 12) putting the four feet at r (N, 4, 3) (trunk frame, m), N targets at
    once: the closed form for a leg of the paper's DH form; otherwise damped Gauss-Newton from
    ``guess`` (N, 12) (``ik.gauss_newton``, every foot of every target in one batch) polished by
    POLISH_STEPS Newton steps. InputError naming the leg if a target is not reached."""
    n = len(r)
    q = np.array(guess, dtype=float).reshape(n, 4, 3)
    numeric = [i for i, params in enumerate(leg_dh_forms(robot)) if params is None]
    for i, params in enumerate(leg_dh_forms(robot)):
        if params is not None:
            q[:, i] = [analytic_ik(robot.legs[i].label, x, params) for x in r[:, i]]
    if numeric:
        feet = robot_feet(robot).map(n)

        def fk(qs: np.ndarray) -> tuple[np.ndarray, np.ndarray]:  # qs (n * len(numeric), 3)
            full = q.copy()
            full[:, numeric] = qs.reshape(n, len(numeric), 3)
            foot, J = feet(full.reshape(n, 12).T)
            foot = np.asarray(foot).reshape(3, n, 4).transpose(1, 2, 0)  # (target, leg, xyz)
            J = np.asarray(J).reshape(3, n, 4, 3).transpose(1, 2, 0, 3)  # (target, leg, row, joint)
            return foot[:, numeric].reshape(-1, 3), J[:, numeric].reshape(-1, 3, 3)

        target = r[:, numeric].reshape(-1, 3)
        qs, residual = gauss_newton(fk, target, q[:, numeric].reshape(-1, 3))
        if not (residual < IK_POSITION_TOL).all():
            k = int(np.argmax(~(residual < IK_POSITION_TOL)))
            raise not_reached(robot, numeric[k % len(numeric)], target[k], float(residual[k]))
        for _ in range(POLISH_STEPS):
            foot, J = fk(qs)
            qs = qs + np.linalg.solve(J, (target - foot)[:, :, None])[:, :, 0]
        q[:, numeric] = qs.reshape(n, len(numeric), 3)
    return q.reshape(n, 12)


@cache
def robot_bias_accelerations(robot: Robot) -> ca.Function:
    """q, qd (12,) -> Jdot qd (3, 4): each leg's ``foot_bias_acceleration`` in one call."""
    kin = robot_kinematics(robot)
    q, qd = ca.SX.sym("q", 12), ca.SX.sym("qd", 12)
    return ca.Function("bias", [q, qd], [ca.horzcat(*[kin[i].foot_bias_acceleration(q[3 * i : 3 * i + 3],
                                                                                       qd[3 * i : 3 * i + 3])
                                                      for i in range(4)])])


def ik_target(plan: Plan, t: float, q_guess: np.ndarray | None = None) -> IkTarget:
    """IK of the plan at time t (``q_guess``: joint angles (12,) near the answer, for numeric IK)."""
    return ik_targets(plan, np.array([t]), q_guess)[0]


def ik_targets(plan: Plan, ts: np.ndarray, q_guess: np.ndarray | None = None) -> list[IkTarget]:
    """``ik_target`` at each time of ``ts`` (s), in one batch (numeric IK of every target from the
    same ``q_guess``, default the gait's posture). InputError unless ``ts`` is a non-empty 1-D array of
    finite times >= 0 and ``q_guess`` (12,) finite."""
    ts = np.asarray(ts)
    if ts.dtype.kind not in "biuf" or ts.ndim != 1 or not len(ts) or not np.all(np.isfinite(ts)) or not np.all(ts >= 0):
        raise InputError(f"ts has shape {ts.shape} and dtype {ts.dtype}; expected a non-empty 1-D array of finite "
                         "times >= 0 (s)")
    ts = ts.astype(float)
    robot = plan.robot
    n = len(ts)
    guess = np.tile(gait_posture(robot) if q_guess is None else check_array("q_guess", q_guess, (12,)), (n, 1))
    r, rd, rdd = np.zeros((n, 4, 3)), np.zeros((n, 4, 3)), np.zeros((n, 4, 3))
    for k, t in enumerate(ts):
        p, pd, pdd = plan.trunk(float(t))
        for i in range(4):
            P, Pd, Pdd = plan.foot(i, float(t))
            r[k, i], rd[k, i], rdd[k, i] = P - p, Pd - pd, Pdd - pdd  # trunk frame = world orientation (R = I)
    q = feet_ik(robot, r, guess)
    J = np.asarray(robot_feet(robot).map(n)(q.T)[1]).reshape(3, n, 4, 3).transpose(1, 2, 0, 3)  # (t, leg, row, joint)
    qd = np.linalg.solve(J, rd[..., None]).reshape(n, 12)
    bias = np.asarray(robot_bias_accelerations(robot).map(n)(q.T, qd.T)).reshape(3, n, 4).transpose(1, 2, 0)
    qdd = np.linalg.solve(J, (rdd - bias)[..., None]).reshape(n, 12)
    extra = np.zeros(plan.gait.n_coords - 12)  # roll, its rate and acceleration: 0 with R = I
    return [IkTarget(np.append(q[k], extra), np.append(qd[k], extra), np.append(qdd[k], extra),
                            plan.stance(float(ts[k]))) for k in range(n)]
