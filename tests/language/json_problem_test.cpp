// A JSON parser's error as a person reads it: the line and column, what was wrong, no
// library codes; other messages pass through unchanged.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "robodiff/language/json_problem.hpp"

namespace robodiff::testing {
namespace {

std::string problemOf(const std::string& text) {
  try {
    [[maybe_unused]] const nlohmann::json parsed = nlohmann::json::parse(text);
  } catch (const nlohmann::json::exception& e) {
    return language::jsonProblem(e.what());
  }
  return "parsed";
}

TEST(JsonProblem, ParseErrorsKeepTheLocationAndTheReasonOnly) {
  const std::string unclosed = problemOf("{\"function\": \"rnea\",\n \"outputs\": [ {\"kind\": \"value\"}\n");
  EXPECT_EQ(unclosed, "line 3, column 1: unexpected end of input; expected ']' (in an array)");
  const std::string stray = problemOf("{\"q\": [1, 2,\n}");
  EXPECT_EQ(stray.rfind("line 2, column 1: unexpected '}'", 0), 0u) << stray;
  EXPECT_EQ(stray.find("json.exception"), std::string::npos) << stray;
  EXPECT_EQ(problemOf("[1e400]").find("json.exception"), std::string::npos) << problemOf("[1e400]");
}

TEST(JsonProblem, OtherMessagesAreUnchanged) {
  EXPECT_EQ(language::jsonProblem("holdout must be a number"), "holdout must be a number");
}

}  // namespace
}  // namespace robodiff::testing
