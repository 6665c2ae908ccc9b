/* quadruped_dyn: derivatives of the full forward dynamics (hand-written, inserted into the
 * generated qd_<robot>_d.c; see quadruped_dyn/codegen/emit_derivatives.py).
 *
 * d/dq is along pinocchio.integrate(q, dq): dq (18) = (dv_b, dw_b, dq_joints), a body-frame
 * (local) increment of the trunk pose, p -> p + R dv_b, R -> R Exp([dw_b]x); 18 columns, none of
 * them a derivative with respect to a quaternion entry (docs/derivatives.md).
 *
 * qd_dfd_full(q, v, tau_full) -> (da_dq, da_dv, da_dtau), a = M^-1 (tau_full - C - G):
 *   M and C + G from the generated qd_dfd_full_parts, M = L L^T (Cholesky, on the stack),
 *   M^-1 = L^-T L^-1, a = M^-1 (tau_full - C - G), then the generated qd_did_full at (q, v, a):
 *   da/dq = -M^-1 dtau/dq, da/dv = -M^-1 dtau/dv (sparse products), da/dtau = M^-1.
 * Return codes: 0 ok; QD_NONFINITE (1) an input or output is NaN/inf (or a zero quaternion);
 * QD_SINGULAR (2) a Cholesky pivot of M is below QD_SINGULAR_RTOL * max diag(M) (M not positive
 * definite to working precision: not a physical robot); the outputs are not written then. */
#include <float.h>
#include <math.h>

#ifndef QD_NONFINITE
#define QD_NONFINITE 1
#define QD_SINGULAR 2
#endif
#ifndef QD_EPS
#define QD_EPS (sizeof(casadi_real) == sizeof(float) ? (casadi_real)FLT_EPSILON \
                : sizeof(casadi_real) == sizeof(double) ? (casadi_real)DBL_EPSILON : (casadi_real)LDBL_EPSILON)
#define QD_SINGULAR_RTOL (450 * QD_EPS)
#endif
#define QD_NV 18

typedef int (*qd_d_eval_fn)(const casadi_real**, casadi_real**, casadi_int*, casadi_real*, int);

/* flag, or QD_NONFINITE if any of the n_out outputs (nnz[i] entries each) is not finite. */
/* Where a generated function is passed as a pointer, the template is inlined into its caller so the
 * call becomes direct and a static stack walk (-fcallgraph-info, docs/embedded.md) can bound it. */
#ifndef QD_INLINE
#if defined(__GNUC__)
#define QD_INLINE static inline __attribute__((always_inline))
#else
#define QD_INLINE static inline
#endif
#endif

static int qd_d_finite(int flag, casadi_real** res, int n_out, const casadi_int* nnz) {
  if (flag) return flag;
  for (int i = 0; i < n_out; ++i) {
    if (!res[i]) continue;
    for (casadi_int j = 0; j < nnz[i]; ++j) {
      if (!isfinite(res[i][j])) return QD_NONFINITE;
    }
  }
  return 0;
}

/* out (18 x 18, column-major) = -Minv D for D in CasADi's compressed-column format (sp, nz). */
static void qd_d_neg_product(const casadi_real* Minv, const casadi_int* sp, const casadi_real* nz, casadi_real* out) {
  const casadi_int ncol = sp[1], *colind = sp + 2, *row = sp + 2 + ncol + 1;
  for (casadi_int j = 0; j < ncol; ++j) {
    casadi_real* o = out + QD_NV * j;
    for (int i = 0; i < QD_NV; ++i) o[i] = 0;
    for (casadi_int k = colind[j]; k < colind[j + 1]; ++k) {
      const casadi_real* m = Minv + QD_NV * row[k]; /* Minv is symmetric: column row[k] = row row[k] */
      const casadi_real d = nz[k];
      for (int i = 0; i < QD_NV; ++i) o[i] -= m[i] * d;
    }
  }
}

