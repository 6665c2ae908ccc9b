"""adam (``adam-robotics``) as a reference and as the benchmark's peer, in the project's conventions.

adam's conventions and how they are converted (tested in ``tests/references/test_drake_adam.py``):

* The URDF is loaded as adam's users load it: ``adam.casadi.KinDynComputations(urdf, joint_names)``,
  the root link (no parent) as the floating base, the joints **by name** in the order given
  (the project's), gravity ``GRAVITY_W`` (adam's default is -9.80665). The base pose is the
  4 x 4 homogeneous H = (R, p).
* The base velocity depends on the representation (adam's default is MIXED). With the
  project's (v_b, omega_b) and the adam base velocity nu = T_b (v_b, omega_b):
  BODY_FIXED: T_b = I (Pinocchio's local free flyer); MIXED: T_b = blockdiag(R, R) (p-dot and
  omega in the world frame); INERTIAL_FIXED: T_b = [[R, [p]x R], [0, R]] (the velocity of the
  body point at the world origin, and omega, in the world frame). Tdot v is
  (R (omega_b x v_b), 0) for MIXED and zero for the other two. Then M = T^T M_L T,
  C + G = T^T (h_L + M_L Tdot v), G = T^T g_L.
* Foot positions from ``forward_kinematics``; Jacobians from ``jacobian``, whose linear rows
  are the foot origin's velocity in foot axes (BODY_FIXED), world axes (MIXED), or the velocity
  of the foot-body point at the world origin (INERTIAL_FIXED: v_o + omega x p_foot is the foot's).
* adam has no inverse dynamics with accelerations (``aba`` is forward dynamics under joint
  torques with a free base): that term is not compared.

Model changes: adam 0.5 fails on an ``<inertial>`` or a ``<joint>`` without ``<origin>`` (a refusal
of the URDF as written); it is then given a copy with ``<origin xyz="0 0 0" rpy="0 0 0"/>`` added
there, the URDF default (exact). Welded links stay links of adam's tree, massless welded leaves become
frames (exact).
"""

from __future__ import annotations

import tempfile
import xml.etree.ElementTree as ET
from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from pathlib import Path

import casadi as ca
import numpy as np
import urdf_parser_py.xml_reflection.core as urdf_reflection
from adam import Representations
from adam.casadi import KinDynComputations

from quadruped_dyn.math.rigid import skew
from quadruped_dyn.model.robot import Robot
from quadruped_dyn.model.state import GRAVITY_W, NV_FULL, FullState, rotation
from quadruped_dyn.model.urdf_edit import strip_geometry, to_text
from quadruped_dyn.references.interface import Dynamics, ModelChange, Prepared

#: The representations, by the names the adapter and its tests use.
REPRESENTATIONS = {"body_fixed": Representations.BODY_FIXED_REPRESENTATION,
                   "mixed": Representations.MIXED_REPRESENTATION,
                   "inertial_fixed": Representations.INERTIAL_FIXED_REPRESENTATION}


class AdamRefusal(Exception):
    """adam could not load the URDF (its error, on one line)."""


@contextmanager
def _quiet_parser() -> Iterator[list[str]]:
    """urdf_parser_py's complaints (unknown tags: transmissions, materials), collected, not printed."""
    said: list[str] = []
    before = urdf_reflection.on_error
    urdf_reflection.on_error = said.append
    try:
        yield said
    finally:
        urdf_reflection.on_error = before


def load_kin_dyn(urdf_text: str, robot: Robot, representation: str = "body_fixed") -> KinDynComputations:
    """adam's CasADi computations of a URDF (text), joints in the project's order."""
    with tempfile.TemporaryDirectory() as tmp, _quiet_parser():
        path = Path(tmp) / "robot.urdf"
        path.write_text(urdf_text)
        try:
            kin_dyn = KinDynComputations(str(path), robot.joint_names, gravity=np.concatenate([GRAVITY_W, np.zeros(3)]))
        except Exception as e:  # adam raises what its parser meets: AttributeError, KeyError, ...
            raise AdamRefusal(f"{type(e).__name__}: {' '.join(str(e).split())[:200]}") from e
    kin_dyn.set_frame_velocity_representation(REPRESENTATIONS[representation])
    return kin_dyn


def with_default_origins(root: ET.Element) -> list[str]:
    """Add ``<origin xyz="0 0 0" rpy="0 0 0"/>`` (the URDF default) to every ``<inertial>`` and
    ``<joint>`` without one, in place; returns the names of the links and joints changed."""
    owners = [(link, link.find("inertial")) for link in root.findall("link")] + [(j, j) for j in root.findall("joint")]
    changed = []
    for owner, element in owners:
        if element is not None and element.find("origin") is None:
            element.insert(0, ET.Element("origin", {"xyz": "0 0 0", "rpy": "0 0 0"}))
            changed.append(owner.get("name", "?"))
    return changed


def pose(q: np.ndarray) -> np.ndarray:
    """adam's base pose H (4, 4) from the project's q."""
    H = np.eye(4)
    H[:3, :3], H[:3, 3] = rotation(q), q[:3]
    return H


