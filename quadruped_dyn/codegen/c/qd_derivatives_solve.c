/* quadruped_dyn: derivatives of the full forward dynamics (hand-written, inserted into the
 * generated qd_<robot>-d.c; see quadruped_dyn/codegen/emit_derivatives.py).
 *
 * d/dq is along pinocchio.integrate(q, dq): dq (18) = (dv_b, dw_b, dq_joints), a body-frame
 * (local) increment of the trunk pose, p -> p + R dv_b, R -> R Exp([dw_b]x); 18 columns, none of
 * them a derivative with respect to a quaternion entry (docs/derivatives.md).
 *
 * qd_dfd_full(q, v, tau_full) -> (da_dq, da_dv, da_dtau), a = M^-1 (tau_full - C - G):
 *   M and C + G from qd_d_parts (qd_M_full and qd_nle_full of qd_<robot>.c), M^-1 by M's tree structure (qd_d_tree_inverse: the legs'
 *   3 x 3 blocks, then the trunk's Schur complement; no fill-in, ~2k multiply-adds), a = M^-1 (tau_full - C - G),
 *   then the generated qd_did_full at (q, v, a): da/dq = -M^-1 dtau/dq, da/dv = -M^-1 dtau/dv (sparse products),
 *   da/dtau = M^-1; da/dq's trunk-pose columns without the product (gravity is uniform: a = M^-1 (tau - C) + [g_b; 0],
 *   so they are 0 for the position and [[g_b]x; 0] for the rotation, read from dtau/dq's rotation rows -m [g_b]x), and
 *   da/dv's linear-velocity columns -[[w_b]x; 0] likewise (v_b enters only through the trunk's classical acceleration
 *   a_lin + w_b x v_b, so dtau/dv_b = M[:, 0:3] [w_b]x; the generator checks did_full's columns are that). Temporaries in the caller's w (QD_DFD_FULL_SZ_W reals, the function's _SZ_W).
 * Return codes: 0 ok; QD_NONFINITE (1) an input or output is NaN/inf (or a zero quaternion);
 * QD_SINGULAR (2) a pivot of M's Cholesky factorisation with the legs ordered first is below QD_SINGULAR_RTOL *
 * max diag(M) (M not positive definite to working precision: not a physical robot); the outputs are not
 * written then. */
#ifndef CASADI_PREFIX /* compiled alone, not pasted into a generated file (codegen/c_alone.py) */
#include "qd_alone.h"
#include "qd_dense.c"
#endif
#include <float.h>
#include <math.h>

#define QD_NV 18

typedef int (*qd_d_eval_fn)(const casadi_real**, casadi_real**, casadi_int*, casadi_real*, int);


/* defined in qd_<robot>.c of the same library (no work memory: checked by the generator) */
int qd_M_full(const casadi_real** arg, casadi_real** res, casadi_int* iw, casadi_real* w, int mem);
const casadi_int* qd_M_full_sparsity_out(casadi_int i);
int qd_nle_full(const casadi_real** arg, casadi_real** res, casadi_int* iw, casadi_real* w, int mem);

/* 1 if any of x[0..n) is NaN or inf: x * 0 is 0 for every finite x and NaN otherwise, summed in 8 independent
 * lanes (a reduction the compiler vectorises; one running flag or sum is a serial chain, ~6x slower here). */
static int qd_d_nonfinite(const casadi_real* restrict x, casadi_int n) {
  casadi_real s[8] = {0};
  casadi_int i = 0;
  for (; i + 8 <= n; i += 8) {
    for (int j = 0; j < 8; ++j) s[j] += x[i + j] * 0;
  }
  for (; i < n; ++i) s[0] += x[i] * 0;
  return !(s[0] + s[1] + s[2] + s[3] + s[4] + s[5] + s[6] + s[7] == 0);
}

/* f (n_in <= 3 inputs of <= 19 reals, read without testing their pointers) at arg, a NULL input as zeros
 * (CasADi's convention). */
static const casadi_real qd_d_zeros[19];
QD_INLINE int qd_d_all_inputs(qd_d_eval_fn f, int n_in, const casadi_real** arg, casadi_real** res, casadi_int* iw,
                              casadi_real* w, int mem) {
  const casadi_real* a[3];
  for (int i = 0; i < n_in; ++i) a[i] = arg[i] ? arg[i] : qd_d_zeros;
  return f(a, res, iw, w, mem);
}

