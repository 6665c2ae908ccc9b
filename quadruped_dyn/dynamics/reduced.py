"""Reduced coordinates and forward dynamics (docs/formulation.md §5-§6.1, paper section 5), symbolic.

Coordinates q_r: the 12 joint angles (three or four stance feet: static walk, standing),
plus the trunk roll phi for two stance feet (trot, pace): 13. The trunk motion is not a
coordinate: it follows from the stance feet staying fixed on the ground.

* Velocity map, per stance foot (trunk frame):  v_b + omega_b x r_i + J_i qd_i = 0, i.e.
  [I, -[r_i]x] xi = -J_i qd_i for xi = (v_b, omega_b); with two feet the roll-rate row
  e_phi . omega_b = phid, e_phi = (1, sin(phi) tan(theta), cos(phi) tan(theta)) (R = Rz Ry Rx).
  xi is the least-squares solution (exact when qd is consistent with the stance).
* Acceleration map, same matrix, classical a_b:
  a_b + alpha x r_i + omega x (omega x r_i) + 2 omega x (J_i qd_i) + J_i qdd_i + Jdot_i qd_i = 0,
  plus d/dt of the roll-rate row. Then vdot_b = a_b - omega_b x v_b (the project's a).
* id_r(q_r, qd_r, qdd_r, quat) -> tau_r: those maps, the paper's GRF model of the stance set,
  the 12 joint torques; with two feet a 13th entry, the trunk wrench residual about the
  foot-to-foot line, e . (M_res - r_1 x F_res) (N m, e from foot 2 to foot 1; zero for a
  motion the robot can make: phi is unactuated).
* M_r by Walker & Orin (unit qdd_r, g = 0, qd = 0) and by CasADi AD; C_r (g = 0, qdd = 0);
  G_r (qd = 0, qdd = 0). The GRF solve is linear, so id_r = M_r qdd + C_r + G_r exactly.
  M_r is not symmetric: the GRF assumptions project the dynamics.
* fd_r(q_r, qd_r, tau_ext, quat) = M_r^-1 (tau_ext - C_r - G_r), tau_ext (n,) = (tau, 0 for the
  unactuated roll); a nonzero 13th entry applies the roll moment as if it were actuated.

``quat`` is the trunk orientation (x, y, z, w): it sets gravity in the trunk frame and, with
two feet, the roll-rate row; it must agree with the stance (``pose`` reconstructs it).
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass
from functools import cache

import casadi as ca
import numpy as np

from quadruped_dyn.dynamics.grf import GrfSolve, grf_expressions, grf_solve
from quadruped_dyn.dynamics.guarded import guard_fields, guarded_call, with_condition
from quadruped_dyn.dynamics.kinematics import foot_position
from quadruped_dyn.dynamics.stance_regularity import regularity
from quadruped_dyn.dynamics.stored import stored_functions
from quadruped_dyn.errors import InputError, NumericalError
from quadruped_dyn.math.linalg import least_squares
from quadruped_dyn.math.rigid import skew
from quadruped_dyn.math.spatial import quat_to_rotation
from quadruped_dyn.model.robot import Robot, check_robot
from quadruped_dyn.model.stance import StanceSet, stance_set
from quadruped_dyn.model.state import check_array
from quadruped_dyn.tolerances import REGULARITY_MIN, TRUNK_PITCH_DEG_MARGIN

REDUCED_KINDS = {4: "stand", 3: "static walk", 2: "trot / pace"}

#: Beyond this condition number M_r's solve keeps fewer than ~4 significant digits in double.
MAX_COND_M_R = 1e12


def roll_rate_row(R: ca.SX) -> ca.SX:
    """e_phi with phid = e_phi . omega_b for R = Rz(psi) Ry(theta) Rx(phi), written with R's
    entries (cos theta > 0): tan(theta) sin(phi) = -R20 R21 / (R21^2 + R22^2), etc.
    ``references.pinocchio.roll_rate_row`` is the reference's own, independent derivation."""
    c2 = R[2, 1] ** 2 + R[2, 2] ** 2
    return ca.vertcat(1, -R[2, 0] * R[2, 1] / c2, -R[2, 0] * R[2, 2] / c2)


def roll_rate_row_dot(R: ca.SX, omega: ca.SX) -> ca.SX:
    """d/dt e_phi(R) along Rdot = R [omega]x (omega in the trunk frame)."""
    R_sym = ca.SX.sym("R", 3, 3)
    e_dot = ca.jtimes(roll_rate_row(R_sym), ca.vec(R_sym), ca.vec(R_sym @ skew(omega)))
    return ca.substitute(e_dot, R_sym, R)


