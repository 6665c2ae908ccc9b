"""The native runs (experiment/native_run.py: DOP853 and the right-hand sides in C) against the
Python path (scipy's DOP853 driving simulate_reduced / simulate_rigid): on a short horizon their
difference stays within NATIVE_TWIN_FACTOR times what one ulp of initial state makes in the Python
path, per robot; the C pose fit against numpy's Kabsch; and (slow) go2's walk in long double against the
exact IK plan."""

from __future__ import annotations

import ctypes
import subprocess

import numpy as np
import pytest

from quadruped_dyn.experiment.gait import TROT, WALK, gait_plan
from quadruped_dyn.experiment.native_run import PRECISIONS, SOURCE, NativeRuns, _structures, layout_checks_c
from quadruped_dyn.experiment.rigid_contact import initial_state, simulate_rigid
from quadruped_dyn.experiment.simulate import TorqueLaw, reduced_dynamics, simulate_reduced
from quadruped_dyn.experiment.torque_table import IkTorqueTable
from quadruped_dyn.experiment.trunk_pose import pose_from_feet
from quadruped_dyn.references.pinocchio import PinocchioReference
from quadruped_dyn.tolerances import EXTENDED_WALK_PCT, NATIVE_TWIN_FACTOR, POSE_FIT_TOL

HORIZON = 0.3  # s: two trot phases, one walk phase (a stance switch for the trot)
DT = 1e-3


def _within_twin_spread(python, twin, native):
    """Every signal of the native run within NATIVE_TWIN_FACTOR x the twin's difference."""
    assert native.stopped_at == python.stopped_at
    assert len(native.t) == len(python.t)
    np.testing.assert_array_equal(native.t, python.t)
    for s in ("q", "qd", "qdd"):
        spread = np.abs(getattr(twin, s) - getattr(python, s)).max()
        diff = np.abs(getattr(native, s) - getattr(python, s)).max()
        assert spread > 0 and np.isfinite(diff), (s, spread, diff)
        assert diff <= NATIVE_TWIN_FACTOR * spread, (s, diff, spread)


CASES = [("paper", TROT), ("paper", WALK), pytest.param("go2", WALK, marks=pytest.mark.slow),
         pytest.param("solo12", TROT, marks=pytest.mark.slow)]


@pytest.fixture(scope="module")
def setups():
    from quadruped_dyn.model.robot import load_robot

    made = {}

    def get(robot_name, gait):
        if (robot_name, gait.name) not in made:
            robot = load_robot(robot_name)
            plan = gait_plan(robot, gait)
            dyn = reduced_dynamics(robot, "c")
            made[robot_name, gait.name] = (plan, dyn, IkTorqueTable(plan, dyn), NativeRuns(robot))
        return made[robot_name, gait.name]

    return get


@pytest.mark.parametrize("robot_name, gait", CASES, ids=lambda x: getattr(x, "name", x))
def test_reduced_native_run_equals_the_python_run(setups, robot_name, gait):
    plan, dyn, table, native = setups(robot_name, gait)
    law = TorqueLaw("paper", roll_applied=True)
    python = simulate_reduced(plan, dyn, law, HORIZON, DT, ik=table)
    twin = simulate_reduced(plan, dyn, law, HORIZON, DT, ik=table, initial_ulps=1)
    run = native.reduced(plan, table, law, HORIZON, DT)
    assert run is not None
    _within_twin_spread(python, twin, run)
    np.testing.assert_allclose(run.closure_m, python.closure_m, rtol=0, atol=NATIVE_TWIN_FACTOR * 1e-14)


@pytest.mark.parametrize("robot_name, gait", CASES, ids=lambda x: getattr(x, "name", x))
def test_rigid_native_run_equals_the_python_run(setups, robot_name, gait):
    plan, _, table, native = setups(robot_name, gait)
    law = TorqueLaw("plus_1pct", scale=1.01)
    y0 = initial_state(plan, table, PinocchioReference(plan.robot))
    python = simulate_rigid(plan, table, law, HORIZON, DT)
    twin = simulate_rigid(plan, table, law, HORIZON, DT, initial=(np.nextafter(y0[:19], np.inf),
                                                                 np.nextafter(y0[19:], np.inf)))
    run = native.rigid(plan, table, law, HORIZON, DT)
    assert run is not None
    _within_twin_spread(python, twin, run)


def test_a_run_that_falls_stops_where_the_python_run_stops(setups):
    """The trot with the roll unactuated rolls over: both paths stop at the same sample."""
    plan, dyn, table, native = setups("paper", TROT)
    law = TorqueLaw("ik")
    python = simulate_reduced(plan, dyn, law, 0.6, DT, ik=table)
    run = native.reduced(plan, table, law, 0.6, DT)
    assert python.stopped_at is not None and run is not None
    assert abs(run.stopped_at - python.stopped_at) <= 2 * DT