/* flag, or QD_NONFINITE if any of the n_out outputs (nnz[i] entries each) is not finite. */
static int qd_d_finite(int flag, casadi_real** res, int n_out, const casadi_int* nnz) {
  if (flag) return flag;
  for (int i = 0; i < n_out; ++i) {
    if (res[i] && qd_d_nonfinite(res[i], nnz[i])) return QD_NONFINITE;
  }
  return 0;
}

/* x: the nonzeros of a CasADi sparsity sp (nrow, ncol, colind[ncol + 1], row[nnz]) -> the dense matrix,
 * column-major, in place (x holds nrow * ncol reals). Backwards: a nonzero's dense index is >= its own. */
static void qd_densify(const casadi_int* sp, casadi_real* x) {
  const casadi_int nrow = sp[0], ncol = sp[1], *colind = sp + 2, *row = sp + 3 + ncol;
  casadi_int next = nrow * ncol; /* entries from here on are final */
  for (casadi_int j = ncol - 1; j >= 0; --j) {
    for (casadi_int k = colind[j + 1] - 1; k >= colind[j]; --k) {
      casadi_int d = row[k] + nrow * j;
      casadi_real value = x[k];
      for (casadi_int i = d + 1; i < next; ++i) x[i] = 0;
      x[d] = value;
      next = d;
    }
  }
  for (casadi_int i = 0; i < next; ++i) x[i] = 0;
}

/* M (18 x 18, dense, column-major) and nle = C + G (18) at (q, v) = (arg[0], arg[1]) from qd_M_full and qd_nle_full,
 * not a second generated copy of them; either may be NULL. With scratch (>= M_full's nonzeros, apart from M),
 * M_full's nonzeros go there and are scattered into M (fewer instructions than densifying in place) and
 * QD_NONFINITE is returned if M has a NaN/inf. */
QD_INLINE int qd_d_parts(const casadi_real** arg, casadi_real* M, casadi_real* nle, casadi_real* scratch, casadi_int* iw,
                         casadi_real* w, int mem) {
  const casadi_int* sp = qd_M_full_sparsity_out(0);
  casadi_real* m_res[1] = {scratch ? scratch : M};
  int flag = M ? qd_M_full(arg, m_res, iw, w, mem) : 0;
  if (!flag && M) {
    if (scratch) qd_scatter(sp, scratch, M);
    else qd_densify(sp, M);
    if (scratch && qd_d_nonfinite(M, QD_NV * QD_NV)) return QD_NONFINITE;
  }
  m_res[0] = nle;
  if (!flag && nle) flag = qd_nle_full(arg, m_res, iw, w, mem);
  return flag;
}

/* qd_dfd_full_parts(q, v) -> (M (18 x 18, dense, column-major), nle = C + G (18)) by qd_d_parts. */
QD_INLINE int qd_dfd_full_parts_eval(const casadi_real** arg, casadi_real** res, casadi_int* iw, casadi_real* w, int mem) {
  return qd_d_parts(arg, res[0], res[1], 0, iw, w, mem);
}

/* out (18 x 18, column-major) = -Minv D for D in CasADi's compressed-column format (sp, nz), columns from first on,
 * each with a nonzero (the generator checks it): the accumulator starts at the first product, not at zeros
 * (fewer instructions; each entry's sum in the same order, so the same bits). */
#if defined(__GNUC__) && !defined(__clang__) /* GCC's -O3 unroll-and-jam turns the vectorised row loop into scalar code */
__attribute__((optimize("no-loop-unroll-and-jam")))
#endif
static void qd_d_neg_product(const casadi_real* restrict Minv, const casadi_int* sp, const casadi_real* restrict nz,
                             casadi_int first, casadi_real* restrict out) {
  const casadi_int ncol = sp[1], *colind = sp + 2, *row = sp + 2 + ncol + 1;
  for (casadi_int j = first; j < ncol; ++j) {
    casadi_real acc[QD_NV];
    const casadi_real* restrict m0 = Minv + QD_NV * row[colind[j]];
    const casadi_real d0 = nz[colind[j]];
    for (int i = 0; i < QD_NV; ++i) acc[i] = 0 - m0[i] * d0;
    for (casadi_int k = colind[j] + 1; k < colind[j + 1]; ++k) {
      const casadi_real* restrict m = Minv + QD_NV * row[k];
      const casadi_real d = nz[k];
      for (int i = 0; i < QD_NV; ++i) acc[i] -= m[i] * d;
    }
    for (int i = 0; i < QD_NV; ++i) out[i + QD_NV * j] = acc[i];
  }
}

