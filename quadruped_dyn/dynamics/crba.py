"""Mass matrix and gravity by composite rigid bodies, symbolic -- the fast forms for generated C.

The paper builds M column by column from unit accelerations and G from the Newton-Euler
recursion with v = 0, a = 0 (``newton_euler``); these must agree with it to round-off (tested).

Each leg is taken in its canonical joint frames (``leg_frames.axis_aligned``): joint i
rotates frame i about a constant axis a_i (a coordinate axis for the robots here) relative
to frame i-1, whose origin it sits at P_i from (frame -1 is the trunk frame b). A body's
spatial inertia at a frame's origin, in its axes, is Y = (m, h = m c, I_o) (mass, first
moment, rotational inertia about the origin). Backwards along the leg, in local frames:
  composite   Yc_2 = Y_2,  Yc_i = Y_i + X_{i+1}(Yc_{i+1})   (X: carried into the parent frame);
  force       F_j = Yc_j S_j with S_j = (0, a_j) the joint's motion at its own origin,
              carried to frames j-1, ..., 0 and b:  M_ij = a_i . n(F_j in frame i),
              M_b,j = F_j in frame b;  M_bb = the sum of all composite inertias in b;
  gravity     G_j = -a_j . (h_c,j x g_j), g_j = gravity in frame j, h_c,j the first moment of
              link j and the links below it about joint j's origin; G_b = -(m g_b, h x g_b).
Legs do not couple: the leg-leg blocks of M are structurally zero. Only one triangle of each
symmetric 3 x 3 block is computed (the other is the same expression).
"""

from __future__ import annotations

import casadi as ca
import numpy as np

from quadruped_dyn.math.rigid import LinkInertia, axis_rotation, skew
from quadruped_dyn.math.spatial import dm, stacked
from quadruped_dyn.model.leg import Leg
from quadruped_dyn.model.leg_frames import axis_aligned
from quadruped_dyn.model.robot import Robot
from quadruped_dyn.model.state import NV_FULL

Inertia = tuple[float | ca.SX, ca.SX, ca.SX]  # (m kg, h kg m, I_o kg m^2) at a frame's origin, in its axes

#: A leg's part of M, in order: (name, rows, columns), each stacked column by column (``leg_mass_blocks``).
MASS_PARTS: tuple[tuple[str, int, int], ...] = (("M_ll", 3, 3), ("M_bl", 6, 3), ("m", 1, 1), ("h", 3, 1), ("I_o", 3, 3))


def _symmetric(X: ca.SX) -> ca.SX:
    """The symmetric matrix with X's upper triangle (its lower triangle is never evaluated)."""
    out = ca.SX(3, 3)
    for a in range(3):
        for b in range(a, 3):
            out[a, b] = out[b, a] = X[a, b]
    return out


def _rotate_symmetric(axis: np.ndarray, q: ca.SX, I: ca.SX) -> ca.SX:
    """R I R^T for R = Rot(axis, q) and a symmetric I. For axis = +-e_k, with (i, j, k) cyclic,
    c2 = cos 2 sigma q, s2 = sin 2 sigma q (sigma the axis' sign), only 6 entries change:
    I'_ii = (I_ii + I_jj)/2 + (I_ii - I_jj)/2 c2 - I_ij s2, I'_jj = I_ii + I_jj - I'_ii,
    I'_ij = (I_ii - I_jj)/2 s2 + I_ij c2, I'_ik = c I_ik - s I_jk, I'_jk = s I_ik + c I_jk."""
    k = int(np.argmax(np.abs(axis)))
    if abs(axis[k]) != 1.0:  # an axis no frame choice could align: the general product
        R = axis_rotation(axis, q)
        return _symmetric(R @ I @ R.T)
    i, j = (k + 1) % 3, (k + 2) % 3
    c, s = ca.cos(q), axis[k] * ca.sin(q)
    c2, s2 = c * c - s * s, 2 * c * s
    half_sum, half_diff = 0.5 * (I[i, i] + I[j, j]), 0.5 * (I[i, i] - I[j, j])
    out = ca.SX(I)
    out[i, i] = half_sum + half_diff * c2 - I[i, j] * s2
    out[j, j] = 2 * half_sum - out[i, i]
    out[i, j] = out[j, i] = half_diff * s2 + I[i, j] * c2
    out[i, k] = out[k, i] = c * I[i, k] - s * I[j, k]
    out[j, k] = out[k, j] = s * I[i, k] + c * I[j, k]
    return out


