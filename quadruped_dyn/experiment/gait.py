"""Gait plans: which feet stand when, where the feet go, where the trunk goes (docs/experiment.md §2).

The experiment flows plan (this module) -> IK plan (``ik_target``) -> forward dynamics
(``simulate``, ``rigid_contact``) -> comparison and report (``validation``).

World frame: z up; the trunk keeps R = I (so the trot's roll phi = 0) and its origin at height
0, the feet below it. Trot: diagonal pairs (FL+BR, then FR+BL) alternate every half period, the
trunk moves forward at constant speed. Static walk: one leg swings at a time, three stand, in
the order BL, FL, FR, BR -- around the foot rectangle, so that two consecutive swing legs share a
side or an end and the support triangles before and after each switch overlap in a triangle of
their own (a diagonal order, e.g. FL, BR, FR, BL, leaves only the diagonal: no margin). The walk
is statically stable: the trunk sways so that the centre of mass (CoM) passes, at each switch,
through the point deepest inside both support triangles (their Chebyshev centre), on a smooth
periodic path (trigonometric interpolation, C-infinity), forward speed added.

A stance foot stays at its world foothold; a swing foot moves to its next foothold with a
quintic smoothstep forward and a 64 s^3 (1 - s)^3 bump upward: position, velocity and
acceleration are continuous (C^2) at lift-off and touch-down. Footholds: the feet of
``gait_posture`` (the paper's standing posture for a leg of the paper's DH form; otherwise a
crouch with each foot under its HFE joint at CROUCH of the leg's length), shifted so that each
foot is under that point in the middle of its stance.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cache

import numpy as np
import pinocchio as pin
from scipy.optimize import linprog

from quadruped_dyn.errors import InputError
from quadruped_dyn.experiment.ik import numeric_ik
from quadruped_dyn.model.paper_robot import STANDING_Q, dh_form
from quadruped_dyn.model.robot import Robot
from quadruped_dyn.model.state import GRAVITY_W

#: Crouch of the posture of URDF robots: feet this fraction of (thigh + shank) below the
#: HFE joint, far enough from full extension for the legs' Jacobians to stay well conditioned.
CROUCH = 0.75

#: The sway's harmonic k is shrunk by 1 + ZMP_WEIGHT h (k w)^2 / g (h: CoM height, w = 2 pi /
#: period). With 1 the cart-table model's zero-moment point (where the ground forces' centre of
#: pressure must be for f_z >= 0) passes through the targets and the CoM lags inside them; with
#: 0 the CoM does and the ZMP overshoots. One half splits the room between the CoM margin and
#: f_z: measured on the paper robot's walk with a 1.6 s cycle, CoM margin 2.8 / 2.3 / 1.9 cm and
#: smallest f_z 0.9 / 8.2 / 13.4 N (weight 98 N) for 0 / 0.5 / 1.
ZMP_WEIGHT = 0.5


@cache
def gait_posture(robot: Robot) -> np.ndarray:
    """Joint angles (12,) the gaits are built around (see the module docstring)."""
    if all(dh_form(leg) is not None for leg in robot.legs):
        return np.tile(STANDING_Q, 4)
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
            raise InputError(f"no crouched posture within joint limits for leg {leg.label} of {robot.name}")
    return q


def gait_feet(robot: Robot) -> list[np.ndarray]:
    """Foot positions (trunk frame, m) of ``gait_posture``: where the footholds are centred."""
    return [leg.foot_position(q) for leg, q in zip(robot.legs, gait_posture(robot).reshape(4, 3))]


@dataclass(frozen=True)
class Gait:
    """A periodic gait: ``phases`` lists the stance feet of each equal phase of the cycle; each
    leg swings in exactly one phase per cycle. The trunk moves forward at ``speed``; with
    ``sway`` it also sways to keep the CoM inside the support triangles (three-feet gaits)."""

    name: str
    phases: tuple[tuple[int, ...], ...]
    speed: float = 0.2  # m/s, forward
    period: float = 0.6  # s, a full cycle
    step_height: float = 0.04  # m
    sway: bool = False

    @property
    def phase_duration(self) -> float:
        return self.period / len(self.phases)

    @property
    def n_coords(self) -> int:
        """12 joint angles, plus the trunk roll when some phase stands on two feet."""
        return 13 if any(len(p) == 2 for p in self.phases) else 12

    def phase(self, t: float) -> tuple[int, float]:
        """(phase counter k since t = 0, fraction s in [0, 1) of phase k)."""
        k = int(np.floor(t / self.phase_duration + 1e-12))
        return k, max(t / self.phase_duration - k, 0.0)

    def stance(self, t: float) -> tuple[int, ...]:
        return self.phases[self.phase(t)[0] % len(self.phases)]

    def swing_phase(self, i: int) -> int:
        return next(j for j, feet in enumerate(self.phases) if i not in feet)

    def foot(self, i: int, t: float, standing: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """World position, velocity, acceleration of foot i (standing = its standing position,
        trunk frame). Foothold m of a leg is under its standing point at the middle of the
        stance that follows its m-th swing."""
        n, h = len(self.phases), self.phase_duration
        k, s = self.phase(t)
        swing_phase = self.swing_phase(i)
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


#: The paper's trot: diagonal pairs alternate. Static walk: one leg swings at a time, in the
#: order BL, FL, FR, BR (around the foot rectangle; see the module docstring).
TROT = Gait("trot", ((0, 3), (1, 2)))
WALK = Gait("walk", ((0, 1, 3), (1, 2, 3), (0, 2, 3), (0, 1, 2)), speed=0.1, period=1.2, sway=True)
GAITS = {g.name: g for g in (TROT, WALK)}


# ----------------------------------------------------------------------------- support polygons


def support_margin(point: np.ndarray, polygon: np.ndarray) -> float:
    """Signed distance (m) from ``point`` (2,) to the nearest edge of the convex polygon
    (k, 2) of footholds, in the ground plane: positive inside, negative outside."""
    P = np.asarray(polygon, dtype=float)[:, :2]
    centre = P.mean(axis=0)
    distances = []
    for a, b in zip(P, np.roll(P, -1, axis=0)):
        n = np.array([b[1] - a[1], a[0] - b[0]]) / np.linalg.norm(b - a)
        n = n if n @ (centre - a) > 0 else -n  # inward normal
        distances.append(float(n @ (np.asarray(point)[:2] - a)))
    return min(distances)


def _halfplanes(polygon: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(N, c): the convex polygon (k, 2) as {x: N x <= c}, rows of N unit outward normals."""
    centre = polygon.mean(axis=0)
    rows, rhs = [], []
    for a, b in zip(polygon, np.roll(polygon, -1, axis=0)):
        n = np.array([b[1] - a[1], a[0] - b[0]]) / np.linalg.norm(b - a)
        n = n if n @ (centre - a) < 0 else -n
        rows.append(n)
        rhs.append(n @ a)
    return np.array(rows), np.array(rhs)


