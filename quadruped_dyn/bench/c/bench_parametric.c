/* Times a family's parametric functions beside the fixed library's same terms, in C, on one state.
 * Usage: bench_parametric CALLS REPS q(19) v(18) a(18) f(12) p(178). Prints "name median_ns" per function
 * (bench_median.h): p_M_full, M_full, p_id_full, id_full, p_nle_full, nle_full. */
#define _POSIX_C_SOURCE 199309L
#include <stdio.h>
#include <stdlib.h>

#include QD_HEADER
#include QD_P_HEADER
#include "bench_median.h"

#define N_INPUTS (19 + 18 + 18 + 12 + 178)
#define WORK 65536

static casadi_int iw[WORK];
static casadi_real w[WORK], out[6][2][18 * 18];

int main(int argc, char** argv) {
  if (argc != 3 + N_INPUTS) {
    fprintf(stderr, "usage: %s CALLS REPS q(19) v(18) a(18) f(12) p(178)\n", argv[0]);
    return 2;
  }
  int calls = atoi(argv[1]), reps = atoi(argv[2]);
  static casadi_real x[N_INPUTS];
  for (int k = 0; k < N_INPUTS; ++k) x[k] = atof(argv[3 + k]);
  casadi_real *q = x, *v = x + 19, *a = v + 18, *f = a + 18, *p = f + 12;
  const casadi_real* args[6][5] = {{q, p}, {q}, {q, v, a, f, p}, {q, v, a, f}, {q, v, p}, {q, v}};
  casadi_real* res[6][2];
  for (int i = 0; i < 6; ++i) res[i][0] = out[i][0], res[i][1] = out[i][1];
  const char* names[6] = {"p_M_full", "M_full", "p_id_full", "id_full", "p_nle_full", "nle_full"};
  qd_bench_fn fns[6] = {qd_p_M_full, qd_M_full, qd_p_id_full, qd_id_full, qd_p_nle_full, qd_nle_full};
  qd_timed t[6];
  for (int i = 0; i < 6; ++i) t[i] = (qd_timed){fns[i], args[i], res[i], &q[7], 0, 0};
  double* runs = malloc(sizeof(double) * (size_t)reps * 6), ns[6];
  if (!runs) return 1;
  qd_medians_ns(t, 6, iw, w, calls, reps, runs, ns);
  for (int i = 0; i < 6; ++i) printf("%s %.2f\n", names[i], ns[i]);
  free(runs);
  return 0;
}
