"""Forward simulation of the paper's reduced dynamics along a gait plan (docs/formulation.md §6, docs/experiment.md §4).

State: the reduced coordinates q_r (12 joint angles in FL, FR, BL, BR x HAA, HFE, KFE order,
+ the trunk roll phi for a gait with two-feet phases) and their rates. The trunk orientation
is not a state: at every evaluation it follows from the stance legs, their footholds (where
each foot landed: the plan's, to round-off, while the run follows IK) and the roll
(``kinematics.pose_from_feet``); quat = (x, y, z, w). qdd_r = fd_r(stance, q_r, qd_r, tau_ext,
quat) with the stance of the plan's phase. The state is kept on the stance closure
(``project_on_stance``) after every step.

Torques (``TorqueLaw``): tau_ext(t) = scale * id_r(IK plan at t) + Kp (q_ref - q) + Kd (qd_ref
- qd) on the 12 joints; the 13th (roll) entry is id_r's roll moment when ``roll_applied`` (the
paper's check: the moment applied as if actuated) and 0 otherwise (unactuated, as on a robot).

Integrators (restarted at every stance switch, where the model changes):
* ``dop853``: scipy's explicit Runge-Kutta 8(5,3) with error control, rtol = atol = ``RTOL``
  (rad, rad/s), sampled every ``dt`` from its 7th-order dense output;
* ``rk4``: classical RK4 with the fixed step ``dt`` (which must divide a phase).
A run stops where the robot has fallen (FALLEN_CLOSURE_M, FALLEN_TRUNK_M) or the model is
singular; ``Run.stopped_at`` says when.

Evaluation backend: anything with the two methods of ``ReducedDynamics``: the generated C
(``compiled_reduced.CompiledReducedDynamics``, the default) or the CasADi graph
(``CasadiReducedDynamics``); ``reduced_dynamics`` picks one by name.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from functools import partial
from typing import Protocol

import numpy as np
import pinocchio as pin
from scipy.integrate import DOP853

from quadruped_dyn.arguments import real_number
from quadruped_dyn.dynamics.guarded import guarded_call
from quadruped_dyn.dynamics.kinematics import robot_feet, robot_kinematics
from quadruped_dyn.dynamics.reduced import reduced_model
from quadruped_dyn.errors import InputError, NumericalError
from quadruped_dyn.experiment.gait import Gait, Plan
from quadruped_dyn.experiment.plan_ik import IkTarget, ik_targets
from quadruped_dyn.experiment.trunk_pose import pose_from_feet
from quadruped_dyn.math.rigid import skew
from quadruped_dyn.model.robot import Robot
from quadruped_dyn.model.stance import StanceSet

#: A simulation stops when a stance foot is this far from its foothold, or the trunk this far
#: from where the plan puts it (m): the robot has fallen, and integrating further only
#: produces overflow.
FALLEN_CLOSURE_M = 0.1
FALLEN_TRUNK_M = 0.1

#: DOP853's relative and absolute tolerance (rad, rad/s: signals of order 1). Measured on the
#: paper robot's trot, 1.2 s: at 1e-13 the truncation error is below the amplified round-off
#: (a run at a 10x tighter tolerance differs from it by less than a one-ulp twin run does).
RTOL = 1e-13

#: The error budget's truncation estimate is a run at this many times RTOL: DOP853's error is
#: proportional to its tolerance (measured on the walks of the paper robot and go2:
#: error ~ rtol^0.8-0.9 from 1e-11 to 1e-13), so the 'paper' run's own truncation error is
#: |coarse - paper| / (factor - 1). A tighter run cannot measure it: below ~3e-14 a double run is
#: limited by its own round-off, which grows with the number of steps (go2's walk: 5.0e-5 % at
#: 1e-13, 3.7e-5 / 4.2e-5 % at 3e-14 / 1e-14), and a run at RTOL / 10 differed from the 'paper' run
#: by less than the paper run's own truncation (go2's walk looked 3-40x over its error budget).
#: Measured against a long-double run (native_run): go2's truncation at 1e-13 is
#: 2.8e-5 % (this estimate: 4.4e-5) and its round-off 2.2e-5 % (the one-ulp twin: 8e-6), so the
#: budget's sum meets the total by compensation (docs/results.md, what limits the walks).
TRUNCATION_RTOL_FACTOR = 10.0

IDENTITY_QUAT = np.array([0.0, 0.0, 0.0, 1.0])


class ReducedDynamics(Protocol):
    """An evaluation of the reduced model (numpy in and out; n = 12, or 13 for two feet)."""

    def id_r(self, stance: StanceSet, q_r: np.ndarray, qd_r: np.ndarray, qdd_r: np.ndarray,
             quat: np.ndarray) -> np.ndarray:
        """tau_r (n,): joint torques (N m), + the roll moment for two feet."""
        ...

    def fd_r(self, stance: StanceSet, q_r: np.ndarray, qd_r: np.ndarray, tau_ext: np.ndarray,
             quat: np.ndarray) -> np.ndarray:
        """qdd_r (n,); NumericalError where M_r is singular, InputError for bad input."""
        ...


class CasadiReducedDynamics:
    """The reduced model's CasADi graph (``reduced_model``), evaluated with checked inputs."""

    def __init__(self, robot: Robot) -> None:
        self.robot = robot

    def id_r(self, stance: StanceSet, q_r: np.ndarray, qd_r: np.ndarray, qdd_r: np.ndarray,
             quat: np.ndarray) -> np.ndarray:
        return guarded_call(reduced_model(self.robot, stance.name).id_r, q_r, qd_r, qdd_r, quat)[0]

    def fd_r(self, stance: StanceSet, q_r: np.ndarray, qd_r: np.ndarray, tau_ext: np.ndarray,
             quat: np.ndarray) -> np.ndarray:
        return reduced_model(self.robot, stance.name).forward_dynamics(q_r, qd_r, tau_ext, quat)[0]


