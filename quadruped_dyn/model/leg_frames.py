"""The same leg in canonical joint frames: the frames the symbolic dynamics are written in.

A URDF may place each joint frame with any constant rotation and any origin on the joint
axis; the physics does not depend on that choice, but the size of the symbolic expressions
(and the cost of the generated C) does. ``axis_aligned`` re-expresses a leg, exactly up to
round-off, so that:

* every fixed placement rotation is the identity: joint frame i is parallel to its parent
  frame at q_i = 0, hence all joint frames are parallel to the trunk frame at q = 0 and the
  joint axis, expressed in its own frame, is the axis as seen from the parent (a coordinate
  axis, +-e_k, for every robot whose joint axes are parallel to trunk axes at q = 0);
* the HFE and KFE frame origins slide along their own axes to the foot of the perpendicular
  from the parent's origin (the placement has no component along the axis), as in a DH
  table. The HAA origin (the hip) stays where the URDF puts it.

Link inertias and the foot follow: CoM and foot point shifted by the slide and rotated,
inertia tensors rotated. Entries that are zero up to round-off (and up to the URDF's printed digits)
are snapped to exact zeros (``tolerances.FRAME_SNAP_TOL``), so structural zeros stay structural.
A leg whose positions and inertias are SX (``parameters.parametric_robot``; rotations and axes numeric) is
re-expressed by the same formulas, symbolically, unsnapped.
"""

from __future__ import annotations

from typing import Any

import casadi as ca
import numpy as np

from quadruped_dyn.math.rigid import LinkInertia, Placement
from quadruped_dyn.model.leg import Leg, LegJoint
from quadruped_dyn.tolerances import FRAME_SNAP_TOL


def _snap(x: Any, scale: float = 1.0) -> Any:
    """Entries within FRAME_SNAP_TOL * scale of 0 or +-scale set exactly (an SX as is)."""
    if isinstance(x, ca.SX):
        return x
    x = np.array(x, dtype=float)
    for target in (0.0, scale, -scale):
        x[np.abs(x - target) < FRAME_SNAP_TOL * scale] = target
    return x + 0.0  # no negative zeros


def _rotated(Q: np.ndarray, x: Any) -> Any:
    """Q @ x for a numeric Q and a numeric or SX x."""
    return ca.DM(Q) @ x if isinstance(x, ca.SX) else Q @ x


def _along(x: Any, axis: np.ndarray) -> Any:
    """(x . axis) axis, numeric or SX."""
    return ca.dot(x, ca.DM(axis)) * ca.DM(axis) if isinstance(x, ca.SX) else (x @ axis) * axis


def _moved_origin(link: LinkInertia, Q: np.ndarray, s: Any) -> tuple[ca.SX, ca.SX]:
    """``link.origin`` (h, I_o) rotated by Q^T and taken at the origin moved by s (new frame): h' = h - m s,
    I' = I_o + m (|s|^2 1 - s s^T) + (h s^T + s h^T) - 2 (s . h) 1 (h rotated)."""
    assert link.origin is not None
    h, I_o = ca.DM(Q.T) @ link.origin[0], ca.DM(Q.T) @ link.origin[1] @ ca.DM(Q)
    s, m = ca.SX(ca.DM(s)) if isinstance(s, np.ndarray) else s, link.mass
    shift = h @ s.T
    return h - m * s, I_o + m * (ca.dot(s, s) * ca.SX.eye(3) - s @ s.T) + shift + shift.T - 2 * ca.dot(s, h) * ca.SX.eye(3)


def axis_aligned(leg: Leg) -> Leg:
    """``leg`` in canonical joint frames (module docstring); joint angles, foot point and every
    trunk-frame quantity unchanged."""
    Q = np.eye(3)  # orientation of the parent's new frame in its URDF frame (trunk: identity)
    slide = np.zeros(3)  # the parent's new origin relative to its URDF origin, parent's new frame
    joints, links = [], []
    for i, (joint, link) in enumerate(zip(leg.joints, leg.links)):
        R, p = joint.placement.R, joint.placement.p
        axis = _snap(Q.T @ R @ joint.axis)  # the axis seen from the parent's new frame
        origin = _rotated(Q.T, p) - slide  # joint origin in the parent's new frame
        slide = -_along(origin, axis) if i > 0 else np.zeros(3)
        Q = R.T @ Q  # the new frame is parallel to the parent's new frame at q_i = 0
        joints.append(LegJoint(joint.name, Placement(np.eye(3), _snap(origin + slide)), axis, joint.lower, joint.upper))
        if isinstance(link.inertia, ca.SX):
            inertia = ca.DM(Q.T) @ link.inertia @ ca.DM(Q)
        else:
            inertia = Q.T @ link.inertia @ Q
            inertia = _snap(0.5 * (inertia + inertia.T), float(np.abs(inertia).max()))  # symmetric to the last bit
        links.append(LinkInertia(link.mass, _snap(_rotated(Q.T, link.com) - slide), inertia,
                                 None if link.origin is None else _moved_origin(link, Q, slide)))
    foot = Placement(_snap(Q.T @ leg.foot.R), _snap(_rotated(Q.T, leg.foot.p) - slide))
    return Leg(leg.label, tuple(joints), tuple(links), foot, leg.foot_frame)  # type: ignore[arg-type]
