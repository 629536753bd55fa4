// Built functions against Pinocchio's derivatives in ../shared/golden (1e-9): RNEA
// d tau/d(q, v, a) and ABA d ddq/d(q, v, tau), fixed and floating base; ABA's analytic
// Jacobian equals the differentiated one and is the smaller graph.
#include <iostream>

#include <Eigen/LU>

#include <gtest/gtest.h>

#include "robodiff/codegen/interpreter.hpp"
#include "robodiff/functions/evaluation.hpp"
#include "robodiff/functions/function_builder.hpp"
#include "robodiff/model/urdf_loader.hpp"
#include "robodiff/symbolic/cone.hpp"
#include "support/golden.hpp"
#include "support/test_paths.hpp"

namespace robodiff {
namespace {

using testing::matricesAgree;

FunctionSpec jacobianSpec(ModelFunction fn) {
  const std::string x = fn == ModelFunction::Rnea ? "a" : "tau";
  return parseFunctionSpec(R"({"function": ")" + std::string(toString(fn)) +
                           R"(", "outputs": [{"kind": "value"}, {"kind": "jacobian", "wrt": ["q", "v", ")" + x +
                           R"("]}]})");
}

std::size_t operations(const BuiltFunction& f) {
  std::vector<symbolic::NodeId> all;
  for (const codegen::OutputBlock& b : f.definition.outputs) all.insert(all.end(), b.values.begin(), b.values.end());
  return symbolic::coneSize(*f.graph, all).operations;
}

class Golden : public ::testing::TestWithParam<std::string> {};

TEST_P(Golden, JacobiansMatchPinocchio) {
  ROBODIFF_REQUIRE_SHARED(shared);
  const testing::GoldenRobot golden = testing::loadGolden(shared, GetParam());
  const Model model = loadUrdfFile(golden.urdf.string(), golden.free_flyer ? RootJoint::FreeFlyer : RootJoint::Fixed);
  const int n = model.nv;
  for (ModelFunction fn : {ModelFunction::Rnea, ModelFunction::Aba}) {
    SCOPED_TRACE(toString(fn));
    const BuiltFunction f = buildFunction(model, jacobianSpec(fn));
    codegen::Interpreter interpreter(*f.graph, f.definition);
    for (std::size_t s = 0; s < golden.samples.size(); s += 4) {
      const auto& x = golden.samples[s];
      const std::vector<Eigen::VectorXd> out =
          evaluateBlocks(interpreter, f.definition, {x.q, x.v, fn == ModelFunction::Rnea ? x.a : x.tau});
      const Eigen::MatrixXd J = blockMatrix(f.definition.outputs[1], out[1]);
      if (fn == ModelFunction::Rnea) {
        EXPECT_TRUE(matricesAgree(out[0], x.tau, 1e-9));
        EXPECT_TRUE(matricesAgree(J.leftCols(n), x.dtau_dq, 1e-9));
        EXPECT_TRUE(matricesAgree(J.middleCols(n, n), x.dtau_dv, 1e-9));
        EXPECT_TRUE(matricesAgree(J.rightCols(n), x.M, 1e-9));
      } else {
        EXPECT_TRUE(matricesAgree(out[0], x.ddq, 1e-9));
        EXPECT_TRUE(matricesAgree(J.leftCols(n), x.dddq_dq, 1e-9));
        EXPECT_TRUE(matricesAgree(J.middleCols(n, n), x.dddq_dv, 1e-9));
        EXPECT_TRUE(matricesAgree(J.rightCols(n), x.M.inverse(), 1e-9));
      }
    }
  }
}

// The choice made for ABA (core/functions/README.md): the analytic Jacobian's graph is
// smaller than differentiating the traced ABA, and both agree.
TEST(AbaJacobian, AnalyticIsSmallerAndEqualToDifferentiated) {
  ROBODIFF_REQUIRE_SHARED(shared);
  for (const char* name : {"panda", "talos"}) {
    SCOPED_TRACE(name);
    const testing::GoldenRobot golden = testing::loadGolden(shared, name);
    const Model model = loadUrdfFile(golden.urdf.string());
    FunctionBuilderOptions differentiate;
    differentiate.aba_jacobian = AbaJacobianMethod::Differentiate;
    const FunctionSpec spec = jacobianSpec(ModelFunction::Aba);
    const BuiltFunction analytic = buildFunction(model, spec), direct = buildFunction(model, spec, differentiate);
    std::cout << name << " ABA value + Jacobian: analytic " << operations(analytic) << " operations ("
              << analytic.method << "), differentiated " << operations(direct) << " (" << direct.method << ")\n";
    EXPECT_LT(operations(analytic), operations(direct));
    const auto& x = golden.samples[0];
    codegen::Interpreter a(*analytic.graph, analytic.definition), d(*direct.graph, direct.definition);
    EXPECT_TRUE(matricesAgree(evaluateBlocks(a, analytic.definition, {x.q, x.v, x.tau})[1],
                              evaluateBlocks(d, direct.definition, {x.q, x.v, x.tau})[1], 1e-10));
  }
}

INSTANTIATE_TEST_SUITE_P(Pinocchio, Golden, ::testing::Values("panda", "ur5", "talos", "talos_ff"));

}  // namespace
}  // namespace robodiff
