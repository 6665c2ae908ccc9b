"""Derivatives of the dynamics, symbolic (CasADi SX), in Pinocchio's tangent convention (docs/derivatives.md).

**Tangent convention.** A derivative with respect to the configuration q (19,) = (p, quaternion
x y z w, 12 joints) is taken along ``pinocchio.integrate(model, q, dq)``: dq (18,) = (dv_b, dw_b,
dq_j) is a body-frame (local) increment of the trunk's pose, p -> p + R dv_b, R -> R Exp([dw_b]x),
and joint angles q_j -> q_j + dq_j. So d/dq has 18 columns, not 19: none is a derivative with
respect to a quaternion entry. Velocities v = (v_b, w_b, qd) (body frame) and a = vdot (spatial
for the trunk, ``model/state.py``) are vector spaces and are differentiated entry by entry. This
is the convention of Pinocchio's ``computeRNEADerivatives`` / ``computeABADerivatives``, against
which these functions are checked. The dynamics do not depend on the trunk position p: the first
three columns of every d/dq are zero.

Functions (``derivative_functions(robot)``):

* ``did_full(q, v, a) -> (dtau_dq, dtau_dv, dtau_da)``: of the full inverse dynamics
  tau (18,) = rnea(q, v, a) = M(q) a + C(q, v) + G(q) (no foot forces; the 6 trunk rows are the
  trunk wrench, body frame); dtau_da = M (composite rigid bodies).
* ``dfd_full(q, v, tau) -> (da_dq, da_dv, da_dtau)``: of the full forward dynamics
  a = M^-1 (tau - C - G), tau (18,) = (trunk wrench, body frame; 12 joint torques). With
  a* = fd(q, v, tau): da/dx = -M^-1 d rnea/dx at a = a* (x = q, v), da/dtau = M^-1. Here M^-1 by a
  symbolic Cholesky factorisation (M is symmetric positive definite); the generated C factorises
  M once in plain C instead (``codegen/c/qd_derivatives_solve.c``).
* ``reduced_derivatives(robot, stance).dfd_r(q_r, qd_r, tau_ext, quat) -> (dqdd_dq, dqdd_dqd, dqdd_dtau,
  dqdd_dtheta)``: of
  the reduced forward dynamics qdd_r = M_r^-1 (tau_ext - C_r - G_r) (``reduced.py``), from the symbolic
  ``did_r`` (id_r and its Jacobians, ``reduced_projection``'s form) and a numeric LU solve. The trunk
  orientation is the separate input quat (it is not a function of q_r inside the reduced
  model): dqdd_dq (n, n) is the partial derivative at fixed quat (its 13th column, the roll,
  is zero: the functions read the roll from quat), and dqdd_dtheta (n, 3) the derivative along
  a body-frame increment of the trunk orientation, quat -> quat (x) exp(dtheta / 2) (the same
  local convention as above). Along a motion on the stance the orientation follows q_r with
  dtheta = W dq_r (W the angular rows of the velocity map, ``reduced_velocity_map``), so the total
  derivative is dqdd_dq + dqdd_dtheta W.
* ``dgrf_<stance>(q, v, a) -> (dlambda_dq, dlambda_dv, dlambda_da)``: of the paper's GRF solve's
  minimum-norm unknowns lambda (``grf.py``), q-derivative in the tangent convention above.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from functools import cache

import casadi as ca
import numpy as np

from quadruped_dyn.dynamics.grf import grf_solve
from quadruped_dyn.dynamics.guarded import GuardedFunction, guard_fields, guarded_call, with_condition
from quadruped_dyn.dynamics.newton_euler import gravity_in_trunk, inverse_dynamics
from quadruped_dyn.dynamics.reduced import MAX_COND_M_R, check_regularity, regularity_function, solve_forward_dynamics
from quadruped_dyn.dynamics.reduced_projection import reduced_projection
from quadruped_dyn.dynamics.rnea_derivatives import rnea_tangent_derivatives
from quadruped_dyn.errors import InputError, NumericalError
from quadruped_dyn.math.spatial import quat_to_rotation, skew
from quadruped_dyn.model.robot import Robot, check_robot
from quadruped_dyn.model.stance import StanceSet, stance_set
from quadruped_dyn.model.state import NQ_FULL, NV_FULL, check_array


def quaternion_tangent(quat: ca.SX) -> ca.SX:
    """(4, 3): d quat / d dtheta of quat (x) (dtheta / 2, 1) at dtheta = 0 (x y z w order), the
    first-order change of the quaternion under a body-frame rotation increment dtheta. It need
    not be unit: R(quat) is scale-invariant and so is this direction."""
    xyz, w = quat[:3], quat[3]
    return 0.5 * ca.vertcat(w * ca.SX.eye(3) + skew(xyz), -xyz.T)


def configuration_tangent(q: ca.SX) -> ca.SX:
    """(19, 18): d q / d dq of ``pinocchio.integrate(q, dq)`` at dq = 0: p -> p + R dv_b, the
    quaternion by ``quaternion_tangent``, joints by the identity."""
    T = ca.SX.zeros(NQ_FULL, NV_FULL)
    T[0:3, 0:3] = quat_to_rotation(q[3:7])
    T[3:7, 3:6] = quaternion_tangent(q[3:7])
    T[7:, 6:] = ca.SX.eye(12)
    return T


def tangent_jacobian(expr: ca.SX, q: ca.SX) -> ca.SX:
    """d expr / dq along ``pinocchio.integrate`` (module docstring): (rows, 18)."""
    return ca.jacobian(expr, q) @ configuration_tangent(q)


def cholesky_solve(M: ca.SX, B: ca.SX) -> ca.SX:
    """M^-1 B for a symmetric positive definite M (n x n), by M = L L^T (symbolic, n^3 / 6 products;
    backward stable for SPD M without pivoting)."""
    n = M.shape[0]
    L = [[ca.SX(0)] * n for _ in range(n)]
    for j in range(n):
        d = M[j, j] - sum((L[j][k] * L[j][k] for k in range(j)), ca.SX(0))
        L[j][j] = ca.sqrt(d)
        for i in range(j + 1, n):
            L[i][j] = (M[i, j] - sum((L[i][k] * L[j][k] for k in range(j)), ca.SX(0))) / L[j][j]
    y: list[ca.SX] = []
    for i in range(n):  # L y = B
        y.append((B[i, :] - sum((L[i][k] * y[k] for k in range(i)), ca.SX.zeros(1, B.shape[1]))) / L[i][i])
    x: list[ca.SX] = [ca.SX.zeros(1, B.shape[1])] * n
    for i in reversed(range(n)):  # L^T x = y
        x[i] = (y[i] - sum((L[k][i] * x[k] for k in range(i + 1, n)), ca.SX.zeros(1, B.shape[1]))) / L[i][i]
    return ca.vertcat(*x)


def _rnea(robot: Robot, q: ca.SX, v: ca.SX, a: ca.SX) -> ca.SX:
    return inverse_dynamics(robot, q[7:], gravity_in_trunk(q), v, a, ca.SX.zeros(12))


@dataclass(frozen=True)
class FullDerivatives:
    """Derivative Functions of the full-coordinate dynamics (module docstring for conventions)."""

    did_full: ca.Function  # q, v, a -> dtau_dq (18, 18), dtau_dv (18, 18), dtau_da = M (18, 18)
    did_full_ad: ca.Function  # the same by ``tangent_jacobian`` of the whole rnea (the convention, literally)
    dfd_full: ca.Function  # q, v, tau -> da_dq, da_dv, da_dtau = M^-1 (18, 18 each)
    fd_full: ca.Function  # q, v, tau -> a = M^-1 (tau - C - G) (18,)
    build_seconds: float
    mass_matrix: ca.Function | None = None  # q -> M (18, 18): the condition of dfd_full's and fd_full's solve

    def __post_init__(self) -> None:
        guard_fields(self)
        for name in ("dfd_full", "fd_full"):  # through M's solve: refused where M is numerically singular
            object.__setattr__(self, name, with_condition(getattr(self, name), self._solvable_at))

    def _solvable_at(self, values: list[np.ndarray]) -> None:
        """NumericalError where cond(M(q)) is not below MAX_COND_M_R, as the reduced model's fd_r."""
        if self.mass_matrix is None:
            return
        (M,) = guarded_call(self.mass_matrix, values[0])
        cond = float(np.linalg.cond(M))
        if not cond < MAX_COND_M_R:
            raise NumericalError(f"M has condition number {cond:.1e} here; the full model's forward dynamics and its "
                                 "derivatives are numerically singular (the robot's inertias: docs/reliability.md §2)")


