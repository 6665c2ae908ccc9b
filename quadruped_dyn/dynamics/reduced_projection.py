"""The reduced terms as projections of the full ones: the forms generated as C (docs/formulation.md §6.2, §11).

``reduced`` follows the paper's recipe (id_r through the maps and the GRF solve; M_r column by
column, Walker & Orin): that is the reference. The same quantities, written so that the work is
shared (equal to ``reduced`` to round-off, tested):

* Acceleration map, linear in qdd_r: a = vdot = T(q_r, R) qdd_r + k(q_r, qd_r, R), T (18, n).
  The stance-foot rows v_b + omega_b x r_i = u_i (plus, for two feet, the roll row
  e_phi . omega_b = rate) are solved by least squares in closed form: with the feet's centroid
  rbar and rho_i = r_i - rbar the normal equations decouple into
      (K + e_phi e_phi^T) omega_b = sum_i rho_i x u_i (+ e_phi rate),  K = sum_i (|rho_i|^2 I - rho_i rho_i^T),
      v_b = mean_i(u_i) - omega_b x rbar,
  one symmetric 3 x 3 solve (K alone for three or four feet; K is singular for collinear feet).
* GRF projection, linear in the full generalized force F (18,) = M_full a + nle(q, v):
  tau_r = S(q_r, R) F, S = [-J_s^T P A+, I_12] (the paper's GRF model, minimum norm), and for
  two feet the 13th row e . (residual moment - r_1 x residual force) = e . (F_moment - r_1 x F_force),
  the required trunk wrench's moment about the foot-to-foot line (the feet produce none).
Hence, with rnea(q, v, a) the project's Newton-Euler with zero foot forces and gravity on,
    M_r = S M_full T,   C_r + G_r = S rnea(q, v, k),   G_r = S G_full = S rnea(q, 0, 0),   id_r = S rnea(q, v, T qdd_r + k),
M_full and G_full by composite rigid bodies (``crba``); S and T are computed once and shared. The generated
C forms S_b, T_b (``mass_matrix_factors``' S_b and T_b) and v, a (``velocity_and_acceleration``) per stance set from the
stance's maps and the feet's kinematics (``codegen.forms.stance_maps``, ``leg_pieces.foot_pieces``) and takes M_full,
G_full and rnea from the robot's full-coordinate C, the products in loops (docs/formulation.md §6.2).
"""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca

from quadruped_dyn.dynamics.crba import generalized_gravity, mass_matrix_crba
from quadruped_dyn.dynamics.kinematics import foot_position
from quadruped_dyn.dynamics.newton_euler import inverse_dynamics
from quadruped_dyn.dynamics.reduced import roll_rate_row, roll_rate_row_dot
from quadruped_dyn.math.rigid import skew
from quadruped_dyn.math.spatial import dm, quat_to_rotation
from quadruped_dyn.model.leg import LEG_LABELS
from quadruped_dyn.model.robot import Robot
from quadruped_dyn.model.stance import StanceSet
from quadruped_dyn.model.state import GRAVITY_W, NV_FULL


def _solve3(K: ca.SX, b: ca.SX) -> ca.SX:
    """K^-1 b for a 3 x 3 K, by its adjugate (K here is conditioned like the foot layout,
    ~1e1-1e2; it is singular, and the result not finite, for collinear feet)."""
    adj = ca.SX(3, 3)
    for i in range(3):
        for j in range(3):
            r = [x for x in range(3) if x != j]
            c = [x for x in range(3) if x != i]
            adj[i, j] = (-1) ** (i + j) * (K[r[0], c[0]] * K[r[1], c[1]] - K[r[0], c[1]] * K[r[1], c[0]])
    det = K[0, 0] * adj[0, 0] + K[0, 1] * adj[1, 0] + K[0, 2] * adj[2, 0]
    return (adj @ b) / det


def rigid_motion(r: list[ca.SX], u: list[ca.SX], e: ca.SX | None = None, rate: ca.SX | None = None) -> tuple[ca.SX, ca.SX]:
    """Least-squares (v, omega) with v + omega x r_i = u_i for every stance foot i (and
    e . omega = rate), in closed form (module docstring). Each u_i (3, m) and rate (1, m) may
    hold m right-hand sides."""
    k = len(r)
    rbar = sum(r[1:], r[0]) / k
    if k == 2:  # rho = +-h: one outer product, one cross product (the same sums, fewer operations)
        h = (r[0] - r[1]) / 2
        K = 2 * (ca.dot(h, h) * ca.SX.eye(3) - h @ h.T)
        rhs = skew(h) @ (u[0] - u[1])
    else:
        rho = [ri - rbar for ri in r]
        K = sum((ca.dot(p, p) * ca.SX.eye(3) - p @ p.T for p in rho[1:]),
                ca.dot(rho[0], rho[0]) * ca.SX.eye(3) - rho[0] @ rho[0].T)
        rhs = sum((skew(p) @ ui for p, ui in zip(rho[1:], u[1:])), skew(rho[0]) @ u[0])
    if e is not None and rate is not None:
        K, rhs = K + e @ e.T, rhs + e @ rate
    omega = _solve3(K, rhs)
    return sum(u[1:], u[0]) / k + skew(rbar) @ omega, omega


