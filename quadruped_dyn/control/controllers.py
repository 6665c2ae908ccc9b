"""Controllers of the closed loop, built on the compiled, verified generated C.

Every controller sees the same inputs at every tick: the reference (the gait's IK at t: q_ref,
qd_ref, qdd_ref, 12 joints + the roll for a gait with two-feet phases, all from the plan), the
plan's stance set, and the ``Measurement`` (joint q, qd; trunk orientation and angular rate,
an IMU). Nothing else of the plant's state is used: no trunk position or linear velocity.
All model-based terms come from the generated C of ``codegen`` (``CompiledFunction`` of the
robot's ``compiled_library``: ``id_r``, ``M_r``, ``CG_r`` of the stance set), never from the
CasADi graph.

* ``pd``: tau = Kp (q_ref - q) + Kd (qd_ref - qd), the baseline.
* ``ff+pd``: tau = id_r(q_ref, qd_ref, qdd_ref, R = I)[:12] + the same PD: the paper's
  torques along the plan (its 13th entry, the roll moment the feet cannot produce, is
  not applied: no joint actuates the roll).
* ``ct``: computed torque on the reduced model at the **measured** state,
  tau = [M_r(q, R) (qdd_ref + Kp_a e + Kd_a edot) + CG_r(q, qd, R)][:12], e = q_ref - q.
  With two stance feet the 13th coordinate is the trunk roll phi, measured by the IMU
  (phi from R = Rz Ry Rx(phi), phid = e_phi . omega_b); its reference is 0, its commanded
  acceleration -Kp_a phi - Kd_a phid, and the 13th row of the result -- the moment about
  the foot-to-foot line it would take -- is dropped (unactuated), so the roll is only
  influenced through the coupling of M_r's first 12 rows.
* ``ct+att``: ``ct`` with trunk-attitude feedback through the GRF model: the commanded
  reduced accelerations of the stance legs also carry the joint accelerations that rotate
  the trunk about its origin with alpha_c = -Kp_att (roll, pitch, 0) - Kd_att omega_b
  (trunk frame; feet held), qdd_i += -J_i^-1 (alpha_c x r_i), so M_r turns them into joint
  torques whose ground forces (the paper's GRF model) produce the corrective moment. With
  two feet the part about the foot-to-foot line cannot be produced by the feet either; this
  controller also commands the roll coordinate's acceleration and, unlike ``ct``, keeps
  the swing legs' share of the 13th row: the joint accelerations of the swing legs are
  changed (least squares) so that the 13th row of M_r qdd + CG_r is zero -- the swing legs'
  reaction is used to roll the trunk as commanded, as far as it can.

Gains are per kg of robot (``Gains``): Kp = kp_per_kg m, Kd = kd_per_kg m for the joint PD
(pd, ff+pd); the computed-torque controllers' gains are accelerations (1/s^2, 1/s), a
natural frequency and damping ratio independent of the mass.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass
from typing import Protocol

import numpy as np
import pinocchio as pin

from quadruped_dyn.codegen.emit import reduced_symbol
from quadruped_dyn.codegen.library import CompiledFunction, compiled_library
from quadruped_dyn.control.plant import Measurement
from quadruped_dyn.dynamics.kinematics import robot_kinematics
from quadruped_dyn.errors import InputError
from quadruped_dyn.experiment.plan_ik import ReferenceSample
from quadruped_dyn.model.robot import Robot
from quadruped_dyn.model.stance import StanceSet

IDENTITY_QUAT = np.array([0.0, 0.0, 0.0, 1.0])

#: Joint PD gains per kg of robot: the paper robot (10 kg) gets 100 N m/rad and 3 N m s/rad.
#: Stiffer than the physics check's (3 and 0.15 per kg, where contacts are rigid): with
#: those, on MuJoCo's soft contacts, the paper robot's walk tracks to ~0.05 rad and topples in
#: its second cycle under ff+pd; the walk's CoM margin is 2 cm.
KP_PER_KG = 10.0  # N m / rad / kg
KD_PER_KG = 0.3  # N m s / rad / kg

#: Natural frequency (rad/s) and damping ratio of the computed-torque controllers' error
#: dynamics: 20 rad/s (3.2 Hz) is well below the 1 kHz loop and the contact's ~50 Hz
#: (MuJoCo's default solref time constant 0.02 s), and fast against a 0.3 s gait phase.
CT_OMEGA = 20.0
CT_ZETA = 1.0

#: Trunk attitude loop of ``ct+att``: natural frequency (rad/s) and damping ratio.
ATT_OMEGA = 10.0
ATT_ZETA = 1.0


@dataclass(frozen=True)
class Gains:
    kp_per_kg: float = KP_PER_KG  # N m / rad / kg
    kd_per_kg: float = KD_PER_KG  # N m s / rad / kg
    ct_omega: float = CT_OMEGA  # rad/s
    ct_zeta: float = CT_ZETA
    att_omega: float = ATT_OMEGA  # rad/s
    att_zeta: float = ATT_ZETA

    def validate(self) -> None:
        for name, value in vars(self).items():
            if not (math.isfinite(value) and value >= 0):
                raise InputError(f"gain {name} = {value}; expected a finite number >= 0")

    def as_dict(self, robot: Robot) -> dict[str, float]:
        m = robot.total_mass
        return {**vars(self), "mass_kg": m, "kp_Nm_per_rad": self.kp_per_kg * m, "kd_Nms_per_rad": self.kd_per_kg * m,
                "ct_kp_per_s2": self.ct_omega**2, "ct_kd_per_s": 2 * self.ct_zeta * self.ct_omega}


class Controller(Protocol):
    name: str

    def torques(self, ref: ReferenceSample, stance: StanceSet, meas: Measurement) -> np.ndarray:
        """Joint torques (12,), N m, project order."""
        ...


class GeneratedC:
    """The robot's generated reduced functions, called through ctypes (``CompiledFunction.raw``:
    preallocated buffers, no checks); ``ns`` accumulates the wall time of these calls (copying
    the inputs in, the ctypes call and the C), for the per-tick cost."""

    def __init__(self, robot: Robot) -> None:
        self.library = compiled_library(robot)
        self._functions: dict[str, tuple[CompiledFunction, int]] = {}
        self.ns = 0

    def __call__(self, name: str, stance: StanceSet, *args: np.ndarray) -> np.ndarray:
        key = reduced_symbol(name, stance)
        entry = self._functions.get(key)
        if entry is None:
            entry = self._functions[key] = (CompiledFunction(self.library, key), 13 if len(stance.feet) == 2 else 12)
        f, n = entry
        t0 = time.perf_counter_ns()
        out = f.raw(*args)[0]
        self.ns += time.perf_counter_ns() - t0
        return out.reshape(n, n, order="F").copy() if out.size == n * n else out.copy()


def imu_roll(meas: Measurement) -> tuple[float, float]:
    """Trunk roll phi (R = Rz Ry Rx(phi)) and its rate phid = e_phi . omega_b, from the IMU."""
    R = pin.Quaternion(meas.quat / np.linalg.norm(meas.quat)).toRotationMatrix()
    roll, pitch, _ = pin.rpy.matrixToRpy(R)
    e = np.array([1.0, math.sin(roll) * math.tan(pitch), math.cos(roll) * math.tan(pitch)])
    return float(roll), float(e @ meas.omega_b)


def _pad(x: np.ndarray, n: int) -> np.ndarray:
    """The reference's first n coordinates (a roll entry of 0 appended if it has none)."""
    return x[:n] if x.size >= n else np.append(x, np.zeros(n - x.size))


