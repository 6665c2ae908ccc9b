"""The paper's recursive Newton-Euler (docs/formulation.md §2-§3), symbolic, in full coordinates.

Per leg (Craig's recursion, quantities in each link's own frame):
  outward  omega_i, omegadot_i, vdot_i (classical acceleration of the frame origin) from the
           trunk, with gravity injected as a base acceleration: vdot_0 = a_b - g_b;
  links    F_i = m_i vdot_ci, N_i = I_ci omegadot_i + omega_i x I_ci omega_i;
  inward   from the foot, with f_4 = -f (f = ground force on the foot, trunk frame):
           f_i, n_i, tau_i = n_i . z_i.
``LegForces.f1, n1`` is Craig's (f_1, n_1) in the trunk frame: the force and moment (about
the hip, the HAA origin) that the trunk exerts on the leg. The paper prints the opposite
sign ("exerted by link 1 on the body"). Its split, eq. (1)-(2):
  f_1 = fbar_1 (suspended leg, f = 0) + fhat_1,  fhat_1 = -f,  nhat_1 = -(r - h) x f.

Trunk (paper eq. (3)-(4)), trunk frame, moments about the trunk origin, CoM c_b allowed:
  residual force  = m_b (a_cb - g_b) + sum_legs f_1
  residual moment = I_c alpha_b + omega_b x I_c omega_b + c_b x m_b (a_cb - g_b)
                    + sum_legs (n_1 + h x f_1)
This residual is the wrench an external agent would have to apply to the trunk for the
given motion and foot forces: zero for a motion the feet can produce.

Whole robot (``FullDynamics``): id_full(q, v, a, f) -> (base wrench residual (6,), tau (12,))
in the project's conventions (``state``): a = vdot, so the body part of ``a`` is spatial
and is converted to the paper's classical a_b = vdot_b + omega_b x v_b before the recursion.
Then  id_full(q, v, a, 0) = M_full(q) a + C_full(q, v) + G_full(q)  (the 6 + 12 rows).
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from functools import cache
from typing import Any

import casadi as ca

from quadruped_dyn.dynamics.crba import generalized_gravity, mass_matrix_crba
from quadruped_dyn.dynamics.guarded import guard_fields
from quadruped_dyn.dynamics.kinematics import foot_position, joint_frames
from quadruped_dyn.math.rigid import LinkInertia, axis_rotation
from quadruped_dyn.math.spatial import (
    dm,
    force_cross,
    force_cross_bar,
    motion_cross,
    placement_rt,
    quat_to_rotation,
    spatial_inertia,
)
from quadruped_dyn.model.leg import Leg
from quadruped_dyn.model.leg_frames import axis_aligned
from quadruped_dyn.model.robot import Robot, check_robot
from quadruped_dyn.model.state import GRAVITY_W, NQ_FULL, NV_FULL


def point_acceleration(w: ca.SX, wd: ca.SX) -> ca.SX:
    """K (3, 3) with K p = wd x p + w x (w x p): the classical acceleration of a point at a fixed offset p in a
    frame of angular velocity w and acceleration wd, relative to the frame origin's. K = [wd]x + w w^T - |w|^2 I,
    formed once per frame and applied to each offset in it (CoM, child joint origins): fewer operations than the
    two cross products per offset (docs/formulation.md §2)."""
    x, y, z = w[0], w[1], w[2]
    xx, yy, zz, xy, xz, yz = x * x, y * y, z * z, x * y, x * z, y * z
    return ca.vertcat(ca.horzcat(-(yy + zz), xy - wd[2], xz + wd[1]),
                      ca.horzcat(xy + wd[2], -(xx + zz), yz - wd[0]),
                      ca.horzcat(xz - wd[1], yz + wd[0], -(xx + yy)))


@dataclass(frozen=True)
class LegForces:
    tau: ca.SX  # (3,) joint torques, N m
    f1: ca.SX  # (3,) force of the trunk on the leg at the hip, trunk frame, N
    n1: ca.SX  # (3,) moment of the trunk on the leg about the hip, trunk frame, N m


def leg_newton_euler(
    leg: Leg, q: ca.SX, qd: ca.SX, qdd: ca.SX, omega_b: ca.SX, alpha_b: ca.SX, a0: ca.SX, f: ca.SX
) -> LegForces:
    """Craig's recursion for one leg. ``a0`` = a_b - g_b (classical trunk-origin acceleration
    minus gravity), ``omega_b``/``alpha_b`` trunk angular velocity/acceleration, ``f`` the
    ground force on the foot; all in the trunk frame."""
    return aligned_leg_newton_euler(axis_aligned(leg), q, qd, qdd, omega_b, alpha_b, a0, f)


def aligned_leg_newton_euler(
    leg: Leg, q: ca.SX, qd: ca.SX, qdd: ca.SX, omega_b: ca.SX, alpha_b: ca.SX, a0: ca.SX, f: ca.SX
) -> LegForces:
    """``leg_newton_euler`` of a leg already in canonical frames (``axis_aligned``); its placements, inertias
    and foot may be SX (a leg template, ``codegen.forms.leg_template``)."""
    w, wd, vd, f_foot = omega_b, alpha_b, a0, -f
    K = point_acceleration(w, wd)  # the trunk's; CSE shares it with the trunk's and the other legs'
    links: list[tuple[Any, Any, Any, Any, Any]] = []  # (R_parent_i, P_i, F_i, N_i, c_i or None) per link
    for i, (joint, link) in enumerate(zip(leg.joints, leg.links)):
        Rf, P = placement_rt(joint.placement)
        R = Rf @ axis_rotation(joint.axis, q[i])  # parent <- i
        z = dm(joint.axis)
        f_foot = R.T @ f_foot  # the foot's push on the ground, carried link by link into the KFE frame
        vd = R.T @ (K @ P + vd)
        w_parent = R.T @ w
        w = w_parent + qd[i] * z
        wd = R.T @ wd + ca.cross(w_parent, qd[i] * z) + qdd[i] * z
        K = point_acceleration(w, wd)
        if link.origin is not None:  # a symbolic body: force and moment about the origin from (h, I_o) as they are
            h, I_o = link.origin
            links.append((R, P, K @ h + link.mass * vd, I_o @ wd + ca.cross(w, I_o @ w) + ca.cross(h, vd), None))
            continue
        c, Ic = dm(link.com), dm(link.inertia)
        vdc = K @ c + vd
        links.append((R, P, link.mass * vdc, Ic @ wd + ca.cross(w, Ic @ w), c))

    # inward, starting at the foot frame: the foot pushes on the ground with f_4 = -f, n_4 = 0
    f_next, n_next = f_foot, ca.SX.zeros(3)
    R_next, P_next = ca.SX.eye(3), dm(leg.foot.p)
    tau: list[ca.SX] = []
    for i in reversed(range(3)):
        R, P, F, N, c = links[i]
        f_i = R_next @ f_next + F
        if c is None:  # N is about the origin already
            n_i = N + R_next @ n_next + ca.cross(P_next, R_next @ f_next)
        else:
            n_i = N + R_next @ n_next + ca.cross(c, F) + ca.cross(P_next, R_next @ f_next)
        tau.insert(0, ca.dot(n_i, dm(leg.joints[i].axis)))
        f_next, n_next, R_next, P_next = f_i, n_i, R, P
    R_b1 = links[0][0]
    return LegForces(ca.SX(ca.vertcat(*tau)), R_b1 @ f_next, R_b1 @ n_next)


def hip_reaction_split(
    leg: Leg, q: ca.SX, qd: ca.SX, qdd: ca.SX, omega_b: ca.SX, alpha_b: ca.SX, a0: ca.SX, f: ca.SX
) -> tuple[LegForces, LegForces]:
    """The paper's eq. (1)-(2): (suspended-leg part with f = 0, ground-force part), whose sum
    is ``leg_newton_euler(..., f)``. The ground-force part is
    tauhat = -J^T f, fhat_1 = -f, nhat_1 = -(r - h) x f (r the foot, h the hip; trunk frame)."""
    suspended = leg_newton_euler(leg, q, qd, qdd, omega_b, alpha_b, a0, ca.SX.zeros(3))
    r = foot_position(leg, q)
    J = ca.jacobian(r, q)
    return suspended, LegForces(-J.T @ f, -f, -ca.cross(r - dm(leg.hip), f))


def trunk_own_wrench(trunk: LinkInertia, omega_b: ca.SX, alpha_b: ca.SX, a0: ca.SX) -> ca.SX:
    """The trunk's own wrench (6,) (force, moment about the trunk origin; trunk frame) for its angular velocity and
    acceleration and a0 = a_b - g_b, its origin's classical acceleration minus gravity."""
    if trunk.origin is not None:  # a symbolic body: (h, I_o) as they are
        h, I_o = trunk.origin
        return ca.vertcat(trunk.mass * a0 + point_acceleration(omega_b, alpha_b) @ h,
                          I_o @ alpha_b + ca.cross(omega_b, I_o @ omega_b) + ca.cross(h, a0))
    c, Ic = dm(trunk.com), dm(trunk.inertia)
    a_c = a0 + point_acceleration(omega_b, alpha_b) @ c
    return ca.vertcat(trunk.mass * a_c, Ic @ alpha_b + ca.cross(omega_b, Ic @ omega_b) + ca.cross(c, trunk.mass * a_c))


