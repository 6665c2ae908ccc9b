"""A ``control`` task's plant as the sweep builds it from a run's sample: a push lands once, at its stated time
of the run (after the settling, on the run's clock), and nowhere else."""

from __future__ import annotations

import numpy as np
import pytest

import quadruped_dyn.control  # noqa: F401  (sets MUJOCO_GL before MuJoCo is imported)

pytest.importorskip("mujoco", reason="MuJoCo is in the 'xlib' extra: pip install 'quadruped_dyn[xlib]'")

from quadruped_dyn.control.closed_loop import run_all  # noqa: E402
from quadruped_dyn.sweep.tasks import control_study  # noqa: E402

#: Before the settling ends (0.5 s): a push on a clock that restarts at each ``set_state`` lands in the settling too.
PUSH_AT_S = 0.1
#: A push's trace on the trunk that round-off cannot fake, AFTER_S after it: 1 mm (1 N s on the 10 kg paper robot
#: is 0.1 m/s, ~10 mm in 0.1 s were nothing to resist it).
MOVED_M = 1e-3
AFTER_S = 0.1
#: A box's placement from the sample: sums of lengths of ~1 m, to round-off.
PLACEMENT_TOL_M = 1e-12


def test_a_push_lands_once_at_its_time_of_the_run(paper):
    o = {"gait": "walk", "controller": "pd-diag", "cycles": 1, "run": 0}
    traces = []
    for sample in ({}, {"push_x_N_s": 1.0, "push_at_s": PUSH_AT_S}):
        study = run_all(control_study(paper, {**o, "perturbation": sample}))
        traces.append(study.traces["pd-diag"])
    still, pushed = traces
    assert still.fell_at is None and pushed.fell_at is None
    n = min(still.t.size, pushed.t.size)
    moved = np.abs(pushed.trunk_p[:n] - still.trunk_p[:n]).max(axis=1)
    assert np.isfinite(moved).all()
    # the same settled start (the settling was not pushed), the same run up to the push, then apart
    first = int(np.argmax(moved > 0))
    assert moved[first] > 0 and pushed.t[first] == pytest.approx(PUSH_AT_S + (still.t[1] - still.t[0]))
    later = first + int(round(AFTER_S / (still.t[1] - still.t[0])))
    assert pushed.trunk_p[later, 0] - still.trunk_p[later, 0] > MOVED_M  # along the push (+x)


def test_a_sampled_ground_step_is_in_the_plant(paper):
    o = {"gait": "walk", "controller": "pd-diag", "cycles": 1, "run": 0,
         "perturbation": {"step_x_m": 0.3, "step_height_m": 0.02, "mass_scale": 1.1}}
    plant = control_study(paper, o).plant
    box = plant.model.geom("quadruped_dyn_step")
    assert plant.options.ground_step == (0.3, 0.02)
    assert box.pos[0] - box.size[0] == pytest.approx(0.3, abs=PLACEMENT_TOL_M)  # the edge at x = 0.3 m
    assert box.pos[2] + box.size[2] == pytest.approx(plant.floor_z + 0.02, abs=PLACEMENT_TOL_M)  # the top 2 cm up
