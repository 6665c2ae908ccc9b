"""``mpc+wbc``: a convex model-predictive controller over the contact forces, at ``MPC_RATE_HZ``,
whose forces the whole-body QP (``wbc``) tracks at every tick.

The model: the robot as one rigid body (its joints locked at the measured posture), whose
inertia is the trunk block of the generated M_full at the measured state -- the composite
rigid body's spatial inertia at the trunk origin, m, the centre of mass c (trunk frame) and the
rotational inertia I_c about it --, linearised about a level trunk (yaw as measured), in the
world frame, relative to the plan's trunk trajectory:

    d/dt (theta, dp, omega, dv) = (omega, dv, I_w^-1 sum (r_i x f_i), sum f_i / m + g - a_plan),

theta the trunk's roll, pitch, yaw (the IMU's; the plan's are 0), dp = p - p_plan from the
contact feet as in ``wbc``, omega the IMU's rate in the world, dv = v - v_plan (leg odometry),
r_i the foot positions from the centre of mass, f_i the ground forces (world). Forward Euler at
dt = 1 / MPC_RATE_HZ over MPC_HORIZON steps; the stance of each step and the feet's positions
from the plan (footholds relative to the planned trunk); the states condensed out, the QP is over
the forces of the horizon (in units of the robot's weight), with the friction pyramid inscribed
in the plant's cone and 0 <= f_z <= MAX_FOOT_LOAD m g, cost sum of x_k^T Q x_k + MPC_FORCE_WEIGHT
|f|^2; proxsuite's dense ProxQP, warm-started from the previous solution. The first step's forces
are the whole-body QP's force targets (weight WBC_FORCE_WEIGHT_MPC) until the next solve.

The locked-joint model is checked against Pinocchio's full dynamics with the joints' accelerations
held at zero, and its input matrix B against the generated GRF solve's derivative (B R P dlambda/da_b
is the identity on the trunk's accelerations, every 3-feet stance, at the states of a wbc walk)
(tests/control/test_wbc.py): the composite rigid body, exact at any posture.
"""

from __future__ import annotations

import time
from typing import TYPE_CHECKING, Any

import numpy as np
import pinocchio as pin
import proxsuite

from quadruped_dyn.control.plan import Target
from quadruped_dyn.control.plant import Command, Measurement
from quadruped_dyn.control.wbc import MAX_FOOT_LOAD, WholeBodyQp, friction_rows
from quadruped_dyn.errors import NumericalError
from quadruped_dyn.experiment.gait import Plan
from quadruped_dyn.experiment.plan_ik import IkTarget
from quadruped_dyn.math.rigid import skew
from quadruped_dyn.model.robot import Robot
from quadruped_dyn.model.stance import StanceSet
from quadruped_dyn.model.state import GRAVITY_W, quaternion_rotation

if TYPE_CHECKING:
    from quadruped_dyn.control.controllers import Gains, GeneratedC

MPC_RATE_HZ = 50.0
MPC_HORIZON = 10  # steps of 1 / MPC_RATE_HZ: 0.2 s
#: State weights of (theta [rad], dp [m], omega [rad/s], dv [m/s]) and of the forces (robot weights).
MPC_Q = np.array([50.0, 50.0, 20.0, 20.0, 20.0, 200.0, 0.5, 0.5, 0.2, 2.0, 2.0, 2.0])
MPC_FORCE_WEIGHT = 1e-3
#: The whole-body QP's weight on the MPC's forces (robot weights^2; ``wbc``'s own regulariser: 1e-3).
WBC_FORCE_WEIGHT_MPC = 0.05


def rigid_body(M_bb: np.ndarray) -> tuple[float, np.ndarray, np.ndarray]:
    """(m, c (3,) trunk frame, I_c (3, 3) trunk frame) of a 6 x 6 spatial inertia at the trunk origin
    (M_full's trunk block: [[m I, -m [c]x], [m [c]x, I_c - m [c]x [c]x]])."""
    m = float(M_bb[0, 0])
    C = M_bb[3:6, 0:3] / m  # [c]x
    c = np.array([C[2, 1], C[0, 2], C[1, 0]])
    return m, c, M_bb[3:6, 3:6] + m * C @ C


