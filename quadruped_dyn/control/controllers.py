"""Controllers of the closed loop, built on the compiled, verified generated C.

Every controller sees the same inputs at every tick: the target (the gait's IK at t: q_ref,
qd_ref, qdd_ref, 12 joints + the roll for a gait with two-feet phases, all from the plan), the
plan's stance set, and the ``Measurement`` (joint q, qd; trunk orientation and angular rate,
an IMU). Nothing else of the plant's state is used: no trunk position or linear velocity.
All model-based terms come from the generated C of ``codegen`` (``CompiledFunction`` of the
robot's ``compiled_library``: ``id_r`` of the stance set, one call per tick; ``G_r`` while the
robot settles; ``M_full`` along the target for the inertia estimate), never from the CasADi
graph.

* ``pd``: tau = Kp (q_ref - q) + Kd (qd_ref - qd), the baseline.
* ``ff+pd``: tau = id_r(q_ref, qd_ref, qdd_ref, R = I)[:12] + the same PD: the paper's
  torques along the plan (its 13th entry, the roll moment the feet cannot produce, is
  not applied: no joint actuates the roll).
* ``ct``, ``ct-diag``, ``ct-diag+land`` and ``id+pd`` take the stance set of their model from the plan and the
  foot contact switches (``model_stance``): a foot the plan has in stance but which is off the
  ground is a swing leg for the model (a lightly loaded foot that lifts early, a late
  touch-down); the other controllers use the plan's stance only.
* ``ct``: computed torque on the reduced model at the **measured** state, the issue's law
  tau = M_r (qdd_ref + Kp e + Kd edot) + C_r + G_r, e = q_ref - q, as ONE generated call:
  id_r(q, qd, qdd_ref + Kp e + Kd edot, R), since id_r = M_r qdd + C_r + G_r exactly.
  Kp = w^2, Kd = 2 zeta w per leg (``Gains``: w of the stance legs, w of the swing legs).
  With two stance feet the 13th coordinate is the trunk roll phi, measured by the IMU
  (phi from R = Rz Ry Rx(phi), phid = e_phi . omega_b); its target is 0, its commanded
  acceleration -Kp phi - Kd phid with the stance legs' gains, and the 13th row of the result
  -- the moment about the foot-to-foot line it would take -- is dropped (unactuated).
  It falls on every robot: the feedback goes through M_r, whose rows of a stance leg carry
  the trunk, and a stance foot that unloads (soft contact) leaves a leg of ~1/100 of that
  inertia under that gain: the 1 kHz loop diverges within ~10 ticks (docs/closed_loop.md).
* ``ct-diag``: the computed-torque law with the feedback's inertia replaced by a positive
  diagonal estimate M_hat (``Target.inertia``: the leg's own joint inertia plus, for a
  stance leg, its share of the robot's mass carried at the hip, m / n_stance J_i^T J_i),
  tau = id_r(q, qd, qdd_ref, R) + M_hat (Kp e + Kd edot) with the same per-leg Kp, Kd as
  ``ct``: one generated call (the model's torques at the measured state), the feedback run
  by the joint drivers at the plant's rate (per-joint gains M_hat w^2, 2 zeta w M_hat), so
  that an unloaded leg meets a stiffness it can carry. Two feet: roll and roll rate from the
  IMU in id_r, the roll's target acceleration (0), the 13th row dropped.
* ``pd-diag``: ``ct-diag``'s per-joint gains without the model: the "pd with the same gains".
* ``ct-diag+land``: ``ct-diag`` whose swing feet aim a few mm below the plan's touch-down
  (``DiagonalCtLand``): what it does about the trot's roll moment the paper's model leaves
  unbalanced.
* ``id+pd``: id_r at the **measured** state (joint q, qd; roll and roll rate from the IMU for
  two feet; the trunk orientation) with the target's accelerations, plus the joint PD of
  ``pd`` (per-kg gains).
* ``ff+pd+level``: ``ff+pd`` tracking the target levelled by the IMU (``levelled``):
  trunk-attitude feedback through the legs -- the stance legs' targets tilt the trunk back to
  level (their forces, through the ground, produce the correcting moment), the swing feet land
  on the ground whatever the tilt. With two feet the moment about the foot-to-foot line,
  which the paper's model leaves unbalanced and which rolls the trunk, cannot be produced by
  the stance feet: what counters it is the swing pair, whose feet are brought down to the
  ground on the side the trunk rolls towards and catch it at touch-down.
* ``ff+pd+step``: ``ff+pd`` with capture-point foot placement of the swing feet (``FfPdStep``),
  the trunk velocity estimated from encoders and IMU: what catches the trot's roll.

Gains are per kg of robot (``Gains``): Kp = kp_per_kg m, Kd = kd_per_kg m for the joint PD
(pd, ff+pd, id+pd and their variants); the computed-torque controllers' gains are natural
frequencies per leg and a damping ratio, independent of the mass.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, replace
from typing import Protocol

import numpy as np
import pinocchio as pin

from quadruped_dyn.arguments import real_number
from quadruped_dyn.codegen.emit import reduced_symbol
from quadruped_dyn.codegen.library import CompiledFunction, compiled_library
from quadruped_dyn.control.mpc import MpcWbc
from quadruped_dyn.control.plan import Target
from quadruped_dyn.control.plant import Command, Measurement
from quadruped_dyn.control.wbc import WholeBodyQp
from quadruped_dyn.errors import InputError
from quadruped_dyn.experiment.gait import Plan
from quadruped_dyn.experiment.plan_ik import IkTarget
from quadruped_dyn.model.robot import Robot
from quadruped_dyn.model.stance import StanceSet
from quadruped_dyn.model.state import quaternion_rotation

IDENTITY_QUAT = np.array([0.0, 0.0, 0.0, 1.0])

#: Joint PD gains per kg of robot: the paper robot (10 kg) gets 200 N m/rad and 5 N m s/rad,
#: run by the joint drivers at the plant's rate (``plant.Command``). Stiffer than the physics
#: check's (3 and 0.15 per kg, rigid contacts): measured on the paper robot's walk under ff+pd
#: on MuJoCo's soft contacts, 3 cycles: 5 and 0.2 per kg fall in the 2nd cycle, 10 and 0.3
#: in the 3rd, 20 and 0.5 stay up with 0.005 rad RMS tracking. The walk's CoM margin is 2 cm.
KP_PER_KG = 20.0  # N m / rad / kg
KD_PER_KG = 0.5  # N m s / rad / kg

#: Natural frequencies (rad/s) of the computed-torque controllers' joint error dynamics, per
#: leg, and their damping ratio (critical). A swing leg is ~1/10-1/100 of a stance leg's
#: inertia and is pushed around by the trunk's motion: it needs the higher bandwidth. Measured
#: on the paper robot's walk, 2 cycles, ct-diag (stance, swing): (20, 100) rad/s joint RMS
#: 0.0038 rad, (30, 150) 0.0019, (50, 250) 0.0011 (pd 0.029). 250 rad/s x the plant's 0.5 ms
#: step = 0.125: well inside what the drivers' implicit PD integrates.
CT_OMEGA_STANCE = 50.0
CT_OMEGA_SWING = 250.0
CT_ZETA = 1.0

#: The largest gain accepted (any of Gains, in its unit). 5e4 x the default kp per kg: the paper
#: robot's pd already saturates every joint's effort at 1e5 and falls within one walk cycle, and
#: 1e10 behaves as 1e100 (bang-bang). Far larger gains overflowed: at 1e308, kp x mass is inf,
#: MuJoCo diverged, and the run died with a NaN state blamed on the stance.
MAX_GAIN = 1e6

#: ct-diag+land: how far below the plan's touch-down point the swing feet aim (m). Measured on
#: the paper robot's trot, 10 cycles asked: 3 mm falls at 2.2 s, 5 mm trots 10 cycles, 10 mm
#: falls at 1.95 s; 5 mm trots solo12 and go2 10 cycles. A narrow window, not a tuned margin.
LANDING_DROP_M = 0.005


@dataclass(frozen=True)
class Gains:
    kp_per_kg: float = KP_PER_KG  # N m / rad / kg
    kd_per_kg: float = KD_PER_KG  # N m s / rad / kg
    ct_omega_stance: float = CT_OMEGA_STANCE  # rad/s
    ct_omega_swing: float = CT_OMEGA_SWING  # rad/s
    ct_zeta: float = CT_ZETA

    def ct_omega(self, stance: StanceSet) -> np.ndarray:
        """(12,) natural frequency per joint: the stance legs' or the swing legs'."""
        w = np.full(12, self.ct_omega_swing)
        for i in stance.feet:
            w[3 * i : 3 * i + 3] = self.ct_omega_stance
        return w

    def validate(self) -> None:
        for name, given in vars(self).items():
            value = real_number(f"gain {name}", given)
            if not (math.isfinite(value) and 0 <= value <= MAX_GAIN):
                raise InputError(f"gain {name} = {value}; expected a finite number from 0 to {MAX_GAIN:g}")

    def as_dict(self, robot: Robot) -> dict[str, float]:
        m = robot.total_mass
        return {**vars(self), "mass_kg": m, "kp_Nm_per_rad": self.kp_per_kg * m, "kd_Nms_per_rad": self.kd_per_kg * m}


class Controller(Protocol):
    name: str

    def command(self, target: IkTarget, stance: StanceSet, meas: Measurement) -> Command:
        """This tick's command to the joint drivers (feedforward torques, PD target and gains)."""
        ...


