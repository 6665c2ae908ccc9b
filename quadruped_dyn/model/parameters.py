"""A robot's numbers as one vector p, and the structure (the *family*) that stays when they change.

Layout of p (``PARAMETER_NAMES``, N_PARAMETERS = 178 entries; SI units; one source for Python and the C header):

1. per body, the trunk then the 12 links in the project's joint order (FL, FR, BL, BR x HAA, HFE, KFE), Pinocchio's
   10 dynamic parameters in ``Inertia.toDynamicParameters`` order: m (kg), m c (kg m, 3), the rotational inertia
   about the body frame's origin (kg m^2) Ixx, Ixy, Iyy, Ixz, Iyz, Izz; the body frame is its joint's (the trunk's own);
2. the 12 joints' placement positions (m, 3 each): each joint's origin in its parent's frame (HAA: the hip in the
   trunk frame; HFE, KFE: the link offsets), the URDF's joint frames as Pinocchio has them;
3. the 4 foot points (m, 3 each): each foot in its KFE frame.

The family is what p leaves out: each joint's axis and its placement's rotation (numbers snapped as the loaded
model's). Robots of one structure share it (go1 and a1); its ``key`` names it in file names and caches.
``check_parameters`` is the one validator of a p: a positive mass and a physical inertia per body
(``urdf_rules.inertia_problem``), then the physical range (``physical_range.check_physical_range``).
"""

from __future__ import annotations

import hashlib
import warnings
from dataclasses import dataclass, replace
from functools import cache
from typing import Any, cast

import casadi as ca
import numpy as np

from quadruped_dyn.errors import InputError, UrdfWarning
from quadruped_dyn.math.rigid import LinkInertia, Placement, skew
from quadruped_dyn.model.leg import JOINT_ROLES, LEG_LABELS, Leg, LegJoint
from quadruped_dyn.model.physical_range import BodyParameters, check_physical_range
from quadruped_dyn.model.robot import Robot, check_robot
from quadruped_dyn.model.urdf_rules import inertia_problem

JOINTS: tuple[str, ...] = tuple(f"{leg}_{role}" for leg in LEG_LABELS for role in JOINT_ROLES)
BODIES: tuple[str, ...] = ("trunk", *JOINTS)  # a link is named after the joint that moves it
INERTIAL_NAMES: tuple[str, ...] = ("m", "mcx", "mcy", "mcz", "Ixx", "Ixy", "Iyy", "Ixz", "Iyz", "Izz")
N_INERTIAL = len(BODIES) * len(INERTIAL_NAMES)  # 130: the part of p the dynamics are linear in
PARAMETER_NAMES: tuple[str, ...] = (
    *(f"{body}.{x}" for body in BODIES for x in INERTIAL_NAMES),
    *(f"{joint}.p{x}" for joint in JOINTS for x in "xyz"),
    *(f"{leg}_foot.p{x}" for leg in LEG_LABELS for x in "xyz"),
)
N_PARAMETERS = len(PARAMETER_NAMES)
JOINT_POSITIONS = slice(N_INERTIAL, N_INERTIAL + 3 * len(JOINTS))
FOOT_POINTS = slice(JOINT_POSITIONS.stop, N_PARAMETERS)
#: Digits of the rotations and axes in the family's key (the loaded model's are snapped, model/robot.py).
KEY_DECIMALS = 9


def inertial_parameters(link: LinkInertia) -> np.ndarray:
    """(10,) Pinocchio's dynamic parameters of a body (m, m c, I about the frame origin: xx, xy, yy, xz, yz, zz)."""
    c = np.asarray(link.com, dtype=float)
    I_o = np.asarray(link.inertia, dtype=float) - link.mass * skew(c) @ skew(c)
    return np.array([link.mass, *(link.mass * c), I_o[0, 0], I_o[0, 1], I_o[1, 1], I_o[0, 2], I_o[1, 2], I_o[2, 2]])


def _body(pi: Any) -> tuple[Any, Any, Any]:
    """(m, c, I about the CoM) of 10 dynamic parameters, numbers (numpy) or symbols (SX)."""
    m, h = pi[0], pi[1:4]
    rows = ((pi[4], pi[5], pi[7]), (pi[5], pi[6], pi[8]), (pi[7], pi[8], pi[9]))
    if isinstance(pi, ca.SX):
        I_s = _inertia_at_origin(pi)
        return m, h / m, I_s + skew(h) @ skew(h) / m
    I_o = np.array(rows, dtype=float)
    return float(m), np.asarray(h, dtype=float) / m, I_o + skew(h) @ skew(h) / m


def _inertia_at_origin(pi: ca.SX) -> ca.SX:
    """I_o (3, 3) of 10 symbolic dynamic parameters."""
    return ca.vertcat(*[ca.horzcat(*row) for row in ((pi[4], pi[5], pi[7]), (pi[5], pi[6], pi[8]), (pi[7], pi[8], pi[9]))])


def _symbolic_body(pi: ca.SX) -> LinkInertia:
    """The body of 10 symbolic dynamic parameters, with its (h, I_o) as they are (``LinkInertia.origin``)."""
    return LinkInertia(*_body(pi), origin=(pi[1:4], _inertia_at_origin(pi)))


def parameters_of(robot: Robot) -> np.ndarray:
    """p (N_PARAMETERS,) of a loaded robot (layout: module docstring)."""
    robot = check_robot(robot)
    links = [robot.trunk, *(link for leg in robot.legs for link in leg.links)]
    return np.concatenate([*(inertial_parameters(link) for link in links),
                           *(j.placement.p for leg in robot.legs for j in leg.joints),
                           *(leg.foot.p for leg in robot.legs)])


