/* Thread safety of the generated functions: each of QD_THREADS threads calls every function
 * QD_ROUNDS times, all at once, each thread with its own work memory (iw, w) and its own
 * inputs and outputs, starting at a different function; every result must equal the serial
 * result bit for bit. Inputs: the check program's reference inputs (qd_<robot>-reference.h).
 * Build and run: `make check-threads` (and `make check-threads-tsan`: ThreadSanitizer).
 * Exit status 0 when every result matches. */
#include <pthread.h>
#include <stdio.h>
#include <string.h>

#include QD_HEADER
#include QD_REFERENCE

#ifndef QD_THREADS
#define QD_THREADS 4
#endif
#ifndef QD_ROUNDS
#define QD_ROUNDS 20
#endif

static casadi_real serial[QD_N_CASES][4][QD_MAX_OUT];
static int serial_flag[QD_N_CASES];

typedef struct {
  int id, mismatches, calls;
  casadi_int iw[QD_MAX_SZ_IW + 1];
  casadi_real w[QD_MAX_SZ_W + 1];
} qd_worker;

/* Evaluate case c with the worker's own work memory into out; its return code. */
static int qd_eval(int c, casadi_int* iw, casadi_real* w, casadi_real out[4][QD_MAX_OUT]) {
  const qd_case* k = &QD_CASES[c];
  casadi_real in[QD_MAX_N_IN][QD_MAX_IN];
  const casadi_real* arg[QD_MAX_N_IN];
  casadi_real* res[4];
  qd_case_args(k, in, arg, out, res);
  memset(out, 0, 4 * sizeof out[0]); /* also the rows a function does not use: compared whole */
  return k->fn(arg, res, iw, w, 0);
}

static void* qd_work(void* p) {
  qd_worker* me = (qd_worker*)p;
  casadi_real out[4][QD_MAX_OUT];
  for (int r = 0; r < QD_ROUNDS; ++r) {
    for (int j = 0; j < QD_N_CASES; ++j) {
      int c = (j + me->id * (QD_N_CASES / QD_THREADS + 1)) % QD_N_CASES; /* threads start apart */
      int flag = qd_eval(c, me->iw, me->w, out);
      ++me->calls;
      if (flag != serial_flag[c] || memcmp(out, serial[c], sizeof out) != 0) ++me->mismatches;
    }
  }
  return NULL;
}

int main(void) {
  static qd_worker workers[QD_THREADS];
  static casadi_int iw[QD_MAX_SZ_IW + 1];
  static casadi_real w[QD_MAX_SZ_W + 1];
  for (int c = 0; c < QD_N_CASES; ++c) serial_flag[c] = qd_eval(c, iw, w, serial[c]);
  pthread_t threads[QD_THREADS];
  for (int t = 0; t < QD_THREADS; ++t) {
    workers[t].id = t;
    if (pthread_create(&threads[t], NULL, qd_work, &workers[t]) != 0) {
      printf("could not start thread %d\n", t);
      return 2;
    }
  }
  int mismatches = 0, calls = 0;
  for (int t = 0; t < QD_THREADS; ++t) {
    pthread_join(threads[t], NULL);
    mismatches += workers[t].mismatches;
    calls += workers[t].calls;
  }
  printf("%d functions, %d threads x %d rounds: %d calls, %d differ from the serial results\n", QD_N_CASES,
         QD_THREADS, QD_ROUNDS, calls, mismatches);
  return mismatches != 0;
}
