#include "robodiff/symbolic/cone.hpp"

#include <algorithm>

namespace robodiff::symbolic {

std::vector<char> coneMask(const Graph& graph, const std::vector<NodeId>& outputs) {
  if (outputs.empty()) return {};
  const NodeId last = *std::max_element(outputs.begin(), outputs.end());
  std::vector<char> in(static_cast<std::size_t>(last) + 1, 0);
  for (NodeId o : outputs) in[o] = 1;
  // Arguments have smaller ids: one pass from the top marks the whole cone.
  for (NodeId id = last + 1; id-- > 0;) {
    if (!in[id]) continue;
    const Node& n = graph.node(id);
    for (int k = 0; k < arity(n.op); ++k) in[n.args[k]] = 1;
  }
  return in;
}

ConeSize coneSize(const Graph& graph, const std::vector<NodeId>& outputs) {
  const std::vector<char> in = coneMask(graph, outputs);
  ConeSize size;
  for (NodeId id = 0; id < in.size(); ++id) {
    if (!in[id]) continue;
    ++size.nodes;
    const Op op = graph.node(id).op;
    if (op == Op::Constant) ++size.constants;
    else if (op == Op::Input) ++size.inputs;
    else ++size.operations;
  }
  return size;
}

}  // namespace robodiff::symbolic
