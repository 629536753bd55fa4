// What a generated (or interpreted) function computes: which graph nodes are its
// outputs, in which blocks and shapes, and how its inputs are grouped.
//
// Inputs: the graph's Input nodes are numbered consecutively across the input blocks in
// order (block 0 holds inputs 0 .. size0-1, block 1 the next size1, ...).
// Outputs: each block lists one node per written double, row-major for a dense block,
// in CSR order (row by row, columns increasing) for a sparse one.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "robodiff/symbolic/graph.hpp"

namespace robodiff::codegen {

using symbolic::NodeId;

struct InputBlock {
  std::string name;
  std::uint32_t size = 0;
};

enum class OutputKind : std::uint8_t { Dense, Sparse };

struct OutputBlock {
  std::string name;
  std::uint32_t rows = 0, cols = 0;
  OutputKind kind = OutputKind::Dense;
  std::vector<std::uint32_t> row_ptr;  // sparse only: rows + 1 entries
  std::vector<std::uint32_t> col_idx;  // sparse only: one per value
  std::vector<NodeId> values;          // one node per written double

  static OutputBlock dense(std::string name, std::uint32_t rows, std::uint32_t cols, std::vector<NodeId> values);
  static OutputBlock sparse(std::string name, std::uint32_t rows, std::uint32_t cols,
                            std::vector<std::uint32_t> row_ptr, std::vector<std::uint32_t> col_idx,
                            std::vector<NodeId> values);

  std::uint32_t size() const { return static_cast<std::uint32_t>(values.size()); }
};

// Where single-knot code seeds its lane pairs (isomorphic operations computed two at a
// time, docs/code-generation.md): nowhere; at twins only (two output values whose
// expressions have the same shape throughout, anywhere in the outputs: a left leg's entry
// and the right leg's); or also at neighbouring values of one output column that match
// at the top (a value vector's entries).
enum class LanePairSeeds : std::uint8_t { None, Twins, TwinsAndColumns };

struct FunctionDefinition {
  std::string name;  // a C identifier: it names the function in the library
  std::vector<InputBlock> inputs;
  std::vector<OutputBlock> outputs;
  // The function builder seeds functions with derivative outputs at twins only: seeds
  // from a Jacobian's columns paired unrelated entries and made the code slower.
  LanePairSeeds lane_pairs = LanePairSeeds::TwinsAndColumns;

  std::uint32_t inputCount() const;   // doubles over all input blocks
  std::uint32_t outputCount() const;  // doubles over all output blocks

  // Throws std::invalid_argument naming the problem: a name that is not a C identifier,
  // an empty or duplicate block name, a shape that does not match the values, a CSR
  // pattern that is not well formed, a node that is not in `graph`, or an Input node
  // whose index is beyond the inputs.
  void validate(const symbolic::Graph& graph) const;
};

}  // namespace robodiff::codegen
