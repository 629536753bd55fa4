// jsonProblem on a parser message that quotes a long client text (nlohmann's "last read:
// '...'" of an unterminated 200 KB string) answers, cut, instead of overflowing the stack
// in std::regex. Found by tests/fuzz/spec_fuzz.cpp (regressions/spec/unterminated_200k_string.json).
#include <gtest/gtest.h>

#include <string>

#include "robodiff/language/json_problem.hpp"

namespace robodiff::language {
namespace {

TEST(JsonProblemLongMessage, IsCutAndStillReadable) {
  const std::string message =
      "[json.exception.parse_error.101] parse error at line 1, column 200008: syntax error while parsing value - "
      "invalid string: missing closing quote; last read: '\"" +
      std::string(200000, 'x') + "'";
  const std::string problem = jsonProblem(message);
  EXPECT_LT(problem.size(), 1200u);
  EXPECT_EQ(problem.rfind("line 1, column 200008: invalid string: missing closing quote; last read: '\"xxx", 0), 0u)
      << problem.substr(0, 200);
}

}  // namespace
}  // namespace robodiff::language
