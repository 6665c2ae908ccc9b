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
#include <memory>
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

// One algorithm to time, and what its runs found.
struct Timed {
  std::string name;
  std::function<void()> f;
  int warm = 0, calls = 0;
  std::vector<double> t;
};

// Median ns per call of each algorithm over REPS runs of CALLS calls (fewer for a slow one: calls_in_budget), the
// runs interleaved as bench_median.h's qd_medians_ns: each calibrated (one call, then CALLS / 10 + 1 within the
// budget), then in each of REPS rounds every algorithm in turn gets its warm-up again and one timed run.
static void medians_ns(std::vector<Timed>& all, int calls, int reps) {
  for (Timed& a : all) {
    double t0 = cpu_ns();
    a.f();
    a.warm = calls_in_budget(cpu_ns() - t0, calls / 10 + 1);
    t0 = cpu_ns();
    for (int k = 0; k < a.warm; ++k) a.f();
    a.calls = calls_in_budget((cpu_ns() - t0) / a.warm, calls);
  }
  for (int r = 0; r < reps; ++r) {
    for (Timed& a : all) {
      for (int k = 0; k < a.warm; ++k) a.f();
      const double t0 = cpu_ns();
      for (int k = 0; k < a.calls; ++k) a.f();
      a.t.push_back((cpu_ns() - t0) / a.calls);
    }
  }
  for (Timed& a : all) {
    std::sort(a.t.begin(), a.t.end());
    std::printf("%s %.2f\n", a.name.c_str(), a.t[a.t.size() / 2]);
  }
}

// The rigid point contacts of one stance set and the Data their algorithms fill (one per set: the runs interleave).
struct Stance {
  std::vector<pin::RigidConstraintModel> contacts;
  std::vector<pin::RigidConstraintData> datas;
  pin::Data data;
  Eigen::MatrixXd ddq_dq, ddq_dv, ddq_dtau, dlambda_dq, dlambda_dv, dlambda_dtau;
  explicit Stance(const pin::Model& model) : data(model) {}
};

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
  std::vector<Timed> all;
  all.push_back({"crba", [&] { pin::crba(model, data, q_r, pin::Convention::LOCAL); sink = sink + data.M(0, 0); }});
  all.push_back({"nonLinearEffects", [&] { sink = sink + pin::nonLinearEffects(model, data, q_r, v_r)[0]; }});
  all.push_back({"computeGeneralizedGravity", [&] { sink = sink + pin::computeGeneralizedGravity(model, data, q_r)[0]; }});
  all.push_back({"rnea", [&] { sink = sink + pin::rnea(model, data, q_r, v_r, a_r)[0]; }});
  // analytical derivatives (Carpentier & Mansard 2018), the peers of did_full and dfd_full
  all.push_back({"aba", [&] { sink = sink + pin::aba(model, data, q_r, v_r, tau_r, pin::Convention::WORLD)[0]; }});
  Eigen::MatrixXd dtau_dq = Eigen::MatrixXd::Zero(model.nv, model.nv), dtau_dv = dtau_dq, dtau_da = dtau_dq;
  Eigen::Ref<Eigen::MatrixXd> dtau_dq_r(dtau_dq), dtau_dv_r(dtau_dv), dtau_da_r(dtau_da);
  all.push_back({"computeRNEADerivatives", [&] {
    pin::computeRNEADerivatives(model, data, q_r, v_r, a_r, dtau_dq_r, dtau_dv_r, dtau_da_r); sink = sink + dtau_dq(0, 0); }});
  all.push_back({"computeABADerivatives", [&] {
    pin::computeABADerivatives(model, data, q_r, v_r, tau_r); sink = sink + data.ddq_dq(0, 0); }});
  std::vector<std::unique_ptr<Stance>> stances; // stable addresses: the lambdas hold them
  pin::ProximalSettings prox(1e-12, 0.0, 1); // constraintDynamics writes its iteration count here
  Eigen::VectorXd tau_c = Eigen::VectorXd::Random(model.nv);
  if (argc == 8) {
    const char* labels[4] = {"FL", "FR", "BL", "BR"};
    for (int set = 0; set < 16; ++set) {
      int k = __builtin_popcount(set);
      if (k < 2) continue;
      stances.push_back(std::make_unique<Stance>(model));
      Stance& s = *stances.back();
      std::string name = "constraintDynamics";
      for (int i = 0; i < 4; ++i) {
        if (!(set & (1 << i))) continue;
        const pin::Frame& frame = model.frames[model.getFrameId(argv[4 + i])];
        s.contacts.emplace_back(pin::CONTACT_3D, model, frame.parentJoint, frame.placement, pin::LOCAL_WORLD_ALIGNED);
        name += std::string("_") + labels[i];
      }
      for (const pin::RigidConstraintModel& c : s.contacts) s.datas.emplace_back(c);
      pin::initConstraintDynamics(model, s.data, s.contacts, s.datas);
      s.ddq_dq.resize(model.nv, model.nv), s.ddq_dv.resize(model.nv, model.nv), s.ddq_dtau.resize(model.nv, model.nv);
      s.dlambda_dq.resize(3 * k, model.nv), s.dlambda_dv.resize(3 * k, model.nv), s.dlambda_dtau.resize(3 * k, model.nv);
      all.push_back({name, [&, p = &s] {
        sink = sink + pin::constraintDynamics(model, p->data, q, v, tau_c, p->contacts, p->datas, prox)[0]; }});
      all.push_back({"constraintDynamicsDerivatives" + name.substr(std::string("constraintDynamics").size()), [&, p = &s] {
        pin::constraintDynamics(model, p->data, q, v, tau_c, p->contacts, p->datas, prox);
        pin::computeConstraintDynamicsDerivatives(model, p->data, p->contacts, p->datas, prox, p->ddq_dq, p->ddq_dv,
                                                  p->ddq_dtau, p->dlambda_dq, p->dlambda_dv, p->dlambda_dtau);
        sink = sink + p->ddq_dq(0, 0); }});
    }
  }
  medians_ns(all, calls, reps);
  return 0;
}
