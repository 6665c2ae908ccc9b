"""iDynTree as a second reference, converted to the project's conventions (optional extra ``xlib``).

iDynTree's conventions and how they are used (tested in ``tests/checks/test_cross_library.py``):

* ``KinDynComputations`` defaults to the MIXED velocity representation (base linear velocity
  in the world frame). It is set to **BODY_FIXED**: the base twist is (v_b, omega_b) in the
  base (trunk) frame, 6D vectors are (linear, angular) — the project's v — and
  M v̇ + h = τ then holds with the project's a = v̇ (spatial body acceleration).
* The floating base is the URDF root link (the project's trunk frame); joint positions and
  rates are set in iDynTree's dof order, mapped **by name** (``Robot.joint_names``).
* Foot Jacobians: ``getFrameFreeFloatingJacobian`` of the foot frame (BODY_FIXED: the foot
  origin's velocity in foot axes), rotated into the trunk frame, the leg's own three columns.

Links are kept as links (welded ones joined by fixed joints); massless leaves welded to a
link become "additional frames" of it. Inertias are taken as written: iDynTree accepts
inertias that are not positive definite or break A + B >= C.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from collections.abc import Sequence

import idyntree.bindings as idt
import numpy as np

from quadruped_dyn.model.robot import Robot
from quadruped_dyn.model.state import GRAVITY_W, NV_FULL, FullState, rotation
from quadruped_dyn.model.urdf_edit import inertia_problems, strip_geometry, to_text
from quadruped_dyn.references.interface import Dynamics, ModelChange, Prepared


class IDynTreeRefusal(Exception):
    """iDynTree could not load the model."""


def load_model(urdf_text: str) -> idt.Model:
    loader = idt.ModelLoader()
    if not loader.loadModelFromString(urdf_text):
        raise IDynTreeRefusal("iDynTree's ModelLoader did not load the URDF")
    return loader.model().copy()  # the loader owns model(); it dies with the loader


class IDynTreeReference:
    """M, C + G, G, inverse dynamics, foot positions and Jacobians from iDynTree, project coordinates (``state``)."""

    name = "idyntree"
    cannot: dict[str, str] = {}

    def __init__(self, model: idt.Model, robot: Robot) -> None:
        self.kin_dyn = idt.KinDynComputations()
        if not self.kin_dyn.loadRobotModel(model):
            raise IDynTreeRefusal("iDynTree's KinDynComputations did not accept the model")
        self.kin_dyn.setFrameVelocityRepresentation(idt.BODY_FIXED_REPRESENTATION)
        if model.getNrOfDOFs() != 12:
            raise IDynTreeRefusal(f"iDynTree model has {model.getNrOfDOFs()} dofs; expected 12")
        self.dof_idx = np.array([model.getJoint(model.getJointIndex(n)).getDOFsOffset() for n in robot.joint_names])
        self.base = self.kin_dyn.getFloatingBase()
        self.feet = [leg.foot_frame for leg in robot.legs]
        for foot in self.feet:
            if model.getFrameIndex(foot) < 0:
                raise IDynTreeRefusal(f"iDynTree has no frame for the foot link '{foot}'")

    def _set(self, q: np.ndarray, v: np.ndarray) -> None:
        H = np.eye(4)
        H[:3, :3] = rotation(q)
        H[:3, 3] = q[:3]
        s, ds = np.zeros(12), np.zeros(12)
        s[self.dof_idx], ds[self.dof_idx] = q[7:], v[6:]
        ok = self.kin_dyn.setRobotState(idt.Transform(H), idt.VectorDynSize(s), idt.Twist(v[:6]),
                                        idt.VectorDynSize(ds), idt.Vector3(GRAVITY_W))
        if not ok:
            raise IDynTreeRefusal("iDynTree's setRobotState failed")

    def _project(self, h: idt.FreeFloatingGeneralizedTorques) -> np.ndarray:
        joints = h.jointTorques().toNumPy()
        return np.concatenate([h.baseWrench().toNumPy(), joints[self.dof_idx]])

    @property
    def _perm(self) -> np.ndarray:
        return np.concatenate([np.arange(6), 6 + self.dof_idx])

    def mass_matrix(self, q: np.ndarray) -> np.ndarray:
        self._set(q, np.zeros(NV_FULL))
        M = idt.MatrixDynSize(NV_FULL, NV_FULL)
        self.kin_dyn.getFreeFloatingMassMatrix(M)
        return M.toNumPy()[np.ix_(self._perm, self._perm)]

    def nonlinear_effects(self, q: np.ndarray, v: np.ndarray) -> np.ndarray:
        """C(q, v) + G(q) (18,): ``generalizedBiasForces``."""
        self._set(q, v)
        h = idt.FreeFloatingGeneralizedTorques(self.kin_dyn.model())
        self.kin_dyn.generalizedBiasForces(h)
        return self._project(h)

    def gravity(self, q: np.ndarray) -> np.ndarray:
        self._set(q, np.zeros(NV_FULL))
        h = idt.FreeFloatingGeneralizedTorques(self.kin_dyn.model())
        self.kin_dyn.generalizedGravityForces(h)
        return self._project(h)

    def inverse_dynamics(self, q: np.ndarray, v: np.ndarray, a: np.ndarray) -> np.ndarray:
        """tau (18,): ``inverseDynamics`` with BODY_FIXED base acceleration a[:6] (the project's vdot_b)."""
        self._set(q, v)
        dds = np.zeros(12)
        dds[self.dof_idx] = a[6:]
        h = idt.FreeFloatingGeneralizedTorques(self.kin_dyn.model())
        no_forces = idt.LinkWrenches(self.kin_dyn.model())
        no_forces.zero()
        if not self.kin_dyn.inverseDynamics(idt.Vector6(a[:6]), idt.VectorDynSize(dds), no_forces, h):
            raise IDynTreeRefusal("iDynTree's inverseDynamics failed")
        return self._project(h)

    def foot_positions(self, q: np.ndarray) -> np.ndarray:
        """(4, 3) foot frames' origins relative to the trunk origin, trunk frame, m."""
        self._set(q, np.zeros(NV_FULL))
        out = []
        for foot in self.feet:
            H = self.kin_dyn.getRelativeTransform(self.base, foot)  # kept: getPosition() is a view into it
            out.append(np.array(H.getPosition().toNumPy()))
        return np.array(out)

    def foot_jacobians(self, q: np.ndarray) -> np.ndarray:
        """(4, 3, 3): d(foot position in b)/d(own 3 joints), trunk frame."""
        self._set(q, np.zeros(NV_FULL))
        out = []
        for leg, foot in enumerate(self.feet):
            J = idt.MatrixDynSize(6, NV_FULL)
            self.kin_dyn.getFrameFreeFloatingJacobian(foot, J)
            R_b_foot = self.kin_dyn.getRelativeTransform(self.base, foot).getRotation().toNumPy()
            out.append(R_b_foot @ J.toNumPy()[:3, 6 + self.dof_idx[3 * leg : 3 * leg + 3]])
        return np.array(out)


def prepare(robot: Robot, states: Sequence[FullState], pin_ref: Dynamics) -> Prepared:
    """What iDynTree does to the robot's URDF (it accepts it as written), and its terms."""
    root = ET.parse(robot.urdf).getroot()
    strip_geometry(root)
    try:
        model = load_model(to_text(root))
        reference = IDynTreeReference(model, robot)
    except IDynTreeRefusal as e:
        return Prepared(None, [ModelChange("idyntree", "refused", [], str(e), in_comparison=False)])
    changes = []
    problems = inertia_problems(root)
    if problems:
        changes.append(ModelChange("idyntree", "accepted_as_is", [p.link for p in problems],
                                   f"accepts {len(problems)} non-physical inertias as written (no change): "
                                   + "; ".join(map(str, problems)), in_comparison=True))
    as_frames = model.getNrOfFrames() - model.getNrOfLinks()
    if as_frames:
        changes.append(ModelChange("idyntree", "links_as_frames", [], f"{as_frames} massless links welded to another "
                                   "become frames of it (exact)", in_comparison=True))
    return Prepared(reference, changes)
