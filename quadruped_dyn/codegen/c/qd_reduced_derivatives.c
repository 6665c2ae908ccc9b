/* quadruped_dyn: derivatives of the reduced forward dynamics (hand-written; in reduced_templates.h,
 * which each qd_<robot>_r_<stance>.c includes, after qd_reduced_solve.c, whose checks, M_r product and LU it uses; see
 * quadruped_dyn/codegen/emit_derivatives.py and docs/derivatives.md).
 *
 * qd_dfd_r_<feet>(q_r, qd_r, tau_ext, quat) -> (dqdd_dq, dqdd_dqd, dqdd_dtau, dqdd_dtheta) of
 * qdd_r = M_r^-1 (tau_ext - C_r - G_r), by the implicit-function rule d qdd_r/dx = -M_r^-1 d id_r/dx at
 * qdd_r (x = q_r, qd_r, theta), d qdd_r / d tau_ext = M_r^-1, and the chain rule over the full-coordinate
 * derivatives: id_r = S(q_r) F(q, v, a), F the full inverse dynamics (no foot forces) at q = (0, quat, q_j),
 * v = (v_b, qd_j), a = (a_b, qdd_j), S = [S_b, I] (row 12 of two feet: S_b only), so
 *   d id_r/dx = d(S_b F_b)/dx at fixed F + S (dF/dq dq/dx + dF/dv dv/dx + M da/dx),
 * with dF/dq, dF/dv from qd_did_full (qd_<robot>-d.c: same library); qdd_r as qd_fd_r_solve forms it (S_b, T_b, the
 * rnea at qdd_r = 0, M), F's trunk rows from that rnea's by M (rnea is linear in a). Only the trunk rows v_b, a_b ("the lift") depend on x other than by
 * identity: the generated qd_dfd_r_lift gives them once (the angles' sines and cosines taken once and passed in)
 * with its tape, the values of its algorithm that its derivative reads; their derivative along a joint angle or
 * theta is the generated qd_dfd_r_lift_columns over that tape (every direction the solve takes, in one graph whose unit
 * seeds are known: 2.3-2.4x fewer operations than one call per direction; at -Os qd_dfd_r_lift_dir, one forward-mode
 * direction per call, a quarter of the code), only for the stance legs' joints and, for two feet, theta; along qd_r,
 * dv_b = T_b and da_b from the same column, which also gives d(S_b F_b)/dq_r. The products in loops.
 * The trunk orientation is the separate input quat: dqdd_dq is the partial derivative at fixed quat (its
 * 13th column, the roll, is zero: the functions read the roll from quat), dqdd_dtheta (n x 3) the
 * derivative along a body-frame increment quat -> quat (x) Exp(dtheta/2), Pinocchio's convention for
 * did_full's rotation columns 3:6. Outputs dense, column-major. Return codes as qd_fd_r_*: 0 ok,
 * QD_NONFINITE, QD_SINGULAR (M_r singular to working precision); no output is usable then. No heap; the
 * temporaries in the caller's w (QD_DFD_R_W(n) reals, stated by the _work entry), ~1 kB on the stack (and
 * the lift's columns, (18 + n) K reals, but at -Os). */
#ifndef CASADI_PREFIX /* compiled alone, not pasted into a generated file (codegen/c_alone.py) */
#include "qd_alone.h"
#include "qd_reduced_solve.c"
#endif

/* defined in qd_<robot>-d.c of the same library (no work memory: checked by the generator): did_full leg by leg with
 * the joints' sines and cosines given, arg = (q, v, a, sin, cos), sin and cos of q[7..18], its legs' outputs in L
 * (QD_DID_FULL_L reals: dfd_r's w, not the stack, the Cortex-M budget); no test of its inputs or outputs (dfd_r tests
 * its own) */
int qd_did_full_trig_in(const casadi_real** arg, casadi_real** res, casadi_real* L, casadi_int* iw, casadi_real* w,
                        int mem);