def test_pose_fit_equals_kabsch(setups):
    """Three and four feet (Horn vs the SVD) and two feet with the roll (the closed form) on
    random rigid motions of the feet, with a small misfit."""
    _, _, _, native = setups("paper", TROT)
    rng = np.random.default_rng(1)
    for k in (2, 3, 4):
        for _ in range(20):
            r_b = rng.uniform(-0.4, 0.4, (k, 3)) + np.array([0.0, 0.0, -0.3])
            rpy = rng.uniform(-0.3, 0.3, 3)
            import pinocchio as pin

            R = pin.rpy.rpyToMatrix(*rpy)
            P = r_b @ R.T + rng.uniform(-1, 1, 3) + rng.normal(0, 1e-4, (k, 3)) * (k > 2)
            roll = float(rpy[0]) if k == 2 else None
            R0, p0, c0 = pose_from_feet(r_b, P, roll=roll, pitch_hint=float(rpy[1]))
            R1, p1, c1 = native.pose(r_b, P, roll=roll, pitch_hint=float(rpy[1]))
            assert np.abs(R1 - R0).max() <= POSE_FIT_TOL, (k, np.abs(R1 - R0).max())
            assert np.abs(p1 - p0).max() <= POSE_FIT_TOL and abs(c1 - c0) <= POSE_FIT_TOL
            assert np.abs(R1.T @ R1 - np.eye(3)).max() <= POSE_FIT_TOL and np.linalg.det(R1) > 0


#: DOP853's tolerance for the long-double run: ~1000 eps of long double (1.1e-19), where DOP853
#: still converges (go2's walk at 1e-17 is within 1.3e-8 % of the run at 1e-16).
EXTENDED_RTOL = 1e-16


@pytest.mark.slow
def test_long_double_walk_reaches_the_plan():
    """go2's walk (numeric IK) integrated in long double: the experiment has no systematic error
    above its double inputs' rounding -- not in the IK plan, the torque table, the pose fit,
    the projection, the landing or the comparison grid (docs/results.md: in double the walk stops
    at its integration's round-off, 4e-5 % in q). The target is the exact IK plan on the grid."""
    from quadruped_dyn.model.robot import load_robot

    robot = load_robot("go2")
    plan = gait_plan(robot, WALK)
    table = IkTorqueTable(plan, reduced_dynamics(robot, "c"))
    horizon = 2 * WALK.period
    run = NativeRuns(robot, "long double").reduced(plan, table, TorqueLaw("paper", roll_applied=True), horizon, DT,
                                                   rtol=EXTENDED_RTOL)
    assert run is not None and run.stopped_at is None and run.q.dtype == np.longdouble
    grid = np.arange(round(horizon / DT) + 1) * DT
    refs = [ref for ref, _ in table.exact_many(grid, [plan.stance(float(t)) for t in grid])]
    assert len(run.t) == len(grid)
    for s in ("q", "qd", "qdd"):
        ref = np.array([getattr(r, s + "_r")[:12] for r in refs])
        pct = np.abs(getattr(run, s)[:, :12].astype(float) - ref).max(axis=0) / np.abs(ref).max(axis=0) * 100
        assert np.all(np.isfinite(pct)) and pct.max() <= EXTENDED_WALK_PCT[s], (s, pct.max())


def test_an_unknown_precision_is_input_error():
    from quadruped_dyn.errors import InputError
    from quadruped_dyn.experiment.native_run import native_library
    from quadruped_dyn.model.robot import load_robot

    with pytest.raises(InputError, match="precision 'quad'"):
        native_library(load_robot("paper"), precision="quad")


@pytest.mark.parametrize("precision", list(PRECISIONS))
def test_structures_agree_with_c_and_a_disagreement_fails_the_build(tmp_path, precision):
    """c/qdx_native_run.c compiles with the check of its structures against ``_structures`` (every size and offset),
    and does not where the ctypes side differs (qdx_law with its int first)."""
    real = PRECISIONS[precision][0]

    def builds(structures: dict) -> subprocess.CompletedProcess:
        unit = tmp_path / "unit.c"
        unit.write_text(SOURCE.read_text() + layout_checks_c(structures))
        defines = ["-DQDX_LONG_DOUBLE"] if precision != "double" else []
        return subprocess.run(["cc", "-std=c99", "-fsyntax-only", *defines, str(unit)], capture_output=True, text=True)

    assert builds(_structures(real)).returncode == 0
    law = type("Law", (ctypes.Structure,), {"_fields_": [("roll_applied", ctypes.c_int), ("scale", real),
                                                          ("kp", real), ("kd", real)]})
    failed = builds({**_structures(real), "qdx_law": law})
    assert failed.returncode != 0 and "qdx_layout_qdx_law_scale" in failed.stderr
