"""quadruped_dyn: the paper's reduced-coordinate Newton-Euler quadruped dynamics,
written symbolically in CasADi, generated as C, and checked against Pinocchio."""

from typing import TYPE_CHECKING

from quadruped_dyn.exports import lazy_exports

__version__ = "0.1.0"  # the one source: pyproject.toml reads it (dynamic version)

if TYPE_CHECKING:  # the names' types for a type checker; imported on first use (CasADi, Pinocchio: ~1 s)
    from quadruped_dyn.errors import InputError as InputError
    from quadruped_dyn.errors import NumericalError as NumericalError
    from quadruped_dyn.math.rigid import LinkInertia as LinkInertia
    from quadruped_dyn.math.rigid import Placement as Placement
    from quadruped_dyn.model.leg import Leg as Leg
    from quadruped_dyn.model.leg import LegJoint as LegJoint
    from quadruped_dyn.model.registry import ROBOT_NAMES as ROBOT_NAMES
    from quadruped_dyn.model.robot import Robot as Robot
    from quadruped_dyn.model.robot import load_robot as load_robot

_MODULES: dict[str, tuple[str, ...]] = {
    "errors": ("InputError", "NumericalError"),
    "math.rigid": ("LinkInertia", "Placement"),
    "model.leg": ("Leg", "LegJoint"),
    "model.registry": ("ROBOT_NAMES",),
    "model.robot": ("Robot", "load_robot"),
}
__all__, __getattr__, __dir__ = lazy_exports(__name__, _MODULES)