BACKENDS = ("c", "casadi")


def reduced_dynamics(robot: Robot, backend: str = "c") -> ReducedDynamics:
    """The reduced model evaluated by the generated C ("c") or the CasADi graph ("casadi")."""
    if backend == "c":
        from quadruped_dyn.codegen.reduced_library import CompiledReducedDynamics

        return CompiledReducedDynamics(robot)
    if backend == "casadi":
        return CasadiReducedDynamics(robot)
    raise InputError(f"unknown backend '{backend}'; expected one of {', '.join(BACKENDS)}")


class IkTorques:
    """The target and id_r's torques along it, memoised by time (twin runs and fixed-step
    runs ask for the same times again)."""

    def __init__(self, plan: Plan, dynamics: ReducedDynamics) -> None:
        self.plan, self.dynamics = plan, dynamics
        self._memo: dict[tuple[float, tuple[int, ...]], tuple[IkTarget, np.ndarray]] = {}
        self._guess: np.ndarray | None = None

    def __call__(self, t: float, stance: tuple[int, ...]) -> tuple[IkTarget, np.ndarray]:
        """(target at t, id_r (n,) of the given stance there -- a step ending on a switch
        keeps its phase's stance)."""
        return self.many(np.array([t]), [stance])[0]

    def many(self, ts: np.ndarray, stances: list[tuple[int, ...]]) -> list[tuple[IkTarget, np.ndarray]]:
        """``self(t, stance)`` for each pair; the times not memoised yet in one batch (``ik_targets``)."""
        keys = [(float(t), stance) for t, stance in zip(ts, stances, strict=True)]
        missing = list(dict.fromkeys(k for k in keys if k not in self._memo))
        if missing:
            targets = ik_targets(self.plan, np.array([t for t, _ in missing]), self._guess)
            self._guess = targets[-1].q_r[:12]
            for (t, stance), target in zip(missing, targets):
                tau = self.dynamics.id_r(StanceSet(stance), target.q_r, target.qd_r, target.qdd_r, IDENTITY_QUAT)
                self._memo[(t, stance)] = (target, tau)
        return [self._memo[k] for k in keys]


