// specJson: the JSON a worker process is sent to build a spec reads back to the same
// function (the same normalizedSpecJson, hence the same cache key) for every example spec
// and for a user function using every field of the user form; a user function's
// normalised JSON, a key, does not read back.
#include <cmath>
#include <filesystem>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "robodiff/functions/function_spec.hpp"
#include "support/test_paths.hpp"

namespace robodiff {
namespace {

// specJson parsed again builds the same function, and is a fixed point.
void expectReadsBack(const FunctionSpec& spec, const std::string& name) {
  SCOPED_TRACE(name);
  const std::string text = specJson(spec);
  FunctionSpec again;
  ASSERT_NO_THROW(again = parseFunctionSpec(text, name + " (specJson)")) << text;
  EXPECT_EQ(normalizedSpecJson(again), normalizedSpecJson(spec));
  EXPECT_EQ(specJson(again), text);
  EXPECT_EQ(again.functionName(), spec.functionName());
  EXPECT_EQ(again.inputNames(), spec.inputNames());
}

TEST(SpecJson, EveryExampleSpecReadsBackToTheSameFunction) {
  int specs = 0, user = 0;
  for (const auto& entry : std::filesystem::directory_iterator(testing::sourceDir() / "examples/specs")) {
    if (entry.path().extension() != ".json") continue;
    const FunctionSpec spec = loadFunctionSpec(entry.path().string());
    expectReadsBack(spec, entry.path().filename().string());
    ++specs;
    user += spec.isUser() ? 1 : 0;
    if (!spec.isUser()) {
      EXPECT_EQ(specJson(spec), normalizedSpecJson(spec));
    }
  }
  EXPECT_GE(specs, 20);
  EXPECT_GE(user, 6);
}

// Every field of the user form: each input kind and size form, a sphere and a capsule,
// every output kind, sparse layouts, input and fixed weights, a vjp's lambda, numbers
// that need all 17 digits, build options.
constexpr const char* kEveryField = R"js({
  "description": "left out of specJson",
  "name": "every_field",
  "inputs": {"q": "configuration", "v": "nv", "w": " 2 * nv ", "target": 3, "lam": "nv",
             "dt": {"fixed": [0.1, -0.0, 1e-300, 40]}},
  "shapes": {
    "hand": {"frame": "tool", "sphere": {"center": [0.1, 0.2, 0.30000000000000004], "radius": 0.05}},
    "arm": {"frame": "link2", "capsule": {"a": [0, 0, 0], "b": [-0.2837, 0.0329, -0.0216], "radius": 0.04}}
  },
  "define": {
    "z_last": "frame_position(q, 'tool') - target",
    "a_first": "v + dt[0] * aba(q, v, w[0:nv])",
    "gap": "distance(q, 'hand', 'arm')"
  },
  "outputs": [
    {"name": "step", "kind": "value", "of": "a_first", "description": "dropped"},
    {"name": "d_step", "kind": "jacobian", "of": "a_first", "wrt": ["v", "q"], "layout": "sparse"},
    {"name": "d_dense", "kind": "jacobian", "of": "a_first", "wrt": ["q"], "layout": "dense"},
    {"name": "g", "kind": "gradient", "of": "sumsq(z_last) + gap", "wrt": ["q"]},
    {"name": "h", "kind": "hessian", "of": "sumsq(z_last)", "wrt": ["q", "target"]},
    {"name": "hw", "kind": "hessian", "of": "z_last", "wrt": ["q"], "weights": [1, 0.5, 0.25], "layout": "sparse"},
    {"name": "hi", "kind": "hessian", "of": "a_first", "wrt": ["v"], "weights": "lam"},
    {"name": "back", "kind": "vjp", "of": "a_first", "wrt": ["q", "v"], "lambda": "lam"}
  ],
  "build": {"optimization": "O1", "march_native": false, "fast_math": true}
})js";

TEST(SpecJson, AUserFunctionWithEveryFieldReadsBack) {
  const FunctionSpec spec = parseFunctionSpec(kEveryField, "every field");
  expectReadsBack(spec, "every field");
  const nlohmann::ordered_json j = nlohmann::ordered_json::parse(specJson(spec));
  // The order written: the inputs' is the runtime blocks' order.
  std::vector<std::string> inputs;
  for (const auto& [name, _] : j["inputs"].items()) inputs.push_back(name);
  EXPECT_EQ(inputs, (std::vector<std::string>{"q", "v", "w", "target", "lam", "dt"}));
  EXPECT_FALSE(j.contains("description"));
  EXPECT_FALSE(j["outputs"][0].contains("description"));
  EXPECT_EQ(j["define"]["a_first"], "v + dt[0] * aba(q, v, w[0:nv])");
  const FunctionSpec again = parseFunctionSpec(j.dump());
  EXPECT_EQ(again.user->shapes.at("hand").a.z(), 0.30000000000000004);
  EXPECT_EQ(again.user->inputs[5].fixed, (std::vector<double>{0.1, -0.0, 1e-300, 40}));
  EXPECT_TRUE(std::signbit(again.user->inputs[5].fixed[1]));
}

// Why specJson exists: the normalised JSON of a user function is a key, not a spec.
TEST(SpecJson, AUserFunctionsNormalisedJsonIsNotASpec) {
  const FunctionSpec spec = parseFunctionSpec(kEveryField, "every field");
  try {
    parseFunctionSpec(normalizedSpecJson(spec), "<key>");
    FAIL() << "the normalised JSON of a user function parsed as a spec";
  } catch (const SpecError& e) {
    EXPECT_NE(std::string(e.what()).find("terms: unknown field"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace robodiff
