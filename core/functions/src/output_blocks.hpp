// A built function's derivative blocks as the generated code lays them out: a
// Jacobian dense (row-major) or sparse (CSR of its structural nonzeros), a Hessian dense
// (the full symmetric matrix) or sparse (the lower triangle's nonzeros in CSR).
#pragma once

#include <string>
#include <vector>

#include "robodiff/codegen/function_definition.hpp"
#include "robodiff/symbolic/graph.hpp"

namespace robodiff::detail {

// entries: rows x cols row-major nodes of `graph`.
codegen::OutputBlock matrixBlock(const std::string& name, int rows, int cols, const std::vector<symbolic::NodeId>& entries,
                                 bool sparse);

// lower: the n (n + 1) / 2 nodes of the lower triangle, row by row.
codegen::OutputBlock hessianBlock(const std::string& name, int n, const std::vector<symbolic::NodeId>& lower, bool sparse,
                                  const symbolic::Graph& graph);

}  // namespace robodiff::detail
