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

from quadruped_dyn.math.rigid import axis_rotation, skew
from quadruped_dyn.math.spatial import dm, placement_rt
from quadruped_dyn.model.leg import Leg
from quadruped_dyn.model.leg_frames import axis_aligned
from quadruped_dyn.model.robot import Robot


def joint_frames(leg: Leg, q: ca.SX) -> list[tuple[ca.SX, ca.SX]]:
    """(R_bi, p_bi) of the three joint frames (after their joint rotation) in the trunk frame,
    in the leg's canonical frames (``leg_frames.axis_aligned``: parallel to the trunk frame at
    q = 0, HFE and KFE origins slid along their axes)."""
    return canonical_joint_frames(axis_aligned(leg), q)


def canonical_joint_frames(leg: Leg, q: ca.SX) -> list[tuple[ca.SX, ca.SX]]:
    """``joint_frames`` of a leg already in canonical frames (a leg template's: SX parameters allowed)."""
    R, p = ca.SX.eye(3), ca.SX.zeros(3)
    frames = []
    for i, joint in enumerate(leg.joints):
        Rf, pf = placement_rt(joint.placement)
        p = p + R @ pf
        R = R @ Rf @ axis_rotation(joint.axis, q[i])
        frames.append((R, p))
    return frames


def foot_position(leg: Leg, q: ca.SX) -> ca.SX:
    """Foot (contact point) position in the trunk frame, m."""
    return canonical_foot_position(axis_aligned(leg), q)


def canonical_foot_position(leg: Leg, q: ca.SX) -> ca.SX:
    """``foot_position`` of a leg already in canonical frames (a leg template's: SX parameters allowed)."""
    R3, p3 = canonical_joint_frames(leg, q)[-1]
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


# ----------------------------------------------------------------------------- trunk pose from the feet




@cache
def robot_feet(robot: Robot) -> ca.Function:
    """All four feet in one call (the simulations' hot path: one CasADi call instead of one per
    leg): q (12,) -> r (3, 4), the foot positions (trunk frame, m), and J (3, 12), each leg's
    ``foot_jacobian`` side by side. The same expressions as ``leg_kinematics``."""
    q = ca.SX.sym("q", 12)
    rs, Js = [], []
    for i, leg in enumerate(robot.legs):
        qi = q[3 * i : 3 * i + 3]
        r = foot_position(leg, qi)
        rs.append(r)
        Js.append(ca.jacobian(r, qi))
    return ca.Function("feet", [q], [ca.horzcat(*rs), ca.horzcat(*Js)], ["q"], ["r", "J"])


def feet_full(robot: Robot) -> ca.Function:
    """The four feet in full coordinates, for a whole-body controller: (q (19,), v (18,)) ->
    r_feet (12,): the foot positions relative to the trunk origin, trunk frame, m (FL, FR, BL, BR);
    J_feet (12, 18): the feet's velocities in the world, expressed in the trunk frame,
    R^T d/dt p_foot = J_feet v (rows of foot i: [I, -[r_i]x, J_i on its leg's joint columns]);
    Jdv_feet (12,): the rest of the feet's classical acceleration, R^T d2/dt2 p_foot = J_feet vdot
    + Jdv_feet (vdot as in the project's ``a``: d/dt of v), i.e. Jdot v + omega_b x (J_feet v).
    The quaternion of q does not enter (everything is in the trunk frame)."""
    q, v = ca.SX.sym("q", 19), ca.SX.sym("v", 18)
    joints, omega, qd = q[7:], v[3:6], v[6:]
    rows, r = [], []
    for i, leg in enumerate(robot.legs):
        ri = foot_position(leg, joints[3 * i : 3 * i + 3])
        Ji = ca.jacobian(ri, joints[3 * i : 3 * i + 3])
        legs = [Ji if k == i else ca.SX(3, 3) for k in range(4)]
        rows.append(ca.horzcat(ca.SX.eye(3), -skew(ri), *legs))
        r.append(ri)
    J = ca.vertcat(*rows)
    u = J @ v
    spin = ca.vertcat(*[ca.cross(omega, u[3 * i : 3 * i + 3]) for i in range(4)])
    Jdv = ca.jacobian(u, joints) @ qd + spin
    return ca.Function("feet_full", [q, v], [ca.vertcat(*r), J, Jdv], ["q", "v"], ["r_feet", "J_feet", "Jdv_feet"])
