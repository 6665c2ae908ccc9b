/* quadruped_dyn: the GRF solves of qd_<robot>.c (hand-written, inserted by quadruped_dyn/codegen/emit.py).
 * qd_grf_<feet>(q, v, a) -> (lambda, f, residual, tau): the required trunk wrench w_req and the joint
 * torques without foot forces from the generated id_full (f = 0), then the generated per-stance-set
 * balance (q, w_req) -> (lambda, f, residual, tau_f), tau_f = -J_i^T f_i the torques the foot forces add
 * (quadruped_dyn/dynamics/grf.py, grf_balance); tau = tau_0 + tau_f. One Newton-Euler pass (id_full's)
 * serves every stance set instead of one unrolled copy per set. A null res[i] skips output i. */
typedef int (*qd_grf_fn)(const casadi_real**, casadi_real**, casadi_int*, casadi_real*, int);

static int qd_grf_solve(qd_grf_fn id_full, qd_grf_fn balance, const casadi_real** arg, casadi_real** res,
                        casadi_int* iw, casadi_real* w, int mem) {
  casadi_real no_force[12] = {0}, w_req[6], tau_0[12], tau_f[12];
  const casadi_real* id_arg[4] = {arg[0], arg[1], arg[2], no_force};
  casadi_real* id_res[2] = {w_req, tau_0};
  int flag = id_full(id_arg, id_res, iw, w, mem);
  if (flag) return flag;
  const casadi_real* b_arg[2] = {arg[0], w_req};
  casadi_real* b_res[4] = {res[0], res[1], res[2], tau_f};
  flag = balance(b_arg, b_res, iw, w, mem);
  if (flag || !res[3]) return flag;
  for (int i = 0; i < 12; ++i) res[3][i] = tau_0[i] + tau_f[i];
  return 0;
}
