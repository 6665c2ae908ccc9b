"""id_full and M (dense) leg by leg: the pieces the reduced files' C calls (``leg_template.LegPieces``; docs/derivatives.md,
"dfd_r and dgrf as generated C", and docs/formulation.md §6.2).

The reduced terms (fd_r, M_r, C_r + G_r, id_r, dfd_r) call the full-coordinate inverse dynamics and M each once per
call, with a stance's parts and the solve around them: ~60 kB of machine code per fd_r call against a 32 kB
instruction cache. Leg by leg, one leg function serves the four legs (docs/benchmark.md, "Design choices"):

* ``id_full_pieces``: head(q, v, a) -> a0 = a_lin + w_b x v_b - g_b (the trunk origin's classical acceleration minus
  gravity, trunk frame); leg(w_b, alpha_b, a0, q_l, qd_l, qdd_l, p) -> (the leg's wrench on the trunk (6), its
  torques (3)) by the leg's Newton-Euler recursion; tail(q, v, a, y_0..y_3) -> (w_res, tau) = (the trunk's own
  wrench + the legs', the legs' torques): ``newton_euler.inverse_dynamics`` without foot forces (the reduced terms'
  rnea: their foot forces are the GRF projection's, not rnea's input);
* ``mass_matrix_pieces``: leg(q_l, p) -> the leg's part of M (``MASS_PARTS``); tail(L_0..L_3) -> M's nonzero blocks
  (``mass_blocks``): ``crba.mass_matrix_crba``;
* ``foot_pieces``: leg(q_l, qd_l, p) -> the foot's r, J, J qd_l, Jdot qd_l (``FOOT_PARTS``, trunk frame); tail(L_0..L_3)
  -> the four feet's, each leg's J turned back by its signs: ``kinematics.foot_position`` and its derivatives. The
  reduced files call the leg function for their stance legs only (``stance_maps``).
"""

from __future__ import annotations

from functools import cache

import casadi as ca
import numpy as np

from quadruped_dyn.dynamics.crba import add_inertia, leg_mass_blocks, trunk_inertia, trunk_mass_block
from quadruped_dyn.dynamics.kinematics import canonical_foot_position
from quadruped_dyn.dynamics.leg_template import LegPieces, leg_signs, leg_templates, template_of
from quadruped_dyn.dynamics.newton_euler import aligned_leg_newton_euler, trunk_own_wrench
from quadruped_dyn.math.spatial import dm, quat_to_rotation
from quadruped_dyn.model.leg import Leg
from quadruped_dyn.model.robot import Robot
from quadruped_dyn.model.state import GRAVITY_W, NQ_FULL, NV_FULL

#: A leg's part of M, in order: (name, rows, columns), each stacked column by column (``crba.leg_mass_blocks``).
MASS_PARTS: tuple[tuple[str, int, int], ...] = (("M_ll", 3, 3), ("M_bl", 6, 3), ("m", 1, 1), ("h", 3, 1), ("I_o", 3, 3))
#: A leg's foot kinematics, in order (trunk frame): its position r [m], J = dr/dq_l (column-major), J qd_l [m/s] and
#: Jdot qd_l [m/s^2] (the foot's classical acceleration relative to the trunk at qdd_l = 0).
FOOT_PARTS: tuple[tuple[str, int, int], ...] = (("r", 3, 1), ("J", 3, 3), ("J_qd", 3, 1), ("Jdot_qd", 3, 1))
#: M's nonzero blocks as ``mass_blocks`` stacks them: M_bb, then per leg (``LEG_MASS_BLOCKS``, four times) M_bl, M_ll.
TRUNK_MASS_BLOCKS: tuple[tuple[str, int, int], ...] = (("M_bb", 6, 6),)
LEG_MASS_BLOCKS: tuple[tuple[str, int, int], ...] = (("M_bl", 6, 3), ("M_ll", 3, 3))


def stacked(parts: tuple[ca.SX, ...]) -> ca.SX:
    """Matrices stacked column by column into one column."""
    return ca.vertcat(*(ca.vec(ca.SX(x)) for x in parts))


