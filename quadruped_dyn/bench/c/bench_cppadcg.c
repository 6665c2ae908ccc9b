/* Times and evaluates Pinocchio's CppADCodeGen functions (bench/cppadcg.py; written by
 * cppadcg_generate.cpp, compiled with this file). Usage, STATE being "nq nv" then q (nq), v (nv),
 * a (nv), tau (nv) in Pinocchio's order, one argument per number:
 *   bench_cppadcg time CALLS REPS STATE   one line per function: "name median_ns" (bench_median.h,
 *                                         the project's harnesses' timing: same calls, same clock)
 *   bench_cppadcg eval STATE              one line per function: "name y0 y1 ..." (%.17g)
 * Inputs: crba q; rnea q, v, a; aba q, v, tau; nle q, v; gravity q. Outputs: crba the upper triangle
 * of M row by row (nv (nv + 1) / 2 values); the others nv values. */
#define _POSIX_C_SOURCE 199309L
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

typedef double casadi_real;
typedef long long int casadi_int;
#include "bench_median.h"

/* CppADCodeGen's interface of a generated function (its LanguageC::ATOMICFUN_STRUCT_DEFINITION). */
typedef struct Array {
  void* data;
  unsigned long size;
  int sparse;
  const unsigned long* idx;
  unsigned long nnz;
} Array;
struct LangCAtomicFun {
  void* libModel;
  int (*forward)(void* libModel, int atomicIndex, int q, int p, const Array tx[], Array* ty);
  int (*reverse)(void* libModel, int atomicIndex, int p, const Array tx[], Array* px, const Array py[]);
};
static struct LangCAtomicFun no_atomic_functions; /* Pinocchio's recordings call none */

/* The project's timing calls fn(arg, res, iw, w, mem): each peer function behind that signature. */
#define QD_PEER(name)                                                                              \
  void name##_forward_zero(double const* const* in, double* const* out, struct LangCAtomicFun f); \
  static int name##_timed(const casadi_real** arg, casadi_real** res, casadi_int* iw, casadi_real* w, int mem) { \
    (void)iw;                                                                                      \
    (void)w;                                                                                       \
    (void)mem;                                                                                     \
    name##_forward_zero(arg, res, no_atomic_functions);                                            \
    return 0;                                                                                      \
  }
QD_PEER(crba)
QD_PEER(rnea)
QD_PEER(aba)
QD_PEER(nle)
QD_PEER(gravity)

typedef struct {
  const char* name;
  qd_bench_fn fn;
  const char* inputs; /* after q: 'v', 'a', 't' (tau) */
  int triangle;       /* output: the upper triangle of an nv x nv matrix */
} qd_peer;
static const qd_peer PEERS[] = {
    {"crba", crba_timed, "", 1}, {"rnea", rnea_timed, "va", 0}, {"aba", aba_timed, "vt", 0},
    {"nle", nle_timed, "v", 0},  {"gravity", gravity_timed, "", 0},
};
#define QD_N_PEERS (sizeof(PEERS) / sizeof(PEERS[0]))

static casadi_int iw[1];
static casadi_real w[1];

int main(int argc, char** argv) {
  int timing = argc > 4 && strcmp(argv[1], "time") == 0, first = timing ? 4 : 2;
  int nq = argc > first + 1 ? atoi(argv[first]) : 0, nv = argc > first + 1 ? atoi(argv[first + 1]) : 0;
  if (!(timing || (argc > 2 && strcmp(argv[1], "eval") == 0)) || nq < 8 || nv < 7 || argc != first + 2 + nq + 3 * nv) {
    fprintf(stderr, "usage: %s time CALLS REPS STATE | eval STATE; STATE: nq nv q (nq) v a tau (nv each)\n", argv[0]);
    return 2;
  }
  double* q = malloc(sizeof(double) * (size_t)(nq + 3 * nv));
  double *v = q + nq, *a = v + nv, *tau = a + nv;
  double* y = malloc(sizeof(double) * (size_t)(nv * (nv + 1) / 2));
  for (int i = 0; i < nq + 3 * nv; ++i) q[i] = atof(argv[first + 2 + i]);
  int calls = timing ? atoi(argv[2]) : 0, reps = timing ? atoi(argv[3]) : 0;
  /* every peer's input (q, then its other vectors) apart: the timed runs interleave */
  double* x = malloc(sizeof(double) * QD_N_PEERS * (size_t)(nq + 2 * nv));
  double* t = malloc(sizeof(double) * QD_N_PEERS * (size_t)(reps > 0 ? reps : 1));
  const casadi_real* arg[QD_N_PEERS][1];
  casadi_real* res[QD_N_PEERS][1];
  qd_timed timed[QD_N_PEERS];
  double ns[QD_N_PEERS];
  for (size_t f = 0; f < QD_N_PEERS; ++f) {
    const qd_peer* p = &PEERS[f];
    double* xf = x + f * (size_t)(nq + 2 * nv);
    int n = nq;
    memcpy(xf, q, sizeof(double) * (size_t)nq);
    for (const char* c = p->inputs; *c; ++c, n += nv)
      memcpy(xf + n, *c == 'v' ? v : *c == 'a' ? a : tau, sizeof(double) * (size_t)nv);
    arg[f][0] = xf;
    res[f][0] = y;
    timed[f] = (qd_timed){p->fn, arg[f], res[f], &xf[7], 0, 0};
  }
  if (timing) qd_medians_ns(timed, (int)QD_N_PEERS, iw, w, calls, reps, t, ns);
  for (size_t f = 0; f < QD_N_PEERS; ++f) {
    const qd_peer* p = &PEERS[f];
    if (timing) {
      printf("%s %.2f\n", p->name, ns[f]);
    } else {
      p->fn(arg[f], res[f], iw, w, 0);
      printf("%s", p->name);
      for (int i = 0; i < (p->triangle ? nv * (nv + 1) / 2 : nv); ++i) printf(" %.17g", y[i]);
      printf("\n");
    }
  }
  free(t);
  free(y);
  free(x);
  free(q);
  return 0;
}
