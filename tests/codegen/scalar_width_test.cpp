// Single-knot code at most 128 bits wide (RD_SCALAR_FN, or the file's target, in c_prologue.cpp): on AVX-512 CPUs
// gcc otherwise packs independent stores into 512-bit registers, measured 25% slower per
// call (docs/code-generation.md); the batched code keeps the full width. Checked on the
// compiled library's disassembly, against the same source with the attribute taken out.
#include <gtest/gtest.h>

#include <iostream>
#include <regex>
#include <set>
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

// Why a width check cannot run here; empty when it can.
std::string whyNoWidthCheck() {
  if (!cpuHasFlag("avx512f")) return "this CPU has no AVX-512: -march=native cannot use 512-bit registers";
  if (!haveProgram("gcc") || !haveProgram("objdump")) return "needs gcc and objdump";
  return "";
}

// A 12-joint chain's forward kinematics in one part (rd_fk_eval), batched `batch_width`
// knots at a time (1: no batched code).
GeneratedLibrary chainLibrary(Graph& g, std::uint32_t batch_width) {
  CodegenOptions options;
  options.split_threshold = 1u << 30;
  options.batch_width = batch_width;
  return generateLibrary(g, {chainFunction(g, "fk", 12)}, options);
}

TEST(ScalarWidth, SingleKnotCodeStaysOff512BitRegistersAndTheBatchedChunkDoesNot) {
  if (const std::string why = whyNoWidthCheck(); !why.empty()) GTEST_SKIP() << why;
  Graph g;
  GeneratedLibrary lib = chainLibrary(g, 0);  // the batch width the target chooses
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

// A library without batched code ("batch": false) takes the preference once, at the top of
// the file, for every function: one target, so gcc sets up its register tables once
// instead of twice. No function of it uses 512-bit registers.
TEST(ScalarWidth, ALibraryWithoutBatchedCodeIsOneTargetAtMost128BitsWide) {
  if (const std::string why = whyNoWidthCheck(); !why.empty()) GTEST_SKIP() << why;
  Graph g;
  GeneratedLibrary lib = chainLibrary(g, 1);  // no batched chunk: eval_batch loops over eval
  std::string& text = lib.sources.at(0).text;
  EXPECT_EQ(text.find("__attribute__((target("), std::string::npos) << "a second target in the file";
  const std::string pragma = "#pragma GCC target(\"prefer-vector-width=128\")";
  ASSERT_NE(text.find(pragma), std::string::npos);
  EXPECT_LT(text.find(pragma), text.find("#include")) << "it must come before every function, the headers' too";
  TempDir dir;
  const std::filesystem::path with = compiled(lib, dir / "with.so");
  EXPECT_EQ(runCommand("objdump -d --no-show-raw-insn " + with.string()).out.find("zmm"), std::string::npos);
  text.replace(text.find(pragma), pragma.size(), "");
  const std::filesystem::path without = compiled(lib, dir / "without.so");
  if (disassembly(without, "rd_fk_eval").find("zmm") == std::string::npos)
    std::cout << "note: gcc does not pack rd_fk_eval into 512-bit registers on this CPU even without the pragma\n";
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

// Every group of four (from element 4k) holding a zero is cleared by one store, its other
// elements written after it, or stored whole with them (a frame Jacobian's zeros are scattered: Talos's took 58 stores
// and now 48, 15.3 -> 13.3 ns); only a tail shorter than four is cleared one by one. The
// values these stores overwrite are checked by CompiledFunctionTest (the same function).
TEST(ScalarWidth, EveryGroupOfFourWithAZeroIsClearedByOneStore) {
  Graph g;
  CodegenOptions options;
  options.split_threshold = 1u << 30;
  const FunctionDefinition f = bandedFunction(g, "banded", 15);
  const GeneratedLibrary lib = generateLibrary(g, {f}, options);
  const std::string& text = lib.sources.at(0).text;
  const std::uint32_t size = f.outputs[0].size();
  std::set<std::uint32_t> groups_with_zeros, tail_zeros;
  for (std::uint32_t k = 0; k < size; ++k) {
    const symbolic::Node& n = g.node(f.outputs[0].values[k]);
    if (n.op != Op::Constant || n.value != 0.0 || std::signbit(n.value)) continue;
    if (k / 4 * 4 + 4 <= size) groups_with_zeros.insert(k / 4 * 4);
    else tail_zeros.insert(k);
  }
  ASSERT_FALSE(tail_zeros.empty()) << "the banded block no longer ends in a short group";
  // Cleared by a four-zero store, or stored whole with its values (output_groups.hpp).
  std::set<std::uint32_t> cleared;
  const std::regex four(R"(RD_(?:ZERO4|STORE4)\(o0 \+ (\d+)[,)])");
  for (auto it = std::sregex_iterator(text.begin(), text.end(), four); it != std::sregex_iterator(); ++it)
    cleared.insert(static_cast<std::uint32_t>(std::stoi((*it)[1])));
  EXPECT_EQ(cleared, groups_with_zeros);
  std::set<std::uint32_t> single;
  const std::regex one(R"(o0\[(\d+)\] = 0\.0;)");
  for (auto it = std::sregex_iterator(text.begin(), text.end(), one); it != std::sregex_iterator(); ++it)
    single.insert(static_cast<std::uint32_t>(std::stoi((*it)[1])));
  EXPECT_EQ(single, tail_zeros);
}

}  // namespace
}  // namespace robodiff::codegen
