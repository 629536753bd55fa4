// The prologue's output stores (a block's structural zeros, its constants) come after the
// first sin-cos kernel (storeAfterTheFirstKernel in lowering.cpp): the kernels' arguments
// are loaded before anything is stored, so no such load waits on a store that matches
// its address in the low 12 bits (4K aliasing; docs/code-generation.md). The values are
// the same.
#include <gtest/gtest.h>

#include <algorithm>
#include <string>

#include "codegen_fixtures.hpp"
#include "robodiff/codegen/c_emitter.hpp"

namespace robodiff::codegen {
namespace {

using namespace testing;

// y (20 values): sin x0 cos x1, a constant, 17 structural zeros and cos x0 + x1.
FunctionDefinition sparseWithAngles(Graph& g) {
  const NodeId x0 = g.input(0), x1 = g.input(1);
  std::vector<NodeId> y(20, g.zero());
  y[0] = g.binary(Op::Mul, g.unary(Op::Sin, x0), g.unary(Op::Cos, x1));
  y[7] = g.constant(2.5);
  y[19] = g.binary(Op::Add, g.unary(Op::Cos, x0), x1);
  return FunctionDefinition{"sparse", {{"x", 2}}, {OutputBlock::dense("y", 1, 20, y)}};
}

// The text of the single-knot entry point's body.
std::string singleKnotBody(const std::string& text) {
  const std::size_t start = text.find("rd_sparse_eval(const double* const* in");
  EXPECT_NE(start, std::string::npos) << "no single-knot entry point";
  if (start == std::string::npos) return {};
  return text.substr(start, text.find("\n}\n", start) - start);
}

TEST(StoreOrder, TheKernelsArgumentsAreLoadedBeforeAnyOutputIsStored) {
  Graph g;
  const FunctionDefinition f = sparseWithAngles(g);
  const GeneratedLibrary lib = generateLibrary(g, {f}, CodegenOptions{});
  const std::string body = singleKnotBody(lib.sources.at(0).text);
  const std::size_t kernel = body.find("rd_sincos");
  ASSERT_NE(kernel, std::string::npos) << body;
  // The first output store: four zeros, a group of four (output_groups.hpp) or one element.
  std::size_t first_store = std::string::npos;
  for (const char* store : {"RD_ZERO4(", "RD_STORE4(", "o0["}) first_store = std::min(first_store, body.find(store));
  ASSERT_NE(first_store, std::string::npos) << body;
  EXPECT_LT(kernel, first_store) << body;
  EXPECT_EQ(body.find("i0[", first_store), std::string::npos) << "an input loaded after a store:\n" << body;

  expectCompiledAsTheGraph(g, f, lib, 1e-15);
}

}  // namespace
}  // namespace robodiff::codegen