class GeneratedC:
    """The robot's generated reduced functions, called through ctypes (``CompiledFunction.raw``:
    preallocated buffers, no checks); ``ns`` accumulates the wall time of these calls (copying
    the inputs in, the ctypes call and the C), for the per-tick cost."""

    def __init__(self, robot: Robot) -> None:
        self.library = compiled_library(robot)
        self._functions: dict[tuple[str, tuple[int, ...]], CompiledFunction] = {}
        self.ns = 0

    def __call__(self, name: str, stance: StanceSet, *args: np.ndarray) -> np.ndarray:
        """The first output of ``name`` of the stance set (a vector): a view of the function's
        output buffer, valid until its next call."""
        f = self._functions.get((name, stance.feet))
        if f is None:
            f = self._functions[(name, stance.feet)] = CompiledFunction(self.library, reduced_symbol(name, stance))
        t0 = time.perf_counter_ns()
        out = f.raw(*args)[0]
        self.ns += time.perf_counter_ns() - t0
        return out


def imu_roll(meas: Measurement) -> tuple[float, float]:
    """Trunk roll phi (R = Rz Ry Rx(phi)) and its rate phid = e_phi . omega_b, from the IMU."""
    R = quaternion_rotation(meas.quat)
    roll, pitch, _ = pin.rpy.matrixToRpy(R)
    e = np.array([1.0, math.sin(roll) * math.tan(pitch), math.cos(roll) * math.tan(pitch)])
    return float(roll), float(e @ meas.omega_b)