def deepest_point(*polygons: np.ndarray) -> tuple[np.ndarray, float]:
    """Chebyshev centre of the intersection of convex polygons (each (k, 2)): the point
    farthest inside all of them, and that distance (m; negative: they do not overlap)."""
    N, c = (np.concatenate(x) for x in zip(*(_halfplanes(np.asarray(p, dtype=float)[:, :2]) for p in polygons)))
    res = linprog([0.0, 0.0, -1.0], A_ub=np.hstack([N, np.ones((len(c), 1))]), b_ub=c,
                  bounds=[(None, None), (None, None), (None, None)])
    if not res.success:
        raise InputError(f"no point inside the support polygons ({res.message}); expected overlapping supports")
    return res.x[:2], float(res.x[2])


# ----------------------------------------------------------------------------- plan of one robot


@dataclass(frozen=True, eq=False)
class Plan:
    """A gait laid out for one robot: footholds, stance feet and the trunk trajectory.

    The trunk origin is at p(t) = (speed t + d_x(t), d_y(t), 0) in the world, R = I, where
    d(t) is the sway (zero without ``gait.sway``): the trigonometric interpolant of period
    ``gait.period`` through the offsets that put the CoM of the posture on the deepest point
    of the two support triangles at each stance switch, each harmonic shrunk for the
    cart-table ZMP (``ZMP_WEIGHT``)."""

    robot: Robot
    gait: Gait
    standing: np.ndarray  # (4, 3) foot positions of the posture, trunk frame, m
    com_b: np.ndarray  # (3,) whole-robot CoM at the posture, trunk frame, m
    sway: np.ndarray  # (2, n) coefficients of d_x, d_y on ``_basis`` (m)

    def foot(self, i: int, t: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """World position, velocity, acceleration of foot i at time t (m, m/s, m/s^2)."""
        return self.gait.foot(i, t, self.standing[i])

    def footholds(self, t: float, feet: tuple[int, ...]) -> np.ndarray:
        """(k, 3) world positions of the given feet at time t."""
        return np.array([self.foot(i, t)[0] for i in feet])

    def stance(self, t: float) -> tuple[int, ...]:
        return self.gait.stance(t)

    def trunk(self, t: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """World position, velocity, classical acceleration of the trunk origin (R = I)."""
        b = _basis(self.gait, t)
        d = self.sway @ b  # (2, 3): offset, rate, acceleration per axis
        g = self.gait
        return (np.array([g.speed * t + d[0, 0], d[1, 0], 0.0]), np.array([g.speed + d[0, 1], d[1, 1], 0.0]),
                np.array([d[0, 2], d[1, 2], 0.0]))

    def switch_times(self, horizon: float) -> np.ndarray:
        """Stance switches in (0, horizon), s."""
        h = self.gait.phase_duration
        return h * np.arange(1, int(np.floor(horizon / h - 1e-9)) + 1)


def _basis(gait: Gait, t: float) -> np.ndarray:
    """(n, 3): the trigonometric basis of period ``gait.period`` with n = number of phases
    (1, cos w t, sin w t, ..., and cos(n/2 w t) for even n), its first and second derivatives."""
    n, w = len(gait.phases), 2 * np.pi / gait.period
    rows = [[1.0, 0.0, 0.0]]
    for k in range(1, n // 2 + 1):
        c, s = np.cos(k * w * t), np.sin(k * w * t)
        rows.append([c, -k * w * s, -((k * w) ** 2) * c])
        if 2 * k != n:
            rows.append([s, k * w * c, -((k * w) ** 2) * s])
    return np.array(rows)


@cache
def gait_plan(robot: Robot, gait: Gait) -> Plan:
    """Lay ``gait`` out for ``robot``: footholds from the posture, and for a swaying gait the
    CoM targets at the stance switches (see ``Plan``)."""
    q = np.concatenate([np.zeros(3), [0.0, 0.0, 0.0, 1.0], gait_posture(robot)])
    from quadruped_dyn.references.pinocchio import PinocchioReference  # Pinocchio's CoM: independent of our dynamics

    ref = PinocchioReference(robot)
    com_b = np.array(pin.centerOfMass(robot.model, ref.data, ref.pin_q(q)))
    standing = np.array(gait_feet(robot))
    n = len(gait.phases)
    sway = np.zeros((2, n))
    if gait.sway:
        plan0 = Plan(robot, gait, standing, com_b, sway)
        offsets = []
        for k in range(n):
            t = k * gait.phase_duration  # the stance of phase k - 1 ends, that of phase k begins
            before, after = gait.phases[(k - 1) % n], gait.phases[k]
            target, _ = deepest_point(plan0.footholds(t, before), plan0.footholds(t, after))
            offsets.append(target - com_b[:2] - np.array([gait.speed * t, 0.0]))
        B = np.array([_basis(gait, k * gait.phase_duration)[:, 0] for k in range(n)])  # (n, n)
        height = com_b[2] - standing[:, 2].mean()  # CoM above the ground, m
        harmonic = np.array([0] + [k for k in range(1, n // 2 + 1) for _ in range(1 if 2 * k == n else 2)])
        cart_table = 1 + ZMP_WEIGHT * height * (harmonic * 2 * np.pi / gait.period) ** 2 / -GRAVITY_W[2]
        sway = np.linalg.solve(B, np.array(offsets)).T / cart_table
    return Plan(robot, gait, standing, com_b, sway)