/* a (n x n, column-major, n <= 6, symmetric positive definite) -> a^-1, by a = L L^T, L^-1 and a^-1 = L^-T L^-1.
 * QD_SINGULAR (a left as is or partly factorised) if a pivot is not above tol. */
static int qd_d_spd_inverse(casadi_real* restrict a, int n, casadi_real tol) {
  casadi_real x[36], r[6]; /* x = L^-1 (lower), r = 1 / diag(L) */
  for (int j = 0; j < n; ++j) { /* a = L L^T, L in the lower triangle */
    for (int k = 0; k < j; ++k) {
      const casadi_real u = a[j + n * k];
      for (int i = j; i < n; ++i) a[i + n * j] -= a[i + n * k] * u;
    }
    if (!(a[j + n * j] > tol)) return QD_SINGULAR;
    r[j] = 1 / qd_sqrt(a[j + n * j]);
    for (int i = j; i < n; ++i) a[i + n * j] *= r[j];
  }
  for (int j = 0; j < n; ++j) { /* L x_j = e_j */
    for (int i = 0; i < j; ++i) x[i + n * j] = 0;
    x[j + n * j] = r[j];
    for (int i = j + 1; i < n; ++i) {
      casadi_real s = 0;
      for (int k = j; k < i; ++k) s += a[i + n * k] * x[k + n * j];
      x[i + n * j] = -s * r[i];
    }
  }
  for (int j = 0; j < n; ++j) { /* a^-1 = X^T X */
    for (int i = 0; i <= j; ++i) {
      casadi_real s = 0;
      for (int k = j; k < n; ++k) s += x[k + n * i] * x[k + n * j];
      a[i + n * j] = s;
      a[j + n * i] = s;
    }
  }
  return 0;
}

/* Minv (18 x 18, column-major) = M^-1 by M's branch-induced sparsity (a tree: the trunk's 6 coordinates, then
 * four legs of 3 joints each coupled only to the trunk and to themselves): with the legs' blocks D_l (3 x 3),
 * their trunk coupling B_l (6 x 3) and E_l = D_l^-1 B_l^T, the Schur complement S = A - sum_l B_l E_l of the
 * trunk block A gives M^-1 = [[S^-1, -S^-1 E_l^T], [-E_l S^-1, delta_lm D_l^-1 + E_l S^-1 E_m^T]]. This is the
 * Cholesky factorisation of M with the legs ordered first (no fill-in): QD_SINGULAR if one of its pivots is not
 * above QD_SINGULAR_RTOL * max diag(M). blk: 4 * 9 + 4 * 18 + 36 reals. */
