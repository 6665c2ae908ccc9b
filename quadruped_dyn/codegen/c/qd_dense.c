/* quadruped_dyn: a CasADi sparse output made dense (hand-written; inserted into qd_<robot>-d.c
 * and in reduced_templates.h, which each qd_<robot>-r-<feet>.c includes; see quadruped_dyn/codegen/emit.py). */
/* x (nrow * ncol reals, column-major) = the dense matrix of the nonzeros nz of a CasADi sparsity sp
 * (nrow, ncol, colind[ncol + 1], row[nnz]), x and nz apart: the zeros in one pass (memset), then the nonzeros; faster
 * than densifying in place, whose gaps are zeroed one nonzero at a time (docs/benchmark.md). */
#ifndef CASADI_PREFIX /* compiled alone, not pasted into a generated file (codegen/c_alone.py) */
#include "qd_alone.h"
#endif
static void qd_scatter(const casadi_int* sp, const casadi_real* restrict nz, casadi_real* restrict x) {
  const casadi_int nrow = sp[0], ncol = sp[1], *colind = sp + 2, *row = sp + 3 + ncol;
  for (casadi_int i = 0; i < nrow * ncol; ++i) x[i] = 0;
  for (casadi_int j = 0; j < ncol; ++j) {
    for (casadi_int k = colind[j]; k < colind[j + 1]; ++k) x[row[k] + nrow * j] = nz[k];
  }
}
