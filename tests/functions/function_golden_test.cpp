// Built functions against Pinocchio's derivatives in ../shared/golden (1e-9): RNEA
// d tau/d(q, v, a) and ABA d ddq/d(q, v, tau), fixed and floating base; ABA's analytic
// Jacobian equals the differentiated one and is the smaller graph; the RNEA Jacobian is
// the cheaper of its two ways, which agree (also on a twin-legged quadruped written
// here); so is a value-only ABA.
#include <algorithm>
#include <iostream>
#include <random>
#include <tuple>
#include <utility>

#include <Eigen/LU>

#include <gtest/gtest.h>

#include "robodiff/codegen/interpreter.hpp"
#include "robodiff/dynamics/configuration.hpp"
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

std::size_t operations(const BuiltFunction& f) { return builtOperations(f); }

// The RNEA Jacobian built with the analytic partials and by differentiation.
std::pair<BuiltFunction, BuiltFunction> rneaJacobianBothWays(const Model& model) {
  FunctionBuilderOptions analytic, differentiate;
  analytic.rnea_jacobian = RneaJacobianMethod::Analytic;
  differentiate.rnea_jacobian = RneaJacobianMethod::Differentiate;
  const FunctionSpec spec = jacobianSpec(ModelFunction::Rnea);
  return {buildFunction(model, spec, analytic), buildFunction(model, spec, differentiate)};
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

// The RNEA Jacobian is built both ways (the analytic derivatives with their sweep's tau,
// and differentiation of the traced RNEA); the default keeps the analytic one when its
// single-knot code saves enough instructions (kAnalyticRneaInstructionsRatio: operations
// less lane pairs), and the two agree (independent algorithms). The Talos, fixed and
// free-flying, and the Panda go analytic; the UR5 does not.
TEST(RneaJacobian, TheCheaperOfAnalyticAndDifferentiatedIsKeptAndBothAgree) {
  ROBODIFF_REQUIRE_SHARED(shared);
  for (const char* name : {"panda", "ur5", "talos", "talos_ff"}) {
    SCOPED_TRACE(name);
    const testing::GoldenRobot golden = testing::loadGolden(shared, name);
    const Model model = loadUrdfFile(golden.urdf.string(), golden.free_flyer ? RootJoint::FreeFlyer : RootJoint::Fixed);
    const FunctionSpec spec = jacobianSpec(ModelFunction::Rnea);
    const auto [analytic, differentiated] = rneaJacobianBothWays(model);
    const BuiltFunction chosen = buildFunction(model, spec);
    const std::size_t analytic_cost = builtInstructions(analytic), differentiated_cost = builtInstructions(differentiated);
    std::cout << name << " RNEA value + Jacobian: analytic " << operations(analytic) << " operations, "
              << analytic_cost << " instructions; differentiated " << operations(differentiated) << ", "
              << differentiated_cost << "; kept: " << chosen.method << "\n";
    EXPECT_LE(analytic_cost, operations(analytic));  // a lane pair saves an instruction
    const bool analytic_kept = static_cast<double>(analytic_cost) <=
                               kAnalyticRneaInstructionsRatio * static_cast<double>(differentiated_cost);
    EXPECT_EQ(operations(chosen), analytic_kept ? operations(analytic) : operations(differentiated));
    EXPECT_NE(chosen.method.find(analytic_kept ? "Jacobian from analytic" : "Jacobian by symbolic differentiation"),
              std::string::npos)
        << chosen.method;
    codegen::Interpreter a(*analytic.graph, analytic.definition), d(*differentiated.graph, differentiated.definition);
    for (std::size_t s = 0; s < golden.samples.size(); s += 5) {
      const auto& x = golden.samples[s];
      const auto from_a = evaluateBlocks(a, analytic.definition, {x.q, x.v, x.a});
      const auto from_d = evaluateBlocks(d, differentiated.definition, {x.q, x.v, x.a});
      EXPECT_TRUE(matricesAgree(from_a[0], from_d[0], 1e-12));  // tau: world-frame sweep against local-frame RNEA
      EXPECT_TRUE(matricesAgree(from_a[1], from_d[1], 1e-10));
    }
  }
  // The measurements this choice was made on (medians over copies of each library,
  // core/functions/README.md): the Talos and the Panda go analytic, the UR5 not.
  for (const auto& [name, analytic] : {std::pair{"talos", true}, std::pair{"panda", true}, std::pair{"ur5", false}}) {
    const testing::GoldenRobot golden = testing::loadGolden(shared, name);
    const std::string method = buildFunction(loadUrdfFile(golden.urdf.string()), jacobianSpec(ModelFunction::Rnea)).method;
    EXPECT_EQ(method.find("Jacobian from analytic") != std::string::npos, analytic) << name << ": " << method;
  }
}

// A free-flying quadruped whose four 3-joint legs are twins (only their hip offsets
// differ), written here: no ../shared needed. Each link's centre of mass is off all three
// axes: on axis (0 0 -0.05), RNEA summed at the centres of mass (codegen 0.4.18) made
// differentiation the smaller by operations too (15,409 against 15,577), and the test
// would no longer tell the two measures apart.
std::string twinLeggedQuadrupedUrdf() {
  auto inertial = [](double mass) {
    return "<inertial><origin xyz=\"0.02 0.01 -0.05\"/><mass value=\"" + std::to_string(mass) +
           "\"/><inertia ixx=\"0.001\" iyy=\"0.0012\" izz=\"0.0008\" ixy=\"0\" ixz=\"0\" iyz=\"0\"/></inertial>";
  };
  auto joint = [](const std::string& name, const std::string& parent, const std::string& child,
                  const std::string& xyz, const std::string& axis) {
    return "<joint name=\"" + name + "\" type=\"revolute\"><parent link=\"" + parent + "\"/><child link=\"" + child +
           "\"/><origin xyz=\"" + xyz + "\"/><axis xyz=\"" + axis +
           "\"/><limit lower=\"-3\" upper=\"3\" effort=\"10\" velocity=\"10\"/></joint>";
  };
  std::string urdf = "<robot name=\"twin_quadruped\"><link name=\"trunk\">" + inertial(2.0) + "</link>";
  for (const auto& [leg, x, y] : {std::tuple{"fl", "0.2", "0.1"}, std::tuple{"fr", "0.2", "-0.1"},
                                  std::tuple{"hl", "-0.2", "0.1"}, std::tuple{"hr", "-0.2", "-0.1"}}) {
    const std::string l = leg, side = y[0] == '-' ? "-0.05" : "0.05";
    urdf += "<link name=\"" + l + "_hip\">" + inertial(0.2) + "</link>" +
            joint(l + "_haa", "trunk", l + "_hip", std::string(x) + " " + y + " 0", "1 0 0");
    urdf += "<link name=\"" + l + "_thigh\">" + inertial(0.3) + "</link>" +
            joint(l + "_hfe", l + "_hip", l + "_thigh", "0 " + side + " 0", "0 1 0");
    urdf += "<link name=\"" + l + "_shank\">" + inertial(0.1) + "</link>" +
            joint(l + "_kfe", l + "_thigh", l + "_shank", "0 0 -0.16", "0 1 0");
  }
  return urdf + "</robot>";
}

// Where the legs are twins, differentiation's reverse sweep pairs far more than the
// analytic partials: compared by operations (at the same ratio) the analytic way would
// be kept; by single-knot instructions the builder keeps differentiation (as on
// Solo-12, where it ran 2.32 against 2.75 µs). Both ways agree.
TEST(RneaJacobian, TwinLegsAreComparedByInstructionsNotOperations) {
  const Model model = loadUrdfString(twinLeggedQuadrupedUrdf(), RootJoint::FreeFlyer, "twin_quadruped");
  const FunctionSpec spec = jacobianSpec(ModelFunction::Rnea);
  const auto [analytic, differentiated] = rneaJacobianBothWays(model);
  std::cout << "twin quadruped RNEA + J: analytic " << operations(analytic) << " operations, "
            << builtInstructions(analytic) << " instructions; differentiated " << operations(differentiated) << ", "
            << builtInstructions(differentiated) << "\n";
  ASSERT_LT(operations(analytic), kAnalyticRneaInstructionsRatio * operations(differentiated));
  ASSERT_GT(builtInstructions(analytic), kAnalyticRneaInstructionsRatio * builtInstructions(differentiated));
  const BuiltFunction chosen = buildFunction(model, spec);
  EXPECT_NE(chosen.method.find("Jacobian by symbolic differentiation"), std::string::npos) << chosen.method;
  codegen::Interpreter a(*analytic.graph, analytic.definition), d(*differentiated.graph, differentiated.definition);
  std::mt19937_64 rng(5);
  const Eigen::VectorXd q = randomConfiguration(model, rng);
  const Eigen::VectorXd v = Eigen::VectorXd::Random(model.nv), acc = Eigen::VectorXd::Random(model.nv);
  const auto from_a = evaluateBlocks(a, analytic.definition, {q, v, acc});
  const auto from_d = evaluateBlocks(d, differentiated.definition, {q, v, acc});
  EXPECT_TRUE(matricesAgree(from_a[1], from_d[1], 1e-10));
}

// A value-only ABA is built both ways (ABA, and M^-1 (tau - nle) by M's tree factors); the
// one with fewer operations is kept, and both give Pinocchio's ABA. The factors are the
// smaller on the Panda and the fixed Talos, ABA on the free-flying Talos.
TEST(AbaValue, TheCheaperOfArticulatedAndFactorsIsKeptAndBothMatchPinocchio) {
  ROBODIFF_REQUIRE_SHARED(shared);
  const FunctionSpec spec = parseFunctionSpec(R"({"function": "aba", "outputs": [{"kind": "value"}]})");
  for (const auto& [name, factors_expected] :
       {std::pair{"panda", true}, std::pair{"talos", true}, std::pair{"talos_ff", false}}) {
    SCOPED_TRACE(name);
    const testing::GoldenRobot golden = testing::loadGolden(shared, name);
    const Model model = loadUrdfFile(golden.urdf.string(), golden.free_flyer ? RootJoint::FreeFlyer : RootJoint::Fixed);
    FunctionBuilderOptions articulated_options, factors_options;
    articulated_options.aba_value = AbaValueMethod::Articulated;
    factors_options.aba_value = AbaValueMethod::Factors;
    const BuiltFunction articulated = buildFunction(model, spec, articulated_options);
    const BuiltFunction factors = buildFunction(model, spec, factors_options);
    const BuiltFunction chosen = buildFunction(model, spec);
    std::cout << name << " ABA value: articulated " << operations(articulated) << " operations, factors "
              << operations(factors) << "; kept: " << chosen.method << "\n";
    const bool factors_kept = operations(factors) <= operations(articulated);
    EXPECT_EQ(factors_kept, factors_expected);
    EXPECT_EQ(operations(chosen), std::min(operations(factors), operations(articulated)));
    EXPECT_EQ(chosen.method.find("by M's tree factors") != std::string::npos, factors_kept) << chosen.method;
    codegen::Interpreter a(*articulated.graph, articulated.definition), f(*factors.graph, factors.definition);
    for (std::size_t s = 0; s < golden.samples.size(); s += 3) {
      const auto& x = golden.samples[s];
      EXPECT_TRUE(matricesAgree(evaluateBlocks(a, articulated.definition, {x.q, x.v, x.tau})[0], x.ddq, 1e-9));
      EXPECT_TRUE(matricesAgree(evaluateBlocks(f, factors.definition, {x.q, x.v, x.tau})[0], x.ddq, 1e-9));
    }
  }
}

INSTANTIATE_TEST_SUITE_P(Pinocchio, Golden, ::testing::Values("panda", "ur5", "talos", "talos_ff"));

}  // namespace
}  // namespace robodiff
