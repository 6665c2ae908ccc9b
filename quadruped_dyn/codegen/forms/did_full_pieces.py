"""did_full as the generated C evaluates it: head, one leg function per leg template, tail (docs/derivatives.md,
"dfd_r and dgrf as generated C"). Equal to ``dynamics.rnea_derivatives.rnea_tangent_derivatives`` (tested): the same leg rows
(``leg_rows``) and the same assembly (``rows_to_derivatives``), with the legs' numbers as a template's parameters.

* ``head(q, v, a) -> a_cl`` (3,): ``newton_euler.trunk_acceleration``, through which alone v_b and gravity enter the
  recursion;
* per leg template, ``leg(w_b, alpha_b, a_cl, q_l, qd_l, qdd_l, p) -> L`` (``LEG_PARTS``): ``leg_rows`` of the
  template;
* ``tail(q, v, a, L_0, ..., L_3) -> (dtau_dq, dtau_dv, dtau_da = M)``: ``rows_to_derivatives`` with the legs' signs.

``did_full_by_leg`` composes the three as a graph: the operations of the C's calls.
"""

from __future__ import annotations

from functools import cache

import casadi as ca

from quadruped_dyn.codegen.forms.leg_pieces import trunk_head, trunk_leg_functions
from quadruped_dyn.codegen.forms.leg_template import LegPieces, leg_signs
from quadruped_dyn.dynamics.rnea_derivatives import leg_rows, rows_to_derivatives
from quadruped_dyn.model.robot import Robot
from quadruped_dyn.model.state import NQ_FULL, NV_FULL


@cache
def did_full_pieces(robot: Robot) -> LegPieces:
    """did_full(q, v, a) -> (dtau_dq, dtau_dv, dtau_da) leg by leg (module docstring)."""
    q, v, a = ca.SX.sym("q", NQ_FULL), ca.SX.sym("v", NV_FULL), ca.SX.sym("a", NV_FULL)
    head = trunk_head("did_full_head", "a_cl")
    templates, legs, of = trunk_leg_functions(
        robot, "did_full", "a_cl", "L",
        lambda leg, w_b, alpha_b, a_cl, q_l, qd_l, qdd_l: leg_rows(leg, q_l, qd_l, qdd_l, w_b, alpha_b, a_cl))
    Ls = [ca.SX.sym(f"L_{k}", legs[of[k]].sparsity_out(0)) for k in range(4)]
    signs = [leg_signs(templates, k) for k in range(4)]
    tail = ca.Function("did_full_tail", [q, v, a, *Ls], list(rows_to_derivatives(robot, q, v, a, Ls, signs)),
                       ["q", "v", "a", *(f"L_{k}" for k in range(4))], ["dtau_dq", "dtau_dv", "dtau_da"], {"cse": True})
    return LegPieces(head, templates, legs, of, tail)


def did_full_by_leg(robot: Robot, q: ca.SX, v: ca.SX, a: ca.SX) -> tuple[ca.SX, ca.SX, ca.SX]:
    """(dtau_dq, dtau_dv, dtau_da = M) (18 x 18 each) composed of ``did_full_pieces``' head, leg and tail functions,
    each leg's inputs times its signs and its parameters as the C passes them."""
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
