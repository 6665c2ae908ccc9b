"""A sweep file's perturbation ranges are checked against the plant's own limits, without importing MuJoCo."""

from __future__ import annotations

import subprocess
import sys

import pytest

from quadruped_dyn.control.plant import PlantOptions
from quadruped_dyn.errors import InputError
from quadruped_dyn.sweep.sampling import BOUNDS

#: A step this much past a bound (relative) is outside it
PAST = 1e-9


def test_ground_step_bounds_are_the_plants():
    """A ground step at each of the sweep's bounds is accepted by the plant, one just past any bound refused."""
    (x_lo, x_hi), (h_lo, h_hi) = BOUNDS["step_x_m"], BOUNDS["step_height_m"]
    for step in ((x_lo, h_lo), (x_hi, h_hi)):
        PlantOptions(ground_step=step).validate()
    for step in ((x_lo * (1 + PAST), 0.0), (x_hi * (1 + PAST), 0.0), (0.0, h_lo * (1 + PAST)), (0.0, h_hi * (1 + PAST))):
        with pytest.raises(InputError, match="ground step"):
            PlantOptions(ground_step=step).validate()


def test_bounds_need_no_mujoco():
    done = subprocess.run([sys.executable, "-c", "import sys, quadruped_dyn.sweep.sampling as s; "
                           "assert s.BOUNDS and 'mujoco' not in sys.modules, sorted(sys.modules)"],
                          capture_output=True, text=True, check=False)
    assert done.returncode == 0, done.stderr[-2000:]
