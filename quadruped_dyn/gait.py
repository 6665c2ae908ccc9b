"""Gaits and the paper's validation experiment (SPEC section 6, paper section 6, Figs. 4-7).

Trot: diagonal pairs (FL+BR, then FR+BL) alternate every half period. Static walk: one leg
swings at a time (FL, BR, FR, BL), three in stance. The trunk moves forward at constant speed
and height with R = I (so the trot's roll phi = 0). A stance foot stays at its
world foothold; a swing foot moves to its next foothold with a quintic smoothstep forward and
a 64 s^3 (1 - s)^3 bump upward: position, velocity and acceleration are continuous (C^2) at
lift-off and touch-down. Footholds: the feet of ``gait_posture`` (the paper's standing posture;
for other robots a crouch with each foot under its HFE joint at CROUCH of the leg's length),
shifted so that each foot is under that point in the middle of its stance.

Experiment: analytic IK (DH leg) or numeric IK -> q, qd, qdd -> id_r -> tau(t); forward
dynamics fd_r with tau(t), integrated by classical RK4 with a fixed step from the IK state at
t = 0; the trunk orientation follows from the stance legs, the footholds and the roll
coordinate at every evaluation (``kinematics.pose_from_feet``). For the trot, two runs:
* ``paper``: tau_ext = all 13 entries of id_r, the roll moment applied as if actuated -- the
  paper's check, which compares the inverse/forward pair with itself;
* ``physical``: tau_ext = (tau, 0): the roll is unactuated, as on the robot.
The static walk has no unactuated coordinate (three feet: the paper's GRF model has rank 6),
so one run is both.
Percentage error of a signal x: max_t |x_sim - x_ref| / max_t |x_ref| x 100. The trot is open-
loop unstable in roll (an unactuated run is 1 % off within ~0.06 s on the paper's robot), so
even the ``paper`` run's error is RK4's O(dt^4) error amplified by that instability: measured
on the paper robot over 1.2 s, the largest joint-angle error is 1.6 / 0.096 / 0.006 % at
dt = 2 / 1 / 0.5 ms (BR HFE: 2.4e-2 / 1.5e-3 / 8.6e-5 %).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cache

import numpy as np
import pinocchio as pin

from .errors import InputError
from .evaluate import evaluate
from .grf import StanceSet
from .kinematics import analytic_ik, numeric_ik, pose_from_feet, robot_kinematics
from .reduced import reduced_model
from .robot import Robot

#: A reference signal whose largest |value| is below this fraction of the largest joint's is
#: treated as identically zero (IK round-off, ~1e-16 rad/s, would give absurd percentages).
ZERO_SIGNAL = 1e-9

#: A simulation stops when a stance foot is this far from its foothold (m): the gait has
#: failed (the robot rolls over), and integrating further only produces overflow.
FALLEN_CLOSURE_M = 0.1

#: Crouch of the trot posture of URDF robots: feet this fraction of (thigh + shank) below the
#: HFE joint, far enough from full extension for the legs' Jacobians to stay well conditioned.
CROUCH = 0.75


@cache
def gait_posture(robot: Robot) -> np.ndarray:
    """Joint angles (12,) the trot is built around (see the module docstring)."""
    if robot.name == "paper":
        return robot.standing_q
    q = np.zeros(12)
    for i, leg in enumerate(robot.legs):
        hfe = (leg.joints[0].placement @ leg.joints[1].placement).p
        neutral_foot = leg.foot_position(robot.standing_q[3 * i : 3 * i + 3])
        length = np.linalg.norm(leg.joints[2].placement.p) + np.linalg.norm(leg.foot.p)
        target = np.array([hfe[0], neutral_foot[1], hfe[2] - CROUCH * length])
        lower, upper = np.array([j.lower for j in leg.joints]), np.array([j.upper for j in leg.joints])
        for guess in ([0.0, 0.7, -1.4], [0.0, -0.7, 1.4]):  # knee bent one way, then the other
            try:
                qi = numeric_ik(robot, i, target, np.clip(guess, lower, upper))
            except InputError:
                continue
            if np.all(qi >= lower - 1e-9) and np.all(qi <= upper + 1e-9):
                q[3 * i : 3 * i + 3] = qi
                break
        else:
            raise InputError(f"no crouched trot posture within joint limits for leg {leg.label} of {robot.name}")
    return q


def gait_feet(robot: Robot) -> list[np.ndarray]:
    """Foot positions (trunk frame, m) of ``gait_posture``: where the footholds are centred."""
    return [leg.foot_position(q) for leg, q in zip(robot.legs, gait_posture(robot).reshape(4, 3))]


@dataclass(frozen=True)
class Gait:
    """A periodic gait: ``phases`` lists the stance feet of each equal phase of the cycle; each
    leg swings in exactly one phase per cycle. The trunk moves forward at ``speed``."""

    name: str
    phases: tuple[tuple[int, ...], ...]
    speed: float = 0.2  # m/s, forward
    period: float = 0.6  # s, a full cycle
    step_height: float = 0.04  # m

    @property
    def phase_duration(self) -> float:
        return self.period / len(self.phases)

    @property
    def n_coords(self) -> int:
        """12 joint angles, plus the trunk roll when some phase stands on two feet."""
        return 13 if any(len(p) == 2 for p in self.phases) else 12

    def _phase(self, t: float) -> tuple[int, float]:
        k = int(np.floor(t / self.phase_duration + 1e-12))
        return k, t / self.phase_duration - k

    def stance(self, t: float) -> tuple[int, ...]:
        return self.phases[self._phase(t)[0] % len(self.phases)]

    def foot(self, i: int, t: float, standing: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """World position, velocity, acceleration of foot i (standing = its standing position,
        trunk frame). Foothold m of a leg is under its standing point at the middle of the
        stance that follows its m-th swing."""
        n, h = len(self.phases), self.phase_duration
        k, s = self._phase(t)
        swing_phase = next(j for j, feet in enumerate(self.phases) if i not in feet)
        m = (k - swing_phase) // n  # the leg's latest swing starts at phase m n + swing_phase <= k

        def hold(m: int) -> float:
            return standing[0] + self.speed * ((m * n + swing_phase + 1) * h + (self.period - h) / 2)

        if k % n != swing_phase:
            return np.array([hold(m), standing[1], standing[2]]), np.zeros(3), np.zeros(3)
        x0, dx = hold(m - 1), hold(m) - hold(m - 1)
        smooth = (10 * s**3 - 15 * s**4 + 6 * s**5, (30 * s**2 - 60 * s**3 + 30 * s**4) / h,
                  (60 * s - 180 * s**2 + 120 * s**3) / h**2)
        bump = (64 * s**3 * (1 - s) ** 3, 64 * (3 * s**2 * (1 - s) ** 3 - 3 * s**3 * (1 - s) ** 2) / h,
                64 * (6 * s * (1 - s) ** 3 - 18 * s**2 * (1 - s) ** 2 + 6 * s**3 * (1 - s)) / h**2)
        pos = np.array([x0 + dx * smooth[0], standing[1], standing[2] + self.step_height * bump[0]])
        vel = np.array([dx * smooth[1], 0.0, self.step_height * bump[1]])
        acc = np.array([dx * smooth[2], 0.0, self.step_height * bump[2]])
        return pos, vel, acc


#: The paper's trot: diagonal pairs alternate. Static walk: one leg swings at a time,
#: in the order FL, BR, FR, BL.
TROT = Gait("trot", ((0, 3), (1, 2)))
WALK = Gait("walk", ((1, 2, 3), (0, 1, 2), (0, 2, 3), (0, 1, 3)), speed=0.1, period=1.6)
GAITS = {g.name: g for g in (TROT, WALK)}


@dataclass(frozen=True)
class ReferenceSample:
    q_r: np.ndarray  # (12,) joints, + the roll (= 0) for a gait with two-feet phases
    qd_r: np.ndarray
    qdd_r: np.ndarray
    stance: tuple[int, ...]


def reference(robot: Robot, gait: Gait, t: float, q_guess: np.ndarray | None = None) -> ReferenceSample:
    """IK of the gait at time t: trunk at (speed t, 0, 0), R = I; feet from the gait."""
    kin = robot_kinematics(robot)
    standing = gait_feet(robot)
    guess = gait_posture(robot) if q_guess is None else q_guess
    p, pd = np.array([gait.speed * t, 0.0, 0.0]), np.array([gait.speed, 0.0, 0.0])
    q, qd, qdd = np.zeros(12), np.zeros(12), np.zeros(12)
    for i, leg in enumerate(robot.legs):
        P, Pd, Pdd = gait.foot(i, t, standing[i])
        r, rd, rdd = P - p, Pd - pd, Pdd  # trunk frame = world orientation (R = I), no trunk acceleration
        s = slice(3 * i, 3 * i + 3)
        if robot.name == "paper":
            q[s] = analytic_ik(leg.label, r)
        else:
            q[s] = numeric_ik(robot, i, r, guess[s])
        J = np.asarray(kin[i].foot_jacobian(q[s]))
        qd[s] = np.linalg.solve(J, rd)
        qdd[s] = np.linalg.solve(J, rdd - np.asarray(kin[i].foot_bias_acceleration(q[s], qd[s])).ravel())
    extra = np.zeros(gait.n_coords - 12)  # roll, its rate and acceleration: 0 with R = I
    return ReferenceSample(np.append(q, extra), np.append(qd, extra), np.append(qdd, extra), gait.stance(t))


def _stance_name(stance: tuple[int, ...]) -> str:
    return StanceSet(stance).name


@dataclass
class Simulation:
    t: np.ndarray
    q: np.ndarray  # (N, n) simulated, n = gait.n_coords
    qd: np.ndarray
    qdd: np.ndarray
    q_ref: np.ndarray  # (N, n) from IK
    qd_ref: np.ndarray
    qdd_ref: np.ndarray
    roll_moment: np.ndarray  # (N,) id_r's 13th entry along the reference, N m
    closure_m: np.ndarray  # (N,) largest distance of a stance foot from its foothold, m
    diverged_at: float | None  # s: where the run stopped, fallen or fd_r singular (None: full horizon)

    def percent_error(self, sim: np.ndarray, ref: np.ndarray) -> np.ndarray:
        """Per coordinate: max_t |sim - ref| / max_t |ref| x 100; nan where the reference is
        (numerically) constant zero -- below ZERO_SIGNAL of the largest coordinate's range --
        such as HAA rates in a straight trot, where a percentage means nothing."""
        scale = np.abs(ref).max(axis=0)
        meaningful = scale > ZERO_SIGNAL * scale.max()
        with np.errstate(invalid="ignore", divide="ignore"):
            return np.where(meaningful, np.abs(sim - ref).max(axis=0) / scale * 100, np.nan)

    def departure_time(self, percent: float = 1.0) -> float | None:
        """First time a joint angle is off its IK value by more than ``percent`` of the largest
        |joint angle| of the reference (one scale for all joints: an HAA held at 0 has none of
        its own); None if never within the run."""
        scale = np.abs(self.q_ref[:, :12]).max()
        off = np.abs(self.q[:, :12] - self.q_ref[:, :12]) > percent / 100 * scale
        rows = np.flatnonzero(off.any(axis=1))
        return float(self.t[rows[0]]) if rows.size else None


@dataclass
class ValidationReport:
    robot: str
    gait: str
    horizon_s: float
    dt_s: float
    integrator: str = "classical RK4, fixed step"
    runs: dict[str, dict[str, list[float]]] = field(default_factory=dict)  # run -> signal -> % error per joint
    max_roll_moment_Nm: float = 0.0
    max_closure_m: dict[str, float] = field(default_factory=dict)
    diverged_at_s: dict[str, float | None] = field(default_factory=dict)
    departs_1pct_at_s: dict[str, float | None] = field(default_factory=dict)


def simulate(robot: Robot, gait: Gait, horizon: float, dt: float, roll_actuated: bool) -> Simulation:
    """Integrate fd_r under the IK torques from the IK state at t = 0 (see module docstring).
    ``roll_actuated`` only matters for gaits with two-feet phases (the roll coordinate)."""
    models = {_stance_name(p): reduced_model(robot, _stance_name(p)) for p in gait.phases}
    n = int(round(horizon / dt))
    times = np.arange(n + 1) * dt
    refs: list[ReferenceSample] = []
    guess = None
    for t in times:
        refs.append(reference(robot, gait, float(t), guess))
        guess = refs[-1].q_r[:12]

    def tau_ext(t: float, stance: tuple[int, ...], ref_sample: ReferenceSample | None = None) -> tuple[np.ndarray, float]:
        """IK torques at t for the given stance (an RK stage at a switch keeps the step's stance),
        and the roll moment id_r asks for (0 without a roll coordinate)."""
        r = ref_sample or reference(robot, gait, t, guess)
        m = models[_stance_name(stance)]
        (tau_r,) = evaluate(m.id_r, r.q_r, r.qd_r, r.qdd_r, np.array([0.0, 0.0, 0.0, 1.0]))
        if m.n == 12:
            return np.append(tau_r, np.zeros(gait.n_coords - 12)), 0.0
        return (tau_r if roll_actuated else np.append(tau_r[:12], 0.0)), float(tau_r[12])

    kin = robot_kinematics(robot)
    standing = gait_feet(robot)
    pitch = [0.0]  # the previous pose's pitch picks between the two-feet pose solutions

    def pose(t: float, q: np.ndarray, stance: tuple[int, ...]) -> tuple[np.ndarray, float]:
        """Trunk orientation from the stance legs and the roll coordinate (SPEC section 5), and
        the closure error: how far the stance legs are from their footholds."""
        feet = np.array([np.asarray(kin[i].foot_position(q[3 * i : 3 * i + 3])).ravel() for i in stance])
        holds = np.array([gait.foot(i, t, standing[i])[0] for i in stance])
        roll = float(q[12]) if len(stance) == 2 else None
        R, _, closure = pose_from_feet(feet, holds, roll=roll, pitch_hint=pitch[0])
        return pin.Quaternion(R).coeffs(), closure

    def qdd_of(t: float, q: np.ndarray, qd: np.ndarray, stance: tuple[int, ...]) -> np.ndarray:
        tau, _ = tau_ext(t, stance)
        (qdd,) = evaluate(models[_stance_name(stance)].fd_r, q, qd, tau, pose(t, q, stance)[0])
        return qdd

    q, qd = refs[0].q_r.copy(), refs[0].qd_r.copy()
    out_q, out_qd, out_qdd, roll, closure = [], [], [], [], []
    diverged_at = None
    for k, t in enumerate(times):
        stance = gait.stance(float(t))
        tau, roll_k = tau_ext(float(t), stance, refs[k])
        try:
            quat, closure_k = pose(float(t), q, stance)
            pitch[0] = float(pin.rpy.matrixToRpy(pin.Quaternion(quat).toRotationMatrix())[1])
            (qdd,) = evaluate(models[_stance_name(stance)].fd_r, q, qd, tau, quat)
        except InputError:  # the state left the model's domain: report where
            diverged_at = float(t)
            break
        out_q.append(q.copy())
        out_qd.append(qd.copy())
        out_qdd.append(qdd)
        roll.append(roll_k)
        closure.append(closure_k)
        if closure_k > FALLEN_CLOSURE_M:  # a stance foot far off its foothold: the trot has failed
            diverged_at = float(t)
            break
        if k == n:
            break
        # RK4 within one stance phase (the step never straddles a switch: dt divides a phase)
        try:
            k1 = (qd, qdd)
            k2 = (qd + dt / 2 * k1[1], qdd_of(t + dt / 2, q + dt / 2 * k1[0], qd + dt / 2 * k1[1], stance))
            k3 = (qd + dt / 2 * k2[1], qdd_of(t + dt / 2, q + dt / 2 * k2[0], qd + dt / 2 * k2[1], stance))
            k4 = (qd + dt * k3[1], qdd_of(t + dt, q + dt * k3[0], qd + dt * k3[1], stance))
        except InputError:
            diverged_at = float(t)
            break
        q = q + dt / 6 * (k1[0] + 2 * k2[0] + 2 * k3[0] + k4[0])
        qd = qd + dt / 6 * (k1[1] + 2 * k2[1] + 2 * k3[1] + k4[1])
    m_ = len(out_q)
    return Simulation(times[:m_], np.array(out_q), np.array(out_qd), np.array(out_qdd),
                      np.array([r.q_r for r in refs[:m_]]), np.array([r.qd_r for r in refs[:m_]]),
                      np.array([r.qdd_r for r in refs[:m_]]), np.array(roll), np.array(closure), diverged_at)


def validate(robot: Robot, gait: Gait = TROT, horizon: float = 1.2, dt: float = 5e-4,
             plot_path: str | None = None) -> tuple[ValidationReport, dict[str, Simulation]]:
    """Run the experiment -- for a gait with a roll coordinate both ways (roll moment applied,
    roll unactuated); otherwise once, where the two coincide -- and optionally plot BR HFE
    (the paper's Figs. 5-7)."""
    sims = {"paper": simulate(robot, gait, horizon, dt, roll_actuated=True)}
    if gait.n_coords == 13:
        sims["physical"] = simulate(robot, gait, horizon, dt, roll_actuated=False)
    report = ValidationReport(robot.name, gait.name, horizon, dt)
    for name, sim in sims.items():
        report.runs[name] = {
            "acceleration": sim.percent_error(sim.qdd, sim.qdd_ref)[:12].tolist(),
            "velocity": sim.percent_error(sim.qd, sim.qd_ref)[:12].tolist(),
            "displacement": sim.percent_error(sim.q, sim.q_ref)[:12].tolist(),
        }
        report.max_closure_m[name] = float(sim.closure_m.max())
        report.diverged_at_s[name] = sim.diverged_at
        report.departs_1pct_at_s[name] = sim.departure_time(1.0)
    report.max_roll_moment_Nm = float(np.abs(sims["paper"].roll_moment).max())
    if plot_path:
        plot_br_hfe(sims, robot, plot_path, gait.name)
    return report, sims


def plot_br_hfe(sims: dict[str, Simulation], robot: Robot, path: str, gait_name: str = "trot") -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    j = 3 * 3 + 1  # BR HFE
    fig, axes = plt.subplots(3, 1, figsize=(8, 8), sharex=True)
    ref = sims["paper"]
    for ax, key, label in zip(axes, ("qdd", "qd", "q"), ("acceleration (rad/s²)", "velocity (rad/s)", "displacement (rad)")):
        ax.plot(ref.t, getattr(ref, key + "_ref")[:, j], "k-", lw=2.5, label="inverse kinematics")
        applied = "forward dynamics, roll moment applied (paper)" if "physical" in sims else "forward dynamics"
        ax.plot(ref.t, getattr(ref, key)[:, j], "C1--", lw=1.5, label=applied)
        if "physical" in sims:
            phys = sims["physical"]
            departs = phys.departure_time(1.0)
            note = f" (1 % off at {departs:.3f} s)" if departs is not None else ""
            ax.plot(phys.t, getattr(phys, key)[:, j], "C0:", lw=1.5, label="forward dynamics, roll unactuated" + note)
        lo, hi = getattr(ref, key + "_ref")[:, j].min(), getattr(ref, key + "_ref")[:, j].max()
        ax.set_ylim(lo - 0.3 * (hi - lo), hi + 0.3 * (hi - lo))  # the unactuated run leaves the frame as it falls
        ax.set_ylabel(label)
        ax.grid(alpha=0.3)
    axes[0].set_title(f"BR HFE ({robot.legs[3].joints[1].name} of {robot.name}), {gait_name}")
    axes[0].legend(fontsize=8)
    axes[-1].set_xlabel("time (s)")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
