"""Generated C of the derivatives of the dynamics (docs/derivatives.md).

In ``qd_<robot>-d.c`` (prefix ``qd_``), compiled into the same library as the others:

* ``did_full(q, v, a) -> (dtau_dq, dtau_dv, dtau_da)``: CasADi's Jacobians of the full inverse
  dynamics (``dynamics/derivatives.py``), sparse outputs (leg rows do not depend on other legs);
* ``dfd_full_parts(q, v) -> (M, nle)``: M (dense) and C + G, what the forward-dynamics derivative needs: a
  signature whose body (``c/qd_derivatives_solve.c``) calls ``qd_M_full`` and ``qd_nle_full`` of ``qd_<robot>.c``
  (same library) instead of a second generated copy of them;
* ``dfd_full(q, v, tau_full) -> (da_dq, da_dv, da_dtau)``: a signature only; its body is
  ``c/qd_derivatives_solve.c`` (M^-1 by M's tree structure in plain C, then -M^-1 dtau/dx at a = fd;
  its temporaries in the caller's w, stated as its work size);
* per stance set of 1-4 feet, ``dgrf_dir_<feet>(q, w, dq) -> (lambda_w, dlambda_w)``: the GRF
  solve for a given trunk wrench w, lambda_w = P(q) w (linear in w), and its forward-mode
  directional derivative along dq at fixed w; and ``dgrf_<feet>(q, v, a)``, a signature whose body
  (``c/qd_derivatives_solve.c``) applies the chain rule to lambda = P(q) w_req(q, v, a), w_req the
  rnea's trunk rows: d lambda / dx = P d w_req / dx (``did_full``'s trunk rows) + d(P w)/dq for x = q,
  P column by column and d(P w)/dq one stance-leg joint direction at a time from dgrf_dir.

In each reduced file ``qd_<robot>-r-<feet>.c`` (``reduced_derivative_functions``, ``dfd_r_pieces``):

* ``dfd_r_<feet>(q_r, qd_r, tau_ext, quat)``: a signature whose body (``c/qd_reduced_derivatives.c``)
  applies the chain rule over the full-coordinate derivatives: id_r = S F(q, v, a), F the full rnea, so
  d id_r / dx = d(S_b F_b)/dx + S (dF/dq dq/dx + dF/dv dv/dx + M da/dx) with ``qd_did_full`` and ``qd_id_full``
  (the same library) and S_b, T_b, M as fd_r takes them; then -M_r^-1 with the LU of ``c/qd_reduced_solve.c``.
  Per stance set only "the lift" is generated: the trunk rows v_b, a_b of v and a
  (``ReducedProjection.velocity_and_acceleration``, without forming T) and their forward-mode derivative along
  one direction of (q_r, theta) and one of qd_r at once, with d(S_b F_b) along the q_r direction (2.8-4.3k
  operations on the paper robot), split (``split_at_seeds``) into the static ``qd_dfd_r_lift`` (v_b, a_b and the
  tape, the values the derivative reads; once per call) and ``qd_dfd_r_lift_dir`` (the derivative over the tape,
  ~70 % of the operations; once per stance-leg joint and two feet's rotation: 9-12 calls, at -Os). For every stance
  set also ``qd_dfd_r_lift_columns`` (``lift_columns``: every one of those directions at once, 2.3-2.4x fewer
  operations, ~4x the C), which dfd_r calls instead but at -Os. Its temporaries (~16 kB in double, the tape included) are the
  caller's w, declared by its _work entry (``dfd_r_work_reals``).

Why directions and a chain rule, not CasADi's Jacobians: those take 48-97k operations per reduced
stance set and 18-21k per GRF solve (~20 bytes of C each), beyond the 6 MB budget of a robot's C.
d/dq is along ``pinocchio.integrate`` (a body-frame increment of the trunk pose; 18 columns).
"""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca
import numpy as np

