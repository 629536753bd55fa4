// Function specs: every shipped example parses; invalid specs name the field and value;
// the normalised form is one spelling per meaning.
#include <filesystem>

#include <gtest/gtest.h>

#include "robodiff/functions/function_spec.hpp"
#include "support/test_paths.hpp"

namespace robodiff {
namespace {

TEST(FunctionSpec, EveryExampleParses) {
  const auto dir = testing::sourceDir() / "examples" / "specs";
  int count = 0;
  for (const auto& entry : std::filesystem::directory_iterator(dir)) {
    if (entry.path().extension() != ".json") continue;
    SCOPED_TRACE(entry.path().string());
    EXPECT_NO_THROW(loadFunctionSpec(entry.path().string()));
    ++count;
  }
  EXPECT_GE(count, 10);
  // The two the issue names, with their meaning.
  FunctionSpec rnea = loadFunctionSpec((dir / "rnea_jacobian.json").string());
  EXPECT_EQ(rnea.function, ModelFunction::Rnea);
  ASSERT_EQ(rnea.outputs.size(), 2u);
  EXPECT_EQ(rnea.outputs[1].kind, OutputKind::Jacobian);
  EXPECT_EQ(rnea.outputs[1].wrt, (std::vector<std::string>{"q", "v", "a"}));
  FunctionSpec aba = loadFunctionSpec((dir / "aba_jacobian.json").string());
  EXPECT_EQ(aba.function, ModelFunction::Aba);
  EXPECT_EQ(aba.outputs[1].wrt, (std::vector<std::string>{"q", "v", "tau"}));
}

TEST(FunctionSpec, DefaultsAndFixedInputs) {
  FunctionSpec s = parseFunctionSpec(R"({"function": "rnea", "inputs": {"v": {"fixed": [0, 0]}},
                                          "outputs": [{"kind": "value"}, {"kind": "hessian", "wrt": ["q"]}]})");
  EXPECT_FALSE(s.input("q").fixed);
  ASSERT_TRUE(s.input("v").fixed);
  EXPECT_EQ(*s.input("v").fixed, (std::vector<double>{0, 0}));
  EXPECT_FALSE(s.outputs[1].fixed_weights);  // weights default to a runtime input
  EXPECT_EQ(s.build.optimization, "O2");
  EXPECT_TRUE(s.build.march_native);
  EXPECT_FALSE(s.build.fast_math);
}

TEST(FunctionSpec, NormalisedFormIgnoresSpellingButNotMeaning) {
  auto norm = [](const std::string& text) { return normalizedSpecJson(parseFunctionSpec(text)); };
  const std::string a = R"({"function": "rnea", "outputs": [{"kind": "value"}]})";
  const std::string b = R"({ "outputs": [ {"kind":"value"} ], "description": "same thing",
                             "inputs": {"q": "variable"}, "function":"rnea", "build": {"optimization": "O2"} })";
  EXPECT_EQ(norm(a), norm(b));
  EXPECT_NE(norm(a), norm(R"({"function": "rnea", "outputs": [{"kind": "value"}], "build": {"optimization": "O3"}})"));
  EXPECT_NE(norm(a), norm(R"({"function": "nle", "outputs": [{"kind": "value"}]})"));
  EXPECT_NE(norm(R"({"function": "rnea", "outputs": [{"kind": "jacobian", "wrt": ["q", "v"]}]})"),
            norm(R"({"function": "rnea", "outputs": [{"kind": "jacobian", "wrt": ["v", "q"]}]})"));
  // A layout is part of the meaning, for Jacobians and Hessians alike.
  EXPECT_NE(norm(R"({"function": "rnea", "outputs": [{"kind": "hessian", "wrt": ["q"]}]})"),
            norm(R"({"function": "rnea", "outputs": [{"kind": "hessian", "wrt": ["q"], "layout": "sparse"}]})"));
  EXPECT_EQ(norm(R"({"function": "rnea", "outputs": [{"kind": "hessian", "wrt": ["q"]}]})"),
            norm(R"({"function": "rnea", "outputs": [{"kind": "hessian", "wrt": ["q"], "layout": "dense"}]})"));
  EXPECT_NE(norm(R"({"function": "rnea", "outputs": [{"kind": "jacobian", "wrt": ["q"]}]})"),
            norm(R"({"function": "rnea", "outputs": [{"kind": "jacobian", "wrt": ["q"], "layout": "sparse"}]})"));
}