def gravity_in_trunk(q: ca.SX) -> ca.SX:
    """g_b (3,): gravity in the trunk frame at q (19,) (quaternion x y z w at q[3:7])."""
    return quat_to_rotation(q[3:7]).T @ dm(GRAVITY_W)


def trunk_acceleration(q: ca.SX, v: ca.SX, a: ca.SX) -> ca.SX:
    """a0 = a_lin + w_b x v_b - g_b (3,): the trunk origin's classical acceleration minus gravity, trunk frame (a: the
    spatial acceleration of the project's convention, ``model/state.py``)."""
    return a[0:3] + ca.cross(v[3:6], v[0:3]) - gravity_in_trunk(q)


def inverse_dynamics_parts(
    robot: Robot, q_joints: ca.SX, g_b: ca.SX, v: ca.SX, a: ca.SX, f: ca.SX
) -> tuple[ca.SX, list[tuple[ca.SX, ca.SX]]]:
    """``inverse_dynamics`` by body: (the trunk's own wrench (6,), per leg (its wrench on the trunk (6,): force
    and moment about the trunk origin, trunk frame; its joint torques (3,))). The trunk rows of
    ``inverse_dynamics`` are the sum of the wrenches, its joint rows the torques."""
    v_b, omega_b = v[0:3], v[3:6]
    a_b = a[0:3] + ca.cross(omega_b, v_b)  # classical, as the paper's recursion needs
    alpha_b = a[3:6]
    a0 = a_b - g_b
    own = trunk_own_wrench(robot.trunk, omega_b, alpha_b, a0)
    legs = []
    for k, leg in enumerate(robot.legs):
        s = slice(3 * k, 3 * k + 3)
        lf = leg_newton_euler(leg, q_joints[s], v[6:][s], a[6:][s], omega_b, alpha_b, a0, f[s])
        legs.append((ca.vertcat(lf.f1, lf.n1 + ca.cross(dm(leg.hip), lf.f1)), lf.tau))
    return own, legs


