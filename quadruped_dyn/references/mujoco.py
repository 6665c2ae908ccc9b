"""MuJoCo as a second reference, converted to the project's conventions (optional extra ``xlib``).

MuJoCo's conventions and how they are converted (tested in ``tests/checks/test_cross_library.py``):

* qpos = (p [world], quaternion **w x y z**, joint angles in MuJoCo's order); the project's
  quaternion is x y z w. Joints are mapped **by name** (``Robot.joint_names``).
* The free joint's velocity is (linear velocity of the body origin in the **world** frame,
  angular velocity in the **body** frame): v_mj = T v with T = blockdiag(R, I, P), where v is
  the project's (v_b, omega_b, qd) and P the joint permutation. Hence
  M = T^T M_mj T and  C + G = T^T (qfrc_bias + M_mj Tdot v),  Tdot v = (R (omega_b x v_b), 0, 0).
* Foot Jacobians: ``mj_jacSite`` at a site added at the origin of each foot link (world
  frame, MuJoCo's dof columns), rotated into the trunk frame, the leg's own three columns.

How the URDF is loaded: MuJoCo's URDF defaults (``fusestatic``: welded links are fused
into their parent; ``discardvisual``), a free joint added to the root link, gravity
``GRAVITY_W``. Geometry is stripped and ``inertiafromgeom`` is off, so the inertias are the
URDF's (MuJoCo's own choices are measured separately, in ``prepare``).
"""

from __future__ import annotations

import os
import xml.etree.ElementTree as ET
from collections.abc import Sequence
from dataclasses import dataclass

os.environ.setdefault("MUJOCO_GL", "egl")  # chosen at import: headless offscreen rendering (control/study_files.py)
import mujoco  # noqa: E402
import numpy as np

from quadruped_dyn.model.robot import Robot
from quadruped_dyn.model.state import GRAVITY_W, NV_FULL, FullState, rotation
from quadruped_dyn.model.urdf_edit import (
    BREAKS_TRIANGLE,
    NOT_POSITIVE_DEFINITE,
    balance_inertia,
    drop_inertial,
    fixed_neighbour,
    inertia_problems,
    merge_inertial,
    strip_geometry,
    to_text,
)
from quadruped_dyn.references.interface import Dynamics, ModelChange, Prepared, max_rel_errors, pinocchio_of


class MuJoCoRefusal(Exception):
    """MuJoCo's compiler refused the model (its message, on one line)."""


@dataclass(frozen=True)
class MuJoCoOptions:
    balanceinertia: bool = False  # MuJoCo: replace principal moments breaking A + B >= C by their mean
    inertia_from_geometry: bool = False  # MuJoCo's default 'auto': links without <inertial> get one from collision shapes


def compile_model(root: ET.Element, robot: Robot, options: MuJoCoOptions) -> mujoco.MjModel:
    """Compile a URDF (an element tree, left untouched) with a free joint and a site per foot."""
    root = ET.fromstring(to_text(root))
    strip_geometry(root, keep_primitive_collisions=options.inertia_from_geometry)
    spec = mujoco.MjSpec.from_string(to_text(root))
    spec.compiler.balanceinertia = options.balanceinertia
    spec.compiler.inertiafromgeom = (mujoco.mjtInertiaFromGeom.mjINERTIAFROMGEOM_AUTO if options.inertia_from_geometry
                                     else mujoco.mjtInertiaFromGeom.mjINERTIAFROMGEOM_FALSE)
    spec.option.gravity = GRAVITY_W
    spec.worldbody.first_body().add_freejoint()
    for leg in robot.legs:
        foot = spec.body(leg.foot_frame)
        if foot is None:
            raise MuJoCoRefusal(f"MuJoCo has no body for the foot link '{leg.foot_frame}'")
        foot.add_site(name=f"quadruped_dyn_foot_{leg.label}", pos=[0.0, 0.0, 0.0])
    try:
        return spec.compile()
    except ValueError as e:
        raise MuJoCoRefusal(" ".join(str(e).replace("Error: ", "").split())) from e