struct Bad {
  const char* json;
  const char* message;  // must appear in the error
};

TEST(FunctionSpec, InvalidSpecsNameTheFieldAndValue) {
  const Bad cases[] = {
      {R"({"function": "rnea", "outputs": [)", "spec.json: not valid JSON"},
      {R"([1, 2])", "a spec is a JSON object"},
      {R"({"outputs": [{"kind": "value"}]})", "function: missing"},
      {R"({"function": "rneaa", "outputs": [{"kind": "value"}]})", "function: 'rneaa' is not a model function"},
      {R"({"function": 3, "outputs": [{"kind": "value"}]})", "function: 3 is not a string"},
      {R"({"function": "rnea"})", "outputs: missing"},
      {R"({"function": "rnea", "outputs": []})", "outputs: must be a non-empty array"},
      {R"({"function": "rnea", "outptus": [], "outputs": [{"kind": "value"}]})", "outptus: unknown field"},
      {R"({"function": "rnea", "outputs": [{"kind": "gradient"}]})", "outputs[0].kind: 'gradient' is not an output kind"},
      {R"({"function": "rnea", "outputs": [{"kind": "value"}, {"kind": "jacobian", "wrt": ["q", "tau"]}]})",
       "outputs[1].wrt[1]: 'tau' is not an input of rnea (its inputs: q, v, a)"},
      {R"({"function": "rnea", "outputs": [{"kind": "jacobian", "wrt": ["q", "q"]}]})", "outputs[0].wrt[1]: 'q' is listed twice"},
      {R"({"function": "rnea", "outputs": [{"kind": "jacobian"}]})", "outputs[0].wrt: missing"},
      {R"({"function": "rnea", "outputs": [{"kind": "jacobian", "wrt": []}]})", "outputs[0].wrt: must be a non-empty array"},
      {R"({"function": "rnea", "outputs": [{"kind": "jacobian", "wrt": ["q"], "layout": "csr"}]})",
       "outputs[0].layout: 'csr' is neither dense nor sparse"},
      {R"({"function": "rnea", "outputs": [{"kind": "hessian", "wrt": ["q"], "weights": [1, "x"]}]})",
       "outputs[0].weights[1]: \"x\" is not a number"},
      {R"({"function": "rnea", "inputs": {"v": {"fixed": [0]}}, "outputs": [{"kind": "jacobian", "wrt": ["v"]}]})",
       "outputs[0].wrt[0]: 'v' is fixed"},
      {R"({"function": "rnea", "inputs": {"tau": "variable"}, "outputs": [{"kind": "value"}]})",
       "inputs.tau: 'tau' is not an input of rnea"},
      {R"({"function": "rnea", "inputs": {"q": "constant"}, "outputs": [{"kind": "value"}]})",
       "inputs.q: \"constant\" is neither \"variable\" nor {\"fixed\": [numbers]}"},
      {R"({"function": "fk", "outputs": [{"kind": "value"}]})", "frame: missing: fk needs a frame name"},
      {R"({"function": "rnea", "frame": "tool", "outputs": [{"kind": "value"}]})", "frame: \"tool\" given, but rnea takes no frame"},
      {R"({"function": "frame_jacobian", "frame": "tool", "reference": "GLOBAL", "outputs": [{"kind": "value"}]})",
       "reference: unknown reference frame 'GLOBAL'"},
      {R"({"function": "com", "reference": "LOCAL", "outputs": [{"kind": "value"}]})", "reference: only frame_jacobian"},
      {R"({"function": "rnea", "outputs": [{"kind": "value"}], "build": {"optimization": "O4"}})",
       "build.optimization: 'O4' is not one of O0, O1, O2, O3"},
      {R"({"function": "rnea", "outputs": [{"kind": "value"}], "build": {"fast_math": "yes"}})",
       "build.fast_math: \"yes\" is not true or false"},
  };
  for (const Bad& c : cases) {
    SCOPED_TRACE(c.json);
    try {
      parseFunctionSpec(c.json, "spec.json");
      ADD_FAILURE() << "accepted";
    } catch (const SpecError& e) {
      EXPECT_NE(std::string(e.what()).find(c.message), std::string::npos) << e.what();
      EXPECT_EQ(std::string(e.what()).rfind("spec.json: ", 0), 0u) << e.what();
    }
  }
  EXPECT_THROW(loadFunctionSpec("/nonexistent/spec.json"), SpecError);
}

}  // namespace
}  // namespace robodiff
