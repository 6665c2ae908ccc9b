/* quadruped_dyn: checks and the forward-dynamics solve of the reduced model (hand-written; in reduced_templates.h,
 * which each qd_<robot>_r_<stance>.c includes (quadruped_dyn/codegen/emit.py) after QD_REGULARITY_MIN and
 * qd_stance_maps (the stance's maps from its feet's positions, codegen/forms/stance_maps.py, and its regularity
 * (r, quat) -> [0, 1] of dynamics/stance_regularity.py), from which qd_parts forms S_b, T_b, v, a. Every
 * entry point takes the joints' sines and cosines once (qd_trig) and passes them to the generated pieces and to the
 * library's qd_*_trig functions. The return codes are documented in qd_<robot>.h. */
#ifndef CASADI_PREFIX /* compiled alone, not pasted into a generated file (codegen/c_alone.py) */
#include "qd_alone.h"
#include "qd_sincos.c"
#include "qd_dense.c"
#endif
#include <float.h>
#include <math.h>
#include <string.h>

#define QD_N_MAX 13
/* Regularity is the square of a relative singular value of the feet's layout; computed from
 * foot positions rounded at eps, it cannot resolve values below ~(64 eps)^2 (float: 6e-11). */
#define QD_REGULARITY_FLOOR ((64 * QD_EPS) * (64 * QD_EPS))

/* Two reals at once where the compiler has vectors (GCC's and Clang's vector extension: SSE2 pairs on x86-64, NEON on
 * AArch64, scalar code where the target has none): the same operations on each entry, in the same order, as the scalar
 * loops below them, so the same results to the bit (docs/benchmark.md, "Design choices"). */
#if defined(__GNUC__) && !defined(QD_NO_PAIRS) /* QD_NO_PAIRS: the scalar loops (tests/codegen/test_pairs.py) */
typedef casadi_real qd_pair __attribute__((vector_size(2 * sizeof(casadi_real))));
#define QD_PAIRS 1
#endif

/* y (m) += A x: A (m x p, column-major, column stride lda), each entry's sum over k ascending; m even with pairs. */
QD_INLINE void qd_gemv(int m, int p, const casadi_real* A, int lda, const casadi_real* x, casadi_real* y) {
#ifdef QD_PAIRS
  if (!(m & 1)) {
    qd_pair s[(QD_N_MAX + 1) / 2], a;
    for (int i = 0; i < m / 2; ++i) memcpy(&s[i], y + 2 * i, sizeof a);
    for (int k = 0; k < p; ++k) {
      const casadi_real xk = x[k];
      for (int i = 0; i < m / 2; ++i) {
        memcpy(&a, A + 2 * i + lda * k, sizeof a);
        s[i] += a * xk;
      }
    }
    for (int i = 0; i < m / 2; ++i) memcpy(y + 2 * i, &s[i], sizeof a);
    return;
  }
#endif
  for (int k = 0; k < p; ++k) {
    for (int i = 0; i < m; ++i) y[i] += A[i + lda * k] * x[k];
  }
}

/* qd_gemv, one copy for all its calls (not inlined): fd_r's fold and K. An fd_r call runs ~38 kB of code, more than the
 * first-level instruction cache holds, and their products inlined were its largest piece (docs/benchmark.md, "Design
 * choices"). */
static QD_NOINLINE void qd_gemv_outlined(int m, int p, const casadi_real* A, int lda, const casadi_real* x, casadi_real* y) {
  qd_gemv(m, p, A, lda, x, y);
}

/* y (m) -= a u, entry by entry. */
QD_INLINE void qd_axpy_minus(int m, casadi_real u, const casadi_real* a, casadi_real* y) {
  int i = 0;
#ifdef QD_PAIRS
  for (; i + 2 <= m; i += 2) {
    qd_pair s, b;
    memcpy(&s, y + i, sizeof s);
    memcpy(&b, a + i, sizeof b);
    s -= b * u;
    memcpy(y + i, &s, sizeof s);
  }
#endif
  for (; i < m; ++i) y[i] -= a[i] * u;
}

/* flag, or QD_NONFINITE if any of the n_out outputs (nnz[i] entries each) is not finite: x - x is 0 for a finite x,
 * else NaN; four sums of it, branch-free and vectorised (~8x faster than isfinite per entry). Not -ffast-math. */
static int qd_finite(int flag, casadi_real** res, int n_out, const casadi_int* nnz) {
  if (flag) return flag;
  for (int i = 0; i < n_out; ++i) {
    if (!res[i]) continue;
    const casadi_real* x = res[i];
    casadi_real a[4] = {0, 0, 0, 0};
    casadi_int j = 0;
    for (; j + 4 <= nnz[i]; j += 4) {
      for (int k = 0; k < 4; ++k) a[k] += x[j + k] - x[j + k];
    }
    for (; j < nnz[i]; ++j) a[0] += x[j] - x[j];
    if (!(a[0] + a[1] + a[2] + a[3] == 0)) return QD_NONFINITE;
  }
  return 0;
}

/* Float builds only (a constant: the tests compile away in double and long double): a result is returned as 0 only where
 * the error bound the build computes is at most QD_FLOAT_MAX_BOUND (defined before this file:
 * quadruped_dyn.tolerances.FLOAT_MAX_BOUND): fd_r's eps * cond_1 of the matrix it eliminates (qd_bound_exceeded), and for
 * two feet every function's QD_FLOAT_ERR_PER_REGULARITY * eps / regularity (qd_regular_value). This makes the float
 * build's "returned 0 means within 1 %" a check instead of an observation (docs/embedded.md). */
#define QD_FLOAT_BOUND_CHECKED (sizeof(casadi_real) == sizeof(float))