def _pad(x: np.ndarray, n: int) -> np.ndarray:
    """The target's first n coordinates (a roll entry of 0 appended if it has none)."""
    return x[:n] if x.size >= n else np.append(x, np.zeros(n - x.size))


class Pd:
    name = "pd"

    def __init__(self, robot: Robot, gains: Gains, c: GeneratedC) -> None:
        self.kp, self.kd = gains.kp_per_kg * robot.total_mass, gains.kd_per_kg * robot.total_mass
        self.c = c

    def pd(self, target: IkTarget, tau: np.ndarray) -> Command:
        """The joint PD to the target, run by the drivers, plus a feedforward ``tau``."""
        return Command(tau, target.q_r[:12], target.qd_r[:12], self.kp, self.kd)

    def command(self, target: IkTarget, stance: StanceSet, meas: Measurement) -> Command:
        return self.pd(target, np.zeros(12))


class FfPd(Pd):
    name = "ff+pd"

    def command(self, target: IkTarget, stance: StanceSet, meas: Measurement) -> Command:
        n = 13 if len(stance.feet) == 2 else 12
        tau = self.c("id_r", stance, _pad(target.q_r, n), _pad(target.qd_r, n), _pad(target.qdd_r, n), IDENTITY_QUAT)
        return self.pd(target, tau[:12].copy())