@dataclass(frozen=True)
class TorqueLaw:
    """tau = scale * tau_IK + kp (q_ref - q) + kd (qd_ref - qd) on the joints (N m, N m/rad,
    N m s/rad); the roll entry: id_r's roll moment if ``roll_applied``, else 0."""

    name: str
    scale: float = 1.0
    kp: float = 0.0
    kd: float = 0.0
    roll_applied: bool = False

    def joints(self, target: IkTarget, tau_ik: np.ndarray, q: np.ndarray, qd: np.ndarray) -> np.ndarray:
        """The 12 joint torques for joint angles and rates q, qd (12,)."""
        return self.scale * tau_ik[:12] + self.kp * (target.q_r[:12] - q) + self.kd * (target.qd_r[:12] - qd)


@dataclass
class Run:
    """One simulation, sampled on ``t``; arrays (N, n)."""

    t: np.ndarray
    q: np.ndarray
    qd: np.ndarray
    qdd: np.ndarray
    closure_m: np.ndarray  # (N,) largest distance of a stance foot from its foothold, m
    stopped_at: float | None  # s: fell or singular (None: the full horizon)
    rhs_evaluations: int


Progress = Callable[[float], None]  # called with the simulated time reached, s

#: Samples per run (horizon / dt) that a command accepts: 100x the default two cycles at 1 ms,
#: minutes of integration per run; beyond it the work (and memory: a state per sample and run)
#: is refused before it starts (validate, optimize's replay).
MAX_SAMPLES = 200_000


INTEGRATORS = ("dop853", "rk4")


def check_times(gait: Gait, horizon: object, dt: object, integrator: str = "dop853", *,
                names: tuple[str, str] = ("horizon", "dt")) -> None:
    """InputError unless ``horizon`` and ``dt`` are positive finite seconds, horizon >= dt, at most
    MAX_SAMPLES samples per run, the integrator is known and (RK4) dt divides a phase. Every run
    checks these before any work (validate, the experiment, both simulations, the replay); a NaN
    horizon, a zero or negative dt or 1e9 s were a ValueError, ZeroDivisionError, IndexError or a
    7 TiB allocation. ``names``: what the messages call the horizon and the step, the API's parameter
    names unless the caller's own (the CLI's options, ``("--horizon", "--dt")``)."""
    h, d = names
    if integrator not in INTEGRATORS:
        raise InputError(f"unknown integrator '{integrator}'; expected {' or '.join(INTEGRATORS)}")
    horizon, dt = real_number(h, horizon), real_number(d, dt)
    if not (math.isfinite(horizon) and horizon > 0):
        raise InputError(f"{h} {horizon} is not a positive finite number of seconds; expected e.g. {2 * gait.period}")
    if not (math.isfinite(dt) and dt > 0):
        raise InputError(f"{d} {dt} is not a positive finite number of seconds; expected e.g. 1e-3")
    if horizon < dt:
        raise InputError(f"{h} {horizon} s is shorter than one step ({d} {dt} s); expected {h} >= {d}")
    samples = horizon / dt
    if samples > MAX_SAMPLES:
        raise InputError(f"{h} {horizon:g} s at {d} {dt:g} s is {samples:.3g} samples per run; expected at most "
                         f"{MAX_SAMPLES:,} samples ({h} / {d}) per run; a larger {d} or a shorter {h}")
    if integrator == "rk4" and abs(gait.phase_duration / dt - round(gait.phase_duration / dt)) > 1e-9:
        raise InputError(f"{d} {dt} does not divide the gait's phase of {gait.phase_duration} s; expected e.g. 1e-3")


def _sample_times(horizon: float, dt: float) -> np.ndarray:
    return np.arange(int(np.floor(horizon / dt + 1e-9)) + 1) * dt


class _Fallen(Exception):
    pass


