"""The closed loop: a controller at a fixed rate on the MuJoCo plant, along a gait plan.

Per control tick (period 1 / ``rate_hz``, default 1 kHz; it must be a whole number of plant
steps): measure (joint q, qd; trunk orientation and angular rate -- ``Plant.measure``), take the
target and stance set of the plan at t, compute the torques (``controllers``), hold them for
the tick's plant steps (zero-order hold). The stance set is the plan's: a foot is in the model's
stance from the planned touch-down to the planned lift-off whatever MuJoCo's contacts say (a
late touch-down is not detected; the joint feedback keeps driving the foot to the planned
foothold, and the feet's actual contacts are recorded and compared, ``measures``).

The target is the gait's IK (``plan_ik.ik_target``) sampled at the control rate over one
gait cycle and repeated: the feet relative to the trunk are periodic in the plan (footholds and
trunk advance by speed x period per cycle), so the joint target is too.

Initial state: the IK at t = 0 with the trunk at the plan's pose and zero velocity is dropped
onto the floor (the feet start exactly on it) and held for ``settle_s`` by joint PD plus the
generated C's gravity torques of the four-feet stance (G_r at the measured state); then the
velocities are set to the plan's at t = 0 (joint rates from IK, trunk twist from the stance legs,
``PinocchioReference.reduced_motion``) and the clock starts. Every controller starts from that
same settled state.

A run stops when the robot has fallen: trunk origin below ``FALL_HEIGHT_FRACTION`` of its
planned height above the floor, or trunk tilt (angle between its z axis and the world's)
above ``FALL_TILT_RAD``; or when the controller fails (a generated function reports a
singular configuration, or a non-finite torque).
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from quadruped_dyn.arguments import real_number, whole_number
from quadruped_dyn.codegen.library import CompiledFunction
from quadruped_dyn.control.controllers import Controller, Gains, GeneratedC, Pd, make_controller
from quadruped_dyn.control.plan import target_cycle
from quadruped_dyn.control.plant import Plant, PlantOptions
from quadruped_dyn.control.wbc import QpInfeasible
from quadruped_dyn.errors import InputError, NumericalError
from quadruped_dyn.experiment.gait import Plan
from quadruped_dyn.experiment.plan_ik import IkTarget
from quadruped_dyn.model.stance import StanceSet
from quadruped_dyn.model.state import rotation
from quadruped_dyn.references.pinocchio import PinocchioReference

#: Fallen: trunk origin below this fraction of its planned height above the floor, or the
#: trunk tilted more than FALL_TILT_RAD (40 deg): no controller here recovers from either.
FALL_HEIGHT_FRACTION = 0.5
FALL_TILT_RAD = math.radians(40.0)

Progress = Callable[[float], None]  # simulated time reached, s


#: MuJoCo steps per controller run that `control` accepts: 80x the default 10 cycles of the paper's walk
#: at 0.5 ms (24,000), minutes per controller; beyond it the work is refused before it starts.
MAX_PLANT_STEPS = 2_000_000


def _whole(x: float) -> bool:
    """x is a whole number to within 1e-9 relative (a ratio of times given in decimal)."""
    return abs(x - round(x)) <= 1e-9 * abs(x)


#: The largest push accepted, N s per kg of robot (a change of trunk velocity of 5 m/s: far past a fall).
MAX_PUSH_N_S_PER_KG = 5.0


@dataclass(frozen=True)
class LoopOptions:
    rate_hz: float = 1000.0
    cycles: int = 10
    settle_s: float = 0.5
    grf_every: int = 10  # control ticks between GRF comparison samples
    #: a push on the trunk (``Plant.push``): (t [s], impulse x, y, z [N s], world frame); None: no push
    push: tuple[float, float, float, float] | None = None

    def validate_push(self, horizon: float, mass: float) -> None:
        if self.push is None:
            return
        if not isinstance(self.push, tuple | list) or len(self.push) != 4:
            raise InputError(f"--push {self.push!r}; expected 4 numbers: the time (s) and the impulse x y z (N s)")
        t, *impulse = (real_number("--push", x) for x in self.push)
        if not (math.isfinite(t) and 0 <= t < horizon):
            raise InputError(f"--push at t = {t} s; expected a time from 0 to the run's {horizon:g} s")
        size = math.sqrt(sum(x * x for x in impulse))
        if not (math.isfinite(size) and size <= MAX_PUSH_N_S_PER_KG * mass):
            raise InputError(f"--push impulse {size:g} N s; expected at most {MAX_PUSH_N_S_PER_KG:g} N s per kg of robot "
                             f"({MAX_PUSH_N_S_PER_KG * mass:.3g} N s)")

    def validate(self, plant: PlantOptions, period: float) -> int:
        """Plant steps per control tick; InputError for a rate that does not divide the plant's step."""
        if whole_number("--cycles", self.cycles) <= 0:
            raise InputError(f"--cycles {self.cycles}; expected a whole number of gait cycles > 0")
        real_number("--rate", self.rate_hz)
        real_number("settle time", self.settle_s)
        if whole_number("grf_every", self.grf_every) < 1:
            raise InputError(f"grf_every {self.grf_every}; expected a whole number of control ticks >= 1")
        if not (math.isfinite(self.rate_hz) and self.rate_hz > 0):
            raise InputError(f"--rate {self.rate_hz} Hz; expected a positive number of control ticks per second")
        total = self.cycles * period / plant.timestep
        if total > MAX_PLANT_STEPS:
            raise InputError(f"--cycles {self.cycles} of {period:g} s at a {plant.timestep:g} s step is {total:.3g} MuJoCo steps "
                             f"per controller; expected at most {MAX_PLANT_STEPS:,} (fewer --cycles or a larger --timestep)")
        if not _whole(period / plant.timestep):  # then no control rate can be whole plant steps and divide the cycle
            raise InputError(f"--timestep {plant.timestep:g} s does not divide the gait cycle of {period:g} s; "
                             f"expected e.g. {PlantOptions.timestep:g} s")
        one_step = f"expected e.g. {1 / plant.timestep:.15g} Hz (one plant step per tick)"  # then both hold
        steps = 1.0 / self.rate_hz / plant.timestep
        if not _whole(steps) or round(steps) < 1:
            raise InputError(f"control period {1 / self.rate_hz:g} s is not a whole number of plant steps "
                             f"({plant.timestep:g} s); {one_step}")
        if not _whole(period * self.rate_hz):
            raise InputError(f"control period {1 / self.rate_hz:g} s does not divide the gait cycle of {period:g} s; "
                             f"{one_step}")
        if not (math.isfinite(self.settle_s) and 0 <= self.settle_s / plant.timestep <= MAX_PLANT_STEPS):
            raise InputError(f"settle time {self.settle_s} s at a {plant.timestep:g} s step; expected >= 0 and at most "
                             f"{MAX_PLANT_STEPS:,} MuJoCo steps ({MAX_PLANT_STEPS * plant.timestep:g} s)")
        return int(round(steps))


