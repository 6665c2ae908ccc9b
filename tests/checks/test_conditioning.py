"""Tolerances of terms through M's solve scale with cond(M) (tolerances.derivative_tolerance): a legal but
ill-conditioned robot passes its own check, an injected error still fails it, the built-in robots keep theirs."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

from quadruped_dyn.checks.terms import DFD_FULL_TERMS, CheckReport, TermResult, _derivative_comparisons
from quadruped_dyn.errors import UrdfWarning
from quadruped_dyn.math.compare import scale_of
from quadruped_dyn.model.registry import ROBOT_NAMES
from quadruped_dyn.model.robot import load_robot
from quadruped_dyn.model.state import random_state
from quadruped_dyn.references.pinocchio import PinocchioReference
from quadruped_dyn.tolerances import REL_TOL_DERIVATIVES, derivative_tolerance
from tests.model.test_physical_range import paper_variant, shank


@pytest.mark.parametrize("name", ROBOT_NAMES)
def test_built_in_robots_keep_their_tolerance(name):
    """Every built-in robot's cond(M) at random states leaves its derivatives' tolerance at REL_TOL_DERIVATIVES."""
    robot = load_robot(name)
    data = robot.model.createData()
    rng = np.random.default_rng(1)
    for _ in range(60):
        q = random_state(robot.lower, robot.upper, rng).q
        M = pin.crba(robot.model, data, q)
        cond = float(np.linalg.cond(np.triu(M) + np.triu(M, 1).T))
        assert cond < 1e5
        for term in (*DFD_FULL_TERMS, "did_full dtau_dq"):
            assert derivative_tolerance(term, cond) == REL_TOL_DERIVATIVES


@pytest.fixture(scope="module")
def ill_conditioned(tmp_path_factory):
    """The paper robot with its FL shank's inertia x1e9: legal (warned), cond(M) ~1e9 (every library agrees)."""
    path = paper_variant(tmp_path_factory.mktemp("ill"), shank(scale_inertia=1e9), "ill_conditioned.urdf")
    with pytest.warns(UrdfWarning, match="radius of gyration"):
        return load_robot(str(path), cached=False)


def _dfd_terms(robot, inject: str | None = None, factor: float = 1.0, scaled: bool = True) -> list[TermResult]:
    """dfd_full against Pinocchio at 3 random states, as the check compares them; ``inject``: that term off by
    ``factor`` x its scaled tolerance (relative to the reference's largest entry), or x ``factor`` if negative."""
    ref, rng = PinocchioReference(robot), np.random.default_rng(0)
    terms = {name: TermResult(name, tol=REL_TOL_DERIVATIVES) for name in DFD_FULL_TERMS}
    for _ in range(3):
        s = random_state(robot.lower, robot.upper, rng)
        cond = float(np.linalg.cond(ref.mass_matrix(s.q)))
        for name, ours, theirs in _derivative_comparisons(robot, ref, s, rng):
            if name not in terms:
                continue
            tol = derivative_tolerance(name, cond) if scaled else REL_TOL_DERIVATIVES
            ours = np.asarray(ours, dtype=float)
            if name == inject:
                ours = ours * -factor if factor < 0 else ours + factor * tol * scale_of(theirs) * np.sign(theirs + 0.5)
            terms[name].add(ours, theirs, tol, cond)
    return list(terms.values())


def test_ill_conditioned_robot_passes_with_scaled_tolerances_and_says_so(ill_conditioned):
    terms = _dfd_terms(ill_conditioned)
    assert all(t.passed for t in terms), [(t.name, t.max_rel_err, t.tol) for t in terms]
    assert all(t.model_limited_cond > 1e8 for t in terms)
    table = CheckReport("ill", 3, 0, terms=terms).table()
    assert "pass (accuracy limited by the model: cond(M) up to" in table
    # the unscaled tolerance fails on this robot: what the scaling is for
    assert not all(t.passed for t in _dfd_terms(ill_conditioned, scaled=False))


@pytest.mark.parametrize("term", DFD_FULL_TERMS)
@pytest.mark.parametrize("factor", [10.0, -10.0])
def test_an_injected_error_still_fails_on_the_ill_conditioned_robot(ill_conditioned, term, factor):
    """An error 10x the scaled tolerance, or the term 10x its value, fails the check."""
    results = {t.name: t for t in _dfd_terms(ill_conditioned, inject=term, factor=factor)}
    assert not results[term].passed
    assert all(t.passed for name, t in results.items() if name != term)


def test_an_error_fails_on_a_built_in_robot_at_the_unscaled_tolerance(paper):
    results = {t.name: t for t in _dfd_terms(paper, inject="dfd_full da_dv", factor=10.0)}
    assert results["dfd_full da_dv"].tol == REL_TOL_DERIVATIVES and not results["dfd_full da_dv"].passed
    assert results["dfd_full da_dq"].passed and results["dfd_full da_dq"].model_limited_cond == 0.0