const casadi_int* qd_did_full_sparsity_out(casadi_int i);

/* Reals of w qd_dfd_r_solve uses for n coordinates (the generator states the same number, checked below). */
#define QD_DFD_R_W(n) ((n) * (n) + 14 * (n) + 3 * 18 * 18 + 36 + (n) * QD_DFD_R_COLUMNS(n) + QD_DFD_R_TAPE + QD_DID_FULL_L)
/* right-hand sides of the one LU solve: the n angle and n rate columns, 3 rotations, and the n of M_r^-1 */
#define QD_DFD_R_COLUMNS(n) (3 * (n) + 3)

/* col (n) = -(S y + extra), S y = S_b y_b + y_j (rows 0..11; row 12 has no joint part); extra may be NULL. */
static void qd_dfd_r_column(int n, const casadi_real* restrict S_b, const casadi_real* restrict y, const casadi_real* restrict extra,
                            casadi_real* restrict col) {
  for (int i = 0; i < n; ++i) col[i] = i < 12 ? y[6 + i] : 0;
  for (int k = 0; k < 6; ++k) {
    for (int i = 0; i < n; ++i) col[i] += S_b[i + n * k] * y[k];
  }
  for (int i = 0; i < n; ++i) col[i] = -(col[i] + (extra ? extra[i] : 0));
}

/* y (18) += H[:, 0:6] dv + M[:, 0:6] da (18 x 18 column-major each): the trunk rows' change through F. */
static void qd_dfd_r_through_trunk(const casadi_real* restrict H, const casadi_real* restrict M, const casadi_real* restrict dv,
                                   const casadi_real* restrict da, casadi_real* restrict y) {
  for (int k = 0; k < 6; ++k) {
    for (int i = 0; i < 18; ++i) y[i] += H[i + 18 * k] * dv[k] + M[i + 18 * k] * da[k];
  }
}

/* Rows i of X's columns c0 .. c0 + W - 1: the lower (lower = 1: x_i -= sum_k<i L_ik x_k, the k ascending) or the
 * upper solve (x_i = (x_i - sum_k>i U_ik x_k, the k descending) (1 / U_ii)), row i's block kept in W locals (registers). */
static inline void qd_dfd_r_solve_block(int n, const casadi_real* restrict LU, casadi_real* restrict X, int m, int c0,
                                        int W, int lower) {
  for (int s = 0; s < n; ++s) {
    const int i = lower ? s : n - 1 - s;
    casadi_real acc[16];
    casadi_real* xi = X + m * i + c0;
    for (int c = 0; c < W; ++c) acc[c] = xi[c];
    if (lower) {
      for (int k = 0; k < i; ++k) {
        const casadi_real l = LU[i + n * k], *xk = X + m * k + c0;
        for (int c = 0; c < W; ++c) acc[c] -= l * xk[c];
      }
      for (int c = 0; c < W; ++c) xi[c] = acc[c];
    } else {
      for (int k = n - 1; k > i; --k) {
        const casadi_real u = LU[i + n * k], *xk = X + m * k + c0;
        for (int c = 0; c < W; ++c) acc[c] -= u * xk[c];
      }
      const casadi_real inv = 1 / LU[i + n * i]; /* one division per row, not per column */
      for (int c = 0; c < W; ++c) xi[c] = acc[c] * inv;
    }
  }
}

/* X (n rows of m right-hand sides, row-major) <- M^-1 X with the factors of qd_lu_factor: qd_lu_solve's operations
 * in its order for each column (row i's updates in the same order of k; U's diagonal as its reciprocal, one division
 * per row: within an ulp of qd_lu_solve's quotient), 16 columns at a time (then 8, 2, 1) with row i's block in registers (a triangular solve per column is a serial chain of n^2 / 2 dependent steps;
 * row by row across all m columns each multiply-subtract loads and stores x_i). */
