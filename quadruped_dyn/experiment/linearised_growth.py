"""The experiment's growth rate predicted from the derivatives (docs/derivatives.md, "The linearised
reduced walk").

The experiment measures how fast a one-ulp perturbation grows: a twin run started one ulp away,
both runs projected onto the stance closure after every step (``paper_experiment.growth_rate`` of
the largest joint-angle difference). The same quantity follows from the linearised model alone:

    delta(t + dt) = P(t + dt) expm(A(t + dt / 2) dt) delta(t),   delta(0) = the twin's one ulp,

A = [[0, I], [dqdd/dq_r + dqdd/dtheta W, dqdd/dqd_r]] the Jacobian of the reduced forward
dynamics (``dynamics.derivatives.reduced_derivatives``, the graphs generated as dfd_r) at the IK
state and IK torques of the plan ('paper' law: the roll moment applied), and P the derivative of
the experiment's own projection (``simulate.project_on_stance``, a central difference along delta). P matters:
the projection keeps the rates tangent to the closure at the perturbed angles, a first-order
term an orthogonal projector onto the closure's tangent misses (that projector predicted
1.3-1.8x the measured rates).
"""

from __future__ import annotations

import numpy as np
from scipy.linalg import expm

from quadruped_dyn.dynamics.derivatives import ReducedDerivatives, reduced_derivatives
from quadruped_dyn.errors import InputError
from quadruped_dyn.experiment.gait import Gait, Plan, gait_plan
from quadruped_dyn.experiment.paper_experiment import growth_rate
from quadruped_dyn.experiment.plan_ik import IkTarget, ik_target
from quadruped_dyn.experiment.simulate import IDENTITY_QUAT, project_on_stance
from quadruped_dyn.model.robot import Robot
from quadruped_dyn.model.stance import StanceSet

#: Central-difference step of the projection's derivative (rad, rad/s, along a unit direction):
#: truncation ~1e-12 and round-off ~1e-16 / 1e-6 = 1e-10 relative, far under the rate's own spread.
PROJECTION_FD_STEP = 1e-6

#: Time step (s) of the propagation: the experiment projects after every DOP853 step (a few ms), and
#: the closure drift grows at 30-45 /s between projections. Predicted rate at 20 / 5 ms:
#: paper walk 7.43 / 7.29, go2 walk 9.33 / 7.53 /s (measured 7.18 and 7.09).
STEP = 0.005


def _jacobian(derivatives: ReducedDerivatives, target: IkTarget) -> np.ndarray:
    """A (2n, 2n) at the target state and its IK torques, the trunk upright (the plan's R = I)."""
    tau = np.asarray(derivatives.did_r(target.q_r, target.qd_r, target.qdd_r, IDENTITY_QUAT)[0]).ravel()
    dq, dqd, _, dtheta = derivatives.dfd_r(target.q_r, target.qd_r, tau, IDENTITY_QUAT)
    n = derivatives.n
    W = np.asarray(derivatives.velocity_map(target.q_r, IDENTITY_QUAT))
    return np.block([[np.zeros((n, n)), np.eye(n)], [dq + dtheta @ W, dqd]])


def _projected(robot: Robot, plan: Plan, t: float, target: IkTarget, delta: np.ndarray) -> np.ndarray:
    """P delta: the derivative of project_on_stance at the target state (footholds of the plan)
    along delta (2n,), by a central difference of step PROJECTION_FD_STEP along delta's direction."""
    holds = np.array([plan.foot(i, t)[0] for i in target.stance])
    y = np.concatenate([target.q_r, target.qd_r])
    size = float(np.linalg.norm(delta))
    if size == 0.0:
        return delta
    e = delta * (PROJECTION_FD_STEP / size)
    return (project_on_stance(robot, target.stance, holds, y + e) - project_on_stance(robot, target.stance, holds, y - e)) * (
        size / (2 * PROJECTION_FD_STEP))


def linearised_departure(robot: Robot, gait: Gait, horizon: float, dt: float = STEP) -> tuple[np.ndarray, np.ndarray]:
    """(t (m,) s, the largest joint-angle component of the propagated perturbation (m,) rad): the
    twin's one-ulp perturbation through the linearised, projected model (module docstring) in
    steps of ``dt`` s over ``horizon`` s -- what the experiment's twin run measures as its
    difference from the 'paper' run."""
    if not (np.isfinite(horizon) and np.isfinite(dt) and 0 < dt <= horizon):
        raise InputError(f"horizon {horizon!r} s and dt {dt!r} s: expected finite times with 0 < dt <= horizon")
    plan = gait_plan(robot, gait)
    target0 = ik_target(plan, 0.0)
    y0 = np.concatenate([target0.q_r, target0.qd_r])
    delta = np.nextafter(y0, np.inf) - y0  # the twin run's initial perturbation (simulate_reduced)
    derivatives: dict[str, ReducedDerivatives] = {}
    times = np.arange(1, int(round(horizon / dt)) + 1) * dt
    largest, guess = [], None
    for t in times:
        mid = ik_target(plan, float(t - dt / 2), guess)
        name = StanceSet(mid.stance).name
        if name not in derivatives:
            derivatives[name] = reduced_derivatives(robot, name)
        end = ik_target(plan, float(t), mid.q_r[:12])
        guess = end.q_r[:12]
        delta = _projected(robot, plan, float(t), end, expm(_jacobian(derivatives[name], mid) * dt) @ delta)
        largest.append(np.abs(delta[:12]).max())
    return times, np.array(largest)


def linearised_growth_rate(robot: Robot, gait: Gait, horizon: float, dt: float = STEP) -> float | None:
    """Growth rate (1/s) of ``linearised_departure``, measured as the experiment measures its
    twin's (``paper_experiment.growth_rate``). None if the perturbation stays zero."""
    return growth_rate(*linearised_departure(robot, gait, horizon, dt))