def _two_feet_forces(r: list[ca.SX], force: ca.SX, moment: ca.SX) -> ca.SX:
    """The paper's two-foot GRF (all six components free) in closed form: the pseudo-inverse
    solution (f_1, f_2) (6, m) for the required trunk wrench (force, moment about the trunk
    origin; 3, m each), as grf.solve_lambda's explicit null-space solve gives it (tested).
    The wrench is first projected onto what the feet can produce, removing its component
    along the left null vector u = (r_1 x e, e) / |.| (e along d = r_1 - r_2); then, with rbar
    the feet's midpoint, f_1,2 = force / 2 +- g with d x g = moment - rbar x force, whose
    minimum-norm solution (g orthogonal to d) is g = (moment - rbar x force) x d / |d|^2."""
    d, rbar = r[0] - r[1], (r[0] + r[1]) / 2
    u_f, u_m = ca.cross(r[0], d), d
    unbalanced = (u_f.T @ force + u_m.T @ moment) / (ca.dot(u_f, u_f) + ca.dot(u_m, u_m))
    force, moment = force - u_f @ unbalanced, moment - u_m @ unbalanced
    g = -skew(d) @ (moment - skew(rbar) @ force) / ca.dot(d, d)
    return ca.vertcat(force / 2 + g, force / 2 - g)


def _three_feet_forces(stance: StanceSet, r: list[ca.SX], force: ca.SX, moment: ca.SX) -> ca.SX:
    """The paper's three-foot GRF in closed form (its 6 x 6 system is regular): per foot
    (fx, fy_i, fz_i) (9, m) with fx common, fy_i = fy_same for the foot on the lifted leg's side
    and fy_opp for the other two, for the required trunk force and moment (3, m each, about the
    trunk origin). fx = F_x / 3; (fy_same, fy_opp) from F_y and the yaw moment; the fz from F_z
    and the roll and pitch moments (the support triangle's 3 x 3 system). Equal to
    grf.solve_lambda's QR solve (tested)."""
    side = LEG_LABELS[stance.lifted[0]][1]
    same = [LEG_LABELS[i][1] == side for i in stance.feet]
    x, y, z = ([ri[c] for ri in r] for c in range(3))
    fx = force[0, :] / 3
    n_roll = moment[0, :]
    n_pitch = moment[1, :] - (z[0] + z[1] + z[2]) * fx
    n_yaw = moment[2, :] + (y[0] + y[1] + y[2]) * fx
    x_same = sum(xi for xi, s_ in zip(x, same) if s_)
    x_opp = sum(xi for xi, s_ in zip(x, same) if not s_)
    det = 2 * x_same - x_opp  # x_same fy_s + x_opp fy_o = n_yaw, fy_s + 2 fy_o = F_y
    fy_same = (2 * n_yaw - x_opp * force[1, :]) / det
    fy_opp = (x_same * force[1, :] - n_yaw) / det
    fy = [fy_same if s_ else fy_opp for s_ in same]
    B = ca.vertcat(ca.horzcat(1, 1, 1), ca.horzcat(*y), -ca.horzcat(*x))
    fz = _solve3(B, ca.vertcat(force[2, :], n_roll + z[0] * fy[0] + z[1] * fy[1] + z[2] * fy[2], n_pitch))
    return ca.vertcat(*[ca.vertcat(fx, fy[j], fz[j, :]) for j in range(3)])


