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

The URDF is validated (``urdf_validation``) before Pinocchio parses it. One robot, one
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
import importlib.metadata
import os
import tempfile
import warnings
import xml.etree.ElementTree as ET
from dataclasses import dataclass
from functools import cache
from pathlib import Path

import numpy as np
import pinocchio as pin

from quadruped_dyn.errors import InputError, UrdfWarning
from quadruped_dyn.files.names import printable, safe_name
from quadruped_dyn.math.rigid import LinkInertia, Placement
from quadruped_dyn.model.leg import LEG_LABELS, Leg, LegJoint
from quadruped_dyn.model.paper_robot import STANDING_Q, URDF_PATH
from quadruped_dyn.model.urdf_edit import strip_geometry, to_text
from quadruped_dyn.model.urdf_rules import check_urdf_size, inertia_problem, validate_urdf

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
    if not isinstance(name_or_path, (str, Path)):
        raise InputError(f"robot {name_or_path!r} is a {type(name_or_path).__name__}; expected a built-in name "
                         f"({', '.join(ROBOT_NAMES)}) or the path of a URDF file")
    key = str(name_or_path)
    if key in ROBOT_NAMES:
        path = _builtin_path(key)
        if not path.is_file():
            raise InputError(f"the URDF of built-in robot '{key}' is missing at '{path}'; expected the installed "
                             "package's file (reinstall quadruped_dyn / example-robot-data)")
        return path.resolve()
    path = Path(key)
    if not path.is_file():
        what = "not a regular file" if path.exists() else "no such file"
        raise InputError(f"{what}: '{printable(key)}'; expected a URDF path or one of: {', '.join(ROBOT_NAMES)}")
    return path.resolve()


@cache
def _builtin_digests() -> dict[str, str]:
    """SHA-256 of each built-in robot's URDF that is installed."""
    return {name: _digest(_builtin_path(name)) for name in ROBOT_NAMES if _builtin_path(name).is_file()}


