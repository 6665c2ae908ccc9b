"""One periodic gait cycle on the reduced model, transcribed as a nonlinear program (docs/optimal_control.md).

Method: direct collocation in inverse-dynamics form. The motion is a piecewise quintic
Hermite trajectory (``hermite``) of the 18 coordinates of ``node`` (12 joints, the roll -- the
trot's 13th reduced coordinate -- pitch, yaw, trunk position) through K = phases x nodes-per-phase
nodes over one cycle of the plan's period; the decision variables are the values, rates and
accelerations at the nodes (3 x 18 per node) and the footholds' (x, y) within FOOTHOLD_BOUND_M
of the plan's. The phase timing is the plan's (not optimised). Torques are not variables: they
are the reduced inverse dynamics id_r of the motion. The dynamics enter as constraints at the
collocation points -- every node and every interval's INTERIOR_POINTS (the interpolant
evaluated there). Within a phase the jerk is continuous at the nodes (a C^3 quintic spline), at
a switch the motion is C^2 as in the plan:

* roll unactuated (two stance feet): id_r's 13th entry = 0, the moment about the foot-to-foot
  line that the paper's trot leaves to an actuator that does not exist;
* effort |tau_j| <= the URDF's effort limit (a robot without one, e.g. solo12's 1000 N m
  placeholder, is limited by it anyway);
* the paper's GRF in the friction cone: f_z >= FZ_MIN_FRACTION of the weight on every stance
  foot and mu^2 f_z^2 >= f_x^2 + f_y^2 (world frame, flat ground);
* static walk (three stance feet): the CoM's ground projection at least MIN_COM_MARGIN_M inside
  the support triangle, as today's plan guarantees;
* stance feet pinned to their footholds (world position, velocity and acceleration zero);
  at a phase switch all four feet are down, the constraints of both phases apply there;
* swing feet above the ground by at least CLEARANCE_FRACTION of the plan's bump at every node;
* joint angles and rates within the URDF's limits (bounds); trunk angles within TRUNK_ANGLE_RAD,
  trunk height within TRUNK_HEIGHT_M of the plan's;
* periodicity: node K (the next cycle's first) is node 0 moved forward by speed x period, and
  every foothold moves forward by the same: the plan's forward speed.

Objective (per cycle, trapezoid rule in time): W_EFFORT * integral sum_j (tau_j / tau_ref)^2 dt,
tau_ref = m g l (robot weight times leg length), plus W_PLAN * integral of |joints - plan|^2
(rad^2) + |trunk angles|^2 (rad^2) + |(p - p_plan) / 0.1 m|^2 dt, plus W_SMOOTH on the
integral of the squared jerk / omega^3 (omega = 2 pi / period; Simpson's rule per interval), which
keeps the interpolant from ringing between collocation points.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from typing import Any

import casadi as ca
import numpy as np

from quadruped_dyn.arguments import real_number, whole_number
from quadruped_dyn.dynamics.grf import MAX_FRICTION_COEFFICIENT
from quadruped_dyn.errors import InputError
from quadruped_dyn.experiment.gait import Gait, Plan, gait_plan
from quadruped_dyn.experiment.plan_ik import ik_target
from quadruped_dyn.model.actuator_limits import actuator_limit, actuator_limits
from quadruped_dyn.model.robot import Robot
from quadruped_dyn.model.stance import StanceSet
from quadruped_dyn.model.state import GRAVITY_W
from quadruped_dyn.optimal_control.hermite import weights
from quadruped_dyn.optimal_control.node import N_X, node_functions

#: Friction coefficient of the cone (rubber feet on a dry floor are ~0.8-1; 0.6 leaves margin).
MU = 0.6
#: Smallest normal force on a stance foot, fraction of the robot's weight: a foot that carries
#: less is about to slip or lift in any real contact.
FZ_MIN_FRACTION = 0.05
#: Static walk: CoM projection at least this far inside the support triangle (today's plan: >= 2 cm).
MIN_COM_MARGIN_M = 0.02
#: A swing foot stays above this fraction of the plan's bump (64 s^3 (1 - s)^3 step height).
CLEARANCE_FRACTION = 0.5
#: Footholds move at most this far (x and y) from the plan's, m.
FOOTHOLD_BOUND_M = 0.03
#: Trunk roll, pitch and yaw bounds (rad), and the trunk height's distance from the plan's (m).
TRUNK_ANGLE_RAD = 0.3
TRUNK_HEIGHT_M = 0.03
#: Objective weights (module docstring): effort per s, closeness to the plan per rad^2 s, smoothness.
W_EFFORT = 1.0
W_PLAN = 1.0
W_SMOOTH = 1e-2
#: Fewest nodes per phase: below this the collocation points are too sparse for the swing's bump.
MIN_NODES_PER_PHASE = 3
#: More nodes per phase than this is refused before any work: the default's 4 transcribe and solve in
#: ~10 s (paper trot); the variables grow linearly and IPOPT's factorisations faster, so 10x the
#: default is minutes, and 100,000 never finished transcribing.
MAX_NODES_PER_PHASE = 40
#: Collocation points inside each interval (fractions), besides the nodes: the roll moment and the
#: effort limits are imposed there too. Nodes and midpoints alone leave the interpolant a cubic
#: acceleration mode s (1 - 2 s)(1 - s) that none of them sees (paper trot, 8 nodes per phase: a
#: +-0.18 N m roll moment at the quarter points, the plan needs 1.7 N m; replayed open loop it left
#: 1 % after 0.29 s). With the quarter points too, the largest roll moment sampled anywhere is
#: 7e-4 N m at 4 nodes per phase and the replay stays within 1 % for two cycles on paper, solo12
#: and go2 (docs/optimal_control.md).
INTERIOR_POINTS = (0.25, 0.5, 0.75)
#: Default nodes per phase: with the quarter points, 4 hold the roll defect below 1e-3 N m (8 cost
#: twice as much and did not converge within 500 iterations on solo12).
NODES_PER_PHASE = 4
#: A step (speed x period) longer than this fraction of the leg's length is beyond what the legs reach.
MAX_STEP_FRACTION = 0.6
#: Position scale of the trunk's closeness term, m.
P_SCALE_M = 0.1


@dataclass(frozen=True)
class Options:
    nodes_per_phase: int = NODES_PER_PHASE
    mu: float = MU
    fz_min_fraction: float = FZ_MIN_FRACTION
    interior_points: tuple[float, ...] = INTERIOR_POINTS  # fractions of each interval where the dynamics are collocated too
    speed: float | None = None  # m/s; None: the gait's

    def check(self, robot: Robot, gait: Gait) -> None:
        """InputError for options no solve can satisfy, before any work."""
        if not MIN_NODES_PER_PHASE <= whole_number("--nodes", self.nodes_per_phase) <= MAX_NODES_PER_PHASE:
            raise InputError(f"--nodes {self.nodes_per_phase}; expected {MIN_NODES_PER_PHASE} to {MAX_NODES_PER_PHASE} "
                             "collocation nodes per phase")
        real_number("mu", self.mu)
        real_number("f_z minimum fraction", self.fz_min_fraction)
        if self.speed is not None:
            real_number("speed", self.speed)
        if not (isinstance(self.interior_points, tuple | list)
                and all(0 < real_number("an interior point", s) < 1 for s in self.interior_points)):
            raise InputError(f"interior points {self.interior_points!r}; expected fractions of an interval, each "
                             "strictly between 0 and 1")
        if not (math.isfinite(self.mu) and 0 < self.mu <= MAX_FRICTION_COEFFICIENT):  # mu**2 of 1e300 overflows
            raise InputError(f"mu = {self.mu} is not a friction coefficient the feet can stand on; "
                             f"expected 0 < mu <= {MAX_FRICTION_COEFFICIENT:g}")
        if not (math.isfinite(self.fz_min_fraction) and 0 <= self.fz_min_fraction < 1 / len(gait.phases[0])):
            raise InputError(f"f_z minimum {self.fz_min_fraction} of the weight per foot cannot be carried; "
                             f"expected 0 <= fraction < {1 / len(gait.phases[0]):.2f}")
        actuator_limits(robot)  # the effort and joint-rate bounds of every node
        speed = gait.speed if self.speed is None else self.speed
        reach = leg_length(robot)
        if not (math.isfinite(speed) and 0 <= speed * gait.period <= MAX_STEP_FRACTION * reach):
            top = MAX_STEP_FRACTION * reach / gait.period
            raise InputError(f"speed {speed} m/s is beyond what {robot.name}'s legs allow for a {gait.period} s cycle; "
                             f"expected 0 <= speed <= {top:.2f} m/s (a step of at most {MAX_STEP_FRACTION:g} leg lengths)")


def leg_length(robot: Robot) -> float:
    """Thigh + shank of the first leg, m."""
    leg = robot.legs[0]
    return float(np.linalg.norm(leg.joints[2].placement.p) + np.linalg.norm(leg.foot.p))


def _bump(s: float) -> float:
    return 64 * s**3 * (1 - s) ** 3


@dataclass(frozen=True)
class Piece:
    """One block of constraints: g[start:stop] = fun(A w + b).g, objective += weight_dt * fun(...).effort."""

    fun: ca.Function
    A: ca.DM
    b: np.ndarray
    start: int
    stop: int
    weight_dt: float


@dataclass
class Transcription:
    """The NLP of one gait cycle: nlpsol's dict, bounds, the warm start and how to read a solution."""

    robot: Robot
    gait: Gait
    plan: Plan
    options: Options
    speed: float
    h: float  # node spacing, s
    n_nodes: int  # K
    nlp: dict
    lbw: np.ndarray
    ubw: np.ndarray
    lbg: np.ndarray
    ubg: np.ndarray
    w0: np.ndarray
    groups: dict[str, list[tuple[int, int, int]]] = field(default_factory=dict)  # name -> (node, start, stop) of g
    outputs: ca.Function | None = None  # w -> tau (12, P (N + 1)), roll, effort, ...
    x_plan: np.ndarray | None = None  # (18, K) the plan's coordinates at the nodes (the warm start)
    pieces: list[Piece] = field(default_factory=list)  # the nonlinear blocks of g (and of the effort), for the derivatives
    linear: tuple[ca.DM, int] | None = None  # (A, start): g[start:] = A w + b, the spline's continuity rows
    quadratic_hessian: ca.DM | None = None  # of the objective's quadratic part (closeness, smoothness)
    build_seconds: float = 0.0

    def unpack(self, w: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """(X, Xd, Xdd (18, K), footholds (2, 4) offsets from the plan's, m)."""
        K = self.n_nodes
        w = np.asarray(w, dtype=float).ravel()
        X, Xd, Xdd = (w[i * N_X * K : (i + 1) * N_X * K].reshape(K, N_X).T for i in range(3))
        return X, Xd, Xdd, w[3 * N_X * K :].reshape(4, 2).T

    def phase_of(self, k: int) -> tuple[int, ...]:
        """The phases node k belongs to (two at a switch)."""
        N, P = self.options.nodes_per_phase, len(self.gait.phases)
        p = k // N
        return ((p - 1) % P, p) if k % N == 0 else (p,)


def plan_coordinates(plan: Plan, t: float, guess: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The plan's 18 coordinates (joints, roll = pitch = yaw = 0, trunk position), rates, accelerations at t."""
    target = ik_target(plan, t, guess)
    p, pd, pdd = plan.trunk(t)
    z3 = np.zeros(3)
    return (np.concatenate([target.q_r[:12], z3, p]), np.concatenate([target.qd_r[:12], z3, pd]),
            np.concatenate([target.qdd_r[:12], z3, pdd]))


Layout = list[tuple[str, int, np.ndarray, np.ndarray]]


def _layout(rows: list[tuple[str, ca.SX, Any, Any]]) -> Layout:
    """(name, size, lower bounds, upper bounds) of each block of rows."""
    return [(n, int(ca.vec(e).shape[0]), np.broadcast_to(np.asarray(lo, float), (int(ca.vec(e).shape[0]),)).copy(),
             np.broadcast_to(np.asarray(hi, float), (int(ca.vec(e).shape[0]),)).copy()) for n, e, lo, hi in rows]


@dataclass
class _Cycle:
    """What every block of the NLP reads: the gait cycle, its nodes, the decision vector w and the plan's values."""

    robot: Robot
    gait: Gait
    options: Options
    plan: Plan
    speed: float
    P: int  # phases
    N: int  # nodes per phase
    K: int  # nodes
    h: float  # node spacing, s
    shift: float  # how far the gait moves in one cycle, m
    holds0: np.ndarray  # (4, 3) the footholds at t = 0, world
    nw: int
    w: ca.MX

    @staticmethod
    def of(robot: Robot, gait: Gait, options: Options) -> _Cycle:
        speed = gait.speed if options.speed is None else options.speed
        if speed != gait.speed:
            gait = Gait(gait.name, gait.phases, speed, gait.period, gait.step_height, gait.sway)
        plan = gait_plan(robot, gait)
        P, N = len(gait.phases), options.nodes_per_phase
        K = P * N
        nw = 3 * N_X * K + 8
        return _Cycle(robot, gait, options, plan, speed, P, N, K, gait.period / K, speed * gait.period,
                      np.array([plan.foot(i, 0.0)[0] for i in range(4)]), nw, ca.MX.sym("w", nw))

    def node_map(self, k: int) -> tuple[np.ndarray, np.ndarray]:
        """(A (54, nw), b (54,)): the node's (x, xd, xdd) = A w + b (node K: node 0 moved forward)."""
        K, j = self.K, k % self.K
        A = np.zeros((3 * N_X, self.nw))
        for i in range(3):
            A[i * N_X : (i + 1) * N_X, i * N_X * K + j * N_X : i * N_X * K + (j + 1) * N_X] = np.eye(N_X)
        b = np.zeros(3 * N_X)
        if k >= K:
            b[15] = self.shift
        return A, b

    def interval(self, k0: int) -> tuple[list[np.ndarray], list[np.ndarray]]:
        """The six (x, xd, xdd at node k0, then at k0 + 1) blocks of A and of b."""
        (A0, b0), (A1, b1) = self.node_map(k0), self.node_map(k0 + 1)
        return ([A0[i * N_X : (i + 1) * N_X] for i in range(3)] + [A1[i * N_X : (i + 1) * N_X] for i in range(3)],
                [b0[i * N_X : (i + 1) * N_X] for i in range(3)] + [b1[i * N_X : (i + 1) * N_X] for i in range(3)])


def _warm_start(cycle: _Cycle) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The plan's coordinates, rates and accelerations at the nodes (18, K) each; InputError if the plan leaves the
    joint limits."""
    robot, K = cycle.robot, cycle.K
    Xp, Xdp, Xddp = np.zeros((N_X, K)), np.zeros((N_X, K)), np.zeros((N_X, K))
    guess = None
    for k in range(K):
        Xp[:, k], Xdp[:, k], Xddp[:, k] = plan_coordinates(cycle.plan, k * cycle.h, guess)
        guess = Xp[:12, k]
    if np.any(Xp[:12] < robot.lower[:, None] - 1e-9) or np.any(Xp[:12] > robot.upper[:, None] + 1e-9):
        raise InputError(f"the {cycle.gait.name} plan of {robot.name} leaves the joint limits at speed {cycle.speed} m/s; "
                         "expected a slower gait")
    return Xp, Xdp, Xddp


class _PointFunctions:
    """One SX Function per (phase, feet pinned there) for a node, one per phase for a midpoint; the NLP (MX) calls
    them, so each is differentiated once, not once per node."""

    def __init__(self, cycle: _Cycle) -> None:
        robot, gait = cycle.robot, cycle.gait
        self.cycle = cycle
        self.nf = node_functions(robot, gait.phases)
        weight = robot.total_mass * -GRAVITY_W[2]
        self.fz_min = cycle.options.fz_min_fraction * weight
        self.tau_ref = weight * leg_length(robot)
        self.effort_limit = actuator_limit(robot, "effort")
        self.swing_phase = [gait.swing_phase(i) for i in range(4)]
        self.ground = cycle.holds0[:, 2]
        self.cache: dict[tuple, tuple[ca.Function, Layout]] = {}

    def hold(self, i: int, p: int, Hv: ca.SX) -> ca.SX:
        """World foothold of foot i during (or at the start of) phase p."""
        holds0 = self.cycle.holds0
        x0 = holds0[i, 0] + Hv[0, i] + (self.cycle.shift if p > self.swing_phase[i] else 0.0)
        return ca.vertcat(x0, holds0[i, 1] + Hv[1, i], self.ground[i])

    def _com_margins(self, p: int, stance: tuple[int, ...], Hs: ca.SX, com: ca.SX) -> list[tuple[str, ca.SX, Any, Any]]:
        """The CoM's distance inside each edge of the support triangle, the inside told by the plan's triangle."""
        holds0, shift = self.cycle.holds0, self.cycle.shift
        tri = [self.hold(i, p, Hs) for i in stance]
        plan_tri = [holds0[i, :2] + (shift if p > self.swing_phase[i] else 0.0) * np.array([1.0, 0.0]) for i in stance]
        rows: list[tuple[str, ca.SX, Any, Any]] = []
        for a, b, c in ((0, 1, 2), (1, 2, 0), (2, 0, 1)):
            edge = tri[b][:2] - tri[a][:2]
            normal = ca.vertcat(-edge[1], edge[0]) / ca.norm_2(edge)
            e_plan = plan_tri[b] - plan_tri[a]  # which side is inside: the plan's triangle (footholds move little)
            side = float(np.sign(np.array([-e_plan[1], e_plan[0]]) @ (plan_tri[c] - plan_tri[a])))
            rows.append(("com_margin", side * ca.dot(normal, com[:2] - tri[a][:2]), MIN_COM_MARGIN_M, np.inf))
        return rows

    def node_point(self, p: int, pinned: tuple[int, ...]) -> tuple[ca.Function, Layout]:
        """(Function x, xd, xdd, H -> g, effort density, tau, roll; layout of g: name, size, lo, hi).
        The clearance rows' lower bound is set per node (layout gives 0)."""
        key = ("node", p, pinned)
        if key in self.cache:
            return self.cache[key]
        z = ca.SX.sym("z", 3 * N_X + 8)
        xs = (z[:N_X], z[N_X : 2 * N_X], z[2 * N_X : 3 * N_X])
        Hs = ca.reshape(z[3 * N_X :], 2, 4)
        stance = self.cycle.gait.phases[p]
        tau, roll, f = self.nf.dynamics[stance](*xs)
        rows: list[tuple[str, ca.SX, Any, Any]] = []
        if len(stance) == 2:
            rows.append(("roll_moment", roll, 0.0, 0.0))
        rows.append(("effort", tau, -self.effort_limit, self.effort_limit))
        F = ca.reshape(f, 3, len(stance))
        rows.append(("fz_min", F[2, :], self.fz_min, np.inf))
        rows.append(("friction", self.cycle.options.mu**2 * F[2, :] ** 2 - F[0, :] ** 2 - F[1, :] ** 2, 0.0, np.inf))
        feet, feet_d, feet_dd, com = self.nf.kinematics(*xs)
        if len(stance) == 3:
            rows += self._com_margins(p, stance, Hs, com)
        for i in pinned:
            rows.append(("stance_foot", ca.vertcat(feet[:, i] - self.hold(i, p, Hs), feet_d[:, i], feet_dd[:, i]), 0.0, 0.0))
        for i in range(4):
            if i not in stance:
                rows.append(("clearance", feet[2, i] - self.ground[i], 0.0, np.inf))
        fun = ca.Function(f"node_point_{p}_{''.join(map(str, pinned))}", [z],
                          [ca.vertcat(*[ca.vec(e) for _, e, _, _ in rows]), ca.sumsqr(tau) / self.tau_ref**2, tau, roll],
                          ["z"], ["g", "effort", "tau", "roll"], {"cse": True})
        self.cache[key] = (fun, _layout(rows))
        return self.cache[key]

    def mid_point(self, p: int) -> tuple[ca.Function, Layout]:
        """(Function of the interpolant's x, xd, xdd at a point between nodes -> g, 0, tau, roll; layout of g)."""
        key = ("mid", p)
        if key in self.cache:
            return self.cache[key]
        z = ca.SX.sym("z", 3 * N_X)  # the interpolant's (x, xd, xdd) at the midpoint
        xs = (z[:N_X], z[N_X : 2 * N_X], z[2 * N_X :])
        stance = self.cycle.gait.phases[p]
        tau, roll, _ = self.nf.dynamics[stance](*xs)
        rows: list[tuple[str, ca.SX, Any, Any]] = [("roll_moment_midpoint", roll, 0.0, 0.0)] if len(stance) == 2 else []
        rows.append(("effort_midpoint", tau, -self.effort_limit, self.effort_limit))
        fun = ca.Function(f"mid_point_{p}", [z], [ca.vertcat(*[ca.vec(e) for _, e, _, _ in rows]), ca.SX(0), tau, roll],
                          ["z"], ["g", "effort", "tau", "roll"], {"cse": True})
        self.cache[key] = (fun, _layout(rows))
        return self.cache[key]


@dataclass
class _Constraints:
    """g, its bounds and groups as they are placed, the effort integral, the torques and roll moments per point."""

    cycle: _Cycle
    g: list[ca.MX] = field(default_factory=list)
    lbg: list[np.ndarray] = field(default_factory=list)
    ubg: list[np.ndarray] = field(default_factory=list)
    groups: dict[str, list[tuple[int, int, int]]] = field(default_factory=dict)
    size: int = 0
    effort: ca.MX = field(default_factory=lambda: ca.MX(0))
    taus: list[ca.MX] = field(default_factory=list)
    rolls: list[ca.MX] = field(default_factory=list)
    pieces: list[Piece] = field(default_factory=list)

    def place(self, k: int, fun: ca.Function, layout: Layout, A: np.ndarray, b: np.ndarray, weight_dt: float,
              s_phase: float | None = None) -> None:
        """``fun`` at the point A w + b of node k: its rows into g (the clearance's lower bound by the swing's
        progress ``s_phase``), its effort density times ``weight_dt`` into the effort."""
        out, dens, tau, roll = fun(ca.mtimes(ca.DM(ca.sparsify(ca.DM(A))), self.cycle.w) + b)
        start = self.size
        self.g.append(out)
        for name, m, lo, hi in layout:
            lo = lo.copy()
            if name == "clearance" and s_phase is not None and 0 < s_phase < 1:
                lo[:] = CLEARANCE_FRACTION * self.cycle.gait.step_height * _bump(s_phase)
            self.lbg.append(lo)
            self.ubg.append(hi)
            self.groups.setdefault(name, []).append((k, self.size, self.size + m))
            self.size += m
        self.pieces.append(Piece(fun, ca.sparsify(ca.DM(A)), b, start, self.size, weight_dt))
        self.effort = self.effort + weight_dt * dens
        self.taus.append(tau)
        self.rolls.append(roll)

    def add_linear(self, k: int, name: str, A: np.ndarray, b: np.ndarray) -> None:
        """Rows A w + b = 0 of node k."""
        self.g.append(ca.mtimes(ca.sparsify(ca.DM(A)), self.cycle.w) + b)
        self.lbg.append(np.zeros(A.shape[0]))
        self.ubg.append(np.zeros(A.shape[0]))
        self.groups.setdefault(name, []).append((k, self.size, self.size + A.shape[0]))
        self.size += A.shape[0]


def _place_nodes(cycle: _Cycle, points: _PointFunctions, cons: _Constraints) -> None:
    """Every node's constraints (two phases' at a switch: the ending one with its feet, the starting one with the
    feet it adds)."""
    K, N, P, nw, gait = cycle.K, cycle.N, cycle.P, cycle.nw, cycle.gait
    H_index = np.arange(3 * N_X * K, nw)
    for k in range(K):
        switch = k % N == 0
        phases = (((k // N) - 1) % P, k // N) if switch else (k // N,)
        for p in phases:
            at_end = switch and p != k // N
            stance = gait.phases[p]
            pinned = stance if not (switch and not at_end) else tuple(i for i in stance if i not in gait.phases[phases[0]])
            fun, layout = points.node_point(p, pinned)
            A, b = cycle.node_map(K if (k == 0 and at_end) else k)  # the previous cycle's last phase ends at node K
            AH = np.zeros((8, nw))
            AH[:, H_index] = np.eye(8)
            cons.place(k, fun, layout, np.vstack([A, AH]), np.concatenate([b, np.zeros(8)]),
                       cycle.h / 2 if switch else cycle.h, 1.0 if at_end else (k - p * N) / N)


def _place_interior_points(cycle: _Cycle, points: _PointFunctions, cons: _Constraints) -> None:
    """The dynamics' rows at the interior points of every interval, on the Hermite interpolant of its two nodes."""
    for s_interior in cycle.options.interior_points:
        W = weights(s_interior, cycle.h)  # (3, 6)
        for k in range(cycle.K):
            fun, layout = points.mid_point(k // cycle.N)
            blocks0, offs = cycle.interval(k)
            A = np.vstack([sum(W[m, j] * blocks0[j] for j in range(6)) for m in range(3)])
            b = np.concatenate([sum(W[m, j] * offs[j] for j in range(6)) for m in range(3)])
            cons.place(k, fun, layout, A, b, 0.0)


def _place_spline_continuity(cycle: _Cycle, cons: _Constraints) -> tuple[ca.DM, int]:
    """Within a phase the motion is a quintic spline: jerk continuous at the nodes inside it (linear rows; without
    them the node accelerations are free to make the interpolant ring between collocation points). At a switch,
    where the contacts change, C^2 as in the plan. Returns (A, start): g[start:] = A w + b."""
    ends0, ends1 = weights(0.0, cycle.h, 5)[3:], weights(1.0, cycle.h, 5)[3:]
    linear_start, linear_rows = cons.size, []
    for k in range(cycle.K):
        if k % cycle.N == 0:
            continue
        (left, lb), (right, rb) = cycle.interval(k - 1), cycle.interval(k)
        for m in range(1):  # jerk (C^3); snap continuity too over-determines the pinned stance feet
            A = sum(ends1[m, j] * left[j] - ends0[m, j] * right[j] for j in range(6))
            b = sum(ends1[m, j] * lb[j] - ends0[m, j] * rb[j] for j in range(6))
            linear_rows.append(A)
            cons.add_linear(k, "spline_continuity", A, b)
    return ca.sparsify(ca.DM(np.vstack(linear_rows))), linear_start


def _quadratic_terms(cycle: _Cycle, Xp: np.ndarray, Xdp: np.ndarray, Xddp: np.ndarray) -> tuple[ca.MX, ca.MX]:
    """(closeness to the plan, smoothness: the squared jerk's integral), each in units of the cycle's frequency."""
    K, h, w = cycle.K, cycle.h, cycle.w
    X, Xd, Xdd = (ca.reshape(w[i * N_X * K : (i + 1) * N_X * K], N_X, K) for i in range(3))
    closeness: ca.MX = ca.MX(0)
    smooth: ca.MX = ca.MX(0)
    omega = 2 * np.pi / cycle.gait.period  # rates and accelerations compared in units of the cycle's frequency
    for k in range(K):
        for x_, target, scale in ((X[:, k], Xp[:, k], 1.0), (Xd[:, k], Xdp[:, k], omega), (Xdd[:, k], Xddp[:, k], omega**2)):
            d = (x_ - target) / scale
            closeness += h * (ca.sumsqr(d[:15]) + ca.sumsqr(d[15:18] / P_SCALE_M))
        (blk, off) = cycle.interval(k)
        for s_ in (0.0, 0.5, 1.0):  # Simpson's rule for the integral of the squared jerk, in units of omega^3
            Wj = weights(s_, h, 4)[3]
            jerk = ca.mtimes(ca.sparsify(ca.DM(sum(Wj[j] * blk[j] for j in range(6)))), w) + sum(Wj[j] * off[j] for j in range(6))
            smooth += (h / 6) * (4 if s_ == 0.5 else 1) * ca.sumsqr(jerk / omega**3)
    return closeness, smooth


def _variable_bounds(cycle: _Cycle, Xp: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(lbw, ubw): joint limits, the trunk's angles and height about the plan's, joint rate limits, footholds."""
    robot, K, big = cycle.robot, cycle.K, np.inf
    rate_limit = actuator_limit(robot, "velocity")
    lo_x = np.full((N_X, K), -big)
    hi_x = np.full((N_X, K), big)
    lo_x[:12], hi_x[:12] = robot.lower[:, None], robot.upper[:, None]
    lo_x[12:15], hi_x[12:15] = -TRUNK_ANGLE_RAD, TRUNK_ANGLE_RAD
    lo_x[17], hi_x[17] = Xp[17] - TRUNK_HEIGHT_M, Xp[17] + TRUNK_HEIGHT_M
    lo_xd = np.full((N_X, K), -big)
    hi_xd = np.full((N_X, K), big)
    lo_xd[:12], hi_xd[:12] = -rate_limit[:, None], rate_limit[:, None]
    lbw = np.concatenate([lo_x.T.ravel(), lo_xd.T.ravel(), np.full(N_X * K, -big), np.full(8, -FOOTHOLD_BOUND_M)])
    ubw = np.concatenate([hi_x.T.ravel(), hi_xd.T.ravel(), np.full(N_X * K, big), np.full(8, FOOTHOLD_BOUND_M)])
    return lbw, ubw


def transcribe(robot: Robot, gait: Gait, options: Options = Options()) -> Transcription:
    """Build the NLP (module docstring); ``options.check`` first."""
    options.check(robot, gait)
    started = time.perf_counter()
    cycle = _Cycle.of(robot, gait, options)
    actuator_limits(robot)  # both checked before the plan's IK
    Xp, Xdp, Xddp = _warm_start(cycle)
    points, cons = _PointFunctions(cycle), _Constraints(cycle)
    _place_nodes(cycle, points, cons)
    _place_interior_points(cycle, points, cons)
    linear = _place_spline_continuity(cycle, cons)
    closeness, smooth = _quadratic_terms(cycle, Xp, Xdp, Xddp)
    quadratic = W_PLAN * closeness + W_SMOOTH * smooth
    objective = W_EFFORT * cons.effort + quadratic
    ws = ca.SX.sym("w", cycle.nw)
    Q = ca.DM(ca.evalf(ca.hessian(ca.Function("q", [cycle.w], [quadratic]).expand()(ws), ws)[0]))
    lbw, ubw = _variable_bounds(cycle, Xp)
    w0 = np.concatenate([Xp.T.ravel(), Xdp.T.ravel(), Xddp.T.ravel(), np.zeros(8)])
    outputs = ca.Function("outputs", [cycle.w], [ca.horzcat(*cons.taus), ca.horzcat(*cons.rolls), cons.effort, closeness],
                          ["w"], ["tau", "roll", "effort", "closeness"])
    nlp = {"x": cycle.w, "f": objective, "g": ca.vertcat(*cons.g)}
    return Transcription(robot, cycle.gait, cycle.plan, options, cycle.speed, cycle.h, cycle.K, nlp, lbw, ubw,
                         np.concatenate(cons.lbg), np.concatenate(cons.ubg), w0, cons.groups, outputs, Xp, cons.pieces,
                         linear, Q, time.perf_counter() - started)


def stance_name(stance: tuple[int, ...]) -> str:
    return StanceSet(stance).name
