// What the expressions compute is bounded (kMaxEvaluatedEntries, docs/function-language.md):
// before, `eye(10000) @ eye(10000)` kept a robodiffd trace thread busy for hours with GBs
// of memory, and a sum of two zeros(10000, 10000) took 22 s and 2.3 GB. Found by
// tests/fuzz/expression_fuzz.cpp. Both the builder (symbolic) and the reference (double)
// refuse them at once with SpecTooLarge (RESOURCE_EXHAUSTED).
#include <gtest/gtest.h>

#include <chrono>
#include <string>

#include "robodiff/functions/function_builder.hpp"
#include "robodiff/functions/reference.hpp"
#include "robodiff/model/urdf_loader.hpp"
#include "support/test_paths.hpp"

namespace robodiff {
namespace {

Model workLimitArm7() {
  return loadUrdfFile((testing::sourceDir() / "examples" / "robots" / "arm7.urdf").string(), RootJoint::Fixed);
}

FunctionSpec specOf(const std::string& expression) {
  return parseFunctionSpec(R"({"inputs": {"q": "configuration"}, "define": {"e": ")" + expression +
                           R"("}, "outputs": [{"name": "y", "kind": "value", "of": "e"}]})");
}

std::string tooLargeMessage(const std::string& expression, bool reference) {
  const Model model = workLimitArm7();
  const FunctionSpec spec = specOf(expression);
  const auto started = std::chrono::steady_clock::now();
  try {
    if (reference)
      userReferenceValue(model, spec, 0, {Eigen::VectorXd::Zero(model.nq)});
    else
      buildFunction(model, spec);
  } catch (const SpecTooLarge& e) {
    EXPECT_LT(std::chrono::steady_clock::now() - started, std::chrono::seconds(2));
    return e.what();
  }
  return "(not refused)";
}

TEST(UserFunctionWorkLimit, HugeProductsAndSumsAreRefusedAtOnce) {
  for (bool reference : {false, true}) {
    const std::string product = tooLargeMessage("sum(eye(10000) @ eye(10000))", reference);
    EXPECT_NE(product.find("define.e: column 5: the expressions compute more than 20000000 entries"), std::string::npos)
        << product;
    const std::string sum = tooLargeMessage("sum(zeros(10000, 10000) + zeros(10000, 10000))", reference);
    EXPECT_NE(sum.find("more than 20000000 entries"), std::string::npos) << sum;
  }
}

TEST(UserFunctionWorkLimit, LargeButReasonableExpressionsStillBuild) {
  const Model model = workLimitArm7();
  const FunctionSpec spec = specOf("sum(eye(1000) @ zeros(1000, 7) @ q) + sumsq(zeros(2000, 2000))");
  EXPECT_NO_THROW(userReferenceValue(model, spec, 0, {Eigen::VectorXd::Zero(model.nq)}));
}

}  // namespace
}  // namespace robodiff