def _digest(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


def builtin_name(path: Path, digest: str | None = None) -> str | None:
    """The built-in robot whose URDF has the same bytes as ``path`` (SHA-256 ``digest``), or None."""
    digest = _digest(path) if digest is None else digest
    return next((name for name, d in _builtin_digests().items() if d == digest), None)


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


#: Words in a frame's name that mark the contact point, and words that mark a frame that is not
#: one (a force sensor or camera can sit nearer the knee than the toe).
FOOT_WORDS = ("foot", "toe", "contact", "sole", "tip")
NOT_FOOT_WORDS = ("sensor", "imu", "camera", "lidar", "cam")
#: A foot frame is at least this far from the knee joint's axis origin (m): a frame at the origin (the shank's
#: own link frame) would make the shank length 0 and the leg a two-link leg.
FOOT_MIN_DISTANCE_M = 1e-9


def _foot_frame(model: pin.Model, knee: int, label: str, wanted: str | None = None) -> int:
    """The foot frame of the leg whose knee is ``knee``: ``wanted`` if the user named it (it must
    hang from the knee's link), else among the leaf frames below the knee that are not named like
    a sensor or camera (``NOT_FOOT_WORDS``), the farthest named like a foot (``FOOT_WORDS``), else
    the farthest. With several candidates a UrdfWarning says which was chosen, why, and how to
    name another."""
    if wanted is not None:  # it exists: _named_feet_exist ran first
        fid = model.getFrameId(wanted)
        if model.frames[fid].parentJoint != knee:
            raise InputError(f"foot frame '{printable(wanted)}' of leg {label} does not hang from the knee joint "
                             f"'{model.names[knee]}'; expected a frame rigidly attached to the last leg link")
        if np.linalg.norm(model.frames[fid].placement.translation) <= FOOT_MIN_DISTANCE_M:
            raise InputError(f"foot frame '{printable(wanted)}' of leg {label} is at the knee joint "
                             f"'{model.names[knee]}' (a shank of length 0); expected a frame at the foot, below the knee")
        return fid
    parents = {f.parentFrame for f in model.frames}
    leaves = [
        i
        for i, f in enumerate(model.frames)
        if f.parentJoint == knee and i not in parents and np.linalg.norm(f.placement.translation) > FOOT_MIN_DISTANCE_M
    ]
    if not leaves:
        raise InputError(
            f"no foot frame below joint '{model.names[knee]}'; expected a link attached to the last leg link (a foot)"
        )

    def dist(i: int) -> float:
        return float(np.linalg.norm(model.frames[i].placement.translation))

    def named(i: int, words: tuple[str, ...]) -> bool:
        return any(w in model.frames[i].name.lower() for w in words)

    pool = [i for i in leaves if not named(i, NOT_FOOT_WORDS)] or leaves
    footish = [i for i in pool if named(i, FOOT_WORDS)]
    chosen = max(footish or pool, key=dist)
    if len(leaves) > 1:
        why = "the farthest leaf frame named like a foot" if footish else "the farthest leaf frame (none is named like a foot)"
        others = ", ".join(f"'{model.frames[i].name}' ({dist(i):.3f} m)" for i in leaves if i != chosen)
        warnings.warn(f"leg {label}: foot frame '{model.frames[chosen].name}' at {dist(chosen):.3f} m from the knee, "
                      f"{why}; other leaf frames below the knee: {others}; name the feet (load_robot(..., "
                      "foot_frames=[...]), or --foot-frames of info, check, codegen, validate, control, optimize and report) "
                      "if another is the contact point",
                      UrdfWarning, stacklevel=4)
    return chosen


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


class _Stderr:
    """Captures what C++ code writes to file descriptor 2 (urdfdom prints its own ``Error:``
    lines before Pinocchio raises): the one-line error says it instead."""

    def __enter__(self) -> _Stderr:
        self._file = tempfile.TemporaryFile()
        try:
            import sys

            sys.stderr.flush()
        except (OSError, ValueError):
            pass
        self._saved = os.dup(2)
        os.dup2(self._file.fileno(), 2)
        return self

    def __exit__(self, *exc: object) -> None:
        os.dup2(self._saved, 2)
        os.close(self._saved)
        self._file.seek(0)
        self.text = self._file.read().decode("utf-8", "replace")
        self._file.close()


def _parse_urdf(path: Path, data: bytes) -> pin.Model:
    """Pinocchio's free-flyer model of the URDF whose bytes are ``data``, validated first. Pinocchio parses
    the XML the validation read (any encoding, as Unicode), without the geometry and
    materials (the dynamics never read them). Its parser (urdfdom) drops an element it cannot read, e.g. a whole
    ``<inertial>`` for ``<mass value="2.0 ">``, says so on stderr and returns the model anyway: that is an
    InputError too, not a model without the mass."""
    for message in validate_urdf(path, data):
        warnings.warn(f"{printable(path.name)}: {message}", UrdfWarning, stacklevel=2)
    root = ET.fromstring(data)  # well-formed: validate_urdf parsed it
    strip_geometry(root)
    for material in root.findall("material"):  # the visuals' colours: urdfdom's complaints about one are harmless
        root.remove(material)
    capture = _Stderr()
    try:
        with capture:
            model = pin.buildModelFromXML(to_text(root), pin.JointModelFreeFlyer())
    except Exception as e:  # Pinocchio raises plain ValueError/RuntimeError with the parser's text
        said = [line.strip() for line in capture.text.splitlines() if line.strip()]
        first = (said[:1] or str(e).strip().splitlines()[:1] or ["no reason given"])[0]
        reason = first.removeprefix("Error:").strip().rstrip(".")  # our sentence goes on after it
        raise InputError(f"Pinocchio cannot parse '{printable(path)}': {printable(reason)}; expected one tree of links "
                         "joined by joints: a trunk with four legs of three revolute joints each") from e
    errors = [line.strip() for line in capture.text.splitlines() if line.strip().startswith("Error:")]
    if errors:
        reasons = "; then ".join(e.removeprefix("Error:").strip().rstrip(".") for e in errors[:2])
        raise InputError(f"Pinocchio's parser skipped part of '{printable(path)}': {printable(reasons)}; expected every "
                         "element readable (numbers without stray characters or spaces inside the quotes)")
    return model


#: The URDF <limit> attributes of a leg joint a controller or an optimiser bounds its motion by, and their units.
ACTUATOR_LIMITS = {"effort": "N m", "velocity": "rad/s"}


def actuator_limit(robot: Robot, kind: str) -> np.ndarray:
    """(12,) the leg joints' <limit effort> (N m) or <limit velocity> (rad/s), project order;
    InputError unless each is positive and finite: at 0 a joint can exert no torque or make no
    motion, which no controller and no optimised gait can use (the dynamics do not read them)."""
    values = {"effort": robot.model.effortLimit, "velocity": robot.model.velocityLimit}[kind]
    limit = np.array([float(values[v]) for v in robot.idx_v])
    if not np.all(np.isfinite(limit) & (limit > 0)):
        raise InputError(f"{robot.name}: {kind} limits {limit.round(2).tolist()} {ACTUATOR_LIMITS[kind]}; expected a "
                         f"positive finite <limit {kind}> on every leg joint")
    return limit


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
    or a mapping from leg label to name (default: chosen by ``_foot_frame``'s rule)."""
    path = robot_path(name_or_path)
    feet = foot_frame_names(foot_frames)
    data = _read_urdf(path)
    digest = hashlib.sha256(data).hexdigest()
    return _load(path, digest, feet) if cached else _load.__wrapped__(path, digest, feet, data)


def _read_urdf(path: Path) -> bytes:
    try:
        check_urdf_size(path, None, path.stat().st_size)  # before reading a huge file
        data = path.read_bytes()
    except OSError as e:
        raise InputError(f"cannot read '{printable(path)}' ({e.strerror}); expected a readable URDF file") from e
    return data


def foot_frame_names(foot_frames: object, what: str = "foot_frames") -> tuple[str, str, str, str] | None:
    """``foot_frames`` (a sequence, a comma-separated string or a dict by leg label) as four names in leg order,
    or None; an InputError for anything else, naming ``what`` (the caller's parameter or option)."""
    if foot_frames is None:
        return None
    if isinstance(foot_frames, dict):
        if set(foot_frames) != set(LEG_LABELS):
            raise InputError(f"{what} has keys {sorted(map(str, foot_frames))}; expected {list(LEG_LABELS)}")
        foot_frames = [foot_frames[label] for label in LEG_LABELS]
    given = foot_frames
    if isinstance(foot_frames, str):
        foot_frames = foot_frames.split(",")
    try:
        names: tuple[object, ...] = tuple(foot_frames)  # type: ignore[arg-type]
    except TypeError as e:
        raise InputError(f"{what} is {type(foot_frames).__name__}; expected four frame names (FL, FR, BL, BR)") from e
    if len(names) != 4 or not all(isinstance(n, str) and n for n in names):
        shown = f"'{given}'" if isinstance(given, str) else str(names)
        raise InputError(f"{what} is {printable(shown)}; expected four frame names in the order FL, FR, BL, BR")
    return names  # type: ignore[return-value]


@dataclass(frozen=True)
class UrdfSource:
    """What ``load_robot`` makes of a URDF's file before parsing it: the name, the path, the SHA-256
    of its bytes and the built-in robot they are (else None), as a ``Robot`` has them."""

    name: str
    urdf: Path
    urdf_sha256: str
    builtin: str | None


def urdf_source(path: Path) -> UrdfSource:
    """The name ``load_robot`` gives the URDF at ``path``, with its path, hash and built-in (without parsing it)."""
    digest = hashlib.sha256(_read_urdf(path)).hexdigest()
    builtin = builtin_name(path, digest)
    return UrdfSource(_name(path, builtin, digest), path, digest, builtin)


def _name(path: Path, builtin: str | None, digest: str) -> str:
    """The robot's name: the built-in's for a built-in's bytes; else the file's stem made safe, and
    never a built-in's name (that name would bring the built-in's posture and output folder)."""
    if builtin is not None:
        return builtin
    name = safe_name(path.stem)
    if name in ROBOT_NAMES:
        name = f"{name}_{digest[:8]}"
    return name


@cache
def _load(path: Path, digest: str, foot_frames: tuple[str, str, str, str] | None = None,
          data: bytes | None = None) -> Robot:
    data = _read_urdf(path) if data is None else data
    digest = hashlib.sha256(data).hexdigest()  # of the bytes parsed (the file may have changed since)
    model = _prepared_model(path, data)
    builtin = builtin_name(path, digest)
    name = _name(path, builtin, digest)
    wanted_feet = dict(zip(LEG_LABELS, foot_frames)) if foot_frames else {}
    _named_feet_exist(model, wanted_feet)
    legs: dict[str, Leg] = {}
    foot_ids: dict[str, int] = {}
    chains = _leg_chains(model, path)
    _check_trunk_frame(model, [chain[0] for chain in chains])
    centre = np.mean([model.jointPlacements[chain[0]].translation for chain in chains], axis=0)
    for chain in chains:
        leg, foot_ids[leg.label] = _leg(model, chain, taken=legs, hips_centre=centre, wanted_feet=wanted_feet)
        legs[leg.label] = leg
    ordered = tuple(legs[label] for label in LEG_LABELS)
    lower = np.array([j.lower for leg in ordered for j in leg.joints])
    upper = np.array([j.upper for leg in ordered for j in leg.joints])
    standing = np.tile(STANDING_Q, 4) if builtin == "paper" else np.clip(0.0, lower, upper)
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
        urdf_sha256=digest,
        builtin=builtin,
    )


def _prepared_model(path: Path, data: bytes) -> pin.Model:
    """Pinocchio's free-flyer model of the validated URDF (its bytes ``data``), without armature,
    placements snapped."""
    model = _parse_urdf(path, data)
    model.armature[:] = 0.0
    for j in range(1, model.njoints):
        model.jointPlacements[j] = _snap(model.jointPlacements[j])
    for frame in model.frames:
        frame.placement = _snap(frame.placement)
    return model


def _named_feet_exist(model: pin.Model, wanted_feet: dict[str, str]) -> None:
    """Every foot frame the user named is a frame of the URDF (checked in leg order, FL FR BL BR,
    before any leg is built)."""
    for label, wanted in wanted_feet.items():
        if not model.existFrame(wanted):
            raise InputError(f"foot frame '{printable(wanted)}' of leg {label} is not a frame of the URDF; "
                             "expected a link or frame below that leg's knee")


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
                kind = model.joints[j].shortname()
                kind = f"prismatic ({kind})" if kind.startswith("JointModelP") else kind  # the only other URDF type left
                raise InputError(
                    f"leg joint '{model.names[j]}' is {kind}; expected revolute joints only"
                )
    return chains


def _check_trunk_frame(model: pin.Model, hips: list[int]) -> None:
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


def _leg(model: pin.Model, chain: list[int], taken: dict[str, Leg], hips_centre: np.ndarray,
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
    links = tuple(_inertia(model, j, f"the link moved by joint '{model.names[j]}'") for j in chain)
    fid = _foot_frame(model, chain[-1], label, (wanted_feet or {}).get(label))
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
