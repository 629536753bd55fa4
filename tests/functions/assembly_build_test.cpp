// Which builds the assembly back end writes (codegenOptionsFor, CodegenOptions::assembly):
// single-knot ("batch": false) builds for this CPU at -O2 or -O3 without fast-math, by a
// driver that assembles; a twin-limbed robot's with their lane pairs. Their values equal
// the interpreter's and the reference's; every other build is C.
#include <gtest/gtest.h>

#include <filesystem>

#include "compiled_examples.hpp"
#include "robodiff/codegen/c_emitter.hpp"
#include "robodiff/codegen/compiler.hpp"
#include "robodiff/codegen/interpreter.hpp"
#include "robodiff/codegen/loaded_library.hpp"
#include "robodiff/functions/evaluation.hpp"
#include "robodiff/functions/function_library.hpp"
#include "robodiff/functions/reference.hpp"
#include "support/temp_dir.hpp"
#include "support/test_paths.hpp"

namespace robodiff {
namespace {

namespace fs = std::filesystem;
using testing::libraryArm7;
using testing::quadruped;
using testing::TempDir;

bool hostRunsAssembly() {
#if defined(__x86_64__)
  return __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma");
#else
  return false;
#endif
}

FunctionSpec valueSpec(const std::string& function, const std::string& build, const std::string& extra = "") {
  return parseFunctionSpec(R"({"function": ")" + function + R"(", )" + extra +
                               R"("outputs": [{"kind": "value"}], "build": )" + build + "}",
                           function + ".json");
}

// The library's main source as compiled: "library.s" or "library.c" (beside its parts).
std::string sourceOf(const fs::path& out_dir) {
  for (const char* name : {"library.s", "library.c"})
    if (fs::exists(out_dir / "src" / name)) return name;
  return "";
}

// Each spec's library is assembly, its values equal to the interpreter's and the
// reference's; `paired`: computed with lane pairs.
void expectAssembledAsTheReference(const Model& model, const std::vector<FunctionSpec>& specs, bool paired) {
  for (const FunctionSpec& spec : specs) {
    SCOPED_TRACE(spec.functionName());
    TempDir dir;
    const GeneratedFunctionLibrary lib = generateFunctionLibrary(model, spec, dir.path());
    EXPECT_EQ(sourceOf(dir.path()), "library.s");
    EXPECT_EQ(lib.info.lane_pairs > 0, paired);
    const codegen::LoadedLibrary loaded = codegen::LoadedLibrary::open(lib.library);
    const codegen::CompiledFunction f = loaded.function(lib.built.definition.name);
    const codegen::Interpreter interpreter(*lib.built.graph, lib.built.definition);
    const double tolerance = spec.function == ModelFunction::Aba ? 1e-10 : 1e-12;
    for (std::uint64_t seed = 1; seed <= 3; ++seed) {
      const std::vector<Eigen::VectorXd> runtime = randomRuntimeInputs(model, spec, seed);
      const Eigen::VectorXd got = evaluateBlocks(f, lib.built.definition, runtime)[0];
      const Eigen::VectorXd interpreted = evaluateBlocks(interpreter, lib.built.definition, runtime)[0];
      const Eigen::VectorXd reference = referenceValue(model, spec, completeInputs(spec, runtime));
      const double scale = 1.0 + reference.cwiseAbs().maxCoeff();
      EXPECT_LE((got - interpreted).cwiseAbs().maxCoeff(), tolerance * scale) << "seed " << seed;
      EXPECT_LE((got - reference).cwiseAbs().maxCoeff(), tolerance * scale) << "seed " << seed;
    }
  }
}

TEST(AssemblyBuild, TheArmsValueFunctionsAreAssembledAndEqualTheInterpreterAndTheReference) {
  if (!hostRunsAssembly()) GTEST_SKIP() << "the assembly back end needs x86-64 with AVX2 and FMA";
  expectAssembledAsTheReference(
      libraryArm7(),
      {valueSpec("rnea", R"({"batch": false})"), valueSpec("crba", R"({"batch": false})"),
       valueSpec("aba", R"({"batch": false, "optimization": "O3"})"),  // 2,208 operations
       valueSpec("frame_jacobian", R"({"batch": false})", R"("frame": "tool", "reference": "LOCAL_WORLD_ALIGNED", )")},
      false);
}

// The quadruped's legs mirror each other: its mass matrix's twins are computed in lane pairs.
TEST(AssemblyBuild, TheQuadrupedsMassMatrixIsAssembledWithLanePairs) {
  if (!hostRunsAssembly()) GTEST_SKIP() << "the assembly back end needs x86-64 with AVX2 and FMA";
  expectAssembledAsTheReference(quadruped(), {valueSpec("crba", R"({"batch": false})")}, true);
}

TEST(AssemblyBuild, BatchedFastMathUnoptimisedGenericAndTccBuildsAreC) {
  const Model& model = libraryArm7();
  struct Case {
    std::string build, compiler;
  };
  std::vector<Case> cases = {{R"({})", ""},
                             {R"({"batch": false, "fast_math": true})", ""},
                             {R"({"batch": false, "optimization": "O1"})", ""},
                             {R"({"batch": false, "target": "x86-64-v3"})", ""}};
  if (testing::programInPath("tcc")) cases.push_back({R"({"batch": false})", "tcc"});
  for (const Case& c : cases) {
    SCOPED_TRACE(c.build + " " + c.compiler);
    TempDir dir;
    LibraryOptions options;
    options.compiler.compiler = c.compiler;
    generateFunctionLibrary(model, valueSpec("crba", c.build), dir.path(), options);
    EXPECT_EQ(sourceOf(dir.path()), "library.c");
  }
}

TEST(AssemblyBuild, OnlyOptimisedUnbatchedBuildsForThisCpuAskForAssembly) {
  const codegen::CodegenOptions base = LibraryOptions::defaultCodegenOptions();
  BuildOptions build;
  build.batch = false;
  EXPECT_TRUE(codegenOptionsFor(build, base).assembly);
  build.optimization = "O3";
  EXPECT_TRUE(codegenOptionsFor(build, base).assembly);
  for (const char* level : {"O0", "O1"}) {
    build.optimization = level;
    EXPECT_FALSE(codegenOptionsFor(build, base).assembly) << level;
  }
  build.optimization = "O2";
  build.batch = true;
  EXPECT_FALSE(codegenOptionsFor(build, base).assembly);
  build.batch = false;
  build.fast_math = true;
  EXPECT_FALSE(codegenOptionsFor(build, base).assembly);
  build.fast_math = false;
  build.target = "x86-64-v3";
  EXPECT_FALSE(codegenOptionsFor(build, base).assembly);
  build.target.clear();
  build.march_native = false;
  EXPECT_FALSE(codegenOptionsFor(build, base).assembly);
}

}  // namespace
}  // namespace robodiff