@dataclass
class Trace:
    """One closed-loop run, sampled at every control tick (arrays (N, ...))."""

    controller: str
    t: np.ndarray
    q: np.ndarray  # (N, 12) measured joint angles, rad
    qd: np.ndarray
    q_ref: np.ndarray  # (N, 12)
    qd_ref: np.ndarray
    tau: np.ndarray  # (N, 12) the drivers' torques at the tick's last plant step, N m (before the effort clamp)
    trunk_p: np.ndarray  # (N, 3) world, m
    trunk_R: np.ndarray  # (N, 3, 3)
    feet: np.ndarray  # (N, 4, 3) foot frame origins, world, m
    contact_f: np.ndarray  # (N, 4, 3) MuJoCo's ground force on each foot, world, N
    touching: np.ndarray  # (N, 4) bool
    stance: list[tuple[int, ...]]  # the plan's stance set per tick
    c_ns: np.ndarray  # (N,) wall time of the controller's generated-C calls, ns
    tick_ns: np.ndarray  # (N,) the whole controller tick in Python (measure + target + torques), ns
    step_ns: np.ndarray  # (N,) MuJoCo's steps of the tick, ns
    grf: list[dict] = field(default_factory=list)  # samples of MuJoCo's forces vs the paper's GRF model
    qpos: np.ndarray | None = None  # (N, nq) MuJoCo's qpos, for the animation
    fell_at: float | None = None  # s
    stopped: str | None = None  # why the run ended early
    qp_infeasible: bool = False  # it ended because the whole-body QP had no solution (wbc.QpInfeasible)
    qp_ns: np.ndarray | None = None  # (N,) wall time of the controller's QP solve per tick (wbc), ns


