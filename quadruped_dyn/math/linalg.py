"""Symbolic (CasADi SX) dense linear algebra that is backward stable: Householder QR.

CasADi's own symbolic ``qr``/``solve`` lose accuracy like cond(A)^2 on the GRF systems
(measured: up to ~200 cond(A) eps against ~1 cond(A) eps for LAPACK's SVD), so the small
systems here are solved with explicit Householder reflections. The sign choice uses
``if_else`` so that the generated C has no division by a vanishing norm.
"""

from __future__ import annotations

import casadi as ca


def householder_qr(M: ca.SX) -> tuple[list[ca.SX], ca.SX]:
    """M (m x n, m >= n) = Q R: the n reflection vectors v_j (unit, length m - j) and R (n x n)."""
    m, n = M.shape
    M = ca.SX(M)
    reflections = []
    for j in range(n):
        x = M[j:, j]
        norm = ca.norm_2(x)
        alpha = ca.if_else(x[0] >= 0, -norm, norm)
        v = x - alpha * ca.DM.eye(m - j)[:, 0]
        v = v / ca.norm_2(v)
        M[j:, j:] = M[j:, j:] - 2 * v @ (v.T @ M[j:, j:])
        reflections.append(v)
    return reflections, ca.triu(M[:n, :])


def _apply_qt(reflections: list[ca.SX], b: ca.SX) -> ca.SX:
    b = ca.SX(b)
    for j, v in enumerate(reflections):
        b[j:, :] = b[j:, :] - 2 * v @ (v.T @ b[j:, :])
    return b


def _apply_q(reflections: list[ca.SX], y: ca.SX, m: int) -> ca.SX:
    b = ca.vertcat(y, ca.SX.zeros(m - y.shape[0], y.shape[1]))
    for j in reversed(range(len(reflections))):
        v = reflections[j]
        b[j:, :] = b[j:, :] - 2 * v @ (v.T @ b[j:, :])
    return b


def _solve_upper(R: ca.SX, b: ca.SX, transpose: bool = False) -> ca.SX:
    """x with R x = b (R upper triangular), or R^T x = b with ``transpose``; b may have several columns."""
    n = R.shape[0]
    x = [ca.SX.zeros(1, b.shape[1])] * n
    for i in range(n) if transpose else reversed(range(n)):
        known = range(i) if transpose else range(i + 1, n)
        x[i] = (b[i, :] - sum(((R[j, i] if transpose else R[i, j]) * x[j] for j in known), ca.SX.zeros(1, b.shape[1]))) / R[i, i]
    return ca.vertcat(*x)


def least_squares(A: ca.SX, b: ca.SX) -> ca.SX:
    """argmin |A x - b| for A of full column rank (square included); b may have several columns."""
    reflections, R = householder_qr(A)
    return _solve_upper(R, _apply_qt(reflections, b)[: A.shape[1], :])


def min_norm(A: ca.SX, b: ca.SX) -> ca.SX:
    """The minimum-norm solution of A x = b for A of full row rank: A^T = Q R, x = Q R^-T b."""
    reflections, R = householder_qr(A.T)
    return _apply_q(reflections, _solve_upper(R, ca.SX(b), transpose=True), A.shape[1])