class AdamReference:
    """M, C + G, G, foot positions and Jacobians from adam's CasADi functions, project coordinates."""

    name = "adam"
    cannot = {"inverse dynamics": "adam has no inverse dynamics with accelerations (its aba is forward dynamics)"}

    def __init__(self, kin_dyn: KinDynComputations, robot: Robot, representation: str = "body_fixed") -> None:
        if kin_dyn.NDoF != 12:
            raise AdamRefusal(f"adam's model has {kin_dyn.NDoF} joints; expected 12")
        self.representation = representation
        self.M, self.h, self.g = kin_dyn.mass_matrix_fun(), kin_dyn.bias_force_fun(), kin_dyn.gravity_term_fun()
        self.feet = [(kin_dyn.forward_kinematics_fun(leg.foot_frame), kin_dyn.jacobian_fun(leg.foot_frame))
                     for leg in robot.legs]

    def _T(self, q: np.ndarray, v: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(T, Tdot v): adam's velocity nu = T v in the representation, and its rate at v-dot = 0."""
        R, p = rotation(q), q[:3]
        T, Tdot_v = np.eye(NV_FULL), np.zeros(NV_FULL)
        if self.representation != "body_fixed":
            T[:3, :3] = T[3:6, 3:6] = R
        if self.representation == "mixed":
            Tdot_v[:3] = R @ np.cross(v[3:6], v[:3])
        if self.representation == "inertial_fixed":
            T[:3, 3:6] = skew(p) @ R
        return T, Tdot_v

    def mass_matrix(self, q: np.ndarray) -> np.ndarray:
        T, _ = self._T(q, np.zeros(NV_FULL))
        return T.T @ np.array(self.M(pose(q), q[7:])) @ T

    def nonlinear_effects(self, q: np.ndarray, v: np.ndarray) -> np.ndarray:
        """C(q, v) + G(q) (18,): T^T (h_L + M_L Tdot v)."""
        T, Tdot_v = self._T(q, v)
        nu = T @ v
        h = np.array(self.h(pose(q), q[7:], nu[:6], nu[6:])).ravel()
        return T.T @ (h + np.array(self.M(pose(q), q[7:])) @ Tdot_v)

    def gravity(self, q: np.ndarray) -> np.ndarray:
        T, _ = self._T(q, np.zeros(NV_FULL))
        return T.T @ np.array(self.g(pose(q), q[7:])).ravel()

    def inverse_dynamics(self, q: np.ndarray, v: np.ndarray, a: np.ndarray) -> np.ndarray:
        raise NotImplementedError(self.cannot["inverse dynamics"])

    def foot_positions(self, q: np.ndarray) -> np.ndarray:
        """(4, 3) foot frames' origins relative to the trunk origin, trunk frame, m."""
        return np.array([np.array(fk(pose(q), q[7:]))[:3, 3] - q[:3] for fk, _ in self.feet]) @ rotation(q)

    def foot_jacobians(self, q: np.ndarray) -> np.ndarray:
        """(4, 3, 3): d(foot position in b)/d(own 3 joints), trunk frame."""
        R, out = rotation(q), []
        for leg, (fk, jac) in enumerate(self.feet):
            H_foot, J = np.array(fk(pose(q), q[7:])), np.array(jac(pose(q), q[7:]))
            J = J[:, 6 + 3 * leg : 9 + 3 * leg]
            if self.representation == "body_fixed":
                out.append(R.T @ H_foot[:3, :3] @ J[:3])
            elif self.representation == "mixed":
                out.append(R.T @ J[:3])
            else:  # the foot point's velocity: v_o + omega x p_foot
                out.append(R.T @ (J[:3] - skew(H_foot[:3, 3]) @ J[3:]))
        return np.array(out)


def casadi_functions(robot: Robot) -> tuple[ca.Function, ca.Function]:
    """adam's M(H, s) and C + G (H, s, v_b, s_dot), BODY_FIXED (Pinocchio's M and nle), of the
    robot's URDF as the comparison loads it (the benchmark's peer)."""
    root = ET.parse(robot.urdf).getroot()
    with_default_origins(root)
    kin_dyn = load_kin_dyn(to_text(root), robot)
    return kin_dyn.mass_matrix_fun(), kin_dyn.bias_force_fun()


def prepare(robot: Robot, states: Sequence[FullState], pin_ref: Dynamics) -> Prepared:
    """What adam does to the robot's URDF, and adam's terms (BODY_FIXED)."""
    root = ET.parse(robot.urdf).getroot()
    strip_geometry(root)
    changes = []
    try:
        kin_dyn = load_kin_dyn(to_text(root), robot)
    except AdamRefusal as refusal:
        fixed = with_default_origins(root)
        changes.append(ModelChange("adam", "refused", fixed, f"adam refuses the URDF as written ({refusal})",
                                   in_comparison=False))
        if not fixed:
            return Prepared(None, changes)
        changes.append(ModelChange("adam", "origin_added", fixed, f"compared on a copy with <origin/> (the URDF default) "
                                   f"added to {len(fixed)} <inertial> or <joint> elements without one (exact)",
                                   in_comparison=True))
        try:
            kin_dyn = load_kin_dyn(to_text(root), robot)
        except AdamRefusal as again:
            changes.append(ModelChange("adam", "refused", [], f"adam refuses the edited copy too ({again}): not compared",
                                       in_comparison=False))
            return Prepared(None, changes)
    as_frames = len(kin_dyn.rbdalgos.model.frames)
    if as_frames:
        changes.append(ModelChange("adam", "links_as_frames", [], f"{as_frames} massless leaf links welded to another "
                                   "become frames of it; the other welded links stay links (exact)", in_comparison=True))
    try:
        reference = AdamReference(kin_dyn, robot)
    except Exception as e:  # adam's own error for a foot frame it does not know (KeyError, ...)
        changes.append(ModelChange("adam", "refused", [], f"adam cannot give the robot's terms ({type(e).__name__}: {e})",
                                   in_comparison=False))
        return Prepared(None, changes)
    return Prepared(reference, changes)
