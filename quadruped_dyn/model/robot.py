"""Loading a quadruped from a URDF (or a built-in name) into the project's leg structure.

Legs are found by tree structure: four chains of three revolute joints hanging from the
trunk (the URDF root link), each ending in a foot frame. Each leg is labelled FL, FR, BL, BR
from the sign of its HAA origin in the trunk frame (x forward, y left, z up).

Joint order inside the project: FL, FR, BL, BR x (HAA, HFE, KFE) -- 12 entries.
``Robot.idx_q`` / ``Robot.idx_v`` map project joint k to Pinocchio's q / v index.
Links rigidly attached by fixed joints are merged into their parent's inertia (Pinocchio's
URDF parser does this). Rotor armature is not part of the paper's model and is set to zero.
Placement entries within ``SNAP_TOL`` of 0 or +-1 are snapped, in Pinocchio's model too.

The URDF is validated (``urdf_validation``) before Pinocchio parses it. One robot, one
identity: a file whose bytes are those of a built-in robot's URDF, reached by its name, by
any path or as a copy, loads as that robot (its name, its standing posture).
"""

from __future__ import annotations

import hashlib
import importlib.metadata
import warnings
from dataclasses import dataclass
from functools import cache
from pathlib import Path

import numpy as np
import pinocchio as pin

from quadruped_dyn.errors import InputError, UrdfWarning
from quadruped_dyn.math.rigid import LinkInertia, Placement
from quadruped_dyn.model.leg import LEG_LABELS, Leg, LegJoint
from quadruped_dyn.model.paper_robot import STANDING_Q, URDF_PATH
from quadruped_dyn.model.urdf_rules import inertia_problem, validate_urdf

#: Built-in robots: the paper's (generated, package data) and six from example-robot-data.
_ERD_FILES = {
    "solo12": "solo_description/robots/solo12.urdf",
    "go2": "go2_description/urdf/go2.urdf",
    "go1": "go1_description/urdf/go1.urdf",
    "a1": "a1_description/urdf/a1.urdf",
    "anymal_c": "anymal_c_simple_description/urdf/anymal.urdf",
    "hyq": "hyq_description/robots/hyq_no_sensors.urdf",
}
ROBOT_NAMES: tuple[str, ...] = ("paper", *_ERD_FILES)

_REVOLUTE_AXES = {"RX": (1.0, 0.0, 0.0), "RY": (0.0, 1.0, 0.0), "RZ": (0.0, 0.0, 1.0)}


def example_robot_data_dir() -> Path:
    """The robots/ folder of the installed example-robot-data package."""
    try:
        dist = importlib.metadata.distribution("example-robot-data")
    except importlib.metadata.PackageNotFoundError as e:
        raise InputError("example-robot-data is not installed; expected it installed (pip install example-robot-data)") from e
    return Path(str(dist.locate_file("cmeel.prefix/share/example-robot-data/robots")))


def _builtin_path(name: str) -> Path:
    return URDF_PATH if name == "paper" else example_robot_data_dir() / _ERD_FILES[name]


def robot_path(name_or_path: str | Path) -> Path:
    """Resolve a built-in robot name or a URDF path to an existing file (absolute, symlinks resolved)."""
    key = str(name_or_path)
    if key in ROBOT_NAMES:
        path = _builtin_path(key)
        if not path.is_file():
            raise InputError(f"the URDF of built-in robot '{key}' is missing at '{path}'; expected the installed "
                             "package's file (reinstall quadruped_dyn / example-robot-data)")
        return path.resolve()
    path = Path(key)
    if not path.is_file():
        raise InputError(f"no such file: '{key}'; expected a URDF path or one of: {', '.join(ROBOT_NAMES)}")
    return path.resolve()


@cache
def _builtin_digests() -> dict[str, str]:
    """SHA-256 of each built-in robot's URDF that is installed."""
    return {name: _digest(_builtin_path(name)) for name in ROBOT_NAMES if _builtin_path(name).is_file()}