def inverse_dynamics(robot: Robot, q_joints: ca.SX, g_b: ca.SX, v: ca.SX, a: ca.SX, f: ca.SX) -> ca.SX:
    """(18,) = (base wrench residual, 12 joint torques). ``g_b`` gravity in the trunk frame
    (0 to drop gravity), v (18,), a = vdot (18,) spatial for the body, f (12,) ground forces."""
    own, legs = inverse_dynamics_parts(robot, q_joints, g_b, v, a, f)
    force, moment = own[0:3], own[3:6]
    for wrench, _ in legs:
        force += wrench[0:3]
        moment += wrench[3:6]
    return ca.vertcat(force, moment, *(tau for _, tau in legs))


def coriolis_matrix(robot: Robot, q_joints: ca.SX, v: ca.SX) -> ca.SX:
    """C(q, v) (18, 18) in Pinocchio's factorisation (Echeandia & Wensing):
    C = sum_bodies J_k^T (Y_k Jdot_k + B(Y_k, V_k) J_k), B(Y, V) = 1/2 (V x* Y - Y V x + (Y V) xbar*),
    evaluated in the trunk frame frozen at this instant (an inertial frame), so the base
    columns of J are the identity and Jdot's column of joint j is V_j x S_j."""
    V_b = v[0:6]
    C = ca.SX.zeros(NV_FULL, NV_FULL)

    def add_body(Y: ca.SX, V: ca.SX, J: ca.SX, Jdot: ca.SX) -> None:
        nonlocal C
        B = 0.5 * (force_cross(V) @ Y - Y @ motion_cross(V) + force_cross_bar(Y @ V))
        C += J.T @ (Y @ Jdot + B @ J)

    J_base = ca.horzcat(ca.SX.eye(6), ca.SX.zeros(6, 12))
    Jdot_base = ca.horzcat(motion_cross(V_b), ca.SX.zeros(6, 12))
    add_body(spatial_inertia(robot.trunk, ca.SX.eye(3), ca.SX.zeros(3)), V_b, J_base, Jdot_base)
    for k, urdf_leg in enumerate(robot.legs):
        leg = axis_aligned(urdf_leg)  # the frames joint_frames returns
        J, Jdot, V = J_base, Jdot_base, V_b
        for i, ((R, p), link) in enumerate(zip(joint_frames(leg, q_joints[3 * k : 3 * k + 3]), leg.links)):
            col = 6 + 3 * k + i
            axis = R @ dm(leg.joints[i].axis)
            S = ca.vertcat(ca.cross(p, axis), axis)
            V = V + S * v[col]
            e = ca.SX.zeros(1, NV_FULL)
            e[col] = 1
            J = J + S @ e
            Jdot = Jdot + (motion_cross(V) @ S) @ e
            add_body(spatial_inertia(link, R, p), V, J, Jdot)
    return C


