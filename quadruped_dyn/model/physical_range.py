"""The physical range of a quadruped's parameters, relative to its own total mass and size
(docs/reliability.md §2).

The URDF rules refuse numbers no body can have (negative masses, broken triangle inequalities);
this module refuses numbers a body can have but no quadruped does: a link of 1e-300 kg on a
10 kg robot, an inertia a million times its mass times the robot's size squared. Such a model
passes every rule and then makes M so ill-conditioned that its solves return garbage
(derivatives of ~1e305). ``check_physical_range`` is the one validator: ``robot.load_robot``
gives it the loaded bodies, and a parametric robot gives it its parameters, per body.

With m the total mass and L the size (the largest of the hips' span and each leg's chain length,
hip to foot, along its joint offsets), a body is refused outside the REFUSE bounds and warned
about (``UrdfWarning``) outside the WARN bounds:

- mass / m: refuse below ``MIN_MASS_FRACTION`` (1e-6), warn below 1e-3;
- radius of gyration sqrt(largest principal moment / mass) / L: refuse above 1e4, warn above 1
  (a body inside the robot has one below L);
- smallest principal moment / (m L^2): refuse below 1e-12, warn below 1e-8;
- CoM distance from its joint / L: refuse above 10, warn above 1;
- each foot's distance from its knee / L: refuse below 1e-3 (the joint offsets are part of L);
- the robot: m in [1e-3, 1e5] kg, L in [1e-3, 100] m.

Every quadruped example-robot-data ships (a1, anymal_b, anymal_c, b1, go1, go2, hyq, laikago, solo12)
and the paper robot are inside the WARN bounds (measured: mass / m >= 1.0e-2, radius of gyration / L <= 0.45
(hyq), smallest moment / (m L^2) >= 5.8e-6, CoM / L <= 0.33, foot / L >= 0.38; m 2.5-87 kg, L 0.41-0.85 m).
The REFUSE bounds are where M's condition number, ~1e4 on these robots, can pass ~1e12 (``MAX_COND_M_R``:
its solves keep fewer than ~4 digits); between the two, the checks scale their tolerances with cond(M)
(``tolerances.derivative_tolerance``).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from quadruped_dyn.errors import InputError
from quadruped_dyn.math.rigid import LinkInertia
from quadruped_dyn.model.leg import Leg

MIN_TOTAL_MASS_KG, MAX_TOTAL_MASS_KG = 1e-3, 1e5
MIN_SIZE_M, MAX_SIZE_M = 1e-3, 100.0
#: (refuse, warn) bounds of each ratio; see the module docstring.
MIN_MASS_FRACTION = (1e-6, 1e-3)
MAX_GYRATION_PER_SIZE = (1e4, 1.0)
MIN_MOMENT_PER_M_L2 = (1e-12, 1e-8)
MAX_COM_PER_SIZE = (10.0, 1.0)
MIN_FOOT_PER_SIZE = 1e-3

RANGE_DOC = "docs/reliability.md §2"


@dataclass(frozen=True)
class BodyParameters:
    """One rigid body of the model: the trunk, or a leg link with the joint that moves it."""

    name: str  # how a message names it, e.g. "the link moved by joint 'FL_HFE'"
    mass: float  # kg
    com: np.ndarray  # (3,) m, in the body's frame (its joint's; the trunk's own)
    inertia: np.ndarray  # (3, 3) kg m^2 about the CoM
    joint_offset: np.ndarray  # (3,) m, its joint's origin in the parent body's frame (zero for the trunk)
    leg: str | None = None  # FL, FR, BL, BR; None for the trunk
    foot: np.ndarray | None = None  # (3,) m, the foot point in this body's frame (the leg's last link)


def _legs(bodies: Sequence[BodyParameters]) -> dict[str, list[BodyParameters]]:
    """Each leg's bodies, hip first, by label."""
    legs: dict[str, list[BodyParameters]] = {}
    for body in bodies:
        if body.leg is not None:
            legs.setdefault(body.leg, []).append(body)
    return legs


