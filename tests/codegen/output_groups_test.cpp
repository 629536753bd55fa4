// Outputs in 32-byte groups (output_groups.hpp): a single-knot function bound by its
// stores writes each group of four elements that would take two stores or more with one
// RD_STORE4 (its zeros included); a function bound by its arithmetic, or cut into parts,
// keeps its stores as they were. The compiled values are the graph's, every element
// written (the output starts as NaN).
#include <gtest/gtest.h>

#include <regex>
#include <set>
#include <string>

#include "codegen_fixtures.hpp"
#include "robodiff/codegen/c_emitter.hpp"

namespace robodiff::codegen {
namespace {

using namespace testing;

// A frame-Jacobian-like block (6 x 10, row-major): a few values from two angles, the same
// value in several places, a constant, and zeros; 12 values of 60 from a handful of
// operations, so its stores outnumber its operations.
FunctionDefinition storeBound(Graph& g) {
  const NodeId x0 = g.input(0), x1 = g.input(1);
  const NodeId s = g.unary(Op::Sin, x0), c = g.unary(Op::Cos, x1);
  const NodeId p = g.binary(Op::Mul, s, c), q = g.binary(Op::Add, s, x1);
  std::vector<NodeId> y(60, g.zero());
  for (int row = 0; row < 6; ++row) {
    y[row * 10 + 0] = row % 2 ? p : q;
    y[row * 10 + 1] = row % 3 ? s : c;
    y[row * 10 + 8] = p;
  }
  y[5] = g.constant(-1.5);
  y[59] = g.unary(Op::Neg, x0);
  return FunctionDefinition{"grouped", {{"x", 2}}, {OutputBlock::dense("J", 6, 10, y)}};
}

// The text of the single-knot entry point (the range-checked body where there is one).
std::string singleKnotText(const GeneratedLibrary& lib, const std::string& name) {
  const std::string& text = lib.sources.at(0).text;
  const std::size_t in_range = text.find("rd_" + name + "_in_range(const double* const* in");
  const std::size_t start = in_range != std::string::npos ? in_range : text.find("rd_" + name + "_eval(const double* const* in");
  EXPECT_NE(start, std::string::npos) << "no single-knot body";
  if (start == std::string::npos) return {};
  return text.substr(start, text.find("\n}\n", start) - start);
}

std::set<std::uint32_t> groupStarts(const std::string& body) {
  std::set<std::uint32_t> starts;
  const std::regex store4(R"(RD_STORE4\(o0 \+ (\d+),)");
  for (auto it = std::sregex_iterator(body.begin(), body.end(), store4); it != std::sregex_iterator(); ++it)
    starts.insert(static_cast<std::uint32_t>(std::stoi((*it)[1])));
  return starts;
}

TEST(OutputGroups, AStoreBoundFunctionWritesEachGroupOfTwoStoresOrMoreWithOne) {
  Graph g;
  const FunctionDefinition f = storeBound(g);
  const GeneratedLibrary lib = generateLibrary(g, {f}, CodegenOptions{});
  const std::string body = singleKnotText(lib, "grouped");
  // Per group of four: its values and whether it holds a zero; it takes a group store
  // where that saves a store (two values, or a value and zeros).
  std::set<std::uint32_t> want;
  for (std::uint32_t start = 0; start < 60; start += 4) {
    int values = 0, zeros = 0;
    for (std::uint32_t e = start; e < start + 4; ++e) {
      const symbolic::Node& n = g.node(f.outputs[0].values[e]);
      (n.op == Op::Constant && n.value == 0.0 ? zeros : values) += 1;
    }
    if (values >= 2 || (values == 1 && zeros > 0)) want.insert(start);
  }
  ASSERT_GE(want.size(), 10u);
  EXPECT_EQ(groupStarts(body), want) << body;
  EXPECT_EQ(body.find("o0["), std::string::npos) << "an element stored alone:\n" << body;
  // The all-zero groups keep their four-zero store.
  EXPECT_EQ(countOf(body, "RD_ZERO4("), 15u - want.size()) << body;
  expectCompiledAsTheGraph(g, f, lib, 1e-15);
}

TEST(OutputGroups, AFunctionBoundByItsArithmeticKeepsItsStores) {
  Graph g;
  const FunctionDefinition f = randomFunction(g, "arith", 7, 400);
  const GeneratedLibrary lib = generateLibrary(g, {f}, CodegenOptions{});
  ASSERT_GT(lib.functions.at(0).operations, 4 * f.outputs[0].size()) << "not bound by its arithmetic";
  EXPECT_EQ(lib.sources.at(0).text.find("RD_STORE4(o"), std::string::npos);
}

TEST(OutputGroups, AFunctionInPartsKeepsItsStores) {
  Graph g;
  const FunctionDefinition f = storeBound(g);
  CodegenOptions split;
  split.split_threshold = 2;  // a part per two operations
  const GeneratedLibrary lib = generateLibrary(g, {f}, split);
  ASSERT_GT(lib.functions.at(0).parts, 1u);
  for (const SourceFile& source : lib.sources) EXPECT_EQ(source.text.find("RD_STORE4(o"), std::string::npos) << source.path;
  expectCompiledAsTheGraph(g, f, lib, 1e-15);
}

}  // namespace
}  // namespace robodiff::codegen
