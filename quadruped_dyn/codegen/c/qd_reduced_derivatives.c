/* quadruped_dyn: derivatives of the reduced forward dynamics (hand-written, inserted into each generated
 * qd_<robot>_r_<stance>.c after qd_reduced_solve.c, whose checks and LU it uses; see
 * quadruped_dyn/codegen/emit_derivatives.py and docs/derivatives.md).
 *
 * qd_dfd_r_<feet>(q_r, qd_r, tau_ext, quat) -> (dqdd_dq, dqdd_dqd, dqdd_dtau, dqdd_dtheta) of
 * qdd_r = M_r^-1 (tau_ext - C_r - G_r):
 *   M_r and C_r + G_r from the generated evaluations, M_r = LU (qd_fd_r_factor), qdd_r by the LU solve;
 *   then the columns D of d id_r / d(q_r, qd_r, theta) at (q_r, qd_r, qdd_r, quat), one forward-mode
 *   directional derivative (the generated qd_did_r_dir_<feet>) per unit direction, and
 *   d qdd_r / dx = -M_r^-1 D (x = q_r, qd_r, theta), d qdd_r / d tau_ext = M_r^-1, all by the same LU.
 * The trunk orientation is the separate input quat: dqdd_dq is the partial derivative at fixed quat
 * (its 13th column, the roll, is zero: the functions read the roll from quat, so that direction is not
 * evaluated), dqdd_dtheta (n x 3) the derivative along a body-frame increment quat -> quat (x) Exp(dtheta/2).
 * Outputs dense, column-major. Return codes as qd_fd_r_*: 0 ok, QD_NONFINITE, QD_SINGULAR (M_r singular to
 * working precision); no output is usable then. No heap; the temporaries (~6 kB in double) on the stack. */

/* n coordinates; nq of them (the first) are differentiated (the rest do not enter id_r: zero columns).
 * dir: the generated directional derivative (q_r, qd_r, qdd_r, quat, dq_r, dqd_r, dtheta) -> (dtau_r). */
QD_INLINE int qd_dfd_r_solve(int n, int nq, qd_eval_fn M_r, qd_eval_fn CG_r, qd_eval_fn dir, const casadi_real** arg,
                          casadi_real** res, casadi_int* iw, casadi_real* w, int mem) {
  casadi_real M[QD_N_MAX * QD_N_MAX], qdd[QD_N_MAX], X[QD_N_MAX * (3 * QD_N_MAX + 3)];
  casadi_real seed[2 * QD_N_MAX + 3];
  int piv[QD_N_MAX];
  int flag = qd_fd_r_factor(n, M_r, CG_r, arg, M, piv, qdd, iw, w, mem);
  if (flag) return flag;
  qd_lu_solve(n, M, piv, qdd);
  /* X's columns: q_r (n), qd_r (n), theta (3), tau_ext (n); the directions' seeds in one array */
  const int m = 2 * n + 3;
  for (int j = 0; j < m; ++j) seed[j] = 0;
  const casadi_real* d_arg[7] = {arg[0], arg[1], qdd, arg[3], seed, seed + n, seed + 2 * n};
  for (int j = 0; j < m; ++j) {
    casadi_real* x = X + n * j;
    if (j >= nq && j < n) { /* a coordinate id_r does not read */
      for (int i = 0; i < n; ++i) x[i] = 0;
      continue;
    }
    casadi_real* d_res[1] = {x};
    seed[j] = 1;
    flag = dir(d_arg, d_res, iw, w, mem);
    seed[j] = 0;
    if (flag) return flag;
    for (int i = 0; i < n; ++i) x[i] = -x[i];
    qd_lu_solve(n, M, piv, x);
  }
  for (int j = 0; j < n; ++j) { /* M_r^-1, column by column */
    casadi_real* x = X + n * (m + j);
    for (int i = 0; i < n; ++i) x[i] = i == j;
    qd_lu_solve(n, M, piv, x);
  }
  const int first[4] = {0, n, 2 * n + 3, 2 * n}, count[4] = {n, n, n, 3}; /* output k: columns of X */
  for (int k = 0; k < 4; ++k) {
    if (!res[k]) continue;
    const casadi_real* x = X + n * first[k];
    for (int i = 0; i < n * count[k]; ++i) res[k][i] = x[i];
  }
  const casadi_int nnz[4] = {n * n, n * n, n * n, 3 * n};
  return qd_finite(0, res, 4, nnz);
}
