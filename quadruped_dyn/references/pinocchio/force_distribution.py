"""Ground reaction forces from Pinocchio quantities: the minimum-norm solution by SVD."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from quadruped_dyn.model.state import rotation
from quadruped_dyn.references.pinocchio.foot_terms import PinocchioFeet
from quadruped_dyn.tolerances import RANK_RTOL


@dataclass(frozen=True)
class GrfReference:
    lam: np.ndarray  # (n,) minimum-norm parameters
    f_b: np.ndarray  # (k, 3) stance-foot forces, trunk frame, N
    residual: np.ndarray  # (6,) w_req - A lambda: what the model cannot balance
    tau: np.ndarray  # (12,) joint torques with these forces, N m
    rank: int
    singular_values: np.ndarray
    w_req: np.ndarray  # (6,) required wrench (force; moment about the trunk origin), trunk frame


def min_norm_solution(A: np.ndarray, w: np.ndarray) -> tuple[np.ndarray, int, np.ndarray]:
    """(lambda, rank, singular values): the minimum-norm least-squares solution of A lambda = w by SVD,
    singular values below RANK_RTOL of the largest treated as zero."""
    U, S, Vt = np.linalg.svd(A, full_matrices=False)
    rank = int(np.sum(S > RANK_RTOL * S[0])) if S.size else 0
    return Vt[:rank].T @ ((U[:, :rank].T @ w) / S[:rank]), rank, S


class PinocchioForceDistribution(PinocchioFeet):
    """The trunk's wrench balance A lambda = w_req and its minimum-norm solution."""

    def grf_system(self, q: np.ndarray, feet: tuple[int, ...], P: np.ndarray) -> np.ndarray:
        """A (6, n): the trunk rows of the contact Jacobian's transpose acting on forces f = P lambda
        given in the trunk frame (sum_i [I; [r_i]x] f_i, from Pinocchio's contact Jacobian)."""
        if not P.size:
            return np.zeros((6, 0))
        Jc = self.contact_jacobian(q, feet)
        return Jc[:, :6].T @ np.kron(np.eye(len(feet)), rotation(q)) @ P

    def grf_solve(self, q: np.ndarray, v: np.ndarray, a: np.ndarray, feet: tuple[int, ...], P: np.ndarray) -> GrfReference:
        """Minimum-norm GRF by SVD from Pinocchio quantities: w_req = base rows of rnea(q, v, a),
        A = (base rows of Jc^T) blockdiag(R) P (forces f = P lambda in the trunk frame)."""
        tau_full = self.rnea(q, v, a)
        w_req = tau_full[:6]
        R = rotation(q)
        Jc = self.contact_jacobian(q, feet)
        Rk = np.kron(np.eye(len(feet)), R)
        A = self.grf_system(q, feet, P)
        lam, rank, S = min_norm_solution(A, w_req)
        f_b = P @ lam if P.size else np.zeros(0)
        tau = tau_full[6:] - Jc[:, 6:].T @ (Rk @ f_b) if P.size else tau_full[6:]
        return GrfReference(lam, f_b.reshape(-1, 3), w_req - A @ lam, tau, rank, S, w_req)
