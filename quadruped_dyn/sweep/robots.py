"""The robots of a sweep, as what a task carries to a worker: a built-in robot by name (the worker's
installed copy, whose bytes must hash the same), or the URDF's bytes themselves (paths, globs and
variants), written on the worker into its verified cache (``files.cache``) under their hash.

A variant is a robot's URDF rewritten by ``model.urdf_edit.scale_urdf`` with mass, length and
inertia scales drawn uniformly from the sweep file's ranges (seed, variant index).
"""

from __future__ import annotations

import hashlib
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from quadruped_dyn.errors import InputError
from quadruped_dyn.sweep.spec import SweepSpec, Variants


@dataclass(frozen=True)
class RobotRef:
    label: str  # the name shown: the robot's, or a variant's <robot>_v<k>
    sha256: str  # of the URDF's bytes
    builtin: str | None = None  # loaded by name on the worker
    urdf: bytes | None = field(default=None, repr=False)  # else these bytes
    scales: tuple[float, float, float] = (1.0, 1.0, 1.0)  # a variant's mass, length, inertia scales


def _path_ref(path: Path) -> RobotRef:
    from quadruped_dyn.model.robot_identity import urdf_source

    source = urdf_source(path)
    if source.builtin is not None:
        return RobotRef(source.builtin, source.urdf_sha256, builtin=source.builtin)
    return RobotRef(source.name, source.urdf_sha256, urdf=path.read_bytes())


def _variant_refs(v: Variants) -> list[RobotRef]:
    from quadruped_dyn.model.registry import robot_path
    from quadruped_dyn.model.robot_identity import urdf_source
    from quadruped_dyn.model.urdf_edit import parse_urdf_text, scale_urdf, to_text

    path = robot_path(v.robot)
    base = urdf_source(path).name
    text = path.read_text(encoding="utf-8")
    refs = []
    for k in range(v.count):
        rng = np.random.default_rng([v.seed, k])
        scales = tuple(float(rng.uniform(lo, hi)) if hi > lo else float(lo)
                       for lo, hi in (v.mass_scale, v.length_scale, v.inertia_scale))
        root = parse_urdf_text(text)
        scale_urdf(root, *scales)
        data = ('<?xml version="1.0"?>\n' + to_text(root)).encode()
        refs.append(RobotRef(f"{base}_v{k:03d}", hashlib.sha256(data).hexdigest(), urdf=data, scales=scales))  # type: ignore[arg-type]
    return refs


def sweep_robots(spec: SweepSpec) -> list[RobotRef]:
    """Every robot of the sweep, in the file's order (names, paths, variants), each URDF once."""
    from quadruped_dyn.model.registry import robot_path

    refs = [_path_ref(robot_path(n)) for n in spec.names] + [_path_ref(p) for p in spec.paths]
    for v in spec.variants:
        refs += _variant_refs(v)
    seen: set[str] = set()
    unique = []
    for r in refs:
        if r.sha256 not in seen:
            seen.add(r.sha256)
            unique.append(r)
    return unique


def materialise(ref: RobotRef) -> object:
    """The ``Robot`` of ``ref`` on this worker: the built-in by name (InputError if its bytes are not the ones the
    sweep was made with: a worker in another environment), else the URDF bytes from the verified cache."""
    from quadruped_dyn.files.cache import cached_build
    from quadruped_dyn.model.robot import load_robot

    if ref.builtin is not None:
        robot = load_robot(ref.builtin)
        if robot.urdf_sha256 != ref.sha256:
            raise InputError(f"built-in robot '{ref.builtin}' on this worker has another URDF (SHA-256 "
                             f"{robot.urdf_sha256[:12]}, the sweep's {ref.sha256[:12]}); expected the sweep's environment")
        return robot
    data = ref.urdf or b""

    def write(path: Path) -> None:
        path.write_bytes(data)

    path = cached_build(f"sweep-urdf-{ref.sha256[:16]}", f"{ref.label}.urdf", write)
    robot = load_robot(str(path))
    if robot.urdf_sha256 != ref.sha256:  # the bytes carried, not another file of that name
        raise InputError(f"the cached URDF '{path}' hashes {robot.urdf_sha256[:12]}; expected the sweep's {ref.sha256[:12]}")
    return robot
