#include "emission_order.hpp"

#include <utility>

namespace robodiff::codegen::detail {

namespace {

// Appends `root` and the nodes it reads that are not yet `seen`, operands first.
void postOrder(const symbolic::Graph& graph, symbolic::NodeId root, std::vector<char>& seen,
               std::vector<symbolic::NodeId>& order) {
  if (seen[root]) return;
  seen[root] = 1;
  std::vector<std::pair<symbolic::NodeId, int>> stack{{root, 0}};  // node, next operand
  while (!stack.empty()) {
    const symbolic::NodeId id = stack.back().first;
    const int operand = stack.back().second;
    const symbolic::Node& node = graph.node(id);
    if (operand == symbolic::arity(node.op)) {
      order.push_back(id);
      stack.pop_back();
      continue;
    }
    ++stack.back().second;
    const symbolic::NodeId next = node.args[operand];
    if (seen[next]) continue;
    seen[next] = 1;
    stack.push_back({next, 0});
  }
}

}  // namespace

std::vector<symbolic::NodeId> outputConeOrder(const symbolic::Graph& graph, const FunctionDefinition& function) {
  std::vector<char> seen(graph.size(), 0);
  std::vector<symbolic::NodeId> order;
  for (const OutputBlock& block : function.outputs) {
    // A Jacobian's columns are independent directions: its sweeps and solves run per column.
    if (block.kind == OutputKind::Dense) {
      for (std::uint32_t c = 0; c < block.cols; ++c)
        for (std::uint32_t r = 0; r < block.rows; ++r) postOrder(graph, block.values[r * block.cols + c], seen, order);
    } else {
      for (symbolic::NodeId id : block.values) postOrder(graph, id, seen, order);
    }
  }
  return order;
}

}  // namespace robodiff::codegen::detail
