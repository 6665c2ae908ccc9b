"""The full solves (``optimize``'s defaults) on paper, solo12 and go2: the trot converges and,
replayed open loop in the rigid-contact dynamics, stays within 1 % of its own plan for a full
cycle; the static walk converges, keeps today's walk's feasibility (checked with Pinocchio's own
GRF and CoM) and needs less torque effort than today's plan. Slow: about a minute each on a quiet
machine (docs/optimal_control.md)."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

from quadruped_dyn.experiment.gait import TROT, WALK
from quadruped_dyn.model.robot import load_robot
from quadruped_dyn.model.stance import StanceSet
from quadruped_dyn.model.state import rotation
from quadruped_dyn.optimal_control.node import trunk_quaternion
from quadruped_dyn.optimal_control.replay import replay_rigid
from quadruped_dyn.optimal_control.solve import solve
from quadruped_dyn.optimal_control.trajectory_files import plan_effort
from quadruped_dyn.optimal_control.transcription import MIN_COM_MARGIN_M, Options, transcribe

ROBOTS = ("paper", "solo12", "go2")

#: Pinocchio's SVD GRF and the transcription's are different derivations of the same forces:
#: they agree to round-off, far below a Newton of margin (N); the CoM likewise (m).
FZ_TOL_N = 1e-6
COM_TOL_M = 1e-9

pytestmark = pytest.mark.slow


@pytest.mark.parametrize("name", ROBOTS)
def test_trot_converges_and_replays_a_full_cycle(name: str) -> None:
    sol = solve(transcribe(load_robot(name), TROT))
    assert sol.converged, (sol.status, sol.constraint_violation)
    replay = replay_rigid(sol, cycles=2.0)
    assert replay.run.stopped_at is None
    assert replay.time_to_1pct_s is None or replay.time_to_1pct_s >= TROT.period, replay.summary()
    assert np.all(np.isfinite(replay.departure_rad)) and replay.departure_rad.size > 0


@pytest.mark.parametrize("name", ROBOTS)
def test_walk_keeps_feasibility_with_less_effort(name: str) -> None:
    from quadruped_dyn.references.pinocchio import PinocchioReference

    robot = load_robot(name)
    options = Options()
    sol = solve(transcribe(robot, WALK, options))
    assert sol.converged, (sol.status, sol.constraint_violation)
    tr = sol.transcription
    X, Xd, Xdd, H = tr.unpack(sol.w)
    ref = PinocchioReference(robot)
    fz_min = options.fz_min_fraction * robot.total_mass * 9.81
    holds = np.array([tr.plan.foot(i, 0.0)[0][:2] for i in range(4)]) + H.T
    for k in range(tr.n_nodes):
        x = X[:, k]
        quat = trunk_quaternion(x[12:15])
        for p in tr.phase_of(k):
            stance = WALK.phases[p]
            q, v, a = ref.reduced_motion(stance, x[:12], Xd[:12, k], Xdd[:12, k], quat)
            f_world = ref.grf_solve(q, v, a, stance, StanceSet(stance).selection("paper")).f_b @ rotation(q).T
            assert np.all(np.isfinite(f_world)) and f_world[:, 2].min() >= fz_min - FZ_TOL_N, (k, stance)
            q_world = q.copy()
            q_world[:3] = x[15:18]
            com = pin.centerOfMass(ref.model, ref.data, q_world)[:2]
            if k == 0 and p != 0:  # the last phase ends at node K: node 0 moved forward one step
                com = com + np.array([tr.speed * WALK.period, 0.0])
            tri = []
            for i in stance:  # the foothold of foot i in this phase (moved forward once it has stepped)
                step = tr.speed * WALK.period if p > WALK.swing_phase(i) else 0.0
                tri.append(holds[i] + np.array([step, 0.0]))
            tri = np.array(tri)
            margins = []
            for a_, b_, c_ in ((0, 1, 2), (1, 2, 0), (2, 0, 1)):
                e = tri[b_] - tri[a_]
                n = np.array([-e[1], e[0]]) / np.linalg.norm(e)
                n *= np.sign(n @ (tri[c_] - tri[a_]))
                margins.append(n @ (com - tri[a_]))
            assert min(margins) >= MIN_COM_MARGIN_M - COM_TOL_M, (k, stance, margins)
    effort = plan_effort(sol)
    assert effort["ratio"] < 1.0, effort
