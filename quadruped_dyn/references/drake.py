"""Drake as a reference, converted to the project's conventions (optional extra ``xlib``).

Drake's conventions and how they are converted (tested in ``tests/references/test_drake_adam.py``):

* The URDF is parsed as Drake's users parse it: ``MultibodyPlant(0.0)``, ``Parser(plant)``,
  ``Finalize()``; the root link gets Drake's quaternion floating joint. Geometry is stripped
  (dynamics never read it; ``package://`` meshes would need a package map). Gravity ``GRAVITY_W``.
* The floating body's positions are (quaternion **w x y z**, position p [world]) and its
  velocities (omega_W, v_W): angular velocity, then the velocity of the body origin, both in
  the **world** frame. Joints are ordered by the plant: mapped **by name**
  (``position_start`` / ``velocity_start``). So v_D = T v with
  T: (v_b, omega_b, qd) -> (R omega_b, R v_b, P qd), and vdot_D = T a + Tdot v with
  Tdot v = (0, R (omega_b x v_b), 0). Hence M = T^T M_D T, C + G = T^T (C_D v + M_D Tdot v - tau_g),
  G = -T^T tau_g, inverse dynamics = T^T ``CalcInverseDynamics(vdot_D, gravity as an applied force)``.
* Foot positions and Jacobians: ``CalcRelativeTransform`` and ``CalcJacobianTranslationalVelocity``
  of the foot link's frame, measured and expressed in the trunk's body frame.

Model changes: welded links stay separate bodies (exact). An inertia that is not physically
valid (the 1e-6 dummy base links) is *regularised* by Drake's parser, with a warning: the adapter
reads back every body's spatial inertia, names each one Drake changed, and the comparison's
Pinocchio runs on a copy of the URDF carrying Drake's inertia (``compared_urdf``).
"""

from __future__ import annotations

import logging
import xml.etree.ElementTree as ET
from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from typing import Any

import numpy as np
import pinocchio as pin
from pydrake.multibody.parsing import Parser
from pydrake.multibody.plant import MultibodyPlant
from pydrake.multibody.tree import JacobianWrtVariable, MultibodyForces

from quadruped_dyn.model.robot import Robot
from quadruped_dyn.model.state import GRAVITY_W, NV_FULL, FullState, rotation
from quadruped_dyn.model.urdf_edit import link_inertia, set_inertial, strip_geometry, to_text
from quadruped_dyn.references.interface import Dynamics, ModelChange, Prepared, max_rel_errors, pinocchio_of

#: A body's inertia as Drake holds it differs from the URDF's by more than this (relative to the
#: largest of mass, |first moment| and |inertia| at the body origin): Drake changed it.
REGULARISED_REL = 1e-12


class DrakeRefusal(Exception):
    """Drake's parser or plant refused the model (its message, on one line)."""


@contextmanager
def _captured_warnings() -> Iterator[list[str]]:
    """Drake's parser warnings (pydrake logs them to the 'drake' logger) collected, not printed."""
    said: list[str] = []

    class Collect(logging.Handler):
        def emit(self, record: logging.LogRecord) -> None:
            said.append(" ".join(record.getMessage().split()))

    logger, handler = logging.getLogger("drake"), Collect()
    propagate = logger.propagate
    logger.addHandler(handler)
    logger.propagate = False
    try:
        yield said
    finally:
        logger.removeHandler(handler)
        logger.propagate = propagate


def load_plant(urdf_text: str) -> tuple[MultibodyPlant, list[str]]:
    """Drake's plant of a URDF (text) and the warnings its parser gave."""
    plant = MultibodyPlant(0.0)
    with _captured_warnings() as said:
        try:
            Parser(plant).AddModelsFromString(urdf_text, "urdf")
            gravity: Any = GRAVITY_W  # pydrake's stubs type arrays as ndarray[float64, ...]: numpy's types never match
            plant.mutable_gravity_field().set_gravity_vector(gravity)
            plant.Finalize()
        except Exception as e:  # pydrake raises RuntimeError with the parser's text
            raise DrakeRefusal(" ".join(str(e).split())[:300]) from e
    return plant, said