def simulate_reduced(plan: Plan, dynamics: ReducedDynamics, law: TorqueLaw, horizon: float, dt: float,
                     integrator: str = "dop853", rtol: float = RTOL, initial_ulps: int = 0,
                     ik: IkTorques | None = None, progress: Progress | None = None, project: bool = True) -> Run:
    """Integrate the reduced forward dynamics from the IK state at t = 0 (see the module
    docstring); ``initial_ulps`` moves every initial coordinate and rate that many ulps up (the
    twin run that measures how round-off grows). ``project``: keep the state on the stance
    closure (``project_on_stance``) after every step."""
    check_times(plan.gait, horizon, dt, integrator)
    robot, gait = plan.robot, plan.gait
    ik = ik or IkTorques(plan, dynamics)
    feet_of = robot_feet(robot)
    n = gait.n_coords
    pitch = [0.0]  # the previous pose's pitch picks between the two-feet pose solutions
    evaluations = [0]

    footholds = {i: plan.foot(i, 0.0)[0] for i in range(4)}  # world, where each foot stands (or last stood)
    current = [gait.stance(0.0)]

    def fit(q: np.ndarray, stance: tuple[int, ...]) -> tuple[np.ndarray, np.ndarray, float]:
        feet = np.asarray(feet_of(q[:12])[0]).T[list(stance)]
        roll = float(q[12]) if len(stance) == 2 else None
        R, p, closure = pose_from_feet(feet, np.array([footholds[i] for i in stance]), roll=roll, pitch_hint=pitch[0])
        pitch[0] = float(pin.rpy.matrixToRpy(R)[1])
        return R, p, closure

    def pose(t: float, q: np.ndarray, stance: tuple[int, ...]) -> tuple[np.ndarray, float]:
        R, p, closure = fit(q, stance)
        if closure > FALLEN_CLOSURE_M or np.linalg.norm(p - plan.trunk(t)[0]) > FALLEN_TRUNK_M:
            raise _Fallen
        return pin.Quaternion(R).coeffs(), closure

    def touch_down(stance: tuple[int, ...], y: np.ndarray) -> np.ndarray:
        R, p, _ = fit(y[:n], current[0])
        land(robot, footholds, current[0], stance, y, R, p)
        current[0] = stance
        return y

    def qdd_of(t: float, q: np.ndarray, qd: np.ndarray, stance: tuple[int, ...]) -> tuple[np.ndarray, float]:
        evaluations[0] += 1
        target, tau_ik = ik(t, stance)
        tau = law.joints(target, tau_ik, q[:12], qd[:12])
        if n == 13:
            tau = np.append(tau, tau_ik[12] if (law.roll_applied and len(stance) == 2) else 0.0)
        quat, closure = pose(t, q, stance)
        qdd = dynamics.fd_r(StanceSet(stance), q, qd, tau, quat)
        return qdd, closure

    target0, _ = ik(0.0, gait.stance(0.0))
    y = np.concatenate([target0.q_r, target0.qd_r])
    for _ in range(initial_ulps):
        y = np.nextafter(y, np.inf)
    out_t: list[float] = []
    out_y: list[np.ndarray] = []
    out_qdd: list[np.ndarray] = []
    out_closure: list[float] = []
    stopped_at = None

    def record(stance: tuple[int, ...], t: float, y: np.ndarray) -> None:
        qdd, closure = qdd_of(t, y[:n], y[n:], stance)
        out_t.append(t)
        out_y.append(y.copy())
        out_qdd.append(qdd)
        out_closure.append(closure)

    def rhs(stance: tuple[int, ...], t: float, y: np.ndarray) -> np.ndarray:
        return np.concatenate([y[n:], qdd_of(t, y[:n], y[n:], stance)[0]])

    def projection(stance: tuple[int, ...], t: float, y: np.ndarray) -> np.ndarray:
        return project_on_stance(plan.robot, stance, np.array([footholds[i] for i in stance]), y, pitch[0])

    try:
        integrate_phases(plan, y, horizon, dt, integrator, rtol, rhs, record, projection if project else None,
                         touch_down, progress)
    except (_Fallen, NumericalError, InputError):  # a run that falls apart can also end in a non-finite state
        stopped_at = float(out_t[-1]) if out_t else 0.0
    Y = np.array(out_y).reshape(-1, 2 * n)
    return Run(np.array(out_t), Y[:, :n], Y[:, n:], np.array(out_qdd).reshape(-1, n), np.array(out_closure),
               stopped_at, evaluations[0])


