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

struct FunctionDefinition {
  std::string name;  // a C identifier: it names the function in the library
  std::vector<InputBlock> inputs;
  std::vector<OutputBlock> outputs;
  // Single-knot code may compute isomorphic operations two at a time (lane pairs,
  // docs/code-generation.md). The function builder turns this off for functions with
  // derivative outputs, which ran slower with pairs.
  bool lane_pairs = true;

  std::uint32_t inputCount() const;   // doubles over all input blocks
  std::uint32_t outputCount() const;  // doubles over all output blocks

  // Throws std::invalid_argument naming the problem: a name that is not a C identifier,
  // an empty or duplicate block name, a shape that does not match the values, a CSR
  // pattern that is not well formed, a node that is not in `graph`, or an Input node
  // whose index is beyond the inputs.
  void validate(const symbolic::Graph& graph) const;
};

}  // namespace robodiff::codegen
