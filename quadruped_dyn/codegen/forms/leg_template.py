"""One symbolic leg for several legs of a robot: the numbers in which they differ as parameters.

The legs of a quadruped share their structure (canonical frames, ``leg_frames.axis_aligned``: the same joint axes)
and differ in a few numbers: the hip's position, the signs of mirrored offsets and products of inertia. A leg
template is the canonical leg with each number in which its legs differ (placements, foot point, masses, centres of
mass, inertia entries; a symmetric pair as one) replaced by an entry of the SX parameter vector ``p``; the numbers
they share stay constants. A generated function of a template is one piece of machine code that serves all its legs,
each call with its leg's ``values`` (docs/derivatives.md, "dfd_r and dgrf as generated C"). A template with a leg's ``values`` put
in is that leg in canonical frames (``leg_frames.axis_aligned``), exactly (tested): the functions built from it are
the ``dynamics`` algorithms of that leg.

A joint turning about -a by q is the joint turning about a by -q (its torque about a is minus the torque about -a):
a leg whose axes are the template's up to sign shares it in the coordinates sigma q, ``signs`` the sigma of each
joint (hyq's left and right hips). Legs whose axes differ otherwise cannot share a template (the axes shape the
expressions): each group gets its own.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import cast

import casadi as ca
import numpy as np

from quadruped_dyn.math.rigid import LinkInertia, Placement
from quadruped_dyn.model.leg import Leg, LegJoint
from quadruped_dyn.model.leg_frames import axis_aligned
from quadruped_dyn.model.robot import Robot


@dataclass(frozen=True)
class LegTemplate:
    """A canonical leg whose differing numbers are the entries of ``p`` (module docstring)."""

    legs: tuple[int, ...]  # the robot's legs it stands for (0..3: FL, FR, BL, BR)
    leg: Leg  # canonical frames; fields SX where these legs differ
    p: ca.SX  # (n_p,) the parameters (n_p may be 0)
    values: np.ndarray  # (len(legs), n_p): each leg's parameters, in ``legs``' order
    signs: np.ndarray  # (len(legs), 3) of +-1: each leg's joint i is the template's at sigma_i q_i


def _up_to_sign(axis: np.ndarray) -> np.ndarray:
    """The axis with its first nonzero entry positive: equal for a and -a."""
    return axis * np.sign(axis[np.flatnonzero(axis)[0]]) + 0.0


def leg_templates(robot: Robot) -> tuple[LegTemplate, ...]:
    """The robot's legs grouped by their joint axes up to sign (canonical frames), one template per group, in leg
    order; a leg's joint turning the other way than the group's first leg's has sign -1."""
    aligned = [axis_aligned(leg) for leg in robot.legs]
    groups: dict[bytes, list[int]] = {}
    for k, leg in enumerate(aligned):
        groups.setdefault(np.array([_up_to_sign(j.axis) for j in leg.joints]).tobytes(), []).append(k)
    return tuple(_template([aligned[k] for k in ks], tuple(ks)) for ks in groups.values())


def _turned(leg: Leg, signs: np.ndarray) -> Leg:
    """``leg`` with joint i's axis times signs[i] (the same leg in the coordinates signs * q)."""
    joints = tuple(LegJoint(j.name, j.placement, s * j.axis + 0.0, *sorted((s * j.lower, s * j.upper)))
                   for j, s in zip(leg.joints, signs))
    return Leg(leg.label, joints, leg.links, leg.foot, leg.foot_frame)  # type: ignore[arg-type]


class _Parameters:
    """Collects the parameters of one template: each number the legs differ in becomes a new symbol."""

    def __init__(self, count: int) -> None:
        self.symbols: list[ca.SX] = []
        self.values: list[list[float]] = [[] for _ in range(count)]

    def scalar(self, per_leg: list[float]) -> float | ca.SX:
        if all(x == per_leg[0] for x in per_leg):
            return per_leg[0]
        s = ca.SX.sym(f"p{len(self.symbols)}")
        self.symbols.append(s)
        for row, x in zip(self.values, per_leg):
            row.append(float(x))
        return s

    def array(self, per_leg: list[np.ndarray], symmetric: bool = False) -> np.ndarray | ca.SX:
        """The legs' arrays (3,) or (3, 3) as a numpy constant if equal, else an SX with parameters where they differ."""
        first = np.asarray(per_leg[0], dtype=float)
        if all(np.array_equal(first, x) for x in per_leg):
            return first
        out = ca.SX(ca.DM(first))
        cols = 1 if first.ndim == 1 else first.shape[1]
        for i in range(first.shape[0]):
            for j in range(cols):
                if symmetric and j < i:
                    out[i, j] = out[j, i]
                    continue
                out[i, j] = self.scalar([float(np.asarray(x)[i] if cols == 1 and first.ndim == 1 else np.asarray(x)[i, j])
                                         for x in per_leg])
        return out


