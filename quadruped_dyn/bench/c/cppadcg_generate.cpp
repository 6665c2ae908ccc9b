// Writes Pinocchio's CppADCodeGen C code of a free-flyer URDF model (the peer "pinocchio-cppadcodegen"
// of bench: quadruped_dyn/bench/cppadcg.py). Usage: cppadcg_generate URDF OUT_DIR.
// Pinocchio's own generators (pinocchio/codegen/cppadcg-algo.hpp) give crba (CodeGenCRBA: the upper
// triangle of M, row by row), rnea (CodeGenRNEA) and aba (CodeGenABA); nonLinearEffects and
// computeGeneralizedGravity have no generator there and are recorded the same way (CodeGenBase:
// CppAD tape of the algorithm on AD<CG<double>>, optimised, C source of its zero-order forward).
// Armature is zeroed (as the project's model). Of what CppADCodeGen writes, bench compiles only
// the forward functions, one file each: OUT_DIR/<name>_forward_zero.c defining
//   void <name>_forward_zero(double const* const* in, double* const* out, struct CLangAtomicFun f);
// with in[0] = x (Pinocchio's order: q = (p, quat xyzw, joints), v = (v_b, omega_b, joint rates)):
// crba x = q; rnea x = (q, v, a); aba x = (q, v, tau); nle x = (q, v); gravity x = q.
#include <cstdio>
#include <string>

#include <pinocchio/codegen/cppadcg-algo.hpp>
#include <pinocchio/algorithm/rnea.hpp>
#include <pinocchio/parsers/urdf.hpp>

namespace pin = pinocchio;

namespace {

// The same recording as Pinocchio's CodeGenRNEA, of nonLinearEffects (x = (q, v)).
struct CodeGenNLE : pin::CodeGenBase<double> {
  using Base = pin::CodeGenBase<double>;
  explicit CodeGenNLE(const Model& model) : Base(model, model.nq + model.nv, model.nv, "nle", "cg_nle_eval") {}
  void buildMap() override {
    CppAD::Independent(ad_X);
    ADConfigVectorType q = ad_X.head(ad_model.nq);
    ADTangentVectorType v = ad_X.tail(ad_model.nv);
    ad_Y = pin::nonLinearEffects(ad_model, ad_data, q, v);
    ad_fun.Dependent(ad_X, ad_Y);
    ad_fun.optimize("no_compare_op");
  }
};

// The same recording, of computeGeneralizedGravity (x = q).
struct CodeGenGravity : pin::CodeGenBase<double> {
  using Base = pin::CodeGenBase<double>;
  explicit CodeGenGravity(const Model& model) : Base(model, model.nq, model.nv, "gravity", "cg_gravity_eval") {}
  void buildMap() override {
    CppAD::Independent(ad_X);
    ADConfigVectorType q = ad_X;
    ad_Y = pin::computeGeneralizedGravity(ad_model, ad_data, q);
    ad_fun.Dependent(ad_X, ad_Y);
    ad_fun.optimize("no_compare_op");
  }
};

// Records the map and writes the C of its zero-order forward (with CppADCodeGen's library files) to OUT_DIR.
template <typename Generator>
void write(Generator& generator, const std::string& out_dir) {
  generator.initLib();
  CppAD::cg::ModelCSourceGen<double>& source = generator.codeGenerator();
  source.setCreateJacobian(false);
  source.setCreateSparseJacobian(false);
  CppAD::cg::ModelLibraryCSourceGen<double> library(source);
  CppAD::cg::SaveFilesModelLibraryProcessor<double>::saveLibrarySourcesTo(library, out_dir);
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 3) {
    std::fprintf(stderr, "usage: %s URDF OUT_DIR\n", argv[0]);
    return 2;
  }
  pin::Model model;
  pin::urdf::buildModel(argv[1], pin::JointModelFreeFlyer(), model);
  model.armature.setZero();
  const std::string out = argv[2];
  { pin::CodeGenCRBA<double> g(model); write(g, out); }
  { pin::CodeGenRNEA<double> g(model); write(g, out); }
  { pin::CodeGenABA<double> g(model); write(g, out); }
  { CodeGenNLE g(model); write(g, out); }
  { CodeGenGravity g(model); write(g, out); }
  return 0;
}
