// Times Pinocchio's native C++ algorithms on a URDF with a free-flyer root, in the same run
// as the generated code. Usage: bench_pinocchio URDF CALLS REPS [FOOT_FL FOOT_FR FOOT_BL FOOT_BR].
// Prints one line per algorithm: "name median_ns". State: neutral + 0.1 * random,
// velocities/accelerations/torques random. Also aba, computeRNEADerivatives and computeABADerivatives. With the four foot frames (project order), also
// constraintDynamics with every set of 2, 3 or 4 stance feet as rigid 3-D point contacts
// (LOCAL_WORLD_ALIGNED, proximal settings mu = 0, one iteration: the exact KKT solve), named
// "constraintDynamics_<feet>" with the feet joined by '_' (e.g. constraintDynamics_FL_BR), and
// constraintDynamics followed by computeConstraintDynamicsDerivatives (the analytical derivatives of the
// accelerations and contact forces w.r.t. q, v, tau; they need constraintDynamics' factorisation), named
// "constraintDynamicsDerivatives_<feet>".
#include <algorithm>
#include <ctime>
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <vector>

#include <string>

#include <pinocchio/algorithm/aba.hpp>
#include <pinocchio/algorithm/constrained-dynamics.hpp>
#include <pinocchio/algorithm/constrained-dynamics-derivatives.hpp>
#include <pinocchio/algorithm/crba.hpp>
#include <pinocchio/algorithm/joint-configuration.hpp>
#include <pinocchio/algorithm/rnea.hpp>
#include <pinocchio/algorithm/rnea-derivatives.hpp>
#include <pinocchio/algorithm/aba-derivatives.hpp>
#include <pinocchio/multibody.hpp>
#include <pinocchio/parsers/urdf.hpp>

namespace pin = pinocchio;
// The algorithms are called with the argument types of the pin wheel's explicit instantiations
// (Eigen::Ref inputs, column-major outputs), so the wheel's compiled code is what is timed and this file
// does not compile its own copy (Data's row-major ddq_dq / dtau_dq and plain VectorXd arguments would
// instantiate computeConstraintDynamicsDerivatives, computeRNEADerivatives and aba here: ~30 % of the build).
typedef Eigen::Ref<const Eigen::VectorXd> Ref;

// This thread's CPU time, ns: on a shared machine a wall clock also counts the time the scheduler
// gives to others, which longer runs catch more often (as bench_qd.c).
static double cpu_ns() {
  timespec t;
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return 1e9 * double(t.tv_sec) + double(t.tv_nsec);
}

// A run stops adding calls once it lasts about this long (ns): bench_median.h's QD_RUN_BUDGET_NS.
static const double run_budget_ns = 2e6;

static int calls_in_budget(double one_call_ns, int calls) {
  double fit = run_budget_ns / std::max(one_call_ns, 1.0);
  return fit < 1.0 ? 1 : fit < double(calls) ? int(fit) : calls;
}

// Median ns per call over REPS runs of CALLS calls (fewer for a slow function: calls_in_budget),
// after a warm-up of CALLS / 10 + 1 calls within the budget, as bench_median.h.
static double median_ns(const std::function<void()>& f, int calls, int reps) {
  std::vector<double> t;
  double t0 = cpu_ns();
  f();
  const int warm = calls_in_budget(cpu_ns() - t0, calls / 10 + 1);
  t0 = cpu_ns();
  for (int k = 0; k < warm; ++k) f();
  calls = calls_in_budget((cpu_ns() - t0) / warm, calls);
  for (int r = 0; r < reps; ++r) {
    double t0 = cpu_ns();
    for (int k = 0; k < calls; ++k) f();
    t.push_back((cpu_ns() - t0) / calls);
  }
  std::sort(t.begin(), t.end());
  return t[t.size() / 2];
}

