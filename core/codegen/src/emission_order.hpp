// The order a function's values are computed in. Small functions keep the trace's order;
// large ones go output by output, each value right after the values it reads (a
// post-order from the outputs, dense blocks column by column), so what crosses parts and
// stays live is smaller. Why and what it bought: docs/code-generation.md ("Order of the
// emitted code").
#pragma once

#include <vector>

#include "robodiff/codegen/function_definition.hpp"
#include "robodiff/symbolic/graph.hpp"

namespace robodiff::codegen::detail {

// Every node the outputs of `function` reach, each after its operands: the first output
// block's values first (a dense block column by column), then the next block's.
std::vector<symbolic::NodeId> outputConeOrder(const symbolic::Graph& graph, const FunctionDefinition& function);

}  // namespace robodiff::codegen::detail
