/* Calls every generated function on the reference inputs and compares each output with
 * the reference values computed by Pinocchio (qd_<robot>-reference.h, generated beside it).
 * Build and run: `make check` (double and float builds). Exit status 0 when all pass.
 * A non-zero return code or a NaN/inf output is a failure, never a pass. The derivatives of the
 * reduced model and of the GRF solve are checked against central differences of Pinocchio-built
 * references: their tolerance is at least the differences' accuracy (tol_floor, times tol_scale).
 * Each function is also called with null iw and w first (the header's contract): one that needs work memory
 * returns QD_NO_WORK, any other what it returns with them; its _batch entry on 3 copies of the inputs gives the
 * call's outputs to the bit and its return code per row. */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include QD_HEADER
#include QD_REFERENCE

#ifndef QD_FLOAT
#define QD_TOL QD_REL_TOL_DOUBLE
#define QD_BOUND_CHECKED 0
#else
#define QD_TOL QD_REL_TOL_FLOAT
#define QD_BOUND_CHECKED 1 /* the float bound checks: QD_SINGULAR or QD_DEGENERATE above QD_FLOAT_MAX_BOUND */
#endif

static casadi_int iw[QD_MAX_SZ_IW + 1];
static casadi_real w[QD_MAX_SZ_W + 1];

/* A case whose tolerance would exceed this (the conditioning leaves fewer than two digits in
 * this precision, e.g. fd_r of the front/back pairs in float) is reported as skipped: it
 * could only fail on NaN. */
#define QD_MAX_TOL 1e-2

/* The batch entry on QD_BATCH_N copies of case k's inputs: each row's outputs equal the one call's (out) to the bit
 * and each status its return code (flag). */
#define QD_BATCH_N 3
static int qd_batch_agrees(const qd_case* k, casadi_real in[QD_MAX_N_IN][QD_MAX_IN], casadi_real out[4][QD_MAX_OUT],
                           int flag) {
  static casadi_real bin[QD_MAX_N_IN][QD_BATCH_N * QD_MAX_IN], bout[4][QD_BATCH_N * QD_MAX_OUT];
  const casadi_real* arg[QD_MAX_N_IN];
  casadi_real* res[4];
  int status[QD_BATCH_N];
  for (int i = 0; i < k->n_in; ++i) {
    for (int s = 0; s < QD_BATCH_N; ++s)
      for (int j = 0; j < k->in_len[i]; ++j) bin[i][s * k->in_len[i] + j] = in[i][j];
    arg[i] = bin[i];
  }
  for (int i = 0; i < k->n_out; ++i) res[i] = bout[i];
  k->batch(QD_BATCH_N, arg, res, status, w);
  for (int s = 0; s < QD_BATCH_N; ++s) {
    if (status[s] != flag) return 0;
    for (int i = 0; i < k->n_out && flag == 0; ++i)
      for (int j = 0; j < k->out_nnz[i]; ++j)
        if (memcmp(&bout[i][s * k->out_nnz[i] + j], &out[i][j], sizeof(casadi_real)) != 0) return 0;
  }
  return 1;
}

int main(void) {
  int passed = 0, failed = 0, skipped = 0;
  for (int c = 0; c < QD_N_CASES; ++c) {
    const qd_case* k = &QD_CASES[c];
    casadi_real in[QD_MAX_N_IN][QD_MAX_IN], out[4][QD_MAX_OUT];
    const casadi_real* arg[QD_MAX_N_IN];
    casadi_real* res[4];
    qd_case_args(k, in, arg, out, res);
    int flag_null_w = k->fn(arg, res, 0, 0, 0); /* its outputs are written again below */
    int flag = k->fn(arg, res, iw, w, 0);
    if (flag_null_w != QD_NO_WORK && flag_null_w != flag) {
      printf("%-24s returned %d with a null w, %d with w: FAIL\n", k->name, flag_null_w, flag);
      ++failed;
      continue;
    }
    if (!qd_batch_agrees(k, in, out, flag)) {
      printf("%-24s batch rows differ from its call (outputs to the bit, or statuses): FAIL\n", k->name);
      ++failed;
      continue;
    }
    if (flag == QD_SINGULAR && QD_TOL * k->tol_scale > QD_MAX_TOL) { /* QD_SINGULAR where this precision has < 2 digits */
      printf("%-24s skipped: singular to this precision (cond x eps = %.1e), as its return code says\n", k->name,
             QD_TOL * k->tol_scale);
      ++skipped;
      continue;
    }
    /* the float build's bound checks at the reference's conditioning (a factor 2 either way: the float build takes
       cond_1 of its own M_r or K, and its own regularity) */
    if (QD_BOUND_CHECKED && (flag == QD_SINGULAR || flag == QD_DEGENERATE) && qd_float_bound[c] > QD_FLOAT_MAX_BOUND / 2) {
      printf("%-24s skipped: float error bound %.1e over %.1e, as its return code says\n", k->name,
             qd_float_bound[c], QD_FLOAT_MAX_BOUND);
      ++skipped;
      continue;
    }
    if (flag != 0) {
      printf("%-24s returned %d\n", k->name, flag);
      ++failed;
      continue;
    }
    /* relative to the largest reference value of the function (a zero residual output
       has no scale of its own) */
    double err = 0.0, scale = 0.0;
    int finite = 1;
    for (int i = 0; i < k->n_out; ++i) {
      for (int j = 0; j < k->out_nnz[i]; ++j) {
        finite = finite && isfinite((double)out[i][j]) && isfinite(k->out[i][j]);
        double d = fabs((double)out[i][j] - k->out[i][j]);
        if (d > err) err = d;
        if (fabs(k->out[i][j]) > scale) scale = fabs(k->out[i][j]);
      }
    }
    /* at least the reference's own accuracy (finite differences), both amplified by the conditioning */
    double worst = err / (scale > 0.0 ? scale : 1.0), tol = (QD_TOL > k->tol_floor ? QD_TOL : k->tol_floor) * k->tol_scale;
    if (QD_BOUND_CHECKED && qd_float_bound[c] > 2 * QD_FLOAT_MAX_BOUND) {
      printf("%-24s returned 0 with a float error bound %.1e over %.1e: FAIL\n", k->name, qd_float_bound[c],
             QD_FLOAT_MAX_BOUND);
      ++failed;
      continue;
    }
    if (finite && tol > QD_MAX_TOL) {
      printf("%-24s max rel err vs Pinocchio %.2e skipped: cond x eps = %.1e leaves < 2 digits\n", k->name, worst, tol);
      ++skipped;
      continue;
    }
    int ok = finite && worst <= tol;
    printf("%-24s max rel err vs Pinocchio %.2e (tol %.1e) %s\n", k->name, worst, tol,
           ok ? "pass" : finite ? "FAIL" : "FAIL (not finite)");
    ok ? ++passed : ++failed;
  }
  if (skipped) printf("%d passed, %d failed, %d skipped\n", passed, failed, skipped);
  else printf("%d passed, %d failed\n", passed, failed);
  return failed != 0;
}