static void qd_dfd_r_lu_solve_rows(int n, const casadi_real* restrict LU, const int* piv, casadi_real* restrict X, int m) {
  for (int k = 0; k < n; ++k) {
    casadi_real *a = X + m * k, *b = X + m * piv[k];
    for (int c = 0; c < m && b != a; ++c) {
      casadi_real t = a[c];
      a[c] = b[c];
      b[c] = t;
    }
  }
  for (int lower = 1; lower >= 0; --lower) {
    int c0 = 0;
    for (; c0 + 16 <= m; c0 += 16) qd_dfd_r_solve_block(n, LU, X, m, c0, 16, lower);
    for (; c0 + 8 <= m; c0 += 8) qd_dfd_r_solve_block(n, LU, X, m, c0, 8, lower);
    for (; c0 + 2 <= m; c0 += 2) qd_dfd_r_solve_block(n, LU, X, m, c0, 2, lower);
    for (; c0 < m; ++c0) qd_dfd_r_solve_block(n, LU, X, m, c0, 1, lower);
  }
}

/* column c of X (n x m, row-major) = col */
static void qd_dfd_r_put(int n, int m, casadi_real* X, int c, const casadi_real* col) {
  for (int i = 0; i < n; ++i) X[m * i + c] = col[i];
}

/* output k (n x ncol, column-major), if wanted, = columns first .. first + ncol of X (n x m, row-major) */
static void qd_dfd_r_store(int n, int m, casadi_real** res, int k, const casadi_real* X, int first, int ncol) {
  if (!res[k]) return;
  for (int j = 0; j < ncol; ++j) {
    for (int i = 0; i < n; ++i) res[k][i + n * j] = X[m * i + first + j];
  }
}

/* column c of qd_dfd_r_lift_columns' outputs L (dv_b, da_b: 6 x K, dSF: n x K, da_qd: 6 x K, column-major; K =
 * QD_DFD_R_LIFT_COLUMNS) into t_res (dv, da, dSF, da_qd): what qd_dfd_r_lift_dir gives along that column's seed */
static inline void qd_dfd_r_take(int n, int K, const casadi_real* L, int c, casadi_real** t_res) {
  const int first[4] = {0, 6 * K, 12 * K, 12 * K + n * K}, rows[4] = {6, 6, n, 6};
  for (int o = 0; o < 4; ++o) {
    for (int i = 0; i < rows[o]; ++i) t_res[o][i] = L[first[o] + rows[o] * c + i];
  }
}

/* n coordinates; legs: bit i set for a stance leg i (the lift and S depend on its joints only);
 * lift_quat: the lift depends on the trunk orientation (two feet). */