int main(int argc, char** argv) {
  if (argc != 4 && argc != 8) {
    std::fprintf(stderr, "usage: %s URDF CALLS REPS [FOOT_FL FOOT_FR FOOT_BL FOOT_BR]\n", argv[0]);
    return 2;
  }
  pin::Model model;
  pin::urdf::buildModel(argv[1], pin::JointModelFreeFlyer(), model);
  pin::Data data(model);
  const int calls = std::atoi(argv[2]), reps = std::atoi(argv[3]);
  std::srand(7);
  Eigen::VectorXd dq = 0.1 * Eigen::VectorXd::Random(model.nv);
  Eigen::VectorXd q = pin::integrate(model, pin::neutral(model), dq);
  Eigen::VectorXd v = Eigen::VectorXd::Random(model.nv), a = Eigen::VectorXd::Random(model.nv);
  Eigen::VectorXd tau = Eigen::VectorXd::Random(model.nv);
  const Ref q_r(q), v_r(v), a_r(a), tau_r(tau);
  volatile double sink = 0;
  std::printf("crba %.2f\n", median_ns([&] { pin::crba(model, data, q_r, pin::Convention::LOCAL); sink = sink + data.M(0, 0); }, calls, reps));
  std::printf("nonLinearEffects %.2f\n", median_ns([&] { sink = sink + pin::nonLinearEffects(model, data, q_r, v_r)[0]; }, calls, reps));
  std::printf("computeGeneralizedGravity %.2f\n",
              median_ns([&] { sink = sink + pin::computeGeneralizedGravity(model, data, q_r)[0]; }, calls, reps));
  std::printf("rnea %.2f\n", median_ns([&] { sink = sink + pin::rnea(model, data, q_r, v_r, a_r)[0]; }, calls, reps));
  { // analytical derivatives (Carpentier & Mansard 2018), the peers of did_full and dfd_full
    std::printf("aba %.2f\n", median_ns([&] { sink = sink + pin::aba(model, data, q_r, v_r, tau_r, pin::Convention::WORLD)[0]; }, calls, reps));
    Eigen::MatrixXd dtau_dq = Eigen::MatrixXd::Zero(model.nv, model.nv), dtau_dv = dtau_dq, dtau_da = dtau_dq;
    Eigen::Ref<Eigen::MatrixXd> dtau_dq_r(dtau_dq), dtau_dv_r(dtau_dv), dtau_da_r(dtau_da);
    std::printf("computeRNEADerivatives %.2f\n", median_ns([&] {
      pin::computeRNEADerivatives(model, data, q_r, v_r, a_r, dtau_dq_r, dtau_dv_r, dtau_da_r); sink = sink + dtau_dq(0, 0); }, calls, reps));
    std::printf("computeABADerivatives %.2f\n", median_ns([&] {
      pin::computeABADerivatives(model, data, q_r, v_r, tau_r); sink = sink + data.ddq_dq(0, 0); }, calls, reps));
  }
  if (argc == 8) {
    const char* labels[4] = {"FL", "FR", "BL", "BR"};
    Eigen::VectorXd tau = Eigen::VectorXd::Random(model.nv);
    for (int set = 0; set < 16; ++set) {
      int k = __builtin_popcount(set);
      if (k < 2) continue;
      std::vector<pin::RigidConstraintModel> contacts;
      std::string name = "constraintDynamics";
      for (int i = 0; i < 4; ++i) {
        if (!(set & (1 << i))) continue;
        const pin::Frame& frame = model.frames[model.getFrameId(argv[4 + i])];
        contacts.emplace_back(pin::CONTACT_3D, model, frame.parentJoint, frame.placement, pin::LOCAL_WORLD_ALIGNED);
        name += std::string("_") + labels[i];
      }
      std::vector<pin::RigidConstraintData> datas;
      for (const pin::RigidConstraintModel& c : contacts) datas.emplace_back(c);
      pin::initConstraintDynamics(model, data, contacts, datas);
      pin::ProximalSettings prox(1e-12, 0.0, 1);
      Eigen::MatrixXd ddq_dq(model.nv, model.nv), ddq_dv(model.nv, model.nv), ddq_dtau(model.nv, model.nv);
      Eigen::MatrixXd dlambda_dq(3 * k, model.nv), dlambda_dv(3 * k, model.nv), dlambda_dtau(3 * k, model.nv);
      std::printf("%s %.2f\n", name.c_str(), median_ns([&] {
        sink = sink + pin::constraintDynamics(model, data, q, v, tau, contacts, datas, prox)[0]; }, calls, reps));
      std::string derivatives = "constraintDynamicsDerivatives" + name.substr(std::string("constraintDynamics").size());
      std::printf("%s %.2f\n", derivatives.c_str(), median_ns([&] {
        pin::constraintDynamics(model, data, q, v, tau, contacts, datas, prox);
        pin::computeConstraintDynamicsDerivatives(model, data, contacts, datas, prox, ddq_dq, ddq_dv, ddq_dtau,
                                                  dlambda_dq, dlambda_dv, dlambda_dtau);
        sink = sink + ddq_dq(0, 0); }, calls, reps));
    }
  }
  return 0;
}