from quadruped_dyn.codegen.by_leg import LegCall, by_leg_c, legs_reals
from quadruped_dyn.codegen.c_facts import DERIVATIVE_SZ_W, derivative_work_c, prelude_c
from quadruped_dyn.codegen.c_file import Entry, FileOptions, c_file, entry_work, evaluation_name, file_helpers
from quadruped_dyn.codegen.file_names import feet_suffix
from quadruped_dyn.codegen.forms.did_full_pieces import did_full_pieces
from quadruped_dyn.codegen.joint_trig import trig_as_inputs
from quadruped_dyn.codegen.precision_math import template_c
from quadruped_dyn.codegen.print_settings import EVALUATION, PREFIX, SINCOS, UNGUARDED
from quadruped_dyn.codegen.printer import SIGNATURE
from quadruped_dyn.dynamics.derivatives import configuration_tangent, full_derivatives, quaternion_tangent
from quadruped_dyn.dynamics.grf import solve_lambda
from quadruped_dyn.dynamics.kinematics import foot_position
from quadruped_dyn.dynamics.newton_euler import full_dynamics
from quadruped_dyn.dynamics.reduced_projection import reduced_projection, stance_forces
from quadruped_dyn.math.rigid import skew
from quadruped_dyn.model.robot import Robot
from quadruped_dyn.model.stance import STANCE_SETS, StanceSet, stance_set
from quadruped_dyn.model.state import JOINT_ANGLES, NQ_FULL, NV_FULL

DERIVATIVE_NAMES = ("did_full", "dfd_full_parts", "dfd_full")
#: Stance sets with a GRF derivative (every set with a foot), as dgrf_parts_<feet> and dgrf_<feet> in qd_<robot>-d.c.
GRF_DERIVATIVE_STANCE_SETS: tuple[StanceSet, ...] = tuple(st for st in STANCE_SETS if st.feet)
GRF_DERIVATIVE_NAMES = ("dgrf_dir", "dgrf")
#: Generated in each reduced stance set's file, as <name>_<feet>.
REDUCED_DERIVATIVE_NAMES = ("dfd_r",)


def grf_derivative_functions(robot: Robot, stance: StanceSet) -> list[ca.Function]:
    """dgrf_dir_<feet> and the signature of dgrf_<feet> (module docstring), with the C prefix."""
    q, w, dq = ca.SX.sym("q", NQ_FULL), ca.SX.sym("w", 6), ca.SX.sym("dq", NV_FULL)
    v, a = ca.SX.sym("v", NV_FULL), ca.SX.sym("a", NV_FULL)
    r = [foot_position(robot.legs[i], q[7 + 3 * i : 10 + 3 * i]) for i in stance.feet]
    if len(r) >= 2:  # the closed forms, ~3x fewer operations than the generic solve: lambda = P^+ f, P's columns disjoint
        P = stance.selection("paper")
        lam = ca.DM(P.T / P.sum(axis=0)[:, None]) @ stance_forces(stance, r, w[:3], w[3:])
    else:
        lam, _ = solve_lambda(stance, "paper", r, w)
    if ca.depends_on(lam, q[:7]):
        raise AssertionError("the GRF solve depends on the trunk pose; qd_dgrf_solve assumes it does not")
    direction = ca.jtimes(lam, q, configuration_tangent(q) @ dq)
    suffix, m, opts = feet_suffix(stance), lam.shape[0], {"cse": True}
    if m > 6:
        raise AssertionError(f"the GRF solve of {stance.name} has {m} unknowns; qd_dgrf_solve holds P (m x 6) for m <= 6")
    grf_dir = ca.Function(f"{PREFIX}dgrf_dir_{suffix}", [q, w, dq], [ca.densify(lam), ca.densify(direction)],
                          ["q", "w", "dq"], ["lambda_w", "dlambda_w"], opts)
    placeholder = ca.repmat(ca.sum1(q) + ca.sum1(v) + ca.sum1(a), m, NV_FULL)  # dense m x 18, depends on every input
    dgrf = ca.Function(f"{PREFIX}dgrf_{suffix}", [q, v, a], [placeholder] * 3, ["q", "v", "a"],
                       ["dlambda_dq", "dlambda_dv", "dlambda_da"], opts)
    return [grf_dir, dgrf]


