/* Times generated functions side by side (quadruped_dyn.peers). Usage: bench_peers CALLS REPS.
 * The functions are listed in qd_peers_list.h as QD_FN(name); every input points at the same
 * array of small pseudo-random numbers (timing only: the values are checked in Python).
 * Prints one line per function: "name median_ns" (median over REPS runs of CALLS calls), timed in
 * this thread's CPU time: on a shared machine a wall clock also counts the time the scheduler gives
 * to others, which a slow function's longer runs catch more often than a fast one's. */
#define _POSIX_C_SOURCE 199309L
#include <stdio.h>
#include <stdlib.h>
#include <time.h>

#include "qd_peers.h"

typedef int (*qd_fn)(const casadi_real**, casadi_real**, casadi_int*, casadi_real*, int);
typedef struct { const char* name; qd_fn fn; } qd_timed;
#define QD_FN(f) {#f, f},
static const qd_timed FUNCTIONS[] = {
#include "qd_peers_list.h"
};
#define QD_N (sizeof(FUNCTIONS) / sizeof(FUNCTIONS[0]))

static casadi_int iw[100000];
static casadi_real w[100000], in[1000], out[8][1000];

static double now_ns(void) {
  struct timespec t;
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return 1e9 * (double)t.tv_sec + (double)t.tv_nsec;
}

static int by_value(const void* a, const void* b) {
  double x = *(const double*)a, y = *(const double*)b;
  return (x > y) - (x < y);
}

int main(int argc, char** argv) {
  int calls = argc > 1 ? atoi(argv[1]) : 10000, reps = argc > 2 ? atoi(argv[2]) : 9;
  double* t = malloc(sizeof(double) * (size_t)reps);
  const casadi_real* arg[8];
  casadi_real* res[8];
  size_t f;
  int i, r, n;
  srand(7);
  for (i = 0; i < 1000; ++i) in[i] = 0.3 * ((double)rand() / RAND_MAX - 0.5);
  in[6] = 1.0; /* a quaternion's w, a homogeneous matrix's entry: nothing degenerate */
  for (i = 0; i < 8; ++i) {
    arg[i] = in;
    res[i] = out[i];
  }
  for (f = 0; f < QD_N; ++f) {
    for (n = 0; n < calls / 10 + 1; ++n) FUNCTIONS[f].fn(arg, res, iw, w, 0); /* warm-up */
    for (r = 0; r < reps; ++r) {
      double t0 = now_ns();
      for (n = 0; n < calls; ++n) {
        in[7] += (casadi_real)1e-15; /* a changing input: no call can be hoisted */
        FUNCTIONS[f].fn(arg, res, iw, w, 0);
      }
      t[r] = (now_ns() - t0) / calls;
    }
    qsort(t, (size_t)reps, sizeof(double), by_value);
    printf("%s %.2f\n", FUNCTIONS[f].name, t[reps / 2]);
  }
  free(t);
  return 0;
}
