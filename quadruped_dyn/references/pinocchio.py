"""Pinocchio ground truth, in the project's coordinates (see ``state`` for conventions).

Every function takes the project's q (19,), v (18,), a = vdot (18,) and returns results in
project order (6 body + 12 joints in FL, FR, BL, BR x HAA, HFE, KFE order), converting to
and from Pinocchio's own order (``Robot.idx_q`` / ``idx_v``) explicitly. Nothing here calls
the project's CasADi code: it is an independent implementation of the same quantities.

Foot quantities are in the trunk frame b, positions relative to the trunk origin, and the
foot Jacobians are w.r.t. the leg's own three joints.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from quadruped_dyn.math.rigid import skew
from quadruped_dyn.model.robot import Robot
from quadruped_dyn.model.state import NQ_FULL, NV_FULL, check_array, rotation
from quadruped_dyn.tolerances import RANK_RTOL

LWA = pin.ReferenceFrame.LOCAL_WORLD_ALIGNED


@dataclass(frozen=True)
class GrfReference:
    lam: np.ndarray  # (n,) minimum-norm parameters
    f_b: np.ndarray  # (k, 3) stance-foot forces, trunk frame, N
    residual: np.ndarray  # (6,) w_req - A lambda: what the model cannot balance
    tau: np.ndarray  # (12,) joint torques with these forces, N m
    rank: int
    singular_values: np.ndarray
    w_req: np.ndarray  # (6,) required wrench (force; moment about the trunk origin), trunk frame


def min_norm_solution(A: np.ndarray, w: np.ndarray) -> tuple[np.ndarray, int, np.ndarray]:
    """(lambda, rank, singular values): the minimum-norm least-squares solution of A lambda = w by SVD,
    singular values below RANK_RTOL of the largest treated as zero."""
    U, S, Vt = np.linalg.svd(A, full_matrices=False)
    rank = int(np.sum(S > RANK_RTOL * S[0])) if S.size else 0
    return Vt[:rank].T @ ((U[:, :rank].T @ w) / S[:rank]), rank, S


class PinocchioReference:
    def __init__(self, robot: Robot) -> None:
        self.robot = robot
        self.model = robot.model
        self.data = robot.model.createData()
        self.perm = robot.v_perm

    # ------------------------------------------------------------------ conversions
    def pin_q(self, q: np.ndarray) -> np.ndarray:
        q = check_array("q", q, (NQ_FULL,))
        out = pin.neutral(self.model)
        out[:7] = q[:7]
        out[3:7] /= np.linalg.norm(q[3:7])
        for k, (iq, nq) in enumerate(zip(self.robot.idx_q, self.robot.joint_nq)):
            out[iq : iq + nq] = q[7 + k] if nq == 1 else (np.cos(q[7 + k]), np.sin(q[7 + k]))
        return out

    def pin_v(self, v: np.ndarray, name: str = "v") -> np.ndarray:
        v = check_array(name, v, (NV_FULL,))
        out = np.zeros(self.model.nv)
        out[self.perm] = v
        return out

    def project_q(self, q_pin: np.ndarray) -> np.ndarray:
        joints = [
            q_pin[iq] if nq == 1 else np.arctan2(q_pin[iq + 1], q_pin[iq])
            for iq, nq in zip(self.robot.idx_q, self.robot.joint_nq)
        ]
        return np.concatenate([q_pin[:7], joints])

    def project_v(self, v_pin: np.ndarray) -> np.ndarray:
        return np.asarray(v_pin)[self.perm]

    def project_matrix(self, M_pin: np.ndarray) -> np.ndarray:
        return np.asarray(M_pin)[np.ix_(self.perm, self.perm)]

    # ------------------------------------------------------------------ dynamics
    def rnea(self, q: np.ndarray, v: np.ndarray, a: np.ndarray) -> np.ndarray:
        """Generalised forces (18,): body wrench (force, moment; body frame) and joint torques."""
        return self.project_v(pin.rnea(self.model, self.data, self.pin_q(q), self.pin_v(v), self.pin_v(a, "a")))

    def mass_matrix(self, q: np.ndarray) -> np.ndarray:
        """M (18, 18) from crba; the Python binding returns it symmetrised."""
        return self.project_matrix(pin.crba(self.model, self.data, self.pin_q(q)))

    def nonlinear_effects(self, q: np.ndarray, v: np.ndarray) -> np.ndarray:
        """C(q, v) + G(q) (18,)."""
        return self.project_v(pin.nonLinearEffects(self.model, self.data, self.pin_q(q), self.pin_v(v)))

    def gravity(self, q: np.ndarray) -> np.ndarray:
        """G(q) (18,)."""
        return self.project_v(pin.computeGeneralizedGravity(self.model, self.data, self.pin_q(q)))

    def coriolis_matrix(self, q: np.ndarray, v: np.ndarray) -> np.ndarray:
        """Pinocchio's Coriolis matrix C(q, v) (18, 18): C v = nle - G, Mdot - 2C skew."""
        return self.project_matrix(pin.computeCoriolisMatrix(self.model, self.data, self.pin_q(q), self.pin_v(v)))

    # ------------------------------------------------------------------ feet
    def _leg_columns(self, leg: int) -> np.ndarray:
        return self.robot.idx_v[3 * leg : 3 * leg + 3]

    def foot_positions(self, q: np.ndarray) -> np.ndarray:
        """(4, 3) foot positions relative to the trunk origin, trunk frame, m."""
        qp = self.pin_q(q)
        pin.framesForwardKinematics(self.model, self.data, qp)
        base = self.data.oMi[1]
        return np.array([base.actInv(self.data.oMf[f].translation) for f in self.robot.foot_frame_ids])

    def foot_jacobians(self, q: np.ndarray) -> np.ndarray:
        """(4, 3, 3): d(foot position in b)/d(own 3 joints), trunk frame."""
        qp = self.pin_q(q)
        pin.computeJointJacobians(self.model, self.data, qp)
        pin.framesForwardKinematics(self.model, self.data, qp)
        R = self.data.oMi[1].rotation
        out = []
        for leg, f in enumerate(self.robot.foot_frame_ids):
            J = pin.getFrameJacobian(self.model, self.data, f, LWA)[:3]
            out.append(R.T @ J[:, self._leg_columns(leg)])
        return np.array(out)

    def foot_accelerations(self, q: np.ndarray, v: np.ndarray, a: np.ndarray) -> np.ndarray:
        """(4, 3) classical acceleration of each foot point in the world, in the trunk frame, m/s^2."""
        pin.forwardKinematics(self.model, self.data, self.pin_q(q), self.pin_v(v), self.pin_v(a, "a"))
        pin.updateFramePlacements(self.model, self.data)
        R = self.data.oMi[1].rotation
        return np.array(
            [R.T @ pin.getFrameClassicalAcceleration(self.model, self.data, f, LWA).linear for f in self.robot.foot_frame_ids]
        )

    def foot_bias_accelerations(self, q: np.ndarray, v: np.ndarray) -> np.ndarray:
        """(4, 3) Jdot qdot of each foot relative to the trunk (trunk frame): the foot's
        classical acceleration with the trunk at rest and zero joint accelerations."""
        v_joints = np.array(v, dtype=float)
        v_joints[:6] = 0.0
        return self.foot_accelerations(q, v_joints, np.zeros(NV_FULL))

    def contact_jacobian(self, q: np.ndarray, stance: tuple[int, ...]) -> np.ndarray:
        """(3k, 18) world-aligned linear Jacobians of the stance feet, project column order."""
        qp = self.pin_q(q)
        pin.computeJointJacobians(self.model, self.data, qp)
        pin.framesForwardKinematics(self.model, self.data, qp)
        rows = [pin.getFrameJacobian(self.model, self.data, self.robot.foot_frame_ids[i], LWA)[:3] for i in stance]
        return np.vstack(rows)[:, self.perm] if rows else np.zeros((0, NV_FULL))

    def constrained_forward_dynamics(
        self, q: np.ndarray, v: np.ndarray, tau: np.ndarray, stance: tuple[int, ...]
    ) -> tuple[np.ndarray, np.ndarray]:
        """Stance feet as rigid point contacts (zero world acceleration).

        Solves the KKT system ``[[M, Jc^T], [Jc, 0]] [a; -f] = [S^T tau - (C + G); -Jcdot v]``.
        Returns a = vdot (18,) and the ground forces on the stance feet, world frame (k, 3), N.
        """
        tau = check_array("tau", tau, (12,))
        M = self.mass_matrix(q)
        h = self.nonlinear_effects(q, v)
        Jc = self.contact_jacobian(q, stance)
        drift = np.concatenate(
            [rotation(q) @ acc for acc in self.foot_accelerations(q, v, np.zeros(NV_FULL))[list(stance)]]
        ) if stance else np.zeros(0)
        k = Jc.shape[0]
        K = np.block([[M, Jc.T], [Jc, np.zeros((k, k))]])
        rhs = np.concatenate([np.concatenate([np.zeros(6), tau]) - h, -drift])
        sol = np.linalg.solve(K, rhs)
        return sol[:NV_FULL], -sol[NV_FULL:].reshape(-1, 3)

    # ------------------------------------------------------------------ ground reaction forces
    def grf_system(self, q: np.ndarray, feet: tuple[int, ...], P: np.ndarray) -> np.ndarray:
        """A (6, n): the trunk rows of the contact Jacobian's transpose acting on forces f = P lambda
        given in the trunk frame (sum_i [I; [r_i]x] f_i, from Pinocchio's contact Jacobian)."""
        if not P.size:
            return np.zeros((6, 0))
        Jc = self.contact_jacobian(q, feet)
        return Jc[:, :6].T @ np.kron(np.eye(len(feet)), rotation(q)) @ P

    def grf_solve(self, q: np.ndarray, v: np.ndarray, a: np.ndarray, feet: tuple[int, ...], P: np.ndarray) -> GrfReference:
        """Minimum-norm GRF by SVD from Pinocchio quantities: w_req = base rows of rnea(q, v, a),
        A = (base rows of Jc^T) blockdiag(R) P (forces f = P lambda in the trunk frame)."""
        tau_full = self.rnea(q, v, a)
        w_req = tau_full[:6]
        R = rotation(q)
        Jc = self.contact_jacobian(q, feet)
        Rk = np.kron(np.eye(len(feet)), R)
        A = self.grf_system(q, feet, P)
        lam, rank, S = min_norm_solution(A, w_req)
        f_b = P @ lam if P.size else np.zeros(0)
        tau = tau_full[6:] - Jc[:, 6:].T @ (Rk @ f_b) if P.size else tau_full[6:]
        return GrfReference(lam, f_b.reshape(-1, 3), w_req - A @ lam, tau, rank, S, w_req)


    # ------------------------------------------------------------------ reduced coordinates
    def velocity_map(self, q: np.ndarray, feet: tuple[int, ...]) -> np.ndarray:
        """A_s (3k, 6), (7, 6) for two feet: the rows [I, -[r_i]x] of each stance foot's velocity
        constraint v_b + omega_b x r_i + J_i qd_i = 0 (Pinocchio's foot positions r_i, trunk
        frame) and, for two feet, the roll-rate row (0, e_phi) with phid = e_phi . omega_b."""
        r = self.foot_positions(q)
        rows = [np.hstack([np.eye(3), -skew(r[i])]) for i in feet]
        if len(feet) == 2:
            rows.append(np.concatenate([np.zeros(3), roll_rate_row(rotation(q))])[None, :])
        return np.vstack(rows)

    def reduced_motion(
        self, feet: tuple[int, ...], q_r: np.ndarray, qd_r: np.ndarray, qdd_r: np.ndarray, quat: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(q, v, a = vdot) of the full robot from reduced coordinates (docs/formulation.md §5), with
        Pinocchio's foot positions, Jacobians and Jdot qdot and numpy least squares; the
        roll-rate row's derivative from the Euler-angle rates (an independent derivation)."""
        q = np.concatenate([np.zeros(3), quat, q_r[:12]])
        R = rotation(q)
        v_joints = np.concatenate([np.zeros(6), qd_r[:12]])
        r, J, bias = self.foot_positions(q), self.foot_jacobians(q), self.foot_bias_accelerations(q, v_joints)
        A = self.velocity_map(q, feet)
        rhs_v = [-J[i] @ qd_r[3 * i : 3 * i + 3] for i in feet]
        if len(feet) == 2:
            rhs_v.append(np.array([qd_r[12]]))
        xi = np.linalg.lstsq(A, np.concatenate(rhs_v), rcond=None)[0]
        v_b, omega = xi[:3], xi[3:]
        rhs_a = []
        for i in feet:
            s = slice(3 * i, 3 * i + 3)
            Jqd = J[i] @ qd_r[s]
            rhs_a.append(-(np.cross(omega, np.cross(omega, r[i])) + 2 * np.cross(omega, Jqd) + J[i] @ qdd_r[s] + bias[i]))
        if len(feet) == 2:  # phidd = e . alpha + edot . omega
            rhs_a.append(np.array([qdd_r[12] - roll_rates(R, omega, np.zeros(3))[1]]))
        acc = np.linalg.lstsq(A, np.concatenate(rhs_a), rcond=None)[0]
        v = np.concatenate([v_b, omega, qd_r[:12]])
        a = np.concatenate([acc[:3] - np.cross(omega, v_b), acc[3:], qdd_r[:12]])
        return q, v, a

    def reduced_inverse_dynamics(
        self, feet: tuple[int, ...], P: np.ndarray, q_r: np.ndarray, qd_r: np.ndarray, qdd_r: np.ndarray, quat: np.ndarray
    ) -> np.ndarray:
        """tau_r from ``reduced_motion`` and the SVD GRF solve (``grf_solve``); with two feet the
        13th entry is the residual moment about the foot-to-foot line."""
        q, v, a = self.reduced_motion(feet, q_r, qd_r, qdd_r, quat)
        g = self.grf_solve(q, v, a, feet, P)
        if len(feet) != 2:
            return g.tau
        r1, r2 = self.foot_positions(q)[list(feet)]
        e = (r1 - r2) / np.linalg.norm(r1 - r2)
        return np.concatenate([g.tau, [e @ (g.residual[3:] - np.cross(r1, g.residual[:3]))]])

    def reduced_mass_matrix(
        self, feet: tuple[int, ...], P: np.ndarray, q_r: np.ndarray, quat: np.ndarray
    ) -> np.ndarray:
        """M_r (n, n) column by column, Pinocchio quantities only: ``reduced_inverse_dynamics``
        is affine in qdd_r, so column c is tau_r(qd = 0, qdd = e_c) - tau_r(qd = 0, qdd = 0)."""
        zero = np.zeros(len(q_r))
        base = self.reduced_inverse_dynamics(feet, P, q_r, zero, zero, quat)
        return np.column_stack([self.reduced_inverse_dynamics(feet, P, q_r, zero, e, quat) - base for e in np.eye(len(q_r))])



def roll_rate_row(R: np.ndarray) -> np.ndarray:
    """e_phi with phid = e_phi . omega_b, from the Euler angles of R = Rz Ry Rx.

    The reference's own on purpose: ``dynamics.reduced.roll_rate_row`` (the code under test)
    writes it with R's entries; this one goes through Pinocchio's Euler angles and sin/tan, an
    independent derivation of the same row (do not merge them)."""
    roll, pitch, _ = pin.rpy.matrixToRpy(R)
    return np.array([1.0, np.sin(roll) * np.tan(pitch), np.cos(roll) * np.tan(pitch)])


def roll_rates(R: np.ndarray, omega: np.ndarray, alpha: np.ndarray) -> tuple[float, float]:
    """(phid, phidd) of the trunk roll for body angular velocity/acceleration omega, alpha,
    by the Euler-angle rates: thetad = cos(phi) omega_y - sin(phi) omega_z."""
    roll, pitch, _ = pin.rpy.matrixToRpy(R)
    e = roll_rate_row(R)
    roll_rate = float(e @ omega)
    pitch_rate = np.cos(roll) * omega[1] - np.sin(roll) * omega[2]
    sec2 = 1.0 / np.cos(pitch) ** 2
    e_dot = np.array([0.0,
                      np.cos(roll) * roll_rate * np.tan(pitch) + np.sin(roll) * sec2 * pitch_rate,
                      -np.sin(roll) * roll_rate * np.tan(pitch) + np.cos(roll) * sec2 * pitch_rate])
    return roll_rate, float(e @ alpha + e_dot @ omega)


class PinocchioDerivatives:
    """Pinocchio's analytical derivatives (Carpentier & Mansard 2018) in the project's order.

    d/dq is along ``pinocchio.integrate(model, q, dq)`` (a body-frame increment of the free
    flyer, dq (18,)); rows and columns are permuted from Pinocchio's ``idx_v`` order to the
    project's (6 trunk + FL, FR, BL, BR x HAA, HFE, KFE). Symmetric matrices (M, M^-1), of
    which Pinocchio fills the upper triangle, are returned symmetrised."""

    def __init__(self, reference: PinocchioReference) -> None:
        self.ref = reference
        self.model = reference.model
        self.data = self.model.createData()

    def _m(self, X: np.ndarray) -> np.ndarray:
        return self.ref.project_matrix(np.array(X))

    @staticmethod
    def _sym(X: np.ndarray) -> np.ndarray:
        U = np.triu(X)
        return U + np.triu(X, 1).T

    def rnea_derivatives(self, q: np.ndarray, v: np.ndarray, a: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(dtau_dq, dtau_dv, M) of rnea(q, v, a) by ``computeRNEADerivatives``."""
        r = self.ref
        dq, dv, da = pin.computeRNEADerivatives(self.model, self.data, r.pin_q(q), r.pin_v(v), r.pin_v(a, "a"))
        return self._m(dq), self._m(dv), self._m(self._sym(np.array(da)))

    def aba_derivatives(self, q: np.ndarray, v: np.ndarray, tau: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(da_dq, da_dv, M^-1) of aba(q, v, tau) by ``computeABADerivatives``; tau (18,) = (trunk
        wrench, body frame; joint torques)."""
        r = self.ref
        dq, dv, dtau = pin.computeABADerivatives(self.model, self.data, r.pin_q(q), r.pin_v(v), r.pin_v(tau, "tau"))
        return self._m(dq), self._m(dv), self._m(self._sym(np.array(dtau)))

    def aba(self, q: np.ndarray, v: np.ndarray, tau: np.ndarray) -> np.ndarray:
        r = self.ref
        return r.project_v(pin.aba(self.model, self.data, r.pin_q(q), r.pin_v(v), r.pin_v(tau, "tau")))

    def integrate(self, q: np.ndarray, dq: np.ndarray) -> np.ndarray:
        """``pinocchio.integrate(model, q, dq)`` in the project's coordinates (dq in project order)."""
        r = self.ref
        return r.project_q(pin.integrate(self.model, r.pin_q(q), r.pin_v(dq, "dq")))