QD_INLINE int qd_dfd_full_solve(qd_d_eval_fn parts, qd_d_eval_fn did, const casadi_int* sp_dq, const casadi_int* sp_dv,
                             const casadi_real** arg, casadi_real** res, casadi_int* iw, casadi_real* w, int mem) {
  casadi_real L[QD_NV * QD_NV], X[QD_NV * QD_NV], Minv[QD_NV * QD_NV], nle[QD_NV], a[QD_NV];
  casadi_real Dq[QD_NV * QD_NV], Dv[QD_NV * QD_NV];
  const casadi_real* p_arg[2] = {arg[0], arg[1]};
  casadi_real* p_res[2] = {L, nle};
  int flag = parts(p_arg, p_res, iw, w, mem);
  if (flag) return flag;
  casadi_real scale = 0, sum = 0; /* a NaN or inf anywhere makes the sum non-finite */
  for (int i = 0; i < QD_NV * QD_NV; ++i) sum += L[i];
  for (int i = 0; i < QD_NV; ++i) {
    sum += nle[i] + arg[2][i];
    scale = L[i + QD_NV * i] > scale ? L[i + QD_NV * i] : scale;
  }
  if (!isfinite(sum)) return QD_NONFINITE;
  for (int j = 0; j < QD_NV; ++j) { /* M = L L^T in place, lower triangle, L[i + n j] = L_ij */
    casadi_real* cj = L + QD_NV * j;
    for (int k = 0; k < j; ++k) {
      const casadi_real* ck = L + QD_NV * k;
      const casadi_real u = ck[j];
      for (int i = j; i < QD_NV; ++i) cj[i] -= ck[i] * u;
    }
    if (!(cj[j] > QD_SINGULAR_RTOL * scale)) return QD_SINGULAR;
    const casadi_real d = sqrt(cj[j]), inv = 1 / d;
    cj[j] = d;
    for (int i = j + 1; i < QD_NV; ++i) cj[i] *= inv;
  }
  for (int c = 0; c < QD_NV; ++c) { /* X = L^-1, lower triangular, column by column */
    casadi_real* x = X + QD_NV * c;
    for (int i = 0; i < c; ++i) x[i] = 0;
    x[c] = 1 / L[c + QD_NV * c];
    for (int i = c + 1; i < QD_NV; ++i) x[i] = 0;
    for (int k = c; k < QD_NV; ++k) { /* forward substitution, by columns of L */
      if (k > c) x[k] /= L[k + QD_NV * k];
      const casadi_real xk = x[k], *lk = L + QD_NV * k;
      for (int i = k + 1; i < QD_NV; ++i) x[i] -= lk[i] * xk;
    }
  }
  for (int j = 0; j < QD_NV; ++j) { /* M^-1 = X^T X */
    for (int i = 0; i <= j; ++i) {
      const casadi_real *xi = X + QD_NV * i, *xj = X + QD_NV * j;
      casadi_real s = 0;
      for (int k = j; k < QD_NV; ++k) s += xi[k] * xj[k];
      Minv[i + QD_NV * j] = s;
      Minv[j + QD_NV * i] = s;
    }
  }
  for (int i = 0; i < QD_NV; ++i) a[i] = 0;
  for (int j = 0; j < QD_NV; ++j) {
    const casadi_real b = arg[2][j] - nle[j], *m = Minv + QD_NV * j;
    for (int i = 0; i < QD_NV; ++i) a[i] += m[i] * b;
  }
  const casadi_real* d_arg[3] = {arg[0], arg[1], a};
  casadi_real* d_res[3] = {Dq, Dv, 0};
  flag = did(d_arg, d_res, iw, w, mem);
  if (flag) return flag;
  if (res[0]) qd_d_neg_product(Minv, sp_dq, Dq, res[0]);
  if (res[1]) qd_d_neg_product(Minv, sp_dv, Dv, res[1]);
  if (res[2]) {
    for (int i = 0; i < QD_NV * QD_NV; ++i) res[2][i] = Minv[i];
  }
  const casadi_int nnz[3] = {QD_NV * QD_NV, QD_NV * QD_NV, QD_NV * QD_NV};
  return qd_d_finite(0, res, 3, nnz);
}

/* out (m x 18, column-major) = P D[0:6, :] for P (m x 6, column-major) and D (18 x 18) in CasADi's
 * compressed-column format (sp, nz): the trunk rows of D only. */
static void qd_d_trunk_product(int m, const casadi_real* P, const casadi_int* sp, const casadi_real* nz, casadi_real* out) {
  const casadi_int nrow = sp[0], ncol = sp[1], dense = sp[2] == 1; /* CasADi writes a dense pattern as (nrow, ncol, 1) */
  const casadi_int *colind = sp + 2, *row = sp + 2 + ncol + 1;
  for (casadi_int j = 0; j < ncol; ++j) {
    casadi_real* o = out + m * j;
    for (int i = 0; i < m; ++i) o[i] = 0;
    const casadi_int begin = dense ? nrow * j : colind[j], end = dense ? nrow * j + 6 : colind[j + 1];
    for (casadi_int k = begin; k < end; ++k) { /* rows ascend within a column: stop after the trunk's */
      const casadi_int r = dense ? k - nrow * j : row[k];
      if (r >= 6) break;
      const casadi_real* p = P + m * r;
      const casadi_real d = nz[k];
      for (int i = 0; i < m; ++i) o[i] += p[i] * d;
    }
  }
}

