// Sparsity patterns of derivative matrices in compressed sparse row form, as generated
// code reports them (CppADCodeGen-style self-description) and sparse solvers take them.
#pragma once

#include <cstdint>
#include <vector>

#include "robodiff/symbolic/graph.hpp"

namespace robodiff::symbolic {

struct SparsityPattern {
  int rows = 0, cols = 0;
  std::vector<int> row_ptr;  // rows + 1 entries; row r holds col_idx[row_ptr[r] .. row_ptr[r+1])
  std::vector<int> col_idx;  // ascending within each row

  int nnz() const { return row_ptr.empty() ? 0 : row_ptr.back(); }
  bool contains(int row, int col) const;
  bool operator==(const SparsityPattern& o) const = default;
};

// The pattern of a dense row-major matrix of nodes: entries that are not the constant 0.
SparsityPattern patternOfNodes(int rows, int cols, const std::vector<NodeId>& entries);

// Which outputs depend on which inputs (input indices `wrt`), by propagating dependency
// bit sets through the graph: the structural pattern of d outputs / d wrt before any
// derivative is built. A superset of the derivative's pattern (a derivative can vanish
// where a dependency exists, e.g. through selectPositive's condition).
SparsityPattern dependencyPattern(const Graph& graph, const std::vector<NodeId>& outputs,
                                  const std::vector<std::uint32_t>& wrt);

}  // namespace robodiff::symbolic
