"""The paper's robot: DH conventions of docs/formulation.md §1 and docs/conventions.md §8 and a reproducible URDF."""

from __future__ import annotations

import numpy as np

from quadruped_dyn.math.rigid import Placement, axis_rotation
from quadruped_dyn.model import paper_robot
from quadruped_dyn.model.leg import LEG_LABELS
from tests.conftest import assert_close


def test_committed_urdf_is_reproducible():
    """Both copies (package data and the checkout's urdf/) are the generator's output."""
    assert len(paper_robot.URDF_COPIES) == 2, "a source checkout has the package's and urdf/'s copy"
    assert not paper_robot.stale_urdf_copies(), "differs from the generator: run `quadruped-dyn make-urdf`"


def test_frame0_is_a_rotation_not_the_papers_reflection():
    assert_close(paper_robot.R_B0.T @ paper_robot.R_B0, np.eye(3))
    assert np.linalg.det(paper_robot.R_B0) == 1.0
    x0, y0, z0 = paper_robot.R_B0.T  # columns
    assert_close(x0, [0, 1, 0]) and assert_close(y0, [1, 0, 0]) and assert_close(z0, [0, 0, -1])


def _joint_axes_in_trunk(label: str, q: np.ndarray) -> list[np.ndarray]:
    leg = paper_robot.dh_leg(label)
    T = Placement.identity()
    axes = []
    for joint, qi in zip(leg.joints, q):
        T = T @ joint.placement
        axes.append(T.R @ joint.axis)
        T = T @ Placement(axis_rotation(joint.axis, qi), np.zeros(3))
    return axes


def test_dh_pose_conventions():
    for label in LEG_LABELS:
        leg = paper_robot.dh_leg(label)
        hip = paper_robot.hip_position(label)
        # theta = 0: the leg points sideways, +y_b, fully stretched
        assert_close(leg.foot_position(np.zeros(3)) - hip, [0, paper_robot.PARAMS.l2 + paper_robot.PARAMS.l3, 0])
        # standing (90, 45, -90) deg: foot right under the hip
        foot = leg.foot_position(paper_robot.STANDING_Q) - hip
        assert_close(foot[:2], [0, 0]) and foot[2] < -0.2
        # knee forward of the hip at standing
        knee = leg.joints[0].placement @ Placement(axis_rotation([0, 0, 1], paper_robot.STANDING_Q[0]), np.zeros(3))
        knee = knee @ leg.joints[1].placement @ Placement(axis_rotation([0, 0, 1], paper_robot.STANDING_Q[1]), np.zeros(3))
        knee = knee @ leg.joints[2].placement
        assert knee.p[0] - hip[0] > 0.1
        # HAA axis parallel to x_b, HFE axis parallel to y_b (at theta_1 = 90 deg)
        haa, hfe, _ = _joint_axes_in_trunk(label, paper_robot.STANDING_Q)
        assert abs(abs(haa[0]) - 1) < 1e-12 and abs(abs(hfe[1]) - 1) < 1e-12


def test_total_mass_about_ten_kilograms():
    legs = sum(link.mass for link in paper_robot.link_inertias())
    assert abs(paper_robot.trunk_inertia().mass + 4 * legs - 10.0) < 1e-12
