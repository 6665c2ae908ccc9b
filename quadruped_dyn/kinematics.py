"""Leg kinematics, symbolic (CasADi SX), from the project's leg structure.

All quantities are in the trunk frame b, positions relative to the trunk origin:
joint frame placements (R_bi, p_bi), the foot position r, the foot's linear Jacobian
J = dr/dq w.r.t. the leg's own three joints, and Jdot qdot (the foot's classical
acceleration relative to the trunk when qddot = 0).

Inverse kinematics: ``analytic_ik`` for the paper's DH leg, ``numeric_ik`` for any leg.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cache

import casadi as ca
import numpy as np
import pinocchio as pin

from .errors import InputError
from .leg import Leg
from .leg_frames import axis_aligned
from .paper_robot import PARAMS, R_B0, PaperRobotParams, hip_position
from .robot import Robot
from .spatial import axis_rotation, dm, placement_rt
from .state import check_array


def joint_frames(leg: Leg, q: ca.SX) -> list[tuple[ca.SX, ca.SX]]:
    """(R_bi, p_bi) of the three joint frames (after their joint rotation) in the trunk frame,
    in the leg's canonical frames (``leg_frames.axis_aligned``: parallel to the trunk frame at
    q = 0, HFE and KFE origins slid along their axes)."""
    R, p = ca.SX.eye(3), ca.SX.zeros(3)
    frames = []
    for i, joint in enumerate(axis_aligned(leg).joints):
        Rf, pf = placement_rt(joint.placement)
        p = p + R @ pf
        R = R @ Rf @ axis_rotation(joint.axis, q[i])
        frames.append((R, p))
    return frames


def foot_position(leg: Leg, q: ca.SX) -> ca.SX:
    """Foot (contact point) position in the trunk frame, m."""
    leg = axis_aligned(leg)
    R3, p3 = joint_frames(leg, q)[-1]
    return p3 + R3 @ dm(leg.foot.p)


@dataclass(frozen=True)
class LegKinematics:
    """Named CasADi Functions of one leg: q (3,), qd (3,) -> b-frame quantities."""

    foot_position: ca.Function  # q -> r (3,)
    foot_jacobian: ca.Function  # q -> J (3, 3)
    foot_bias_acceleration: ca.Function  # q, qd -> Jdot qdot (3,)


def leg_kinematics(leg: Leg) -> LegKinematics:
    q, qd = ca.SX.sym("q", 3), ca.SX.sym("qd", 3)
    r = foot_position(leg, q)
    J = ca.jacobian(r, q)
    Jdot_qd = ca.jacobian(J @ qd, q) @ qd
    name = leg.label
    return LegKinematics(
        ca.Function(f"foot_position_{name}", [q], [r], ["q"], ["r"]),
        ca.Function(f"foot_jacobian_{name}", [q], [J], ["q"], ["J"]),
        ca.Function(f"foot_bias_acceleration_{name}", [q, qd], [Jdot_qd], ["q", "qd"], ["Jdot_qd"]),
    )


@cache
def robot_kinematics(robot: Robot) -> tuple[LegKinematics, ...]:
    """The four legs' kinematics Functions, built once per robot."""
    return tuple(leg_kinematics(leg) for leg in robot.legs)


# ----------------------------------------------------------------------------- inverse kinematics


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
    for _ in range(iterations):
        e = r - np.array(kin.foot_position(q)).ravel()
        if np.linalg.norm(e) < IK_POSITION_TOL:
            return q
        J = np.array(kin.foot_jacobian(q))
        q = q + np.linalg.solve(J.T @ J + 1e-9 * np.eye(3), J.T @ e)
    raise InputError(
        f"numeric IK for leg {robot.legs[leg_index].label} did not reach {np.round(r, 4)} m "
        f"(residual {np.linalg.norm(e):.2e} m); expected a target inside the leg's workspace"
    )


# ----------------------------------------------------------------------------- trunk pose from the feet


def pose_from_feet(
    r_b: np.ndarray, P_w: np.ndarray, roll: float | None = None, pitch_hint: float = 0.0
) -> tuple[np.ndarray, np.ndarray, float]:
    """Trunk pose (R, p) that best puts the body-frame foot points r_b (k, 3) on the world
    footholds P_w (k, 3), and the closure error: max_i |R r_i + p - P_i| (m), how far the
    stance legs are from reaching their footholds.

    Three or four feet: least-squares rigid fit (Kabsch, proper rotation). Two feet: R =
    Rz(psi) Ry(theta) Rx(roll) with R (r_1 - r_2) parallel to P_1 - P_2 (closed form; the
    roll is the trot's coordinate; of the two pitch solutions the one nearer ``pitch_hint``,
    e.g. the previous step's pitch, is taken)."""
    r_b, P_w = np.atleast_2d(np.asarray(r_b, dtype=float)), np.atleast_2d(np.asarray(P_w, dtype=float))
    k = r_b.shape[0]
    if k >= 3:
        rc, Pc = r_b - r_b.mean(axis=0), P_w - P_w.mean(axis=0)
        U, _, Vt = np.linalg.svd(rc.T @ Pc)
        D = np.diag([1.0, 1.0, np.sign(np.linalg.det(Vt.T @ U.T))])
        R = Vt.T @ D @ U.T
    elif k == 2 and roll is not None:
        c, s = np.cos(roll), np.sin(roll)
        u = np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]]) @ (r_b[0] - r_b[1])
        d = (P_w[0] - P_w[1]) / np.linalg.norm(P_w[0] - P_w[1]) * np.linalg.norm(u)
        rho, beta = np.hypot(u[0], u[2]), np.arctan2(u[0], u[2])
        base = np.arccos(np.clip(d[2] / rho, -1.0, 1.0))
        theta = min((base - beta, -base - beta),
                    key=lambda x: abs(np.arctan2(np.sin(x - pitch_hint), np.cos(x - pitch_hint))))
        w = np.array([u[0] * np.cos(theta) + u[2] * np.sin(theta), u[1]])
        psi = np.arctan2(d[1], d[0]) - np.arctan2(w[1], w[0])
        R = pin.rpy.rpyToMatrix(roll, theta, psi)
    else:
        raise InputError(f"a trunk pose needs 3 or 4 stance feet, or 2 and the roll angle; got {k} feet")
    p = P_w.mean(axis=0) - R @ r_b.mean(axis=0)
    closure = float(np.abs(np.linalg.norm(r_b @ R.T + p - P_w, axis=1)).max())
    return R, p, closure
