"""Finite nonsense is not an answer, and the Python API takes only what it can use.

At collinear stance feet the GRF system loses rank and the symbolic reduced model returns finite
values of ~1e15; with two front feet at zero pitch and roll the stance's regularity is 0 (M_r has
cond ~1e19): every numeric call of the reduced model reports it (NumericalError naming the cause). Arguments of the wrong kind
(complex, strings, None, lists for names, an __array__ that raises, absurd mu) are InputErrors."""

from __future__ import annotations

import re

import numpy as np
import pytest
from scipy.optimize import least_squares

from quadruped_dyn.dynamics.derivatives import full_derivatives, grf_derivatives, reduced_derivatives
from quadruped_dyn.dynamics.grf import grf_solve
from quadruped_dyn.dynamics.guarded import guarded_call
from quadruped_dyn.dynamics.newton_euler import full_dynamics
from quadruped_dyn.dynamics.reduced import reduced_model, solve_forward_dynamics
from quadruped_dyn.errors import InputError, NumericalError
from quadruped_dyn.model.stance import StanceSet, stance_set
from quadruped_dyn.model.state import full_q
from quadruped_dyn.references.pinocchio import PinocchioReference
from quadruped_dyn.tolerances import TRUNK_PITCH_DEG_MARGIN

QUAT = np.array([0.0, 0.0, 0.0, 1.0])


def _collinear_joints(robot, moved: int, line: tuple[int, int]) -> np.ndarray:
    """Standing joints with leg ``moved``'s foot put (by Pinocchio IK) on the line through the
    feet of legs ``line``, midway: three collinear stance feet."""
    ref = PinocchioReference(robot)

    def feet(j: np.ndarray) -> np.ndarray:
        return ref.foot_positions(full_q(np.eye(3), np.zeros(3), j))

    j0 = robot.standing_q.copy()
    target = feet(j0)[list(line)].mean(axis=0)

    def residual(x: np.ndarray) -> np.ndarray:
        j = j0.copy()
        j[3 * moved : 3 * moved + 3] = x
        return feet(j)[moved] - target

    x = least_squares(residual, j0[3 * moved : 3 * moved + 3], xtol=1e-15, ftol=1e-15, gtol=1e-15).x
    j = j0.copy()
    j[3 * moved : 3 * moved + 3] = x
    assert np.linalg.norm(residual(x)) < 1e-8
    return j


@pytest.mark.parametrize(("stance", "moved", "line"), [("FL+FR+BL", 1, (0, 2)), ("FR+BL+BR", 2, (1, 3))])
def test_collinear_stance_feet_are_reported_by_every_numeric_call(paper, stance, moved, line):
    j = _collinear_joints(paper, moved, line)
    m = reduced_model(paper, stance)
    z = np.zeros(12)
    calls = {"id_r": lambda: m.id_r(j, z, z, QUAT), "guarded id_r": lambda: guarded_call(m.id_r, j, z, z, QUAT),
             "M_r": lambda: m.M_r(j, QUAT), "M_r_ad": lambda: m.M_r_ad(j, QUAT), "C_r": lambda: m.C_r(j, z, QUAT),
             "G_r": lambda: m.G_r(j, QUAT), "fd_r": lambda: m.fd_r(j, z, z, QUAT), "maps": lambda: m.maps(j, z, z, QUAT),
             "forward_dynamics": lambda: m.forward_dynamics(j, z, z, QUAT),
             "by name": lambda: m.id_r(q_r=j, qd_r=z, qdd_r=z, quat=QUAT),
             "GRF solve": lambda: grf_solve(paper, stance).solve(np.r_[np.zeros(3), QUAT, j], np.zeros(18), np.zeros(18))}
    for what, call in calls.items():
        rank = re.escape(f"stance {stance}: the body equations have rank ") + ".* coincident or collinear"
        with pytest.raises(NumericalError, match=rank):
            call()
            pytest.fail(f"{what} returned at collinear stance feet")
    tau = m.id_r(paper.standing_q, z, z, QUAT)  # regular next door: still an answer
    assert np.all(np.isfinite(np.asarray(tau)))


def test_a_degenerate_pair_is_reported_by_every_numeric_call(paper):
    """Two front feet, zero pitch and roll: the roll axis is perpendicular to the feet's line, so the
    roll row cannot fix the rotation about it (M_r has cond ~1e19): the stance's regularity is 0."""
    m = reduced_model(paper, "FL+FR")
    q = np.r_[paper.standing_q, 0.0]
    z = np.zeros(13)
    for call in (lambda: m.fd_r(q, z, z, QUAT), lambda: guarded_call(m.fd_r, q, z, z, QUAT),
                 lambda: m.forward_dynamics(q, z, z, QUAT), lambda: m.id_r(q, z, z, QUAT), lambda: m.M_r(q, QUAT),
                 lambda: m.G_r(q, QUAT)):
        with pytest.raises(NumericalError, match="stance FL\\+FR is degenerate here .* perpendicular to the roll axis"):
            call()
    diagonal = reduced_model(paper, "FL+BR")  # the trot's pair at the same posture: regular
    assert np.all(np.isfinite(np.asarray(diagonal.fd_r(q, z, z, QUAT))))


