"""The four legs found in a Pinocchio model by its tree: chains of three revolute joints hanging from the trunk,
each labelled FL, FR, BL, BR by its hip's quadrant about the hips' centre, with its joints, links and foot."""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
import pinocchio as pin

from quadruped_dyn.errors import InputError, UrdfWarning
from quadruped_dyn.files.names import printable
from quadruped_dyn.math.rigid import LinkInertia, Placement
from quadruped_dyn.model.foot_frames import foot_frame
from quadruped_dyn.model.leg import Leg, LegJoint
from quadruped_dyn.model.urdf_rules import inertia_problem

_REVOLUTE_AXES = {"RX": (1.0, 0.0, 0.0), "RY": (0.0, 1.0, 0.0), "RZ": (0.0, 0.0, 1.0)}


def link_inertia_of(model: pin.Model, joint_id: int, what: str) -> LinkInertia:
    Y = model.inertias[joint_id]
    I = np.array(Y.inertia)
    eig = np.linalg.eigvalsh(I)
    if not Y.mass > 0.0 or not eig.min() > 0.0:
        raise InputError(
            f"{what} has mass {Y.mass:g} kg and inertia eigenvalues {np.array2string(eig, precision=3)} kg m^2; "
            "expected a positive mass and a positive-definite inertia"
        )
    problem = inertia_problem(eig)
    if problem is not None:
        raise InputError(f"{what} (fixed links merged) has an inertia that {problem}: principal moments "
                         f"{np.array2string(eig, precision=3)} kg m^2; expected a physical rigid body")
    return LinkInertia(float(Y.mass), np.array(Y.lever), I)


def _axis(joint: pin.JointModel) -> np.ndarray | None:
    """Unit axis of a revolute joint in its own frame, or None if the joint is not revolute."""
    kind = joint.shortname().removeprefix("JointModel")
    kind = kind.replace("RUB", "R")  # continuous (unbounded) revolute joints
    if kind in _REVOLUTE_AXES:
        return np.array(_REVOLUTE_AXES[kind])
    if kind in ("RevoluteUnaligned", "RUnaligned"):
        return np.array(joint.extract().axis, dtype=float)
    return None


def _chain(model: pin.Model, first: int) -> tuple[list[int], bool]:
    """Joints from ``first`` down the tree while it does not branch; True if it then branches."""
    children: dict[int, list[int]] = {}
    for j in range(2, model.njoints):
        children.setdefault(model.parents[j], []).append(j)
    chain = [first]
    while len(children.get(chain[-1], [])) == 1:
        chain.append(children[chain[-1]][0])
    return chain, bool(children.get(chain[-1]))


def leg_chains(model: pin.Model, path: Path) -> list[list[int]]:
    """The four joint chains hanging from the trunk, each of 3 revolute joints; InputError otherwise."""
    hips = [j for j in range(2, model.njoints) if model.parents[j] == 1]
    found = [_chain(model, h) for h in hips]
    chains = [c for c, _ in found]
    shape = [f"{len(c)}+branches" if branches else len(c) for c, branches in found]
    if len(chains) != 4 or any(n != 3 for n in shape):
        raise InputError(
            f"'{path.name}' has {len(chains)} joint chains from the trunk with {shape} joints; "
            "expected a quadruped: 4 legs of 3 revolute joints (HAA, HFE, KFE)"
        )
    for chain in chains:
        for j in chain:
            if _axis(model.joints[j]) is None:
                kind = model.joints[j].shortname()
                kind = f"prismatic ({kind})" if kind.startswith("JointModelP") else kind  # the only other URDF type left
                raise InputError(
                    f"leg joint '{model.names[j]}' is {kind}; expected revolute joints only"
                )
    return chains