class MuJoCoReference:
    """M, C + G, G, inverse dynamics, foot positions and Jacobians from MuJoCo, project coordinates (``state``)."""

    name = "mujoco"
    cannot: dict[str, str] = {}

    def __init__(self, model: mujoco.MjModel, robot: Robot) -> None:
        self.model = model
        self.data = mujoco.MjData(model)
        if model.nv != NV_FULL or model.jnt_type[0] != mujoco.mjtJoint.mjJNT_FREE:
            raise MuJoCoRefusal(f"MuJoCo model has nv = {model.nv} and first joint type {model.jnt_type[0]}; "
                                f"expected a free joint and 12 hinges")
        self.qpos_idx = np.array([model.joint(n).qposadr[0] for n in robot.joint_names])
        self.dof_idx = np.array([model.joint(n).dofadr[0] for n in robot.joint_names])
        self.sites = [model.site(f"quadruped_dyn_foot_{leg.label}").id for leg in robot.legs]

    def _set(self, q: np.ndarray, v: np.ndarray) -> np.ndarray:
        """Set qpos, qvel from the project's q, v and run the position and velocity stages; returns T."""
        R = rotation(q)
        T = np.zeros((NV_FULL, NV_FULL))
        T[:3, :3] = R
        T[3:6, 3:6] = np.eye(3)
        T[self.dof_idx, np.arange(6, NV_FULL)] = 1.0
        self.data.qpos[:3] = q[:3]
        self.data.qpos[3:7] = np.array([q[6], q[3], q[4], q[5]]) / np.linalg.norm(q[3:7])  # xyzw -> wxyz
        self.data.qpos[self.qpos_idx] = q[7:]
        self.data.qvel[:] = T @ v
        mujoco.mj_forward(self.model, self.data)
        return T

    def _mass_matrix_mj(self) -> np.ndarray:
        M = np.zeros((NV_FULL, NV_FULL))
        mujoco.mj_fullM(self.model, self.data, M)
        return M

    def mass_matrix(self, q: np.ndarray) -> np.ndarray:
        T = self._set(q, np.zeros(NV_FULL))
        return T.T @ self._mass_matrix_mj() @ T

    def nonlinear_effects(self, q: np.ndarray, v: np.ndarray) -> np.ndarray:
        """C(q, v) + G(q) (18,): T^T (qfrc_bias + M_mj Tdot v)."""
        T = self._set(q, v)
        Tdot_v = np.zeros(NV_FULL)
        Tdot_v[:3] = rotation(q) @ np.cross(v[3:6], v[:3])
        return T.T @ (self.data.qfrc_bias + self._mass_matrix_mj() @ Tdot_v)

    def gravity(self, q: np.ndarray) -> np.ndarray:
        T = self._set(q, np.zeros(NV_FULL))
        return T.T @ self.data.qfrc_bias

    def inverse_dynamics(self, q: np.ndarray, v: np.ndarray, a: np.ndarray) -> np.ndarray:
        """tau (18,) = T^T (M_mj qacc + bias) at qacc = T a + Tdot v: ``mj_rne`` with accelerations (the
        rigid-body part of ``mj_inverse``, without the passive and friction forces of joint damping)."""
        T = self._set(q, v)
        self.data.qacc[:] = T @ a
        self.data.qacc[:3] += rotation(q) @ np.cross(v[3:6], v[:3])
        tau = np.zeros(NV_FULL)
        mujoco.mj_rne(self.model, self.data, 1, tau)
        return T.T @ tau

    def foot_positions(self, q: np.ndarray) -> np.ndarray:
        """(4, 3) foot sites relative to the trunk origin, trunk frame, m."""
        self._set(q, np.zeros(NV_FULL))
        return np.array([self.data.site_xpos[site] - q[:3] for site in self.sites]) @ rotation(q)

    def foot_jacobians(self, q: np.ndarray) -> np.ndarray:
        """(4, 3, 3): d(foot position in b)/d(own 3 joints), trunk frame."""
        self._set(q, np.zeros(NV_FULL))
        R = rotation(q)
        out = []
        for leg, site in enumerate(self.sites):
            jacp = np.zeros((3, NV_FULL))
            mujoco.mj_jacSite(self.model, self.data, jacp, None, site)
            out.append(R.T @ jacp[:, self.dof_idx[3 * leg : 3 * leg + 3]])
        return np.array(out)


