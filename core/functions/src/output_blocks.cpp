#include "output_blocks.hpp"

#include "robodiff/symbolic/sparsity.hpp"

namespace robodiff::detail {

using symbolic::NodeId;

codegen::OutputBlock matrixBlock(const std::string& name, int rows, int cols, const std::vector<NodeId>& entries,
                                 bool sparse) {
  if (!sparse) return codegen::OutputBlock::dense(name, rows, cols, entries);
  const symbolic::SparsityPattern p = symbolic::patternOfNodes(rows, cols, entries);
  std::vector<NodeId> nz;
  for (int r = 0; r < p.rows; ++r)
    for (int e = p.row_ptr[r]; e < p.row_ptr[r + 1]; ++e) nz.push_back(entries[static_cast<std::size_t>(r) * cols + p.col_idx[e]]);
  return codegen::OutputBlock::sparse(name, rows, cols, std::vector<std::uint32_t>(p.row_ptr.begin(), p.row_ptr.end()),
                                      std::vector<std::uint32_t>(p.col_idx.begin(), p.col_idx.end()), std::move(nz));
}

codegen::OutputBlock hessianBlock(const std::string& name, int n, const std::vector<NodeId>& lower, bool sparse,
                                  const symbolic::Graph& graph) {
  auto at = [&](int i, int j) {
    if (i < j) std::swap(i, j);
    return lower[static_cast<std::size_t>(i) * (i + 1) / 2 + j];
  };
  if (!sparse) {
    std::vector<NodeId> full;
    for (int i = 0; i < n; ++i)
      for (int j = 0; j < n; ++j) full.push_back(at(i, j));
    return codegen::OutputBlock::dense(name, n, n, std::move(full));
  }
  std::vector<std::uint32_t> row_ptr{0}, col_idx;
  std::vector<NodeId> nz;
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j <= i; ++j)
      if (!graph.isConstant(at(i, j), 0.0)) col_idx.push_back(j), nz.push_back(at(i, j));
    row_ptr.push_back(static_cast<std::uint32_t>(nz.size()));
  }
  return codegen::OutputBlock::sparse(name, n, n, std::move(row_ptr), std::move(col_idx), std::move(nz));
}

}  // namespace robodiff::detail
