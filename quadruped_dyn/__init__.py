"""quadruped_dyn: the paper's reduced-coordinate Newton-Euler quadruped dynamics,
written symbolically in CasADi, generated as C, and checked against Pinocchio."""

from quadruped_dyn.errors import InputError, NumericalError
from quadruped_dyn.math.rigid import LinkInertia, Placement
from quadruped_dyn.model.leg import Leg, LegJoint
from quadruped_dyn.model.robot import ROBOT_NAMES, Robot, load_robot

__all__ = ["InputError", "NumericalError", "Leg", "LegJoint", "LinkInertia", "Placement", "ROBOT_NAMES", "Robot", "load_robot"]