def unstacked(L: ca.SX, layout: tuple[tuple[str, int, int], ...]) -> dict[str, ca.SX]:
    """``stacked``'s inverse for ``layout``."""
    out, start = {}, 0
    for name, rows, cols in layout:
        out[name] = ca.reshape(L[start : start + rows * cols], rows, cols)
        start += rows * cols
    return out


def leg_mass_parts(leg: Leg, q: ca.SX) -> ca.SX:
    """The leg's ``MASS_PARTS`` stacked (canonical frames; SX parameters allowed)."""
    M_ll, M_bl, (m, h, I_o) = leg_mass_blocks(leg, q)
    return stacked((M_ll, M_bl, ca.SX(m), h, I_o))


def assembled_mass_matrix(robot: Robot, parts: list[dict[str, ca.SX]], signs: list[np.ndarray]) -> ca.SX:
    """M (18, 18, sparse) from each leg's ``MASS_PARTS`` in its template's coordinates sigma q (``leg_template``)
    and the trunk's inertia: the legs' blocks and composite inertias as ``crba.mass_matrix_crba`` places them."""
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


def mass_blocks(M: ca.SX | ca.DM) -> ca.SX | ca.DM:
    """M's (18 x 18) nonzero blocks, as fd_r reads them (codegen/c/qd_reduced_solve.c, QD_M_BB, QD_M_BL, QD_M_LL):
    M_bb (6 x 6), then for each leg l M_bl (6 x 3) and M_ll (3 x 3), each column by column: (144,). M's blocks
    between two legs are zero and M_lb = M_bl^T: nothing else."""
    blocks = {"M_bb": lambda s: M[0:6, 0:6], "M_bl": lambda s: M[0:6, s], "M_ll": lambda s: M[s, s]}
    parts = [blocks[name](None) for name, _, _ in TRUNK_MASS_BLOCKS]
    for k in range(4):
        s = slice(6 + 3 * k, 9 + 3 * k)
        parts += [blocks[name](s) for name, _, _ in LEG_MASS_BLOCKS]
    return ca.vertcat(*(ca.vec(ca.densify(x)) for x in parts))


def gravity_in_trunk(q: ca.SX) -> ca.SX:
    """g_b (3,): gravity in the trunk frame at q (19,) (quaternion x y z w at q[3:7])."""
    return quat_to_rotation(q[3:7]).T @ dm(GRAVITY_W)


def trunk_acceleration(q: ca.SX, v: ca.SX, a: ca.SX) -> ca.SX:
    """a0 = a_lin + w_b x v_b - g_b (3,): the trunk origin's classical acceleration minus gravity, trunk frame (a: the
    spatial acceleration of the project's convention, ``model/state.py``)."""
    return a[0:3] + ca.cross(v[3:6], v[0:3]) - gravity_in_trunk(q)


def trunk_head(name: str, output: str) -> ca.Function:
    """The head of id_full's and did_full's pieces: (q, v, a) -> ``trunk_acceleration``, named ``output``."""
    q, v, a = ca.SX.sym("q", NQ_FULL), ca.SX.sym("v", NV_FULL), ca.SX.sym("a", NV_FULL)
    return ca.Function(name, [q, v, a], [trunk_acceleration(q, v, a)], ["q", "v", "a"], [output], {"cse": True})


