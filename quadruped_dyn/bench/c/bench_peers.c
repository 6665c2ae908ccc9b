/* Times generated functions side by side (quadruped_dyn.bench.peers). Usage: bench_peers CALLS REPS.
 * The functions are listed in qd_peers_list.h as QD_FN(name); every input points at the same
 * array of small pseudo-random numbers (timing only: the values are checked in Python).
 * Prints one line per function: "name median_ns" (median over REPS runs of CALLS calls, interleaved, in
 * this thread's CPU time: bench_median.h). */
#define _POSIX_C_SOURCE 199309L
#include <stdio.h>
#include <stdlib.h>
#include <time.h>

#include "qd_peers.h"
#include "bench_median.h"

typedef struct { const char* name; qd_bench_fn fn; } qd_named;
#define QD_FN(f) {#f, f},
static const qd_named FUNCTIONS[] = {
#include "qd_peers_list.h"
};
#define QD_N (sizeof(FUNCTIONS) / sizeof(FUNCTIONS[0]))

static casadi_int iw[100000];
static casadi_real w[100000], in[1000], out[8][1000];

int main(int argc, char** argv) {
  int calls = argc > 1 ? atoi(argv[1]) : 10000, reps = argc > 2 ? atoi(argv[2]) : 9;
  double *t = malloc(sizeof(double) * (size_t)reps * QD_N), ns[QD_N];
  const casadi_real* arg[8];
  casadi_real* res[8];
  qd_timed f[QD_N];
  size_t i;
  if (!t) return 1;
  srand(7);
  for (i = 0; i < 1000; ++i) in[i] = 0.3 * ((double)rand() / RAND_MAX - 0.5);
  in[6] = 1.0; /* a quaternion's w, a homogeneous matrix's entry: nothing degenerate */
  for (i = 0; i < 8; ++i) {
    arg[i] = in;
    res[i] = out[i];
  }
  for (i = 0; i < QD_N; ++i) f[i] = (qd_timed){FUNCTIONS[i].fn, arg, res, &in[7], 0, 0};
  qd_medians_ns(f, (int)QD_N, iw, w, calls, reps, t, ns);
  for (i = 0; i < QD_N; ++i) printf("%s %.2f\n", FUNCTIONS[i].name, ns[i]);
  free(t);
  return 0;
}
