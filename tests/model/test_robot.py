"""Robot loading: leg discovery by tree structure, labels, foot frames, joint maps."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

from quadruped_dyn.model import paper_robot
from quadruped_dyn.model.leg import LEG_LABELS
from quadruped_dyn.model.robot import load_robot
from quadruped_dyn.model.state import full_q
from quadruped_dyn.references.pinocchio import PinocchioReference
from tests.conftest import assert_close

#: Each robot's own name of its FL leg's joints (labels come from hip positions, not names).
FL_JOINTS = {
    "paper": ["FL_HAA", "FL_HFE", "FL_KFE"],
    "solo12": ["FL_HAA", "FL_HFE", "FL_KFE"],
    "go2": ["FL_hip_joint", "FL_thigh_joint", "FL_calf_joint"],
    "go1": ["FL_hip_joint", "FL_thigh_joint", "FL_calf_joint"],
    "a1": ["FL_hip_joint", "FL_thigh_joint", "FL_calf_joint"],
    "anymal_c": ["LF_HAA", "LF_HFE", "LF_KFE"],
    "hyq": ["lf_haa_joint", "lf_hfe_joint", "lf_kfe_joint"],
}
BR_JOINTS = {"solo12": "HR_KFE", "go2": "RR_calf_joint", "anymal_c": "RH_KFE", "hyq": "rh_kfe_joint", "paper": "BR_KFE"}


def test_fl_leg_joint_names(robot):
    assert [j.name for j in robot.legs[0].joints] == FL_JOINTS[robot.name]
    if robot.name in BR_JOINTS:
        assert robot.legs[3].joints[2].name == BR_JOINTS[robot.name]


def test_labels_follow_hip_quadrants(robot):
    for label, leg in zip(LEG_LABELS, robot.legs):
        assert leg.label == label
        assert np.sign(leg.hip[0]) == (1 if label[0] == "F" else -1)
        assert np.sign(leg.hip[1]) == (1 if label[1] == "L" else -1)


def test_joint_map_matches_pinocchio(robot):
    model = robot.model
    for k, name in enumerate(robot.joint_names):
        joint = model.joints[model.getJointId(name)]
        assert robot.idx_q[k] == joint.idx_q and robot.idx_v[k] == joint.idx_v
    assert sorted(robot.idx_v) == list(range(6, 18))


def test_foot_is_the_leaf_below_the_knee(robot):
    for leg, fid in zip(robot.legs, robot.foot_frame_ids):
        frame = robot.model.frames[fid]
        assert frame.name == leg.foot_frame
        assert robot.model.names[frame.parentJoint] == leg.joints[2].name
        assert "foot" in frame.name.lower()


def test_leg_structure_forward_kinematics_matches_pinocchio(robot):
    """The project's leg structure (placements, axes) reproduces Pinocchio's foot positions."""
    ref = PinocchioReference(robot)
    rng = np.random.default_rng(3)
    for _ in range(5):
        qj = rng.uniform(robot.lower, robot.upper)
        feet = ref.foot_positions(full_q(np.eye(3), np.zeros(3), qj))
        for i, leg in enumerate(robot.legs):
            assert_close(leg.foot_position(qj[3 * i : 3 * i + 3]), feet[i], what=f"{leg.label} foot")


def test_inertias_merged_and_total_mass(robot):
    assert robot.total_mass == pytest.approx(sum(Y.mass for Y in robot.model.inertias), rel=1e-12)


def test_load_by_path_equals_builtin(robot):
    """One robot, one identity: the path of a built-in's file loads the same Robot."""
    by_path = load_robot(str(robot.urdf))
    assert by_path is robot
    assert by_path.name == robot.name


def test_paper_leg_from_urdf_equals_dh_compilation(paper):
    """URDF writer + Pinocchio parser round-trip the DH-compiled legs exactly."""
    for leg in paper.legs:
        dh = paper_robot.dh_leg(leg.label)
        for a, b in zip(leg.joints, dh.joints):
            assert_close(a.placement.homogeneous(), b.placement.homogeneous(), what=a.name)
            assert_close(a.axis, b.axis, what=a.name)
        for a, b in zip(leg.links, dh.links):
            assert a.mass == pytest.approx(b.mass)
            assert_close(a.com, b.com)
            assert_close(a.inertia, b.inertia)
        assert_close(leg.foot.homogeneous(), dh.foot.homogeneous())


def test_another_quadruped_urdf_by_path(erd):
    """A quadruped that is not built in (Laikago, same leg structure) loads by path."""
    r = load_robot(str(erd / "laikago_description/urdf/laikago.urdf"))
    assert [leg.label for leg in r.legs] == list(LEG_LABELS)
    assert r.model.nv == 18


def test_free_flyer_convention():
    """Pinocchio's free-flyer q is (p, quaternion x y z w, joints) -- the project relies on it."""
    model = load_robot("solo12").model
    q = pin.neutral(model)
    assert np.allclose(q[3:7], [0, 0, 0, 1])


@pytest.mark.parametrize("robot", [None, 123, 1.5, b"paper"])
def test_a_robot_that_is_not_a_name_or_path_says_its_type(robot):
    """load_robot(None) said "no such file: 'None'" (found on a fresh clone)."""
    from quadruped_dyn.errors import InputError

    with pytest.raises(InputError, match=f"is a {type(robot).__name__}; expected a built-in name"):
        load_robot(robot)