def _maps(robot: Robot, stance: StanceSet, q_r: ca.SX, qd_r: ca.SX, qdd_r: ca.SX, R: ca.SX) -> tuple[ca.SX, ca.SX]:
    """Full v (18,) and a = vdot (18,) from the reduced coordinates."""
    rows, rhs_v, feet = [], [], []
    for i in stance.feet:
        s = slice(3 * i, 3 * i + 3)
        r = foot_position(robot.legs[i], q_r[s])
        J = ca.jacobian(r, q_r[s])
        feet.append((r, J, ca.jacobian(J @ qd_r[s], q_r[s]) @ qd_r[s], qd_r[s], qdd_r[s]))
        rows.append(ca.horzcat(ca.SX.eye(3), -skew(r)))
        rhs_v.append(-J @ qd_r[s])
    two_feet = len(stance.feet) == 2
    if two_feet:
        e_phi = roll_rate_row(R)
        rows.append(ca.horzcat(ca.SX.zeros(1, 3), e_phi.T))
        rhs_v.append(qd_r[12])
    A = ca.vertcat(*rows)
    xi = least_squares(A, ca.vertcat(*rhs_v))
    v_b, omega = xi[:3], xi[3:]
    rhs_a = [
        -(ca.cross(omega, ca.cross(omega, r)) + 2 * ca.cross(omega, J @ qd) + J @ qdd + Jdqd)
        for r, J, Jdqd, qd, qdd in feet
    ]
    if two_feet:
        rhs_a.append(qdd_r[12] - ca.dot(roll_rate_row_dot(R, omega), omega))
    acc = least_squares(A, ca.vertcat(*rhs_a))  # (a_b classical, alpha)
    v = ca.vertcat(v_b, omega, qd_r[:12])
    a = ca.vertcat(acc[:3] - ca.cross(omega, v_b), acc[3:], qdd_r[:12])
    return v, a


def reduced_inverse_dynamics(
    robot: Robot, stance: StanceSet, q_r: ca.SX, qd_r: ca.SX, qdd_r: ca.SX, quat: ca.SX, gravity: bool = True
) -> ca.SX:
    """tau_r (12 or 13,) for the paper's GRF model of the stance set."""
    R = quat_to_rotation(quat)
    v, a = _maps(robot, stance, q_r, qd_r, qdd_r, R)
    q = ca.vertcat(ca.SX.zeros(3), quat, q_r[:12])
    g = grf_expressions(robot, stance, "paper", q, v, a, gravity=gravity)
    if len(stance.feet) != 2:
        return g.tau
    i, j = stance.feet
    r1 = foot_position(robot.legs[i], q_r[3 * i : 3 * i + 3])
    r2 = foot_position(robot.legs[j], q_r[3 * j : 3 * j + 3])
    e = (r1 - r2) / ca.norm_2(r1 - r2)
    return ca.vertcat(g.tau, ca.dot(e, g.residual[3:] - ca.cross(r1, g.residual[:3])))


@cache  # built once per robot and stance set: by the model, the generator and the reference header (per case)
def regularity_function(robot: Robot, stance: StanceSet) -> ca.Function:
    """q_r (n,), quat (4,) -> the stance's regularity (``stance_regularity``), dimensionless: the
    one expression ``ReducedModel`` checks and the generated C evaluates."""
    n = 13 if len(stance.feet) == 2 else 12
    q, quat = ca.SX.sym("q_r", n), ca.SX.sym("quat", 4)
    r = [foot_position(robot.legs[i], q[3 * i : 3 * i + 3]) for i in stance.feet]
    e_phi = roll_rate_row(quat_to_rotation(quat)) if len(stance.feet) == 2 else None
    return ca.Function(f"regularity_{stance.name.replace('+', '_')}", [q, quat], [regularity(stance, r, e_phi)],
                       ["q_r", "quat"], ["regularity"], {"cse": True})


def check_regularity(stance: StanceSet, value: float) -> None:
    """NumericalError unless the stance's regularity ``value`` exceeds REGULARITY_MIN."""
    if not value > REGULARITY_MIN:
        raise NumericalError(
            f"stance {stance.name} is degenerate here (regularity {value:.1e}, at most {REGULARITY_MIN:.0e}): "
            "coincident or collinear stance feet, or two feet whose line is perpendicular to the roll axis "
            "(the front or back pair with zero pitch or roll), or two feet with the trunk pitched within "
            f"{TRUNK_PITCH_DEG_MARGIN:.1f} deg of 90 deg; the reduced model is undefined"
        )


