// A generated function library's failures: each is the documented exception (the node
// limit a resource error, a failing compiler a compile error with its message, a spec
// that does not fit the model a spec error naming the field), and no library or
// description is left behind.
#include <filesystem>
#include <fstream>
#include <string>

#include <gtest/gtest.h>

#include "compiled_examples.hpp"
#include "robodiff/codegen/compiler.hpp"
#include "robodiff/functions/function_spec.hpp"
#include "robodiff/symbolic/graph.hpp"

namespace robodiff {
namespace {

namespace fs = std::filesystem;
using testing::exampleSpec;
using testing::libraryArm7;
using testing::quadruped;
using testing::TempDir;

// Nothing at `out_dir` except, possibly, an empty directory or sources.
void expectNoLibrary(const fs::path& out_dir, const std::string& name) {
  EXPECT_FALSE(fs::exists(out_dir / (name + ".so"))) << out_dir / (name + ".so");
  EXPECT_FALSE(fs::exists(out_dir / (name + ".json"))) << out_dir / (name + ".json");
}

TEST(LibraryErrors, TheNodeLimitIsAResourceErrorAndNothingIsWritten) {
  TempDir dir;
  const fs::path out = dir.path() / "out";
  LibraryOptions options;
  options.builder.node_limit = 2000;
  try {
    generateFunctionLibrary(quadruped(), exampleSpec("aba_jacobian"), out, options);
    FAIL() << "no error";
  } catch (const symbolic::GraphTooLarge& e) {
    EXPECT_EQ(e.limit(), 2000u);
    EXPECT_NE(std::string(e.what()).find("2000"), std::string::npos) << e.what();
  }
  expectNoLibrary(out, "aba");
  EXPECT_TRUE(!fs::exists(out) || fs::is_empty(out)) << "the build failed before anything was emitted";
}

TEST(LibraryErrors, AFailingCompilerIsACompileErrorWithItsMessage) {
  TempDir dir;
  const fs::path cc = dir.path() / "fake-cc";
  std::ofstream(cc) << "#!/bin/sh\necho 'fake compiler failure: boom' >&2\nexit 1\n";
  fs::permissions(cc, fs::perms::owner_all);
  const fs::path out = dir.path() / "out";
  LibraryOptions options;
  options.compiler.compiler = cc.string();
  try {
    generateFunctionLibrary(libraryArm7(), exampleSpec("crba"), out, options);
    FAIL() << "no error";
  } catch (const codegen::CompileError& e) {
    EXPECT_EQ(e.kind(), codegen::CompileError::Kind::CompilerFailed);
    const std::string what = e.what();
    EXPECT_TRUE(what.find("fake compiler failure: boom") != std::string::npos ||
                e.compilerOutput().find("fake compiler failure: boom") != std::string::npos)
        << what << "\n--- compiler output:\n"
        << e.compilerOutput();
  }
  expectNoLibrary(out, "crba");
}

TEST(LibraryErrors, SpecsThatDoNotFitTheModelAreSpecErrors) {
  TempDir dir;
  {
    SCOPED_TRACE("fixed inputs of the wrong size");
    // gravity_compensation fixes v and a to 7 zeros: a 7-joint arm, not the quadruped (nv 18).
    const fs::path out = dir.path() / "fixed";
    try {
      generateFunctionLibrary(quadruped(), exampleSpec("gravity_compensation"), out);
      FAIL() << "no error";
    } catch (const SpecError& e) {
      const std::string what = e.what();
      EXPECT_NE(what.find("inputs.v.fixed"), std::string::npos) << what;
      EXPECT_NE(what.find("18"), std::string::npos) << what;
    }
    expectNoLibrary(out, "rnea");
  }
  {
    SCOPED_TRACE("unknown frame");
    FunctionSpec spec = exampleSpec("fk");
    spec.frame = "no_such_frame";
    const fs::path out = dir.path() / "frame";
    try {
      generateFunctionLibrary(libraryArm7(), spec, out);
      FAIL() << "no error";
    } catch (const SpecError& e) {
      const std::string what = e.what();
      EXPECT_NE(what.find("no_such_frame"), std::string::npos) << what;
      EXPECT_NE(what.find("tool"), std::string::npos) << "lists the frames there are: " << what;
    }
    expectNoLibrary(out, "fk");
  }
}

}  // namespace
}  // namespace robodiff