def test_a_singular_M_r_is_reported_by_fd_r():
    """fd_r's solve (``solve_forward_dynamics``, the one numeric definition) refuses an M_r of
    condition number beyond MAX_COND_M_R. (No regular state of a built-in robot is known to reach it
    since the trunk pitched near 90 deg is degenerate for two feet: a regularity just above
    REGULARITY_MIN means cond(M_r) ~ 1 / sqrt(regularity) ~ 1e9.)"""
    M = np.diag([1.0] * 12 + [1e-14])
    with pytest.raises(NumericalError, match="M_r of FL\\+BR has condition number .*e\\+1[2-9]"):
        solve_forward_dynamics(stance_set("FL+BR"), M, np.ones(13))


def test_two_feet_with_the_trunk_pitched_near_90_deg_are_degenerate(paper):
    """Within TRUNK_PITCH_DEG_MARGIN of a 90 deg pitch every numeric call of a two-feet model raises,
    naming the pitch (the generated forms' error grows as eps / cos(pitch)^3: docs/reliability.md §7)."""
    m = reduced_model(paper, "FL+BR")
    q, z = np.r_[paper.standing_q, 0.0], np.zeros(13)
    for margin in (1e-13, np.radians(TRUNK_PITCH_DEG_MARGIN) - 1e-3):
        pitched = np.array([0.0, np.sin((np.pi / 2 - margin) / 2), 0.0, np.cos((np.pi / 2 - margin) / 2)])
        for call in (m.id_r, m.fd_r):
            with pytest.raises(NumericalError, match="pitched within 2.0 deg of 90 deg"):
                call(q, z, z, pitched)
    outside = np.radians(TRUNK_PITCH_DEG_MARGIN) + 1e-3
    pitched = np.array([0.0, np.sin((np.pi / 2 - outside) / 2), 0.0, np.cos((np.pi / 2 - outside) / 2)])
    assert np.all(np.isfinite(np.asarray(m.fd_r(q, z, z, pitched))))


class _Raises:
    def __array__(self, *args, **kwargs):
        raise RuntimeError("cannot convert")


def test_api_type_confusion_is_input_error(paper):
    q = np.r_[np.zeros(3), QUAT, paper.standing_q]
    v = np.zeros(18)
    solve = grf_solve(paper, "FL+FR+BL+BR")
    bad = {
        "complex q": lambda: solve.solve(q + 1j, v, v),
        "complex q, zero imaginary": lambda: solve.solve(q.astype(complex), v, v),
        "string q": lambda: solve.solve("q", v, v),
        "object q": lambda: solve.solve([None] * 19, v, v),
        "__array__ raises": lambda: solve.solve(_Raises(), v, v),
        "mu string": lambda: solve.solve(q, v, v, mu="0.6"),
        "mu bool": lambda: solve.solve(q, v, v, mu=True),
        "mu 1e308": lambda: solve.solve(q, v, v, mu=1e308),
        "mu list": lambda: solve.solve(q, v, v, mu=[0.6]),
        "mu negative": lambda: solve.solve(q, v, v, mu=-0.1),
        "stance None": lambda: grf_solve(paper, None),
        "stance list": lambda: grf_solve(paper, ["FL"]),
        "stance int": lambda: grf_solve(paper, 3),
        "StanceSet foot 7": lambda: grf_solve(paper, StanceSet((0, 0, 7))),  # was an IndexError
        "StanceSet unsorted": lambda: grf_solve(paper, StanceSet((3, 0))),  # was a KeyError
        "model None": lambda: grf_solve(paper, "FL+FR", None),
        "robot name": lambda: grf_solve("paper", "FL+FR"),
        "reduced list": lambda: reduced_model(paper, ["FL"]),
        "reduced None": lambda: reduced_model(paper, None),
        "reduced one foot": lambda: reduced_model(paper, "FL"),
        "reduced robot None": lambda: reduced_model(None, "FL+FR"),
        # the cached builders check before the cache hashes (a list: TypeError) or the build reads (a str: AttributeError)
        "full_dynamics name": lambda: full_dynamics("paper"),
        "full_dynamics list": lambda: full_dynamics([paper]),
        "full_derivatives name": lambda: full_derivatives("paper"),
        "reduced_derivatives name": lambda: reduced_derivatives("paper", "FL+BR"),
        "reduced_derivatives list": lambda: reduced_derivatives(paper, ["FL", "BR"]),
        "grf_derivatives list": lambda: grf_derivatives(paper, ["FL", "BR"]),
        "id_r complex": lambda: reduced_model(paper, "FL+FR+BL+BR").id_r(paper.standing_q + 0j, np.zeros(12),
                                                                          np.zeros(12), QUAT),
        "M_r __array__": lambda: reduced_model(paper, "FL+FR+BL+BR").M_r(_Raises(), QUAT),
    }
    for what, call in bad.items():
        with pytest.raises(InputError):
            call()
            pytest.fail(f"{what}: no InputError")
    ok = solve.solve(q, v, v, mu=np.float64(0.6))
    assert ok.in_friction_cone is not None and np.all(np.isfinite(ok.friction_margin))
    assert np.all(np.isfinite(solve.solve(q, v, v, mu=1000).friction_margin))
