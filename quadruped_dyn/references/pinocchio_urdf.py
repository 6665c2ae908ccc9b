"""Pinocchio as its users load a URDF, as a reference beside the toolkit's own Pinocchio model.

``pinocchio.buildModelFromXML(urdf, JointModelFreeFlyer())``, nothing else: no validation, the
placements as written (the toolkit snaps entries within ``SNAP_TOL`` of 0 or +-1), armature as
the parser reads it (the toolkit zeroes it). Conventions are the project's (q = (p, quaternion
x y z w, joints), v = (v_b, omega_b, qd), Pinocchio's local free flyer); joints and foot frames
are mapped **by name**.
"""

from __future__ import annotations

import dataclasses
import xml.etree.ElementTree as ET
from collections.abc import Sequence

import numpy as np
import pinocchio as pin

from quadruped_dyn.model.robot import Robot
from quadruped_dyn.model.state import FullState
from quadruped_dyn.model.urdf_edit import strip_geometry, to_text
from quadruped_dyn.references.interface import Dynamics, ModelChange, PinocchioTerms, Prepared


def as_loaded(robot: Robot) -> Robot:
    """The robot with Pinocchio's model of its URDF as users build it, indices mapped by name."""
    root = ET.parse(robot.urdf).getroot()
    strip_geometry(root)  # and the visuals' colours: urdfdom prints complaints about them, dynamics never reads them
    for material in root.findall("material"):
        root.remove(material)
    model = pin.buildModelFromXML(to_text(root), pin.JointModelFreeFlyer())
    joints = [model.joints[model.getJointId(n)] for n in robot.joint_names]
    feet = tuple(model.getFrameId(robot.model.frames[f].name) for f in robot.foot_frame_ids)
    return dataclasses.replace(robot, model=model, idx_q=np.array([j.idx_q for j in joints]),
                               idx_v=np.array([j.idx_v for j in joints]), joint_nq=np.array([j.nq for j in joints]),
                               foot_frame_ids=feet)


def prepare(robot: Robot, states: Sequence[FullState], pin_ref: Dynamics) -> Prepared:
    """Pinocchio on the URDF as written, and what the toolkit's own loading changes in it."""
    loaded = as_loaded(robot)
    changes = [ModelChange("pinocchio", "fused_links", [], "welded links merged into their parent joint's body "
                           "(Pinocchio's URDF parser; the toolkit's model too: exact)", in_comparison=True)]
    if np.any(loaded.model.armature):
        changes.append(ModelChange("pinocchio", "armature", [], f"armature {np.array2string(loaded.model.armature)} read "
                                   "from the URDF (the toolkit's model has none)", in_comparison=True))
    return Prepared(PinocchioTerms(loaded), changes)