/* 0 where a stance of regularity m is regular; QD_DEGENERATE or QD_NONFINITE. In the float build also QD_DEGENERATE where
 * QD_FLOAT_ERR_PER_REGULARITY * eps / m exceeds QD_FLOAT_MAX_BOUND (defined before this file: with two feet the maps'
 * rounding grows as eps / regularity, quadruped_dyn.tolerances.FLOAT_ERR_PER_REGULARITY; 0 for three and four feet). */
static int qd_regular_value(casadi_real m) {
  if (!isfinite(m)) return QD_NONFINITE;
  if (QD_FLOAT_BOUND_CHECKED && QD_FLOAT_ERR_PER_REGULARITY * QD_EPS > QD_FLOAT_MAX_BOUND * m) return QD_DEGENERATE;
  return m > QD_REGULARITY_MIN && m > QD_REGULARITY_FLOOR ? 0 : QD_DEGENERATE;
}

/* The sines and cosines of q_r's first n entries (the joint angles first), taken once per call (qd_sincos): n = 12
 * where nothing reads the roll's (q_r[12]; fd_r and the reduced terms), n = 13 where dfd_r's lift does. */
typedef struct {
  casadi_real s[QD_N_MAX], c[QD_N_MAX];
} qd_trig;

static void qd_trig_of(int n, const casadi_real* q_r, qd_trig* t) { qd_sincos(n, q_r, t->c, t->s); }

/* defined in qd_<robot>.c of the same library: leg k's foot kinematics y (QD_FOOT reals: codegen/forms/leg_pieces.py,
 * FOOT_PARTS) at its joints' q_l, qd_l and their sines s and cosines c (3 each): the foot's position r, J = dr/dq_l, J qd_l
 * and Jdot qd_l, trunk frame, read by QD_FOOT_R, QD_FOOT_J, QD_FOOT_JQD and QD_FOOT_JDQD (codegen/c_facts.py). */
int qd_foot_trig(int k, const casadi_real* q_l, const casadi_real* qd_l, const casadi_real* s, const casadi_real* c,
                 casadi_real* y);
/* qd_parts' scratch: the stance feet (QD_FOOT each), their positions, W_T and Y (6 x 3k each), y_e, s_e, D */
#define QD_PARTS_WORK (4 * QD_FOOT + 12 + 6 * 12 + 6 * 12 + 6 + 6 + 9)

/* c = a x b (3-vectors). */
static void qd_cross(const casadi_real* a, const casadi_real* b, casadi_real* c) {
  for (int d = 0; d < 3; ++d) c[d] = a[(d + 1) % 3] * b[(d + 2) % 3] - a[(d + 2) % 3] * b[(d + 1) % 3];
}

/* The parts of the reduced terms at (q_r, qd_r, qdd_r, quat) (null qd_r, qdd_r: zero), t q_r's sines and cosines, legs
 * bit l for a stance leg l (docs/formulation.md §6.2): the regularity *m, S_b (n x 6),
 * T_b (6 x n) (column-major; S = [S_b, I_12], T = [T_b; I_12], row/column 12 no joint part), the full v, a = T qdd_r + k.
 * Without rates (qd_r and qdd_r null) v and a are not written. The stance feet's kinematics (qd_foot_trig), the
 * stance's maps from their positions (qd_stance_maps, generated before this file: codegen/forms/stance_maps.py; W_T (6 x 3k),
 * Y (6 x 3k), with two feet y_e, s_e, D), then by foot j on leg l:
 * S_b's rows of l = -(W_T,j J_j)^T, T_b's columns of l = -Y_j J_j (row and column 12: s_e, y_e);
 * (v_b, omega_b) = sum_j Y_j (-J_j qd_j) + y_e qd_r[12] (= T_b qd_r); (a_b + omega_b x v_b, alpha_b) = sum_j Y_j b_j
 * + y_e b_e (= T_b qdd_r + the bias) with the stance rows' right-hand sides
 * b_j = -(omega_b x (omega_b x r_j) + 2 omega_b x J_j qd_j + Jdot_j qd_j) - J_j qdd_j, b_e = qdd_r[12] - (D omega_b) . omega_b. */
