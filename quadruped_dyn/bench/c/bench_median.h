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

/* A run of a slow function stops adding calls once it lasts about this long (ns): CALLS calls of a
 * 440 us function (dfd_r) would take 9 s per run, the whole benchmark most of an hour, and more calls
 * do not make a run of that length steadier. bench_pinocchio.cpp uses the same budget. */
#define QD_RUN_BUDGET_NS 2e6

/* Calls per run: CALLS, or as many as fit in QD_RUN_BUDGET_NS at one_call_ns each (at least one). */
static int qd_calls_in_budget(double one_call_ns, int calls) {
  double fit = QD_RUN_BUDGET_NS / (one_call_ns > 1.0 ? one_call_ns : 1.0);
  return fit < 1.0 ? 1 : fit < (double)calls ? (int)fit : calls;
}

/* Median ns per call of fn(arg, res, iw, w, 0) after a warm-up (caches, clock; CALLS / 10 + 1 calls,
 * within the budget), over REPS runs of CALLS calls (fewer for a slow function: qd_calls_in_budget);
 * *changing moves by 1e-15 before every call so that no call can be hoisted. t: scratch of reps entries. */
static double qd_median_ns(qd_bench_fn fn, const casadi_real** arg, casadi_real** res, casadi_int* iw, casadi_real* w,
                           casadi_real* changing, int calls, int reps, double* t) {
  double t0 = now_ns();
  fn(arg, res, iw, w, 0);
  int warm = qd_calls_in_budget(now_ns() - t0, calls / 10 + 1);
  t0 = now_ns();
  for (int n = 0; n < warm; ++n) fn(arg, res, iw, w, 0);
  calls = qd_calls_in_budget((now_ns() - t0) / warm, calls);
  for (int r = 0; r < reps; ++r) {
    t0 = now_ns();
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
