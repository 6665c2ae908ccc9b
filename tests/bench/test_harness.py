"""The Pinocchio benchmark harness times the pin wheel's compiled algorithms (bench/harnesses.py)."""

from __future__ import annotations

import re
import shutil
import subprocess

import pytest

#: Algorithms the harness times (and their conventions' implementations, e.g. crbaLocalConvention); each must be
#: the wheel's explicit instantiation (an undefined symbol of the harness, resolved from libpinocchio_default),
#: not a copy compiled into the harness.
TIMED = ("crba", "rnea", "nonLinearEffects", "computeGeneralizedGravity", "aba", "computeRNEADerivatives",
         "computeABADerivatives", "constraintDynamics", "computeConstraintDynamicsDerivatives")
ALGORITHM = re.compile(r"pinocchio::(?:impl::)?(" + "|".join(TIMED) + r")\w*<")


@pytest.mark.slow
@pytest.mark.skipif(shutil.which("nm") is None, reason="needs binutils' nm")
def test_the_harness_calls_the_wheels_algorithms():
    from quadruped_dyn.bench.timing import pinocchio_harness

    symbols = subprocess.run(["nm", "-C", str(pinocchio_harness())], capture_output=True, text=True, check=True).stdout
    defined, undefined = set(), set()
    for line in symbols.splitlines():
        kind = line[17:18]  # nm: 16-digit address (or blanks), a space, the symbol type
        for name in set(ALGORITHM.findall(line)):
            (undefined if kind == "U" else defined).add(name)
    assert not defined, f"compiled into the harness instead of taken from the wheel: {sorted(defined)}"
    assert set(TIMED) <= undefined, f"not called at all: {sorted(set(TIMED) - undefined)}"