def check_trunk_frame(model: pin.Model, hips: list[int]) -> None:
    """InputError if the URDF's root link holds the trunk link (the nearest link above every hip: the
    root itself unless it is, e.g., a 'world' or 'base_footprint' link welded to the trunk) rotated:
    the model's frame b (the root link's) would then not be the trunk's, and legs labelled in it
    would be the wrong legs."""

    def links_above(joint: int) -> list[int]:
        frame = model.frames[model.getFrameId(model.names[joint], pin.FrameType.JOINT)].parentFrame
        above = []
        while model.frames[frame].parentJoint == 1:
            if model.frames[frame].type == pin.FrameType.BODY:
                above.append(frame)
            frame = model.frames[frame].parentFrame
        return above

    paths = [links_above(h) for h in hips]
    trunk = next(f for f in paths[0] if all(f in p for p in paths[1:]))  # the root link is above every hip
    placement = model.frames[trunk].placement
    if not np.array_equal(placement.rotation, np.eye(3)):
        root = model.frames[paths[0][-1]].name
        rpy = np.array2string(pin.rpy.matrixToRpy(placement.rotation) + 0.0, precision=4)  # a 1e-6 rad turn is not 0
        raise InputError(f"the legs hang from link '{printable(model.frames[trunk].name)}', which the URDF's root link "
                         f"'{printable(root)}' holds rotated (rpy {rpy} through fixed joints); expected the trunk as the "
                         "root link, or welded to it without rotation (x forward, y left, z up)")


def leg_of_chain(model: pin.Model, chain: list[int], taken: dict[str, Leg], hips_centre: np.ndarray,
         wanted_feet: dict[str, str] | None = None) -> tuple[Leg, int]:
    """The leg of one joint chain, labelled by its hip's quadrant about the centre of the four hips
    ``hips_centre`` in the trunk frame (not one of ``taken``; the trunk frame's origin may be anywhere,
    e.g. a CAD export's), and the Pinocchio id of its foot frame (``wanted_feet[label]`` if the user
    named it)."""
    hip = model.jointPlacements[chain[0]].translation - hips_centre
    if abs(hip[0]) < 1e-9 or abs(hip[1]) < 1e-9:
        raise InputError(
            f"hip '{model.names[chain[0]]}' at {np.round(hip, 4) + 0.0} from the centre of the four hips is level with "
            "it; expected hips with nonzero x (front/back) and y (left/right) about their centre"
        )
    label = ("F" if hip[0] > 0 else "B") + ("L" if hip[1] > 0 else "R")
    if label in taken:
        raise InputError(f"two legs have their hip in the {label} quadrant about the hips' centre; expected one leg per quadrant")
    joints = tuple(
        LegJoint(
            name=model.names[j],
            placement=Placement(np.array(model.jointPlacements[j].rotation), np.array(model.jointPlacements[j].translation)),
            axis=_axis(model.joints[j]),  # type: ignore[arg-type]
            lower=_limit(model, j, lower=True),
            upper=_limit(model, j, lower=False),
        )
        for j in chain
    )
    links = tuple(link_inertia_of(model, j, f"the link moved by joint '{model.names[j]}'") for j in chain)
    fid = foot_frame(model, chain[-1], label, (wanted_feet or {}).get(label))
    foot = model.frames[fid].placement
    foot_placement = Placement(np.array(foot.rotation), np.array(foot.translation))
    return Leg(label, joints, links, foot_placement, model.frames[fid].name), fid  # type: ignore[arg-type]


def _limit(model: pin.Model, j: int, lower: bool) -> float:
    """Joint limit in rad, clipped to [-pi, pi] (URDFs often state +-10 rad or none), unless the
    range lies wholly beyond one of them (e.g. [3.5, 4.0]): clipping would leave lower > upper. A revolute
    joint whose limits are equal (a ``<limit>`` without ``lower``/``upper`` reads as [0, 0]) gets
    the continuous-joint rule, [-pi, pi], with a UrdfWarning: a leg joint that cannot move is no
    range to sample or plan in."""
    joint = model.joints[j]
    if joint.nq != 1:
        return -np.pi if lower else np.pi
    lo, hi = model.lowerPositionLimit[joint.idx_q], model.upperPositionLimit[joint.idx_q]
    if lo == hi:
        if lower:
            warnings.warn(f"joint '{model.names[j]}' has the limits [{lo:g}, {hi:g}] (no lower/upper in its <limit>?); "
                          "using [-pi, pi] as for a continuous joint", UrdfWarning, stacklevel=4)
        return -np.pi if lower else np.pi
    value = lo if lower else hi
    if lo > np.pi or hi < -np.pi:
        return float(value)
    return float(max(value, -np.pi)) if lower else float(min(value, np.pi))
