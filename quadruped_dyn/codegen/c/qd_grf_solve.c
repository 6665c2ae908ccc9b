/* quadruped_dyn: the GRF solves of qd_<robot>.c (hand-written, inserted by quadruped_dyn/codegen/emit.py).
 * qd_grf_<feet>(q, v, a) -> (lambda, f, residual, tau): the required trunk wrench w_req and the joint
 * torques without foot forces tau_0 from the generated id_full (f = 0, qd_grf_begin), then the generated
 * per-stance-set balance (q, w_req) -> (lambda, f, residual, tau_f), tau_f = -J_i^T f_i the torques the
 * foot forces add (quadruped_dyn/dynamics/grf.py, grf_balance), then tau = tau_0 + tau_f (qd_grf_end).
 * One Newton-Euler pass (id_full's) serves every stance set instead of one unrolled copy per set. Direct
 * calls only (no function pointers), so the Cortex-M stack walk stays bounded. A null res[i] skips output i.
 * Before this text the generator defines QD_ID_FULL_EVAL, id_full's evaluation. */
#ifndef CASADI_PREFIX /* compiled alone, not pasted into a generated file (codegen/c_alone.py) */
#include "qd_alone.h"
#endif
static int qd_grf_begin(const casadi_real** arg, casadi_real* w_req, casadi_real* tau_0, casadi_int* iw, casadi_real* w,
                        int mem) {
  const casadi_real no_force[12] = {0};
  const casadi_real* id_arg[4] = {arg[0], arg[1], arg[2], no_force};
  casadi_real* id_res[2] = {w_req, tau_0};
  return QD_ID_FULL_EVAL(id_arg, id_res, iw, w, mem);
}

static int qd_grf_end(casadi_real** res, const casadi_real* tau_0, const casadi_real* tau_f) {
  if (res[3]) {
    for (int i = 0; i < 12; ++i) res[3][i] = tau_0[i] + tau_f[i];
  }
  return 0;
}
