/* Times every generated function on the reference inputs, in C. Usage: bench_qd CALLS REPS.
 * Prints one line per function: "name median_ns" (median over REPS runs of CALLS calls, interleaved: bench_median.h). */
#define _POSIX_C_SOURCE 199309L
#include <stdio.h>
#include <stdlib.h>
#include <time.h>

#include QD_HEADER
#include QD_REFERENCE
#include "bench_median.h"

static casadi_int iw[QD_MAX_SZ_IW + 1];
static casadi_real w[QD_MAX_SZ_W + 1];

/* every case's inputs and outputs, set up before any timing (the runs of the cases interleave) */
typedef struct {
  casadi_real in[QD_MAX_N_IN][QD_MAX_IN], out[4][QD_MAX_OUT];
  const casadi_real* arg[QD_MAX_N_IN];
  casadi_real* res[4];
} qd_case_data;

int main(int argc, char** argv) {
  int calls = argc > 1 ? atoi(argv[1]) : 10000, reps = argc > 2 ? atoi(argv[2]) : 9;
  /* the harness may allocate; the functions do not */
  qd_case_data* d = malloc(sizeof(qd_case_data) * QD_N_CASES);
  qd_timed* f = malloc(sizeof(qd_timed) * QD_N_CASES);
  double *t = malloc(sizeof(double) * (size_t)reps * QD_N_CASES), *ns = malloc(sizeof(double) * QD_N_CASES);
  if (!d || !f || !t || !ns) return 1;
  for (int c = 0; c < QD_N_CASES; ++c) {
    qd_case_args(&QD_CASES[c], d[c].in, d[c].arg, d[c].out, d[c].res);
    f[c] = (qd_timed){QD_CASES[c].fn, d[c].arg, d[c].res, &d[c].in[0][7], 0, 0};
  }
  qd_medians_ns(f, QD_N_CASES, iw, w, calls, reps, t, ns);
  for (int c = 0; c < QD_N_CASES; ++c) printf("%s %.2f\n", QD_CASES[c].name, ns[c]);
  free(ns);
  free(t);
  free(f);
  free(d);
  return 0;
}