static int qd_parts(int n, int legs, const casadi_real* q_r, const casadi_real* qd_r, const casadi_real* qdd_r,
                    const casadi_real* quat, const qd_trig* t, casadi_real* m, casadi_real* restrict S_b,
                    casadi_real* restrict T_b, casadi_real* restrict v, casadi_real* restrict a,
                    casadi_real* restrict scratch, casadi_int* iw, casadi_real* w, int mem) {
  static const casadi_real zero[QD_N_MAX];
  const int rates = qd_r || qdd_r; /* else v and a are not written (M_r's and G_r's calls) */
  qd_r = qd_r ? qd_r : zero;
  qdd_r = qdd_r ? qdd_r : zero;
  /* in the caller's scratch (QD_PARTS_WORK reals, space it uses later: the Cortex-M stack budget): the feet, their
   * positions, W_T, Y, and e = (y_e, s_e, D) with two feet */
  casadi_real *foot = scratch, *r = foot + 4 * QD_FOOT, *W = r + 12, *Y = W + 6 * 12, *e = Y + 6 * 12;
  const int k = (legs & 1) + (legs >> 1 & 1) + (legs >> 2 & 1) + (legs >> 3 & 1); /* stance feet */
  int leg[4], flag = 0;
  for (int l = 0, j = 0; l < 4; ++l) {
    if (!(legs >> l & 1)) continue;
    casadi_real* y = foot + QD_FOOT * j;
    flag |= qd_foot_trig(l, q_r + 3 * l, rates ? qd_r + 3 * l : 0, t->s + 3 * l, t->c + 3 * l, y);
    for (int d = 0; d < 3; ++d) r[3 * j + d] = QD_FOOT_R(y, d);
    leg[j++] = l;
  }
  const casadi_real* m_arg[2] = {r, quat};
  casadi_real* m_res[6] = {m, W, Y, e, e + 6, e + 12};
  flag |= qd_stance_maps(m_arg, m_res, iw, w, mem);
  if (flag) return flag;
  for (int l = 0; l < 4; ++l) { /* the swing legs' rows of S_b and columns of T_b: zero */
    for (int c = 0; c < 3 && !(legs >> l & 1); ++c) {
      for (int col = 0; col < 6; ++col) S_b[3 * l + c + n * col] = T_b[col + 6 * (3 * l + c)] = 0;
    }
  }
  casadi_real vw[6] = {0, 0, 0, 0, 0, 0}, aw[6] = {0, 0, 0, 0, 0, 0};
  for (int j = 0; j < k; ++j) {
    const casadi_real* y = foot + QD_FOOT * j;
    const casadi_real *Y_j = Y + 18 * j, *W_j = W + 18 * j;
    casadi_real u[3];
    for (int c = 0; c < 3; ++c) { /* S_b's row and T_b's column of the joint 3 leg[j] + c: -W_T,j J_j e_c, -Y_j J_j e_c */
      const casadi_real Jc[3] = {-QD_FOOT_J(y, 0, c), -QD_FOOT_J(y, 1, c), -QD_FOOT_J(y, 2, c)};
      casadi_real s[6] = {0, 0, 0, 0, 0, 0}, *T_c = T_b + 6 * (3 * leg[j] + c);
      for (int col = 0; col < 6; ++col) T_c[col] = 0;
      qd_gemv(6, 3, W_j, 6, Jc, s);
      qd_gemv(6, 3, Y_j, 6, Jc, T_c);
      for (int col = 0; col < 6; ++col) S_b[3 * leg[j] + c + n * col] = s[col];
      u[c] = -QD_FOOT_JQD(y, c);
    }
    qd_gemv(6, 3, Y_j, 6, u, vw); /* (v_b, omega_b) = sum_j Y_j (-J_j qd_j) + y_e qd_r[12] */
  }
  if (n > 12) {
    for (int col = 0; col < 6; ++col) S_b[12 + n * col] = e[6 + col], T_b[col + 6 * 12] = e[col], vw[col] += e[col] * qd_r[12];
  }
  if (!rates) return 0;
  const casadi_real* o = vw + 3; /* omega_b */
  for (int j = 0; j < k; ++j) {
    const casadi_real* y = foot + QD_FOOT * j;
    const casadi_real* q_dd = qdd_r + 3 * leg[j];
    casadi_real x[3], b[3]; /* x = omega_b x r_j + 2 J_j qd_j; b = -(omega_b x x + Jdot_j qd_j) - J_j qdd_j */
    qd_cross(o, &QD_FOOT_R(y, 0), x);
    for (int d = 0; d < 3; ++d) x[d] += 2 * QD_FOOT_JQD(y, d);
    qd_cross(o, x, b);
    for (int d = 0; d < 3; ++d) {
      b[d] = -(b[d] + QD_FOOT_JDQD(y, d)) - (QD_FOOT_J(y, d, 0) * q_dd[0] + QD_FOOT_J(y, d, 1) * q_dd[1]
                                             + QD_FOOT_J(y, d, 2) * q_dd[2]);
    }
    qd_gemv(6, 3, Y + 18 * j, 6, b, aw);
  }
  if (n > 12) {
    const casadi_real* D = e + 12;
    casadi_real b_e = qdd_r[12];
    for (int d = 0; d < 3; ++d) b_e -= (D[d] * o[0] + D[d + 3] * o[1] + D[d + 6] * o[2]) * o[d];
    for (int i = 0; i < 6; ++i) aw[i] += e[i] * b_e;
  }
  casadi_real ov[3]; /* omega_b x v_b */
  qd_cross(o, vw, ov);
  for (int i = 0; i < 6; ++i) v[i] = vw[i];
  for (int d = 0; d < 3; ++d) a[d] = aw[d] - ov[d], a[3 + d] = aw[3 + d];
  for (int i = 0; i < 12; ++i) v[6 + i] = qd_r[i], a[6 + i] = qdd_r[i];
  return 0;
}

/* defined in qd_<robot>.c of the same library (no work memory: checked by the generator): M_full (dense, zeros
 * written), M's nonzero blocks (leg by leg), G_full, and id_full without foot forces (leg by leg) with the joints' sines
 * and cosines as their last two inputs, (q, sin, cos) and (q, v, a, sin, cos), sin and cos of q[7..18] */
int qd_M_full_dense_trig(const casadi_real** arg, casadi_real** res, casadi_int* iw, casadi_real* w, int mem);
int qd_M_blocks_legs_trig(const casadi_real** arg, casadi_real** res, casadi_int* iw, casadi_real* w, int mem);
int qd_G_full_trig(const casadi_real** arg, casadi_real** res, casadi_int* iw, casadi_real* w, int mem);
int qd_id_full_trig(const casadi_real** arg, casadi_real** res, casadi_int* iw, casadi_real* w, int mem);

/* q (19) = (0, quat, q_r's joint angles): the library's functions ignore the trunk position. */
static void qd_full_q(const casadi_real* q_r, const casadi_real* quat, casadi_real* q) {
  for (int i = 0; i < 3; ++i) q[i] = 0;
  for (int i = 0; i < 4; ++i) q[3 + i] = quat[i];
  for (int i = 0; i < 12; ++i) q[7 + i] = q_r[i];
}