class _Stop(Exception):
    pass


def fallen(plant: Plant, height0: float) -> str | None:
    """Why the robot has fallen (trunk origin below FALL_HEIGHT_FRACTION of ``height0``, its
    planned height above the floor, or trunk tilt above FALL_TILT_RAD), or None: the one test of
    a run (it stops) and of the settled start (it is refused)."""
    height = float(plant.data.qpos[2] - plant.floor_z)
    tilt = math.acos(max(-1.0, min(1.0, float(plant.rotation()[2, 2]))))
    if height < FALL_HEIGHT_FRACTION * height0 or tilt > FALL_TILT_RAD:
        return f"trunk height {height:.3f} m above the floor, tilt {math.degrees(tilt):.0f} deg"
    return None


def settled_state(plant: Plant, plan: Plan, gains: Gains, c: GeneratedC, rate_hz: float, substeps: int,
                  settle_s: float, grf_every: int = 10) -> tuple[tuple[np.ndarray, np.ndarray], list[dict]]:
    """((q (19,), v (18,)), GRF samples): the initial state every run starts from (see the module
    docstring), and MuJoCo's contact forces vs the paper's four-feet GRF model over the second
    half of the settling (the robot standing: the only four-feet instants of the gaits)."""
    target0 = target_cycle(plan, rate_hz)[0]
    four = StanceSet((0, 1, 2, 3))
    q0 = np.concatenate([plan.trunk(0.0)[0], [0.0, 0.0, 0.0, 1.0], target0.q_r[:12]])
    plant.set_state(q0, np.zeros(18))
    pd = Pd(plant.robot, gains, c)
    hold = IkTarget(target0.q_r[:12], np.zeros(12), np.zeros(12), four.feet)
    ticks = int(round(settle_s * rate_hz))
    functions: dict[str, CompiledFunction] = {}
    grf = []
    for k in range(ticks):
        meas = plant.measure()
        sample = k >= ticks // 2 and k % grf_every == 0
        if sample:
            q_full, v_full = plant.full_state()
        plant.step(pd.pd(hold, c("G_r", four, meas.q, meas.quat)), substeps)
        if sample:
            f, touch = plant.contact_forces()
            grf.append(_grf_sample(plant, functions, c, k / rate_hz - settle_s, four, q_full, v_full, f, touch))
    q, _ = plant.full_state()
    height0 = q0[2] - plant.floor_z
    fell = fallen(plant, height0) if np.isfinite(q).all() else "a non-finite state"
    if plant.unstable() or fell:
        # every run would start from it: MuJoCo diverged (and reset the state) or the robot did not stand
        # (fell, or was thrown: a trunk 2.9 m up and tilted 72 deg at mu <= 1e-5, MuJoCo's smallest friction)
        raise NumericalError(f"the robot did not stand after settling for {settle_s:g} s in MuJoCo ({fell or 'MuJoCo diverged'}, "
                             f"started at {height0:.3f} m; friction mu = {plant.options.mu:g}, "
                             f"step {plant.options.timestep:g} s)")
    stance0 = plan.stance(0.0)
    _, v, _ = PinocchioReference(plant.robot).reduced_motion(stance0, target0.q_r, target0.qd_r, target0.qdd_r, q[3:7])
    return (q, v), grf


