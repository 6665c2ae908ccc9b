/* quadruped_dyn: a CasADi sparse output made dense (hand-written; inserted into qd_<robot>_d.c
 * and in qd_reduced_templates.h, which each qd_<robot>_r_<feet>.c includes; see quadruped_dyn/codegen/emit.py). */
/* x: the nonzeros of a CasADi sparsity sp (nrow, ncol, colind[ncol + 1], row[nnz]) -> the dense matrix,
 * column-major, in place (x holds nrow * ncol reals). Backwards: a nonzero's dense index is >= its own. */
static void qd_densify(const casadi_int* sp, casadi_real* x) {
  const casadi_int nrow = sp[0], ncol = sp[1], *colind = sp + 2, *row = sp + 3 + ncol;
  casadi_int next = nrow * ncol; /* entries from here on are final */
  for (casadi_int j = ncol - 1; j >= 0; --j) {
    for (casadi_int k = colind[j + 1] - 1; k >= colind[j]; --k) {
      casadi_int d = row[k] + nrow * j;
      casadi_real value = x[k];
      for (casadi_int i = d + 1; i < next; ++i) x[i] = 0;
      x[d] = value;
      next = d;
    }
  }
  for (casadi_int i = 0; i < next; ++i) x[i] = 0;
}
