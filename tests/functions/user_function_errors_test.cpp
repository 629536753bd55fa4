// Bad user functions get errors a person can act on: the define or output, the column,
// what was expected; the closest names for unknown ones; both shapes of a mismatch;
// the closest frames; limits as SpecTooLarge; nothing crashes on hostile input.
#include <gtest/gtest.h>

#include "robodiff/functions/function_builder.hpp"
#include "robodiff/model/urdf_loader.hpp"
#include "support/test_paths.hpp"

namespace robodiff {
namespace {

Model arm7() {
  return loadUrdfFile((testing::sourceDir() / "examples" / "robots" / "arm7.urdf").string(), RootJoint::Fixed);
}

std::string spec(const std::string& define, const std::string& extra_inputs = "") {
  return R"js({"inputs": {"q": "configuration", "v": "nv")js" + extra_inputs + R"js(},
    "define": {"y": ")js" + define + R"js("},
    "outputs": [{"name": "y", "kind": "value", "of": "y"}]})js";
}

// The message of the SpecError that parsing and building `json` throws.
std::string errorOf(const std::string& json) {
  try {
    buildFunction(arm7(), parseFunctionSpec(json, "s.json"));
  } catch (const SpecError& e) {
    return e.what();
  }
  ADD_FAILURE() << "no error for " << json;
  return "";
}

void expectError(const std::string& json, std::initializer_list<const char*> phrases) {
  const std::string message = errorOf(json);
  for (const char* phrase : phrases) EXPECT_NE(message.find(phrase), std::string::npos) << "'" << phrase << "' not in:\n" << message;
}

TEST(UserFunctionErrors, SyntaxNamesTheDefineColumnAndWhatWasExpected) {
  expectError(spec("v + aba(q, v"), {"s.json", "define.y", "column", "expected", "^"});
  expectError(spec("v * * v"), {"define.y", "column 3", "expected an operand after '*'"});
  expectError(spec("v $ v"), {"define.y", "column 3", "$"});
}

TEST(UserFunctionErrors, UnknownNamesSuggestTheClosest) {
  expectError(spec("vv + v"), {"define.y", "column 1", "unknown name 'vv'", "did you mean", "'v'"});
  expectError(spec("abba(q, v, v)"), {"unknown function 'abba'", "'aba'"});
  expectError(spec("frame_positon(q, 'tool')"), {"'frame_position'"});
  expectError(R"js({"inputs": {"q": "configuration"}, "outputs": [{"name": "y", "kind": "valeu", "of": "q"}]})js",
              {"outputs[0].kind", "'value'"});
  expectError(R"js({"inputs": {"q": "configuration"}, "outputs": [{"name": "y", "kind": "jacobian", "of": "q", "wrt": ["qq"]}]})js",
              {"outputs[0].wrt[0]", "'qq'", "'q'"});
}

TEST(UserFunctionErrors, ShapeMismatchNamesBothShapes) {
  expectError(spec("v + [1; 2; 3]"), {"define.y", "7x1", "3x1"});
  expectError(spec("crba(q) @ [1; 2]"), {"7x7", "2x1", "'@'"});
  expectError(spec("aba(q, v, [1; 2])"), {"aba() argument 3", "nv = 7", "2x1"});
  expectError(R"js({"inputs": {"q": "configuration"}, "define": {"y": "q"},
    "outputs": [{"name": "g", "kind": "gradient", "of": "y", "wrt": ["q"]}]})js",
              {"outputs[0]", "gradient is of a scalar"});
}

TEST(UserFunctionErrors, UnknownFrameSuggestsTheClosestFrames) {
  const std::string message = errorOf(spec("frame_position(q, 'tol')"));
  EXPECT_EQ(message.rfind("s.json: define.y: column 19: ", 0), 0u) << "the source, define and column first: " << message;
  EXPECT_NE(message.find("'tol' is not a frame"), std::string::npos) << message;
  EXPECT_NE(message.find("'tool'"), std::string::npos) << message;
  EXPECT_EQ(message.find("link1"), std::string::npos) << "lists frames that are not close: " << message;
}

TEST(UserFunctionErrors, CyclesAndMisuse) {
  expectError(R"js({"inputs": {"q": "configuration"}, "define": {"a": "b + 1", "b": "2 * a"},
    "outputs": [{"name": "y", "kind": "value", "of": "a"}]})js", {"depends on itself"});
  expectError(spec("'tool' + v"), {"only names a frame"});
  expectError(spec("v[9]"), {"index 9", "7x1"});
  expectError(spec("v", R"js(, "nq": 3)js"), {"inputs.nq", "reserved"});
  expectError(spec("frame_position([1; 2], 'tool')"), {"argument 1", "configuration", "2x1"});
}

TEST(UserFunctionErrors, ShapesOnUnknownFramesAndOversizedInputs) {
  expectError(R"js({"inputs": {"q": "configuration"}, "shapes": {"s": {"frame": "tol", "sphere": {"radius": 0.1}}},
    "outputs": [{"name": "y", "kind": "value", "of": "sum(q)"}]})js", {"shapes.s.frame", "'tool'"});
  EXPECT_THROW(buildFunction(arm7(), parseFunctionSpec(R"js({"inputs": {"x": "nv * 100000"},
    "outputs": [{"name": "y", "kind": "value", "of": "sum(x)"}]})js")), SpecTooLarge);
}

TEST(UserFunctionErrors, LimitsAreResourceErrors) {
  auto tooLarge = [](const std::string& json) {
    try {
      parseFunctionSpec(json);
    } catch (const SpecTooLarge& e) {
      return std::string(e.what());
    } catch (const std::exception& e) {
      return std::string("other error: ") + e.what();
    }
    return std::string("no error");
  };
  EXPECT_NE(tooLarge(spec(std::string(100000, '(') + "v" + std::string(100000, ')'))).find("define.y"), std::string::npos);
  std::string chain = "v";
  for (int k = 0; k < 2000; ++k) chain += " + v";
  EXPECT_NE(tooLarge(spec(chain)).find("deeper"), std::string::npos);
  std::string many = R"js({"inputs": {"q": "configuration"}, "define": {)js";
  for (int k = 0; k < 1500; ++k) many += (k ? ", " : "") + std::string("\"d") + std::to_string(k) + "\": \"q\"";
  many += R"js(}, "outputs": [{"name": "y", "kind": "value", "of": "q"}]})js";
  EXPECT_NE(tooLarge(many).find("defines"), std::string::npos);
}

TEST(UserFunctionErrors, NothingInASpecIsExecuted) {
  // Strings are names looked up in the model or the spec, never paths or commands.
  expectError(spec("frame_position(q, '/etc/passwd')"), {"is not a frame"});
  expectError(spec("system(v)"), {"unknown function 'system'"});
  const std::string message = errorOf(spec("frame_position(q, '" + std::string(10'000'000, 'x') + "')"));
  EXPECT_LT(message.size(), 2000u) << "a 10 MB name is repeated in the message";
}

}  // namespace
}  // namespace robodiff
