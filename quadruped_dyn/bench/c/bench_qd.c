/* Times every generated function on the reference inputs, in C. Usage: bench_qd CALLS REPS.
 * Prints one line per function: "name median_ns" (median over REPS runs of CALLS calls). */
#define _POSIX_C_SOURCE 199309L
#include <stdio.h>
#include <stdlib.h>
#include <time.h>

#include QD_HEADER
#include QD_REFERENCE
#include "bench_median.h"

static casadi_int iw[QD_MAX_SZ_IW + 1];
static casadi_real w[QD_MAX_SZ_W + 1];

int main(int argc, char** argv) {
  int calls = argc > 1 ? atoi(argv[1]) : 10000, reps = argc > 2 ? atoi(argv[2]) : 9;
  double* t = malloc(sizeof(double) * (size_t)reps); /* the harness may allocate; the functions do not */
  for (int c = 0; c < QD_N_CASES; ++c) {
    const qd_case* k = &QD_CASES[c];
    casadi_real in[QD_MAX_N_IN][QD_MAX_IN], out[4][QD_MAX_OUT];
    const casadi_real* arg[QD_MAX_N_IN];
    casadi_real* res[4];
    qd_case_args(k, in, arg, out, res);
    printf("%s %.2f\n", k->name, qd_median_ns(k->fn, arg, res, iw, w, &in[0][7], calls, reps, t));
  }
  free(t);
  return 0;
}