Stance = tuple[int, ...]


def land(robot: Robot, footholds: dict[int, np.ndarray], before: Stance, after: Stance, y: np.ndarray,
         R: np.ndarray, p: np.ndarray) -> None:
    """At a stance switch: a landing foot stands where the simulated motion puts it (trunk pose
    R, p fitted to the stance before; on the planned foothold to round-off while the run follows
    IK). ``footholds`` (world, m) is updated; the coordinates carry over unchanged."""
    kin = robot_kinematics(robot)
    for i in set(after) - set(before):
        footholds[i] = R @ np.asarray(kin[i].foot_position(y[3 * i : 3 * i + 3])).ravel() + p


def phase_segments(plan: Plan, horizon: float, dt: float) -> list[tuple[float, float, Stance, np.ndarray]]:
    """The stretches an integration restarts at: (t0, t1, stance, the sample times in [t0, t1),
    or [t0, t1] for the last), the plan's phases up to ``horizon`` sampled every ``dt``."""
    samples = _sample_times(horizon, dt)
    bounds = np.concatenate([[0.0], plan.switch_times(horizon), [samples[-1]]])
    out = []
    for t0, t1 in zip(bounds[:-1], bounds[1:]):
        last = t1 == bounds[-1]
        inside = samples[(samples >= t0 - 1e-12) & ((samples < t1 - 1e-12) | last)]
        out.append((float(t0), float(t1), plan.stance(0.5 * (t0 + t1)), inside))
    return out


def integrate_phases(plan: Plan, y: np.ndarray, horizon: float, dt: float, integrator: str, rtol: float,
                     rhs: Callable[[Stance, float, np.ndarray], np.ndarray],
                     record: Callable[[Stance, float, np.ndarray], None],
                     project: Callable[[Stance, float, np.ndarray], np.ndarray] | None = None,
                     switch: Callable[[Stance, np.ndarray], np.ndarray] | None = None,
                     progress: Progress | None = None) -> np.ndarray:
    """Integrate y' = rhs(stance, t, y) phase by phase of the plan up to ``horizon``, restarting
    at every stance switch (``switch`` maps the state across it, e.g. an impact), calling
    ``record`` on the samples every ``dt``; ``project`` after every step. Exceptions
    of the callbacks propagate: the caller decides what a failure means."""
    for t0, t1, stance, inside in phase_segments(plan, horizon, dt):
        if switch is not None and t0 > 0:
            y = switch(stance, y)
        f = partial(rhs, stance)
        rec = partial(record, stance)
        proj = partial(project, stance) if project else None
        if integrator == "rk4":
            y = _rk4_segment(f, y, t0, t1, dt, inside, rec, proj)
        else:
            y = _dop853_segment(f, y, t0, t1, rtol, inside, rec, proj, progress)
        if progress:
            progress(float(t1))
    return y


