"""The derivatives of the full inverse dynamics in closed form, leg by leg (docs/derivatives.md, "What there is").

rnea(q, v, a) (no foot forces) in Pinocchio's tangent convention (``derivatives`` module docstring): each leg's rows
y = (its wrench on the trunk, its three torques) depend on the trunk only through w_b, alpha_b and the trunk's
classical linear acceleration minus gravity a_cl = a_lin + w_b x v_b - g_b (``newton_euler.trunk_acceleration``).
Per leg, ``leg_rows`` differentiates y along its joints and w_b and gives its part of M (composite rigid bodies);
``rows_to_derivatives`` sums the legs and the trunk's own wrench and forms the v_b, gravity and w_b columns from
M[:, 0:3] by the identities of docs/derivatives.md. ``rnea_tangent_derivatives`` is the two over the robot's legs:
equal to CasADi's Jacobian of the whole rnea (``derivatives.FullDerivatives.did_full_ad``, tested). The generated
C evaluates the same per-leg rows as one function per leg template (``codegen.forms.did_full_pieces``).
"""

from __future__ import annotations

import casadi as ca
import numpy as np

from quadruped_dyn.dynamics.crba import MASS_PARTS, assembled_mass_matrix, leg_mass_blocks
from quadruped_dyn.dynamics.newton_euler import (
    aligned_leg_newton_euler,
    gravity_in_trunk,
    trunk_acceleration,
    trunk_own_wrench,
)
from quadruped_dyn.math.spatial import dm, skew, stacked, unstacked
from quadruped_dyn.model.leg import Leg
from quadruped_dyn.model.leg_frames import axis_aligned
from quadruped_dyn.model.robot import Robot
from quadruped_dyn.model.state import NV_FULL

#: A leg's rows' derivatives and part of M (``leg_rows``), in order: (name, rows, columns), each stacked column by column.
LEG_PARTS: tuple[tuple[str, int, int], ...] = (("J_q", 9, 3), ("J_qd", 9, 3), ("J_w", 9, 3), *MASS_PARTS)


def _motion_cross(x: ca.SX, y: ca.SX) -> ca.SX:
    """x x y of spatial motions in the project's (linear, angular) order."""
    return ca.vertcat(ca.cross(x[3:], y[:3]) + ca.cross(x[:3], y[3:]), ca.cross(x[3:], y[3:]))


def _force_cross(x: ca.SX, f: ca.SX) -> ca.SX:
    """x x* f of a spatial motion x and a force f = (force, moment), (linear, angular) order."""
    return ca.vertcat(ca.cross(x[3:], f[:3]), ca.cross(x[3:], f[3:]) + ca.cross(x[:3], f[:3]))


def leg_rows(leg: Leg, q: ca.SX, qd: ca.SX, qdd: ca.SX, w_b: ca.SX, alpha_b: ca.SX, a_cl: ca.SX) -> ca.SX:
    """L (``LEG_PARTS``) of one leg in canonical frames (SX parameters allowed), at the trunk's w_b, alpha_b and
    a_cl (trunk frame) and the leg's angles, rates and accelerations (3,) each:

    * J_w = dy/dw_b at fixed a_cl;
    * its first joint's rate and angle columns by the hip identities (its axis a_1 through the hip p, fixed in the
      trunk; S = (p x a_1, a_1); K = dy/d(a_cl, alpha_b), the leg's composite inertia over M_bl^T):
      d/dqd_1 = J_w a_1 + K (2 w_b x (p x a_1), w_b x a_1) and, u = (0, w_b) x S, A_b = (a_cl, alpha_b),
      d/dq_1 = J_w u_ang + K ((w_b x u_lin, 0) - S x A_b) + (S x* wrench, 0);
    * the other two joints by CasADi's Jacobian of the leg's recursion."""
    lf = aligned_leg_newton_euler(leg, q, qd, qdd, w_b, alpha_b, a_cl, ca.SX.zeros(3))
    wrench = ca.vertcat(lf.f1, lf.n1 + ca.cross(dm(leg.hip), lf.f1))
    y = ca.vertcat(wrench, lf.tau)  # the leg's rows: its wrench on the trunk, its torques
    M_ll, M_bl, (m, h, I_o) = leg_mass_blocks(leg, q)
    p, a1 = dm(leg.joints[0].placement.p), dm(leg.joints[0].axis)  # canonical: the placement's rotation is 1
    S = ca.vertcat(ca.cross(p, a1), a1)
    K = ca.vertcat(ca.horzcat(m * ca.SX.eye(3), -skew(h)), ca.horzcat(skew(h), I_o), M_bl.T)
    A_b = ca.vertcat(a_cl, alpha_b)
    J_w = ca.jacobian(y, w_b)
    u = _motion_cross(ca.vertcat(ca.SX.zeros(3), w_b), S)
    d_q1 = J_w @ u[3:] + K @ (ca.vertcat(ca.cross(w_b, u[:3]), ca.SX.zeros(3)) - _motion_cross(S, A_b))
    d_q1 = d_q1 + ca.vertcat(_force_cross(S, wrench), ca.SX.zeros(3))
    d_qd1 = J_w @ a1 + K @ ca.vertcat(2 * ca.cross(w_b, ca.cross(p, a1)), ca.cross(w_b, a1))
    J_q = ca.horzcat(d_q1, ca.jacobian(y, q[1:]))
    J_qd = ca.horzcat(d_qd1, ca.jacobian(y, qd[1:]))
    return stacked((J_q, J_qd, J_w, M_ll, M_bl, ca.SX(m), h, I_o))


