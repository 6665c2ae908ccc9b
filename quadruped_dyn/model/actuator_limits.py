"""The leg joints' actuator limits from the URDF (effort, velocity): what a controller or an optimiser bounds its
motion by (the dynamics never read them)."""

from __future__ import annotations

import numpy as np

from quadruped_dyn.errors import InputError
from quadruped_dyn.model.robot import Robot

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


def actuator_limits(robot: Robot) -> dict[str, np.ndarray]:
    """Every kind of ``ACTUATOR_LIMITS`` by ``actuator_limit``: the one rule ``control`` and ``optimize`` apply."""
    return {kind: actuator_limit(robot, kind) for kind in ACTUATOR_LIMITS}
