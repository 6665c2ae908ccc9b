"""A stance set's maps from its feet's positions alone: what the generated C of the reduced terms evaluates per stance
set, with the feet's kinematics (``leg_pieces.foot_pieces``) and the products by leg in loops around it
(docs/formulation.md §6.2). S_b, T_b, v and a assembled from them equal the reduced model's
(``reduced_projection.ReducedProjection``, ``reduced.reduced_maps``; tested, every stance set of two to four feet).

With k stance feet at r_j (trunk frame, in the order of ``stance.feet``) and J_j the Jacobian of foot j in its leg's
joints (``ReducedProjection``'s forms, linear in what multiplies them):

* W_T (6 x 3k), W^T: the stance forces f = W F_b for a required trunk wrench F_b (force, moment about the trunk
  origin), ``stance_forces``: S_b's rows of stance foot j's joints are -J_j^T W_j = -(W_T,j J_j)^T (W_T,j its columns
  3j..3j+2), a product of the same shape as T_b's;
* Y (6 x 3k) and, for two feet, y_e (6): (v_b, omega_b) = Y u + y_e rate, ``rigid_motion``'s least-squares
  solution of v_b + omega_b x r_j = u_j (and e_phi . omega_b = rate): T_b's columns of foot j's joints are
  -Y_j J_j, its 13th column y_e; v and a are Y and y_e applied to -J_j qd_j and to the stance rows' bias;
* two feet: s_e (6), S_b's 13th row (the required wrench's moment about the foot-to-foot line, ``project``), and
  D (3 x 3) with d/dt e_phi = D omega_b (``roll_rate_row_dot``, linear in omega_b);
* the stance's regularity (``stance_regularity``).
"""

from __future__ import annotations

from functools import cache

import casadi as ca

from quadruped_dyn.dynamics.reduced import roll_rate_row, roll_rate_row_dot
from quadruped_dyn.dynamics.reduced_projection import rigid_motion, stance_forces
from quadruped_dyn.dynamics.stance_regularity import regularity
from quadruped_dyn.math.rigid import skew
from quadruped_dyn.math.spatial import quat_to_rotation
from quadruped_dyn.model.stance import StanceSet


@cache
def stance_maps(stance: StanceSet) -> ca.Function:
    """(r (3k,): the stance feet's positions stacked, quat (4,)) -> (regularity, W_T, Y), and for two feet also
    (y_e, s_e, D) (module docstring); quat read only with two feet (e_phi)."""
    k = len(stance.feet)
    r_all, quat = ca.SX.sym("r", 3 * k), ca.SX.sym("quat", 4)
    r = [r_all[3 * j : 3 * j + 3] for j in range(k)]
    R = quat_to_rotation(quat)
    e = roll_rate_row(R) if k == 2 else None
    F = ca.SX.sym("F_b", 6)
    W = ca.jacobian(stance_forces(stance, r, F[:3], F[3:6]), F)  # linear in F: W exactly
    u, rate = ca.SX.sym("u", 3 * k), ca.SX.sym("rate")
    v_b, omega = rigid_motion(r, [u[3 * j : 3 * j + 3] for j in range(k)], e, rate if e is not None else None)
    motion = ca.vertcat(v_b, omega)
    outputs = {"regularity": regularity(stance, r, e), "W_T": W.T, "Y": ca.jacobian(motion, u)}  # linear in u and rate
    if e is not None:
        line = (r[0] - r[1]) / ca.norm_2(r[0] - r[1])
        omega_s = ca.SX.sym("omega", 3)
        outputs |= {"y_e": ca.jacobian(motion, rate), "s_e": ca.jacobian(line.T @ (F[3:6] - skew(r[0]) @ F[:3]), F).T,
                    "D": ca.jacobian(roll_rate_row_dot(R, omega_s), omega_s)}
    return ca.Function(f"stance_maps_{stance.name.replace('+', '_')}", [r_all, quat],
                       [ca.densify(x) for x in outputs.values()], ["r", "quat"], list(outputs), {"cse": True})
