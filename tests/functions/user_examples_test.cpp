// The user-function specs of examples/specs (the "inputs" / "define" / "outputs" form)
// built on their robots, every output checked against the double evaluation of the same
// expressions and its central finite differences, so that the examples cannot rot. Each
// spec's robot follows from its file name's prefix; a user spec with an unknown prefix
// fails. The Panda's need ../shared and skip without it.
#include <algorithm>
#include <cctype>
#include <filesystem>
#include <iostream>

#include <gtest/gtest.h>

#include "robodiff/codegen/interpreter.hpp"
#include "robodiff/functions/evaluation.hpp"
#include "robodiff/functions/function_builder.hpp"
#include "robodiff/functions/reference.hpp"
#include "robodiff/model/urdf_loader.hpp"
#include "support/golden.hpp"
#include "support/test_paths.hpp"

namespace robodiff {
namespace {

namespace fs = std::filesystem;
using testing::matricesAgree;

fs::path specsDir() { return testing::sourceDir() / "examples" / "specs"; }

// The example specs of the user form, by file stem.
std::vector<std::string> userExampleSpecs() {
  std::vector<std::string> names;
  for (const auto& entry : fs::directory_iterator(specsDir()))
    if (entry.path().extension() == ".json" && loadFunctionSpec(entry.path().string()).user)
      names.push_back(entry.path().stem().string());
  std::sort(names.begin(), names.end());
  return names;
}

struct Robot {
  std::string urdf;  // empty: not known for this spec
  RootJoint root = RootJoint::Fixed;
  bool shared = false;  // the URDF is in ../shared
};

Robot robotFor(const std::string& spec) {
  const fs::path robots = testing::sourceDir() / "examples" / "robots";
  if (spec.rfind("panda_", 0) == 0) return {"robots/panda_arm_fixed_fingers.urdf", RootJoint::Fixed, true};
  if (spec.rfind("arm7_", 0) == 0) return {(robots / "arm7.urdf").string(), RootJoint::Fixed, false};
  if (spec.rfind("quadruped_", 0) == 0) return {(robots / "quadruped.urdf").string(), RootJoint::FreeFlyer, false};
  return {};
}

class UserExampleSpec : public ::testing::TestWithParam<std::string> {};

TEST_P(UserExampleSpec, EveryOutputMatchesTheReference) {
  const std::string name = GetParam();
  const Robot robot = robotFor(name);
  ASSERT_FALSE(robot.urdf.empty()) << name << ".json: no robot for its prefix (panda_, arm7_, quadruped_); add one here";
  fs::path urdf = robot.urdf;
  if (robot.shared) {
    ROBODIFF_REQUIRE_SHARED(shared);
    urdf = shared / robot.urdf;
  }
  const Model model = loadUrdfFile(urdf.string(), robot.root);
  const FunctionSpec spec = loadFunctionSpec((specsDir() / (name + ".json")).string());
  const BuiltFunction f = buildFunction(model, spec);
  std::cout << name << ": " << f.rule_operations << " operations with the primitives' rules, " << f.traced_operations
            << " differentiating their traces\n";
  codegen::Interpreter interpreter(*f.graph, f.definition);
  for (std::uint64_t seed = 1; seed <= 2; ++seed) {
    const std::vector<Eigen::VectorXd> variable = randomRuntimeInputs(model, spec, seed);
    const std::vector<Eigen::VectorXd> all = completeInputs(spec, variable);
    const std::vector<Eigen::VectorXd> out = evaluateBlocks(interpreter, f.definition, variable);
    const std::vector<Eigen::MatrixXd> expected = userReferenceOutputs(model, spec, all, 1e-6, 1e-4);
    ASSERT_EQ(out.size(), expected.size());
    for (std::size_t k = 0; k < out.size(); ++k) {
      SCOPED_TRACE(f.definition.outputs[k].name + " at seed " + std::to_string(seed));
      const Eigen::MatrixXd actual = blockMatrix(f.definition.outputs[k], out[k], spec.outputs[k].kind == OutputKind::Hessian);
      ASSERT_EQ(actual.rows(), expected[k].rows());
      ASSERT_EQ(actual.cols(), expected[k].cols());
      switch (spec.user->outputs[k].kind) {
        case UserOutputKind::Value: EXPECT_TRUE(matricesAgree(actual, expected[k], 1e-10)); break;
        case UserOutputKind::Hessian: EXPECT_TRUE(matricesAgree(actual, expected[k], 5e-5)); break;
        default: EXPECT_TRUE(matricesAgree(actual, expected[k], 1e-5)); break;
      }
    }
  }
}

INSTANTIATE_TEST_SUITE_P(Examples, UserExampleSpec, ::testing::ValuesIn(userExampleSpecs()),
                         [](const ::testing::TestParamInfo<std::string>& info) {
                           std::string name = info.param;  // a test name: letters, digits, _
                           for (char& c : name)
                             if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
                           return name;
                         });

// The examples the documentation and the MPC example rely on are there.
TEST(UserExampleSpecs, TheDocumentedOnesExist) {
  const std::vector<std::string> names = userExampleSpecs();
  for (const char* wanted : {"panda_euler_step", "panda_rk4_step", "panda_tracking_cost", "panda_collision_cost",
                             "panda_mpc_knot", "arm7_mpc_knot", "quadruped_step"})
    EXPECT_NE(std::find(names.begin(), names.end(), wanted), names.end()) << wanted;
}

}  // namespace
}  // namespace robodiff
