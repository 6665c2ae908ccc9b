"""Canonical leg frames: the dynamics' cost and values do not depend on how a URDF writes its frames."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from quadruped_dyn.bench.call_cost import arithmetic_operations
from quadruped_dyn.dynamics.newton_euler import full_dynamics
from quadruped_dyn.math.rigid import LinkInertia, Placement
from quadruped_dyn.model.leg import Leg, LegJoint
from quadruped_dyn.model.leg_frames import axis_aligned
from quadruped_dyn.model.robot import Robot, load_robot
from quadruped_dyn.model.state import random_state, rotation
from quadruped_dyn.references.pinocchio import PinocchioReference
from tests.conftest import assert_close


def _random_rotation(rng: np.random.Generator) -> np.ndarray:
    Q, R = np.linalg.qr(rng.normal(size=(3, 3)))
    Q = Q @ np.diag(np.sign(np.diag(R)))
    return Q if np.linalg.det(Q) > 0 else -Q


def _inverse(T: Placement) -> Placement:
    return Placement(T.R.T, -T.R.T @ T.p)


def rewritten(leg: Leg, rng: np.random.Generator) -> Leg:
    """The same leg with each joint frame rotated at random (its axis and inertia follow) and the
    HFE and KFE origins slid along their axes: what another URDF of the same robot could write."""
    old = Placement.identity()  # new parent frame in the old parent frame
    joints, links = [], []
    for i, (joint, link) in enumerate(zip(leg.joints, leg.links)):
        new = Placement(_random_rotation(rng), rng.uniform(-0.1, 0.1) * joint.axis if i > 0 else np.zeros(3))
        joints.append(LegJoint(joint.name, _inverse(old) @ joint.placement @ new, new.R.T @ joint.axis, joint.lower, joint.upper))
        links.append(LinkInertia(link.mass, new.R.T @ (link.com - new.p), new.R.T @ link.inertia @ new.R))
        old = new
    return Leg(leg.label, tuple(joints), tuple(links), _inverse(old) @ leg.foot, leg.foot_frame)  # type: ignore[arg-type]


@pytest.fixture(scope="module", params=["solo12", "go2"])
def pair(request: pytest.FixtureRequest) -> tuple[Robot, Robot]:
    robot = load_robot(request.param)
    rng = np.random.default_rng(3)
    return robot, dataclasses.replace(robot, legs=tuple(rewritten(leg, rng) for leg in robot.legs))


def test_canonical_frames_are_axis_aligned(robot):
    for leg in robot.legs:
        canonical = axis_aligned(leg)
        for joint in canonical.joints:
            assert np.array_equal(joint.placement.R, np.eye(3)), joint.name
            assert sorted(np.abs(joint.axis)) == [0.0, 0.0, 1.0], f"{joint.name}: axis {joint.axis}"
        for joint in canonical.joints[1:]:
            assert joint.placement.p @ joint.axis == 0.0, f"{joint.name} origin not slid along its axis"
        assert np.array_equal(canonical.hip, leg.hip)
        for q in np.random.default_rng(0).uniform(-1.0, 1.0, size=(5, 3)):
            assert_close(canonical.foot_position(q), leg.foot_position(q), what=f"{leg.label} foot")


def test_rewritten_frames_give_the_same_canonical_leg(pair):
    robot, variant = pair
    for leg, other in zip(robot.legs, variant.legs):
        a, b = axis_aligned(leg), axis_aligned(other)
        for ja, jb, la, lb in zip(a.joints, b.joints, a.links, b.links):
            assert np.array_equal(ja.axis, jb.axis) and np.array_equal(jb.placement.R, np.eye(3))
            assert_close(jb.placement.p, ja.placement.p, what=ja.name)
            assert_close(lb.com, la.com, what=ja.name) and assert_close(lb.inertia, la.inertia, what=ja.name)
        assert_close(b.foot.p, a.foot.p, what=f"{leg.label} foot")


def test_rewritten_frames_same_cost_same_values(pair):
    """Operation counts equal the original's (to 1%: where two of a URDF's numbers are equal, e.g.
    solo12's links, CSE shares a few products, and the rewrite's round-off breaks such ties;
    without canonical frames, randomly rotated ones cost twice as much (go2: nle 1821 -> 3645)); values equal
    Pinocchio's on the original model."""
    robot, variant = pair
    fd, fv = full_dynamics(robot), full_dynamics(variant)
    for name in ("M_full_crba", "G_full_crb", "nle_full", "id_full", "C_full"):
        ours, theirs = arithmetic_operations(getattr(fd, name)), arithmetic_operations(getattr(fv, name))
        assert ours <= theirs <= 1.01 * ours, f"{name}: {theirs} operations in rewritten frames, {ours} as written"
    ref = PinocchioReference(robot)
    s = random_state(robot.lower, robot.upper, np.random.default_rng(5))
    assert_close(np.array(fv.M_full_crba(s.q)), ref.mass_matrix(s.q), what="M")
    assert_close(np.array(fv.G_full_crb(s.q)).ravel(), ref.gravity(s.q), what="G")
    assert_close(np.array(fv.nle_full(s.q, s.v)).ravel(), ref.nonlinear_effects(s.q, s.v), what="nle")
    R = rotation(s.q)
    expected = ref.rnea(s.q, s.v, s.a) - ref.contact_jacobian(s.q, (0, 1, 2, 3)).T @ np.concatenate([R @ f for f in s.f])
    w, tau = fv.id_full(s.q, s.v, s.a, s.f.ravel())
    assert_close(np.concatenate([np.array(w).ravel(), np.array(tau).ravel()]), expected, what="id")