def _template(turning: list[Leg], indices: tuple[int, ...]) -> LegTemplate:
    signs = np.array([[np.sign(a.axis @ b.axis) for a, b in zip(leg.joints, turning[0].joints)] for leg in turning])
    if any(not np.array_equal(s * a.axis + 0.0, b.axis) for leg, row in zip(turning, signs)
           for s, a, b in zip(row, leg.joints, turning[0].joints)):
        raise AssertionError("the legs' axes are not equal up to sign")
    legs = [_turned(leg, s) for leg, s in zip(turning, signs)]
    par = _Parameters(len(legs))
    first = legs[0]
    if any(not np.array_equal(j.placement.R, np.eye(3)) for leg in legs for j in leg.joints):
        raise AssertionError("a canonical joint placement is not the identity rotation")
    # The fields are typed numeric; a template's hold SX where its legs differ, which every function the template is
    # built for reads through ``dm`` (module docstring): the casts say so to the type checker.
    joints = tuple(LegJoint(j.name, Placement(j.placement.R, cast(np.ndarray, par.array([leg.joints[i].placement.p
                                                                                        for leg in legs]))),
                            j.axis, j.lower, j.upper) for i, j in enumerate(first.joints))
    links = tuple(LinkInertia(cast(float, par.scalar([leg.links[i].mass for leg in legs])),
                              cast(np.ndarray, par.array([leg.links[i].com for leg in legs])),
                              cast(np.ndarray, par.array([leg.links[i].inertia for leg in legs], symmetric=True)))
                  for i in range(3))
    foot = Placement(first.foot.R, cast(np.ndarray, par.array([leg.foot.p for leg in legs])))
    template = Leg("template", joints, links, foot, first.foot_frame)  # type: ignore[arg-type]
    p = ca.vertcat(*par.symbols) if par.symbols else ca.SX(0, 1)
    return LegTemplate(indices, template, p, np.array(par.values, dtype=float).reshape(len(legs), len(par.symbols)), signs)


@dataclass(frozen=True)
class LegPieces:
    """A function of the whole robot as generated pieces (docs/derivatives.md, "dfd_r and dgrf as generated C"): an optional
    ``head`` of the trunk's inputs, one ``legs`` Function per template (called once per leg of it, with the leg's
    parameters and its joint inputs times its signs) and a ``tail`` that takes the legs' outputs L_0..L_3 (in the
    template's coordinates: the tail turns them back by the signs) to the function's outputs."""

    head: ca.Function | None
    templates: tuple[LegTemplate, ...]
    legs: tuple[ca.Function, ...]  # per template
    template_of: tuple[int, ...]  # per robot leg 0..3: the index of its template
    tail: ca.Function

    def leg_values(self, k: int) -> tuple[float, ...]:
        """Robot leg k's parameters for its template's function."""
        t = self.templates[self.template_of[k]]
        return tuple(float(x) for x in t.values[t.legs.index(k)])

    def leg_signs(self, k: int) -> tuple[float, float, float]:
        """Robot leg k's joint signs: its template's function takes sigma q, sigma qd, sigma qdd (module docstring)."""
        return tuple(float(x) for x in leg_signs(self.templates, k))  # type: ignore[return-value]


def leg_signs(templates: tuple[LegTemplate, ...], k: int) -> np.ndarray:
    """Robot leg k's joint signs (3,) in the template that stands for it."""
    t = templates[template_of(templates)[k]]
    return t.signs[t.legs.index(k)]


def template_of(templates: tuple[LegTemplate, ...]) -> tuple[int, ...]:
    """Per robot leg 0..3, the index of the template that stands for it."""
    return tuple(next(i for i, t in enumerate(templates) if k in t.legs) for k in range(4))