@dataclass(frozen=True)
class DfdRPieces:
    """What qd_dfd_r_<feet>'s template (``c/qd_reduced_derivatives.c``) calls and is told, for one stance set."""

    #: dfd_r_lift (q_r, qd_r, qdd_r, quat, sin q_r, cos q_r) -> (v_b, a_b (6 each), tape): the lift, and the values
    #: of its algorithm that its derivative reads (``split_at_seeds``), once per dfd_r
    lift: ca.Function
    #: dfd_r_lift_dir (tape, F_b, dq_r, dtheta, dqd_r) -> (dv_b, da_b (6 each), dSF (n), da_qd (6)): the lift's
    #: derivative along (dq_r, dtheta), d(S_b F_b) along dq_r, d a_b along dqd_r; once per stance-leg joint
    lift_dir: ca.Function
    #: dfd_r_lift_columns (tape, F_b) -> (dv_b, da_b (6 x K), dSF (n x K), da_qd (6 x K)): lift_dir at each of the K
    #: unit seeds qd_dfd_r_solve takes, one column each in its order (``lift_columns``); once per dfd_r (but at -Os,
    #: where lift_dir is called per seed: the embedded size budget)
    lift_columns: ca.Function
    legs: int  # bit i set: leg i is a stance leg (the lift and S depend on its joints, not on the others')
    lift_reads_quat: bool  # two feet: the roll row makes v_b, a_b depend on the trunk orientation
    did_legs: int  # reals of did_full's legs' outputs, in dfd_r's w (qd_did_full_trig_in): the Cortex-M stack budget

    @property
    def tape(self) -> int:
        """Reals of the tape (the lift's values its derivative reads)."""
        return self.lift.nnz_out(2)


def dfd_r_pieces(robot: Robot, stance: StanceSet) -> DfdRPieces:
    """The per-stance generated pieces of dfd_r (module docstring) as Functions for static C helpers: the lift
    (``dfd_r_lift``), its sines and cosines as inputs, split at its seeds."""
    lift = dfd_r_lift(robot, stance)
    x = lift.sx_in()
    reads_quat = bool(ca.depends_on(ca.vertcat(*lift.call(x)[:2]), x[3]))
    primal, direction = split_at_seeds(trig_as_inputs(lift, 0), seeds=(4, 5, 6, 7), n_primal_out=2)
    legs = sum(1 << i for i in stance.feet)
    return DfdRPieces(primal, direction, lift_columns(direction, legs, reads_quat), legs, reads_quat,
                      legs_reals(did_full_pieces(robot)))