def measured_state(target: IkTarget, stance: StanceSet, meas: Measurement,
                   qdd: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(q_r, qd_r, qdd_r) of the reduced model at the measured state: the joints' q, qd and the
    given joint accelerations (12,); with two stance feet the roll phi and its rate from the IMU
    appended, and the roll's target acceleration."""
    if len(stance.feet) != 2:
        return meas.q, meas.qd, qdd
    roll, roll_rate = imu_roll(meas)
    return np.append(meas.q, roll), np.append(meas.qd, roll_rate), np.append(qdd, _pad(target.qdd_r, 13)[12])


class MeasuredIdPd(Pd):
    """id_r at the **measured** state with the target's accelerations, plus the same joint PD
    (run by the drivers): the model's torques where the robot is, not where the plan is."""

    name = "id+pd"

    def command(self, target: IkTarget, stance: StanceSet, meas: Measurement) -> Command:
        stance = model_stance(stance, meas)
        tau = self.c("id_r", stance, *measured_state(target, stance, meas, target.qdd_r[:12]), meas.quat)
        return self.pd(target, tau[:12].copy())


def model_stance(stance: StanceSet, meas: Measurement) -> StanceSet:
    """The stance set of the measured-state controllers' model: the plan's stance feet that the
    foot contact switches report on the ground (a foot that lifts early or lands late is a swing
    leg for the model), the plan's set if fewer than two remain (the reduced model needs two)."""
    feet = tuple(i for i in stance.feet if meas.touching[i])
    return StanceSet(feet) if len(feet) >= 2 else stance


class ComputedTorque:
    name = "ct"

    def __init__(self, robot: Robot, gains: Gains, c: GeneratedC) -> None:
        self.gains, self.c = gains, c

    def command(self, target: IkTarget, stance: StanceSet, meas: Measurement) -> Command:
        stance = model_stance(stance, meas)
        w, z = self.gains.ct_omega(stance), self.gains.ct_zeta
        qdd = target.qdd_r[:12] + w**2 * (target.q_r[:12] - meas.q) + 2 * z * w * (target.qd_r[:12] - meas.qd)
        q, qd, qdd = measured_state(target, stance, meas, qdd)
        if len(stance.feet) == 2:  # the roll's feedback, stance gains, target 0
            ws = self.gains.ct_omega_stance
            qdd[12] -= ws**2 * q[12] + 2 * z * ws * qd[12]
        return Command(self.c("id_r", stance, q, qd, qdd, meas.quat)[:12].copy())


class DiagonalPd(Pd):
    """``pd-diag``: joint PD with ``ct-diag``'s per-joint gains, M_hat w^2 and 2 zeta w M_hat
    (M_hat = ``Target.inertia`` of the plan's stance), no model torques."""

    name = "pd-diag"

    def __init__(self, robot: Robot, gains: Gains, c: GeneratedC) -> None:
        super().__init__(robot, gains, c)
        self.gains = gains
        self._cache: dict[int, tuple[np.ndarray, np.ndarray]] = {}

    def diagonal_gains(self, target: IkTarget, stance: StanceSet) -> tuple[np.ndarray, np.ndarray]:
        """(Kp, Kd) per joint at this target tick (computed once per tick of the cycle)."""
        gains = self._cache.get(id(target))
        if gains is None:
            assert isinstance(target, Target)
            w, z = self.gains.ct_omega(stance), self.gains.ct_zeta
            gains = self._cache[id(target)] = (target.inertia * w**2, target.inertia * 2 * z * w)
        return gains

    def command(self, target: IkTarget, stance: StanceSet, meas: Measurement) -> Command:
        kp, kd = self.diagonal_gains(target, stance)
        return Command(np.zeros(12), target.q_r[:12], target.qd_r[:12], kp, kd)


class DiagonalCt(DiagonalPd):
    """``ct-diag`` (see the module docstring): id_r at the measured state with the target's
    accelerations, plus the drivers' PD with the per-joint gains of ``pd-diag``."""

    name = "ct-diag"

    def command(self, target: IkTarget, stance: StanceSet, meas: Measurement) -> Command:
        kp, kd = self.diagonal_gains(target, stance)
        model = model_stance(stance, meas)
        tau = self.c("id_r", model, *measured_state(target, model, meas, target.qdd_r[:12]), meas.quat)
        return Command(tau[:12].copy(), target.q_r[:12], target.qd_r[:12], kp, kd)


class DiagonalCtLand(DiagonalCt):
    """``ct-diag+land``: ``ct-diag`` whose swing feet aim ``LANDING_DROP_M`` below the plan's
    touch-down point (in the trunk frame, ramped in with the swing's smoothstep, through the
    inverse foot Jacobians at the target): the landing pair meets the ground a little before
    the plan's switch and is loaded when it comes. What it does about the trot's unbalanced
    roll moment: nothing within a phase; the roll it builds over a phase is caught at each
    switch by a pair already on the ground."""

    name = "ct-diag+land"

    def command(self, target: IkTarget, stance: StanceSet, meas: Measurement) -> Command:
        assert isinstance(target, Target)
        base = super().command(target, stance, meas)
        s = target.phase_s
        drop = np.array([0.0, 0.0, -LANDING_DROP_M * (10 * s**3 - 15 * s**4 + 6 * s**5)])
        q_des = target.q_r[:12].copy()
        for i in set(range(4)) - set(stance.feet):
            q_des[3 * i : 3 * i + 3] += target.J_inv[i] @ drop
        return Command(base.tau, q_des, base.qd_des, base.kp, base.kd)


def levelled(target: Target, meas: Measurement) -> Target:
    """The target corrected for the measured trunk tilt: each foot's target moved in the trunk
    frame by delta x r_i, delta = (roll, pitch, 0) from the IMU -- where the plan's foot (on
    the ground, or on its swing path) is seen from a trunk tilted by delta, to first order --
    so that the stance legs push the trunk back to level and the swing feet land on the ground
    rather than above or below it; the rates likewise with (omega_x, omega_y, 0). Through the
    inverse foot Jacobians at the target (``Target.J_inv``): no kinematics per tick."""
    R = quaternion_rotation(meas.quat)
    roll, pitch, _ = pin.rpy.matrixToRpy(R)
    delta = np.array([roll, pitch, 0.0])
    rate = np.array([meas.omega_b[0], meas.omega_b[1], 0.0])
    dq = np.einsum("ijk,ik->ij", target.J_inv, np.cross(delta, target.r_feet)).ravel()
    dqd = np.einsum("ijk,ik->ij", target.J_inv, np.cross(rate, target.r_feet)).ravel()
    q, qd = target.q_r.copy(), target.qd_r.copy()
    q[:12] += dq
    qd[:12] += dqd
    return replace(target, q_r=q, qd_r=qd)


class FfPdLevel(FfPd):
    """``ff+pd`` tracking the IMU-levelled target (``levelled``); the feedforward id_r stays
    the plan's."""

    name = "ff+pd+level"

    def command(self, target: IkTarget, stance: StanceSet, meas: Measurement) -> Command:
        n = 13 if len(stance.feet) == 2 else 12
        tau = self.c("id_r", stance, _pad(target.q_r, n), _pad(target.qd_r, n), _pad(target.qdd_r, n), IDENTITY_QUAT)
        assert isinstance(target, Target)
        return self.pd(levelled(target, meas), tau[:12].copy())


class FfPdStep(FfPd):
    """``ff+pd`` with capture-point foot placement: the trunk's horizontal velocity relative to
    the stance feet is estimated from the encoders and the IMU (v_b = -(omega_b x r_i + J_i qd_i),
    averaged over the stance feet, kinematics at the target), its error e_v against the
    plan's, and each swing foot's target is moved horizontally (trunk frame) towards
    sqrt(h / g) e_v at touch-down (h: the trunk's height above the feet; the capture point of a
    linear inverted pendulum), ramped in with the swing's smoothstep; a foot keeps the offset it
    landed with through its stance. This is what acts on the roll the paper's model leaves
    unbalanced in the trot: the diagonal pair falling sideways is caught by the next pair
    landing further out."""

    name = "ff+pd+step"
    gain = 1.0  # times the capture point's sqrt(h / g)

    def __init__(self, robot: Robot, gains: Gains, c: GeneratedC) -> None:
        super().__init__(robot, gains, c)
        self.offsets = np.zeros((4, 3))  # trunk frame, m: where each foot landed relative to the plan
        self.swing_from = np.zeros((4, 3))
        self.was_stance = [True] * 4

    def command(self, target: IkTarget, stance: StanceSet, meas: Measurement) -> Command:
        assert isinstance(target, Target)
        base = super().command(target, stance, meas)
        feet = list(stance.feet)
        Jqd = np.einsum("ijk,ik->ij", target.J, meas.qd.reshape(4, 3))
        Jqd_ref = np.einsum("ijk,ik->ij", target.J, target.qd_r[:12].reshape(4, 3))
        v = -(np.cross(meas.omega_b, target.r_feet[feet]) + Jqd[feet]).mean(axis=0)
        v_plan = -Jqd_ref[feet].mean(axis=0)
        h = -float(target.r_feet[:, 2].mean())
        step = np.zeros(3)
        step[:2] = self.gain * math.sqrt(max(h, 0.0) / 9.81) * (v - v_plan)[:2]
        s = target.phase_s
        ramp = 10 * s**3 - 15 * s**4 + 6 * s**5
        q_des = np.array(base.q_des if base.q_des is not None else target.q_r[:12], dtype=float)
        for i in range(4):
            if i in feet:
                self.was_stance[i] = True
            else:
                if self.was_stance[i]:  # lift-off: ramp from the offset it stood with
                    self.swing_from[i] = self.offsets[i].copy()
                    self.was_stance[i] = False
                self.offsets[i] = (1 - ramp) * self.swing_from[i] + ramp * step
            q_des[3 * i : 3 * i + 3] += target.J_inv[i] @ self.offsets[i]
        return Command(base.tau, q_des, base.qd_des, base.kp, base.kd)


CONTROLLERS = {c.name: c for c in (Pd, FfPd, ComputedTorque, DiagonalCt, DiagonalPd, DiagonalCtLand, MeasuredIdPd,
                                    FfPdLevel, FfPdStep, WholeBodyQp, MpcWbc)}


def parse_controllers(names: tuple[str, ...] | list[str]) -> list[str]:
    """Validated controller names (all of them for an empty selection), in CONTROLLERS' order."""
    if not isinstance(names, tuple | list):  # a str would be read letter by letter
        raise InputError(f"controllers {names!r} is a {type(names).__name__}; expected a list of names from "
                         f"{', '.join(CONTROLLERS)}")
    unknown = [n for n in names if not isinstance(n, str) or n not in CONTROLLERS]
    if unknown:
        raise InputError(f"unknown controller '{unknown[0]}'; expected one of {', '.join(CONTROLLERS)}")
    return [n for n in CONTROLLERS if not names or n in names]


def make_controller(name: str, robot: Robot, gains: Gains, c: GeneratedC, mu: float = 0.8,
                    rate_hz: float = 1000.0, plan: Plan | None = None) -> Controller:
    """Controller ``name``; those with ``friction`` (wbc, mpc+wbc) also get the plant's friction
    coefficient, the control rate and the gait plan."""
    cls = CONTROLLERS[name]
    if getattr(cls, "friction", False):
        return cls(robot, gains, c, mu=mu, rate_hz=rate_hz, plan=plan)  # type: ignore[call-arg]
    return cls(robot, gains, c)
