"""The project's coordinates and Pinocchio's: q (19,), v (18,) and matrices converted both ways.

The project's order is 6 body + 12 joints in FL, FR, BL, BR x HAA, HFE, KFE order; Pinocchio's
is the model's own (``Robot.idx_q`` / ``idx_v``; continuous joints as (cos, sin) pairs).
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from quadruped_dyn.model.robot import Robot
from quadruped_dyn.model.state import NQ_FULL, NV_FULL, check_array

LWA = pin.ReferenceFrame.LOCAL_WORLD_ALIGNED


class PinocchioCoordinates:
    """A robot's Pinocchio model and data, with the conversions to and from the project's order."""

    def __init__(self, robot: Robot) -> None:
        self.robot = robot
        self.model = robot.model
        self.data = robot.model.createData()
        self.perm = robot.v_perm

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