@cache
def id_full_pieces(robot: Robot) -> LegPieces:
    """id_full(q, v, a, f = 0) -> (w_res, tau) leg by leg (module docstring)."""
    q, v, a = ca.SX.sym("q", NQ_FULL), ca.SX.sym("v", NV_FULL), ca.SX.sym("a", NV_FULL)
    opts = {"cse": True}
    head = trunk_head("id_full_head", "a0")
    templates = leg_templates(robot)
    legs = []
    for i, t in enumerate(templates):
        xs = [ca.SX.sym(n, 3) for n in ("w_b", "alpha_b", "a0", "q_l", "qd_l", "qdd_l")]
        lf = aligned_leg_newton_euler(t.leg, xs[3], xs[4], xs[5], xs[0], xs[1], xs[2], ca.SX.zeros(3))
        y = ca.vertcat(lf.f1, lf.n1 + ca.cross(dm(t.leg.hip), lf.f1), lf.tau)
        legs.append(ca.Function(f"id_full_leg{i}", [*xs, t.p], [y], ["w_b", "alpha_b", "a0", "q_l", "qd_l", "qdd_l", "p"],
                                ["y"], opts))
    of = template_of(templates)
    ys = [ca.SX.sym(f"y_{k}", legs[of[k]].sparsity_out(0)) for k in range(4)]
    w_res = trunk_own_wrench(robot.trunk, v[3:6], a[3:6], trunk_acceleration(q, v, a))
    for y in ys:
        w_res = w_res + y[0:6]
    tau = ca.vertcat(*(ca.DM(leg_signs(templates, k)) * ys[k][6:9] for k in range(4)))
    tail = ca.Function("id_full_tail", [q, v, a, *ys], [w_res, tau], ["q", "v", "a", *(f"y_{k}" for k in range(4))],
                       ["w_res", "tau"], opts)
    return LegPieces(head, templates, tuple(legs), of, tail)


@cache
def mass_matrix_pieces(robot: Robot) -> LegPieces:
    """M(q)'s nonzero blocks (``mass_blocks``) leg by leg (module docstring)."""
    opts = {"cse": True}
    templates = leg_templates(robot)
    legs = []
    for i, t in enumerate(templates):
        q_l = ca.SX.sym("q_l", 3)
        legs.append(ca.Function(f"M_leg{i}", [q_l, t.p], [leg_mass_parts(t.leg, q_l)], ["q_l", "p"], ["L"], opts))
    of = template_of(templates)
    Ls = [ca.SX.sym(f"L_{k}", legs[of[k]].sparsity_out(0)) for k in range(4)]
    M = assembled_mass_matrix(robot, [unstacked(L, MASS_PARTS) for L in Ls], [leg_signs(templates, k) for k in range(4)])
    tail = ca.Function("M_tail", Ls, [mass_blocks(M)], [f"L_{k}" for k in range(4)], ["M_blocks"], opts)
    return LegPieces(None, templates, tuple(legs), of, tail)


def foot_kinematics(r: ca.SX, q_l: ca.SX, qd_l: ca.SX) -> ca.SX:
    """``FOOT_PARTS`` stacked for a foot position r(q_l)."""
    J = ca.jacobian(r, q_l)
    J_qd = J @ qd_l
    return ca.densify(stacked((r, J, J_qd, ca.jacobian(J_qd, q_l) @ qd_l)))


@cache
def foot_pieces(robot: Robot) -> LegPieces:
    """The four feet's ``FOOT_PARTS`` leg by leg (module docstring): a leg function per template, the tail stacking
    the legs' parts with each J's columns times the leg's signs (J = J_template diag(sigma); r, J qd and Jdot qd are
    the template's at sigma q, sigma qd)."""
    opts = {"cse": True}
    templates = leg_templates(robot)
    legs = []
    for i, t in enumerate(templates):
        q_l, qd_l = ca.SX.sym("q_l", 3), ca.SX.sym("qd_l", 3)
        y = foot_kinematics(canonical_foot_position(t.leg, q_l), q_l, qd_l)
        legs.append(ca.Function(f"foot_leg{i}", [q_l, qd_l, t.p], [y], ["q_l", "qd_l", "p"], ["y"], opts))
    of = template_of(templates)
    Ls = [ca.SX.sym(f"L_{k}", legs[of[k]].sparsity_out(0)) for k in range(4)]
    feet = []
    for k, L in enumerate(Ls):
        x = unstacked(L, FOOT_PARTS)
        feet.append(stacked((x["r"], x["J"] @ ca.diag(ca.DM(leg_signs(templates, k))), x["J_qd"], x["Jdot_qd"])))
    tail = ca.Function("foot_tail", Ls, [ca.horzcat(*feet)], [f"L_{k}" for k in range(4)], ["feet"], opts)
    return LegPieces(None, templates, tuple(legs), of, tail)
