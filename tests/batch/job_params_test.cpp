// A job's parameters: a key the kind does not read (a typo) is refused with the closest
// names and the list of what the kind takes, before anything runs; a value of the wrong
// type is refused naming the key.
#include <gtest/gtest.h>

#include <fstream>

#include <nlohmann/json.hpp>

#include "robodiff/batch/batch_job.hpp"
#include "support/temp_dir.hpp"
#include "support/test_paths.hpp"

namespace robodiff::testing {
namespace {

using nlohmann::json;

std::string refusal(const std::string& kind, const json& params) {
  try {
    batch::validateBatchJob(kind, params);
  } catch (const batch::JobParamsError& e) {
    return e.what();
  }
  return "";
}

json identifyParams(const TempDir& tmp) {
  const auto data = tmp / "samples.csv";
  std::ofstream(data) << "q_0\n0\n";
  return {{"urdf", (sourceDir() / "examples/robots/arm7.urdf").string()}, {"data", data.string()}};
}

TEST(JobParams, AMisspeltKeyIsRefusedWithTheClosestNames) {
  TempDir tmp;
  json p = identifyParams(tmp);
  ASSERT_EQ(refusal("identify", p), "");  // the valid base
  p["holdot"] = 0.3;
  const std::string message = refusal("identify", p);
  EXPECT_NE(message.find("unknown parameter \"holdot\" for a job of kind identify"), std::string::npos) << message;
  EXPECT_NE(message.find("did you mean 'holdout'"), std::string::npos) << message;
  EXPECT_NE(message.find("it takes: urdf, urdf_text, floating_base, data, holdout"), std::string::npos) << message;

  p.erase("holdot");
  p["max_iterations"] = 10;  // a trajopt key: not one of identify's
  EXPECT_NE(refusal("identify", p).find("unknown parameter \"max_iterations\""), std::string::npos);
}

TEST(JobParams, ValuesOfTheWrongTypeAreRefusedNamingTheKey) {
  TempDir tmp;
  json p = identifyParams(tmp);
  p["weighted"] = "yes";
  EXPECT_NE(refusal("identify", p).find("weighted must be true or false, not \"yes\""), std::string::npos)
      << refusal("identify", p);
  p["weighted"] = true;
  p["holdout"] = "0.2";
  EXPECT_NE(refusal("identify", p).find("holdout must be a number"), std::string::npos) << refusal("identify", p);
}

}  // namespace
}  // namespace robodiff::testing