/* M (18 x 18, dense column-major) at q (t: q_r's sines and cosines, q's joint angles), or with blocks only M's nonzero
 * blocks (QD_M_BLOCKS reals, read by QD_M_BB, QD_M_BL, QD_M_LL) leg by leg: the same values to round-off. Leg by leg
 * and without M's zeros the code is smaller, and a caller that runs much other code per call (fd_r) gains more from
 * that than it loses to the calls (docs/benchmark.md, "Design choices"). */
static int qd_M_at(const casadi_real* q, const qd_trig* t, casadi_real* M, casadi_int* iw, casadi_real* w, int mem,
                   int blocks) {
  const casadi_real* m_arg[3] = {q, t->s, t->c};
  casadi_real* m_res[1] = {M};
  return blocks ? qd_M_blocks_legs_trig(m_arg, m_res, iw, w, mem) : qd_M_full_dense_trig(m_arg, m_res, iw, w, mem);
}
/* M's blocks (codegen/forms/leg_pieces.py, mass_blocks; QD_M_BLOCKS, QD_M_BB, QD_M_BL, QD_M_LL: codegen/c_facts.py): M_bb
 * (6 x 6), then per leg l M_bl (6 x 3) and M_ll (3 x 3), each column-major; the blocks between two legs are zero and
 * M_lb = M_bl^T. */

/* M_r = S M T (n x n, column-major) by columns: mt = M[:, 0:6] T_b e_j + M[:, 6 + j], then S_b mt[0:6] + mt[6:18].
 * legs: bit i for a stance leg i; S_b's rows and T_b's columns of the other legs' joints are zero: no trunk product
 * there (15: none). */
QD_INLINE void qd_M_r_legs(int n, int legs, const casadi_real* S_b, const casadi_real* T_b, const casadi_real* M,
                           casadi_real* M_r) {
  for (int j = 0; j < n; ++j) {
    casadi_real mt[18];
    if (j < 12) {
      for (int i = 0; i < 18; ++i) mt[i] = M[i + 18 * (6 + j)];
    } else {
      for (int i = 0; i < 18; ++i) mt[i] = 0;
    }
    if (j >= 12 || legs >> (j / 3) & 1) {
      const casadi_real* t = T_b + 6 * j;
      for (int k = 0; k < 6; ++k) {
        for (int i = 0; i < 18; ++i) mt[i] += M[i + 18 * k] * t[k];
      }
    }
    casadi_real col[QD_N_MAX]; /* a local column: the compiler need not assume that M_r aliases S_b (dfd_r's w) */
    for (int i = 0; i < 12; ++i) col[i] = mt[6 + i];
    if (n > 12) col[12] = 0;
    for (int k = 0; k < 6; ++k) {
      if (n == 12) { /* three or four feet: all rows (vectorised) */
        for (int i = 0; i < 12; ++i) col[i] += S_b[i + n * k] * mt[k];
        continue;
      }
      for (int l = 0; l < 4; ++l) { /* two feet: the swing legs' rows of S_b are zero */
        for (int i = 3 * l; i < 3 * l + 3 && (legs >> l & 1); ++i) col[i] += S_b[i + n * k] * mt[k];
      }
      col[12] += S_b[12 + n * k] * mt[k];
    }
    for (int i = 0; i < n; ++i) M_r[i + n * j] = col[i];
  }
}

/* tau (n) = S F = S_b F[0:6] + F[6:18] (row 12, two feet: S_b only) for a full generalized force F (18). */
static void qd_project(int n, const casadi_real* S_b, const casadi_real* F, casadi_real* tau) {
  casadi_real s[QD_N_MAX]; /* every row at once (vectorised), each row's sum over k ascending */
  for (int i = 0; i < n; ++i) s[i] = i < 12 ? F[6 + i] : 0;
  for (int k = 0; k < 6; ++k) {
    for (int i = 0; i < n; ++i) s[i] += S_b[i + n * k] * F[k];
  }
  for (int i = 0; i < n; ++i) tau[i] = s[i];
}

/* tau (n) = S rnea(q, v, a), rnea by the library's qd_id_full_trig (no foot forces; t: q_r's sines and cosines);
 * work: QD_RNEA_R_WORK reals, the caller's (fd_r lends space it uses later: Cortex-M stack budget). */
static int qd_rnea_r(int n, const casadi_real* S_b, const casadi_real* q_r, const casadi_real* quat, const qd_trig* t,
                     const casadi_real* v, const casadi_real* a, casadi_real* tau, casadi_real* work, casadi_int* iw,
                     casadi_real* w, int mem) {
  casadi_real *q = work, *F = q + 19;
  qd_full_q(q_r, quat, q);
  const casadi_real* i_arg[5] = {q, v, a, t->s, t->c};
  casadi_real* i_res[2] = {F, F + 6};
  int flag = qd_id_full_trig(i_arg, i_res, iw, w, mem);
  if (!flag) qd_project(n, S_b, F, tau);
  return flag;
}
#define QD_RNEA_R_WORK (19 + 18)

/* The reduced terms (dynamics/reduced_projection.py) into res[0] (n): which = 0 M_r (arg = q_r, quat; S M T),
 * 1 C_r + G_r (q_r, qd_r, quat; S rnea(q, v, k)), 2 G_r (q_r, quat; S G_full), 3 id_r (q_r, qd_r, qdd_r, quat;
 * S rnea(q, v, T qdd_r + k)); legs as qd_M_r_legs'. Regularity checked first (res[0] written only on 0). */
