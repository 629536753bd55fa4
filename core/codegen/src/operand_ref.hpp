// How the lowering reads a node: negations (a Neg node, a product with the constant -1)
// are operand flags, not instructions, and constants are literals. Shared by the
// lowering and the choice of lane pairs.
#pragma once

#include "robodiff/symbolic/graph.hpp"

namespace robodiff::codegen::detail {

// A node as its consumers read it: a constant, or a computed/input node, maybe negated.
struct Ref {
  bool is_constant = false;
  double value = 0.0;
  symbolic::NodeId base = 0;
  bool negated = false;
};

// Neg nodes and products with the constant -1 are read through: they are operand flags.
inline bool isNegation(const symbolic::Graph& g, const symbolic::Node& n, symbolic::NodeId* operand) {
  if (n.op == symbolic::Op::Neg) {
    *operand = n.args[0];
    return true;
  }
  if (n.op == symbolic::Op::Mul) {
    if (g.isConstant(n.args[0], -1.0)) {
      *operand = n.args[1];
      return true;
    }
    if (g.isConstant(n.args[1], -1.0)) {
      *operand = n.args[0];
      return true;
    }
  }
  return false;
}

inline Ref resolve(const symbolic::Graph& g, symbolic::NodeId id) {
  Ref r;
  symbolic::NodeId operand;
  while (isNegation(g, g.node(id), &operand)) {
    r.negated = !r.negated;
    id = operand;
  }
  const symbolic::Node& n = g.node(id);
  if (n.op == symbolic::Op::Constant) {
    r.is_constant = true;
    r.value = r.negated ? -n.value : n.value;
    r.negated = false;
  } else {
    r.base = id;
  }
  return r;
}

}  // namespace robodiff::codegen::detail
