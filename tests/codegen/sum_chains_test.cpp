// Sums as chains (core/codegen/src/sum_chains.hpp): a sum tree of products off the
// critical path is generated as one running sum, so gcc fuses every product but the
// first into a multiply-add; the values stay those of the tree up to rounding, and no
// operation is added.
#include <gtest/gtest.h>

#include "codegen_fixtures.hpp"
#include "robodiff/codegen/c_emitter.hpp"
#include "robodiff/codegen/compiler.hpp"
#include "robodiff/codegen/interpreter.hpp"
#include "robodiff/codegen/loaded_library.hpp"
#include "robodiff/symbolic/cone.hpp"
#include "support/temp_dir.hpp"

namespace robodiff::codegen {
namespace {

using namespace testing;
using robodiff::testing::TempDir;

// y0 = (x0 x1 + x2 x3) + (x4 x5 + x6 x7), y1 = x8 - (x0 x4 - (x9 + x1 x5)) + s, where s =
// x2 + x3 is also an output (read twice: it stays one value, a term of y1's chain).
FunctionDefinition sumTrees(Graph& g) {
  NodeId x[10];
  for (std::uint32_t i = 0; i < 10; ++i) x[i] = g.input(i);
  auto mul = [&](NodeId a, NodeId b) { return g.binary(Op::Mul, a, b); };
  auto add = [&](NodeId a, NodeId b) { return g.binary(Op::Add, a, b); };
  auto sub = [&](NodeId a, NodeId b) { return g.binary(Op::Sub, a, b); };
  const NodeId y0 = add(add(mul(x[0], x[1]), mul(x[2], x[3])), add(mul(x[4], x[5]), mul(x[6], x[7])));
  const NodeId s = add(x[2], x[3]);
  const NodeId y1 = add(sub(x[8], sub(mul(x[0], x[4]), add(x[9], mul(x[1], x[5])))), s);
  return FunctionDefinition{"sums", {{"x", 10}}, {OutputBlock::dense("y", 3, 1, {y0, y1, s})}};
}

std::filesystem::path compiledWithGcc(const GeneratedLibrary& lib, const std::filesystem::path& out) {
  CompilerOptions options;
  options.compiler = "gcc";
  options.native = true;
  return compileLibrary(lib, out, options).library;
}

// The disassembly of y0 = (x0 x1 + x2 x3) + (x4 x5 + x6 x7) compiled by gcc -march=native,
// alone or beside a longer computation (ten divisions in a row, another output).
std::string sumOfFourProducts(bool beside_a_longer_path) {
  Graph g;
  FunctionDefinition f = sumTrees(g);
  std::vector<NodeId> values{f.outputs[0].values[0]};
  if (beside_a_longer_path) {
    NodeId q = g.input(9);
    for (int i = 0; i < 10; ++i) q = g.binary(Op::Div, q, g.input(8));
    values.push_back(q);
  }
  f.outputs[0] = OutputBlock::dense("y", static_cast<std::uint32_t>(values.size()), 1, values);
  CodegenOptions options;
  options.split_threshold = 1u << 30;  // one part: rd_sums_eval
  TempDir dir;
  return disassembly(compiledWithGcc(generateLibrary(g, {f}, options), dir / "sums.so"), "rd_sums_eval");
}

TEST(SumChains, ASumOfFourProductsOffTheCriticalPathIsOneMultiplyAndThreeFusedAdds) {
  if (!cpuHasFlag("fma")) GTEST_SKIP() << "this CPU has no FMA: nothing to fuse";
  if (!haveProgram("gcc") || !haveProgram("objdump")) GTEST_SKIP() << "needs gcc and objdump";
  const std::string eval = sumOfFourProducts(true);
  ASSERT_FALSE(eval.empty());
  // As a tree: two multiplies, two fused adds and an add joining the two sums.
  EXPECT_EQ(countOf(eval, "vmulsd"), 1u) << eval;
  EXPECT_EQ(countOf(eval, "vaddsd"), 0u) << eval;
  EXPECT_EQ(countOf(eval, "vfmadd"), 3u) << eval;
}

// A chain is longer than a tree: where the sum is the function's critical path (a small
// serial algorithm's, say), it stays a tree.
TEST(SumChains, ASumOnTheCriticalPathStaysATree) {
  if (!cpuHasFlag("fma")) GTEST_SKIP() << "this CPU has no FMA: nothing to fuse";
  if (!haveProgram("gcc") || !haveProgram("objdump")) GTEST_SKIP() << "needs gcc and objdump";
  const std::string eval = sumOfFourProducts(false);
  ASSERT_FALSE(eval.empty());
  EXPECT_EQ(countOf(eval, "vmulsd"), 2u) << eval;
  EXPECT_EQ(countOf(eval, "vaddsd"), 1u) << eval;
  EXPECT_EQ(countOf(eval, "vfmadd"), 2u) << eval;
}

// y = ((L1 x0 - L2 x1) + x2 x3) + 0.5 with L1 and L2 at the end of a row of divisions:
// the terms ready first are summed first, 0.5 + x2 x3 in one multiply-add while the
// divisions run, and each late product joins in a multiply-add of its own. In the
// tree's order the late products were subtracted first and the constant added last.
TEST(SumChains, LateTermsJoinTheChainLast) {
  if (!cpuHasFlag("fma")) GTEST_SKIP() << "this CPU has no FMA: nothing to fuse";
  if (!haveProgram("gcc") || !haveProgram("objdump")) GTEST_SKIP() << "needs gcc and objdump";
  Graph g;
  NodeId x[7];
  for (std::uint32_t i = 0; i < 7; ++i) x[i] = g.input(i);
  auto late = [&](NodeId a) {
    for (int k = 0; k < 4; ++k) a = g.binary(Op::Div, a, x[5]);
    return a;
  };
  const NodeId l1 = g.binary(Op::Mul, late(x[4]), x[0]), l2 = g.binary(Op::Mul, late(x[6]), x[1]);
  const NodeId y = g.binary(Op::Add, g.binary(Op::Add, g.binary(Op::Sub, l1, l2), g.binary(Op::Mul, x[2], x[3])),
                            g.constant(0.5));
  const FunctionDefinition f{"sums", {{"x", 7}}, {OutputBlock::dense("y", 1, 1, {y})}};
  TempDir dir;
  const std::string eval = disassembly(compiledWithGcc(generateLibrary(g, {f}), dir / "late.so"), "rd_sums_eval");
  ASSERT_FALSE(eval.empty());
  EXPECT_EQ(countOf(eval, "vaddsd"), 0u) << eval;
  EXPECT_EQ(countOf(eval, "vmulsd"), 0u) << eval;
  EXPECT_EQ(countOf(eval, "vfmadd") + countOf(eval, "vfnmadd") + countOf(eval, "vfmsub") + countOf(eval, "vfnmsub"),
            3u)
      << eval;
  const LoadedLibrary library = LoadedLibrary::open(dir / "late.so");
  std::vector<double> work(library.function("sums").workSize() + 1);
  for (std::uint32_t seed = 1; seed <= 10; ++seed) {
    auto in = randomInputs(f, 1, seed);
    in[0][5] = 1.5 + in[0][5] * 0.25;  // divisions by 1.25 to 1.75
    const auto expected = reference(g, f, in, 0);
    auto out = outputBuffers(f, 1);
    library.function("sums").evaluate(pointers(in, f).data(), pointers(out, f).data(), work.data());
    EXPECT_NEAR(out[0][0], expected[0][0], 1e-14) << seed;
  }
}

TEST(SumChains, ChainsKeepTheValuesAndTheOperationCount) {
  Graph g;
  const FunctionDefinition f = sumTrees(g);
  const GeneratedLibrary lib = generateLibrary(g, {f});
  std::vector<NodeId> outputs = f.outputs[0].values;
  // Chaining reorders additions, it adds none (a chain that starts from a subtracted
  // term reads it negated, as every operand can be).
  EXPECT_EQ(lib.functions.at(0).operations, symbolic::coneSize(g, outputs).operations);

  TempDir dir;
  const LoadedLibrary library = LoadedLibrary::open(compileLibrary(lib, dir / "sums.so").library);
  const CompiledFunction compiled = library.function("sums");
  const Interpreter interpreter(g, f);
  std::vector<double> work(std::max(compiled.workSize(), interpreter.workSize()) + 1);
  for (std::uint32_t seed = 1; seed <= 20; ++seed) {
    const auto in = randomInputs(f, 1, seed);
    const auto expected = reference(g, f, in, 0);  // Graph::evaluate: the tree as traced
    auto from_c = outputBuffers(f, 1), from_interpreter = outputBuffers(f, 1);
    compiled.evaluate(pointers(in, f).data(), pointers(from_c, f).data(), work.data());
    interpreter.evaluate(pointers(in, f).data(), pointers(from_interpreter, f).data(), work.data());
    for (std::size_t i = 0; i < 3; ++i) {
      // Inputs in [-1, 1]: the terms are at most 1, so rounding moves a sum by ~1e-16.
      EXPECT_NEAR(from_c[0][i], expected[0][i], 1e-14) << seed << " " << i;
      EXPECT_NEAR(from_interpreter[0][i], expected[0][i], 1e-14) << seed << " " << i;
    }
    EXPECT_EQ(from_c[0][2], expected[0][2]);  // s = x2 + x3: one addition, nothing to reorder
  }
}

}  // namespace
}  // namespace robodiff::codegen