static int qd_d_tree_inverse(const casadi_real* restrict M, casadi_real* restrict Minv, casadi_real* restrict blk) {
  casadi_real *Dinv = blk, *E = blk + 4 * 9, *S = E + 4 * 18; /* E_l: 3 x 6, column-major */
  casadi_real scale = 0;
  for (int i = 0; i < QD_NV; ++i) scale = M[i + QD_NV * i] > scale ? M[i + QD_NV * i] : scale;
  const casadi_real tol = QD_SINGULAR_RTOL * scale;
  for (int i = 0; i < 6; ++i) {
    for (int j = 0; j < 6; ++j) S[i + 6 * j] = M[i + QD_NV * j];
  }
  for (int l = 0; l < 4; ++l) {
    const int o = 6 + 3 * l;
    casadi_real *Di = Dinv + 9 * l, *El = E + 18 * l;
    for (int c = 0; c < 3; ++c) {
      for (int r = 0; r < 3; ++r) Di[r + 3 * c] = M[o + r + QD_NV * (o + c)];
    }
    if (qd_d_spd_inverse(Di, 3, tol)) return QD_SINGULAR;
    for (int i = 0; i < 6; ++i) { /* E_l[:, i] = D_l^-1 B_l^T[:, i], B_l^T[c, i] = M[o + c, i] */
      for (int r = 0; r < 3; ++r) {
        El[r + 3 * i] = Di[r] * M[o + QD_NV * i] + Di[r + 3] * M[o + 1 + QD_NV * i] + Di[r + 6] * M[o + 2 + QD_NV * i];
      }
    }
    for (int j = 0; j < 6; ++j) { /* S -= B_l E_l */
      for (int i = 0; i < 6; ++i) {
        S[i + 6 * j] -= M[o + QD_NV * i] * El[3 * j] + M[o + 1 + QD_NV * i] * El[1 + 3 * j] + M[o + 2 + QD_NV * i] * El[2 + 3 * j];
      }
    }
  }
  if (qd_d_spd_inverse(S, 6, tol)) return QD_SINGULAR;
  for (int j = 0; j < 6; ++j) {
    for (int i = 0; i < 6; ++i) Minv[i + QD_NV * j] = S[i + 6 * j];
  }
  for (int l = 0; l < 4; ++l) { /* F_l = E_l S^-1 (3 x 6): Minv's leg-trunk block is -F_l */
    const int o = 6 + 3 * l;
    const casadi_real* El = E + 18 * l;
    for (int j = 0; j < 6; ++j) {
      for (int r = 0; r < 3; ++r) {
        casadi_real s = 0;
        for (int i = 0; i < 6; ++i) s += El[r + 3 * i] * S[i + 6 * j];
        Minv[o + r + QD_NV * j] = -s;
        Minv[j + QD_NV * (o + r)] = -s;
      }
    }
  }
  for (int l = 0; l < 4; ++l) { /* leg-leg blocks: delta_lm D_l^-1 + F_l E_m^T = delta_lm D_l^-1 - Minv[l, trunk] E_m^T */
    const int o = 6 + 3 * l;
    for (int m = 0; m <= l; ++m) {
      const int p = 6 + 3 * m;
      const casadi_real* Em = E + 18 * m;
      for (int c = 0; c < 3; ++c) {
        for (int r = 0; r < 3; ++r) {
          casadi_real s = m == l ? Dinv[9 * l + r + 3 * c] : 0;
          for (int i = 0; i < 6; ++i) s -= Minv[o + r + QD_NV * i] * Em[c + 3 * i];
          Minv[o + r + QD_NV * (p + c)] = s;
          Minv[p + c + QD_NV * (o + r)] = s;
        }
      }
    }
  }
  return 0;
}