def _digest(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


def builtin_name(path: Path) -> str | None:
    """The built-in robot whose URDF has the same bytes as ``path``, or None."""
    digest = _digest(path)
    return next((name for name, d in _builtin_digests().items() if d == digest), None)


@dataclass(frozen=True, eq=False)
class Robot:
    """A quadruped: Pinocchio free-flyer model plus the project's view of it."""

    name: str  # the built-in name if the URDF's bytes are a built-in's, else the file's stem
    urdf: Path  # absolute
    model: pin.Model  # free-flyer model; q = (p, quat xyzw, joints), v = (v_b, omega_b, qd)
    trunk: LinkInertia  # in the trunk frame b
    legs: tuple[Leg, Leg, Leg, Leg]  # FL, FR, BL, BR
    idx_q: np.ndarray  # (12,) Pinocchio q index of project joint k
    idx_v: np.ndarray  # (12,) Pinocchio v index of project joint k
    joint_nq: np.ndarray  # (12,) 1 for revolute, 2 for continuous ((cos, sin) in Pinocchio's q)
    foot_frame_ids: tuple[int, int, int, int]  # Pinocchio frame ids of the feet, project leg order
    standing_q: np.ndarray  # (12,) a standing posture: the paper's Fig. 1d, else neutral clipped to limits

    @property
    def joint_names(self) -> list[str]:
        return [j.name for leg in self.legs for j in leg.joints]

    @property
    def total_mass(self) -> float:
        return self.trunk.mass + sum(link.mass for leg in self.legs for link in leg.links)

    @property
    def v_perm(self) -> np.ndarray:
        """(18,) Pinocchio v index of each project velocity entry (6 base + 12 joints)."""
        return np.concatenate([np.arange(6), self.idx_v])

    @property
    def lower(self) -> np.ndarray:
        """(12,) joint lower limits, rad, project order."""
        return np.array([j.lower for leg in self.legs for j in leg.joints])

    @property
    def upper(self) -> np.ndarray:
        """(12,) joint upper limits, rad, project order."""
        return np.array([j.upper for leg in self.legs for j in leg.joints])


def _inertia(model: pin.Model, joint_id: int, what: str) -> LinkInertia:
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


def _foot_frame(model: pin.Model, knee: int) -> int:
    """The leaf frame below the knee joint: prefer names containing 'foot', else the farthest."""
    parents = {f.parentFrame for f in model.frames}
    leaves = [
        i
        for i, f in enumerate(model.frames)
        if f.parentJoint == knee and i not in parents and np.linalg.norm(f.placement.translation) > 1e-9
    ]
    if not leaves:
        raise InputError(
            f"no foot frame below joint '{model.names[knee]}'; expected a link attached to the last leg link (a foot)"
        )
    footish = [i for i in leaves if "foot" in model.frames[i].name.lower()]
    pool = footish or leaves
    return max(pool, key=lambda i: np.linalg.norm(model.frames[i].placement.translation))


def _chain(model: pin.Model, first: int) -> tuple[list[int], bool]:
    """Joints from ``first`` down the tree while it does not branch; True if it then branches."""
    children: dict[int, list[int]] = {}
    for j in range(2, model.njoints):
        children.setdefault(model.parents[j], []).append(j)
    chain = [first]
    while len(children.get(chain[-1], [])) == 1:
        chain.append(children[chain[-1]][0])
    return chain, bool(children.get(chain[-1]))


#: Placement entries within this of 0 or +-1 are snapped exactly. URDF text carries rotations
#: as rpy angles, so cos(pi/2) arrives as ~6e-17 instead of 0, or as 4.9e-12 where pi/2 is
#: written with ten digits (hyq, anymal_c: 1.5707963268); snapping keeps structural zeros zero
#: (smaller symbolic graphs, smaller C: with the 4.9e-12 kept, every joint axis of hyq is tilted
#: and its generated M costs 2.7x) and moves nothing by more than 1e-9 m/rad.
SNAP_TOL = 1e-9


def _snap(M: pin.SE3) -> pin.SE3:
    def snap(x: np.ndarray) -> np.ndarray:
        x = np.array(x)
        for target in (0.0, 1.0, -1.0):
            x[np.abs(x - target) < SNAP_TOL] = target
        return x

    return pin.SE3(snap(M.rotation), snap(M.translation))


def _parse_urdf(path: Path) -> pin.Model:
    for message in validate_urdf(path):
        warnings.warn(f"{path.name}: {message}", UrdfWarning, stacklevel=2)
    try:
        return pin.buildModelFromUrdf(str(path), pin.JointModelFreeFlyer())
    except Exception as e:  # Pinocchio raises plain ValueError/RuntimeError with the parser's text
        raise InputError(f"Pinocchio cannot parse '{path}': {str(e).strip().splitlines()[0]}") from e


def load_robot(name_or_path: str, cached: bool = True) -> Robot:
    """Load a built-in robot by name, or any quadruped URDF by path (cached per file unless
    ``cached`` is False, e.g. for a temporary file)."""
    path = robot_path(name_or_path)
    return _load(path) if cached else _load.__wrapped__(path)


@cache
def _load(path: Path) -> Robot:
    model = _prepared_model(path)
    name = builtin_name(path) or path.stem
    legs: dict[str, Leg] = {}
    foot_ids: dict[str, int] = {}
    for chain in _leg_chains(model, path):
        leg, foot_ids[leg.label] = _leg(model, chain, taken=legs)
        legs[leg.label] = leg
    ordered = tuple(legs[label] for label in LEG_LABELS)
    lower = np.array([j.lower for leg in ordered for j in leg.joints])
    upper = np.array([j.upper for leg in ordered for j in leg.joints])
    standing = np.tile(STANDING_Q, 4) if name == "paper" else np.clip(0.0, lower, upper)
    ids = [model.getJointId(j.name) for leg in ordered for j in leg.joints]
    return Robot(
        name=name,
        urdf=path,
        model=model,
        trunk=_inertia(model, 1, "the trunk"),
        legs=ordered,  # type: ignore[arg-type]
        idx_q=np.array([model.joints[j].idx_q for j in ids]),
        idx_v=np.array([model.joints[j].idx_v for j in ids]),
        joint_nq=np.array([model.joints[j].nq for j in ids]),
        foot_frame_ids=tuple(foot_ids[label] for label in LEG_LABELS),  # type: ignore[arg-type]
        standing_q=standing,
    )


def _prepared_model(path: Path) -> pin.Model:
    """Pinocchio's free-flyer model of the validated URDF, without armature, placements snapped."""
    model = _parse_urdf(path)
    model.armature[:] = 0.0
    for j in range(1, model.njoints):
        model.jointPlacements[j] = _snap(model.jointPlacements[j])
    for frame in model.frames:
        frame.placement = _snap(frame.placement)
    return model


def _leg_chains(model: pin.Model, path: Path) -> list[list[int]]:
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
                raise InputError(
                    f"leg joint '{model.names[j]}' is {model.joints[j].shortname()}; expected revolute joints only"
                )
    return chains


def _leg(model: pin.Model, chain: list[int], taken: dict[str, Leg]) -> tuple[Leg, int]:
    """The leg of one joint chain, labelled by its hip's quadrant (not one of ``taken``), and the
    Pinocchio id of its foot frame."""
    hip = model.jointPlacements[chain[0]].translation
    if abs(hip[0]) < 1e-9 or abs(hip[1]) < 1e-9:
        raise InputError(
            f"hip '{model.names[chain[0]]}' at {np.round(hip, 4)} lies on a trunk axis; "
            "expected hips with nonzero x (front/back) and y (left/right)"
        )
    label = ("F" if hip[0] > 0 else "B") + ("L" if hip[1] > 0 else "R")
    if label in taken:
        raise InputError(f"two legs have their hip in the {label} quadrant; expected one leg per quadrant")
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
    links = tuple(_inertia(model, j, f"the link moved by joint '{model.names[j]}'") for j in chain)
    fid = _foot_frame(model, chain[-1])
    foot = model.frames[fid].placement
    foot_placement = Placement(np.array(foot.rotation), np.array(foot.translation))
    return Leg(label, joints, links, foot_placement, model.frames[fid].name), fid  # type: ignore[arg-type]


def _limit(model: pin.Model, j: int, lower: bool) -> float:
    """Joint limit in rad, clipped to [-pi, pi] (URDFs often state +-10 rad or none)."""
    joint = model.joints[j]
    if joint.nq != 1:
        return -np.pi if lower else np.pi
    value = (model.lowerPositionLimit if lower else model.upperPositionLimit)[joint.idx_q]
    return float(max(value, -np.pi)) if lower else float(min(value, np.pi))
