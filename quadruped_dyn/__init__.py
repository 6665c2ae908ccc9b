"""quadruped_dyn: the paper's reduced-coordinate Newton-Euler quadruped dynamics,
written symbolically in CasADi, generated as C, and checked against Pinocchio."""

from .errors import InputError
from .leg import Leg, LegJoint, LinkInertia, Placement
from .robot import ROBOT_NAMES, Robot, load_robot

__all__ = ["InputError", "Leg", "LegJoint", "LinkInertia", "Placement", "ROBOT_NAMES", "Robot", "load_robot"]