@dataclass(frozen=True)
class ReducedModel:
    """Named Functions of the reduced model of one stance set; n = 12 or 13 coordinates.

    Inputs: q_r, qd_r, qdd_r (n,) [rad, rad/s, rad/s^2; the 13th is the trunk roll phi],
    quat (4,) trunk orientation (x, y, z, w), tau_ext (n,) joint torques [N m] (+ roll moment)."""

    stance: StanceSet
    n: int
    maps: ca.Function  # q_r, qd_r, qdd_r, quat -> v (18,), a = vdot (18,)
    id_r: ca.Function  # q_r, qd_r, qdd_r, quat -> tau_r (n,)
    M_r: ca.Function  # q_r, quat -> (n, n), Walker & Orin
    M_r_ad: ca.Function  # q_r, quat -> (n, n), CasADi AD of id_r
    C_r: ca.Function  # q_r, qd_r, quat -> (n,)
    G_r: ca.Function  # q_r, quat -> (n,)
    fd_r: ca.Function  # q_r, qd_r, tau_ext, quat -> qdd_r (n,)
    build_seconds: float
    grf: GrfSolve | None = None  # the stance set's GRF solve: its rank is checked before numeric calls
    regularity: ca.Function | None = None  # q_r, quat -> the stance's regularity, checked before numeric calls

    def __post_init__(self) -> None:
        guard_fields(self)  # numeric calls check shapes, finiteness, quaternions (dynamics/guarded.py)
        # finite nonsense is not an answer: every numeric call first checks the GRF system's rank
        # (collinear or coincident stance feet), fd_r also M_r's condition number
        for name in ("maps", "id_r", "M_r", "M_r_ad", "C_r", "G_r"):
            f = getattr(self, name)
            object.__setattr__(self, name, with_condition(f, self._regular_at(f)))
        object.__setattr__(self, "fd_r", with_condition(self.fd_r, self._solvable_at(self.fd_r)))

    def _regular_at(self, f: ca.Function) -> Callable[[list[np.ndarray]], None]:
        i_q, i_quat = f.name_in().index("q_r"), f.name_in().index("quat")

        def check(values: list[np.ndarray]) -> None:
            if self.grf is not None:
                self.grf.check_regular(np.concatenate([np.zeros(3), values[i_quat], values[i_q][:12]]))
            if self.regularity is not None:
                check_regularity(self.stance, guarded_call(self.regularity, values[i_q], values[i_quat])[0].item())

        return check

    def _solvable_at(self, f: ca.Function) -> Callable[[list[np.ndarray]], None]:
        regular = self._regular_at(f)
        i_q, i_quat = f.name_in().index("q_r"), f.name_in().index("quat")

        def check(values: list[np.ndarray]) -> None:
            regular(values)
            (M,) = guarded_call(self.M_r, values[i_q], values[i_quat])
            solve_forward_dynamics(self.stance, M, np.zeros(self.n))  # NumericalError where M_r is singular

        return check

    def forward_dynamics(self, q_r: np.ndarray, qd_r: np.ndarray, tau_ext: np.ndarray,
                         quat: np.ndarray) -> tuple[np.ndarray, float]:
        """(qdd_r, cond(M_r)) by ``solve_forward_dynamics`` from this graph's M_r, C_r and G_r, with
        checked inputs (InputError); NumericalError where M_r is numerically singular."""
        (M,) = guarded_call(self.M_r, q_r, quat)
        (C,), (G,) = guarded_call(self.C_r, q_r, qd_r, quat), guarded_call(self.G_r, q_r, quat)
        return solve_forward_dynamics(self.stance, M, check_array("tau_ext", tau_ext, (self.n,)) - C - G)


def solve_forward_dynamics(stance: StanceSet, M_r: np.ndarray, rhs: np.ndarray) -> tuple[np.ndarray, float]:
    """The reduced forward dynamics (paper eq. (5)), the one numeric definition: qdd_r = M_r^-1 rhs
    with rhs = tau_ext - C_r - G_r, by LU, and cond(M_r); NumericalError where cond(M_r) is not below
    MAX_COND_M_R. (The generated C's fd_r does the same solve in C, c/qd_reduced_solve.c.)"""
    cond = float(np.linalg.cond(M_r))
    if not cond < MAX_COND_M_R:
        raise NumericalError(f"M_r of {stance.name} has condition number {cond:.1e} here; the reduced model is "
                             "singular (e.g. collinear stance feet)")
    return np.linalg.solve(M_r, rhs), cond