def continuous_model(m: float, I_w: np.ndarray, r: list[np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
    """(A (12, 12), B (12, 3 k)) of d/dt x = A x + B f + (0, 0, 0, g - a_plan) for feet at r (world,
    from the centre of mass); x = (theta, dp, omega, dv)."""
    A = np.zeros((12, 12))
    A[0:3, 6:9] = np.eye(3)
    A[3:6, 9:12] = np.eye(3)
    B = np.zeros((12, 3 * len(r)))
    I_inv = np.linalg.inv(I_w)
    for k, ri in enumerate(r):
        B[6:9, 3 * k : 3 * k + 3] = I_inv @ skew(ri)
        B[9:12, 3 * k : 3 * k + 3] = np.eye(3) / m
    return A, B


class MpcWbc(WholeBodyQp):
    """``mpc+wbc`` (see the module docstring)."""

    name = "mpc+wbc"
    force_weight = WBC_FORCE_WEIGHT_MPC

    def __init__(self, robot: Robot, gains: Gains, c: GeneratedC, mu: float = 0.8, rate_hz: float = 1000.0,
                 plan: Plan | None = None) -> None:
        super().__init__(robot, gains, c, mu, rate_hz, plan)
        if plan is None:
            raise NumericalError("mpc+wbc needs the gait plan (make_controller passes it)")
        self.plan = plan
        self.every = max(1, int(round(rate_hz / MPC_RATE_HZ)))
        self.tick = 0
        self.mpc: dict[tuple, Any] = {}

    def command(self, target: IkTarget, stance: StanceSet, meas: Measurement) -> Command:
        """The whole-body QP's command; every ``every`` ticks the MPC first (its time counted in ``qp_ns``)."""
        assert isinstance(target, Target)
        t0 = time.perf_counter_ns()
        if self.tick % self.every == 0 and self.terms is not None:
            self.force_ref = self.plan_forces(target, meas)
        mpc_ns = time.perf_counter_ns() - t0
        self.tick += 1
        command = super().command(target, stance, meas)
        self.qp_ns += mpc_ns
        return command

    def plan_forces(self, target: Target, meas: Measurement) -> np.ndarray:
        """(4, 3) world ground forces of the MPC's first step (zeros for its swing feet)."""
        assert self.terms is not None
        t = self.tick * self.dt
        h = 1.0 / MPC_RATE_HZ
        R = quaternion_rotation(meas.quat)
        m, c, I_c = rigid_body(self.terms.M[:6, :6])
        I_w = R @ I_c @ R.T
        com_w = R @ c
        feet = list(self.last_contact or target.stance)
        e_p = np.mean(self.terms.r[feet] @ R.T - target.r_feet[feet], axis=0)
        x = np.concatenate([pin.rpy.matrixToRpy(R), -e_p, R @ meas.omega_b, R @ self.v_b - target.trunk_v])
        steps = []
        for k in range(MPC_HORIZON):
            tk = t + k * h
            trunk, _, a_plan = self.plan.trunk(tk)
            stance = self.plan.stance(tk)
            r = [self.plan.foot(i, tk)[0] - trunk - com_w for i in stance]
            steps.append((stance, *continuous_model(m, I_w, r), GRAVITY_W - a_plan))
        return self._solve(x, steps, R, m, h)

    def _solve(self, x0: np.ndarray, steps: list, R: np.ndarray, m: float, h: float) -> np.ndarray:
        """The condensed QP over the horizon's forces (robot weights); the first step's, world, N."""
        weight = m * 9.81
        sizes = [3 * len(s[0]) for s in steps]
        offsets = np.concatenate([[0], np.cumsum(sizes)])
        n = int(offsets[-1])
        X_u = np.zeros((12 * MPC_HORIZON, n))  # x_{k+1} = x_free_k + X_u U
        x_free = np.zeros(12 * MPC_HORIZON)
        prev_u, prev_x = np.zeros((12, n)), x0.copy()
        for k, (_, A, B, d) in enumerate(steps):
            Ad = np.eye(12) + h * A
            prev_u = Ad @ prev_u
            prev_u[:, offsets[k] : offsets[k + 1]] += h * B * weight
            prev_x = Ad @ prev_x + h * np.concatenate([np.zeros(9), d])
            X_u[12 * k : 12 * k + 12] = prev_u
            x_free[12 * k : 12 * k + 12] = prev_x
        Q = np.tile(MPC_Q, MPC_HORIZON)
        H = X_u.T @ (Q[:, None] * X_u) + MPC_FORCE_WEIGHT * np.eye(n)
        g = X_u.T @ (Q * x_free)
        rows = [friction_rows(np.eye(3), self.mu, n + 18, np.full(len(s[0]), MAX_FOOT_LOAD)) for s in steps]
        C = np.zeros((sum(r[0].shape[0] for r in rows), n))
        upper = np.concatenate([r[1] for r in rows])
        row = 0
        for k, (Ck, _) in enumerate(rows):
            block = Ck[:, 18 : 18 + 3 * len(steps[k][0])]  # friction_rows lays the forces from column 18
            C[row : row + block.shape[0], offsets[k] : offsets[k + 1]] = block
            row += block.shape[0]
        key = tuple(s[0] for s in steps)
        qp = self.mpc.get(key)
        if qp is None:
            qp = self.mpc[key] = proxsuite.proxqp.dense.QP(n, 0, C.shape[0])
            qp.settings.eps_abs = 1e-6
            qp.settings.eps_primal_inf = qp.settings.eps_dual_inf = 1e-10
            qp.settings.initial_guess = proxsuite.proxqp.InitialGuess.WARM_START_WITH_PREVIOUS_RESULT
            qp.init(H, g, None, None, C, np.full(C.shape[0], -1e20), upper)
        else:
            qp.update(H, g, None, None, C, np.full(C.shape[0], -1e20), upper)
        qp.solve()
        f = np.zeros((4, 3))
        if qp.results.info.status != proxsuite.proxqp.QPSolverOutput.PROXQP_SOLVED:
            return self.force_ref if self.force_ref is not None else f  # keep the last plan
        for k, i in enumerate(steps[0][0]):
            f[i] = weight * qp.results.x[3 * k : 3 * k + 3]
        return f