def run_controller(plant: Plant, plan: Plan, name: str, gains: Gains, options: LoopOptions, substeps: int,
                   initial: tuple[np.ndarray, np.ndarray], c: GeneratedC, progress: Progress | None = None,
                   keep_qpos: bool = False) -> Trace:
    """One controller on the plant from ``initial`` for ``options.cycles`` gait cycles."""
    controller: Controller = make_controller(name, plant.robot, gains, c, plant.options.mu, options.rate_hz, plan)
    cycle = target_cycle(plan, options.rate_hz)
    dt = 1.0 / options.rate_hz
    n = int(round(options.cycles * plan.gait.period * options.rate_hz))
    plant.set_state(*initial)
    grf_functions: dict[str, CompiledFunction] = {}
    height0 = -plant.floor_z  # planned trunk height above the floor (the plan's trunk is at z = 0)
    keys = ("t", "q", "qd", "q_ref", "qd_ref", "tau", "p", "R", "feet", "f", "touch", "c", "tick", "step", "qpos", "qp")
    rec: dict[str, list] = {k: [] for k in keys}
    stances: list[tuple[int, ...]] = []
    grf: list[dict] = []
    fell_at, stopped, infeasible = None, None, False
    every = max(1, n // 200)
    try:
        for k in range(n):
            t = k * dt
            t0 = time.perf_counter_ns()
            c.ns = 0
            meas = plant.measure()
            target = cycle[k % len(cycle)]
            stance = StanceSet(target.stance)
            try:
                command = controller.command(target, stance, meas)
            except (InputError, NumericalError) as e:  # the generated C's return codes (CompiledFunction.raw)
                stopped = f"controller failed at t = {t:.3f} s: {e}"
                infeasible = isinstance(e, QpInfeasible)
                raise _Stop from e
            t1 = time.perf_counter_ns()
            if not all(x is None or np.all(np.isfinite(x)) for x in (command.tau, command.q_des, command.qd_des)):
                stopped = f"controller returned a non-finite torque at t = {t:.3f} s"
                raise _Stop
            sample = k % options.grf_every == 0
            if sample:
                q_full, v_full = plant.full_state()
            p, R = plant.trunk_position(), plant.rotation()
            feet = plant.foot_positions()
            if options.push is not None:
                plant.push(options.push[1:], options.push[0], t)
            plant.step(command, substeps)
            t2 = time.perf_counter_ns()
            if plant.unstable():
                stopped = f"MuJoCo reports the simulation unstable at t = {t:.3f} s (non-finite or huge accelerations)"
                raise _Stop
            tau = plant.joint_torques()
            f, touch = plant.contact_forces()
            for key, value in (("t", t), ("q", meas.q), ("qd", meas.qd), ("q_ref", target.q_r[:12]), ("qd_ref", target.qd_r[:12]),
                               ("tau", tau), ("p", p), ("R", R), ("feet", feet), ("f", f), ("touch", touch),
                               ("c", c.ns), ("tick", t1 - t0), ("step", t2 - t1), ("qp", getattr(controller, "qp_ns", 0))):
                rec[key].append(value)
            if keep_qpos:
                rec["qpos"].append(plant.data.qpos.copy())
            stances.append(target.stance)
            if sample:
                grf.append(_grf_sample(plant, grf_functions, c, t, stance, q_full, v_full, f, touch))
            fell = fallen(plant, height0)
            if fell:
                fell_at = t + dt
                stopped = f"fell at t = {fell_at:.3f} s ({fell})"
                raise _Stop
            if progress and (k + 1) % every == 0:
                progress((k + 1) * dt)
    except _Stop:
        pass
    arr = {k: np.array(v) for k, v in rec.items()}
    return Trace(name, arr["t"], arr["q"].reshape(-1, 12), arr["qd"].reshape(-1, 12), arr["q_ref"].reshape(-1, 12),
                 arr["qd_ref"].reshape(-1, 12), arr["tau"].reshape(-1, 12), arr["p"].reshape(-1, 3),
                 arr["R"].reshape(-1, 3, 3), arr["feet"].reshape(-1, 4, 3), arr["f"].reshape(-1, 4, 3),
                 arr["touch"].reshape(-1, 4), stances, arr["c"], arr["tick"], arr["step"], grf,
                 arr["qpos"] if keep_qpos else None, fell_at, stopped, infeasible, arr["qp"])


def _grf_sample(plant: Plant, functions: dict[str, CompiledFunction], c: GeneratedC, t: float, stance: StanceSet,
                q: np.ndarray, v: np.ndarray, f_mj: np.ndarray, touch: np.ndarray) -> dict:
    """MuJoCo's contact forces and the paper's GRF model (generated C ``grf_<stance>``) at the same
    instant: the state before the step, MuJoCo's acceleration of that step."""
    a = plant.acceleration()
    symbol = f"grf_{stance.name.replace('+', '_')}"
    if symbol not in functions:
        functions[symbol] = CompiledFunction(c.library, symbol)
    _, f_b, residual, _ = functions[symbol](q, v, a)
    f_paper = f_b.reshape(4, 3) @ rotation(q).T
    feet = list(stance.feet)
    return {"t": t, "stance": stance.feet, "contacts_match": bool(np.array_equal(np.nonzero(touch)[0], np.array(feet))),
            "mujoco": f_mj[feet], "paper": f_paper[feet], "residual": residual}
