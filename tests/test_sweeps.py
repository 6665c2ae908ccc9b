"""Long sweeps (marked slow; `./run test --slow`): the full check on every built-in robot,
with the sample count the acceptance criteria name."""

from __future__ import annotations

import pytest

from quadruped_dyn.checks.terms import run_check


@pytest.mark.slow
def test_check_200_samples(robot):
    report = run_check(robot, samples=200, seed=0)
    assert report.passed, report.table()