def _four_feet_forces(r: list[ca.SX], force: ca.SX, moment: ca.SX) -> ca.SX:
    """The paper's four-foot GRF (fz per foot, fx and fy common) in closed form: the
    pseudo-inverse solution, per foot (fx, fy, fz_i) (12, m), as grf.solve_lambda's null-space
    solve gives it (tested). The wrench is first projected onto what the model can produce,
    removing its component along the left null vector u = (ybar, -xbar, 0, 0, 0, 1) (a yaw
    moment off the line xbar F_y - ybar F_x); then fx = F_x / 4, fy = F_y / 4, and the fz are
    the minimum-norm solution of F_z and the roll and pitch moments: fz = B^T (B B^T)^-1 rhs,
    B = [1; y; -x] (3 x 4)."""
    x, y, z = (ca.vertcat(*[ri[c] for ri in r]) for c in range(3))
    u_f = ca.vertcat(ca.sum1(y) / 4, -ca.sum1(x) / 4, 0)
    unbalanced = (u_f.T @ force + moment[2, :]) / (1 + ca.dot(u_f, u_f))
    force = force - u_f @ unbalanced
    fx, fy = force[0, :] / 4, force[1, :] / 4
    Z = ca.sum1(z)
    B = ca.horzcat(ca.SX.ones(4), y, -x).T
    fz = B.T @ _solve3(B @ B.T, ca.vertcat(force[2, :], moment[0, :] + Z * fy, moment[1, :] - Z * fx))
    return ca.vertcat(*[ca.vertcat(fx, fy, fz[j, :]) for j in range(4)])


def stance_forces(stance: StanceSet, r: list[ca.SX], force: ca.SX, moment: ca.SX) -> ca.SX:
    """The paper's GRF of 2, 3 or 4 stance feet at r (trunk frame) in closed form: the stacked
    stance-foot forces (3k, m), trunk frame, for the required trunk force and moment (3, m each,
    moment about the trunk origin); equal to ``grf.solve_lambda``'s forces P lambda (tested)."""
    forces = {2: lambda: _two_feet_forces(r, force, moment), 3: lambda: _three_feet_forces(stance, r, force, moment),
              4: lambda: _four_feet_forces(r, force, moment)}
    return forces[len(r)]()