QD_INLINE int qd_reduced_term(int n, int legs, int which, const casadi_real** arg, casadi_real** res, casadi_int* iw,
                              casadi_real* w, int mem) {
  const casadi_real* quat = arg[which == 1 ? 2 : which == 3 ? 3 : 1];
  const casadi_real* qd_r = which == 1 || which == 3 ? arg[1] : 0;
  casadi_real m = 0, S_b[QD_N_MAX * 6], T_b[6 * QD_N_MAX], v[18], a[18], M[18 * 18]; /* M: the parts' scratch first */
  typedef char scratch_fits[QD_PARTS_WORK <= 18 * 18 ? 1 : -1];
  (void)sizeof(scratch_fits);
  qd_trig t;
  qd_trig_of(12, arg[0], &t);
  int flag = qd_parts(n, legs, arg[0], qd_r, which == 3 ? arg[2] : 0, quat, &t, &m, S_b, T_b, v, a, M, iw, w, mem);
  if (!flag) flag = qd_regular_value(m);
  if (flag || !res[0]) return flag;
  if (which == 1 || which == 3) {
    casadi_real work[QD_RNEA_R_WORK];
    return qd_rnea_r(n, S_b, arg[0], quat, &t, v, a, res[0], work, iw, w, mem);
  }
  casadi_real q[19];
  qd_full_q(arg[0], quat, q);
  if (which == 2) {
    const casadi_real* g_arg[3] = {q, t.s, t.c};
    casadi_real* g_res[1] = {M};
    flag = qd_G_full_trig(g_arg, g_res, iw, w, mem);
    if (!flag) qd_project(n, S_b, M, res[0]);
    return flag;
  }
  flag = qd_M_at(q, &t, M, iw, w, mem, 0);
  if (!flag) qd_M_r_legs(n, legs, S_b, T_b, M, res[0]);
  return flag;
}

/* LU factorisation with partial pivoting of M (n x n, column-major, in place: L's multipliers below the diagonal,
 * U on and above; piv[k] the row swapped with k at step k), the inner loops down contiguous columns. 0, or
 * QD_SINGULAR when a pivot is below QD_SINGULAR_RTOL * scale. Shared by fd_r and the reduced derivatives. */
static int qd_lu_factor(int n, casadi_real* M, int* piv, casadi_real scale) {
  for (int k = 0; k < n; ++k) { /* M[i + n j] = M_ij */
    casadi_real* col = M + n * k;
    int p = k;
    for (int i = k + 1; i < n; ++i) p = qd_fabs(col[i]) > qd_fabs(col[p]) ? i : p;
    if (!(qd_fabs(col[p]) > QD_SINGULAR_RTOL * scale)) return QD_SINGULAR;
    piv[k] = p;
    if (p != k) {
      for (int j = 0; j < n; ++j) {
        casadi_real t = M[k + n * j];
        M[k + n * j] = M[p + n * j];
        M[p + n * j] = t;
      }
    }
    casadi_real inv = 1 / col[k];
    for (int i = k + 1; i < n; ++i) col[i] *= inv; /* the multipliers, L below the diagonal */
    for (int j = k + 1; j < n; ++j) {
      casadi_real* cj = M + n * j;
      casadi_real u = cj[k];
      for (int i = k + 1; i < n; ++i) cj[i] -= col[i] * u;
    }
  }
  return 0;
}

/* x <- M^-1 x with the factors of qd_lu_factor: the row swaps, L y = P x, U x = y. */
static void qd_lu_solve(int n, const casadi_real* LU, const int* piv, casadi_real* x) {
  for (int k = 0; k < n; ++k) {
    casadi_real t = x[k];
    x[k] = x[piv[k]];
    x[piv[k]] = t;
  }
  for (int k = 0; k < n; ++k) {
    const casadi_real* col = LU + n * k;
    for (int i = k + 1; i < n; ++i) x[i] -= col[i] * x[k];
  }
  for (int j = n - 1; j >= 0; --j) { /* U x = y, column by column */
    x[j] /= LU[j + n * j];
    for (int i = 0; i < j; ++i) x[i] -= LU[i + n * j] * x[j];
  }
}

/* x <- M^-1 x for A = [M, x] (n x (n + 1), column-major; x its last column): Gaussian elimination with partial
 * pivoting, x updated with M's columns as it goes (one pass fewer over M than qd_lu_factor + qd_lu_solve), then
 * U x = y. A is overwritten (U on and above the diagonal, step k's multipliers below it in column k, rows swapped only
 * from column k on); piv, unless null, gets the row swapped with k at step k (qd_bound_exceeded's solves). 0, or
 * QD_SINGULAR when a pivot is below QD_SINGULAR_RTOL * scale (qd_lu_factor's test). */
QD_INLINE int qd_gauss_solve(int n, casadi_real* A, casadi_real scale, int* piv) {
  casadi_real inv[QD_N_MAX]; /* 1 / U's diagonal, for U x = y */
  for (int k = 0; k < n; ++k) { /* A[i + n j] = A_ij */
    casadi_real* col = A + n * k;
    int p = k; /* the first entry of largest magnitude, found by its value (a chain of compares, not of loads) */
    casadi_real big = qd_fabs(col[k]), pv = col[k]; /* pv = col[p]: 1 / pv need not wait for the rows' swap */
    for (int i = k + 1; i < n; ++i) {
      const casadi_real a = qd_fabs(col[i]);
      p = a > big ? i : p;
      pv = a > big ? col[i] : pv;
      big = a > big ? a : big;
    }
    if (!(big > QD_SINGULAR_RTOL * scale)) return QD_SINGULAR;
    if (piv) piv[k] = p;
    inv[k] = 1 / pv;
    if (p != k) { /* the columns left of k are not read again */
      for (int j = k; j <= n; ++j) {
        casadi_real t = A[k + n * j];
        A[k + n * j] = A[p + n * j];
        A[p + n * j] = t;
      }
    }
    for (int i = k + 1; i < n; ++i) col[i] *= inv[k]; /* the multipliers */
    for (int j = k + 1; j <= n; ++j) {
      casadi_real* cj = A + n * j;
      casadi_real u = cj[k];
      qd_axpy_minus(n - k - 1, u, col + k + 1, cj + k + 1);
    }
  }
  casadi_real* x = A + n * n;
  for (int j = n - 1; j >= 0; --j) { /* U x = y, column by column; products, not divisions, on its chain */
    x[j] *= inv[j];
    for (int i = 0; i < j; ++i) x[i] -= A[i + n * j] * x[j];
  }
  return 0;
}

