"""The plan the controllers track: the gait's IK at the control rate over one cycle.

The feet relative to the trunk are periodic in the plan (footholds and trunk advance by
speed x period per cycle), so the joint target is too: one cycle is computed and repeated.
Each tick also carries the legs' kinematics at the target (foot positions r_i in the trunk
frame and the inverse foot Jacobians), for the attitude-levelling controllers, and a positive
diagonal estimate of the joints' inertia for the computed-torque feedback (``inertia``), and
for the whole-body controller the feet's planned velocity and acceleration relative to the
trunk and the trunk's planned velocity and acceleration.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cache

import numpy as np

from quadruped_dyn.codegen.library import CompiledFunction, compiled_library
from quadruped_dyn.dynamics.kinematics import robot_kinematics
from quadruped_dyn.experiment.gait import Plan
from quadruped_dyn.experiment.plan_ik import IkTarget, ik_targets


@dataclass(frozen=True)
class Target(IkTarget):
    """An ``IkTarget`` (q_r, qd_r, qdd_r, stance) and the legs' kinematics there."""

    r_feet: np.ndarray  # (4, 3) foot positions, trunk frame, m
    J_inv: np.ndarray  # (4, 3, 3) inverse foot Jacobians d r_i / d q_i
    J: np.ndarray  # (4, 3, 3) foot Jacobians
    phase_s: float  # fraction [0, 1) of the current gait phase
    inertia: np.ndarray  # (12,) positive diagonal joint inertia estimate, kg m^2 (``joint_inertia``)
    dr_feet: np.ndarray  # (4, 3) d/dt r_feet = J qd_r, trunk frame, m/s
    ddr_feet: np.ndarray  # (4, 3) d2/dt2 r_feet (central differences of dr_feet along the periodic cycle), m/s^2
    trunk_v: np.ndarray  # (3,) the plan's trunk velocity, world (= trunk frame: R = I in the plan), m/s
    trunk_a: np.ndarray  # (3,) the plan's trunk classical acceleration, world, m/s^2


def joint_inertia(M_legs: np.ndarray, J: np.ndarray, stance: tuple[int, ...], mass: float) -> np.ndarray:
    """(12,) the diagonal of a positive definite joint-space inertia estimate: the legs' own
    joint inertia (the joint block of M_full, ``M_legs`` (12, 12)) plus, for each stance leg, its
    equal share of the robot's mass as a point mass at the hip moving with the foot fixed,
    (m / n_stance) J_i^T J_i (J_i the foot Jacobian, trunk frame). Unlike M_r's diagonal (which
    spreads over 0.002-1.1 kg m^2 on the paper robot and has a negative entry on go2) it is
    positive and means the same for every stance set."""
    m = np.diag(M_legs).copy()
    for i in stance:
        m[3 * i : 3 * i + 3] += mass / len(stance) * np.sum(J[i] ** 2, axis=0)
    return m


#: The IK target is computed at knots this far apart (s) and interpolated at the control
#: rate: cubic Hermite in (q, qd), linear in qdd. Measured on the paper robot's walk against
#: IK at every 1 ms tick: error ~1e-8 rad in q, ~1e-2 rad/s^2 in qdd (IK costs ~5 ms a sample
#: here, 1.2 s of walk at 1 kHz would take 6 s per robot and gait).
TARGET_KNOT_S = 0.005


@cache
def target_cycle(plan: Plan, rate_hz: float) -> tuple[Target, ...]:
    """The IK target at the control rate over one gait cycle (see the module docstring and
    ``TARGET_KNOT_S``); the stance set of each tick is the plan's."""
    period = plan.gait.period
    m = max(1, int(round(period / TARGET_KNOT_S)))
    h = period / m
    knots = ik_targets(plan, h * np.arange(m + 1))
    Q = np.array([s.q_r for s in knots])
    QD = np.array([s.qd_r for s in knots])
    QDD = np.array([s.qdd_r for s in knots])
    out = []
    rows = []
    kin = robot_kinematics(plan.robot)
    M_full = CompiledFunction(compiled_library(plan.robot), "M_full")
    origin = np.array([0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0])
    for k in range(int(round(period * rate_hz))):
        t = k / rate_hz
        j = min(int(t / h), m - 1)
        u = t / h - j
        h00, h10, h01, h11 = 2 * u**3 - 3 * u**2 + 1, u**3 - 2 * u**2 + u, -2 * u**3 + 3 * u**2, u**3 - u**2
        d00, d10, d01, d11 = (6 * u**2 - 6 * u) / h, 3 * u**2 - 4 * u + 1, (-6 * u**2 + 6 * u) / h, 3 * u**2 - 2 * u
        q = h00 * Q[j] + h10 * h * QD[j] + h01 * Q[j + 1] + h11 * h * QD[j + 1]
        qd = d00 * Q[j] + d10 * QD[j] + d01 * Q[j + 1] + d11 * QD[j + 1]
        qdd = (1 - u) * QDD[j] + u * QDD[j + 1]
        r = np.array([np.asarray(kin[i].foot_position(q[3 * i : 3 * i + 3])).ravel() for i in range(4)])
        J = np.array([np.asarray(kin[i].foot_jacobian(q[3 * i : 3 * i + 3])) for i in range(4)])
        stance = plan.stance(t)
        M_legs = M_full(np.concatenate([origin, q[:12]]))[0][6:, 6:]
        rows.append((q, qd, qdd, stance, r, np.linalg.inv(J), J, plan.gait.phase(t)[1],
                     joint_inertia(M_legs, J, stance, plan.robot.total_mass)))
    dr = np.array([np.einsum("ijk,ik->ij", row[6], row[1][:12].reshape(4, 3)) for row in rows])
    ddr = (np.roll(dr, -1, axis=0) - np.roll(dr, 1, axis=0)) * rate_hz / 2
    for k, row in enumerate(rows):
        _, v, a = plan.trunk(k / rate_hz)
        out.append(Target(*row, dr[k], ddr[k], v, a))
    return tuple(out)
