/* The timing of the C harnesses (bench_qd.c, bench_peers.c, bench_cppadcg.c): the median time of one call over
 * REPS runs of CALLS calls, the runs interleaved across the functions (qd_medians_ns), in this thread's CPU time (a
 * wall clock on a shared machine also counts the time the scheduler gives to others, which a slow function's longer
 * runs catch more often). */
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

/* One function to time: fn(arg, res, iw, w, 0), *changing moved by 1e-15 before every timed call so that no call can
 * be hoisted. warm and calls: set by qd_medians_ns. */
typedef struct {
  qd_bench_fn fn;
  const casadi_real** arg;
  casadi_real** res;
  casadi_real* changing;
  int warm, calls;
} qd_timed;

/* Median ns per call of each of the n functions f into ns, over REPS runs of CALLS calls (fewer for a slow function:
 * qd_calls_in_budget), the runs interleaved: every function is first calibrated (one call, then CALLS / 10 + 1 within
 * the budget), then in each of REPS rounds every function in turn gets its warm-up again (its caches and branch
 * history back after the others') and one timed run. A disturbance of a few ms (another job on a shared 2-core
 * machine) then spoils one run of a few functions, not every run of one. t: scratch of n * reps entries. */
static void qd_medians_ns(qd_timed* f, int n, casadi_int* iw, casadi_real* w, int calls, int reps, double* t, double* ns) {
  for (int i = 0; i < n; ++i) {
    double t0 = now_ns();
    f[i].fn(f[i].arg, f[i].res, iw, w, 0);
    f[i].warm = qd_calls_in_budget(now_ns() - t0, calls / 10 + 1);
    t0 = now_ns();
    for (int k = 0; k < f[i].warm; ++k) f[i].fn(f[i].arg, f[i].res, iw, w, 0);
    f[i].calls = qd_calls_in_budget((now_ns() - t0) / f[i].warm, calls);
  }
  for (int r = 0; r < reps; ++r) {
    for (int i = 0; i < n; ++i) {
      for (int k = 0; k < f[i].warm; ++k) f[i].fn(f[i].arg, f[i].res, iw, w, 0);
      double t0 = now_ns();
      for (int k = 0; k < f[i].calls; ++k) {
        *f[i].changing += (casadi_real)1e-15;
        f[i].fn(f[i].arg, f[i].res, iw, w, 0);
      }
      t[reps * i + r] = (now_ns() - t0) / f[i].calls;
    }
  }
  for (int i = 0; i < n; ++i) {
    qsort(t + reps * i, (size_t)reps, sizeof(double), by_value);
    ns[i] = t[reps * i + reps / 2];
  }
}
#endif
