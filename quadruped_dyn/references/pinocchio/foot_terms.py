"""Pinocchio's foot kinematics and rigid point contacts, in the trunk frame b (positions relative
to the trunk origin; each foot Jacobian w.r.t. the leg's own three joints)."""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from quadruped_dyn.model.state import NV_FULL, check_array, rotation
from quadruped_dyn.references.pinocchio.coordinates import LWA
from quadruped_dyn.references.pinocchio.whole_body import PinocchioWholeBody


class PinocchioFeet(PinocchioWholeBody):
    """Foot positions, Jacobians, accelerations and the stance feet's contact dynamics."""

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