/* max|x_i| over n entries (four lanes: the compiler vectorises them); NaN entries are skipped (qd_finite tests them). */
static casadi_real qd_max_abs(int n, const casadi_real* x) {
  casadi_real top[4] = {0, 0, 0, 0};
  int i = 0;
  for (; i + 4 <= n; i += 4) {
    for (int k = 0; k < 4; ++k) top[k] = qd_fabs(x[i + k]) > top[k] ? qd_fabs(x[i + k]) : top[k];
  }
  for (; i < n; ++i) top[0] = qd_fabs(x[i]) > top[0] ? qd_fabs(x[i]) : top[0];
  casadi_real a = top[0] > top[1] ? top[0] : top[1], b = top[2] > top[3] ? top[2] : top[3];
  return a > b ? a : b;
}

/* ||A||_1 (n x n, column-major): the largest column sum of |A_ij|. */
static casadi_real qd_norm1(int n, const casadi_real* A) {
  casadi_real top = 0;
  for (int j = 0; j < n; ++j) {
    casadi_real s = 0;
    for (int i = 0; i < n; ++i) s += qd_fabs(A[i + n * j]);
    top = s > top ? s : top;
  }
  return top;
}

/* fd_r's float bound (the float error measured at most 0.94 eps cond_1 on the paper robot, 300 states near standing,
 * tests/checks/test_float_accuracy.py): QD_SINGULAR where eps * ||A||_1 ||A^-1||_1 > QD_FLOAT_MAX_BOUND, else 0: LU and piv A's factors from qd_gauss_solve,
 * norm1 = ||A||_1 taken before it; ||A^-1||_1 exactly, column by column (n solves of n^2 multiply-adds: the row swaps
 * and multipliers in the order of the elimination, then U). */
static int qd_bound_exceeded(int n, const casadi_real* LU, const int* piv, casadi_real norm1) {
  casadi_real inv_norm1 = 0;
  for (int c = 0; c < n; ++c) {
    casadi_real x[QD_N_MAX] = {0}, s = 0;
    x[c] = 1;
    for (int k = 0; k < n; ++k) {
      casadi_real t = x[k];
      x[k] = x[piv[k]];
      x[piv[k]] = t;
      for (int i = k + 1; i < n; ++i) x[i] -= LU[i + n * k] * x[k];
    }
    for (int j = n - 1; j >= 0; --j) {
      x[j] /= LU[j + n * j];
      for (int i = 0; i < j; ++i) x[i] -= LU[i + n * j] * x[j];
    }
    for (int i = 0; i < n; ++i) s += qd_fabs(x[i]);
    inv_norm1 = s > inv_norm1 ? s : inv_norm1;
  }
  return QD_EPS * norm1 * inv_norm1 > QD_FLOAT_MAX_BOUND ? QD_SINGULAR : 0;
}

/* qd_gauss_solve of A = [M, x] (n x (n + 1)), and in the float build qd_bound_exceeded's test of M after it. */
QD_INLINE int qd_gauss_solve_bounded(int n, casadi_real* A, casadi_real scale) {
  casadi_real norm1 = QD_FLOAT_BOUND_CHECKED ? qd_norm1(n, A) : 0;
  int piv[QD_N_MAX];
  int flag = qd_gauss_solve(n, A, scale, QD_FLOAT_BOUND_CHECKED ? piv : 0);
  return !flag && QD_FLOAT_BOUND_CHECKED ? qd_bound_exceeded(n, A, piv, norm1) : flag;
}

/* b <- tau_ext - b (b: C_r + G_r), *max = max|M| (M = M_r), both checked, and M's LU (qd_lu_factor): dfd_r's.
 * 0, QD_NONFINITE or QD_SINGULAR. */
static int qd_fd_r_factor(int n, const casadi_real* tau_ext, casadi_real* M, int* piv, casadi_real* b, casadi_real* max) {
  casadi_real* res[2] = {M, b};
  casadi_int nnz[2] = {n * n, n};
  for (int i = 0; i < n; ++i) b[i] = tau_ext[i] - b[i];
  if (qd_finite(0, res, 2, nnz)) return QD_NONFINITE;
  *max = qd_max_abs(n * n, M);
  return qd_lu_factor(n, M, piv, *max);
}

