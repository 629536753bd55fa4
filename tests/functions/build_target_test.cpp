// A spec's build target (`"build": {"target": ...}`): the x86-64 levels a build host
// compiles for the robots of a fleet, what they normalise to, and the compiler flags.
#include <gtest/gtest.h>

#include <algorithm>

#include "robodiff/codegen/compiler.hpp"
#include "robodiff/codegen/loaded_library.hpp"
#include "robodiff/functions/evaluation.hpp"
#include "robodiff/functions/function_library.hpp"
#include "robodiff/functions/function_spec.hpp"
#include "robodiff/functions/reference.hpp"
#include "robodiff/model/urdf_loader.hpp"
#include "support/temp_dir.hpp"
#include "support/test_paths.hpp"

namespace robodiff {
namespace {

FunctionSpec rneaWithBuild(const std::string& build_json) {
  return parseFunctionSpec(R"({"function": "rnea", "outputs": [{"kind": "value"}], "build": )" + build_json + "}", "target.json");
}

std::string refusalOf(const std::string& build_json) {
  try {
    rneaWithBuild(build_json);
  } catch (const SpecError& e) {
    return e.what();
  }
  return "accepted";
}

bool hasFlag(const std::vector<std::string>& flags, const std::string& flag) {
  return std::find(flags.begin(), flags.end(), flag) != flags.end();
}

TEST(BuildTarget, ALevelIsKeptAndTurnsNativeOff) {
  const FunctionSpec s = rneaWithBuild(R"({"target": "x86-64-v3"})");
  EXPECT_EQ(s.build.target, "x86-64-v3");
  EXPECT_FALSE(s.build.march_native);
  EXPECT_NE(normalizedSpecJson(s).find(R"("target":"x86-64-v3")"), std::string::npos) << normalizedSpecJson(s);
  // The normalised JSON reads back to the same build.
  EXPECT_EQ(normalizedSpecJson(parseFunctionSpec(normalizedSpecJson(s))), normalizedSpecJson(s));
}

TEST(BuildTarget, NativeAndGenericAreTheMarchNativeForms) {
  EXPECT_EQ(normalizedSpecJson(rneaWithBuild(R"({"target": "native"})")),
            normalizedSpecJson(rneaWithBuild(R"({"march_native": true})")));
  EXPECT_EQ(normalizedSpecJson(rneaWithBuild(R"({"target": "x86-64"})")),
            normalizedSpecJson(rneaWithBuild(R"({"march_native": false})")));
  EXPECT_TRUE(rneaWithBuild(R"({"target": "native"})").build.target.empty());
  // A spec without a target keeps the JSON (and so the cache key) it had before targets.
  EXPECT_EQ(normalizedSpecJson(rneaWithBuild("{}")).find("target"), std::string::npos);
}

TEST(BuildTarget, UnknownOrContradictoryTargetsAreRefusedByName) {
  const std::string unknown = refusalOf(R"({"target": "x86-64-v9"})");
  EXPECT_NE(unknown.find("build.target"), std::string::npos) << unknown;
  EXPECT_NE(unknown.find("x86-64-v9"), std::string::npos) << unknown;
  EXPECT_NE(unknown.find("x86-64-v3"), std::string::npos) << unknown;  // the valid ones are listed
  const std::string contradiction = refusalOf(R"({"march_native": true, "target": "x86-64-v2"})");
  EXPECT_NE(contradiction.find("contradicts"), std::string::npos) << contradiction;
  EXPECT_EQ(refusalOf(R"({"march_native": false, "target": "x86-64-v2"})"), "accepted");
  EXPECT_NE(refusalOf(R"({"target": 3})").find("build.target"), std::string::npos);
}

TEST(BuildTarget, ALevelCompilesForTheLevelNotForThisCpu) {
  const auto flags = codegen::compilerFlags(compilerOptionsFor(rneaWithBuild(R"({"target": "x86-64-v3"})").build, {}));
  EXPECT_TRUE(hasFlag(flags, "-march=x86-64-v3"));
  EXPECT_TRUE(hasFlag(flags, "-mtune=generic"));
  EXPECT_FALSE(hasFlag(flags, "-march=native"));
  const auto native = codegen::compilerFlags(compilerOptionsFor(rneaWithBuild("{}").build, {}));
  EXPECT_TRUE(hasFlag(native, "-march=native"));
}

// Compiled for the lowest level (every x86-64 CPU of the last 15 years has it): the
// library's flags name the level, and it gives the double reference's CRBA.
TEST(BuildTarget, ALibraryForALevelRunsAndAgreesWithTheReference) {
  const Model arm = loadUrdfFile((testing::sourceDir() / "examples/robots/arm7.urdf").string());
  FunctionSpec spec = loadFunctionSpec((testing::sourceDir() / "examples/specs/crba.json").string());
  spec.build.optimization = "O1";
  spec.build.march_native = false;
  spec.build.target = "x86-64-v2";
  testing::TempDir dir;
  const GeneratedFunctionLibrary generated = generateFunctionLibrary(arm, spec, dir.path() / "out");
  EXPECT_TRUE(hasFlag(generated.compile.flags, "-march=x86-64-v2"));
  const codegen::LoadedLibrary library = codegen::LoadedLibrary::open(generated.library);
  const codegen::CompiledFunction f = library.function(generated.built.definition.name);
  const std::vector<Eigen::VectorXd> inputs = randomRuntimeInputs(arm, spec, 7);
  const Eigen::VectorXd compiled = evaluateBlocks(f, generated.built.definition, inputs)[0];
  const Eigen::VectorXd reference = referenceValue(arm, spec, inputs);
  ASSERT_EQ(compiled.size(), reference.size());
  EXPECT_LT((compiled - reference).cwiseAbs().maxCoeff(), 1e-12 * (1 + reference.cwiseAbs().maxCoeff()));
}

}  // namespace
}  // namespace robodiff
