// The output order (core/codegen/src/emission_order.hpp): a function of at least
// CodegenOptions::output_order_from operations computes its values output by output,
// each right after what it reads. Traced stage by stage over 64 columns, every first-stage
// value crosses the parts in the trace's order; in the output order almost none do. The
// values are the same either way.
#include <gtest/gtest.h>

#include "codegen_fixtures.hpp"
#include "robodiff/codegen/c_emitter.hpp"
#include "robodiff/codegen/compiler.hpp"
#include "robodiff/codegen/loaded_library.hpp"
#include "support/temp_dir.hpp"

namespace robodiff::codegen {
namespace {

using namespace testing;
using robodiff::testing::TempDir;

constexpr std::uint32_t kColumns = 64;

// Stage by stage, as an algorithm traces: a_c = x_c x_c+1 + x_c for every c, then
// b_c = a_c a_c - x_c, then y_c = b_c a_c; y is one row of 64 columns.
FunctionDefinition staged(Graph& g) {
  std::vector<NodeId> x, a, y;
  for (std::uint32_t c = 0; c <= kColumns; ++c) x.push_back(g.input(c));
  for (std::uint32_t c = 0; c < kColumns; ++c) a.push_back(g.binary(Op::Add, g.binary(Op::Mul, x[c], x[c + 1]), x[c]));
  std::vector<NodeId> b;
  for (std::uint32_t c = 0; c < kColumns; ++c) b.push_back(g.binary(Op::Sub, g.binary(Op::Mul, a[c], a[c]), x[c]));
  for (std::uint32_t c = 0; c < kColumns; ++c) y.push_back(g.binary(Op::Mul, b[c], a[c]));
  return FunctionDefinition{"staged", {{"x", kColumns + 1}}, {OutputBlock::dense("y", 1, kColumns, y)}};
}

GeneratedLibrary generated(const Graph& g, const FunctionDefinition& f, std::uint32_t output_order_from) {
  CodegenOptions options;
  options.split_threshold = 40;  // parts of 40 operations: values cross them through the work buffer
  options.output_order_from = output_order_from;
  return generateLibrary(g, {f}, options);
}

TEST(EmissionOrder, OutputByOutputFewValuesCrossThePartsAndTheValuesAreTheSame) {
  Graph g;
  const FunctionDefinition f = staged(g);
  const GeneratedLibrary trace_order = generated(g, f, 0), output_order = generated(g, f, 1);
  const GeneratedFunctionInfo& t = trace_order.functions.at(0);
  const GeneratedFunctionInfo& o = output_order.functions.at(0);
  std::cout << "work doubles between parts: trace order " << t.transfer_slots << ", output order "
            << o.transfer_slots << "\n";
  EXPECT_EQ(t.operations, o.operations);
  EXPECT_GE(t.transfer_slots, kColumns / 2);  // the a_c wait for the second stage
  EXPECT_LE(o.transfer_slots, 4u);
  // Below the threshold the trace's order stays.
  EXPECT_EQ(generated(g, f, t.operations + 1).functions.at(0).transfer_slots, t.transfer_slots);
  EXPECT_EQ(generated(g, f, t.operations).functions.at(0).transfer_slots, o.transfer_slots);

  TempDir dir;
  const LoadedLibrary a = LoadedLibrary::open(compileLibrary(trace_order, dir / "trace.so").library);
  const LoadedLibrary b = LoadedLibrary::open(compileLibrary(output_order, dir / "output.so").library);
  const CompiledFunction& fa = a.function("staged");
  const CompiledFunction& fb = b.function("staged");
  std::vector<double> work(std::max(fa.workSize(), fb.workSize()) + 1);
  for (std::uint32_t seed = 1; seed <= 5; ++seed) {
    const auto in = randomInputs(f, 1, seed);
    const auto expected = reference(g, f, in, 0);
    auto from_a = outputBuffers(f, 1), from_b = outputBuffers(f, 1);
    fa.evaluate(pointers(in, f).data(), pointers(from_a, f).data(), work.data());
    fb.evaluate(pointers(in, f).data(), pointers(from_b, f).data(), work.data());
    for (std::uint32_t c = 0; c < kColumns; ++c) {
      EXPECT_NEAR(from_a[0][c], expected[0][c], 1e-14) << seed << " " << c;
      EXPECT_EQ(from_b[0][c], from_a[0][c]) << seed << " " << c;
    }
  }
}

}  // namespace
}  // namespace robodiff::codegen
