// Sums as chains: a tree of sums ((a b + c d) + (e f + g h)) rebuilt as one running sum
// (((a b + c d) + e f) + g h) that takes each term where the tree took it, so the C
// compiler fuses every product after the first into a multiply-add. With `ready_first`,
// where a tree's terms are ready at different times, the chain takes them in that order
// instead (the latest last) when that ends sooner. A tree whose chain would lengthen the
// function's critical path stays a tree. Why and what it bought: docs/code-generation.md
// ("Sums as chains").
//
// This reassociates: results may differ from the traced operations in the last bits.
// The graph itself never reassociates (graph.hpp); this pass runs before lowering, so
// the C and the interpreter compute the same chains.
#pragma once

#include "robodiff/codegen/function_definition.hpp"
#include "robodiff/symbolic/graph.hpp"

namespace robodiff::codegen::detail {

struct ChainedFunction {
  symbolic::Graph graph;        // the function's cone, sums chained
  FunctionDefinition function;  // the definition, its outputs renumbered into `graph`
};

ChainedFunction chainSums(const symbolic::Graph& graph, const FunctionDefinition& function, bool ready_first);

}  // namespace robodiff::codegen::detail