def _link(link: LinkInertia) -> Inertia:
    """(m, h, I_o) of a link in its joint frame (constants; a symbolic body's ``origin`` as it is)."""
    if link.origin is not None:
        return link.mass, ca.SX(link.origin[0]), ca.SX(link.origin[1])
    if any(isinstance(x, ca.SX) for x in (link.mass, link.com, link.inertia)):  # a leg template's parameters
        c_sx = ca.SX(dm(link.com))
        return link.mass, link.mass * c_sx, ca.SX(dm(link.inertia)) - link.mass * skew(c_sx) @ skew(c_sx)
    c = np.asarray(link.com)
    return link.mass, ca.SX(dm(link.mass * c)), ca.SX(dm(link.inertia - link.mass * skew(c) @ skew(c)))


def _to_parent(Y: Inertia, axis: np.ndarray, q: ca.SX, P: np.ndarray) -> Inertia:
    """Y carried into the parent frame, reached by Rot(axis, q) then the offset P:
    h_p = R h + m P, I_p = R I_o R^T + m (|P|^2 1 - P P^T) - (P h'^T + h' P^T) + 2 (P . h') 1, h' = R h."""
    m, h, I_o = Y
    hr = axis_rotation(axis, q) @ h
    Pd = dm(P)
    shift = Pd @ hr.T
    parallel: ca.SX | ca.DM
    if isinstance(P, ca.SX) or isinstance(m, ca.SX):  # a leg template's parameters
        Ps = ca.SX(dm(P))
        parallel = m * (ca.dot(Ps, Ps) * ca.SX.eye(3) - Ps @ Ps.T)
    else:
        parallel = dm(m * (P @ P * np.eye(3) - np.outer(P, P)))
    I_p = _rotate_symmetric(axis, q, I_o) + parallel - shift - shift.T
    return m, hr + m * Pd, _symmetric(I_p + 2 * ca.dot(Pd, hr) * ca.SX.eye(3))


def _add(Y1: Inertia, Y2: Inertia) -> Inertia:
    return Y1[0] + Y2[0], Y1[1] + Y2[1], Y1[2] + Y2[2]


def _composites(leg: Leg, q: ca.SX) -> list[Inertia]:
    """Composite inertia of link j and the links below it, in frame j, j = 0, 1, 2."""
    links = [_link(link) for link in leg.links]
    out = [links[2]]
    for j in (1, 0):
        child = leg.joints[j + 1]
        out.insert(0, _add(links[j], _to_parent(out[0], child.axis, q[j + 1], child.placement.p)))
    return out


def leg_composite_inertia(leg: Leg, q: ca.SX) -> Inertia:
    """(m, h, I_o) of a whole leg (canonical frames, ``axis_aligned``) at the trunk origin, in trunk axes: its
    block of M's trunk rows and columns, M[0:6, 0:6] = [[m 1, -[h]x], [[h]x, I_o]] summed with the trunk's."""
    return _to_parent(_composites(leg, q)[0], leg.joints[0].axis, q[0], leg.joints[0].placement.p)


def _force_to_parent(f: ca.SX, n: ca.SX, axis: np.ndarray, q: ca.SX, P: np.ndarray) -> tuple[ca.SX, ca.SX]:
    """A force (f, n) carried into the parent frame: (R f, R n + P x R f)."""
    R = axis_rotation(axis, q)
    f_p = R @ f
    return f_p, R @ n + ca.cross(dm(P), f_p)


def leg_mass_blocks(leg: Leg, q: ca.SX) -> tuple[ca.SX, ca.SX, Inertia]:
    """A leg's part of M (canonical frames, ``axis_aligned``; SX parameters allowed): (M_ll (3, 3), its joints' block;
    M_bl (6, 3), the trunk rows of its columns; the leg's composite inertia at the trunk origin,
    ``leg_composite_inertia``)."""
    Yc = _composites(leg, q)
    M_ll, M_bl = ca.SX(3, 3), ca.SX(6, 3)
    for j in range(3):
        a = dm(leg.joints[j].axis)
        f, n = ca.cross(a, Yc[j][1]), Yc[j][2] @ a
        M_ll[j, j] = ca.dot(a, n)
        for i in reversed(range(j)):
            joint = leg.joints[i + 1]
            f, n = _force_to_parent(f, n, joint.axis, q[i + 1], joint.placement.p)
            M_ll[i, j] = M_ll[j, i] = ca.dot(dm(leg.joints[i].axis), n)
        f, n = _force_to_parent(f, n, leg.joints[0].axis, q[0], leg.joints[0].placement.p)
        M_bl[:, j] = ca.vertcat(f, n)
    return M_ll, M_bl, _to_parent(Yc[0], leg.joints[0].axis, q[0], leg.joints[0].placement.p)