@dataclass(frozen=True, eq=False)
class Family:
    """The structure p leaves out (module docstring), with a robot of it for names and joint limits."""

    key: str  # "f" + 12 hex digits of the rotations' and axes' digest
    rotations: np.ndarray  # (12, 3, 3) each joint placement's rotation, child -> parent
    axes: np.ndarray  # (12, 3) each joint's unit axis in its own frame
    foot_rotations: np.ndarray  # (4, 3, 3) each foot frame's rotation in its KFE frame
    robot: Robot  # the robot the family was taken from


def _structure(robot: Robot) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    joints = [j for leg in robot.legs for j in leg.joints]
    return (np.array([j.placement.R for j in joints]), np.array([j.axis for j in joints]),
            np.array([leg.foot.R for leg in robot.legs]))


def family_of(robot: Robot) -> Family:
    """The robot's family: robots whose joints have the same axes and placement rotations share its key."""
    return _family_of(check_robot(robot))


@cache
def _family_of(robot: Robot) -> Family:
    rotations, axes, feet = _structure(robot)
    digest = hashlib.sha256((np.round(np.concatenate([rotations.ravel(), axes.ravel()]), KEY_DECIMALS) + 0.0).tobytes())
    return Family("f" + digest.hexdigest()[:12], rotations, axes, feet, robot)


def check_family(family: Family, robot: Robot) -> None:
    """InputError naming the first joint whose axis or placement rotation differs from the family's."""
    if family_of(robot).key == family.key:
        return
    rotations, axes, _ = _structure(robot)
    for k, joint in enumerate(JOINTS):
        for what, theirs, ours in (("axis", axes[k], family.axes[k]), ("placement rotation", rotations[k],
                                                                          family.rotations[k])):
            if not np.allclose(theirs, ours, rtol=0.0, atol=10.0 ** -KEY_DECIMALS):
                raise InputError(f"{robot.name}: joint {joint} has the {what} {np.round(theirs, 6).tolist()}; "
                                 f"expected {np.round(ours, 6).tolist()} (family {family.key} of {family.robot.name})")


def _checked_vector(p: object) -> np.ndarray:
    x = np.asarray(p, dtype=float) if isinstance(p, np.ndarray | list | tuple) else None
    if x is None or x.shape != (N_PARAMETERS,) or not np.all(np.isfinite(x)):
        what = type(p).__name__ if x is None else f"shape {x.shape}" + ("" if x.shape != (N_PARAMETERS,) else
                                                                         ", not all finite")
        raise InputError(f"parameters p: {what}; expected {N_PARAMETERS} finite numbers (model/parameters.py layout)")
    return x


def check_parameters(p: object) -> np.ndarray:
    """p as a float array, or InputError (one line) if it is not a physical robot: a body with mass <= 0 or an
    inertia about its CoM that is not positive semi-definite or breaks the triangle inequality, or a body outside
    the physical range (docs/reliability.md §2); warns (UrdfWarning) where the range does."""
    x = _checked_vector(p)
    bodies = []
    for b, body in enumerate(BODIES):
        pi = x[10 * b: 10 * b + 10]
        if not pi[0] > 0.0:
            raise InputError(f"parameters p: {body} has mass {pi[0]:g} kg; expected a positive mass")
        m, c, I_c = _body(pi)
        problem = inertia_problem(np.linalg.eigvalsh(I_c))
        if problem is not None:
            raise InputError(f"parameters p: {body}'s inertia about its CoM {problem}; expected a physical rigid body")
        k = b - 1
        offset = x[JOINT_POSITIONS][3 * k: 3 * k + 3] if b else np.zeros(3)
        foot = x[FOOT_POINTS][k - 2: k + 1] if b and k % 3 == 2 else None
        leg = LEG_LABELS[k // 3] if b else None
        bodies.append(BodyParameters(f"parameters p: {body}", m, c, I_c, offset, leg, foot))
    for message in check_physical_range(bodies):
        warnings.warn(message, UrdfWarning, stacklevel=2)
    return x


def parametric_robot(family: Family, p: ca.SX) -> Robot:
    """The family's robot with p's numbers (SX) in place of its own: masses, CoMs, inertias, joint positions and
    foot points symbolic; axes and rotations the family's. The ``dynamics`` algorithms accept it."""
    if p.shape != (N_PARAMETERS, 1):
        raise InputError(f"p has shape {p.shape}; expected ({N_PARAMETERS}, 1)")
    bodies = [_symbolic_body(p[10 * b: 10 * b + 10]) for b in range(len(BODIES))]
    positions, feet = p[JOINT_POSITIONS], p[FOOT_POINTS]
    legs = []
    for n, leg in enumerate(family.robot.legs):
        joints = tuple(LegJoint(j.name, Placement(family.rotations[3 * n + i], cast(np.ndarray, positions[3 * (3 * n + i):
                                                                                                       3 * (3 * n + i) + 3])),
                                family.axes[3 * n + i], j.lower, j.upper) for i, j in enumerate(leg.joints))
        foot = Placement(family.foot_rotations[n], cast(np.ndarray, feet[3 * n: 3 * n + 3]))
        legs.append(Leg(leg.label, joints, tuple(bodies[1 + 3 * n: 4 + 3 * n]), foot, leg.foot_frame))  # type: ignore[arg-type]
    return replace(family.robot, trunk=bodies[0], legs=cast(tuple[Leg, Leg, Leg, Leg], tuple(legs)))
