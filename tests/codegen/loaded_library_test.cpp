// The loader: descriptors checked before anything is called, clear refusals, unloading.
#include "robodiff/codegen/loaded_library.hpp"

#include <dlfcn.h>

#include <fstream>
#include <optional>

#include <gtest/gtest.h>

#include "codegen_fixtures.hpp"
#include "robodiff/codegen/compiler.hpp"

namespace robodiff::codegen {
namespace {

using namespace testing;
namespace fs = std::filesystem;

// A library written by hand against abi.h; the placeholders let a test break it.
std::string handWritten(const std::string& abi_version = "ROBODIFF_ABI_VERSION", const std::string& nnz = "1u",
                        const std::string& eval = "twice") {
  std::string s = R"(#include <stdlib.h>
#include "robodiff/codegen/abi.h"
static void twice(const double* const* in, double* const* out, double* w) { (void)w; out[0][0] = 2.0 * in[0][0]; }
static void twice_batch(uint64_t n, const double* const* in, double* const* out, double* w) {
  (void)w;
  for (uint64_t k = 0; k < n; ++k) out[0][k] = 2.0 * in[0][k];
}
static void explode(const double* const* in, double* const* out, double* w) { (void)in; (void)out; (void)w; abort(); }
static const robodiff_input_desc inputs[] = {{"x", 1u}};
static const robodiff_output_desc outputs[] = {{"y", 1u, 1u, ROBODIFF_OUTPUT_DENSE, @NNZ@, NULL, NULL}};
static const robodiff_function_desc functions[] = {{"twice", 1u, inputs, 1u, outputs, 0u, 0u, 1u, @EVAL@, twice_batch}};
const robodiff_library_desc robodiff_library = {@ABI@, sizeof(robodiff_library_desc), "hand-written 1.0", 1u, functions};
)";
  auto put = [&](const std::string& key, const std::string& value) { s.replace(s.find(key), key.size(), value); };
  put("@NNZ@", nnz);
  put("@EVAL@", eval);
  put("@ABI@", abi_version);
  return s;
}

fs::path compile(const TempDir& dir, const std::string& name, const std::string& source) {
  GeneratedLibrary lib;
  lib.sources.push_back({"lib.c", source});
  lib.headers.push_back({"robodiff/codegen/abi.h", abiHeaderText()});
  CompilerOptions o;
  o.compiler = "gcc";
  o.optimization = OptimizationLevel::O0;
  return compileLibrary(lib, dir / name, o).library;
}

std::string loadError(const fs::path& path, const FunctionExpectations* expected = nullptr) {
  try {
    LoadedLibrary lib = LoadedLibrary::open(path);
    if (expected) lib.function(*expected);
  } catch (const LoadError& e) {
    return e.what();
  }
  return {};
}

TEST(LoadedLibrary, LoadsAHandWrittenLibraryAndCallsIt) {
  TempDir dir;
  const fs::path path = compile(dir, "good.so", handWritten());
  LoadedLibrary lib = LoadedLibrary::open(path);
  EXPECT_EQ(lib.generatorVersion(), "hand-written 1.0");
  EXPECT_EQ(lib.functionNames(), std::vector<std::string>{"twice"});
  FunctionExpectations expected;
  expected.name = "twice";
  expected.input_sizes = std::vector<std::uint32_t>{1};
  expected.output_sizes = std::vector<std::uint32_t>{1};
  const CompiledFunction f = lib.function(expected);
  const double x = 21.0;
  double y = 0.0;
  const double* in[] = {&x};
  double* out[] = {&y};
  f.evaluate(in, out, nullptr);
  EXPECT_EQ(y, 42.0);
}

TEST(LoadedLibrary, RefusesAnotherAbiVersionBeforeCallingAnything) {
  TempDir dir;
  // Its entry point would abort the test: the loader must not get that far.
  const fs::path path = compile(dir, "old.so", handWritten("999u", "1u", "explode"));
  const std::string error = loadError(path);
  EXPECT_NE(error.find("ABI version 999"), std::string::npos) << error;
  EXPECT_NE(error.find("version " + std::to_string(ROBODIFF_ABI_VERSION)), std::string::npos) << error;
  EXPECT_NE(error.find("old.so"), std::string::npos) << error;
}

TEST(LoadedLibrary, RefusesAnInconsistentDescriptor) {
  TempDir dir;
  const std::string error = loadError(compile(dir, "bad.so", handWritten("ROBODIFF_ABI_VERSION", "7u")));
  EXPECT_NE(error.find("nnz != rows * cols"), std::string::npos) << error;
  const std::string no_entry = loadError(compile(dir, "null.so", handWritten("ROBODIFF_ABI_VERSION", "1u", "NULL")));
  EXPECT_NE(no_entry.find("no entry point"), std::string::npos) << no_entry;
}

// The 3-input triangular test function "tri", compiled by gcc -O0 into dir/tri.so.
fs::path compileTriangular(const TempDir& dir) {
  Graph g;
  FunctionDefinition f = triangularFunction(g, "tri", 3);
  CompilerOptions o;
  o.compiler = "gcc";
  o.optimization = OptimizationLevel::O0;
  return compileLibrary(generateLibrary(g, {f}), dir / "tri.so", o).library;
}

TEST(LoadedLibrary, RefusesAWrongFunctionNameOrShape) {
  TempDir dir;
  const fs::path path = compileTriangular(dir);

  FunctionExpectations wrong_name;
  wrong_name.name = "rnea";
  std::string error = loadError(path, &wrong_name);
  EXPECT_NE(error.find("no function 'rnea'"), std::string::npos) << error;
  EXPECT_NE(error.find("'tri'"), std::string::npos) << error;

  FunctionExpectations wrong_inputs;
  wrong_inputs.name = "tri";
  wrong_inputs.input_sizes = std::vector<std::uint32_t>{4};
  error = loadError(path, &wrong_inputs);
  EXPECT_NE(error.find("input blocks of sizes [3], expected [4]"), std::string::npos) << error;

  FunctionExpectations wrong_outputs;
  wrong_outputs.name = "tri";
  wrong_outputs.output_sizes = std::vector<std::uint32_t>{9, 3};
  error = loadError(path, &wrong_outputs);
  EXPECT_NE(error.find("output blocks of sizes [6, 3], expected [9, 3]"), std::string::npos) << error;
}

TEST(LoadedLibrary, RefusesWhatIsNotARobodiffLibrary) {
  TempDir dir;
  std::string error = loadError(compile(dir, "plain.so", "int robodiff_something_else = 1;\n"));
  EXPECT_NE(error.find("does not export 'robodiff_library'"), std::string::npos) << error;
  std::ofstream(dir / "text.so") << "not an ELF file";
  error = loadError(dir / "text.so");
  EXPECT_NE(error.find("cannot load"), std::string::npos) << error;
  error = loadError(dir / "missing.so");
  EXPECT_NE(error.find("cannot load"), std::string::npos) << error;
}

TEST(LoadedLibrary, DescribesAGeneratedFunction) {
  Graph g;
  const FunctionDefinition f = triangularFunction(g, "tri", 3);  // what the library must describe
  TempDir dir;
  LoadedLibrary lib = LoadedLibrary::open(compileTriangular(dir));
  EXPECT_EQ(lib.generatorVersion(), kGeneratorVersion);
  EXPECT_EQ(lib.descriptor().abi_version, ROBODIFF_ABI_VERSION);
  const robodiff_function_desc& d = lib.function("tri").descriptor();
  ASSERT_EQ(d.n_inputs, 1u);
  EXPECT_STREQ(d.inputs[0].name, "q");
  EXPECT_EQ(d.inputs[0].size, 3u);
  ASSERT_EQ(d.n_outputs, 2u);
  const robodiff_output_desc& J = d.outputs[0];
  EXPECT_STREQ(J.name, "J");
  EXPECT_EQ(J.kind, ROBODIFF_OUTPUT_SPARSE);
  EXPECT_EQ(J.nnz, 6u);
  EXPECT_EQ(std::vector<std::uint32_t>(J.row_ptr, J.row_ptr + 4), f.outputs[0].row_ptr);
  EXPECT_EQ(std::vector<std::uint32_t>(J.col_idx, J.col_idx + 6), f.outputs[0].col_idx);
  EXPECT_EQ(d.outputs[1].kind, ROBODIFF_OUTPUT_DENSE);
  EXPECT_EQ(d.outputs[1].rows, 3u);
  EXPECT_EQ(d.outputs[1].row_ptr, nullptr);
}

TEST(LoadedLibrary, UnloadsWhenTheLastUserIsGone) {
  TempDir dir;
  const fs::path path = compile(dir, "unload.so", handWritten());
  auto loaded = [&] {
    void* h = dlopen(path.c_str(), RTLD_NOW | RTLD_NOLOAD);
    if (h) dlclose(h);
    return h != nullptr;
  };
  std::optional<CompiledFunction> f;
  {
    LoadedLibrary lib = LoadedLibrary::open(path);
    EXPECT_TRUE(loaded());
    f = lib.function("twice");
  }
  EXPECT_TRUE(loaded()) << "a function keeps its library loaded";
  f.reset();
  EXPECT_FALSE(loaded());
}

}  // namespace
}  // namespace robodiff::codegen