/* qd_dgrf_<feet>(q, v, a) -> (dlambda_dq, dlambda_dv, dlambda_da), m x 18 each, of the GRF solve's
 * lambda = P(q) w_req(q, v, a), linear in the required trunk wrench w_req (the rnea's trunk rows):
 *   w_req = M[0:6] a + nle[0:6] from the generated qd_dfd_full_parts; P column by column and d(P w)/dq one
 *   joint direction at a time (the joints of the stance legs, bit i of legs for leg i; no other coordinate
 *   enters P) from the generated qd_dgrf_dir_<feet> (dir: q, w, dq -> P w, d(P w)/dq dq); d w_req/dx from the
 *   generated qd_did_full's trunk rows (sp_dq, sp_dv: its output patterns) and M:
 *   dlambda/dq = P dtau_dq[0:6] + d(P w)/dq, dlambda/dv = P dtau_dv[0:6], dlambda/da = P M[0:6].
 * d/dq along pinocchio.integrate as above. Return codes: 0, QD_NONFINITE. */
QD_INLINE int qd_dgrf_solve(int m, int legs, qd_d_eval_fn parts, qd_d_eval_fn did, qd_d_eval_fn dir, const casadi_int* sp_dq,
                         const casadi_int* sp_dv, const casadi_real** arg, casadi_real** res, casadi_int* iw, casadi_real* w,
                         int mem) {
  casadi_real M[QD_NV * QD_NV], nle[QD_NV], wrench[6], seed[QD_NV], P[6 * 6], dPw[6 * QD_NV], Dq[QD_NV * QD_NV],
      Dv[QD_NV * QD_NV];
  casadi_real* p_res[2] = {M, nle};
  int flag = parts(arg, p_res, iw, w, mem);
  if (flag) return flag;
  for (int i = 0; i < 6; ++i) {
    wrench[i] = nle[i];
    for (int j = 0; j < QD_NV; ++j) wrench[i] += M[i + QD_NV * j] * arg[2][j];
  }
  for (int i = 0; i < QD_NV; ++i) seed[i] = 0;
  const casadi_real* g_arg[3] = {arg[0], seed, seed}; /* P e_k: the wrench e_k, no direction */
  for (int k = 0; k < 6 && !flag; ++k) {
    casadi_real* g_res[2] = {P + m * k, 0};
    seed[k] = 1;
    flag = dir(g_arg, g_res, iw, w, mem);
    seed[k] = 0;
  }
  g_arg[1] = wrench; /* d(P w)/dq along each stance-leg joint, at w = w_req */
  for (int j = 0; j < QD_NV; ++j) {
    casadi_real* x = dPw + m * j;
    for (int i = 0; i < m; ++i) x[i] = 0;
    if (j < 6 || !(legs & (1 << ((j - 6) / 3))) || flag) continue;
    casadi_real* g_res[2] = {0, x};
    seed[j] = 1;
    flag = dir(g_arg, g_res, iw, w, mem);
    seed[j] = 0;
  }
  if (flag) return flag;
  const casadi_real* d_arg[3] = {arg[0], arg[1], arg[2]};
  casadi_real* d_res[3] = {Dq, Dv, 0};
  flag = did(d_arg, d_res, iw, w, mem);
  if (flag) return flag;
  if (res[0]) {
    qd_d_trunk_product(m, P, sp_dq, Dq, res[0]);
    for (int i = 0; i < m * QD_NV; ++i) res[0][i] += dPw[i];
  }
  if (res[1]) qd_d_trunk_product(m, P, sp_dv, Dv, res[1]);
  if (res[2]) { /* P M[0:6] (M dense) */
    for (int j = 0; j < QD_NV; ++j) {
      for (int i = 0; i < m; ++i) {
        casadi_real s = 0;
        for (int k = 0; k < 6; ++k) s += P[i + m * k] * M[k + QD_NV * j];
        res[2][i + m * j] = s;
      }
    }
  }
  const casadi_int nnz[3] = {m * QD_NV, m * QD_NV, m * QD_NV};
  return qd_d_finite(0, res, 3, nnz);
}
