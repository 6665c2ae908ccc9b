"""Ground reaction forces from the six body equations (docs/formulation.md §3-§4, paper section 4).

The body equations (paper eq. (3)-(4)) with the stance feet's forces f_i (trunk frame) as
unknowns read  sum_i [I; [r_i]x] f_i = w_req,  where w_req (6,) = (force; moment about the
trunk origin) is the base residual of ``id_full`` with zero foot forces: what the trunk
needs, given the motion, gravity and the suspended legs. A GRF model parameterises
f = P lambda (P constant, 3k x n) so the system is  A lambda = w_req,  A = G P.

Models:
* ``paper``  -- the paper's assumptions, in the trunk frame (x forward, y left, z up):
  4 feet: (fz1..fz4, fx, fy) with fx, fy common to all feet              -> rank 5
  3 feet: (fz1..fz3, fx, fy_same, fy_opp): the stance foot on the lifted leg's side has
          its own fy, the two on the opposite side share one             -> rank 6
  2 feet: (f1, f2), all six components free                              -> rank 5
  1 foot: (f1) all free (the paper is silent; an extension)              -> rank 3
  0 feet: f = 0.
* ``min_norm`` -- all 3k components free; the minimum-norm solution (pseudo-inverse).

Rank 5 is structural, not bad luck: with four feet the yaw row is x_mean Fy - y_mean Fx of
the force rows, so a yaw moment off that line cannot be balanced and one combination of the
fz is free; with two feet (p1 - p2) x f1 has rank 2, so the force along the foot-to-foot
line is free (a squeeze) and the moment about that line cannot be produced by the feet.

Every case is solved rank-revealingly, returning the minimum-norm lambda and the residual
w_req - A lambda (the part of w_req the model cannot balance). Symbolically, the square
rank-deficient cases use explicit orthonormal null-space (N) and left-null-space (U) bases:
A+ = (A + U N^T)^-1 - N U^T, where A + U N^T is invertible; no solve on a singular matrix.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cache

import casadi as ca
import numpy as np

from quadruped_dyn.arguments import real_number
from quadruped_dyn.dynamics.guarded import guard_fields, guarded_call
from quadruped_dyn.dynamics.kinematics import foot_position
from quadruped_dyn.dynamics.newton_euler import inverse_dynamics
from quadruped_dyn.dynamics.stored import stored_functions
from quadruped_dyn.errors import InputError, NumericalError
from quadruped_dyn.math.linalg import least_squares, min_norm
from quadruped_dyn.math.rigid import skew
from quadruped_dyn.math.spatial import dm, quat_to_rotation
from quadruped_dyn.model.robot import Robot, check_robot
from quadruped_dyn.model.stance import GRF_MODELS, STANCE_SETS, StanceSet, stance_set
from quadruped_dyn.model.state import GRAVITY_W, NQ_FULL, NV_FULL, check_array, rotation
from quadruped_dyn.tolerances import RANK_RTOL

# ----------------------------------------------------------------------------- symbolic solve


def contact_map(r: list[ca.SX]) -> ca.SX:
    """G (6, 3k): wrench (force; moment about the trunk origin) of forces at points r_i."""
    if not r:
        return ca.SX.zeros(6, 0)
    return ca.horzcat(*[ca.vertcat(ca.SX.eye(3), skew(ri)) for ri in r])


def _unit(x: ca.SX) -> ca.SX:
    return x / ca.norm_2(x)


def _deficiency_bases(stance: StanceSet, model: str, r: list[ca.SX]) -> tuple[ca.SX, ca.SX] | None:
    """Orthonormal (N, U): null space of A and left null space, for the rank-5 cases."""
    k = len(stance.feet)
    if k == 2:
        e = _unit(r[0] - r[1])
        return _unit(ca.vertcat(e, -e)), _unit(ca.vertcat(ca.cross(r[0], e), e))
    if k == 4 and model == "paper":
        x = ca.vertcat(*[ri[0] for ri in r])
        y = ca.vertcat(*[ri[1] for ri in r])
        rows = ca.horzcat(ca.SX.ones(4), x, y).T  # 3 x 4: sum, sum x, sum y of the fz must vanish
        n = ca.vertcat(*[(-1) ** j * ca.det(rows[:, [c for c in range(4) if c != j]]) for j in range(4)])
        N = _unit(ca.vertcat(n, 0, 0))
        U = _unit(ca.vertcat(ca.sum1(y) / 4, -ca.sum1(x) / 4, 0, 0, 0, 1))  # yaw - x_mean Fy + y_mean Fx
        return N, U
    return None


def min_norm_solve(A: ca.SX, w: ca.SX, bases: tuple[ca.SX, ca.SX] | None) -> ca.SX:
    """Minimum-norm least-squares solution of A lambda = w for the structures that occur here:
    square and rank-deficient with known orthonormal bases N, U: A+ w = (A + U N^T)^-1 w - N U^T w;
    otherwise full row or full column rank, by Householder QR."""
    m, n = A.shape
    if n == 0:
        return ca.SX.zeros(0, w.shape[1])
    if bases is not None:
        N, U = bases
        return least_squares(A + U @ N.T, w) - N @ (U.T @ w)
    return min_norm(A, w) if n > m else least_squares(A, w)


def solve_lambda(stance: StanceSet, model: str, r: list[ca.SX], w_req: ca.SX) -> tuple[ca.SX, ca.SX]:
    """(lambda, A): the model's minimum-norm unknowns for the required trunk wrench(es) w_req
    (6, m: one column per right-hand side), stance feet at r (trunk frame), and A = G P."""
    P = stance.selection(model)
    if not P.size:
        return ca.SX.zeros(0, w_req.shape[1]), ca.SX.zeros(6, 0)
    A = contact_map(r) @ dm(P)
    return min_norm_solve(A, w_req, _deficiency_bases(stance, model, r)), A


@dataclass(frozen=True)
class GrfSolution:
    lam: np.ndarray  # (n,) the model's unknowns, minimum norm
    f_body: np.ndarray  # (k, 3) ground force on each stance foot, trunk frame, N
    f_world: np.ndarray  # (k, 3) the same in the world frame, N
    residual: np.ndarray  # (6,) required trunk wrench the model cannot balance: force N, moment N m
    tau: np.ndarray  # (12,) joint torques, N m
    rank: int  # rank of the model's 6 x n system
    in_friction_cone: np.ndarray | None  # (k,) per stance foot, if mu was given
    friction_margin: np.ndarray | None  # (k,) mu f_z - |f_t|, N


@dataclass(frozen=True)
class GrfSolve:
    """Named Function ``grf_<stance>_<model>``: q (19,), v (18,), a = vdot (18,) ->
    lambda (n,), f (12,) ground forces on all feet in the trunk frame (0 for swing feet),
    residual (6,) = w_req - A lambda, tau (12,) joint torques with those forces."""

    stance: StanceSet
    model: str
    rank: int
    function: ca.Function
    system: ca.Function  # q -> A (6, n), the model's body-equation matrix

    def __post_init__(self) -> None:
        guard_fields(self)  # numeric calls check shapes, finiteness, quaternions (dynamics/guarded.py)

    def check_regular(self, q: np.ndarray) -> None:
        """NumericalError where the body equations have less than their structural rank at ``q``
        (coincident or collinear stance feet): there the symbolic solve, the generated C and
        everything built on them (the reduced model) give finite nonsense."""
        (A,) = guarded_call(self.system, q)
        sv = np.linalg.svd(np.atleast_2d(A), compute_uv=False) if A.size else np.zeros(0)
        numeric_rank = int(np.sum(sv > RANK_RTOL * sv[0])) if sv.size and sv[0] > 0 else 0
        if numeric_rank < self.rank:
            smallest = sv[self.rank - 1] / sv[0] if sv.size >= self.rank and sv[0] > 0 else 0.0
            raise NumericalError(
                f"stance {self.stance.name}: the body equations have rank {numeric_rank} at this configuration, "
                f"{self.rank} expected (smallest singular value {smallest:.1e} of the largest); the stance feet are "
                "coincident or collinear"
            )

    def solve(self, q: np.ndarray, v: np.ndarray, a: np.ndarray, mu: float | None = None) -> GrfSolution:
        """Numeric solve with checked inputs (InputError). Raises NumericalError where the stance
        feet are coincident or collinear, so that A has less than its structural rank (the symbolic
        solve, and the generated C, would return meaningless forces there)."""
        if mu is not None:
            mu = check_friction_coefficient(mu)
        self.check_regular(q)
        lam, f, residual, tau = guarded_call(self.function, q, v, a)
        feet = list(self.stance.feet)
        f_body = f.reshape(4, 3)[feet]
        f_world = f_body @ rotation(np.asarray(q, dtype=float)).T
        ok, margin = friction_cone(f_world, mu) if mu is not None else (None, None)
        return GrfSolution(lam, f_body, f_world, residual, tau, self.rank, ok, margin)


@dataclass(frozen=True)
class GrfExpressions:
    """SX expressions of one solve (see ``GrfSolve`` for the meaning of each)."""

    lam: ca.SX
    f: ca.SX
    residual: ca.SX
    tau: ca.SX
    A: ca.SX


def grf_expressions(
    robot: Robot, stance: StanceSet, model: str, q: ca.SX, v: ca.SX, a: ca.SX, gravity: bool = True
) -> GrfExpressions:
    """The GRF solve and the joint torques for given (q, v, a = vdot) expressions
    (``gravity=False`` drops gravity, as Walker & Orin's unit-acceleration columns need)."""
    qj = q[7:]
    g_b = quat_to_rotation(q[3:7]).T @ dm(GRAVITY_W) if gravity else ca.SX.zeros(3)
    w_req = inverse_dynamics(robot, qj, g_b, v, a, ca.SX.zeros(12))[:6]
    b = grf_balance(robot, stance, model, qj, w_req)
    tau = inverse_dynamics(robot, qj, g_b, v, a, b.f)[6:]
    return GrfExpressions(b.lam, b.f, b.residual, tau, b.A)


def grf_balance(robot: Robot, stance: StanceSet, model: str, q_joints: ca.SX, w_req: ca.SX) -> GrfExpressions:
    """The GRF solve for a given required trunk wrench w_req (6,) (force [N], moment about the trunk
    origin [N m], trunk frame) at the joint angles q_joints (12,): lambda, f (12,), residual, and as
    ``tau`` the joint torques the foot forces add, -J_i^T f_i per stance leg (paper eq. (1))."""
    r = [foot_position(robot.legs[i], q_joints[3 * i : 3 * i + 3]) for i in stance.feet]
    P = stance.selection(model)
    lam, A = solve_lambda(stance, model, r, w_req)
    f_stance = dm(P) @ lam if P.size else ca.SX.zeros(0)
    f, tau = ca.SX.zeros(12), ca.SX.zeros(12)
    for j, i in enumerate(stance.feet):
        s = slice(3 * i, 3 * i + 3)
        f[s] = f_stance[3 * j : 3 * j + 3]
        tau[s] = -ca.jacobian(r[j], q_joints[s]).T @ f[s]
    residual = w_req - (A @ lam if P.size else 0)
    return GrfExpressions(lam, f, residual, tau, A)


def _grf_functions(robot: Robot, stance: StanceSet, model: str) -> tuple[ca.Function, ca.Function]:
    """(the solve, the body-equation matrix) of ``GrfSolve``, built from the symbols."""
    q, v, a = ca.SX.sym("q", NQ_FULL), ca.SX.sym("v", NV_FULL), ca.SX.sym("a", NV_FULL)
    e = grf_expressions(robot, stance, model, q, v, a)
    name = f"grf_{stance.name.replace('+', '_')}_{model}"
    outputs = ["lambda", "f", "residual", "tau"]
    fun = ca.Function(name, [q, v, a], [e.lam, e.f, e.residual, e.tau], ["q", "v", "a"], outputs, {"cse": True})
    return fun, ca.Function(f"{name}_A", [q], [ca.densify(e.A)], ["q"], ["A"])


@cache
def grf_solves(robot: Robot) -> dict[tuple[str, str], GrfSolve]:
    """All (stance name, model) solves of a robot, built once (and stored: ``stored.py``)."""
    cases = [(s, m) for s in STANCE_SETS for m in GRF_MODELS]
    names = tuple(f"{s.name} {m} {part}" for s, m in cases for part in ("solve", "system"))

    def build() -> dict[str, ca.Function]:
        return dict(zip(names, [f for s, m in cases for f in _grf_functions(robot, s, m)]))

    functions = stored_functions(robot, "GRF solves", names, build)
    return {(s.name, m): GrfSolve(s, m, s.rank(m), functions[f"{s.name} {m} solve"], functions[f"{s.name} {m} system"])
            for s, m in cases}


def grf_solve(robot: Robot, stance: str | StanceSet, model: str = "paper") -> GrfSolve:
    check_robot(robot)
    s = stance_set(stance)
    if not isinstance(model, str):
        raise InputError(f"model is {type(model).__name__}; expected one of {GRF_MODELS}")
    s.selection(model)  # validates the model name
    return grf_solves(robot)[(s.name, model)]


# ----------------------------------------------------------------------------- friction


def friction_cone(f_world: np.ndarray, mu: float) -> tuple[np.ndarray, np.ndarray]:
    """Per stance foot (k, 3 world-frame forces; flat ground, normal z_w): feasible flags
    (|f_t| <= mu f_z and f_z >= 0) and margins mu f_z - |f_t| (N; negative = slipping)."""
    mu = check_friction_coefficient(mu)
    f = np.atleast_2d(np.asarray(f_world, dtype=float))
    margin = mu * f[:, 2] - np.hypot(f[:, 0], f[:, 1])
    return (margin >= 0) & (f[:, 2] >= 0), margin


#: Larger than any friction coefficient (rubber on concrete ~1, adhesive contacts a few): beyond
#: it mu f_z overflows no sooner, but the margins stop meaning anything; mu = 1e308 gave inf.
MAX_FRICTION_COEFFICIENT = 1e3


def check_friction_coefficient(mu: object) -> float:
    """mu as a float, or an InputError unless it is a real number (not a string, not a bool) in
    [0, MAX_FRICTION_COEFFICIENT]."""
    if isinstance(mu, np.ndarray):  # a 0-d array: masked, boolean and float16 ones refused as any array input
        mu = check_array("mu", mu, ()).item()
    value = real_number("mu", mu)
    if not (np.isfinite(value) and 0.0 <= value <= MAX_FRICTION_COEFFICIENT):
        raise InputError(f"mu = {value} is not a friction coefficient; expected a finite number in "
                         f"[0, {MAX_FRICTION_COEFFICIENT:g}]")
    return value