# ---------------------------------------------------------------------------- model diagnosis
def prepare(robot: Robot, states: Sequence[FullState], pin_ref: Dynamics) -> Prepared:
    """What MuJoCo does to the robot's URDF, and MuJoCo's terms on the copy it accepts.

    A refused URDF (a link inertia not positive definite or breaking A + B >= C): the size of
    MuJoCo's own fix (``balanceinertia``) is measured, and the comparison runs on a copy with
    each offending inertial merged into its welded neighbour (exact), else balanced as MuJoCo would.
    """
    original = ET.parse(robot.urdf).getroot()
    changes: list[ModelChange] = []
    copy: ET.Element | None = None
    try:
        model = compile_model(original, robot, MuJoCoOptions())
    except MuJoCoRefusal as refusal:
        problems = inertia_problems(original)
        changes.append(ModelChange("mujoco", "refused", [p.link for p in problems],
                                   f"MuJoCo refuses the URDF: {refusal}. Inertias it cannot take: "
                                   + ("; ".join(map(str, problems)) or "none found by the toolkit"), in_comparison=False))
        copy, edits = _accepted_copy(original, robot, states, pin_ref)
        changes += edits
        try:
            model = compile_model(copy, robot, MuJoCoOptions())
        except MuJoCoRefusal as again:
            changes.append(ModelChange("mujoco", "refused", [], f"MuJoCo refuses the edited copy too ({again}): not compared",
                                       in_comparison=False))
            return Prepared(None, changes)
    reference = MuJoCoReference(model, robot)
    fused = len(original.findall("link")) - (model.nbody - 1)
    changes.append(ModelChange("mujoco", "fused_links", [], f"{fused} welded links fused into their parent bodies "
                               "(fusestatic, MuJoCo's URDF default; Pinocchio merges them too: exact)", in_comparison=True))
    changes += _inertia_from_geometry(original, robot, states)
    return Prepared(reference, changes, None if copy is None else to_text(copy))


def _merge_welded(root: ET.Element, kinds: tuple[str, ...]) -> list[str]:
    """Merge the inertials with these problems into their welded neighbours, repeatedly (a merge
    can leave the neighbour non-physical); returns 'link -> neighbour' for each merge."""
    merged = []
    for _ in range(len(root.findall("link"))):
        todo = [p.link for p in inertia_problems(root) if p.kind in kinds and fixed_neighbour(root, p.link) is not None]
        if not todo:
            break
        merged += [f"{link} -> {merge_inertial(root, link)}" for link in todo]
    return merged