class DrakeReference:
    """M, C + G, G, inverse dynamics, foot positions and Jacobians from Drake, project coordinates."""

    name = "drake"
    cannot: dict[str, str] = {}

    def __init__(self, plant: MultibodyPlant, robot: Robot) -> None:
        floating = list(plant.GetFloatingBaseBodies())
        if plant.num_velocities() != NV_FULL or len(floating) != 1:
            raise DrakeRefusal(f"Drake's plant has {plant.num_velocities()} velocities and {len(floating)} floating "
                               "bodies; expected one floating trunk and 12 joints")
        self.plant, self.context = plant, plant.CreateDefaultContext()
        self.base = plant.get_body(floating[0])
        self.q_start, self.v_start = self.base.floating_positions_start(), self.base.floating_velocities_start_in_v()
        joints = [plant.GetJointByName(n) for n in robot.joint_names]
        self.qpos_idx = np.array([j.position_start() for j in joints])
        self.dof_idx = np.array([j.velocity_start() for j in joints])
        missing = [leg.foot_frame for leg in robot.legs if not plant.HasFrameNamed(leg.foot_frame)]
        if missing:
            raise DrakeRefusal(f"Drake has no frame for the foot link(s) {missing}")
        self.feet = [plant.GetFrameByName(leg.foot_frame) for leg in robot.legs]

    def _set(self, q: np.ndarray, v: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Set Drake's positions and velocities from the project's q, v; returns (T, Tdot v)."""
        R = rotation(q)
        s = self.v_start
        T = np.zeros((NV_FULL, NV_FULL))
        T[s : s + 3, 3:6] = R  # omega_W = R omega_b
        T[s + 3 : s + 6, 0:3] = R  # v_W = R v_b
        T[self.dof_idx, np.arange(6, NV_FULL)] = 1.0
        Tdot_v = np.zeros(NV_FULL)
        Tdot_v[s + 3 : s + 6] = R @ np.cross(v[3:6], v[:3])
        positions: Any = np.zeros(self.plant.num_positions())  # Any: as for the gravity vector
        positions[self.q_start : self.q_start + 4] = np.r_[q[6], q[3:6]] / np.linalg.norm(q[3:7])  # xyzw -> wxyz
        positions[self.q_start + 4 : self.q_start + 7] = q[:3]
        positions[self.qpos_idx] = q[7:]
        self.plant.SetPositions(self.context, positions)
        self.plant.SetVelocities(self.context, T @ v)
        return T, Tdot_v

    def mass_matrix(self, q: np.ndarray) -> np.ndarray:
        T, _ = self._set(q, np.zeros(NV_FULL))
        return T.T @ self.plant.CalcMassMatrix(self.context) @ T

    def nonlinear_effects(self, q: np.ndarray, v: np.ndarray) -> np.ndarray:
        """C(q, v) + G(q) (18,): T^T (C_D v + M_D Tdot v - tau_g)."""
        T, Tdot_v = self._set(q, v)
        ctx, plant = self.context, self.plant
        return T.T @ (plant.CalcBiasTerm(ctx) + plant.CalcMassMatrix(ctx) @ Tdot_v - plant.CalcGravityGeneralizedForces(ctx))

    def gravity(self, q: np.ndarray) -> np.ndarray:
        T, _ = self._set(q, np.zeros(NV_FULL))
        return -T.T @ self.plant.CalcGravityGeneralizedForces(self.context)

    def inverse_dynamics(self, q: np.ndarray, v: np.ndarray, a: np.ndarray) -> np.ndarray:
        """tau (18,) with M a + C + G = tau: ``CalcInverseDynamics`` with gravity as the applied force."""
        T, Tdot_v = self._set(q, v)
        forces = MultibodyForces(self.plant)
        forces.mutable_generalized_forces()[:] = self.plant.CalcGravityGeneralizedForces(self.context)
        return T.T @ self.plant.CalcInverseDynamics(self.context, T @ a + Tdot_v, forces)

    def foot_positions(self, q: np.ndarray) -> np.ndarray:
        """(4, 3) foot positions relative to the trunk origin, trunk frame, m."""
        self._set(q, np.zeros(NV_FULL))
        trunk = self.base.body_frame()
        return np.array([self.plant.CalcRelativeTransform(self.context, trunk, foot).translation() for foot in self.feet])

    def foot_jacobians(self, q: np.ndarray) -> np.ndarray:
        """(4, 3, 3): d(foot position in b)/d(own 3 joints), trunk frame."""
        self._set(q, np.zeros(NV_FULL))
        trunk, origin = self.base.body_frame(), np.zeros(3)
        out = []
        for leg, foot in enumerate(self.feet):
            J = self.plant.CalcJacobianTranslationalVelocity(self.context, JacobianWrtVariable.kV, foot, origin,  # type: ignore[arg-type]
                                                             trunk, trunk)
            out.append(J[:, self.dof_idx[3 * leg : 3 * leg + 3]])
        return np.array(out)


def _drake_inertia(plant: MultibodyPlant, link: str) -> np.ndarray:
    """The body's spatial inertia as Drake holds it: (m, m c, the 6 entries of the inertia about the body origin)."""
    M_BBo = plant.GetBodyByName(link).default_spatial_inertia()
    mass, com = M_BBo.get_mass(), np.asarray(M_BBo.get_com())
    return np.r_[mass, mass * com, M_BBo.CalcRotationalInertia().CopyToFullMatrix3()[np.triu_indices(3)]]


def _urdf_inertia(link: ET.Element) -> np.ndarray:
    """The same of the link's URDF ``<inertial>`` (zero without one)."""
    Y = link_inertia(link)
    if Y is None:
        return np.zeros(10)
    c = np.asarray(Y.lever)
    I_origin = np.asarray(Y.inertia) + Y.mass * (c @ c * np.eye(3) - np.outer(c, c))
    return np.r_[Y.mass, Y.mass * c, I_origin[np.triu_indices(3)]]


def regularised_links(root: ET.Element, plant: MultibodyPlant) -> dict[str, pin.Inertia]:
    """Links whose inertia Drake holds differently from the URDF's, with Drake's inertia (about the CoM)."""
    changed = {}
    for link in root.findall("link"):
        name = link.get("name", "")
        written, held = _urdf_inertia(link), _drake_inertia(plant, name)
        if np.abs(held - written).max() > REGULARISED_REL * max(np.abs(written).max(), np.finfo(float).tiny):
            M_BBo = plant.GetBodyByName(name).default_spatial_inertia()
            com: Any = np.asarray(M_BBo.get_com())  # Any: as for the gravity vector
            I_com = M_BBo.Shift(com).CalcRotationalInertia().CopyToFullMatrix3()
            changed[name] = pin.Inertia(M_BBo.get_mass(), com, I_com)
    return changed


def prepare(robot: Robot, states: Sequence[FullState], pin_ref: Dynamics) -> Prepared:
    """What Drake does to the robot's URDF, and Drake's terms on it."""
    root = ET.parse(robot.urdf).getroot()
    strip_geometry(root)
    try:
        plant, said = load_plant(to_text(root))
        reference = DrakeReference(plant, robot)
    except DrakeRefusal as e:
        return Prepared(None, [ModelChange("drake", "refused", [], f"Drake refuses the URDF: {e}", in_comparison=False)])
    bodies = plant.num_bodies() - 1  # less the world body
    changes = [ModelChange("drake", "welded_bodies", [], f"{bodies} bodies: welded links kept as bodies joined by weld "
                           "joints (Pinocchio merges them: exact)", in_comparison=True)]
    damped = [n for n in robot.joint_names if np.any(plant.GetJointByName(n).default_damping_vector())]
    if damped:
        changes.append(ModelChange("drake", "joint_damping", damped, f"Drake applies the URDF's <dynamics damping> of "
                                   f"{len(damped)} joints as a force element (CalcForceElementsContribution); the terms "
                                   "compared are the rigid-body ones, without it (Pinocchio's rnea has none)",
                                   in_comparison=False))
    regularised = regularised_links(root, plant)
    if not regularised:
        return Prepared(reference, changes)
    for link, inertia in regularised.items():
        set_inertial(root, link, inertia)
    warned = next((w for w in said if "inertia" in w.lower()), "")
    held = "; ".join(np.array2string(np.linalg.eigvalsh(np.asarray(y.inertia)), precision=2) for y in regularised.values())
    changes.append(ModelChange("drake", "regularised_inertia", list(regularised),
                               f"Drake's parser replaces the invalid inertia of {list(regularised)} by a valid one "
                               f"(principal moments about the CoM {held}); compared on a copy carrying Drake's inertia. "
                               f"Drake said: {warned[:160]}", in_comparison=True,
                               size=max_rel_errors(pinocchio_of(to_text(root)), pin_ref, states)))
    return Prepared(reference, changes, to_text(root))
