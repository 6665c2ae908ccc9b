"""Inverse kinematics of one leg: closed form for the paper's DH leg, damped Gauss-Newton for any leg."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from quadruped_dyn.dynamics.kinematics import robot_kinematics
from quadruped_dyn.errors import InputError
from quadruped_dyn.model.paper_robot import PARAMS, R_B0, PaperRobotParams, hip_position
from quadruped_dyn.model.robot import Robot
from quadruped_dyn.model.state import check_array


def analytic_ik(label: str, r: np.ndarray, params: PaperRobotParams = PARAMS) -> np.ndarray:
    """Joint angles (HAA, HFE, KFE), rad, that put the paper DH leg's foot at ``r`` (trunk frame, m).

    Branch: the leg below the hip side (x_0 component > 0) and the knee forward (KFE < 0),
    as in the standing posture (90, 45, -90) deg. In frame 0 the foot is at
    (X cos t1, l2 sin t2 + l3 sin(t2 + t3), X sin t1) with X = l2 cos t2 + l3 cos(t2 + t3).
    """
    r = check_array("r", r, (3,))
    x0, y0, z0 = R_B0.T @ (r - hip_position(label, params))
    X = np.hypot(x0, z0)
    l2, l3 = params.l2, params.l3
    d = np.hypot(X, y0)
    c3 = (d**2 - l2**2 - l3**2) / (2 * l2 * l3)
    if not -1.0 <= c3 <= 1.0 or X < 1e-12:
        raise InputError(
            f"foot target {np.round(r, 4)} m is {d:.4f} m from the {label} hip; reachable distances are "
            f"[{abs(l2 - l3):.4f}, {l2 + l3:.4f}] m off the HAA axis"
        )
    t1 = np.arctan2(z0, x0)
    t3 = -np.arccos(c3)
    t2 = np.arctan2(y0, X) - np.arctan2(l3 * np.sin(t3), l2 + l3 * np.cos(t3))
    return np.array([t1, t2, t3])

#: Numeric IK stops when the foot is this close to the target, m (well below any
#: manufacturing tolerance, well above the round-off of a 3-joint FK, ~1e-16 m).
IK_POSITION_TOL = 1e-12

def numeric_ik(robot: Robot, leg_index: int, r: np.ndarray, q0: np.ndarray | None = None, iterations: int = 100) -> np.ndarray:
    """Joint angles (rad) putting leg ``leg_index``'s foot at ``r`` (trunk frame, m), by damped
    Gauss-Newton from ``q0`` (default: the robot's standing posture). Raises InputError if the
    target is not reached (out of reach or outside the leg's workspace branch)."""
    r = check_array("r", r, (3,))
    kin = robot_kinematics(robot)[leg_index]
    q = np.array(robot.standing_q[3 * leg_index : 3 * leg_index + 3] if q0 is None else q0, dtype=float)

    def fk(q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        return np.asarray(kin.foot_position(q[0])).T, np.asarray(kin.foot_jacobian(q[0]))[None]

    q, residual = gauss_newton(fk, r[None], q[None], iterations)
    if not residual[0] < IK_POSITION_TOL:
        raise not_reached(robot, leg_index, r, residual[0])
    return q[0]


def not_reached(robot: Robot, leg_index: int, r: np.ndarray, residual: float) -> InputError:
    """The error of a numeric IK that did not reach ``r`` (``residual`` m away)."""
    return InputError(
        f"numeric IK for leg {robot.legs[leg_index].label} did not reach {np.round(r, 4)} m "
        f"(residual {residual:.2e} m); expected a target inside the leg's workspace"
    )


FootKinematics = Callable[[np.ndarray], tuple[np.ndarray, np.ndarray]]


def gauss_newton(fk: FootKinematics, r: np.ndarray, q0: np.ndarray, iterations: int = 100
                 ) -> tuple[np.ndarray, np.ndarray]:
    """Damped Gauss-Newton for m independent 3-joint problems at once: q (m, 3) from q0 with
    fk(q) = (foot (m, 3), Jacobian (m, 3, 3)) reaching r (m, 3) (m), each problem iterated until
    its foot is within IK_POSITION_TOL, at most ``iterations`` steps. Returns (q, each foot's
    residual |r - foot| (m,), m): a residual not below IK_POSITION_TOL did not converge."""
    q = np.array(q0, dtype=float)
    for _ in range(iterations):
        foot, J = fk(q)
        residual = np.linalg.norm(r - foot, axis=1)
        active = ~(residual < IK_POSITION_TOL)  # NaN stays active
        if not active.any():
            break
        Ja, ea = J[active], (r - foot)[active]
        JT = Ja.transpose(0, 2, 1)
        q[active] += np.linalg.solve(JT @ Ja + 1e-9 * np.eye(3), JT @ ea[:, :, None])[:, :, 0]
    else:
        foot, _ = fk(q)
        residual = np.linalg.norm(r - foot, axis=1)
    return q, residual
