// How deep two operations have the same shape: the same operations, reading operands of
// the same shape, level after level (a hash per node and level; constants and inputs are
// leaves, whatever their value). A left leg's recursion and the right leg's have the same
// shape all the way down; two joints of one leg part within a few levels. The choice of
// lane pairs (lane_pairs.cpp) ranks its candidates by it.
#pragma once

#include <cstdint>
#include <vector>

#include "robodiff/symbolic/graph.hpp"

namespace robodiff::codegen::detail {

class ShapeSignatures {
 public:
  // Signatures of the nodes n with of_interest[n]; the others are leaves.
  ShapeSignatures(const symbolic::Graph& graph, const std::vector<char>& of_interest);

  // The deepest recorded level (kLevels) at which a and b have the same shape; 0 when
  // their operations differ.
  int matchDepth(symbolic::NodeId a, symbolic::NodeId b) const;
  // The signature at the deepest level kept: equal for two nodes whose expressions have
  // the same shape throughout (hash collisions aside).
  std::uint64_t deepest(symbolic::NodeId n) const { return kept_.back()[n]; }

 private:
  std::vector<int> levels_;                       // the levels kept, increasing
  std::vector<std::vector<std::uint64_t>> kept_;  // kept_[i][node]: signature at levels_[i]
};

}  // namespace robodiff::codegen::detail
