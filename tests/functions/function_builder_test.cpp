// The function builder against the double reference: every example spec on the
// project's robots (a fixed-base arm with prismatic joints, a floating-base quadruped),
// interpreted. Values equal core/dynamics to 1e-12, Jacobians match central finite
// differences, Hessians second differences; ABA's analytic Jacobian equals the
// differentiated one and is smaller; spec problems and graph limits are clear errors.
#include <filesystem>

#include <Eigen/Eigenvalues>

#include <gtest/gtest.h>

#include "robodiff/codegen/interpreter.hpp"
#include "robodiff/functions/evaluation.hpp"
#include "robodiff/functions/function_builder.hpp"
#include "robodiff/functions/model_function.hpp"
#include "robodiff/functions/reference.hpp"
#include "robodiff/model/urdf_loader.hpp"
#include "robodiff/symbolic/cone.hpp"
#include "support/golden.hpp"
#include "support/robot_cases.hpp"
#include "support/test_paths.hpp"

namespace robodiff {
namespace {

namespace fs = std::filesystem;
using testing::matricesAgree;

struct Case {
  std::string label;
  Model model;
};

std::vector<Case> robots() {
  GeneratorOptions quadruped;
  quadruped.kind = RobotKind::Tree;
  quadruped.tree = "quadruped";
  quadruped.seed = 3;
  quadruped.prismatic_fraction = 0.2;
  GeneratorOptions chain;
  chain.joints = 6;
  chain.seed = 11;
  chain.prismatic_fraction = 0.3;
  return {
      {"arm7", loadUrdfFile((testing::sourceDir() / "examples/robots/arm7.urdf").string())},
      {"chain6_prismatic", loadUrdfString(generateRobotUrdf(chain), RootJoint::Fixed, "chain6")},
      {"quadruped_free_flyer", loadUrdfString(generateRobotUrdf(quadruped), RootJoint::FreeFlyer, "quadruped")},
  };
}

// The example specs, made to fit `model` (fixed inputs resized, frames chosen).
std::vector<std::pair<std::string, FunctionSpec>> exampleSpecs(const Model& model) {
  std::vector<std::pair<std::string, FunctionSpec>> specs;
  for (const auto& entry : fs::directory_iterator(testing::sourceDir() / "examples/specs")) {
    FunctionSpec spec = loadFunctionSpec(entry.path().string());
    if (spec.isUser()) continue;  // user functions: tests/functions/user_examples_test.cpp
    for (InputSpec& in : spec.inputs)
      if (in.fixed) in.fixed->assign(static_cast<std::size_t>(inputSize(model, in.name)), 0.0);
    if (functionInfo(spec.function).needs_frame && !model.findFrame(spec.frame)) spec.frame = model.frames.back().name;
    specs.emplace_back(entry.path().stem().string(), spec);
  }
  std::sort(specs.begin(), specs.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
  return specs;
}

std::vector<Eigen::VectorXd> interpret(const BuiltFunction& f, const std::vector<Eigen::VectorXd>& runtime) {
  codegen::Interpreter interpreter(*f.graph, f.definition);
  return evaluateBlocks(interpreter, f.definition, runtime);
}

// The runtime inputs without the weights block (the function's own inputs).
std::vector<Eigen::VectorXd> variableInputs(const BuiltFunction& f, const std::vector<Eigen::VectorXd>& runtime) {
  std::vector<Eigen::VectorXd> v;
  for (std::size_t b = 0; b < f.definition.inputs.size(); ++b)
    if (f.definition.inputs[b].name != "weights") v.push_back(runtime[b]);
  return v;
}

// 1e-12 relative; for functions that invert the mass matrix, rounding differences
// (Eigen's vectorised sums in double against the traced sequential order) grow with
// its condition number, so the bound is 1e-14 cond(M) when that is larger.
double valueTolerance(const Model& model, const FunctionSpec& spec, const std::vector<Eigen::VectorXd>& all) {
  if (spec.function != ModelFunction::Aba && spec.function != ModelFunction::Minv) return 1e-12;
  Data<double> data(model);
  const Eigen::VectorXd ev = Eigen::MatrixXd(crba(model, data, all[0])).selfadjointView<Eigen::Lower>().eigenvalues();
  return std::max(1e-12, 1e-14 * ev.maxCoeff() / ev.minCoeff());
}

class ExampleSpecs : public ::testing::TestWithParam<int> {};

TEST_P(ExampleSpecs, ValuesJacobiansAndHessiansMatchTheReference) {
  const Case robot = robots()[static_cast<std::size_t>(GetParam())];
  SCOPED_TRACE(robot.label);
  const Model& model = robot.model;
  for (const auto& [name, spec] : exampleSpecs(model)) {
    SCOPED_TRACE(name);
    const BuiltFunction f = buildFunction(model, spec);
    for (std::uint64_t seed = 1; seed <= 2; ++seed) {
      const std::vector<Eigen::VectorXd> runtime = randomRuntimeInputs(model, spec, seed);
      const std::vector<Eigen::VectorXd> all = completeInputs(spec, variableInputs(f, runtime));
      const std::vector<Eigen::VectorXd> out = interpret(f, runtime);
      const Eigen::VectorXd value = referenceValue(model, spec, all);
      for (std::size_t k = 0; k < spec.outputs.size(); ++k) {
        const OutputSpec& o = spec.outputs[k];
        const BuiltOutput& b = f.outputs[k];
        SCOPED_TRACE(b.name);
        const Eigen::MatrixXd got = blockMatrix(f.definition.outputs[k], out[k], o.kind == OutputKind::Hessian);
        ASSERT_EQ(got.rows(), b.rows);
        ASSERT_EQ(got.cols(), b.cols);
        if (o.kind == OutputKind::Value) {
          Eigen::MatrixXd expected(b.rows, b.cols);
          for (int r = 0, i = 0; r < b.rows; ++r)
            for (int c = 0; c < b.cols; ++c) expected(r, c) = value[i++];
          EXPECT_TRUE(matricesAgree(got, expected, valueTolerance(model, spec, all)));
        } else if (o.kind == OutputKind::Jacobian) {
          EXPECT_TRUE(matricesAgree(got, finiteDifferenceJacobian(model, spec, all, o.wrt), 1e-5));
        } else {
          const Eigen::VectorXd w = o.fixed_weights ? Eigen::Map<const Eigen::VectorXd>(o.fixed_weights->data(),
                                                                                        o.fixed_weights->size())
                                                    : Eigen::VectorXd(runtime.back());
          EXPECT_TRUE(matricesAgree(got, finiteDifferenceHessian(model, spec, all, w, o.wrt), 2e-5));
        }
      }
    }
  }
}

INSTANTIATE_TEST_SUITE_P(ProjectRobots, ExampleSpecs, ::testing::Values(0, 1, 2),
                         [](const ::testing::TestParamInfo<int>& info) {
                           return robots()[static_cast<std::size_t>(info.param)].label;
                         });

}  // namespace
}  // namespace robodiff
