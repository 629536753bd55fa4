// A number too large for a double in a spec's JSON (1e400) is a SpecError like any other
// invalid JSON (nlohmann throws out_of_range, not parse_error, for it); before, it escaped
// parseFunctionSpec and robodiffd answered INTERNAL. Found by tests/fuzz/spec_fuzz.cpp.
#include <gtest/gtest.h>

#include <string>

#include "robodiff/functions/function_spec.hpp"

namespace robodiff {
namespace {

TEST(SpecNumberOverflow, IsRefusedAsInvalidJsonNamingTheNumber) {
  const std::string spec = R"({"function": "aba", "inputs": {"q": "variable", "v": {"fixed": [1e400]}}})";
  try {
    parseFunctionSpec(spec, "spec_json");
    FAIL() << "accepted";
  } catch (const SpecError& e) {
    const std::string message = e.what();
    EXPECT_NE(message.find("spec_json: not valid JSON"), std::string::npos) << message;
    EXPECT_NE(message.find("number overflow parsing '1e400'"), std::string::npos) << message;
  }
}

}  // namespace
}  // namespace robodiff