def trunk_mass_block(total: Inertia) -> ca.SX:
    """M[0:6, 0:6] = [[m 1, -[h]x], [[h]x, I_o]] of the whole robot's composite inertia at the trunk origin."""
    m_total, h_total, I_total = total
    H = skew(h_total)
    return ca.vertcat(ca.horzcat(m_total * ca.SX.eye(3), -H), ca.horzcat(H, I_total))


def mass_matrix_crba(robot: Robot, q_joints: ca.SX) -> ca.SX:
    """M (18, 18), sparse (leg-leg blocks absent), for the 12 joint angles."""
    M = ca.SX(ca.Sparsity(NV_FULL, NV_FULL))
    total = _link(robot.trunk)
    for k, urdf_leg in enumerate(robot.legs):
        M_ll, M_bl, composite = leg_mass_blocks(axis_aligned(urdf_leg), q_joints[3 * k : 3 * k + 3])
        s = slice(6 + 3 * k, 9 + 3 * k)
        M[s, s] = M_ll
        M[0:6, s] = M_bl
        M[s, 0:6] = M_bl.T
        total = _add(total, composite)
    M[0:6, 0:6] = trunk_mass_block(total)
    return M


def trunk_inertia(robot: Robot) -> Inertia:
    """(m, h, I_o) of the trunk alone at its origin (constants)."""
    return _link(robot.trunk)


def add_inertia(Y1: Inertia, Y2: Inertia) -> Inertia:
    return _add(Y1, Y2)


def generalized_gravity(robot: Robot, q_joints: ca.SX, g_b: ca.SX) -> ca.SX:
    """G (18,) = (trunk force, moment about the trunk origin, 12 joint torques) holding the
    robot against gravity ``g_b`` (trunk frame), from composite first moments."""
    m_total, h_total, _ = _link(robot.trunk)
    tau = []
    for k, urdf_leg in enumerate(robot.legs):
        leg = axis_aligned(urdf_leg)
        q = q_joints[3 * k : 3 * k + 3]
        Yc = _composites(leg, q)
        g = g_b
        for j, joint in enumerate(leg.joints):
            g = axis_rotation(joint.axis, q[j]).T @ g  # gravity in frame j
            tau.append(-ca.dot(dm(joint.axis), ca.cross(Yc[j][1], g)))
        m, h, _ = _to_parent(Yc[0], leg.joints[0].axis, q[0], leg.joints[0].placement.p)
        m_total, h_total = m_total + m, h_total + h
    return ca.vertcat(-m_total * g_b, -ca.cross(h_total, g_b), *tau)


def leg_mass_parts(leg: Leg, q: ca.SX) -> ca.SX:
    """The leg's ``MASS_PARTS`` stacked (canonical frames; SX parameters allowed)."""
    M_ll, M_bl, (m, h, I_o) = leg_mass_blocks(leg, q)
    return stacked((M_ll, M_bl, ca.SX(m), h, I_o))


def assembled_mass_matrix(robot: Robot, parts: list[dict[str, ca.SX]], signs: list[np.ndarray]) -> ca.SX:
    """M (18, 18, sparse) from each leg's ``MASS_PARTS`` in the coordinates sigma q (sigma = +-1 per joint, ``signs``)
    and the trunk's inertia: the legs' blocks and composite inertias as ``mass_matrix_crba`` places them."""
    M = ca.SX(ca.Sparsity(NV_FULL, NV_FULL))
    total = trunk_inertia(robot)
    for k, (x, sigma) in enumerate(zip(parts, signs)):
        D = ca.diag(ca.DM(sigma))
        M_ll, M_bl = (x["M_ll"], x["M_bl"]) if np.all(sigma == 1.0) else (D @ x["M_ll"] @ D, x["M_bl"] @ D)
        s = slice(6 + 3 * k, 9 + 3 * k)
        M[s, s] = M_ll
        M[0:6, s] = M_bl
        M[s, 0:6] = M_bl.T
        total = add_inertia(total, (x["m"], x["h"], x["I_o"]))
    M[0:6, 0:6] = trunk_mass_block(total)
    return M
