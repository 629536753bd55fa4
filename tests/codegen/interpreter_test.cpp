// The interpreter against Graph::evaluate, and its batched entry against the single one.
#include "robodiff/codegen/interpreter.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "codegen_fixtures.hpp"

namespace robodiff::codegen {
namespace {

using namespace testing;

void expectMatchesReference(const Graph& g, const FunctionDefinition& f, std::uint32_t seed) {
  const Interpreter interpreter(g, f);
  std::vector<double> work(interpreter.workSize());
  const auto in = randomInputs(f, 4, seed);
  for (std::uint64_t k = 0; k < 4; ++k) {
    auto out = outputBuffers(f, 1);
    interpreter.evaluate(pointers(in, f, k).data(), pointers(out, f).data(), work.data());
    const auto expected = reference(g, f, in, k);
    for (std::size_t b = 0; b < out.size(); ++b)
      for (std::size_t i = 0; i < out[b].size(); ++i)
        ASSERT_TRUE(closeRelative(out[b][i], expected[b][i]))
            << f.name << " block " << f.outputs[b].name << "[" << i << "]: " << out[b][i] << " vs " << expected[b][i];
  }
}

TEST(Interpreter, MatchesGraphEvaluateOnRandomGraphsWithEveryOp) {
  for (std::uint32_t seed = 1; seed <= 8; ++seed) {
    Graph g;
    FunctionDefinition f = randomFunction(g, "random", seed, 250);
    expectMatchesReference(g, f, seed);
  }
}

TEST(Interpreter, MatchesGraphEvaluateOnStructuredGraphs) {
  Graph g;
  expectMatchesReference(g, chainFunction(g, "fk", 7), 11);
  expectMatchesReference(g, triangularFunction(g, "tri", 6), 12);
}

TEST(Interpreter, BatchedEqualsSingle) {
  Graph g;
  FunctionDefinition f = randomFunction(g, "random", 5, 200);
  const Interpreter interpreter(g, f);
  std::vector<double> work(interpreter.workSize());
  for (std::uint64_t n : {1u, 3u, 17u}) {
    const auto in = randomInputs(f, n, 100 + static_cast<std::uint32_t>(n));
    auto batched = outputBuffers(f, n);
    interpreter.evaluateBatch(n, pointers(in, f).data(), pointers(batched, f).data(), work.data());
    for (std::uint64_t k = 0; k < n; ++k) {
      auto single = outputBuffers(f, 1);
      interpreter.evaluate(pointers(in, f, k).data(), pointers(single, f).data(), work.data());
      for (std::size_t b = 0; b < single.size(); ++b)
        for (std::size_t i = 0; i < single[b].size(); ++i)
          ASSERT_EQ(batched[b][k * single[b].size() + i], single[b][i]) << "n=" << n << " knot " << k;
    }
  }
}

TEST(Interpreter, IsCompact) {
  // A chain of 300 operations needs a handful of slots, and one instruction per
  // operation plus the loads and stores.
  Graph g;
  NodeId acc = g.input(0);
  for (int i = 0; i < 300; ++i) acc = g.unary(Op::Sin, g.binary(Op::Mul, acc, g.constant(1.0 + 0.001 * (i + 1))));
  FunctionDefinition f{"chain", {{"x", 1}}, {OutputBlock::dense("y", 1, 1, {acc})}};
  const Interpreter interpreter(g, f);
  EXPECT_EQ(interpreter.instructionCount(), 600u + 2u);
  EXPECT_LE(interpreter.workSize(), 300u + 3u + 2u);  // constants, scratch, two locals
}

// Products and sums read once are fused into their reader ((a*b)*c, (a+b)-c, ...): fewer
// instructions run, and the results stay bit for bit those of the unfused operations.
// (The lowering first makes every sum tree a left-deep chain, sum_chains.hpp, so the sums
// here are chains already: c - (a+b) would reach the interpreter as (-a - b) + c.)
TEST(Interpreter, FusesProductsAndSumsReadOnce) {
  Graph g;
  const NodeId a = g.input(0), b = g.input(1), c = g.input(2), d = g.input(3);
  const NodeId ab = g.binary(Op::Mul, a, b), cd = g.binary(Op::Add, c, d);
  const NodeId y0 = g.binary(Op::Mul, ab, c);                      // (a*b)*c
  const NodeId y1 = g.binary(Op::Sub, cd, a);                      // (c+d) - a
  const NodeId y2 = g.binary(Op::Sub, g.binary(Op::Add, a, d), b);  // (a+d) - b
  const NodeId y3 = g.binary(Op::Add, g.binary(Op::Add, b, c), a);  // (b+c) + a
  FunctionDefinition f{"fused", {{"x", 4}}, {OutputBlock::dense("y", 4, 1, {y0, y1, y2, y3})}};
  const Interpreter interpreter(g, f);
  EXPECT_EQ(interpreter.executedCount() + 4, interpreter.instructionCount());  // four fused producers
  std::vector<double> work(interpreter.workSize());
  const auto in = randomInputs(f, 1, 3);
  auto out = outputBuffers(f, 1);
  interpreter.evaluate(pointers(in, f).data(), pointers(out, f).data(), work.data());
  const double* x = in[0].data();
  const double expected[4] = {x[0] * x[1] * x[2], x[2] + x[3] - x[0], x[0] + x[3] - x[1], x[1] + x[2] + x[0]};
  for (int i = 0; i < 4; ++i) EXPECT_EQ(out[0][i], expected[i]) << i;
}

// Many independent columns (as in a Jacobian): the scheduler groups instructions of one
// opcode, so a dispatch runs many of them, and the results stay those of Graph::evaluate.
// The output block is mostly structural zeros (cleared at once) and starts out as NaN.
TEST(Interpreter, GroupsIndependentInstructionsOfOneOpcode) {
  Graph g;
  const int n = 40;
  std::vector<NodeId> values(4 * n, g.constant(0.0));
  for (int i = 0; i < n; ++i) {
    const NodeId x = g.input(i), y = g.input((i + 1) % n);
    const NodeId p = g.binary(Op::Mul, x, g.constant(1.0 + 0.01 * i));
    const NodeId q = g.binary(Op::Add, g.binary(Op::Mul, p, y), g.unary(Op::Sin, x));
    values[4 * i] = g.binary(Op::Sub, g.binary(Op::Mul, q, q), g.binary(Op::Mul, p, g.unary(Op::Cos, y)));
  }
  FunctionDefinition f{"wide", {{"x", static_cast<std::uint32_t>(n)}}, {OutputBlock::dense("y", 4 * n, 1, values)}};
  const Interpreter interpreter(g, f);
  EXPECT_LE(interpreter.groupCount() * 10, interpreter.instructionCount());
  std::vector<double> work(interpreter.workSize());
  const auto in = randomInputs(f, 1, 7);
  auto out = outputBuffers(f, 1);
  for (double& x : out[0]) x = std::nan("");
  interpreter.evaluate(pointers(in, f).data(), pointers(out, f).data(), work.data());
  const auto expected = reference(g, f, in, 0);
  for (std::size_t i = 0; i < out[0].size(); ++i)
    ASSERT_TRUE(closeRelative(out[0][i], expected[0][i])) << "[" << i << "]: " << out[0][i] << " vs " << expected[0][i];
}

TEST(Interpreter, RejectsABadDefinition) {
  Graph g;
  FunctionDefinition f{"f", {{"x", 1}}, {OutputBlock::dense("y", 1, 1, {g.input(2)})}};
  EXPECT_THROW(Interpreter(g, f), std::invalid_argument);
}

}  // namespace
}  // namespace robodiff::codegen