class Pd:
    name = "pd"

    def __init__(self, robot: Robot, gains: Gains, c: GeneratedC) -> None:
        self.kp, self.kd = gains.kp_per_kg * robot.total_mass, gains.kd_per_kg * robot.total_mass
        self.c = c

    def feedback(self, ref: ReferenceSample, meas: Measurement) -> np.ndarray:
        return self.kp * (ref.q_r[:12] - meas.q) + self.kd * (ref.qd_r[:12] - meas.qd)

    def torques(self, ref: ReferenceSample, stance: StanceSet, meas: Measurement) -> np.ndarray:
        return self.feedback(ref, meas)


class FfPd(Pd):
    name = "ff+pd"

    def torques(self, ref: ReferenceSample, stance: StanceSet, meas: Measurement) -> np.ndarray:
        n = 13 if len(stance.feet) == 2 else 12
        tau = self.c("id_r", stance, _pad(ref.q_r, n), _pad(ref.qd_r, n), _pad(ref.qdd_r, n), IDENTITY_QUAT)
        return tau[:12] + self.feedback(ref, meas)


class ComputedTorque:
    name = "ct"

    def __init__(self, robot: Robot, gains: Gains, c: GeneratedC) -> None:
        self.kp, self.kd = gains.ct_omega**2, 2 * gains.ct_zeta * gains.ct_omega
        self.c, self.robot = c, robot

    def commanded(self, ref: ReferenceSample, stance: StanceSet, meas: Measurement) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(q_r, qd_r, qdd_r commanded) at the measured state."""
        qdd = ref.qdd_r[:12] + self.kp * (ref.q_r[:12] - meas.q) + self.kd * (ref.qd_r[:12] - meas.qd)
        if len(stance.feet) != 2:
            return meas.q, meas.qd, qdd
        roll, roll_rate = imu_roll(meas)
        return (np.append(meas.q, roll), np.append(meas.qd, roll_rate),
                np.append(qdd, -self.kp * roll - self.kd * roll_rate))

    def torques(self, ref: ReferenceSample, stance: StanceSet, meas: Measurement) -> np.ndarray:
        q, qd, qdd = self.commanded(ref, stance, meas)
        M = self.c("M_r", stance, q, meas.quat)
        CG = self.c("CG_r", stance, q, qd, meas.quat)
        return (M @ qdd + CG)[:12]


class ComputedTorqueAttitude(ComputedTorque):
    name = "ct+att"

    def __init__(self, robot: Robot, gains: Gains, c: GeneratedC) -> None:
        super().__init__(robot, gains, c)
        self.kp_att, self.kd_att = gains.att_omega**2, 2 * gains.att_zeta * gains.att_omega
        self.kin = robot_kinematics(robot)

    def torques(self, ref: ReferenceSample, stance: StanceSet, meas: Measurement) -> np.ndarray:
        q, qd, qdd = self.commanded(ref, stance, meas)
        R = pin.Quaternion(meas.quat / np.linalg.norm(meas.quat)).toRotationMatrix()
        roll, pitch, _ = pin.rpy.matrixToRpy(R)
        alpha = -self.kp_att * np.array([roll, pitch, 0.0]) - self.kd_att * meas.omega_b
        for i in stance.feet:
            s = slice(3 * i, 3 * i + 3)
            r = np.asarray(self.kin[i].foot_position(meas.q[s])).ravel()
            J = np.asarray(self.kin[i].foot_jacobian(meas.q[s]))
            qdd[s] += np.linalg.solve(J, -np.cross(alpha, r))
        M = self.c("M_r", stance, q, meas.quat)
        CG = self.c("CG_r", stance, q, qd, meas.quat)
        if len(stance.feet) == 2:
            qdd[12] = -self.kp_att * q[12] - self.kd_att * qd[12]
            swing = np.concatenate([np.arange(3 * i, 3 * i + 3) for i in range(4) if i not in stance.feet])
            row = M[12]
            residual = row @ qdd + CG[12]  # the moment about the support line it would take, N m
            a = row[swing]
            if a @ a > 0:
                qdd[swing] -= a * residual / (a @ a)
        return (M @ qdd + CG)[:12]


CONTROLLERS = {c.name: c for c in (Pd, FfPd, ComputedTorque, ComputedTorqueAttitude)}


def parse_controllers(names: tuple[str, ...] | list[str]) -> list[str]:
    """Validated controller names (all of them for an empty selection), in CONTROLLERS' order."""
    unknown = [n for n in names if n not in CONTROLLERS]
    if unknown:
        raise InputError(f"unknown controller '{unknown[0]}'; expected one of {', '.join(CONTROLLERS)}")
    return [n for n in CONTROLLERS if not names or n in names]


def make_controller(name: str, robot: Robot, gains: Gains, c: GeneratedC) -> Controller:
    return CONTROLLERS[name](robot, gains, c)
