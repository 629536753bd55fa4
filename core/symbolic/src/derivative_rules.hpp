// The derivative rule of every Op, in the two forms the sweeps need: the tangent of a
// node from its arguments' tangents (forward mode) and the contributions of a node's
// adjoint to its arguments' adjoints (reverse mode). Internal to core/symbolic.
#pragma once

#include "robodiff/symbolic/graph.hpp"

namespace robodiff::symbolic::detail {

// A signed term (negative: -node), so that negations fold into add/sub instead of
// becoming nodes of their own.
struct Term {
  NodeId node = 0;
  bool negative = false;
};

// sum + term (sum may be the zero node).
NodeId accumulate(Graph& graph, NodeId sum, const Term& term);

// The tangent of node `id` (whose node is `n`) given its arguments' tangents.
NodeId pushTangent(Graph& graph, NodeId id, const Node& n, const NodeId arg_tangents[3]);

// The terms that the adjoint `bar` of node `id` adds to its arguments' adjoints, for
// the arguments with wanted[k] (the others, and those that get nothing: the zero node).
// Skipping arguments that depend on no differentiation input keeps useless partials
// (log a for a constant exponent, ...) out of the graph.
void pullAdjoint(Graph& graph, NodeId id, const Node& n, NodeId bar, const bool wanted[3], Term arg_terms[3]);

}  // namespace robodiff::symbolic::detail