def _accepted_copy(original: ET.Element, robot: Robot, states: Sequence[FullState],
                   pin_ref: Dynamics) -> tuple[ET.Element, list[ModelChange]]:
    """A copy MuJoCo accepts, and the changes made: offending inertials merged into their welded
    neighbours (exact), any left that break A + B >= C balanced as MuJoCo does. Also measures
    MuJoCo's own fix (``balanceinertia``) once the non-positive-definite ones are merged."""
    root = ET.fromstring(to_text(original))
    changes = []
    merged = _merge_welded(root, (NOT_POSITIVE_DEFINITE,))
    unbalanced = [p.link for p in inertia_problems(root) if p.kind == BREAKS_TRIANGLE]
    if unbalanced:
        where = " on the copy with the non-positive-definite inertials merged" if merged else ""
        try:
            balanced = MuJoCoReference(compile_model(root, robot, MuJoCoOptions(balanceinertia=True)), robot)
            changes.append(ModelChange("mujoco", "balanceinertia", unbalanced,
                                       f"MuJoCo's own fix, balanceinertia='true'{where}, sets the principal moments of "
                                       f"{unbalanced} to their mean (not used for the comparison)", in_comparison=False,
                                       size=max_rel_errors(balanced, pin_ref, states)))
        except MuJoCoRefusal as e:
            changes.append(ModelChange("mujoco", "balanceinertia", unbalanced,
                                       f"balanceinertia='true'{where} does not make MuJoCo accept it ({e})", in_comparison=False))
    merged += _merge_welded(root, (NOT_POSITIVE_DEFINITE, BREAKS_TRIANGLE))
    if merged:
        changes.append(ModelChange("mujoco", "merged_inertial", merged,
                                   f"compared on a copy with {len(merged)} refused inertials merged into the links they are "
                                   f"welded to ({', '.join(merged[:3])}{', ...' if len(merged) > 3 else ''})",
                                   in_comparison=True, size=max_rel_errors(pinocchio_of(to_text(root)), pin_ref, states)))
    unbalanced = [p.link for p in inertia_problems(root) if p.kind == BREAKS_TRIANGLE]
    if unbalanced:
        before = pinocchio_of(to_text(root))
        for link in unbalanced:
            balance_inertia(root, link)
        changes.append(ModelChange("mujoco", "balanced_inertia", unbalanced,
                                   f"compared on a copy with MuJoCo's balanceinertia rule applied to {unbalanced} "
                                   "(principal moments -> their mean)", in_comparison=True,
                                   size=max_rel_errors(pinocchio_of(to_text(root)), before, states)))
    return root, changes


def _inertia_from_geometry(original: ET.Element, robot: Robot, states: Sequence[FullState]) -> list[ModelChange]:
    """Links without <inertial> but with collision shapes: MuJoCo's default inertiafromgeom='auto'
    gives them mass and inertia from the shapes (density 1000 kg/m^3; mesh shapes are not loaded
    here). Measured on a copy with the refused inertials dropped, with the shapes vs without."""
    links = [x for x in original.findall("link") if x.find("inertial") is None and x.find("collision") is not None]
    if not links:
        return []
    names = [x.get("name", "?") for x in links]
    meshes = sum(len(x.findall("collision/geometry/mesh")) for x in links)
    root = ET.fromstring(to_text(original))
    refused = [p.link for p in inertia_problems(root)]
    for link in refused:
        drop_inertial(root, link)
    try:
        without = MuJoCoReference(compile_model(root, robot, MuJoCoOptions()), robot)
        with_geometry = MuJoCoReference(compile_model(root, robot, MuJoCoOptions(inertia_from_geometry=True)), robot)
    except MuJoCoRefusal as e:
        return [ModelChange("mujoco", "inertiafromgeom", names, f"with collision shapes MuJoCo refuses it ({e})", False)]
    added = float(with_geometry.model.body_mass.sum() - without.model.body_mass.sum())
    dropped = f"; measured with {len(refused)} refused inertials dropped" if refused else ""
    return [ModelChange("mujoco", "inertiafromgeom", names,
                        f"with collision shapes kept, MuJoCo's default inertiafromgeom='auto' gives {names} {added:.2f} kg "
                        f"({meshes} mesh shapes not loaded{dropped}); the comparison keeps the URDF's inertias",
                        in_comparison=False, size=max_rel_errors(with_geometry, without, states))]


def accepted_urdf(original: ET.Element) -> tuple[ET.Element, list[str]]:
    """A copy of the URDF MuJoCo's compiler accepts, and what was changed (one line each): the
    refused inertials merged into the links they are welded to (exact), any left that break
    A + B >= C balanced as MuJoCo's ``balanceinertia`` would (principal moments -> their mean).
    Used by the closed-loop plant; ``prepare`` measures what each change does to the terms."""
    root = ET.fromstring(to_text(original))
    changes = [f"inertial merged: {m}" for m in _merge_welded(root, (NOT_POSITIVE_DEFINITE, BREAKS_TRIANGLE))]
    for link in [p.link for p in inertia_problems(root) if p.kind == BREAKS_TRIANGLE]:
        balance_inertia(root, link)
        changes.append(f"inertia balanced (A + B >= C): {link}")
    return root, changes
