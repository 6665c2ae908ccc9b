"""Finite-difference values of the reduced model's and the GRF solve's derivatives (docs/derivatives.md).

Fourth-order central differences (step ``FD_STEP_DERIVATIVES``) of the Pinocchio-built model: the reduced
inverse dynamics ``PinocchioReference.reduced_inverse_dynamics`` (the forward dynamics' derivative from it by the
implicit-function rule, M_r built column by column from it, then a numpy solve) and Pinocchio's GRF solve (SVD).
Nothing here calls the project's CasADi code. The
conventions are those of ``dynamics/derivatives.py``: the trunk orientation of the reduced model is the
input quat (d/dq_r at fixed quat; d/dtheta along quat -> quat (x) exp(dtheta / 2), a body-frame
increment), and d/dq of the full configuration is along ``pinocchio.integrate`` (18 columns).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import pinocchio as pin

from quadruped_dyn.model.stance import StanceSet
from quadruped_dyn.model.state import NV_FULL
from quadruped_dyn.references.pinocchio import PinocchioDerivatives, PinocchioReference, min_norm_solution
from quadruped_dyn.tolerances import FD_STEP_DERIVATIVES


def central(f: Callable[[np.ndarray], np.ndarray], x0: np.ndarray, h: float = FD_STEP_DERIVATIVES) -> np.ndarray:
    """(rows, x0.size): fourth-order central differences of f at x0, one column per entry of x0,
    (8 (f(x + h) - f(x - h)) - (f(x + 2h) - f(x - 2h))) / 12h: truncation O(h^4) (``FD_STEP_DERIVATIVES``)."""

    def column(e: np.ndarray) -> np.ndarray:
        return (8 * (f(x0 + h * e) - f(x0 - h * e)) - (f(x0 + 2 * h * e) - f(x0 - 2 * h * e))) / (12 * h)

    return np.column_stack([column(e) for e in np.eye(x0.size)])


def rotated(quat: np.ndarray, dtheta: np.ndarray) -> np.ndarray:
    """quat (x) exp(dtheta / 2) (x y z w): a body-frame rotation increment dtheta [rad]."""
    return np.asarray((pin.Quaternion(np.asarray(quat, dtype=float)) * pin.Quaternion(pin.exp3(dtheta))).coeffs())


class ReducedFiniteDifferences:
    """The Pinocchio-built reduced forward dynamics of one stance set and its differences."""

    def __init__(self, ref: PinocchioReference, stance: StanceSet) -> None:
        self.ref, self.stance, self.P = ref, stance, stance.selection("paper")

    def id_r(self, q_r: np.ndarray, qd: np.ndarray, qdd: np.ndarray, quat: np.ndarray) -> np.ndarray:
        return self.ref.reduced_inverse_dynamics(self.stance.feet, self.P, q_r, qd, qdd, quat)

    def mass_matrix(self, q_r: np.ndarray, quat: np.ndarray) -> np.ndarray:
        return self.ref.reduced_mass_matrix(self.stance.feet, self.P, q_r, quat)

    def fd_r(self, q_r: np.ndarray, qd: np.ndarray, tau: np.ndarray, quat: np.ndarray, M: np.ndarray | None = None) -> np.ndarray:
        """qdd_r = M_r^-1 (tau - C_r - G_r) (M_r passed in when the configuration is unchanged)."""
        M = self.mass_matrix(q_r, quat) if M is None else M
        return np.linalg.solve(M, tau - self.id_r(q_r, qd, np.zeros(q_r.size), quat))

    def dfd_r(self, q_r: np.ndarray, qd: np.ndarray, tau: np.ndarray, quat: np.ndarray
              ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """(dqdd_dq, dqdd_dqd, M_r^-1, dqdd_dtheta) at qdd = ``fd_r``: id_r(x, qdd(x)) = tau for every x, so
        dqdd/dx = -M_r^-1 d id_r/dx at fixed qdd (the implicit-function rule, exact), d id_r/dx by central
        differences of ``id_r``. The same limit as differences of ``fd_r`` itself, for one M_r instead of one per
        difference point (M_r is built column by column: ~8x fewer id_r evaluations). Against the symbolic dfd_r
        (paper, four feet): 1.5e-11 / 9.1e-9 / 3.5e-9 relative for q_r / qd_r / theta, where differences of fd_r
        gave 2.1e-9 / 7.9e-9 / 2.7e-7 (``REL_TOL_FD_DERIVATIVES`` unchanged)."""
        M = self.mass_matrix(q_r, quat)
        qdd = self.fd_r(q_r, qd, tau, quat, M)
        Minv = np.linalg.inv(M)
        D_q = central(lambda x: self.id_r(x, qd, qdd, quat), q_r)
        D_qd = central(lambda x: self.id_r(q_r, x, qdd, quat), qd)
        D_theta = central(lambda th: self.id_r(q_r, qd, qdd, rotated(quat, th)), np.zeros(3))
        return -Minv @ D_q, -Minv @ D_qd, Minv, -Minv @ D_theta


def grf_derivatives_by_differences(ref: PinocchioReference, stance: StanceSet, q: np.ndarray, v: np.ndarray, a: np.ndarray
                              ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(dlambda_dq, dlambda_dv, dlambda_da) of Pinocchio's GRF solve by central differences, q along
    ``pinocchio.integrate``."""
    P, integrate = stance.selection("paper"), PinocchioDerivatives(ref).integrate

    def lam(q_: np.ndarray, v_: np.ndarray, a_: np.ndarray) -> np.ndarray:
        return ref.grf_solve(q_, v_, a_, stance.feet, P).lam

    return (central(lambda x: lam(integrate(q, x), v, a), np.zeros(NV_FULL)), central(lambda x: lam(q, x, a), v),
            central(lambda x: lam(q, v, x), a))


def grf_wrench_by_differences(ref: PinocchioReference, stance: StanceSet, q: np.ndarray, w: np.ndarray, dq: np.ndarray
                         ) -> tuple[np.ndarray, np.ndarray]:
    """(lambda_w, dlambda_w): Pinocchio's GRF solve for the trunk wrench w (SVD, minimum norm; the
    system A of ``PinocchioReference.grf_solve``) and its central difference along q -> integrate(q, t dq)."""
    P, integrate = stance.selection("paper"), PinocchioDerivatives(ref).integrate

    def lam(q_: np.ndarray) -> np.ndarray:
        return min_norm_solution(ref.grf_system(q_, stance.feet, P), w)[0]

    return lam(q), central(lambda t: lam(integrate(q, t[0] * dq)), np.zeros(1))[:, 0]
