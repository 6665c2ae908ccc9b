"""A robot's identity is its URDF's content: the SHA-256 of the bytes, the built-in robot they are, and the
name a robot gets (the built-in's, else the file's stem made safe, never a built-in's name)."""

from __future__ import annotations

import hashlib
from dataclasses import dataclass
from functools import cache
from pathlib import Path

from quadruped_dyn.files.names import safe_name
from quadruped_dyn.model.registry import ROBOT_NAMES, builtin_path
from quadruped_dyn.model.urdf_parsing import read_urdf


@cache
def _builtin_digests() -> dict[str, str]:
    """SHA-256 of each built-in robot's URDF that is installed."""
    return {name: _digest(builtin_path(name)) for name in ROBOT_NAMES if builtin_path(name).is_file()}


def _digest(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


def builtin_name(path: Path, digest: str | None = None) -> str | None:
    """The built-in robot whose URDF has the same bytes as ``path`` (SHA-256 ``digest``), or None."""
    digest = _digest(path) if digest is None else digest
    return next((name for name, d in _builtin_digests().items() if d == digest), None)


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
    digest = hashlib.sha256(read_urdf(path)).hexdigest()
    builtin = builtin_name(path, digest)
    return UrdfSource(robot_name(path, builtin, digest), path, digest, builtin)


def robot_name(path: Path, builtin: str | None, digest: str) -> str:
    """The robot's name: the built-in's for a built-in's bytes; else the file's stem made safe, and
    never a built-in's name (that name would bring the built-in's posture and output folder)."""
    if builtin is not None:
        return builtin
    name = safe_name(path.stem)
    if name in ROBOT_NAMES:
        name = f"{name}_{digest[:8]}"
    return name