/* x <- M_r^-1 x (legs as qd_M_r_legs'), M_r = S M T never formed, from M's blocks Mc (QD_M_BB, QD_M_BL, QD_M_LL;
 * docs/formulation.md §6.2): a swing leg l's rows of S_b and columns of T_b are zero, so its rows read
 * M_lb a_b + M_ll qdd_l = x_l (a_b = T_b qdd_r, the trunk's acceleration), so qdd_l = w_l - Z_l a_b with
 * [Z_l, w_l] = M_ll^-1 [M_lb, x_l] (3 x 3 LU, no pivoting: M_ll is SPD); folded into the trunk,
 * M_bb <- M_bb - sum M_bl Z_l (in a copy of M_bb) and the rest R (stance joints, row 12; m = n - 3 swing legs)
 * solves K qdd_R = x_R - S_b[R] sum M_bl w_l with K = (S M T)[R, R] (qd_gauss_solve of [K, y]); then qdd_l. With four
 * feet there is no swing leg and K is M_r. M's swing blocks and [K, y] are checked finite (QD_NONFINITE); the swing
 * pivots against QD_SINGULAR_RTOL max|M_ll|, K's against QD_SINGULAR_RTOL max(max|K|, max|M_ll|) (QD_SINGULAR).
 * work: [K, y], then [Z_l, w_l] (3 x 7) per swing leg: m (m + 1) + 21 (4 - stance legs) <= 169 reals. */
QD_INLINE int qd_fd_r_folded(int n, int legs, const casadi_real* S_b, const casadi_real* T_b, const casadi_real* Mc,
                             casadi_real* x, casadi_real* work) {
  const int m = n - 3 * (4 - (legs & 1) - (legs >> 1 & 1) - (legs >> 2 & 1) - (legs >> 3 & 1));
  int r[QD_N_MAX];
  for (int l = 0, i = 0; l < 4; ++l) {
    for (int c = 0; c < 3 && (legs >> l & 1); ++c) r[i++] = 3 * l + c;
  }
  r[m - 1] = n > 12 ? 12 : r[m - 1];
  casadi_real *K = work, *y = K + m * m, *Z = y + m, f[6] = {0, 0, 0, 0, 0, 0}, sw[4] = {0, 0, 0, 0}, scale = 0;
  for (int l = 0; l < 4; ++l) { /* the swing blocks M_ll: finite, and their scale */
    if (legs >> l & 1) continue;
    for (int j = 0; j < 3; ++j) {
      for (int i = 0; i < 3; ++i) {
        const casadi_real a = QD_M_LL(Mc, l, i, j);
        sw[0] += a - a;
        scale = qd_fabs(a) > scale ? qd_fabs(a) : scale;
      }
    }
  }
  if (!(sw[0] == 0)) return QD_NONFINITE;
  const casadi_real thr = QD_SINGULAR_RTOL * scale;
  casadi_real Mbb[36]; /* M_bb, folded below: a copy */
  memcpy(Mbb, &QD_M_BB(Mc, 0, 0), sizeof Mbb);
  for (int l = 0; l < 4; ++l) {
    if (legs >> l & 1) continue;
    const casadi_real* B = &QD_M_BL(Mc, l, 0, 0); /* M_bl: B[i + 6 c] */
    casadi_real u00 = QD_M_LL(Mc, l, 0, 0), u01 = QD_M_LL(Mc, l, 0, 1), u02 = QD_M_LL(Mc, l, 0, 2);
    casadi_real l10 = QD_M_LL(Mc, l, 1, 0) / u00, l20 = QD_M_LL(Mc, l, 2, 0) / u00;
    casadi_real u11 = QD_M_LL(Mc, l, 1, 1) - l10 * u01, u12 = QD_M_LL(Mc, l, 1, 2) - l10 * u02;
    casadi_real l21 = (QD_M_LL(Mc, l, 2, 1) - l20 * u01) / u11;
    casadi_real u22 = QD_M_LL(Mc, l, 2, 2) - l20 * u02 - l21 * u12, i00 = 1 / u00, i11 = 1 / u11, i22 = 1 / u22;
    if (!(qd_fabs(u00) > thr && qd_fabs(u11) > thr && qd_fabs(u22) > thr)) return QD_SINGULAR;
    for (int p = 0; p <= 6; ++p) { /* [Z_l, w_l] = M_ll^-1 [M_lb, x_l], M_lb's column p = M_bl's row p */
      const casadi_real a0 = p < 6 ? B[p] : x[3 * l], a1 = p < 6 ? B[p + 6] : x[3 * l + 1];
      const casadi_real a2 = p < 6 ? B[p + 12] : x[3 * l + 2];
      casadi_real y1 = a1 - l10 * a0, x2 = (a2 - l20 * a0 - l21 * y1) * i22, x1 = (y1 - u12 * x2) * i11;
      Z[3 * p] = (a0 - u01 * x1 - u02 * x2) * i00, Z[3 * p + 1] = x1, Z[3 * p + 2] = x2;
    }
    for (int j = 0; j < 6; ++j) { /* M_bb -= M_bl Z_l (= M_bl M_ll^-1 M_lb): symmetric, its lower triangle */
      for (int i = j; i < 6; ++i) Mbb[i + 6 * j] -= B[i] * Z[3 * j] + B[i + 6] * Z[3 * j + 1] + B[i + 12] * Z[3 * j + 2];
    }
    for (int i = 0; i < 6; ++i) f[i] += B[i] * Z[18] + B[i + 6] * Z[19] + B[i + 12] * Z[20];
    Z += 21;
  }
  for (int j = 1; j < 6; ++j) { /* the upper triangle from the lower */
    for (int i = 0; i < j; ++i) Mbb[i + 6 * j] = Mbb[j + 6 * i];
  }
  /* S_b's rows R and M's (joint rows R, trunk columns), gathered, rows padded with zeros to an even count mp */
  const int mp = (m + 1) & ~1;
  casadi_real S_R[(QD_N_MAX + 1) * 6], M_Rb[(QD_N_MAX + 1) * 6];
  for (int k = 0; k < 6; ++k) {
    for (int i = 0; i < mp; ++i) {
      S_R[i + mp * k] = i < m ? S_b[r[i] + n * k] : 0;
      M_Rb[i + mp * k] = i < m && r[i] < 12 ? QD_M_BL(Mc, r[i] / 3, k, r[i] % 3) : 0;
    }
  }
  const int mj = m - (n > 12), mjp = (mj + 1) & ~1; /* R's joint rows (M_Rb's nonzero rows), padded to even */
  for (int q = 0; q < m; ++q) { /* K's column q: (S M T) e_r[q] on the rows R = M_Rj + M_Rb t + S_R (M_bj + M_bb t) */
    const int j = r[q];
    const casadi_real* t = T_b + 6 * j;
    casadi_real mt[6], mr[QD_N_MAX + 1];
    for (int i = 0; i < 6; ++i) mt[i] = M_Rb[q + mp * i]; /* M_bj: M_Rb's row q (zero for the roll) */
    for (int i = 0; i < mp; ++i) mr[i] = 0;
    for (int c = 0; c < 3 && j < 12; ++c) mr[q - q % 3 + c] = QD_M_LL(Mc, j / 3, c, j % 3); /* M_Rj: j's leg's rows */
    qd_gemv_outlined(6, 6, Mbb, 6, t, mt);
    qd_gemv_outlined(mjp, 6, M_Rb, mp, t, mr);
    qd_gemv_outlined(mp, 6, S_R, mp, mt, mr);
    for (int i = 0; i < m; ++i) K[i + m * q] = mr[i];
  }
  casadi_real nf[6] = {-f[0], -f[1], -f[2], -f[3], -f[4], -f[5]}, xr[QD_N_MAX + 1];
  for (int i = 0; i < mp; ++i) xr[i] = i < m ? x[r[i]] : 0;
  qd_gemv_outlined(mp, 6, S_R, mp, nf, xr); /* y = x_R - S_R f (x + a (-b) is x - a b to the bit) */
  for (int i = 0; i < m; ++i) y[i] = xr[i];
  casadi_real* res[1] = {K};
  casadi_int nnz[1] = {m * (m + 1)};
  if (qd_finite(0, res, 1, nnz)) return QD_NONFINITE;
  casadi_real k_max = qd_max_abs(m * m, K);
  int flag = qd_gauss_solve_bounded(m, K, k_max > scale ? k_max : scale); /* [K, y] */
  if (flag) return flag;
  for (int l = 0; l < 4; ++l) { /* x = qdd_R on R, 0 on the swing legs (their columns of T_b are zero) */
    for (int c = 0; c < 3 && !(legs >> l & 1); ++c) x[3 * l + c] = 0;
  }
  for (int i = 0; i < m; ++i) x[r[i]] = y[i];
  casadi_real a_b[6] = {0, 0, 0, 0, 0, 0}; /* a_b = T_b qdd_r, the trunk's acceleration */
  qd_gemv_outlined(6, n, T_b, 6, x, a_b);
  const casadi_real na_b[6] = {-a_b[0], -a_b[1], -a_b[2], -a_b[3], -a_b[4], -a_b[5]};
  for (int l = 3; l >= 0; --l) { /* qdd_l = w_l - Z_l a_b, the swing legs last to first */
    if (legs >> l & 1) continue;
    Z -= 21;
    for (int c = 0; c < 3; ++c) x[3 * l + c] = Z[18 + c];
    qd_gemv_outlined(3, 6, Z, 3, na_b, x + 3 * l);
  }
  return 0;
}