def project_on_stance(robot: Robot, stance: tuple[int, ...], holds: np.ndarray, y: np.ndarray,
                      pitch_hint: float = 0.0) -> np.ndarray:
    """The state y = (q_r, qd_r) moved onto the stance closure: the stance feet on their
    footholds ``holds`` (k, 3; world, m) for the trunk pose fitted to them (``pose_from_feet``; two Newton steps of each
    stance leg's IK), and the stance legs' rates those of the trunk twist fitted to them (docs/
    formulation.md §5's velocity map, least squares, roll-rate row for two feet). The reduced coordinates
    are redundant -- 12 for 9 degrees of freedom with three feet, 13 for 12 with two -- and the
    paper's ODE does not keep the closure: its drift off it is the fastest-growing error. Right
    after a touch-down whose foot lands moving, the rate projection is a kinematic impact."""
    from quadruped_dyn.references.pinocchio import roll_rate_row  # its rounding is the experiment's

    feet_of = robot_feet(robot)
    n = y.size // 2
    q, qd = y[:n].copy(), y[n:].copy()
    roll = float(q[12]) if len(stance) == 2 else None
    for _ in range(2):
        r_all, J_all = (np.asarray(x) for x in feet_of(q[:12]))
        feet = r_all.T[list(stance)]
        R, p, _ = pose_from_feet(feet, holds, roll=roll, pitch_hint=pitch_hint)
        for j, i in enumerate(stance):
            s = slice(3 * i, 3 * i + 3)
            q[s] += np.linalg.solve(J_all[:, s], R.T @ (holds[j] - p) - feet[j])
    rows, rhs, legs = [], [], []
    r_all, J_all = (np.asarray(x) for x in feet_of(q[:12]))
    for i in stance:
        s = slice(3 * i, 3 * i + 3)
        r, J = r_all[:, i].copy(), J_all[:, s]
        rows.append(np.hstack([np.eye(3), -skew(r)]))
        rhs.append(-J @ qd[s])
        legs.append((s, r, J))
    if len(stance) == 2:
        rows.append(np.concatenate([np.zeros(3), roll_rate_row(R)])[None, :])
        rhs.append(np.array([qd[12]]))
    xi = np.linalg.lstsq(np.vstack(rows), np.concatenate(rhs), rcond=None)[0]
    for s, r, J in legs:
        qd[s] = np.linalg.solve(J, -(xi[:3] + np.cross(xi[3:], r)))
    return np.concatenate([q, qd])


def _rk4_segment(f: Callable[[float, np.ndarray], np.ndarray], y: np.ndarray, t0: float, t1: float, dt: float,
                 samples: np.ndarray, record: Callable[[float, np.ndarray], None],
                 project: Callable[[float, np.ndarray], np.ndarray] | None = None) -> np.ndarray:
    steps = int(round((t1 - t0) / dt))
    if abs(steps * dt - (t1 - t0)) > 1e-9:
        raise InputError(f"dt {dt} s does not divide the gait's phase of {t1 - t0} s; expected e.g. 1e-3")
    for k in range(steps):
        t = t0 + k * dt
        record(t, y)
        k1 = f(t, y)
        k2 = f(t + dt / 2, y + dt / 2 * k1)
        k3 = f(t + dt / 2, y + dt / 2 * k2)
        k4 = f(t + dt, y + dt * k3)
        y = y + dt / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
        if project is not None:
            y = project(t + dt, y)
    if samples.size and samples[-1] >= t1 - 1e-12:  # the horizon's last sample
        record(t1, y)
    return y


def _dop853_segment(f: Callable[[float, np.ndarray], np.ndarray], y: np.ndarray, t0: float, t1: float, rtol: float,
                    samples: np.ndarray, record: Callable[[float, np.ndarray], None],
                    project: Callable[[float, np.ndarray], np.ndarray] | None = None,
                    progress: Progress | None = None) -> np.ndarray:
    """DOP853 over [t0, t1]; ``project`` (if given) maps the state back onto the constraint
    manifold after every accepted step (coordinate projection: the step's end value and its
    stored derivative are replaced, so the next step starts on the manifold); ``progress`` gets
    the time reached after every step."""
    solver = DOP853(f, t0, y, t1, rtol=rtol, atol=rtol)
    pending = list(samples)
    while pending and pending[0] <= t0 + 1e-12:
        record(pending.pop(0), y)
    while solver.status == "running":
        message = solver.step()
        if solver.status == "failed":  # e.g. a run that is falling apart: the caller reports where it stopped
            raise NumericalError(f"DOP853 failed at t = {solver.t:.4f} s: {message}")
        if project is not None:
            solver.y = project(solver.t, solver.y)
            solver.f = f(solver.t, solver.y)  # scipy's RungeKutta keeps the end derivative here (FSAL)
        dense = solver.dense_output()
        while pending and pending[0] <= solver.t + 1e-12:
            ts = pending.pop(0)
            record(ts, solver.y if abs(ts - solver.t) < 1e-12 else dense(ts))
        if progress is not None:
            progress(float(solver.t))
    return np.asarray(solver.y)
