"""Rigid-body quantities, numeric: placements, link inertias, rotations about an axis, cross-product matrices.

Frames: a ``Placement`` maps child-frame points into the parent frame (x_parent = R x_child + p).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


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


def axis_rotation(axis: np.ndarray, angle: float) -> np.ndarray:
    """Rotation by ``angle`` (rad) about the unit ``axis`` (Rodrigues)."""
    k = np.asarray(axis, dtype=float)
    K = skew(k)
    return np.eye(3) + np.sin(angle) * K + (1.0 - np.cos(angle)) * (K @ K)


def skew(w: np.ndarray) -> np.ndarray:
    """Cross-product matrix: ``skew(w) @ x == np.cross(w, x)``."""
    return np.array([[0.0, -w[2], w[1]], [w[2], 0.0, -w[0]], [-w[1], w[0], 0.0]])