@dataclass(frozen=True)
class ReducedProjection:
    """Symbolic pieces of one stance set's reduced model (n = 12 or 13 coordinates)."""

    robot: Robot
    stance: StanceSet
    n: int
    q_r: ca.SX
    quat: ca.SX
    T: ca.SX  # (18, n): a = T qdd_r + k
    r: list[ca.SX]  # stance-foot positions, trunk frame
    g_b: ca.SX  # gravity in the trunk frame

    @property
    def q_joints(self) -> ca.SX:
        return self.q_r[:12]

    def velocity_and_bias(self, qd_r: ca.SX) -> tuple[ca.SX, ca.SX]:
        """(v (18,), k (18,)): the full velocity and the acceleration at qdd_r = 0 (a = vdot,
        spatial for the trunk: vdot_b = a_b - omega_b x v_b)."""
        return self._motion(qd_r, None)

    def velocity_and_acceleration(self, qd_r: ca.SX, qdd_r: ca.SX) -> tuple[ca.SX, ca.SX]:
        """(v (18,), a (18,) = T qdd_r + k) without forming T: the stance rows are solved once for the
        right-hand side of qdd_r and the bias together (``rigid_motion`` is linear in it). Fewer operations than
        T @ qdd_r + k, and a cheaper derivative (dfd_r's lift, ``codegen/emit_derivatives.py``)."""
        return self._motion(qd_r, qdd_r)

    def _motion(self, qd_r: ca.SX, qdd_r: ca.SX | None) -> tuple[ca.SX, ca.SX]:
        feet = self.stance.feet
        qj, qdj = self.q_joints, qd_r[:12]
        J = [ca.jacobian(ri, qj[3 * i : 3 * i + 3]) for ri, i in zip(self.r, feet)]
        Jqd = [Ji @ qdj[3 * i : 3 * i + 3] for Ji, i in zip(J, feet)]
        e = roll_rate_row(quat_to_rotation(self.quat)) if len(feet) == 2 else None
        v_b, omega = rigid_motion(self.r, [-x for x in Jqd], e, qd_r[12] if e is not None else None)
        rhs = []
        for ri, Ji, x, i in zip(self.r, J, Jqd, feet):
            s = slice(3 * i, 3 * i + 3)
            Jdqd = ca.jacobian(Ji @ qdj[s], qj[s]) @ qdj[s]
            bias = -(ca.cross(omega, ca.cross(omega, ri)) + 2 * ca.cross(omega, x) + Jdqd)
            rhs.append(bias - Ji @ qdd_r[s] if qdd_r is not None else bias)
        rate = None
        if e is not None:
            rate = -ca.dot(roll_rate_row_dot(quat_to_rotation(self.quat), omega), omega)
            rate = rate + qdd_r[12] if qdd_r is not None else rate
        a_b, alpha = rigid_motion(self.r, rhs, e, rate)
        v = ca.vertcat(v_b, omega, qdj)
        return v, ca.vertcat(a_b - ca.cross(omega, v_b), alpha, qdd_r[:12] if qdd_r is not None else ca.SX.zeros(12))

    def project(self, F: ca.SX) -> ca.SX:
        """tau_r (n, m) = S F for full generalized forces F (18, m) (module docstring)."""
        f = stance_forces(self.stance, self.r, F[:3, :], F[3:6, :])
        tau = ca.SX(F[6:, :])
        for j, i in enumerate(self.stance.feet):
            J = ca.jacobian(self.r[j], self.q_r[3 * i : 3 * i + 3])
            tau[3 * i : 3 * i + 3, :] = tau[3 * i : 3 * i + 3, :] - J.T @ f[3 * j : 3 * j + 3, :]
        if self.n == 12:
            return tau
        # Forces at the two feet have no moment about the line through them, so the residual's
        # moment about that line is the required wrench's own: no residual needs forming.
        r1, r2 = self.r
        e = (r1 - r2) / ca.norm_2(r1 - r2)
        return ca.vertcat(tau, e.T @ (F[3:6, :] - skew(r1) @ F[:3, :]))

    def rnea(self, v: ca.SX, a: ca.SX, gravity: bool = True) -> ca.SX:
        """The full generalized force (18,) with zero foot forces."""
        return inverse_dynamics(self.robot, self.q_joints, self.g_b if gravity else ca.SX.zeros(3), v, a, ca.SX.zeros(12))

    def mass_matrix(self) -> ca.SX:
        """M_r = S M_full T (n, n)."""
        return self.project(mass_matrix_crba(self.robot, self.q_joints) @ self.T)

    def mass_matrix_factors(self) -> tuple[ca.SX, ca.SX, ca.SX]:
        """(S_b (n, 6), T_b (6, n), M_full (18, 18)) with M_r = S M_full T, S = [S_b, I_12] (the
        13th row, two feet, has no joint part) and T = [T_b; I_12] (the 13th column has none); T_b's
        columns and S_b's rows of the swing legs' joints are zero (checked): what the generated C multiplies in loops
        (codegen/c/qd_reduced_solve.c, qd_M_r_legs)."""
        x = ca.SX.sym("x", NV_FULL)
        S = ca.jacobian(self.project(x), x)  # project is linear in F: S exactly
        joint_rows = ca.DM.eye(self.n)[:, :12]
        if not (ca.is_equal(ca.simplify(S[:, 6:]), ca.SX(joint_rows)) and ca.is_equal(self.T[6:, :], ca.SX(joint_rows.T))):
            raise AssertionError("S or T has a joint part other than the identity; qd_M_r_legs assumes it")
        swing = [3 * i + c for i in range(4) if i not in self.stance.feet for c in range(3)]
        if any(not (self.T[k, j].is_zero() and S[j, k].is_zero()) for k in range(6) for j in swing):
            raise AssertionError("T_b (S_b) has a nonzero entry in a swing leg's joint column (row); qd_M_r_legs skips those")
        return S[:, :6], self.T[:6, :], mass_matrix_crba(self.robot, self.q_joints)

    def coriolis_gravity(self, qd_r: ca.SX) -> ca.SX:
        """C_r + G_r (n,) in one Newton-Euler pass."""
        v, k = self.velocity_and_bias(qd_r)
        return self.project(self.rnea(v, k))

    def gravity(self) -> ca.SX:
        """G_r (n,) = S G_full, G_full by composite bodies (~25 % fewer operations than S rnea(q, 0, 0))."""
        return self.project(generalized_gravity(self.robot, self.q_joints, self.g_b))

    def inverse_dynamics(self, qd_r: ca.SX, qdd_r: ca.SX) -> ca.SX:
        """id_r (n,) = M_r qdd_r + C_r + G_r, in one Newton-Euler pass (a = T qdd_r + k without forming T)."""
        return self.project(self.rnea(*self.velocity_and_acceleration(qd_r, qdd_r)))


def reduced_projection(robot: Robot, stance: StanceSet, q_r: ca.SX, quat: ca.SX) -> ReducedProjection:
    """The shared pieces (foot positions, T) for symbols q_r (n,) and quat (4,)."""
    n = q_r.shape[0]
    feet = stance.feet
    r = [foot_position(robot.legs[i], q_r[3 * i : 3 * i + 3]) for i in feet]
    R = quat_to_rotation(quat)
    columns = ca.SX(ca.DM.eye(n))  # unit qdd_r columns: T is the map applied to them
    u = [-ca.jacobian(ri, q_r[3 * i : 3 * i + 3]) @ columns[3 * i : 3 * i + 3, :] for ri, i in zip(r, feet)]
    e = roll_rate_row(R) if len(feet) == 2 else None
    a_b, alpha = rigid_motion(r, u, e, columns[12, :] if e is not None else None)
    T = ca.vertcat(a_b, alpha, columns[:12, :])
    return ReducedProjection(robot, stance, n, q_r, quat, T, r, R.T @ dm(GRAVITY_W))
