"""did_full's form: the derivatives of the full inverse dynamics, leg by leg (docs/derivatives.md, "What there is",
"dfd_r and dgrf as generated C").

rnea(q, v, a) (no foot forces) in Pinocchio's tangent convention (``derivatives`` module docstring) is evaluated in
three generated pieces, so that one piece of machine code serves every leg (``leg_template``):

* ``head(q, v, a) -> a_cl`` (3,): the trunk's classical linear acceleration a_lin + w_b x v_b - g_b, trunk frame,
  through which alone v_b and gravity enter the recursion;
* per leg template, ``leg(w_b, alpha_b, a_cl, q_l, qd_l, qdd_l, p) -> L`` (``LEG_PARTS``, stacked column by column):
  the leg's rows y = (its wrench on the trunk, its three torques) differentiated along its joint angles (J_q),
  rates (J_qd) and w_b (J_w), and its part of M (M_ll, M_bl, its composite inertia (m, h, I_o));
* ``tail(q, v, a, L_0, ..., L_3) -> (dtau_dq, dtau_dv, dtau_da = M)``: the trunk's own wrench, the sums over the legs
  and the v_b, gravity and w_b columns by M[:, 0:3] (the identities of "How did_full is formed").

``rnea_tangent_derivatives`` is the three composed as a graph: the same operations as the C's calls.
"""

from __future__ import annotations

from functools import cache

import casadi as ca
import numpy as np

from quadruped_dyn.dynamics.by_leg import (
    MASS_PARTS,
    assembled_mass_matrix,
    gravity_in_trunk,
    stacked,
    trunk_acceleration,
    trunk_head,
    unstacked,
)
from quadruped_dyn.dynamics.crba import leg_mass_blocks
from quadruped_dyn.dynamics.leg_template import LegPieces, leg_signs, leg_templates, template_of
from quadruped_dyn.dynamics.newton_euler import aligned_leg_newton_euler, trunk_own_wrench
from quadruped_dyn.math.spatial import dm, skew
from quadruped_dyn.model.leg import Leg
from quadruped_dyn.model.robot import Robot
from quadruped_dyn.model.state import NQ_FULL, NV_FULL

#: A leg function's output L, in order: (name, rows, columns), each stacked column by column.
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


@cache
def did_full_pieces(robot: Robot) -> LegPieces:
    """did_full(q, v, a) -> (dtau_dq, dtau_dv, dtau_da) leg by leg (module docstring)."""
    q, v, a = ca.SX.sym("q", NQ_FULL), ca.SX.sym("v", NV_FULL), ca.SX.sym("a", NV_FULL)
    opts = {"cse": True}
    head = trunk_head("did_full_head", "a_cl")
    templates = leg_templates(robot)
    legs = []
    for i, t in enumerate(templates):
        xs = [ca.SX.sym(n, 3) for n in ("w_b", "alpha_b", "a_cl", "q_l", "qd_l", "qdd_l")]
        legs.append(ca.Function(f"did_full_leg{i}", [*xs, t.p], [leg_rows(t.leg, xs[3], xs[4], xs[5], *xs[0:3])],
                                ["w_b", "alpha_b", "a_cl", "q_l", "qd_l", "qdd_l", "p"], ["L"], opts))
    of = template_of(templates)
    Ls = [ca.SX.sym(f"L_{k}", legs[of[k]].sparsity_out(0)) for k in range(4)]
    signs = [leg_signs(templates, k) for k in range(4)]
    tail = ca.Function("did_full_tail", [q, v, a, *Ls], list(_tail(robot, q, v, a, Ls, signs)),
                       ["q", "v", "a", *(f"L_{k}" for k in range(4))], ["dtau_dq", "dtau_dv", "dtau_da"], opts)
    return LegPieces(head, templates, tuple(legs), of, tail)


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


def _tail(robot: Robot, q: ca.SX, v: ca.SX, a: ca.SX, Ls: list[ca.SX],
          signs: list[np.ndarray]) -> tuple[ca.SX, ca.SX, ca.SX]:
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
    """(dtau_dq (18, 18), dtau_dv (18, 18), dtau_da = M (18, 18)) of the full inverse dynamics (no foot forces),
    composed of ``did_full_pieces``' head, leg and tail functions (module docstring). The trunk position does not
    enter (its columns are structurally zero). Equal to ``tangent_jacobian``'s of the whole rnea (tested)."""
    pieces = did_full_pieces(robot)
    if pieces.head is None:
        raise AssertionError("did_full's pieces have a head")
    a_cl = pieces.head(q, v, a)
    Ls = []
    for k in range(4):
        i, s = pieces.template_of[k], slice(3 * k, 3 * k + 3)
        sigma = ca.DM(pieces.leg_signs(k))
        Ls.append(pieces.legs[i](v[3:6], a[3:6], a_cl, sigma * q[7:][s], sigma * v[6:][s], sigma * a[6:][s],
                                 ca.DM(pieces.leg_values(k))))
    return tuple(pieces.tail(q, v, a, *Ls))  # type: ignore[return-value]
