"""Rigid-body quantities: placements and link inertias (numeric), and the rotation about an axis
and the cross-product matrix, each one formula for numbers (numpy) and symbols (CasADi).

Frames: a ``Placement`` maps child-frame points into the parent frame (x_parent = R x_child + p).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import casadi as ca
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
    #: (h = m c kg m, I_o kg m^2 about the frame's origin) where the body is symbolic (``parameters.parametric_robot``):
    #: the composite-inertia algorithms take them as they are, not m (h / m) back from com and inertia
    origin: tuple[Any, Any] | None = None


def skew(w: Any) -> Any:
    """Cross-product matrix: ``skew(w) @ x == w x x``. One formula for numbers and symbols: a numpy
    (3, 3) for a numeric w, a CasADi matrix of w's type for an SX / MX / DM w."""
    rows = ((0, -w[2], w[1]), (w[2], 0, -w[0]), (-w[1], w[0], 0))
    if isinstance(w, ca.SX | ca.MX | ca.DM):
        return ca.vertcat(*[ca.horzcat(*row) for row in rows])
    return np.array(rows, dtype=float)


def axis_rotation(axis: np.ndarray, angle: Any) -> Any:
    """Rotation by ``angle`` (rad) about the constant unit ``axis`` (Rodrigues), a numpy (3, 3) for a
    numeric angle, SX for a symbolic one. One formula, K = [a]x, K^2 = a a^T - I, in the arrangement
    each side has always used: for SX cos (I - a a^T) + a a^T + sin K, so that for an axis-aligned
    joint the constant entries stay exact 0 and 1 (a small graph, small generated C); for numbers
    I + sin K + (1 - cos) K^2, whose rounding the numeric foot positions (and so the gait's
    footholds and the experiment's round-off) are measured with."""
    a = np.asarray(axis, dtype=float)
    K = skew(a)
    if isinstance(angle, ca.SX):
        aaT = np.outer(a, a)
        return ca.cos(angle) * ca.DM(np.eye(3) - aaT) + ca.DM(aaT) + ca.sin(angle) * ca.DM(K)
    angle = float(angle)  # a 1 x 1 DM too: numpy's sin of a CasADi value is legacy behaviour CasADi will change
    return np.eye(3) + np.sin(angle) * K + (1.0 - np.cos(angle)) * (K @ K)
