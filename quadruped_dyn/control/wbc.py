"""``wbc``: a whole-body QP controller on the generated C (docs/closed_loop.md, "Whole-body QP").

Each control tick solves one quadratic program over x = (vdot (18,), f / m g (3 n_c,)) -- the
project's vdot (d/dt of v: trunk linear, angular, 12 joints) and the ground force on each
contact foot (trunk frame), in units of the robot's weight m g so that every variable is of
order 1 (in newtons ProxQP declared feasible QPs primal infeasible) --; the joint torques are the joint rows of the dynamics,
tau = M_j vdot + h_j - J_cj^T f, so the QP over (vdot, f, tau) is this one with tau eliminated:

* equalities: the six floating-base rows M_b vdot + h_b = J_cb^T f; each contact foot not
  accelerating, J_i vdot + Jdv_i = 0;
* inequalities: per contact foot the friction pyramid inscribed in the plant's cone,
  |f . t_k| <= mu / sqrt(2) (f . n) for the world's x and y axes t_k, and f . n >= 0, n the
  world's z axis (flat ground, the plan's); |tau| <= the URDF's effort limits;
* cost, weighted least squares of tasks: the trunk's classical acceleration and angular
  acceleration towards the plan (PD on the trunk's pose relative to the contact feet and on its
  twist, the plan's acceleration fed forward), each swing foot's acceleration relative to the
  trunk towards the plan's (PD in the trunk frame), a posture regulariser on the joint
  accelerations (PD to the plan's joints), a small force regulariser.

Model terms: M_full, nle_full and feet_full (positions, Jacobian, Jdot v) of the compiled
generated C, one call each per tick, at the estimated state. Sensing as the other controllers:
joint encoders, the IMU (orientation, angular rate), the foot contact switches; the trunk's
linear velocity from leg odometry (``leg_odometry``), never from the simulator. The contact
feet are the plan's stance feet that the switches report on the ground.

Solver: proxsuite's dense ProxQP (Pinocchio's team; a dense problem of 24-30 variables, where
a dense factorisation beats OSQP's sparse ADMM in time and in accuracy of the equalities), one
QP object per contact set, warm-started from the previous tick's solution while the contact
set stays the same (set up afresh at a switch, and again if a warm start fails: a warm start
from a solution of another phase made ProxQP declare feasible QPs infeasible). A tick whose QP is not
solved (ProxQP's status, or the equalities violated by more than ``QP_EQUALITY_TOL``) stops the
run: ``QpInfeasible`` names the tick and the contact set.

The command to the drivers: the QP's torques fed forward, plus the drivers' PD to the plan with
``pd-diag``'s per-joint gains (the stance legs' for the contact feet's legs, the swing legs'
for the others; run at the plant's rate: what lets a 1 kHz torque loop hold a leg of ~1e-4
kg m^2; the stiffness capped where it would reach the effort limit within ``PD_LINEAR_RAD``).
Measured: with the PD on the swing legs only, solo12's trot fell at 1.2 s and the paper
robot's trot tracked 0.0041 rad RMS; with it on every leg both trot 10 cycles, 0.013 and 0.0006 (0.0007 capped).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np
import pinocchio as pin
import proxsuite

from quadruped_dyn.codegen.library import CompiledFunction
from quadruped_dyn.control.plan import Target
from quadruped_dyn.control.plant import Command, Measurement
from quadruped_dyn.errors import NumericalError
from quadruped_dyn.experiment.gait import Plan
from quadruped_dyn.experiment.plan_ik import IkTarget
from quadruped_dyn.model.actuator_limits import actuator_limit
from quadruped_dyn.model.robot import Robot
from quadruped_dyn.model.stance import StanceSet
from quadruped_dyn.model.state import quaternion_rotation

if TYPE_CHECKING:
    from quadruped_dyn.control.controllers import Gains, GeneratedC

#: Task gains: natural frequencies (rad/s), critically damped. The trunk's pose and twist
#: relative to the contact feet; the swing feet relative to the trunk; the posture regulariser.
WBC_OMEGA_TRUNK = 12.0
WBC_OMEGA_ATTITUDE = 20.0
WBC_OMEGA_SWING = 40.0
WBC_OMEGA_POSTURE = 20.0
#: Task weights (of squared accelerations, m/s^2 or rad/s^2; of forces in units of the robot's weight).
WBC_WEIGHTS = {"trunk": 1.0, "attitude": 1.0, "swing": 1.0, "posture": 1e-3, "force": 1e-3}
#: The last part of a swing (fraction of the phase) in which a foot on the ground (contact switch)
#: becomes a contact foot of the QP, and the stance feet's load is ramped down to 0 at the phase's
#: end (f . n <= MAX_FOOT_LOAD (1 - s) / (1 - LANDING_PHASE)): the load goes over to the landing feet
#: before the plan's switch instead of at once (the trot's pairs switch with no double support:
#: lifting a loaded pair kicked the trunk ~2.5 deg in roll at each switch).
LANDING_PHASE = 0.85
MAX_FOOT_LOAD = 2.0  # robot weights
#: The drivers' PD stays linear up to this joint error (rad): its stiffness M^ omega^2 is capped at the
#: effort limit / PD_LINEAR_RAD and its damping is 2 zeta sqrt(K_p M^) (~2x the joint errors wbc tracks).
#: Uncapped it reached anymal_c's 80 N m at 4-8 mrad (stance legs with their share of the mass, and its
#: 0.16-0.3 kg m^2 swing hips at 250 rad/s): a bang-bang PD that bounced the stance feet off the ground
#: half the time; the walk fell at 6-8.5 s (capping the stance legs only, or the stiffness only: 6-7 s).
#: It binds on the hips of go2's legs and of the paper robot's trot stance, never on solo12's.
PD_LINEAR_RAD = 0.02
#: An equality residual above this (N, m/s^2) means the QP was not solved, whatever the status.
QP_EQUALITY_TOL = 1e-3
#: ProxQP's absolute accuracy (m/s^2, robot weights).
QP_EPS_ABS = 1e-6
#: ProxQP's infeasibility certificates' threshold: at its default (1e-4) it declared QPs of the
#: trot primal infeasible that an LP solver (HiGHS) finds feasible and ProxQP solves at 1e-10.
QP_EPS_INFEASIBLE = 1e-10


class QpInfeasible(NumericalError):
    """The whole-body QP has no solution at a tick (friction, unilateral contact and torque limits
    cannot hold the contact feet still with the floating base's dynamics)."""


def leg_odometry(J: np.ndarray, v: np.ndarray, feet: tuple[int, ...]) -> np.ndarray | None:
    """Trunk linear velocity (trunk frame, m/s) from the feet in ``feet`` assumed still on the
    ground: each gives v_b = -(omega_b x r_i + J_i qd_i) = -(J_feet row i) (0, omega_b, qd);
    their mean, None without a foot. ``J`` is feet_full's (12, 18), ``v`` the state with any v_b."""
    if not feet:
        return None
    u = J @ np.concatenate([np.zeros(3), v[3:]])
    return -np.mean([u[3 * i : 3 * i + 3] for i in feet], axis=0)


@dataclass
class QpTerms:
    """The model terms of one tick, from the generated C: M (18, 18), h = nle (18,), the feet's
    positions r (4, 3), Jacobian J (12, 18) and bias Jdv (12,), trunk frame."""

    M: np.ndarray
    h: np.ndarray
    r: np.ndarray
    J: np.ndarray
    Jdv: np.ndarray


Estimate = tuple[np.ndarray, np.ndarray, QpTerms, tuple[int, ...]]  # q (19,), v (18,), terms, contact feet


class WholeBodyQp:
    """``wbc`` (see the module docstring). ``qp_ns`` and ``c_ns`` hold the last tick's QP and
    generated-C wall times (the C: the ctypes calls, inputs copied in); ``solved`` counts the ticks."""

    name = "wbc"
    friction = True  # make_controller passes the plant's mu, the control rate and the plan

    force_weight = WBC_WEIGHTS["force"]

    def __init__(self, robot: Robot, gains: Gains, c: GeneratedC, mu: float = 0.8, rate_hz: float = 1000.0,
                 plan: Plan | None = None) -> None:
        self.robot, self.gains, self.c, self.mu, self.dt = robot, gains, c, mu, 1.0 / rate_hz
        self.functions = {n: CompiledFunction(c.library, n) for n in ("M_full", "nle_full", "feet_full")}
        self.effort = actuator_limit(robot, "effort")
        self.weight = robot.total_mass * 9.81
        self.qps: dict[tuple[int, ...], Any] = {}  # proxsuite.proxqp.dense.QP (no type stubs)
        self.last_contact: tuple[int, ...] | None = None
        self.v_b = np.zeros(3)  # the last odometry estimate, trunk frame
        self.qp_ns = self.c_ns = 0
        self.solved = 0
        self.terms: QpTerms | None = None
        self.q, self.v = np.zeros(19), np.zeros(18)  # the last estimated state (trunk position 0)
        self.force_ref: np.ndarray | None = None  # (4, 3) world: forces a planner asks the QP to track

    # ------------------------------------------------------------------ model terms
    def call(self, name: str, *args: np.ndarray) -> list[np.ndarray]:
        """Generated function ``name``'s outputs, dense (matrices 2-D), through ``CompiledFunction.raw``
        (no input checks: ~1-6 us a call instead of ~25-33 us; the inputs are the IMU's and
        encoders', finite, the quaternion unit) scattered into the function's own patterns."""
        f = self.functions[name]
        out = []
        t0 = time.perf_counter_ns()
        raw = f.raw(*args)
        self.c_ns += time.perf_counter_ns() - t0
        for buf, shape, index in zip(raw, f._shapes, f._index):  # its sparsity patterns, read once at load
            dense = np.zeros(shape[0] * shape[1])
            dense[index] = buf
            out.append(dense if shape[1] == 1 else dense.reshape(shape, order="F"))
        return out

    def state(self, meas: Measurement, stance: StanceSet, phase_s: float) -> Estimate:
        """(q, v, terms, contact feet) at the estimated state: trunk position 0 (nothing here
        depends on it), orientation and angular rate from the IMU, v_b from leg odometry over
        the plan's stance feet the switches report on the ground (the plan's if none is). The
        contact feet: those, and a swing foot on the ground after LANDING_PHASE of the phase.
        Model terms from the generated C, one call each: feet_full (with the last estimate of
        v_b: its J does not depend on v, and Jdv = Jdot v + omega x (J v) gains omega x dv_b per
        foot when v_b changes by dv_b), then M_full and nle_full at the new v."""
        stance_feet = tuple(i for i in stance.feet if meas.touching[i])
        contact = tuple(i for i in range(4) if meas.touching[i] and (i in stance.feet or phase_s >= LANDING_PHASE))
        q = np.concatenate([np.zeros(3), meas.quat, meas.q])
        v = np.concatenate([self.v_b, meas.omega_b, meas.qd])
        self.c_ns = 0
        r, J, Jdv = self.call("feet_full", q, v)
        v_b = leg_odometry(J, v, stance_feet or stance.feet)
        if v_b is not None:
            Jdv = Jdv + np.tile(np.cross(meas.omega_b, v_b - self.v_b), 4)
            self.v_b = v_b
            v[:3] = v_b
        (M,) = self.call("M_full", q)
        (h,) = self.call("nle_full", q, v)
        self.q, self.v = q, v
        return q, v, QpTerms(M, h, r.reshape(4, 3), J, Jdv), contact

    # ------------------------------------------------------------------ tasks
    def trunk_targets(self, target: Target, R: np.ndarray, terms: QpTerms, v: np.ndarray,
                      contact: tuple[int, ...], stance: StanceSet) -> tuple[np.ndarray, np.ndarray]:
        """Desired (d/dt v_b, d/dt omega_b): PD on the trunk's position relative to the contact feet
        (the plan's r_feet, R = I, against R r_i measured) and on its velocity (the plan's against
        odometry), the plan's acceleration fed forward; PD on roll, pitch, yaw to level."""
        feet = list(contact or stance.feet)
        w, wa = WBC_OMEGA_TRUNK, WBC_OMEGA_ATTITUDE
        e_p = np.mean(terms.r[feet] @ R.T - target.r_feet[feet], axis=0)  # p_plan - p, world
        v_w = R @ v[:3]
        a_w = target.trunk_a + w**2 * e_p + 2 * w * (target.trunk_v - v_w)
        lin = R.T @ a_w - np.cross(v[3:6], v[:3])
        rpy = np.array(pin.rpy.matrixToRpy(R))
        e_R = -R.T @ rpy  # small-angle: the rotation back to level and yaw 0, trunk frame
        ang = wa**2 * e_R - 2 * wa * v[3:6]
        return lin, ang

    def swing_targets(self, target: Target, terms: QpTerms, v: np.ndarray, swing: list[int]) -> dict[int, np.ndarray]:
        """Per swing foot, the desired d2/dt2 r_i minus J_i-dot qd_i (trunk frame): PD to the plan."""
        w = WBC_OMEGA_SWING
        u = terms.J @ v
        omega = v[3:6]
        out = {}
        for i in swing:
            rows = slice(3 * i, 3 * i + 3)
            Ji_qd = terms.J[rows, 6:] @ v[6:]
            bias = terms.Jdv[rows] - np.cross(omega, Ji_qd) - np.cross(omega, u[rows])  # Jdot_i qd_i
            acc = target.ddr_feet[i] + w**2 * (target.r_feet[i] - terms.r[i]) + 2 * w * (target.dr_feet[i] - Ji_qd)
            out[i] = acc - bias
        return out

    # ------------------------------------------------------------------ the QP
    def qp_matrices(self, target: Target, meas: Measurement, stance: StanceSet) -> tuple:
        q, v, terms, contact = self.state(meas, stance, target.phase_s)
        self.terms = terms
        R = quaternion_rotation(meas.quat)
        nc = len(contact)
        n = 18 + 3 * nc
        wts = WBC_WEIGHTS
        rows, targets, weights = [], [], []

        def task(A: np.ndarray, b: np.ndarray, w: float) -> None:
            rows.append(A)
            targets.append(b)
            weights.append(np.full(b.size, w))

        lin, ang = self.trunk_targets(target, R, terms, v, contact, stance)
        task(np.eye(3, n), lin, wts["trunk"])
        task(np.eye(3, n, 3), ang, wts["attitude"])
        for i, b in self.swing_targets(target, terms, v, [i for i in range(4) if i not in contact]).items():
            A = np.zeros((3, n))
            A[:, 6:18] = terms.J[3 * i : 3 * i + 3, 6:]
            task(A, b, wts["swing"])
        wp = WBC_OMEGA_POSTURE
        qdd = target.qdd_r[:12] + wp**2 * (target.q_r[:12] - meas.q) + 2 * wp * (target.qd_r[:12] - meas.qd)
        task(np.eye(12, n, 6), qdd, wts["posture"])
        f_ref = np.zeros(3 * nc)
        if nc:
            per = np.tile(R.T @ np.array([0.0, 0.0, self.weight / nc]), nc)
            f_ref = per if self.force_ref is None else np.concatenate([R.T @ self.force_ref[i] for i in contact])
        task(np.eye(3 * nc, n, 18), f_ref / self.weight, self.force_weight)
        A_t, b_t, w_t = np.vstack(rows), np.concatenate(targets), np.concatenate(weights)
        H = A_t.T @ (w_t[:, None] * A_t)
        g = -A_t.T @ (w_t * b_t)
        Jc = terms.J[[3 * i + k for i in contact for k in range(3)]]
        A_eq = np.zeros((6 + 3 * nc, n))
        A_eq[:6, :18], A_eq[:6, 18:] = terms.M[:6], -self.weight * Jc[:, :6].T
        A_eq[6:, :18] = Jc
        b_eq = np.concatenate([-terms.h[:6], -terms.Jdv[[3 * i + k for i in contact for k in range(3)]]])
        landing = any(i not in stance.feet for i in contact)
        ramp = min(1.0, (1.0 - target.phase_s) / (1.0 - LANDING_PHASE))
        f_max = np.array([ramp * MAX_FOOT_LOAD if landing and i in stance.feet else np.inf for i in contact])
        C_f, u_f = friction_rows(R, self.mu, n, f_max)
        C_tau = np.zeros((12, n))
        C_tau[:, :18], C_tau[:, 18:] = terms.M[6:], -self.weight * Jc[:, 6:].T
        C = np.vstack([C_f, C_tau])
        lower = np.concatenate([np.full(C_f.shape[0], -np.inf), -self.effort - terms.h[6:]])
        upper = np.concatenate([u_f, self.effort - terms.h[6:]])
        return (H, g, A_eq, b_eq, C, lower, upper), contact, terms

    def solve(self, target: Target, meas: Measurement, stance: StanceSet) -> tuple[np.ndarray, np.ndarray, tuple[int, ...]]:
        """(vdot, f (n_c, 3) trunk frame, contact feet) of this tick's QP; QpInfeasible if unsolved."""
        (H, g, A, b, C, lower, upper), contact, terms = self.qp_matrices(target, meas, stance)
        t0 = time.perf_counter_ns()
        qp = self.qps.get(contact)
        if qp is not None and contact == self.last_contact:  # warm start: last tick's solution
            qp.update(H, g, A, b, C, lower, upper)
            qp.solve()
        if qp is None or contact != self.last_contact or not _solved(qp):
            qp = self.qps[contact] = _new_qp(H, g, A, b, C, lower, upper)  # cold: a switch, or the warm start failed
            qp.solve()
        self.last_contact = contact
        self.qp_ns = time.perf_counter_ns() - t0
        x = qp.results.x
        residual = float(np.abs(A @ x - b).max()) if b.size else 0.0
        if not _solved(qp) or not np.all(np.isfinite(x)) or residual > QP_EQUALITY_TOL:
            over = C @ x - upper if np.all(np.isfinite(x)) else np.zeros(1)
            worst = "friction or f_z >= 0" if over[: 6 * len(contact)].max(initial=-1) > 0 else "torque limits"
            raise QpInfeasible(f"whole-body QP not solved with contact feet {list(contact)} (status "
                               f"{qp.results.info.status.name}, equality residual {residual:.1e}; {worst} first)")
        self.solved += 1
        return x[:18], self.weight * x[18:].reshape(-1, 3), contact

    def torques(self, vdot: np.ndarray, f: np.ndarray, contact: tuple[int, ...]) -> np.ndarray:
        """tau = M_j vdot + h_j - J_cj^T f (the dynamics' joint rows)."""
        t = self.terms
        assert t is not None
        Jc = t.J[[3 * i + k for i in contact for k in range(3)]]
        return t.M[6:] @ vdot + t.h[6:] - Jc[:, 6:].T @ f.ravel()

    def command(self, target: IkTarget, stance: StanceSet, meas: Measurement) -> Command:
        assert isinstance(target, Target)
        vdot, f, contact = self.solve(target, meas, stance)
        self.c.ns += self.c_ns
        tau = self.torques(vdot, f, contact)
        w, z = self.gains.ct_omega(StanceSet(contact) if len(contact) else stance), self.gains.ct_zeta
        kp = np.minimum(target.inertia * w**2, self.effort / PD_LINEAR_RAD)
        return Command(tau, target.q_r[:12], target.qd_r[:12], kp, 2 * z * np.sqrt(kp * target.inertia))


def _new_qp(H: np.ndarray, g: np.ndarray, A: np.ndarray, b: np.ndarray, C: np.ndarray, lower: np.ndarray,
            upper: np.ndarray) -> Any:
    """A ProxQP dense problem set up with these matrices: the first solve starts from the
    equality-constrained point, later ones (``update``) from the previous solution."""
    qp = proxsuite.proxqp.dense.QP(H.shape[0], A.shape[0], C.shape[0])
    qp.settings.eps_abs = QP_EPS_ABS
    qp.settings.eps_primal_inf = qp.settings.eps_dual_inf = QP_EPS_INFEASIBLE
    qp.settings.verbose = False
    qp.settings.initial_guess = proxsuite.proxqp.InitialGuess.WARM_START_WITH_PREVIOUS_RESULT
    qp.init(H, g, A, b, C, lower, upper)
    return qp


def _solved(qp: Any) -> bool:
    return bool(qp.results.info.status == proxsuite.proxqp.QPSolverOutput.PROXQP_SOLVED)


def friction_rows(R: np.ndarray, mu: float, n: int, f_max: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(C, upper) of C x <= upper for the contact forces x[18:] (trunk frame, robot weights): per
    foot the pyramid inscribed in the cone of friction ``mu`` about the world's z axis (four
    faces, |f . t_k| <= mu / sqrt(2) f . n), 0 <= f . n <= f_max (inf: no bound)."""
    t1, t2, nz = R.T[:, 0], R.T[:, 1], R.T[:, 2]  # world x, y, z in the trunk frame
    m = mu / math.sqrt(2.0)
    faces = np.array([t1 - m * nz, -t1 - m * nz, t2 - m * nz, -t2 - m * nz, -nz, nz])
    nc = f_max.size
    C = np.zeros((6 * nc, n))
    upper = np.zeros(6 * nc)
    for k in range(nc):
        C[6 * k : 6 * k + 6, 18 + 3 * k : 21 + 3 * k] = faces
        upper[6 * k + 5] = f_max[k]
    return C, upper
