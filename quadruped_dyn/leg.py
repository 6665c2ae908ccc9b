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

LEG_LABELS: tuple[str, ...] = ("FL", "FR", "BL", "BR")
JOINT_ROLES: tuple[str, ...] = ("HAA", "HFE", "KFE")


@dataclass(frozen=True)
class Placement:
    """Rigid placement: maps a point x in the child frame to ``R @ x + p`` in the parent."""

    R: np.ndarray  # (3, 3) rotation child -> parent
    p: np.ndarray  # (3,) child origin in the parent frame, m

    @staticmethod
    def identity() -> Placement:
        return Placement(np.eye(3), np.zeros(3))

    def __matmul__(self, other: Placement) -> Placement:
        return Placement(self.R @ other.R, self.R @ other.p + self.p)

    def homogeneous(self) -> np.ndarray:
        T = np.eye(4)
        T[:3, :3] = self.R
        T[:3, 3] = self.p
        return T


@dataclass(frozen=True)
class LinkInertia:
    """Rigid-body inertia in the frame of the joint that moves the link."""

    mass: float  # kg
    com: np.ndarray  # (3,) centre of mass, m
    inertia: np.ndarray  # (3, 3) about the CoM, axes of the joint frame, kg m^2


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


def axis_rotation(axis: np.ndarray, angle: float) -> np.ndarray:
    """Rotation by ``angle`` (rad) about the unit ``axis`` (Rodrigues)."""
    k = np.asarray(axis, dtype=float)
    K = skew(k)
    return np.eye(3) + np.sin(angle) * K + (1.0 - np.cos(angle)) * (K @ K)


def skew(w: np.ndarray) -> np.ndarray:
    """Cross-product matrix: ``skew(w) @ x == np.cross(w, x)``."""
    return np.array([[0.0, -w[2], w[1]], [w[2], 0.0, -w[0]], [-w[1], w[0], 0.0]])