/* qdd_r = M_r^-1 (tau_ext - (C_r + G_r)): arg = (q_r, qd_r, tau_ext, quat), res = (qdd_r). The parts once
 * (qd_parts), C_r + G_r (qd_rnea_r), M's blocks, and the folded solve (qd_fd_r_folded: M_r not formed); temporaries on
 * the stack. Called once per file with constant n and legs. */
QD_INLINE int qd_fd_r_solve(int n, int legs, const casadi_real** arg, casadi_real** res, casadi_int* iw, casadi_real* w,
                            int mem) {
  casadi_real m = 0, S_b[QD_N_MAX * 6], T_b[6 * QD_N_MAX], space[QD_M_BLOCKS + QD_N_MAX * QD_N_MAX], b[QD_N_MAX];
  /* M's blocks Mc, then the fold's work; before them v, a and the parts' scratch: fd_r's stack stays within budget */
  casadi_real *Mc = space, *work = space + QD_M_BLOCKS, *v = space, *a = v + 18, *q = work;
  typedef char scratch_fits[36 + QD_PARTS_WORK <= QD_M_BLOCKS + QD_N_MAX * QD_N_MAX ? 1 : -1];
  (void)sizeof(scratch_fits);
  qd_trig t;
  qd_trig_of(12, arg[0], &t);
  int flag = qd_parts(n, legs, arg[0], arg[1], 0, arg[3], &t, &m, S_b, T_b, v, a, a + 18, iw, w, mem);
  if (!flag) flag = qd_regular_value(m);
  if (!flag) flag = qd_rnea_r(n, S_b, arg[0], arg[3], &t, v, a, b, Mc + 36, iw, w, mem);
  if (flag) return flag;
  qd_full_q(arg[0], arg[3], q);
  flag = qd_M_at(q, &t, Mc, iw, w, mem, 1);
  if (flag) return flag;
  for (int i = 0; i < n; ++i) b[i] = arg[2][i] - b[i];
  flag = qd_fd_r_folded(n, legs, S_b, T_b, Mc, b, work);
  if (flag) return flag;
  if (res[0]) {
    for (int i = 0; i < n; ++i) res[0][i] = b[i];
  }
  casadi_int nnz[1] = {n};
  return qd_finite(0, res, 1, nnz);
}
