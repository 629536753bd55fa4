#include "robodiff/symbolic/substitute.hpp"

#include <stdexcept>
#include <string>

#include "robodiff/symbolic/cone.hpp"

namespace robodiff::symbolic {

std::vector<NodeId> copyCone(const Graph& from, const std::vector<NodeId>& outputs, Graph& to,
                             const std::vector<NodeId>& input_nodes) {
  if (&from == &to) throw std::invalid_argument("copyCone: source and destination are the same graph");
  const std::vector<char> cone = coneMask(from, outputs);
  std::vector<NodeId> image(cone.size(), 0);
  for (NodeId id = 0; id < cone.size(); ++id) {
    if (!cone[id]) continue;
    const Node& n = from.node(id);
    switch (arity(n.op)) {
      case 0:
        if (n.op == Op::Constant) {
          image[id] = to.constant(n.value);
        } else {
          if (n.index >= input_nodes.size())
            throw std::invalid_argument("copyCone: input " + std::to_string(n.index) + " has no replacement (" +
                                        std::to_string(input_nodes.size()) + " given)");
          image[id] = input_nodes[n.index];
        }
        break;
      case 1: image[id] = to.unary(n.op, image[n.args[0]]); break;
      case 2: image[id] = to.binary(n.op, image[n.args[0]], image[n.args[1]]); break;
      default: image[id] = to.selectPositive(image[n.args[0]], image[n.args[1]], image[n.args[2]]); break;
    }
  }
  std::vector<NodeId> out;
  out.reserve(outputs.size());
  for (NodeId o : outputs) out.push_back(image[o]);
  return out;
}

}  // namespace robodiff::symbolic
