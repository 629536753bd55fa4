// The part of a graph some outputs depend on (their cone): what generated code for
// those outputs contains. The graph itself may hold more (other functions traced into
// it, intermediate results of differentiation that were not needed).
#pragma once

#include <cstddef>
#include <vector>

#include "robodiff/symbolic/graph.hpp"

namespace robodiff::symbolic {

// in_cone[id] for every id up to the largest output (one backward pass, no recursion).
std::vector<char> coneMask(const Graph& graph, const std::vector<NodeId>& outputs);

struct ConeSize {
  std::size_t nodes = 0;       // every node the outputs depend on
  std::size_t operations = 0;  // of which operations (not constants or inputs)
  std::size_t constants = 0;
  std::size_t inputs = 0;
};
ConeSize coneSize(const Graph& graph, const std::vector<NodeId>& outputs);

}  // namespace robodiff::symbolic
