"""The reduced model (docs/formulation.md) from Pinocchio quantities and numpy least squares:
the velocity map, the full motion from reduced coordinates, tau_r and M_r."""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from quadruped_dyn.math.rigid import skew
from quadruped_dyn.model.state import rotation
from quadruped_dyn.references.pinocchio.force_distribution import PinocchioForceDistribution


class PinocchioReducedCoordinates(PinocchioForceDistribution):
    """Reduced-coordinate terms of a stance set, independent of ``dynamics.reduced``."""

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
