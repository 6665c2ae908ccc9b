"""Random variants of a robot, each as its own URDF: masses x [0.5, 2], every joint origin (hips, link offsets,
feet) x [0.8, 1.25], CoMs shifted, inertias replaced by random valid ones (random principal axes, moments within
[0.7, 1.3] of their mean: the triangle inequality holds)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pinocchio as pin

from quadruped_dyn import load_robot
from quadruped_dyn.model.robot import Robot
from quadruped_dyn.model.urdf_edit import link_inertia, parse_urdf_text, set_inertial, strip_geometry, to_text

#: CoM shift, m: within a few cm, as a payload or a revised part moves it.
COM_SHIFT_M = 0.02


def _random_inertia(Y: pin.Inertia, rng: np.random.Generator) -> pin.Inertia:
    mass = Y.mass * rng.uniform(0.5, 2.0)
    mean = np.trace(Y.inertia) / 3.0 * mass / Y.mass
    R = pin.Quaternion(*rng.normal(size=4)).normalized().matrix()
    moments = mean * rng.uniform(0.7, 1.3, size=3)
    return pin.Inertia(mass, Y.lever + rng.uniform(-COM_SHIFT_M, COM_SHIFT_M, size=3), R @ np.diag(moments) @ R.T)


def variant(robot: Robot, seed: int, directory: Path) -> Robot:
    """A random variant of ``robot`` (module docstring), written to ``directory`` and loaded from there."""
    rng = np.random.default_rng(seed)
    root = parse_urdf_text(robot.urdf.read_text())
    strip_geometry(root)
    for link in root.findall("link"):
        Y = link_inertia(link)
        if Y is not None and Y.mass > 0.0:
            set_inertial(root, link.get("name", ""), _random_inertia(Y, rng))
    for origin in (joint.find("origin") for joint in root.findall("joint")):
        if origin is not None and "xyz" in origin.attrib:
            xyz = np.array([float(x) for x in origin.get("xyz", "").split()]) * rng.uniform(0.8, 1.25)
            origin.set("xyz", " ".join(repr(float(x)) for x in xyz))
    path = directory / f"{robot.name}_variant_{seed}.urdf"
    path.write_text(to_text(root))
    return load_robot(str(path), cached=False)
