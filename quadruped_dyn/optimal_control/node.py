"""What the transcription evaluates at one node, as CasADi SX Functions (docs/optimal_control.md).

Coordinates x (18,) of the whole robot: the 12 joint angles (FL, FR, BL, BR x HAA, HFE, KFE),
the trunk's Euler angles (roll phi, pitch theta, yaw psi; R = Rz(psi) Ry(theta) Rx(phi), the
project's convention) and the trunk origin p (world, m). The reduced model's coordinates are
q_r = x[:12] for three or four stance feet and q_r = x[:13] (the roll appended) for two: the
pitch, yaw and p are not reduced coordinates -- the transcription carries them so that the
stance feet can be pinned to their footholds in the world, and the reduced model's velocity
and acceleration maps then return exactly the trunk motion they describe.

* ``kinematics``: x, xd, xdd -> the four feet's world positions, velocities, accelerations
  (3, 4 each) and the whole robot's CoM in the world (3,);
* ``dynamics`` of a stance set: x, xd, xdd -> tau (12,) the paper's reduced inverse dynamics
  (``reduced_projection``: id_r = S rnea(q, v, T qdd_r + k)), roll (1,) the 13th entry of
  id_r for two stance feet (the unbalanced moment about the foot-to-foot line, N m; 0 for three
  feet: the paper's three-foot model balances any wrench), and f (3k,) the paper's GRF on the
  stance feet in the world frame (N).
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cache

import casadi as ca
import numpy as np

from quadruped_dyn.dynamics.grf import grf_expressions
from quadruped_dyn.dynamics.kinematics import foot_position, joint_frames
from quadruped_dyn.dynamics.reduced_projection import reduced_projection
from quadruped_dyn.math.spatial import dm
from quadruped_dyn.model.leg_frames import axis_aligned
from quadruped_dyn.model.robot import Robot
from quadruped_dyn.model.stance import StanceSet

N_X = 18  # 12 joints, roll, pitch, yaw, p (3)
ROLL = 12


def euler_rotation(angles: ca.SX) -> ca.SX:
    """R = Rz(psi) Ry(theta) Rx(phi) for angles (phi, theta, psi)."""
    phi, theta, psi = angles[0], angles[1], angles[2]
    cx, sx, cy, sy, cz, sz = ca.cos(phi), ca.sin(phi), ca.cos(theta), ca.sin(theta), ca.cos(psi), ca.sin(psi)
    Rx = ca.vertcat(ca.horzcat(1, 0, 0), ca.horzcat(0, cx, -sx), ca.horzcat(0, sx, cx))
    Ry = ca.vertcat(ca.horzcat(cy, 0, sy), ca.horzcat(0, 1, 0), ca.horzcat(-sy, 0, cy))
    Rz = ca.vertcat(ca.horzcat(cz, -sz, 0), ca.horzcat(sz, cz, 0), ca.horzcat(0, 0, 1))
    return Rz @ Ry @ Rx


def euler_quaternion(angles: ca.SX) -> ca.SX:
    """(x, y, z, w) of R = Rz(psi) Ry(theta) Rx(phi)."""
    cx, sx = ca.cos(angles[0] / 2), ca.sin(angles[0] / 2)
    cy, sy = ca.cos(angles[1] / 2), ca.sin(angles[1] / 2)
    cz, sz = ca.cos(angles[2] / 2), ca.sin(angles[2] / 2)
    return ca.vertcat(sx * cy * cz - cx * sy * sz, cx * sy * cz + sx * cy * sz, cx * cy * sz - sx * sy * cz,
                      cx * cy * cz + sx * sy * sz)


def com_position(robot: Robot, q_joints: ca.SX) -> ca.SX:
    """Whole-robot CoM in the trunk frame (3,), m."""
    total = ca.SX(robot.trunk.mass * dm(robot.trunk.com))
    for i, leg in enumerate(robot.legs):
        leg_c = axis_aligned(leg)
        for (R, p), link in zip(joint_frames(leg_c, q_joints[3 * i : 3 * i + 3]), leg_c.links):
            total = total + link.mass * (p + R @ dm(link.com))
    return total / robot.total_mass


@dataclass(frozen=True)
class NodeFunctions:
    kinematics: ca.Function  # x, xd, xdd -> feet (3, 4), feet_d (3, 4), feet_dd (3, 4), com (3,)
    dynamics: dict[tuple[int, ...], ca.Function]  # stance -> (x, xd, xdd -> tau (12,), roll (1,), f (3k,))


def _kinematics(robot: Robot) -> ca.Function:
    x, xd, xdd = ca.SX.sym("x", N_X), ca.SX.sym("xd", N_X), ca.SX.sym("xdd", N_X)
    R, p = euler_rotation(x[12:15]), x[15:18]
    feet = ca.horzcat(*[p + R @ foot_position(leg, x[3 * i : 3 * i + 3]) for i, leg in enumerate(robot.legs)])
    feet_v = ca.vec(feet)
    J = ca.jacobian(feet_v, x)
    vel = J @ xd
    acc = J @ xdd + ca.jacobian(vel, x) @ xd
    com = p + R @ com_position(robot, x[:12])
    return ca.Function("node_kinematics", [x, xd, xdd], [feet, ca.reshape(vel, 3, 4), ca.reshape(acc, 3, 4), com],
                       ["x", "xd", "xdd"], ["feet", "feet_d", "feet_dd", "com"], {"cse": True})


def _dynamics(robot: Robot, stance: StanceSet) -> ca.Function:
    x, xd, xdd = ca.SX.sym("x", N_X), ca.SX.sym("xd", N_X), ca.SX.sym("xdd", N_X)
    two = len(stance.feet) == 2
    n = 13 if two else 12
    quat = euler_quaternion(x[12:15])
    q_r, qd_r, qdd_r = x[:n], xd[:n], xdd[:n]
    proj = reduced_projection(robot, stance, q_r, quat)
    v, k = proj.velocity_and_bias(qd_r)
    a = proj.T @ qdd_r + k
    g = grf_expressions(robot, stance, "paper", ca.vertcat(ca.SX.zeros(3), quat, x[:12]), v, a)
    if two:
        r1, r2 = proj.r
        e = (r1 - r2) / ca.norm_2(r1 - r2)
        roll = ca.dot(e, g.residual[3:] - ca.cross(r1, g.residual[:3]))
    else:
        roll = ca.SX(0)
    R = euler_rotation(x[12:15])
    f = ca.vertcat(*[R @ g.f[3 * i : 3 * i + 3] for i in stance.feet])
    name = stance.name.replace("+", "_")
    return ca.Function(f"node_dynamics_{name}", [x, xd, xdd], [g.tau, roll, f], ["x", "xd", "xdd"],
                       ["tau", "roll", "f"], {"cse": True})


@cache
def node_functions(robot: Robot, stances: tuple[tuple[int, ...], ...]) -> NodeFunctions:
    """The node Functions of a robot for the stance sets of a gait (built once)."""
    return NodeFunctions(_kinematics(robot), {s: _dynamics(robot, StanceSet(s)) for s in stances})


def trunk_quaternion(angles: np.ndarray) -> np.ndarray:
    """Numeric (x, y, z, w) of R = Rz(psi) Ry(theta) Rx(phi), angles = (phi, theta, psi) rad."""
    a = ca.SX.sym("a", 3)
    return np.asarray(ca.Function("q", [a], [euler_quaternion(a)])(np.asarray(angles, dtype=float))).ravel()
