"""Leg templates (codegen/forms/leg_template.py) and did_full composed of them (codegen/forms/did_full_pieces.py)
against the closed-form algorithm (dynamics/rnea_derivatives.py) and CasADi's Jacobian of the whole rnea."""

from __future__ import annotations

import dataclasses

import casadi as ca
import numpy as np
import pytest

from quadruped_dyn.codegen.forms.did_full_pieces import did_full_by_leg, did_full_pieces
from quadruped_dyn.codegen.forms.leg_template import leg_templates
from quadruped_dyn.dynamics.derivatives import full_derivatives
from quadruped_dyn.model.leg import LegJoint
from quadruped_dyn.model.leg_frames import axis_aligned
from quadruped_dyn.model.registry import ROBOT_NAMES
from quadruped_dyn.model.robot import load_robot
from quadruped_dyn.model.state import NQ_FULL, NV_FULL, random_state
from quadruped_dyn.tolerances import REL_TOL_DERIVATIVES
from tests.conftest import assert_close


def _numeric(x: object, p: ca.SX, values: np.ndarray) -> np.ndarray:
    """A template field with one leg's parameters put in."""
    if isinstance(x, ca.SX):
        return ca.evalf(ca.substitute(x, p, ca.DM(values))).full().squeeze()
    return np.asarray(x, dtype=float)


@pytest.mark.parametrize("name", ROBOT_NAMES)
def test_each_legs_parameters_give_back_its_canonical_leg(name):
    """Every number of every canonical leg, exactly: the template's constants where the legs agree, its
    parameters with that leg's values where they differ, its axes times the leg's signs."""
    robot = load_robot(name)
    templates = leg_templates(robot)
    assert sorted(k for t in templates for k in t.legs) == [0, 1, 2, 3]
    for t in templates:
        assert t.values.shape == (len(t.legs), t.p.numel())
        for row, sigma, k in zip(t.values, t.signs, t.legs):
            leg = axis_aligned(robot.legs[k])
            for mine, theirs, s in zip(t.leg.joints, leg.joints, sigma):
                assert s in (1.0, -1.0) and np.array_equal(s * mine.axis, theirs.axis)
                assert np.array_equal(_numeric(mine.placement.p, t.p, row), theirs.placement.p)
            for mine, theirs in zip(t.leg.links, leg.links):
                assert float(_numeric(mine.mass, t.p, row)) == theirs.mass
                assert np.array_equal(_numeric(mine.com, t.p, row), theirs.com)
                assert np.array_equal(_numeric(mine.inertia, t.p, row), theirs.inertia)
            assert np.array_equal(_numeric(t.leg.foot.p, t.p, row), leg.foot.p)


def test_the_paper_robots_legs_share_one_template_with_two_parameters():
    """Its legs differ only in the hip's position (x and y signs): one piece of code for the four."""
    (t,) = leg_templates(load_robot("paper"))
    assert t.legs == (0, 1, 2, 3) and t.p.numel() == 2


def turned_robot():
    """The paper robot with FL's hip axis reversed (the others' template at -q: a sign) and FR's knee turning about x
    (a template of its own): every path of the templates."""
    paper = load_robot("paper")
    fl, fr = paper.legs[0], paper.legs[1]
    hip, knee = fl.joints[0], fr.joints[2]
    fl = dataclasses.replace(fl, joints=(LegJoint(hip.name, hip.placement, -hip.axis, -hip.upper, -hip.lower), *fl.joints[1:]))
    fr = dataclasses.replace(fr, joints=(*fr.joints[:2], LegJoint(knee.name, knee.placement, np.array([1.0, 0.0, 0.0]),
                                                                     knee.lower, knee.upper)))
    return dataclasses.replace(paper, legs=(fl, fr, *paper.legs[2:]))


def _did_full_by_leg(robot) -> ca.Function:
    q, v, a = ca.SX.sym("q", NQ_FULL), ca.SX.sym("v", NV_FULL), ca.SX.sym("a", NV_FULL)
    return ca.Function("did_full_by_leg", [q, v, a], list(did_full_by_leg(robot, q, v, a)))


def _check_did_full_by_leg(robot, seeds=(0, 1)) -> None:
    """did_full composed of the templates' pieces equals the closed form over the robot's own legs
    (``full_derivatives().did_full``) and CasADi's Jacobian of the whole rnea (``did_full_ad``): the same sparsity
    (the generated C's) and the same values."""
    d, by_leg = full_derivatives(robot), _did_full_by_leg(robot)
    assert all(by_leg.sparsity_out(k) == d.did_full.sparsity_out(k) for k in range(3))
    for seed in seeds:
        s = random_state(robot.lower, robot.upper, np.random.default_rng(seed))
        for k, (ours, closed, literal) in enumerate(zip(by_leg(s.q, s.v, s.a), d.did_full(s.q, s.v, s.a),
                                                        d.did_full_ad(s.q, s.v, s.a))):
            name = f"{robot.name} did_full by leg output {k}"
            assert_close(np.array(ours), np.array(closed), REL_TOL_DERIVATIVES, name + " vs the closed form")
            assert_close(np.array(ours), np.array(literal), REL_TOL_DERIVATIVES, name + " vs did_full_ad")


@pytest.mark.parametrize("name", [n if n == "paper" else pytest.param(n, marks=pytest.mark.slow) for n in ROBOT_NAMES])
def test_did_full_by_leg_equals_the_closed_form_and_the_jacobian(name):
    """Every built-in robot (the paper robot by default; two templates and a sign: the turned robot's test)."""
    _check_did_full_by_leg(load_robot(name))


def test_legs_with_other_axes_get_their_own_template_and_did_full_is_unchanged():
    """A leg whose knee turns about another axis cannot share the others' code: it gets a template of its own; a leg
    whose hip turns the other way shares it at -q. did_full composed of them still equals the closed form and
    CasADi's Jacobian of the whole rnea (did_full_ad)."""
    robot = turned_robot()
    pieces = did_full_pieces(robot)
    assert [t.legs for t in pieces.templates] == [(0, 2, 3), (1,)] and pieces.template_of == (0, 1, 0, 0)
    assert [pieces.leg_signs(k)[0] for k in (0, 2, 3)] == [1.0, -1.0, -1.0]
    _check_did_full_by_leg(robot)
