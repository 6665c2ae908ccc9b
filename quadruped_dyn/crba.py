"""Mass matrix by composite rigid bodies (CRBA), symbolic -- the fast form for generated C.

The paper builds M column by column from unit accelerations (Walker & Orin, in
``newton_euler``); both must agree to round-off (tested). Here, in the trunk frame b with
spatial vectors (linear, angular) at the trunk origin, each link has the spatial inertia
Y = (m, h = m c, I_o) (mass, first moment, rotational inertia about the trunk origin), and
  M_bb = sum of all Y,   M_b,j = F_j = Ic_j S_j,   M_ij = S_i . F_j (i before j in a leg),
with Ic_j the composite inertia of link j and the links below it and S_j = (p_j x a_j, a_j)
the joint's motion. Legs do not couple: the leg-leg blocks are structurally zero.
"""

from __future__ import annotations

import casadi as ca

from .kinematics import joint_frames
from .leg import LinkInertia
from .robot import Robot
from .spatial import dm, skew
from .state import NV_FULL

Inertia = tuple[ca.SX, ca.SX, ca.SX]  # (m, h, I_o)


def _body_inertia(link: LinkInertia, R: ca.SX, p: ca.SX) -> Inertia:
    """(m, h, I_o) of a link placed at (R, p) in b: first moment and inertia about b's origin."""
    c = p + R @ dm(link.com)
    C = skew(c)
    return ca.SX(link.mass), link.mass * c, R @ dm(link.inertia) @ R.T - link.mass * C @ C


def _add(Y1: Inertia, Y2: Inertia) -> Inertia:
    return Y1[0] + Y2[0], Y1[1] + Y2[1], Y1[2] + Y2[2]


def _apply(Y: Inertia, S: ca.SX) -> ca.SX:
    """Spatial inertia times motion S = (v, w): (m v + w x h, I_o w + h x v)."""
    m, h, I_o = Y
    v, w = S[:3], S[3:]
    return ca.vertcat(m * v + ca.cross(w, h), I_o @ w + ca.cross(h, v))


def mass_matrix_crba(robot: Robot, q_joints: ca.SX) -> ca.SX:
    """M (18, 18), sparse (leg-leg blocks absent), for the 12 joint angles."""
    M = ca.SX(ca.Sparsity(NV_FULL, NV_FULL))
    total = _body_inertia(robot.trunk, ca.SX.eye(3), ca.SX.zeros(3))
    for k, leg in enumerate(robot.legs):
        frames = joint_frames(leg, q_joints[3 * k : 3 * k + 3])
        links = [_body_inertia(link, R, p) for link, (R, p) in zip(leg.links, frames)]
        S = [ca.vertcat(ca.cross(p, R @ dm(joint.axis)), R @ dm(joint.axis)) for joint, (R, p) in zip(leg.joints, frames)]
        composite = links[2]
        for j in reversed(range(3)):
            if j < 2:
                composite = _add(links[j], composite)
            F = _apply(composite, S[j])
            col = 6 + 3 * k + j
            M[0:6, col] = F
            M[col, 0:6] = F.T
            for i in range(j + 1):
                M[6 + 3 * k + i, col] = M[col, 6 + 3 * k + i] = ca.dot(S[i], F)
        total = _add(total, composite)
    m_total, h_total, I_total = total
    H = skew(h_total)
    M[0:6, 0:6] = ca.vertcat(ca.horzcat(m_total * ca.SX.eye(3), -H), ca.horzcat(H, I_total))
    return M
