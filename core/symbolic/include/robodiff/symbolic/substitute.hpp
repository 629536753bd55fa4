// Copying a graph's cone into another graph with its inputs replaced: how a traced
// function becomes the function that is generated.
//
// Each input index of `from` maps to any node of `to` (a new input, a constant, or a
// result already copied), and every node above is rebuilt through `to`'s constructors,
// so the simplifications run again: inputs replaced by constants fold away (fixed
// inputs, the tangent displacement dq = 0 of a floating base), and only what the
// outputs need is copied, with `to`'s inputs numbered as the caller chooses.
// A loop over node ids, never a recursion.
#pragma once

#include <vector>

#include "robodiff/symbolic/graph.hpp"

namespace robodiff::symbolic {

// The nodes of `outputs` rebuilt in `to`. input_nodes[i] is the node of `to` that input
// index i of `from` becomes; an input that the outputs reach must have an entry
// (std::invalid_argument otherwise). `from` and `to` may not be the same graph.
std::vector<NodeId> copyCone(const Graph& from, const std::vector<NodeId>& outputs, Graph& to,
                             const std::vector<NodeId>& input_nodes);

}  // namespace robodiff::symbolic