QD_INLINE int qd_dfd_full_solve(qd_d_eval_fn did, const casadi_int* sp_dq, const casadi_int* sp_dv,
                             const casadi_real** arg, casadi_real** res, casadi_int* iw, casadi_real* w, int mem) {
  if (!w) return QD_NO_WORK;
  casadi_real *M = w, *Minv = M + QD_NV * QD_NV, *Dq = Minv + QD_NV * QD_NV, *Dv = Dq + QD_NV * QD_NV;
  casadi_real *nle = Dv + QD_NV * QD_NV, *a = nle + QD_NV, *blk = a + QD_NV, *rest = blk + 4 * 9 + 4 * 18 + 36;
  int flag = qd_d_parts(arg, M, nle, Minv, iw, rest, mem); /* M_full's nonzeros in Minv's place until the inverse */
  if (flag) return flag;
  if (qd_d_nonfinite(nle, QD_NV) | qd_d_nonfinite(arg[2], QD_NV)) return QD_NONFINITE;
  if (res[2]) Minv = res[2]; /* da/dtau = M^-1: formed in place (written only once every pivot has passed) */
  if (qd_d_tree_inverse(M, Minv, blk)) return QD_SINGULAR;
  for (int i = 0; i < QD_NV; ++i) a[i] = 0;
  for (int j = 0; j < QD_NV; ++j) {
    const casadi_real b = arg[2][j] - nle[j], *m = Minv + QD_NV * j;
    for (int i = 0; i < QD_NV; ++i) a[i] += m[i] * b;
  }
  const casadi_real* d_arg[3] = {arg[0], arg[1], a};
  casadi_real* d_res[3] = {Dq, Dv, 0};
  flag = did(d_arg, d_res, iw, rest, mem);
  if (flag) return flag;
  if (res[0]) { /* the trunk pose's columns without the product: gravity is uniform, a = M^-1 (tau - C) + [g_b; 0] */
    const casadi_int *colind = sp_dq + 2, *row = sp_dq + 2 + QD_NV + 1;
    for (int i = 0; i < 6 * QD_NV; ++i) res[0][i] = 0; /* position: 0; rotation: [[g_b]x; 0] */
    for (casadi_int j = 3; j < 6; ++j) { /* dtau/dq's rotation columns are -M[:, 0:3] [g_b]x, M[0:3, 0:3] = m I */
      for (casadi_int k = colind[j]; k < colind[j + 1] && row[k] < 3; ++k) res[0][row[k] + QD_NV * j] = -Dq[k] / M[0];
    }
    qd_d_neg_product(Minv, sp_dq, Dq, 6, res[0]);
  }
  if (res[1]) { /* the trunk's linear-velocity columns without the product: dtau/dv_b = M[:, 0:3] [w_b]x, so -[[w_b]x; 0] */
    const casadi_real* w_b = arg[1] + 3;
    for (int i = 0; i < 3 * QD_NV; ++i) res[1][i] = 0;
    res[1][1] = -w_b[2], res[1][2] = w_b[1];
    res[1][QD_NV] = w_b[2], res[1][QD_NV + 2] = -w_b[0];
    res[1][2 * QD_NV] = -w_b[1], res[1][2 * QD_NV + 1] = w_b[0];
    qd_d_neg_product(Minv, sp_dv, Dv, 3, res[1]);
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
 *   w_req = M[0:6] a + nle[0:6] from qd_d_parts; P column by column and d(P w)/dq one
 *   joint direction at a time (the joints of the stance legs, bit i of legs for leg i; no other coordinate
 *   enters P) from the generated qd_dgrf_dir_<feet> (dir: q, w, dq -> P w, d(P w)/dq dq); d w_req/dx from the
 *   generated qd_did_full's trunk rows (sp_dq, sp_dv: its output patterns) and M:
 *   dlambda/dq = P dtau_dq[0:6] + d(P w)/dq, dlambda/dv = P dtau_dv[0:6], dlambda/da = P M[0:6].
 * d/dq along pinocchio.integrate as above. Return codes: 0, QD_NONFINITE. */
QD_INLINE int qd_dgrf_solve(int m, int legs, qd_d_eval_fn did, qd_d_eval_fn dir, const casadi_int* sp_dq,
                         const casadi_int* sp_dv, const casadi_real** arg, casadi_real** res, casadi_int* iw, casadi_real* w,
                         int mem) {
  if (!w) return QD_NO_WORK;
  casadi_real *M = w, *Dq = M + QD_NV * QD_NV, *Dv = Dq + QD_NV * QD_NV, *nle = Dv + QD_NV * QD_NV, *seed = nle + QD_NV;
  casadi_real *wrench = seed + QD_NV, *P = wrench + 6, *dPw = P + 6 * 6, *rest = dPw + 6 * QD_NV; /* m <= 6 */
  int flag = qd_d_parts(arg, M, nle, Dq, iw, rest, mem); /* M_full's nonzeros in Dq's place until did_full */
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
    flag = dir(g_arg, g_res, iw, rest, mem);
    seed[k] = 0;
  }
  g_arg[1] = wrench; /* d(P w)/dq along each stance-leg joint, at w = w_req */
  for (int j = 0; j < QD_NV; ++j) {
    casadi_real* x = dPw + m * j;
    for (int i = 0; i < m; ++i) x[i] = 0;
    if (j < 6 || !(legs & (1 << ((j - 6) / 3))) || flag) continue;
    casadi_real* g_res[2] = {0, x};
    seed[j] = 1;
    flag = dir(g_arg, g_res, iw, rest, mem);
    seed[j] = 0;
  }
  if (flag) return flag;
  const casadi_real* d_arg[3] = {arg[0], arg[1], arg[2]};
  casadi_real* d_res[3] = {Dq, Dv, 0};
  flag = did(d_arg, d_res, iw, rest, mem);
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
