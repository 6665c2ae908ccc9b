"""One data structure for a leg, whether it came from a DH table or from a URDF.

A leg is a chain of three revolute joints (HAA, HFE, KFE) hanging from the trunk, ending
in a foot frame. Each joint i has a fixed placement ``(R, p)`` of its frame relative to
the previous joint frame (for HAA: relative to the trunk frame b), a unit axis in its own
frame, and the inertia of the link it moves, expressed in that joint frame.

The pose of joint frame i is ``T_{i-1,i}(q_i) = [R_i, p_i] * Rot(axis_i, q_i)``.
The foot (contact point) is the origin of ``foot`` placed relative to the KFE frame.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from quadruped_dyn.math.rigid import LinkInertia, Placement, axis_rotation

LEG_LABELS: tuple[str, ...] = ("FL", "FR", "BL", "BR")
JOINT_ROLES: tuple[str, ...] = ("HAA", "HFE", "KFE")

#: Project joint index (FL, FR, BL, BR x HAA, HFE, KFE) of BR HFE, the joint of the paper's Figs. 5-7.
BR_HFE = 3 * LEG_LABELS.index("BR") + JOINT_ROLES.index("HFE")


@dataclass(frozen=True)
class LegJoint:
    name: str
    placement: Placement  # relative to the previous joint frame (HAA: trunk frame)
    axis: np.ndarray  # (3,) unit rotation axis in this joint's frame
    lower: float  # rad
    upper: float  # rad


@dataclass(frozen=True)
class Leg:
    label: str  # FL, FR, BL or BR
    joints: tuple[LegJoint, LegJoint, LegJoint]  # HAA, HFE, KFE
    links: tuple[LinkInertia, LinkInertia, LinkInertia]  # moved by HAA, HFE, KFE
    foot: Placement  # foot frame relative to the KFE frame; its origin is the contact point
    foot_frame: str

    @property
    def hip(self) -> np.ndarray:
        """HAA joint origin in the trunk frame, m."""
        return self.joints[0].placement.p

    def foot_position(self, q: np.ndarray) -> np.ndarray:
        """Foot position in the trunk frame for joint angles q (3,), rad (numeric FK)."""
        T = Placement.identity()
        for joint, qi in zip(self.joints, q):
            T = T @ joint.placement @ Placement(axis_rotation(joint.axis, qi), np.zeros(3))
        return (T @ self.foot).p


