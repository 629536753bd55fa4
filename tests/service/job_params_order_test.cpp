// A job's spec given as a JSON object keeps its key order on the way to the job's worker:
// a user spec's inputs are its calling convention, and sorted keys would reorder them.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "robodiff/functions/function_spec.hpp"
#include "robodiff/server/job_manager.hpp"
#include "support/test_paths.hpp"

namespace robodiff::server {
namespace {

std::vector<std::string> inputOrder(const FunctionSpec& spec) {
  std::vector<std::string> names;
  for (const InputSpec& input : spec.inputs) names.push_back(input.name);
  return names;
}

TEST(JobParams, ASpecObjectKeepsItsInputOrderOnTheWayToTheWorker) {
  const std::string spec_text = testing::readFile(testing::sourceDir() / "examples/specs/arm7_mpc_knot.json");
  const std::string params = R"({"urdf": "arm7.urdf", "spec_json": )" + spec_text + R"(, "data": "knots.csv"})";
  const FunctionSpec written = parseFunctionSpec(spec_text, "arm7_mpc_knot.json");

  const nlohmann::json kept = nlohmann::json::parse(jobParamsKeepingSpecOrder(params));
  ASSERT_TRUE(kept["spec_json"].is_string());
  const FunctionSpec received = parseFunctionSpec(kept["spec_json"].get<std::string>(), "spec_json");
  EXPECT_EQ(inputOrder(received), inputOrder(written));
  EXPECT_EQ(normalizedSpecJson(received), normalizedSpecJson(written));  // the same cache key
  EXPECT_EQ(kept["urdf"], "arm7.urdf");

  // What plain (sorted) JSON did before: another input order, another function.
  const nlohmann::json sorted = nlohmann::json::parse(params);
  const FunctionSpec reordered = parseFunctionSpec(sorted["spec_json"].dump(), "spec_json");
  EXPECT_NE(inputOrder(reordered), inputOrder(written));
}

TEST(JobParams, TextSpecsAndOtherParametersPassUnchanged) {
  const std::string params = R"({"spec_json": "{\"function\": \"rnea\"}", "knots": 3})";
  const nlohmann::json kept = nlohmann::json::parse(jobParamsKeepingSpecOrder(params));
  EXPECT_EQ(kept, nlohmann::json::parse(params));
  EXPECT_EQ(jobParamsKeepingSpecOrder("[1, 2]"), "");
  EXPECT_EQ(jobParamsKeepingSpecOrder("{not json"), "");
  EXPECT_EQ(jobParamsKeepingSpecOrder(""), "{}");
}

}  // namespace
}  // namespace robodiff::server
