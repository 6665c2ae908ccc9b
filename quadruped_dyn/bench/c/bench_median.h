/* The timing of both C harnesses (bench_qd.c, bench_peers.c): the median time of one call over
 * REPS runs of CALLS calls, in this thread's CPU time (a wall clock on a shared machine also counts
 * the time the scheduler gives to others, which a slow function's longer runs catch more often). */
#ifndef QD_BENCH_MEDIAN_H
#define QD_BENCH_MEDIAN_H
#include <stdlib.h>
#include <time.h>

typedef int (*qd_bench_fn)(const casadi_real**, casadi_real**, casadi_int*, casadi_real*, int);

static double now_ns(void) {
  struct timespec t;
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return 1e9 * (double)t.tv_sec + (double)t.tv_nsec;
}

static int by_value(const void* a, const void* b) {
  double x = *(const double*)a, y = *(const double*)b;
  return (x > y) - (x < y);
}

/* Median ns per call of fn(arg, res, iw, w, 0) after a warm-up (caches, clock); *changing moves by
 * 1e-15 before every call so that no call can be hoisted. t: scratch of reps entries. */
static double qd_median_ns(qd_bench_fn fn, const casadi_real** arg, casadi_real** res, casadi_int* iw, casadi_real* w,
                           casadi_real* changing, int calls, int reps, double* t) {
  for (int n = 0; n < calls / 10 + 1; ++n) fn(arg, res, iw, w, 0);
  for (int r = 0; r < reps; ++r) {
    double t0 = now_ns();
    for (int n = 0; n < calls; ++n) {
      *changing += (casadi_real)1e-15;
      fn(arg, res, iw, w, 0);
    }
    t[r] = (now_ns() - t0) / calls;
  }
  qsort(t, (size_t)reps, sizeof(double), by_value);
  return t[reps / 2];
}
#endif
