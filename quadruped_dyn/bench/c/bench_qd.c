/* Times every generated function on the reference inputs, in C. Usage: bench_qd CALLS REPS.
 * Prints one line per function: "name median_ns" (median over REPS runs of CALLS calls). */
#define _POSIX_C_SOURCE 199309L
#include <stdio.h>
#include <stdlib.h>
#include <time.h>

#include QD_HEADER
#include QD_REFERENCE

static casadi_int iw[QD_MAX_SZ_IW + 1];
static casadi_real w[QD_MAX_SZ_W + 1];

static double now_ns(void) {
  struct timespec t;
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t); /* CPU time: not the time the scheduler gives to others */
  return 1e9 * (double)t.tv_sec + (double)t.tv_nsec;
}

static int by_value(const void* a, const void* b) {
  double x = *(const double*)a, y = *(const double*)b;
  return (x > y) - (x < y);
}

int main(int argc, char** argv) {
  int calls = argc > 1 ? atoi(argv[1]) : 10000, reps = argc > 2 ? atoi(argv[2]) : 9;
  double* t = malloc(sizeof(double) * (size_t)reps); /* the harness may allocate; the functions do not */
  for (int c = 0; c < QD_N_CASES; ++c) {
    const qd_case* k = &QD_CASES[c];
    casadi_real in[4][QD_MAX_IN], out[4][QD_MAX_OUT];
    const casadi_real* arg[4];
    casadi_real* res[4];
    qd_case_args(k, in, arg, out, res);
    for (int n = 0; n < calls / 10 + 1; ++n) k->fn(arg, res, iw, w, 0); /* warm-up: caches, clock */
    for (int r = 0; r < reps; ++r) {
      double t0 = now_ns();
      for (int n = 0; n < calls; ++n) {
        in[0][7] += (casadi_real)1e-15; /* a changing input: no call can be hoisted */
        k->fn(arg, res, iw, w, 0);
      }
      t[r] = (now_ns() - t0) / calls;
    }
    qsort(t, (size_t)reps, sizeof(double), by_value);
    printf("%s %.2f\n", k->name, t[reps / 2]);
  }
  free(t);
  return 0;
}
