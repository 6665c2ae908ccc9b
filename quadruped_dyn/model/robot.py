"""Loading a quadruped from a URDF (or a built-in name) into the project's leg structure.

Legs are found by tree structure: four chains of three revolute joints hanging from the
trunk (the URDF root link, or a link welded to it without rotation, e.g. below a 'world' link),
each ending in a foot frame. Each leg is labelled FL, FR, BL, BR from the sign of its HAA origin
about the centre of the four HAA origins, in the trunk frame (x forward, y left, z up).

Joint order inside the project: FL, FR, BL, BR x (HAA, HFE, KFE) -- 12 entries.
``Robot.idx_q`` / ``Robot.idx_v`` map project joint k to Pinocchio's q / v index.
Links rigidly attached by fixed joints are merged into their parent's inertia (Pinocchio's
URDF parser does this). Rotor armature is not part of the paper's model and is set to zero.
Placement entries within ``SNAP_TOL`` of 0 or +-1 are snapped, in Pinocchio's model too.

One concept a module: ``registry`` (the built-in robots), ``urdf_parsing`` (read, validate, parse, snap),
``leg_discovery`` (the legs in the tree), ``foot_frames``, ``robot_identity`` (digests and names),
``actuator_limits``; this module assembles the ``Robot``.

The URDF is validated (``urdf_rules``) before Pinocchio parses it. One robot, one
identity, and identity is content: a file whose bytes are those of a built-in robot's URDF,
reached by its name, by any path or as a copy, loads as that robot (its name, its standing
posture); any other file is named after its stem (``files.names.safe_name``: valid as a C
identifier and a file name), with a hash of its content appended when the stem is a built-in's
name (a user's ``paper.urdf`` is not the paper robot). Two files with the same stem share the name;
the commands keep their outputs apart (``files.provenance``).

A model never outlives its file's content: the bytes are read once, hashed
(``Robot.urdf_sha256``) and parsed from memory, and the cache of loaded robots is keyed by
path and that hash, so an edited URDF is loaded afresh, and everything derived from a Robot
(e.g. the compiled library's key) hashes the bytes the model was built from.
"""

from __future__ import annotations

import hashlib
import warnings
from dataclasses import dataclass
from functools import cache
from pathlib import Path

import numpy as np
import pinocchio as pin

from quadruped_dyn.errors import InputError, UrdfWarning
from quadruped_dyn.files.names import printable
from quadruped_dyn.math.rigid import LinkInertia
from quadruped_dyn.model.foot_frames import foot_frame_names, named_feet_exist
from quadruped_dyn.model.leg import LEG_LABELS, Leg
from quadruped_dyn.model.leg_discovery import check_trunk_frame, leg_chains, leg_of_chain, link_inertia_of
from quadruped_dyn.model.paper_robot import STANDING_Q
from quadruped_dyn.model.physical_range import check_physical_range, robot_bodies
from quadruped_dyn.model.registry import robot_path
from quadruped_dyn.model.robot_identity import builtin_name, robot_name
from quadruped_dyn.model.urdf_parsing import prepared_model, read_urdf


@dataclass(frozen=True, eq=False)
class Robot:
    """A quadruped: Pinocchio free-flyer model plus the project's view of it."""

    name: str  # the built-in name if the URDF's bytes are a built-in's, else from the file's stem (safe_name)
    urdf: Path  # absolute
    model: pin.Model  # free-flyer model; q = (p, quat xyzw, joints), v = (v_b, omega_b, qd)
    trunk: LinkInertia  # in the trunk frame b
    legs: tuple[Leg, Leg, Leg, Leg]  # FL, FR, BL, BR
    idx_q: np.ndarray  # (12,) Pinocchio q index of project joint k
    idx_v: np.ndarray  # (12,) Pinocchio v index of project joint k
    joint_nq: np.ndarray  # (12,) 1 for revolute, 2 for continuous ((cos, sin) in Pinocchio's q)
    foot_frame_ids: tuple[int, int, int, int]  # Pinocchio frame ids of the feet, project leg order
    standing_q: np.ndarray  # (12,) a standing posture: the paper's Fig. 1d, else neutral clipped to limits
    urdf_sha256: str = ""  # SHA-256 of the bytes the model was parsed from
    builtin: str | None = None  # the built-in robot whose URDF these bytes are, else None

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


def check_robot(robot: object) -> Robot:
    """``robot`` itself, or an InputError if it is not a Robot (a name or a path is load_robot's):
    the first check of every public function of a robot, before a cache hashes the argument."""
    if not isinstance(robot, Robot):
        raise InputError(f"robot is {type(robot).__name__}; expected a Robot (quadruped_dyn.load_robot)")
    return robot


def load_robot(name_or_path: str, cached: bool = True, foot_frames: object = None) -> Robot:
    """Load a built-in robot by name, or any quadruped URDF by path. Cached per path and
    content (an edited file is loaded afresh) unless ``cached`` is False (e.g. a temporary file).
    ``foot_frames``: the foot frame of each leg, as four frame names in the order FL, FR, BL, BR
    or a mapping from leg label to name (default: chosen by ``foot_frames.foot_frame``'s rule)."""
    path = robot_path(name_or_path)
    feet = foot_frame_names(foot_frames)
    data = read_urdf(path)
    digest = hashlib.sha256(data).hexdigest()
    return _load(path, digest, feet) if cached else _load.__wrapped__(path, digest, feet, data)


@cache
def _load(path: Path, digest: str, foot_frames: tuple[str, str, str, str] | None = None,
          data: bytes | None = None) -> Robot:
    data = read_urdf(path) if data is None else data
    digest = hashlib.sha256(data).hexdigest()  # of the bytes parsed (the file may have changed since)
    model = prepared_model(path, data)
    builtin = builtin_name(path, digest)
    name = robot_name(path, builtin, digest)
    wanted_feet = dict(zip(LEG_LABELS, foot_frames)) if foot_frames else {}
    named_feet_exist(model, wanted_feet)
    legs: dict[str, Leg] = {}
    foot_ids: dict[str, int] = {}
    chains = leg_chains(model, path)
    check_trunk_frame(model, [chain[0] for chain in chains])
    centre = np.mean([model.jointPlacements[chain[0]].translation for chain in chains], axis=0)
    for chain in chains:
        leg, foot_ids[leg.label] = leg_of_chain(model, chain, taken=legs, hips_centre=centre, wanted_feet=wanted_feet)
        legs[leg.label] = leg
    ordered = tuple(legs[label] for label in LEG_LABELS)
    trunk = link_inertia_of(model, 1, "the trunk")
    for message in check_physical_range(robot_bodies(trunk, ordered)):
        warnings.warn(f"{printable(path.name)}: {message}", UrdfWarning, stacklevel=3)
    lower = np.array([j.lower for leg in ordered for j in leg.joints])
    upper = np.array([j.upper for leg in ordered for j in leg.joints])
    standing = np.tile(STANDING_Q, 4) if builtin == "paper" else np.clip(0.0, lower, upper)
    ids = [model.getJointId(j.name) for leg in ordered for j in leg.joints]
    return Robot(
        name=name,
        urdf=path,
        model=model,
        trunk=trunk,
        legs=ordered,  # type: ignore[arg-type]
        idx_q=np.array([model.joints[j].idx_q for j in ids]),
        idx_v=np.array([model.joints[j].idx_v for j in ids]),
        joint_nq=np.array([model.joints[j].nq for j in ids]),
        foot_frame_ids=tuple(foot_ids[label] for label in LEG_LABELS),  # type: ignore[arg-type]
        standing_q=standing,
        urdf_sha256=digest,
        builtin=builtin,
    )