@dataclass(frozen=True)
class FullDynamics:
    """Named CasADi Functions of the whole robot in full coordinates (see ``state``).

    Inputs: q (19,) = (p, quaternion x y z w, joints), v (18,), a = vdot (18,), f (12,) ground
    forces on the feet (FL, FR, BL, BR, trunk frame, N). Outputs in project order.
    """

    id_full: ca.Function  # q, v, a, f -> (w_res (6,), tau (12,))
    M_full_walker_orin: ca.Function  # q -> M (18, 18), by the paper's unit accelerations (Walker & Orin)
    M_full_ad: ca.Function  # q -> M (18, 18), CasADi AD of id_full w.r.t. a
    M_full_crba: ca.Function  # q -> M (18, 18), composite rigid bodies: the form generated as C
    C_full: ca.Function  # q, v -> C (18,) velocity terms (g = 0, a = 0)
    G_full_newton_euler: ca.Function  # q -> G (18,) (v = 0, a = 0)
    G_full_crb: ca.Function  # q -> G (18,) from composite first moments: the form generated as C
    nle_full: ca.Function  # q, v -> C + G (18,) in one evaluation (Pinocchio's nonLinearEffects)
    coriolis: ca.Function  # q, v -> C(q, v) (18, 18), Pinocchio's factorisation
    build_seconds: float

    def __post_init__(self) -> None:
        guard_fields(self)  # numeric calls check shapes, finiteness, quaternions (dynamics/guarded.py)


def _ordered_inputs() -> tuple[ca.SX, ca.SX, ca.SX, ca.SX]:
    return ca.SX.sym("q", NQ_FULL), ca.SX.sym("v", NV_FULL), ca.SX.sym("a", NV_FULL), ca.SX.sym("f", 12)


def full_dynamics(robot: Robot) -> FullDynamics:
    """Build the full-coordinate Functions once per robot."""
    return _full_dynamics(check_robot(robot))


@cache
def _full_dynamics(robot: Robot) -> FullDynamics:
    start = time.perf_counter()
    q, v, a, f = _ordered_inputs()
    qj = q[7:]
    g_b = gravity_in_trunk(q)
    zero_v, zero_f = ca.SX.zeros(NV_FULL), ca.SX.zeros(12)
    tau = inverse_dynamics(robot, qj, g_b, v, a, f)
    # Walker & Orin: column k of M is the inverse dynamics of a unit acceleration e_k, g = 0, v = 0
    unit = ca.SX(ca.DM.eye(NV_FULL))
    M = ca.horzcat(*[inverse_dynamics(robot, qj, ca.SX.zeros(3), zero_v, unit[:, k], zero_f) for k in range(NV_FULL)])
    # entries that are identically zero (the leg-leg blocks) become structural zeros
    M, M_ad = ca.sparsify(M), ca.sparsify(ca.jacobian(tau, a))
    C = inverse_dynamics(robot, qj, ca.SX.zeros(3), v, zero_v, zero_f)
    G = inverse_dynamics(robot, qj, g_b, zero_v, zero_v, zero_f)
    nle = inverse_dynamics(robot, qj, g_b, v, zero_v, zero_f)
    Cmat = ca.sparsify(coriolis_matrix(robot, qj, v))
    opts = {"cse": True}
    return FullDynamics(
        id_full=ca.Function("id_full", [q, v, a, f], [tau[:6], tau[6:]], ["q", "v", "a", "f"], ["w_res", "tau"], opts),
        M_full_walker_orin=ca.Function("M_full_walker_orin", [q], [M], ["q"], ["M"], opts),
        M_full_ad=ca.Function("M_full_ad", [q], [M_ad], ["q"], ["M"], opts),
        M_full_crba=ca.Function("M_full_crba", [q], [mass_matrix_crba(robot, qj)], ["q"], ["M"], opts),
        C_full=ca.Function("C_full", [q, v], [C], ["q", "v"], ["C"], opts),
        G_full_newton_euler=ca.Function("G_full_newton_euler", [q], [G], ["q"], ["G"], opts),
        G_full_crb=ca.Function("G_full_crb", [q], [generalized_gravity(robot, qj, g_b)], ["q"], ["G"], opts),
        nle_full=ca.Function("nle_full", [q, v], [nle], ["q", "v"], ["nle"], opts),
        coriolis=ca.Function("coriolis_matrix", [q, v], [Cmat], ["q", "v"], ["C"], opts),
        build_seconds=time.perf_counter() - start,
    )