def full_derivatives(robot: Robot) -> FullDerivatives:
    return _full_derivatives(check_robot(robot))


@cache
def _full_derivatives(robot: Robot) -> FullDerivatives:
    start = time.perf_counter()
    q, v, a, tau = ca.SX.sym("q", NQ_FULL), ca.SX.sym("v", NV_FULL), ca.SX.sym("a", NV_FULL), ca.SX.sym("tau", NV_FULL)
    dq, dv, M = rnea_tangent_derivatives(robot, q, v, a)
    opts = {"cse": True}
    did = ca.Function("did_full", [q, v, a], [dq, dv, M], ["q", "v", "a"], ["dtau_dq", "dtau_dv", "dtau_da"], opts)
    rnea = _rnea(robot, q, v, a)
    did_ad = ca.Function("did_full_ad", [q, v, a], [tangent_jacobian(rnea, q), ca.jacobian(rnea, v), ca.jacobian(rnea, a)],
                         ["q", "v", "a"], ["dtau_dq", "dtau_dv", "dtau_da"], opts)
    nle = _rnea(robot, q, v, ca.SX.zeros(NV_FULL))
    Minv = cholesky_solve(M, ca.SX.eye(NV_FULL))
    acc = Minv @ (tau - nle)
    dq_fd, dv_fd, _ = did(q, v, acc)
    dfd = ca.Function("dfd_full", [q, v, tau], [-Minv @ dq_fd, -Minv @ dv_fd, Minv], ["q", "v", "tau"],
                      ["da_dq", "da_dv", "da_dtau"], opts)
    fd = ca.Function("fd_full", [q, v, tau], [acc], ["q", "v", "tau"], ["a"], opts)
    mass = ca.Function("M_full_crba", [q], [M], ["q"], ["M"], opts)
    return FullDerivatives(did, did_ad, dfd, fd, time.perf_counter() - start, mass)