def reduced_model(robot: Robot, stance_name: str) -> ReducedModel:
    """Build the reduced model for a stance set of two, three or four feet (once per robot)."""
    return _reduced_model(check_robot(robot), stance_set(stance_name).name)  # checked before the cache hashes it


@cache
def reduced_maps(robot: Robot, stance_name: str) -> ca.Function:
    """``ReducedModel.maps`` alone (q_r, qd_r, qdd_r, quat -> v (18,), a = vdot (18,)), for
    callers that need the full motion and not the dynamics: a small part of ``reduced_model``'s
    build. The same expressions (``_maps``)."""
    stance = stance_set(stance_name)
    n = 13 if len(stance.feet) == 2 else 12
    q, qd, qdd, quat = ca.SX.sym("q_r", n), ca.SX.sym("qd_r", n), ca.SX.sym("qdd_r", n), ca.SX.sym("quat", 4)
    v, a = _maps(robot, stance, q, qd, qdd, quat_to_rotation(quat))
    return ca.Function(f"maps_{stance.name.replace('+', '_')}", [q, qd, qdd, quat], [v, a],
                       ["q_r", "qd_r", "qdd_r", "quat"], ["v", "a"], {"cse": True})


#: The Functions of a ReducedModel, in the order they are stored (``stored.py``).
MODEL_FUNCTIONS = ("maps", "id_r", "M_r", "M_r_ad", "C_r", "G_r", "fd_r", "regularity")


@cache
def _reduced_model(robot: Robot, stance_name: str) -> ReducedModel:
    stance = stance_set(stance_name)
    k = len(stance.feet)
    if k not in REDUCED_KINDS:
        raise InputError(f"stance {stance.name} has {k} feet; the reduced model needs 2, 3 or 4 stance feet")
    start = time.perf_counter()
    functions = stored_functions(robot, f"reduced model {stance.name}", MODEL_FUNCTIONS,
                                 lambda: _model_functions(robot, stance))
    return ReducedModel(stance=stance, n=13 if k == 2 else 12, **functions, build_seconds=time.perf_counter() - start,
                        grf=grf_solve(robot, stance, "paper"))


def _model_functions(robot: Robot, stance: StanceSet) -> dict[str, ca.Function]:
    """The Functions of the reduced model of ``stance`` (MODEL_FUNCTIONS), built from the symbols."""
    n = 13 if len(stance.feet) == 2 else 12
    q, qd, qdd = ca.SX.sym("q_r", n), ca.SX.sym("qd_r", n), ca.SX.sym("qdd_r", n)
    quat, tau_ext = ca.SX.sym("quat", 4), ca.SX.sym("tau_ext", n)
    zero = ca.SX.zeros(n)

    def idr(qd_: ca.SX, qdd_: ca.SX, gravity: bool) -> ca.SX:
        return reduced_inverse_dynamics(robot, stance, q, qd_, qdd_, quat, gravity)

    unit = ca.SX(ca.DM.eye(n))
    M = ca.horzcat(*[idr(zero, unit[:, c], gravity=False) for c in range(n)])
    C, G = idr(qd, zero, gravity=False), idr(zero, zero, gravity=True)
    opts = {"cse": True}
    name = stance.name.replace("+", "_")
    v, a = _maps(robot, stance, q, qd, qdd, quat_to_rotation(quat))
    tau_r = idr(qd, qdd, gravity=True)
    return {
        "maps": ca.Function(f"maps_{name}", [q, qd, qdd, quat], [v, a], ["q_r", "qd_r", "qdd_r", "quat"], ["v", "a"], opts),
        "id_r": ca.Function(f"id_r_{name}", [q, qd, qdd, quat], [tau_r], ["q_r", "qd_r", "qdd_r", "quat"], ["tau_r"], opts),
        "M_r": ca.Function(f"M_r_{name}", [q, quat], [M], ["q_r", "quat"], ["M_r"], opts),
        "M_r_ad": ca.Function(f"M_r_ad_{name}", [q, quat], [ca.jacobian(tau_r, qdd)], ["q_r", "quat"], ["M_r"], opts),
        "C_r": ca.Function(f"C_r_{name}", [q, qd, quat], [C], ["q_r", "qd_r", "quat"], ["C_r"], opts),
        "G_r": ca.Function(f"G_r_{name}", [q, quat], [G], ["q_r", "quat"], ["G_r"], opts),
        "fd_r": ca.Function(f"fd_r_{name}", [q, qd, tau_ext, quat], [least_squares(M, tau_ext - C - G)],
                            ["q_r", "qd_r", "tau_ext", "quat"], ["qdd_r"], opts),
        "regularity": regularity_function(robot, stance),
    }
