"""id_full, M's blocks and the feet's kinematics leg by leg: the pieces the reduced files' C calls (``LegPieces``;
docs/derivatives.md, "dfd_r and dgrf as generated C", and docs/formulation.md §6.2). Each equals the whole-robot
algorithm it stands for (tested, every built-in robot):

* ``id_full_pieces`` equals ``newton_euler.inverse_dynamics`` without foot forces (the reduced terms' rnea: their foot
  forces are the GRF projection's): head(q, v, a) -> a0 (``newton_euler.trunk_acceleration``); leg(w_b, alpha_b, a0,
  q_l, qd_l, qdd_l, p) -> (the leg's wrench on the trunk (6), its torques (3)) by the leg's Newton-Euler recursion;
  tail(q, v, a, y_0..y_3) -> (w_res, tau) = (the trunk's own wrench + the legs', the legs' torques);
* ``mass_matrix_pieces`` equals ``crba.mass_matrix_crba``: leg(q_l, p) -> the leg's ``MASS_PARTS``; tail(L_0..L_3) ->
  M's nonzero blocks (``mass_blocks``);
* ``foot_pieces`` equals ``kinematics.foot_position`` and its derivatives: leg(q_l, qd_l, p) -> the foot's
  ``FOOT_PARTS`` (trunk frame); tail(L_0..L_3) -> the four feet's, each leg's J turned back by its signs. The reduced
  files call the leg function for their stance legs only (``stance_maps``).

Why leg by leg: the reduced terms call id_full and M each once per call, ~60 kB of machine code per fd_r call against
a 32 kB instruction cache; one leg function serves the four legs (docs/benchmark.md, "Design choices").
"""

from __future__ import annotations

from collections.abc import Callable
from functools import cache

import casadi as ca

from quadruped_dyn.codegen.forms.leg_template import LegPieces, LegTemplate, leg_signs, leg_templates, template_of
from quadruped_dyn.dynamics.crba import MASS_PARTS, assembled_mass_matrix, leg_mass_parts
from quadruped_dyn.dynamics.kinematics import canonical_foot_position
from quadruped_dyn.dynamics.newton_euler import aligned_leg_newton_euler, trunk_acceleration, trunk_own_wrench
from quadruped_dyn.math.spatial import dm, stacked, unstacked
from quadruped_dyn.model.leg import Leg
from quadruped_dyn.model.robot import Robot
from quadruped_dyn.model.state import NQ_FULL, NV_FULL

#: A leg's foot kinematics, in order (trunk frame): its position r [m], J = dr/dq_l (column-major), J qd_l [m/s] and
#: Jdot qd_l [m/s^2] (the foot's classical acceleration relative to the trunk at qdd_l = 0).
FOOT_PARTS: tuple[tuple[str, int, int], ...] = (("r", 3, 1), ("J", 3, 3), ("J_qd", 3, 1), ("Jdot_qd", 3, 1))
#: M's nonzero blocks as ``mass_blocks`` stacks them: M_bb, then per leg (``LEG_MASS_BLOCKS``, four times) M_bl, M_ll.
TRUNK_MASS_BLOCKS: tuple[tuple[str, int, int], ...] = (("M_bb", 6, 6),)
LEG_MASS_BLOCKS: tuple[tuple[str, int, int], ...] = (("M_bl", 6, 3), ("M_ll", 3, 3))


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


def trunk_head(name: str, output: str) -> ca.Function:
    """The head of id_full's and did_full's pieces: (q, v, a) -> ``trunk_acceleration``, named ``output``."""
    q, v, a = ca.SX.sym("q", NQ_FULL), ca.SX.sym("v", NV_FULL), ca.SX.sym("a", NV_FULL)
    return ca.Function(name, [q, v, a], [trunk_acceleration(q, v, a)], ["q", "v", "a"], [output], {"cse": True})


def trunk_leg_functions(robot: Robot, prefix: str, acceleration: str, output: str,
                        rows: Callable[..., ca.SX]) -> tuple[tuple[LegTemplate, ...], tuple[ca.Function, ...], tuple[int, ...]]:
    """(templates, one leg function per template, template_of) for a leg function of the trunk's motion:
    ``{prefix}_leg{i}(w_b, alpha_b, <acceleration>, q_l, qd_l, qdd_l, p) -> <output>`` = rows(template leg, w_b,
    alpha_b, acceleration, q_l, qd_l, qdd_l) (trunk frame; the acceleration ``trunk_head``'s)."""
    names = ("w_b", "alpha_b", acceleration, "q_l", "qd_l", "qdd_l")
    templates = leg_templates(robot)
    legs = []
    for i, t in enumerate(templates):
        xs = [ca.SX.sym(n, 3) for n in names]
        legs.append(ca.Function(f"{prefix}_leg{i}", [*xs, t.p], [rows(t.leg, *xs)], [*names, "p"], [output],
                                {"cse": True}))
    return templates, tuple(legs), template_of(templates)


def _wrench_and_torques(leg: Leg, w_b: ca.SX, alpha_b: ca.SX, a0: ca.SX, q_l: ca.SX, qd_l: ca.SX, qdd_l: ca.SX) -> ca.SX:
    """(the leg's wrench on the trunk (6), its torques (3)) by its Newton-Euler recursion, no foot force."""
    lf = aligned_leg_newton_euler(leg, q_l, qd_l, qdd_l, w_b, alpha_b, a0, ca.SX.zeros(3))
    return ca.vertcat(lf.f1, lf.n1 + ca.cross(dm(leg.hip), lf.f1), lf.tau)


@cache
def id_full_pieces(robot: Robot) -> LegPieces:
    """id_full(q, v, a, f = 0) -> (w_res, tau) leg by leg (module docstring)."""
    q, v, a = ca.SX.sym("q", NQ_FULL), ca.SX.sym("v", NV_FULL), ca.SX.sym("a", NV_FULL)
    head = trunk_head("id_full_head", "a0")
    templates, legs, of = trunk_leg_functions(robot, "id_full", "a0", "y", _wrench_and_torques)
    ys = [ca.SX.sym(f"y_{k}", legs[of[k]].sparsity_out(0)) for k in range(4)]
    w_res = trunk_own_wrench(robot.trunk, v[3:6], a[3:6], trunk_acceleration(q, v, a))
    for y in ys:
        w_res = w_res + y[0:6]
    tau = ca.vertcat(*(ca.DM(leg_signs(templates, k)) * ys[k][6:9] for k in range(4)))
    tail = ca.Function("id_full_tail", [q, v, a, *ys], [w_res, tau], ["q", "v", "a", *(f"y_{k}" for k in range(4))],
                       ["w_res", "tau"], {"cse": True})
    return LegPieces(head, templates, legs, of, tail)


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
