#include "robodiff/symbolic/sparsity.hpp"

#include <algorithm>
#include <stdexcept>

#include "robodiff/symbolic/cone.hpp"

namespace robodiff::symbolic {

bool SparsityPattern::contains(int row, int col) const {
  if (row < 0 || row >= rows) return false;
  auto first = col_idx.begin() + row_ptr[row], last = col_idx.begin() + row_ptr[row + 1];
  return std::binary_search(first, last, col);
}

SparsityPattern patternOfNodes(int rows, int cols, const std::vector<NodeId>& entries) {
  if (entries.size() != static_cast<std::size_t>(rows) * static_cast<std::size_t>(cols))
    throw std::invalid_argument("patternOfNodes: entries do not match rows x cols");
  SparsityPattern p;
  p.rows = rows;
  p.cols = cols;
  p.row_ptr.reserve(static_cast<std::size_t>(rows) + 1);
  p.row_ptr.push_back(0);
  for (int r = 0; r < rows; ++r) {
    for (int c = 0; c < cols; ++c)
      if (entries[static_cast<std::size_t>(r) * cols + c] != 0) p.col_idx.push_back(c);
    p.row_ptr.push_back(static_cast<int>(p.col_idx.size()));
  }
  return p;
}

SparsityPattern dependencyPattern(const Graph& graph, const std::vector<NodeId>& outputs,
                                  const std::vector<std::uint32_t>& wrt) {
  const std::size_t words = (wrt.size() + 63) / 64;
  const std::vector<char> in = coneMask(graph, outputs);
  std::vector<std::uint64_t> bits(in.size() * words, 0);
  // Input index -> its bits (an index may appear several times in wrt).
  std::vector<std::vector<std::size_t>> columns_of(graph.inputCount());
  for (std::size_t c = 0; c < wrt.size(); ++c)
    if (wrt[c] < columns_of.size()) columns_of[wrt[c]].push_back(c);
  for (NodeId id = 0; id < in.size(); ++id) {
    if (!in[id]) continue;
    const Node& n = graph.node(id);
    std::uint64_t* mine = &bits[id * words];
    if (n.op == Op::Input) {
      for (std::size_t c : columns_of[n.index]) mine[c / 64] |= std::uint64_t{1} << (c % 64);
      continue;
    }
    for (int k = 0; k < arity(n.op); ++k) {
      const std::uint64_t* theirs = &bits[n.args[k] * words];
      for (std::size_t w = 0; w < words; ++w) mine[w] |= theirs[w];
    }
  }
  SparsityPattern p;
  p.rows = static_cast<int>(outputs.size());
  p.cols = static_cast<int>(wrt.size());
  p.row_ptr.push_back(0);
  for (NodeId o : outputs) {
    for (std::size_t c = 0; c < wrt.size(); ++c)
      if (bits[o * words + c / 64] >> (c % 64) & 1) p.col_idx.push_back(static_cast<int>(c));
    p.row_ptr.push_back(static_cast<int>(p.col_idx.size()));
  }
  return p;
}

}  // namespace robodiff::symbolic