def _in_robot_coordinates(parts: dict[str, ca.SX], sigma: np.ndarray) -> dict[str, ca.SX]:
    """A leg's Jacobians from its template's coordinates sigma q back to the robot's: its torque rows and its joints'
    columns times sigma (sigma = +-1: a product with 1 is dropped, with -1 a negation); M's parts: see
    ``assembled_mass_matrix``."""
    if np.all(sigma == 1.0):
        return parts
    D3, D9 = ca.diag(ca.DM(sigma)), ca.diag(ca.DM(np.r_[np.ones(6), sigma]))
    out = dict(parts)
    out["J_q"], out["J_qd"], out["J_w"] = D9 @ parts["J_q"] @ D3, D9 @ parts["J_qd"] @ D3, D9 @ parts["J_w"]
    return out


def rows_to_derivatives(robot: Robot, q: ca.SX, v: ca.SX, a: ca.SX, Ls: list[ca.SX],
                        signs: list[np.ndarray]) -> tuple[ca.SX, ca.SX, ca.SX]:
    """(dtau_dq, dtau_dv, dtau_da = M) from the four legs' ``leg_rows`` L_0..L_3, each leg's in the coordinates
    sigma q (``signs``: +-1 per joint; ones for the robot's own), and the trunk's own wrench (module docstring)."""
    w_b, v_b = v[3:6], v[0:3]
    a_cl = ca.SX.sym("a_cl", 3)
    own = trunk_own_wrench(robot.trunk, w_b, a[3:6], a_cl)
    dw = ca.vertcat(ca.substitute(ca.jacobian(own, w_b), a_cl, trunk_acceleration(q, v, a)), ca.SX(12, 3))
    dq_legs, dv_legs, all_parts = [], [], []
    for k, L in enumerate(Ls):
        parts = _in_robot_coordinates(unstacked(L, LEG_PARTS), signs[k])
        all_parts.append(parts)

        def rows(Y: ca.SX, k: int = k) -> ca.SX:  # the leg's 9 rows into the 18: trunk, then its own joints
            return ca.vertcat(Y[0:6, :], ca.SX(3 * k, Y.shape[1]), Y[6:9, :], ca.SX(9 - 3 * k, Y.shape[1]))

        dq_legs.append(rows(parts["J_q"]))
        dv_legs.append(rows(parts["J_qd"]))
        dw = dw + rows(parts["J_w"])
    M = assembled_mass_matrix(robot, all_parts, signs)
    M_lin = M[:, 0:3]
    g_b = gravity_in_trunk(q)
    dq = ca.horzcat(ca.SX(NV_FULL, 3), -M_lin @ skew(g_b), *dq_legs)
    dv = ca.horzcat(M_lin @ skew(w_b), dw - M_lin @ skew(v_b), *dv_legs)
    return dq, dv, M


def rnea_tangent_derivatives(robot: Robot, q: ca.SX, v: ca.SX, a: ca.SX) -> tuple[ca.SX, ca.SX, ca.SX]:
    """(dtau_dq (18, 18), dtau_dv (18, 18), dtau_da = M (18, 18)) of the full inverse dynamics (no foot forces) by
    ``leg_rows`` for each of the robot's legs (canonical frames) and ``rows_to_derivatives``. The trunk position does
    not enter (its columns are structurally zero)."""
    xs = [ca.SX.sym(n, 3) for n in ("w_b", "alpha_b", "a_cl", "q_l", "qd_l", "qdd_l")]
    a_cl = trunk_acceleration(q, v, a)
    Ls = []
    for k, leg in enumerate(robot.legs):  # a_cl, w_b separate inputs of the leg's rows: J_w is at fixed a_cl
        rows = ca.Function("leg_rows", xs, [leg_rows(axis_aligned(leg), xs[3], xs[4], xs[5], *xs[0:3])])
        s = slice(3 * k, 3 * k + 3)
        Ls.append(rows(v[3:6], a[3:6], a_cl, q[7:][s], v[6:][s], a[6:][s]))
    return rows_to_derivatives(robot, q, v, a, Ls, [np.ones(3)] * 4)