def robot_size(bodies: Sequence[BodyParameters]) -> float:
    """L (m): the largest of the hips' span and each leg's chain length (its joint offsets after the hip, and the foot)."""
    legs = _legs(bodies)
    hips = np.array([chain[0].joint_offset for chain in legs.values()]).reshape(-1, 3)
    span = max((float(np.linalg.norm(a - b)) for a in hips for b in hips), default=0.0)
    chains = [sum(float(np.linalg.norm(b.joint_offset)) for b in chain[1:])
              + sum(float(np.linalg.norm(b.foot)) for b in chain if b.foot is not None) for chain in legs.values()]
    return max([span, *chains])


def _bounded(what: str, value: float, low: float | None, high: float | None, unit: str) -> None:
    if not (low is None or value >= low) or not (high is None or value <= high):
        expected = f">= {low:g}" if high is None else (f"<= {high:g}" if low is None else f"in [{low:g}, {high:g}]")
        raise InputError(f"{what} is {value:.3g}{unit}; expected {expected} ({RANGE_DOC}, physical range)")


def _ratio(body: BodyParameters, what: str, value: float, bounds: tuple[float, float], below: bool,
           warnings: list[str]) -> None:
    """Refuse (InputError) or warn when ``value`` is below (``below``) or above the (refuse, warn) bounds."""
    refuse, warn = bounds
    outside = (lambda limit: value < limit) if below else (lambda limit: value > limit)
    side = "at least" if below else "at most"
    message = f"{body.name} has {what} {value:.3g}"
    if outside(refuse) or not np.isfinite(value):
        raise InputError(f"{message}; expected {side} {refuse:g} ({RANGE_DOC}, physical range: "
                         "a model outside it makes M too ill-conditioned to solve)")
    if outside(warn):
        warnings.append(f"{message}, outside what a quadruped has ({side} {warn:g}; {RANGE_DOC}): "
                        "its terms through M^-1 lose digits")


def check_physical_range(bodies: Sequence[BodyParameters]) -> list[str]:
    """InputError if a body's parameters are outside the physical range relative to the robot's total
    mass and size (module docstring); returns the warnings (one line each) for those outside the warned range."""
    total = float(sum(b.mass for b in bodies))
    _bounded("the robot's total mass", total, MIN_TOTAL_MASS_KG, MAX_TOTAL_MASS_KG, " kg")
    size = robot_size(bodies)
    _bounded("the robot's size (hips' span, leg chains)", size, MIN_SIZE_M, MAX_SIZE_M, " m")
    warnings: list[str] = []
    for body in bodies:
        _ratio(body, "a mass / the robot's total mass of", body.mass / total, MIN_MASS_FRACTION, True, warnings)
        moments = np.linalg.eigvalsh(0.5 * (body.inertia + body.inertia.T))
        gyration = float(np.sqrt(max(moments[-1], 0.0) / body.mass)) / size
        _ratio(body, "a radius of gyration / the robot's size of", gyration, MAX_GYRATION_PER_SIZE, False, warnings)
        _ratio(body, "a smallest principal moment / (total mass x size^2) of", float(moments[0]) / (total * size**2),
               MIN_MOMENT_PER_M_L2, True, warnings)
        _ratio(body, "a CoM distance / the robot's size of", float(np.linalg.norm(body.com)) / size, MAX_COM_PER_SIZE,
               False, warnings)
        if body.foot is not None and not float(np.linalg.norm(body.foot)) / size >= MIN_FOOT_PER_SIZE:
            raise InputError(f"{body.name} has its foot at {float(np.linalg.norm(body.foot)):.3g} m from the knee, "
                             f"{float(np.linalg.norm(body.foot)) / size:.3g} of the robot's size; expected at least "
                             f"{MIN_FOOT_PER_SIZE:g} ({RANGE_DOC}, physical range)")
    return warnings


def robot_bodies(trunk: LinkInertia, legs: Sequence[Leg]) -> list[BodyParameters]:
    """The trunk and each leg's three links as BodyParameters (the last with its foot point)."""
    bodies = [BodyParameters("the trunk", trunk.mass, trunk.com, trunk.inertia, np.zeros(3))]
    for leg in legs:
        for k, (joint, link) in enumerate(zip(leg.joints, leg.links)):
            bodies.append(BodyParameters(f"the link moved by joint '{joint.name}'", link.mass, link.com, link.inertia,
                                         joint.placement.p, leg.label, leg.foot.p if k == 2 else None))
    return bodies
