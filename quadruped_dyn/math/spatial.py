"""Small CasADi (SX) helpers: quaternion rotations, 6D spatial algebra (``skew`` and
``axis_rotation``, for numbers and symbols alike, are in ``rigid``).

Spatial vectors are ordered (linear, angular), as in Pinocchio: a motion V = (v, omega)
and a force F = (f, n).
"""

from __future__ import annotations

import casadi as ca
import numpy as np

from quadruped_dyn.math.rigid import LinkInertia, Placement, skew


def quat_to_rotation(quat: ca.SX) -> ca.SX:
    """R (b -> w) from a quaternion (x, y, z, w); scale-invariant, so it need not be unit."""
    x, y, z, w = quat[0], quat[1], quat[2], quat[3]
    s = 2 / (x * x + y * y + z * z + w * w)
    return ca.vertcat(
        ca.horzcat(1 - s * (y * y + z * z), s * (x * y - z * w), s * (x * z + y * w)),
        ca.horzcat(s * (x * y + z * w), 1 - s * (x * x + z * z), s * (y * z - x * w)),
        ca.horzcat(s * (x * z - y * w), s * (y * z + x * w), 1 - s * (x * x + y * y)),
    )


def dm(x: np.ndarray | ca.SX) -> ca.DM | ca.SX:
    """A constant as a CasADi matrix; an SX (a robot parameter left symbolic, ``codegen.forms.leg_template``) as is."""
    if isinstance(x, ca.SX):
        return x
    return ca.DM(np.asarray(x, dtype=float))


def placement_rt(T: Placement) -> tuple[ca.DM | ca.SX, ca.DM | ca.SX]:
    return dm(T.R), dm(T.p)


def motion_cross(V: ca.SX) -> ca.SX:
    """6x6 matrix of V x (motion cross product), V = (v, omega)."""
    v, w = V[:3], V[3:]
    Z = ca.SX.zeros(3, 3)
    return ca.vertcat(ca.horzcat(skew(w), skew(v)), ca.horzcat(Z, skew(w)))


def force_cross(V: ca.SX) -> ca.SX:
    """6x6 matrix of V x* (dual cross product on forces): -motion_cross(V)^T."""
    return -motion_cross(V).T


def force_cross_bar(F: ca.SX) -> ca.SX:
    """6x6 matrix M with M @ V = V x* F for a force F = (f, n)."""
    f, n = F[:3], F[3:]
    Z = ca.SX.zeros(3, 3)
    return ca.vertcat(ca.horzcat(Z, -skew(f)), ca.horzcat(-skew(f), -skew(n)))


def spatial_inertia(link: LinkInertia, R: ca.SX, p: ca.SX) -> ca.SX:
    """6x6 spatial inertia of ``link`` (given in a frame placed at (R, p)), expressed at the
    origin and axes of the outer frame: [[m I, -m [c]x], [m [c]x, I_c - m [c]x [c]x]]."""
    c = p + R @ dm(link.com)
    Ic = R @ dm(link.inertia) @ R.T
    C = skew(c)
    m = link.mass
    return ca.vertcat(ca.horzcat(m * ca.DM.eye(3), -m * C), ca.horzcat(m * C, Ic - m * C @ C))


def stacked(parts: tuple[ca.SX, ...]) -> ca.SX:
    """Matrices stacked column by column into one column."""
    return ca.vertcat(*(ca.vec(ca.SX(x)) for x in parts))


def unstacked(L: ca.SX, layout: tuple[tuple[str, int, int], ...]) -> dict[str, ca.SX]:
    """``stacked``'s inverse for ``layout``: (name, rows, columns) of each part, in order."""
    out, start = {}, 0
    for name, rows, cols in layout:
        out[name] = ca.reshape(L[start : start + rows * cols], rows, cols)
        start += rows * cols
    return out