QD_INLINE int qd_dfd_r_solve(int n, int legs, int lift_quat, const casadi_real** arg, casadi_real** res, casadi_int* iw,
                             casadi_real* w, int mem) {
  if (!w) return QD_NO_WORK;
  casadi_real *M_r = w, *qdd = M_r + n * n, *S_b = qdd + n, *T_b = S_b + 6 * n, *M = T_b + 6 * n, *G = M + 18 * 18,
              *H = G + 18 * 18, *F = H + 18 * 18, *y = F + 18, *col = y + 18, *X = col + n, *tape = X + n * QD_DFD_R_COLUMNS(n);
  const int m = QD_DFD_R_COLUMNS(n);
  casadi_real q[19], v[18], a[18], k[18], dv[6], da[6], dSF[QD_N_MAX], da_qd[6], reg = 0;
  casadi_real dq[QD_N_MAX] = {0}, dqd[QD_N_MAX] = {0}, dtheta[3] = {0};
  qd_trig t; /* q_r's sines and cosines, once for the parts, id_full, M_full and the lift */
  qd_trig_of(n, arg[0], &t);
  int piv[QD_N_MAX];
  /* qdd_r as qd_fd_r_solve: the parts once (S_b, T_b, v and a at qdd_r = 0: k), C_r + G_r = S rnea(q, v, k), M_r */
  typedef char scratch_fits[QD_PARTS_WORK <= 18 * 18 ? 1 : -1]; /* the parts' scratch in M, used after them */
  (void)sizeof(scratch_fits);
  int flag = qd_parts(n, legs, arg[0], arg[1], 0, arg[3], &t, &reg, S_b, T_b, v, a, M, iw, w, mem);
  if (!flag) flag = qd_regular_value(reg);
  if (flag) return flag;
  qd_full_q(arg[0], arg[3], q);
  const casadi_real* d_arg[5] = {q, v, a, t.s, t.c};
  casadi_real* i_res[2] = {F, F + 6};
  flag = qd_id_full_trig(d_arg, i_res, iw, w, mem);
  if (!flag) flag = qd_M_at(q, &t, M, iw, w, mem, 0);
  if (flag) return flag;
  qd_project(n, S_b, F, qdd);
  qd_M_r_legs(n, legs, S_b, T_b, M, M_r);
  casadi_real scale; /* max|M_r| (qd_lu_factor's reference for a singular pivot) */
  flag = qd_fd_r_factor(n, arg[2], M_r, piv, qdd, &scale);
  if (flag) return flag;
  qd_lu_solve(n, M_r, piv, qdd);
  for (int i = 0; i < 18; ++i) k[i] = a[i];
  /* the lift at qdd_r and its tape; then v, a = (v_b, qd_j), (a_b, qdd_j) */
  const casadi_real* l_arg[6] = {arg[0], arg[1], qdd, arg[3], t.s, t.c}; /* the lift reads the angles' sines, cosines */
  casadi_real* l_res[3] = {v, a, tape};
  flag = qd_dfd_r_lift(l_arg, l_res, iw, w, mem);
  if (flag) return flag;
  for (int i = 0; i < 12; ++i) {
    v[6 + i] = arg[1][i];
    a[6 + i] = qdd[i];
  }
  /* F's trunk rows at (q, v, a) from those at (q, v, k), rnea being linear in a: F_b += M[0:6, :] (a - k); then
     dF/dq, dF/dv at (q, v, a) */
  for (int j = 0; j < 18; ++j) {
    const casadi_real d = a[j] - k[j];
    for (int i = 0; i < 6; ++i) F[i] += M[i + 18 * j] * d;
  }
  /* dF/dq's nonzeros in H's place, dF/dv's in X's (n (3n + 3) >= 18 x 18), each scattered into its dense matrix */
  const casadi_real* did_arg[5] = {q, v, a, t.s, t.c};
  casadi_real* d_res[3] = {H, X, 0};
  flag = qd_did_full_trig_in(did_arg, d_res, tape + QD_DFD_R_TAPE, iw, w, mem);
  if (flag) return flag;
  qd_scatter(qd_did_full_sparsity_out(0), H, G);
  qd_scatter(qd_did_full_sparsity_out(1), X, H);
  casadi_real* t_res[4] = {dv, da, dSF, da_qd};
#ifdef QD_DFD_R_LIFT_COLUMNS /* every seed's column at once (emit_derivatives.lift_seeds' order), taken in turn */
  casadi_real L[(18 + QD_N_MAX) * QD_DFD_R_LIFT_COLUMNS];
  const casadi_real* c_arg[2] = {tape, F};
  casadi_real* c_res[4] = {L, L + 6 * QD_DFD_R_LIFT_COLUMNS, L + 12 * QD_DFD_R_LIFT_COLUMNS,
                           L + (12 + n) * QD_DFD_R_LIFT_COLUMNS};
  flag = qd_dfd_r_lift_columns(c_arg, c_res, iw, w, mem);
  if (flag) return flag;
  int next = 0;
  (void)dq, (void)dtheta; /* the seeds, set below as qd_dfd_r_lift_dir reads them: here the columns' order is theirs */
#define QD_DFD_R_LIFT() (qd_dfd_r_take(n, QD_DFD_R_LIFT_COLUMNS, L, next++, t_res), 0)
#else /* one direction per call (-Os: a quarter of the code) */
  const casadi_real* t_arg[5] = {tape, F, dq, dtheta, dqd};
#define QD_DFD_R_LIFT() qd_dfd_r_lift_dir(t_arg, t_res, iw, w, mem)
#endif
  /* columns of -d id_r/dx, then M_r^-1 of each. theta: gravity in the trunk frame (did_full's rotation columns), the
     lift for two feet; the roll rate's da_b (its own output of the lift, seed dqd) in theta's first call */
  casadi_real da_roll[6];
  const int roll_with_theta = lift_quat && n > 12;
  for (int k = 0; k < 3; ++k) {
    for (int i = 0; i < 18; ++i) y[i] = G[i + 18 * (3 + k)];
    if (lift_quat) {
      dtheta[k] = 1;
      if (k == 0 && roll_with_theta) dqd[12] = 1;
      flag = QD_DFD_R_LIFT(); /* along (dq, dtheta, dqd) */
      dtheta[k] = 0;
      if (n > 12) dqd[12] = 0;
      if (flag) return flag;
      if (k == 0 && roll_with_theta) {
        for (int i = 0; i < 6; ++i) da_roll[i] = da_qd[i];
      }
      qd_dfd_r_through_trunk(H, M, dv, da, y);
    }
    qd_dfd_r_column(n, S_b, y, 0, col);
    qd_dfd_r_put(n, m, X, 2 * n + k, col);
  }
  /* the joint angle and rate j together (one lift call for a stance leg's joint; the roll, read by no function, has a
     zero column; its rate moves the lift) */
  for (int j = 0; j < n; ++j) {
    int moves = j < 12 ? legs >> (j / 3) & 1 : 1;
    if (moves && !(j >= 12 && roll_with_theta)) {
      dq[j] = j < 12;
      dqd[j] = 1;
      flag = QD_DFD_R_LIFT(); /* along (dq, dtheta, dqd) */
      dq[j] = dqd[j] = 0;
      if (flag) return flag;
    }
    for (int i = 0; i < 18; ++i) y[i] = j < 12 ? G[i + 18 * (6 + j)] : 0;
    if (moves && j < 12) qd_dfd_r_through_trunk(H, M, dv, da, y);
    qd_dfd_r_column(n, S_b, y, moves && j < 12 ? dSF : 0, col);
    qd_dfd_r_put(n, m, X, j, col);
    for (int i = 0; i < 18; ++i) y[i] = j < 12 ? H[i + 18 * (6 + j)] : 0;
    if (moves) qd_dfd_r_through_trunk(H, M, T_b + 6 * j, j >= 12 && roll_with_theta ? da_roll : da_qd, y); /* dv_b = T_b e_j */
    qd_dfd_r_column(n, S_b, y, 0, col);
    qd_dfd_r_put(n, m, X, n + j, col);
  }
  for (int i = 0; i < n; ++i) { /* M_r^-1 from the identity */
    for (int j = 0; j < n; ++j) X[m * i + 2 * n + 3 + j] = i == j;
  }
  qd_dfd_r_lu_solve_rows(n, M_r, piv, X, m);
  qd_dfd_r_store(n, m, res, 0, X, 0, n);
  qd_dfd_r_store(n, m, res, 1, X, n, n);
  qd_dfd_r_store(n, m, res, 3, X, 2 * n, 3);
  qd_dfd_r_store(n, m, res, 2, X, 2 * n + 3, n);
  const casadi_int nnz[4] = {n * n, n * n, n * n, 3 * n};
  return qd_finite(0, res, 4, nnz);
}
#undef QD_DFD_R_LIFT
