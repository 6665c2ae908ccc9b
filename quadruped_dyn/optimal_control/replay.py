"""The optimised gait as a trajectory in time, and its torques replayed open loop in the
rigid-contact physics check (``experiment.rigid_contact``: Pinocchio's free-flyer model, stance feet
as rigid point contacts, nothing of the paper's model).

The motion between nodes is the quintic Hermite interpolant (``hermite``), repeated cycle after
cycle (each cycle moved forward by speed x period). The torques replayed are the reduced inverse
dynamics of that motion, tau(t) = id_r(stance(t), x(t), xd(t), xdd(t)) -- at the collocation points
exactly the optimiser's; between them the roll moment the interpolant would need is the
transcription's defect (reported as ``max_roll_defect_Nm``, sampled on the replay grid).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from quadruped_dyn.arguments import real_number
from quadruped_dyn.errors import InputError
from quadruped_dyn.experiment.paper_experiment import DEPARTURE_PCT, departure, growth_rate
from quadruped_dyn.experiment.plan_ik import IkTarget
from quadruped_dyn.experiment.rigid_contact import simulate_rigid
from quadruped_dyn.experiment.simulate import Run, TorqueLaw, check_times
from quadruped_dyn.optimal_control.hermite import interpolate
from quadruped_dyn.optimal_control.node import N_X, node_functions, trunk_quaternion
from quadruped_dyn.optimal_control.solve import Solution
from quadruped_dyn.references.pinocchio import PinocchioReference

#: Sampling interval of the replay's output, s.
REPLAY_DT = 2e-3


@dataclass
class OptimizedTrajectory:
    """x(t), xd(t), xdd(t) (18,) of a solution, for any t >= 0, and the torques along it."""

    solution: Solution

    def __post_init__(self) -> None:
        tr = self.solution.transcription
        self.X, self.Xd, self.Xdd, self.footholds = tr.unpack(self.solution.w)
        self.period, self.h, self.K = tr.gait.period, tr.h, tr.n_nodes
        self.shift = tr.speed * tr.gait.period
        self.functions = node_functions(tr.robot, tr.gait.phases)
        self.gait = tr.gait

    def _node(self, k: int, cycle: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        c, j = cycle + k // self.K, k % self.K
        x = self.X[:, j].copy()
        x[15] += c * self.shift
        return x, self.Xd[:, j], self.Xdd[:, j]

    def state(self, t: float, stance: tuple[int, ...] | None = None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(x, xd, xdd) at t; at a node on a phase switch, ``stance`` picks the side (no matter: C^2)."""
        cycle = int(np.floor(t / self.period + 1e-12))
        local = t - cycle * self.period
        k = min(int(np.floor(local / self.h + 1e-9)), self.K - 1)
        s = (local - k * self.h) / self.h
        y = interpolate(self._node(k, cycle), self._node(k + 1, cycle), float(np.clip(s, 0.0, 1.0)), self.h)
        return tuple(np.asarray(v, dtype=float) for v in y)  # type: ignore[return-value]

    def torques(self, t: float, stance: tuple[int, ...]) -> tuple[np.ndarray, float]:
        """(tau (12,), roll moment (N m)) of the reduced inverse dynamics of stance at t."""
        x, xd, xdd = self.state(t)
        tau, roll, _ = self.functions.dynamics[stance](x, xd, xdd)
        return np.asarray(tau).ravel(), float(roll)

    def target(self, t: float, stance: tuple[int, ...]) -> IkTarget:
        x, xd, xdd = self.state(t)
        n = self.gait.n_coords
        return IkTarget(x[:n], xd[:n], xdd[:n], stance)


class _OptimizedTorques:
    """The ``IkTorques`` interface of ``simulate_rigid``: (target at t, torques (n,))."""

    def __init__(self, trajectory: OptimizedTrajectory) -> None:
        self.trajectory = trajectory
        self.max_roll = 0.0

    def __call__(self, t: float, stance: tuple[int, ...]) -> tuple[IkTarget, np.ndarray]:
        tau, roll = self.trajectory.torques(t, stance)
        self.max_roll = max(self.max_roll, abs(roll))
        target = self.trajectory.target(t, stance)
        return target, np.append(tau, np.zeros(target.q_r.size - 12))


@dataclass
class Replay:
    run: Run
    target_q: np.ndarray  # (N, 12) the optimised joint angles on run.t
    departure_rad: np.ndarray  # (N,) largest joint-angle difference, rad
    time_to_1pct_s: float | None
    growth_rate_per_s: float | None
    max_roll_defect_Nm: float
    horizon_s: float
    threshold_rad: float  # DEPARTURE_PCT % of the largest |optimised joint angle|

    def summary(self) -> dict[str, Any]:
        return {"horizon_s": self.horizon_s, "time_to_1pct_s": self.time_to_1pct_s,
                "growth_rate_per_s": self.growth_rate_per_s, "stopped_at_s": self.run.stopped_at,
                "max_joint_angle_diff_rad": float(self.departure_rad.max()) if self.departure_rad.size else None,
                "departure_threshold_rad": self.threshold_rad, "max_roll_defect_Nm": self.max_roll_defect_Nm,
                "departure_threshold_pct_of_max_joint_angle": DEPARTURE_PCT}


def replay_rigid(solution: Solution, cycles: float = 2.0, dt: float = REPLAY_DT) -> Replay:
    """The optimised torques, open loop, in the rigid-contact dynamics for ``cycles`` cycles
    from the optimised state at t = 0; departure from the optimised joint angles as the
    paper experiment measures it (1 % of the largest |joint angle|)."""
    tr = solution.transcription
    cycles = real_number("cycles", cycles)
    if not (math.isfinite(cycles) and cycles > 0):
        raise InputError(f"cycles {cycles} is not a positive finite number; expected e.g. 2")
    check_times(tr.gait, cycles * tr.gait.period, dt, names=("cycles × period", "dt"))
    traj = OptimizedTrajectory(solution)
    torques = _OptimizedTorques(traj)
    stance0 = tr.gait.stance(0.0)
    x, xd, xdd = traj.state(0.0)
    n = tr.gait.n_coords
    q0, v0, _ = PinocchioReference(tr.robot).reduced_motion(stance0, x[:n], xd[:n], xdd[:n], trunk_quaternion(x[12:15]))
    q0[:3] = x[15:18]
    horizon = cycles * tr.gait.period
    run = simulate_rigid(tr.plan, torques, TorqueLaw("optimised"), horizon, dt, initial=(q0, v0),  # type: ignore[arg-type]
                         trunk=lambda t: traj.state(t)[0][15:18])
    ref_q = np.array([traj.state(float(t))[0][:12] for t in run.t]).reshape(-1, 12)
    scale = float(np.abs(ref_q).max()) if ref_q.size else 1.0
    d, t1 = departure(run.t, run.q, ref_q, scale)
    return Replay(run, ref_q, d, t1, growth_rate(run.t[: len(d)], d), torques.max_roll, horizon, DEPARTURE_PCT / 100 * scale)


def node_count(solution: Solution) -> int:
    return N_X * solution.transcription.n_nodes
