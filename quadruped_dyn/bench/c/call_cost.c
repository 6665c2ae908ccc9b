/* Calls one generated function on its reference inputs, for counting under valgrind (bench/call_cost.py).
 * Usage: call_cost CASE CALLS. Prints the case's C function name (call_cost alone: every case's, one a line). The
 * inputs are the same on every call, so every call takes the same path; call_cost.py counts only inside the function
 * (callgrind --toggle-collect). */
#include <stdio.h>
#include <stdlib.h>

#include QD_HEADER
#include QD_REFERENCE

static casadi_int iw[QD_MAX_SZ_IW + 1];
static casadi_real w[QD_MAX_SZ_W + 1];
static casadi_real in[QD_MAX_N_IN][QD_MAX_IN], out[4][QD_MAX_OUT];
static const casadi_real* arg[QD_MAX_N_IN];
static casadi_real* res[4];

int main(int argc, char** argv) {
  if (argc == 1) {
    for (int c = 0; c < QD_N_CASES; ++c) printf("%s\n", QD_CASES[c].name);
    return 0;
  }
  if (argc != 3) return 2;
  int c = atoi(argv[1]), calls = atoi(argv[2]);
  if (c < 0 || c >= QD_N_CASES || calls < 0) return 2;
  qd_case_args(&QD_CASES[c], in, arg, out, res);
  int status = 0;
  for (int k = 0; k < calls; ++k) status |= QD_CASES[c].fn(arg, res, iw, w, 0);
  printf("%s %d\n", QD_CASES[c].name, status);
  return 0;
}