# ----------------------------------------------------------------------------- reduced model and GRF


def rotation_jacobian(expr: ca.SX, quat: ca.SX) -> ca.SX:
    """d expr / d dtheta (rows, 3) along quat -> quat (x) exp(dtheta / 2) (body-frame increment)."""
    return ca.jacobian(expr, quat) @ quaternion_tangent(quat)


@dataclass(frozen=True)
class ReducedDerivatives:
    """Derivatives of one stance set's reduced dynamics (module docstring); n = 12 or 13."""

    stance: StanceSet
    n: int
    #: q_r, qd_r, qdd_r, quat -> tau_r (n,), dtau_dq (n, n), dtau_dqd (n, n), dtau_dqdd = M_r (n, n),
    #: dtau_dtheta (n, 3): the reduced inverse dynamics and its derivatives (``reduced_projection``'s form)
    did_r: ca.Function
    velocity_map: ca.Function  # q_r, quat -> W (3, n): omega_b = W qd_r (for the total derivative)
    regularity: ca.Function  # q_r, quat -> the stance's regularity, checked before numeric calls

    def __post_init__(self) -> None:
        guard_fields(self)
        for name in ("did_r", "velocity_map"):  # a degenerate stance is a NumericalError, as in ReducedModel
            object.__setattr__(self, name, with_condition(getattr(self, name), self._regular_at))

    def _regular_at(self, values: list[np.ndarray]) -> None:
        check_regularity(self.stance, guarded_call(self.regularity, values[0], values[-1])[0].item())

    def dfd_r(self, q_r: np.ndarray, qd_r: np.ndarray, tau_ext: np.ndarray,
              quat: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """(dqdd_dq (n, n), dqdd_dqd (n, n), dqdd_dtau = M_r^-1 (n, n), dqdd_dtheta (n, 3)) at
        qdd_r = fd_r(q_r, qd_r, tau_ext, quat), by d qdd/dx = -M_r^-1 d id_r/dx there. Inputs are
        checked (InputError on a wrong shape, NaN/inf or a zero quaternion); NumericalError at a
        degenerate stance or a singular M_r, as ``ReducedModel.fd_r``."""
        zero = np.zeros(self.n)
        tau0, _, _, M, _ = guarded_call(self.did_r, q_r, qd_r, zero, quat)
        tau_ext = check_array("tau_ext", tau_ext, (self.n,))
        qdd, _ = solve_forward_dynamics(self.stance, M, tau_ext - tau0)
        _, Dq, Dqd, M, Dth = guarded_call(self.did_r, q_r, qd_r, qdd, quat)
        Minv = np.linalg.inv(M)
        return -Minv @ Dq, -Minv @ Dqd, Minv, -Minv @ Dth


def reduced_derivatives(robot: Robot, stance_name: str) -> ReducedDerivatives:
    """did_r and dfd_r of a stance set of 2, 3 or 4 feet: dfd_r by the implicit-function rule on
    id_r, d qdd/dx = -M_r^-1 d id_r/dx at qdd = fd_r (x = q_r, qd_r, theta), d qdd/d tau_ext = M_r^-1."""
    return _reduced_derivatives(check_robot(robot), stance_set(stance_name).name)  # checked before the cache hashes it


@cache
def _reduced_derivatives(robot: Robot, stance_name: str) -> ReducedDerivatives:
    stance = stance_set(stance_name)
    if len(stance.feet) not in (2, 3, 4):
        raise InputError(f"stance {stance.name} has {len(stance.feet)} feet; the reduced model needs 2, 3 or 4 stance feet")
    n = 13 if len(stance.feet) == 2 else 12
    q, qd, qdd, quat = (ca.SX.sym(s, k) for s, k in (("q_r", n), ("qd_r", n), ("qdd_r", n), ("quat", 4)))
    p = reduced_projection(robot, stance, q, quat)
    idr = p.inverse_dynamics(qd, qdd)
    name = stance.name.replace("+", "_")
    did = ca.Function(f"did_r_{name}", [q, qd, qdd, quat],
                      [idr, ca.jacobian(idr, q), ca.jacobian(idr, qd), ca.jacobian(idr, qdd), rotation_jacobian(idr, quat)],
                      ["q_r", "qd_r", "qdd_r", "quat"], ["tau_r", "dtau_dq", "dtau_dqd", "dtau_dqdd", "dtau_dtheta"],
                      {"cse": True})
    v, _ = p.velocity_and_bias(qd)
    W = ca.Function(f"velocity_map_{name}", [q, quat], [ca.jacobian(v[3:6], qd)], ["q_r", "quat"], ["W"])
    return ReducedDerivatives(stance, n, did, W, regularity_function(robot, stance))


def grf_derivatives(robot: Robot, stance_name: str) -> ca.Function:
    """dgrf_<stance>(q, v, a) -> dlambda_dq (n, 18, tangent convention), dlambda_dv (n, 18),
    dlambda_da (n, 18) of the paper's GRF model's minimum-norm unknowns."""
    return _grf_derivatives(check_robot(robot), stance_set(stance_name).name)  # checked before the cache hashes it


@cache
def _grf_derivatives(robot: Robot, stance_name: str) -> ca.Function:
    g = grf_solve(robot, stance_name, "paper")
    q, v, a = ca.SX.sym("q", NQ_FULL), ca.SX.sym("v", NV_FULL), ca.SX.sym("a", NV_FULL)
    lam = g.function(q, v, a)[0]
    name = g.stance.name.replace("+", "_")
    f = ca.Function(f"dgrf_{name}", [q, v, a], [tangent_jacobian(lam, q), ca.jacobian(lam, v), ca.jacobian(lam, a)],
                    ["q", "v", "a"], ["dlambda_dq", "dlambda_dv", "dlambda_da"], {"cse": True})
    return GuardedFunction(f)