def lift_seeds(n: int, legs: int, reads_quat: bool) -> list[tuple[np.ndarray, np.ndarray, np.ndarray]]:
    """The seeds (dq_r, dtheta, dqd_r) along which qd_dfd_r_solve (c/qd_reduced_derivatives.c) differentiates the
    lift, in its order: with two feet the rotations theta_k (the roll rate's with theta_0), then each stance-leg
    joint j with its rate (dq_r = dqd_r = e_j)."""
    roll_with_theta = reads_quat and n > 12
    seeds = []
    for k in range(3 if reads_quat else 0):
        dq, dtheta, dqd = np.zeros(n), np.zeros(3), np.zeros(n)
        dtheta[k] = 1
        if k == 0 and roll_with_theta:
            dqd[12] = 1
        seeds.append((dq, dtheta, dqd))
    for j in range(n):
        moves = bool(legs >> (j // 3) & 1) if j < 12 else True
        if moves and not (j >= 12 and roll_with_theta):
            dq, dtheta, dqd = np.zeros(n), np.zeros(3), np.zeros(n)
            dq[j], dqd[j] = float(j < 12), 1
            seeds.append((dq, dtheta, dqd))
    return seeds


def lift_columns(direction: ca.Function, legs: int, reads_quat: bool) -> ca.Function:
    """``direction`` (the lift's derivative over its tape) at every seed of ``lift_seeds`` in one graph: with the
    seeds' zeros and ones known, CasADi drops their products, 2.3-2.4x fewer operations than as many calls of the
    one-direction function (a1: 9 x 2,225 -> 8,563 two feet, 12 x 3,320 -> 16,944 four), at ~4x its C
    (docs/derivatives.md)."""
    n = direction.size1_out(2)
    tape, F_b = (ca.SX.sym(direction.name_in(i), direction.sparsity_in(i)) for i in range(2))
    columns = [direction.call([tape, F_b, *(ca.DM(x) for x in seed)]) for seed in lift_seeds(n, legs, reads_quat)]
    return ca.Function("dfd_r_lift_columns", [tape, F_b],
                       [ca.densify(ca.horzcat(*[c[i] for c in columns])) for i in range(4)],
                       ["tape", "F_b"], ["dv_b", "da_b", "dSF", "da_qd"], {"cse": True})


def dfd_r_lift(robot: Robot, stance: StanceSet) -> ca.Function:
    """dfd_r_lift (q_r, qd_r, qdd_r, quat, F_b, dq_r, dtheta, dqd_r) -> (v_b, a_b, dv_b, da_b, dSF, da_qd): the lift
    and its derivatives in one piece. id_r = S(q_r) F(q, v, a) with F the full rnea (no foot forces) at
    q = (0, quat, joints), v = (v_b, qd_j), a = (a_b, qdd_j): only the trunk rows v_b, a_b ("the lift") depend on
    (q_r, qd_r, quat) other than by identity, S only on the stance legs' joints and only through S_b (S = [S_b, I])."""
    n = 13 if len(stance.feet) == 2 else 12
    q_r, qd_r, qdd_r, quat = (ca.SX.sym(s, k) for s, k in (("q_r", n), ("qd_r", n), ("qdd_r", n), ("quat", 4)))
    dq_r, dtheta, dqd_r, F_b = ca.SX.sym("dq_r", n), ca.SX.sym("dtheta", 3), ca.SX.sym("dqd_r", n), ca.SX.sym("F_b", 6)
    p = reduced_projection(robot, stance, q_r, quat)
    v, a = p.velocity_and_acceleration(qd_r, qdd_r)
    trunk = ca.vertcat(v[:6], a[:6])
    SF = p.project(ca.vertcat(F_b, ca.SX.zeros(12)))
    swing = [x[3 * i + j] for x in (q_r, qd_r) for i in range(4) if i not in stance.feet for j in range(3)]
    swing += [q_r[k] for k in range(12, n)]
    if any(ca.depends_on(ca.vertcat(trunk, SF), x) for x in swing) or ca.depends_on(SF, quat):
        raise AssertionError("the lift or S reads a swing leg's joint or rate or the roll q_r[12], or S reads quat; "
                             "qd_dfd_r_solve assumes neither")
    lifted = ca.jtimes(trunk, ca.vertcat(q_r, quat), ca.vertcat(dq_r, quaternion_tangent(quat) @ dtheta))
    return ca.Function("dfd_r_lift", [q_r, qd_r, qdd_r, quat, F_b, dq_r, dtheta, dqd_r],
                       [v[:6], a[:6], lifted[:6], lifted[6:], ca.jtimes(SF, q_r, dq_r), ca.jtimes(a[:6], qd_r, dqd_r)],
                       {"cse": True})


def split_at_seeds(f: ca.Function, seeds: tuple[int, ...], n_primal_out: int) -> tuple[ca.Function, ca.Function]:
    """``f``'s algorithm in two: the primal (the instructions that read no input in ``seeds``: inputs the others,
    outputs f's first ``n_primal_out`` and the tape, the primal values the rest reads) and the direction (inputs
    the tape and the seeds, outputs f's others). A caller evaluating f at one point along many seeds (dfd_r's
    lift, 7-13 directions) runs the primal once and only the direction per seed. The same operations in the same
    order, rebuilt instruction by instruction from f's algorithm (so the same results to the digit)."""
    ins = [ca.SX.sym(f.name_in(i), f.sparsity_in(i)) for i in range(f.n_in())]
    outs = [ca.SX(f.sparsity_out(i)) for i in range(f.n_out())]
    tape_sym = ca.SX.sym("tape", f.n_instructions())
    work: dict[int, tuple[ca.SX, bool]] = {}  # slot -> (value, whether it reads a seed)
    tape: dict[int, int] = {}  # a primal value (its element_hash) -> its entry of the tape
    tape_values: list[ca.SX] = []

    def read(slot: int) -> ca.SX:  # a value as the direction's algorithm sees it
        value, seeded = work[slot]
        if seeded or value.is_constant():
            return value
        if value.element_hash() not in tape:
            tape[value.element_hash()] = len(tape_values)
            tape_values.append(value)
        return tape_sym[tape[value.element_hash()]]

    for k in range(f.n_instructions()):
        op, a, r = f.instruction_id(k), f.instruction_input(k), f.instruction_output(k)
        if op == ca.OP_OUTPUT:
            if r[0] < n_primal_out:
                if work[a[0]][1]:
                    raise AssertionError(f"{f.name()}: output {r[0]} reads a seed; split_at_seeds assumes it does not")
                outs[r[0]].nz[r[1]] = work[a[0]][0]
            else:
                outs[r[0]].nz[r[1]] = read(a[0])
        elif op == ca.OP_INPUT:
            work[r[0]] = (ins[a[0]].nz[a[1]], a[0] in seeds)
        elif op == ca.OP_CONST:
            work[r[0]] = (ca.SX(f.instruction_constant(k)), False)
        elif any(work[x][1] for x in a):
            args = [read(x) for x in a]
            work[r[0]] = (ca.SX.unary(op, *args) if len(a) == 1 else ca.SX.binary(op, *args), True)
        else:
            args = [work[x][0] for x in a]
            work[r[0]] = (ca.SX.unary(op, *args) if len(a) == 1 else ca.SX.binary(op, *args), False)
    others = [i for i in range(f.n_in()) if i not in seeds]
    primal = ca.Function(f.name(), [ins[i] for i in others], [*outs[:n_primal_out], ca.vertcat(*tape_values)],
                         [f.name_in(i) for i in others], [*f.name_out()[:n_primal_out], "tape"], {"cse": True})
    direction = ca.Function(f.name() + "_dir", [tape_sym[:len(tape_values)], *(ins[i] for i in seeds)],
                            outs[n_primal_out:], ["tape", *(f.name_in(i) for i in seeds)], f.name_out()[n_primal_out:],
                            {"cse": True})
    return primal, direction


def dfd_r_work_reals(n: int, tape: int, did_legs: int) -> int:
    """Reals of caller work memory qd_dfd_r_<feet> uses (``QD_DFD_R_W`` of c/qd_reduced_derivatives.c, which
    checks at compile time that the two agree): M_r's LU, qdd_r, S_b, T_b, M, d rnea/dq, d rnea/dv, F, one
    full-coordinate column, one reduced column, the 3 n + 3 right-hand sides of the one LU solve, the lift's
    tape (``DfdRPieces.tape``) and did_full's legs' outputs (``DfdRPieces.did_legs``)."""
    return n * n + 14 * n + 3 * 18 * 18 + 36 + n * (3 * n + 3) + tape + did_legs


def reduced_derivative_functions(robot: Robot, stance: StanceSet) -> list[ca.Function]:
    """The signature of dfd_r_<feet> (module docstring), with the C prefix: its body is the template's."""
    n = 13 if len(stance.feet) == 2 else 12
    q_r, qd_r, tau_ext, quat = ca.SX.sym("q_r", n), ca.SX.sym("qd_r", n), ca.SX.sym("tau_ext", n), ca.SX.sym("quat", 4)
    placeholder = ca.sum1(q_r) + ca.sum1(qd_r) + ca.sum1(tau_ext) + ca.sum1(quat)  # dense, depends on every input
    dfd = ca.Function(f"{PREFIX}dfd_r_{feet_suffix(stance)}", [q_r, qd_r, tau_ext, quat],
                      [ca.repmat(placeholder, n, k) for k in (n, n, n, 3)], ["q_r", "qd_r", "tau_ext", "quat"],
                      ["dqdd_dq", "dqdd_dqd", "dqdd_dtau", "dqdd_dtheta"], {"cse": True})
    return [dfd]


def derivative_functions(robot: Robot) -> list[ca.Function]:
    """The generated derivative Functions, named with the C prefix."""
    q, v, a, tau = ca.SX.sym("q", NQ_FULL), ca.SX.sym("v", NV_FULL), ca.SX.sym("a", NV_FULL), ca.SX.sym("tau_full", NV_FULL)
    d, fd = full_derivatives(robot), full_dynamics(robot)
    opts = {"cse": True}
    did = ca.Function(PREFIX + "did_full", [q, v, a], d.did_full.call([q, v, a]), ["q", "v", "a"],
                      ["dtau_dq", "dtau_dv", "dtau_da"], opts)
    M = did.sparsity_out(2)
    if any(M.has_nz(6 + 3 * leg + i, 6 + 3 * other + j) for leg in range(4) for other in range(4) if leg != other
           for i in range(3) for j in range(3)):
        raise AssertionError("M couples two legs; qd_d_tree_inverse assumes each leg couples only to the trunk")
    trunk = d.did_full.call([q, v, a])[2][0:3, 0:3]  # qd_dfd_full_solve reads [g_b]x from dtau_dq's rotation columns / m
    dq = did.sparsity_out(0)
    if (not all(trunk[i, j].is_constant() and float(trunk[i, j]) == (float(trunk[0, 0]) if i == j else 0.0)
                for i in range(3) for j in range(3)) or dq.is_dense() or any(dq.colind()[j] != 0 for j in range(4))):
        raise AssertionError("M[0:3, 0:3] is not m I or dtau_dq has position entries; qd_dfd_full_solve assumes both")
    dv = did.sparsity_out(1)
    if any(sp.colind()[j] == sp.colind()[j + 1] for sp, first in ((dq, 6), (dv, 3)) for j in range(first, NV_FULL)):
        raise AssertionError("a column of dtau_dq[:, 6:] or dtau_dv[:, 3:] is empty; qd_d_neg_product assumes none is")
    if not _linear_velocity_columns_are_m_wx(did, q, v, a):
        raise AssertionError("dtau_dv[:, 0:3] is not M[:, 0:3] [w_b]x; qd_dfd_full_solve writes da/dv_b = -[[w_b]x; 0]")
    if (fd.M_full_crba.name_in(), fd.nle_full.name_in()) != (["q"], ["q", "v"]):
        raise AssertionError("qd_dfd_full_parts calls qd_M_full(q) and qd_nle_full(q, v)")
    dense = ca.sum1(q) + ca.sum1(v)  # a placeholder depending on every input: the template's body computes
    parts = ca.Function(PREFIX + "dfd_full_parts", [q, v], [ca.repmat(dense, NV_FULL, NV_FULL), ca.repmat(dense, NV_FULL, 1)],
                        ["q", "v"], ["M", "nle"], opts)
    placeholder = ca.repmat(tau, 1, NV_FULL) + ca.sum1(q) + ca.sum1(v)  # dense 18 x 18, depends on every input
    dfd = ca.Function(PREFIX + "dfd_full", [q, v, tau], [placeholder] * 3, ["q", "v", "tau_full"],
                      ["da_dq", "da_dv", "da_dtau"], opts)
    return [did, parts, dfd, *(f for st in GRF_DERIVATIVE_STANCE_SETS for f in grf_derivative_functions(robot, st))]


def _linear_velocity_columns_are_m_wx(did: ca.Function, q: ca.SX, v: ca.SX, a: ca.SX) -> bool:
    """did_full's v_b columns are M[:, 0:3] [w_b]x: linear in w_b alone, and equal to it exactly for w_b = e_k (a
    product with 0 and +-1, no rounding) at a fixed configuration."""
    dv_b = did.call([q, v, a])[1][:, 0:3]
    if not ca.is_linear(dv_b, v[3:6]) or ca.depends_on(dv_b, ca.vertcat(v[0:3], v[6:], a)):
        return False
    q0 = np.r_[0.0, 0.0, 0.0, 0.1, -0.2, 0.3, 0.9, np.linspace(-0.7, 0.8, 12)]
    for k in range(3):
        w = np.eye(3)[k]
        _, dv, M = (np.asarray(ca.densify(x)) for x in did(q0, np.r_[0.0, 0.0, 0.0, w, np.zeros(12)], np.zeros(NV_FULL)))
        if not np.array_equal(dv[:, 0:3], M[:, 0:3] @ np.asarray(skew(w))):
            return False
    return True


#: qd_did_full_trig's arg (q, v, a, sin, cos) as did_full's pieces read it (``rnea_derivatives.did_full_pieces``).
DID_FULL_CALL = LegCall(head_args=(0, 1, 2), leg_inputs=(("arg", 1, 3), ("arg", 2, 3), ("head", 0), ("joint", 0, 7),
                                                         ("joint", 1, 6), ("joint", 2, 6)),
                        sin_arg=3, tail_args=(0, 1, 2))


def _did_full_trig_once(did: ca.Function, robot: Robot, host_helpers: frozenset[str]) -> str:
    """did_full's evaluation casadi_f0 as the joints' sines and cosines taken once (c/qd_sincos.c) and qd_did_full_trig
    reading them, did_full leg by leg (``by_leg``, docs/derivatives.md "dfd_r and dgrf as generated C"), also called by
    dfd_r (c/qd_reduced_derivatives.c), which has the sines and cosines already. Its callers pass every input
    (qd_d_all_inputs gives a NULL one qd_d_zeros)."""
    if did.n_in() > 3 or max(did.nnz_in(i) for i in range(did.n_in())) > NQ_FULL:
        raise AssertionError(f"{did.name()}: more inputs or reals than qd_d_all_inputs holds")
    exported = by_leg_c("qd_did_full_trig", did_full_pieces(robot), DID_FULL_CALL, host_helpers,
                        test_outputs=True, export_in=True)  # dfd_r lends the legs' outputs its w (stack budget)
    n = len(JOINT_ANGLES)
    wrapper = (f"static int {evaluation_name(0)}{SIGNATURE} {{\n"
               f"  casadi_real s[{n}], c[{n}]; /* the joints' sines and cosines, once (qd_sincos) */\n"
               f"  qd_sincos({n}, arg[0] + {JOINT_ANGLES.start}, c, s);\n"
               f"  const casadi_real* a[{did.n_in() + 2}] = {{{', '.join(f'arg[{i}]' for i in range(did.n_in()))}, s, c}};\n"
               f"  return qd_did_full_trig(a, res, iw, w, mem);\n}}\n")
    return template_c(SINCOS) + "\n" + exported + "\n" + wrapper


def _derivative_entry(f: ca.Function, index: dict[str, str], template_w: dict[str, int]) -> Entry:
    """How qd_<robot>-d.c prints ``f`` (``derivative_source``); ``index``: function name -> its evaluation's C name."""
    name, raw = f.name()[len(PREFIX):], index[f.name()]
    nnz = ", ".join(str(f.nnz_out(i)) for i in range(f.n_out()))
    did = index[PREFIX + "did_full"]
    sparsity = f"{PREFIX}did_full_sparsity_out(0), {PREFIX}did_full_sparsity_out(1)"
    if name == "dfd_full_parts":  # the template's qd_dfd_full_parts_eval: qd_M_full and qd_nle_full
        return Entry(f, None, f"  return qd_d_finite(qd_dfd_full_parts_eval(arg, res, iw, w, mem), res, 2, "
                              f"(const casadi_int[]){{{nnz}}});\n")
    if name == "dfd_full":  # the template solves, its temporaries in the caller's w
        return Entry(f, None, f"  return qd_dfd_full_solve({did}, {sparsity}, arg, res, iw, w, mem);\n",
                     template_w["DFD_FULL"])
    if name.startswith("dgrf_") and not name.startswith("dgrf_dir_"):
        suffix = name[len("dgrf_"):]
        legs = sum(1 << i for i in stance_set(suffix.replace("_", "+")).feet)  # the joints lambda reads
        direction = index[f"{PREFIX}dgrf_dir_{suffix}"]
        return Entry(f, None, f"  return qd_dgrf_solve({f.size1_out(0)}, {legs}, {did}, {direction}, {sparsity}, arg, "
                              "res, iw, w, mem);\n", template_w["DGRF"])
    if name in UNGUARDED:  # did_full: its evaluation reads the inputs unguarded: NULL ones are zeros here
        return Entry(f, EVALUATION, f"  return qd_d_finite(qd_d_all_inputs({raw}, {f.n_in()}, arg, res, iw, w, mem), "
                                    f"res, {f.n_out()}, (const casadi_int[]){{{nnz}}});\n")
    return Entry(f, EVALUATION, f"  return qd_d_finite({raw}(arg, res, iw, w, mem), res, {f.n_out()}, "
                                f"(const casadi_int[]){{{nnz}}});\n")


def derivative_source(robot: Robot, file_stem: str, functions: list[ca.Function],
                      precision: str) -> tuple[str, str, dict[str, tuple[int, int]]]:
    """(C source, header, work sizes) of qd_<robot>-d.c: c/qd_dense.c and c/qd_derivatives_solve.c, then the
    functions; every entry point returns QD_NONFINITE for a non-finite output, dfd_full solves. dfd_full calls
    qd_did_full_sparsity_out, defined further down: declared first."""
    declaration = f"CASADI_SYMBOL_EXPORT const casadi_int* {PREFIX}did_full_sparsity_out(casadi_int i);\n"
    solve = template_c("qd_derivatives_solve.c")
    template = prelude_c() + declaration + "\n" + derivative_work_c() + "\n" + solve
    template_w = {k: reals for k, (reals, _) in DERIVATIVE_SZ_W.items()}
    index = {f.name(): evaluation_name(k) for k, f in enumerate(functions)}
    entries = [_derivative_entry(f, index, template_w) for f in functions]
    if functions[0].name() != PREFIX + "did_full":
        raise AssertionError("qd_<robot>-d.c's first function is not did_full, whose evaluation it prints leg by leg")
    entries[0] = Entry(functions[0], _did_full_trig_once(functions[0], robot, file_helpers(functions)), entries[0].body)
    preamble = template_c("qd_dense.c") + "\n" + template + "\n"
    options = FileOptions(precision, preamble=preamble, precision_math=True)
    return (*c_file(file_stem, entries, options), entry_work(entries))
