"""A robot's summary as plain data: legs, joints, link lengths, masses, standing feet."""

from __future__ import annotations

from typing import Any

import numpy as np

from quadruped_dyn.model.robot import Robot


def robot_info(robot: Robot) -> dict[str, Any]:
    feet = [leg.foot_position(q) for leg, q in zip(robot.legs, robot.standing_q.reshape(4, 3))]
    return {
        "name": robot.name,
        "urdf": str(robot.urdf),
        "total_mass_kg": robot.total_mass,
        "trunk_mass_kg": robot.trunk.mass,
        "standing_q_rad": robot.standing_q.tolist(),
        "legs": [
            {
                "label": leg.label,
                "joints": [j.name for j in leg.joints],
                "foot_frame": leg.foot_frame,
                "hip_position_m": leg.hip.tolist(),
                "thigh_length_m": float(np.linalg.norm(leg.joints[2].placement.p)),
                "shank_length_m": float(np.linalg.norm(leg.foot.p)),
                "link_masses_kg": [link.mass for link in leg.links],
                "foot_position_standing_m": foot.tolist(),
            }
            for leg, foot in zip(robot.legs, feet)
        ],
    }
