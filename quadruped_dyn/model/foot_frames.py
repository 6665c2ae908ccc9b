"""Which frame of a leg is its foot: the one the user named, else the rule of ``foot_frame`` (leaf frames below
the knee, named like a foot, the farthest)."""

from __future__ import annotations

import warnings

import numpy as np
import pinocchio as pin

from quadruped_dyn.errors import InputError, UrdfWarning
from quadruped_dyn.files.names import printable
from quadruped_dyn.model.leg import LEG_LABELS

#: Words in a frame's name that mark the contact point, and words that mark a frame that is not
#: one (a force sensor or camera can sit nearer the knee than the toe).
FOOT_WORDS = ("foot", "toe", "contact", "sole", "tip")
NOT_FOOT_WORDS = ("sensor", "imu", "camera", "lidar", "cam")
#: A foot frame is at least this far from the knee joint's axis origin (m): a frame at the origin (the shank's
#: own link frame) would make the shank length 0 and the leg a two-link leg.
FOOT_MIN_DISTANCE_M = 1e-9


def foot_frame(model: pin.Model, knee: int, label: str, wanted: str | None = None) -> int:
    """The foot frame of the leg whose knee is ``knee``: ``wanted`` if the user named it (it must
    hang from the knee's link), else among the leaf frames below the knee that are not named like
    a sensor or camera (``NOT_FOOT_WORDS``), the farthest named like a foot (``FOOT_WORDS``), else
    the farthest. With several candidates a UrdfWarning says which was chosen, why, and how to
    name another."""
    if wanted is not None:  # it exists: named_feet_exist ran first
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


def named_feet_exist(model: pin.Model, wanted_feet: dict[str, str]) -> None:
    """Every foot frame the user named is a frame of the URDF (checked in leg order, FL FR BL BR,
    before any leg is built)."""
    for label, wanted in wanted_feet.items():
        if not model.existFrame(wanted):
            raise InputError(f"foot frame '{printable(wanted)}' of leg {label} is not a frame of the URDF; "
                             "expected a link or frame below that leg's knee")
