// Single-knot code at most 128 bits wide (RD_SCALAR_FN in c_emitter.cpp): on AVX-512 CPUs
// gcc otherwise packs independent stores into 512-bit registers, measured 25% slower per
// call (docs/code-generation.md); the batched code keeps the full width. Checked on the
// compiled library's disassembly, against the same source with the attribute taken out.
#include <gtest/gtest.h>

#include <iostream>
#include <regex>
#include <string>

#include "codegen_fixtures.hpp"
#include "robodiff/codegen/c_emitter.hpp"
#include "robodiff/codegen/compiler.hpp"
#include "support/process.hpp"
#include "support/temp_dir.hpp"

namespace robodiff::codegen {
namespace {

using namespace testing;
using robodiff::testing::runCommand;
using robodiff::testing::TempDir;

std::filesystem::path compiled(const GeneratedLibrary& lib, const std::filesystem::path& out) {
  CompilerOptions options;
  options.compiler = "gcc";
  options.native = true;
  return compileLibrary(lib, out, options).library;
}

TEST(ScalarWidth, SingleKnotCodeStaysOff512BitRegistersAndTheBatchedChunkDoesNot) {
  if (!cpuHasFlag("avx512f")) GTEST_SKIP() << "this CPU has no AVX-512: -march=native cannot use 512-bit registers";
  if (!haveProgram("gcc") || !haveProgram("objdump")) GTEST_SKIP() << "needs gcc and objdump";
  Graph g;
  FunctionDefinition f = chainFunction(g, "fk", 12);
  CodegenOptions options;
  options.split_threshold = 1u << 30;  // one part: rd_fk_eval
  GeneratedLibrary lib = generateLibrary(g, {f}, options);
  TempDir dir;
  const std::filesystem::path with = compiled(lib, dir / "with.so");
  // The same source with the attribute taken out: what gcc does on its own.
  std::string& text = lib.sources.at(0).text;
  const std::string attribute = "__attribute__((target(\"prefer-vector-width=128\")))";
  ASSERT_NE(text.find(attribute), std::string::npos);
  text.replace(text.find(attribute), attribute.size(), "");
  const std::filesystem::path without = compiled(lib, dir / "without.so");

  const std::string eval_without = disassembly(without, "rd_fk_eval");
  ASSERT_FALSE(eval_without.empty()) << "no rd_fk_eval in " << without;
  // gcc packs it where -march=native tunes for 512-bit vectors (Sapphire Rapids and
  // later); where it tunes for 256 bits (a CPU it reports as Rocket Lake) it does not,
  // and the attribute's effect does not show, but the checks below still hold.
  if (eval_without.find("zmm") == std::string::npos)
    std::cout << "note: gcc does not pack rd_fk_eval into 512-bit registers on this CPU even without the attribute\n";
  const std::string eval_with = disassembly(with, "rd_fk_eval");
  EXPECT_EQ(eval_with.find("zmm"), std::string::npos) << eval_with;
  // The batched entry point (its chunk inlined there) keeps the full width.
  EXPECT_NE(runCommand("objdump -d --no-show-raw-insn " + with.string()).out.find("zmm"), std::string::npos);
}

// A block with up to 256 structural zeros: a memset there costs ~35 ns before anything
// else runs (gcc's inline `rep stos`), as much again as Solo-12's whole frame Jacobian, so
// the single knot stores its zeros four at a time (256 bits), never 512.
TEST(ScalarWidth, AFewHundredStructuralZerosAreStoredWithoutMemset) {
  if (!haveProgram("gcc") || !haveProgram("objdump")) GTEST_SKIP() << "needs gcc and objdump";
  Graph g;
  CodegenOptions options;
  options.split_threshold = 1u << 30;  // one part: rd_banded_eval
  GeneratedLibrary lib = generateLibrary(g, {bandedFunction(g, "banded", 15)}, options);
  TempDir dir;
  const std::filesystem::path library = compiled(lib, dir / "banded.so");
  std::string eval = disassembly(library, "rd_banded_eval");
  ASSERT_FALSE(eval.empty()) << "no rd_banded_eval in " << library;
  EXPECT_EQ(eval.find("memset"), std::string::npos) << eval;
  EXPECT_EQ(eval.find("rep stos"), std::string::npos) << eval;
  if (cpuHasFlag("avx512f")) {
    EXPECT_EQ(eval.find("zmm"), std::string::npos) << eval;
    EXPECT_NE(eval.find("ymm"), std::string::npos) << "no longer four zeros a store";
  }
}

// Four zeros a store from elements 4k of the block only, the ends of each run of zeros
// stored one by one: into a 32-byte aligned output no store is split across two cache
// lines or two pages (a page-split store cost Talos's frame Jacobian 6 ns of its 20).
TEST(ScalarWidth, FourZeroStoresStartAtMultiplesOfFour) {
  Graph g;
  CodegenOptions options;
  options.split_threshold = 1u << 30;
  const GeneratedLibrary lib = generateLibrary(g, {bandedFunction(g, "banded", 15)}, options);
  const std::string& text = lib.sources.at(0).text;
  const std::regex four(R"(RD_ZERO4\(o0 \+ (\d+)\))");
  int stores = 0;
  for (auto it = std::sregex_iterator(text.begin(), text.end(), four); it != std::sregex_iterator(); ++it) {
    ++stores;
    EXPECT_EQ(std::stoi((*it)[1]) % 4, 0) << (*it)[0];
  }
  EXPECT_GT(stores, 10);
}

}  // namespace
}  // namespace robodiff::codegen
