// Lane pairs: two isomorphic operations of single-knot code computed together, in the
// two lanes of one 128-bit vector (a 2-wide SLP vectorisation of the straight-line code).
// A robot's symmetric limbs run the same algorithm on different data: the left leg's
// recursion and the right leg's pair operation by operation. Why and what it bought:
// docs/code-generation.md ("Lane pairs").
#pragma once

#include <cstdint>
#include <vector>

#include "robodiff/codegen/function_definition.hpp"
#include "shape_signatures.hpp"
#include "robodiff/symbolic/graph.hpp"

namespace robodiff::codegen::detail {

inline constexpr std::uint32_t kNoPair = 0xFFFFFFFFu;

class LanePairs {
 public:
  explicit LanePairs(std::size_t nodes) : partner_(nodes, kNoPair), lane_(nodes, 0), swapped_(nodes, 0) {}

  bool paired(symbolic::NodeId n) const { return partner_[n] != kNoPair; }
  symbolic::NodeId partner(symbolic::NodeId n) const { return partner_[n]; }
  int lane(symbolic::NodeId n) const { return lane_[n]; }
  // The lane-1 node of a pair of a commutative operation reads its operands swapped.
  bool swapped(symbolic::NodeId n) const { return swapped_[n] != 0; }
  std::size_t count() const { return count_; }

  void pair(symbolic::NodeId lane0, symbolic::NodeId lane1, bool swapped);
  void dissolve(symbolic::NodeId n);

 private:
  std::vector<symbolic::NodeId> partner_;
  std::vector<std::uint8_t> lane_, swapped_;
  std::size_t count_ = 0;
};

// The pairs worth computing together in `function`'s single-knot code, among the
// operations n with pairable[n] (the function's operations but sin and cos). Seeds are
// pairs of output values whose expressions match to some depth, those whose shapes match
// deepest first; a pair's operands, and the readers of its members, are paired in turn
// while they match (the reader whose shape matches deepest). Groups of pairs that
// would cost more lane shuffles than they save operations are dropped. With same_depth,
// only operations at the same depth (longest chain of operations from the inputs) pair:
// fewer pairs, but every one can be ordered.
LanePairs chooseLanePairs(const symbolic::Graph& graph, const FunctionDefinition& function,
                          const std::vector<char>& pairable, const ShapeSignatures& shapes, bool same_depth);

// One step of a schedule: a node computed; a sin/cos pair (first the sin, second the
// cos); or a lane pair (first lane 0, lane1 lane 1).
struct Step {
  symbolic::NodeId first = 0;
  symbolic::NodeId second = kNoPair;
  symbolic::NodeId lane1 = kNoPair;
  std::uint32_t chunk = 0;

  bool operator==(const Step&) const = default;
};

// A function's steps (in an order where each node follows its operands) reordered
// so that each pair is one step after both members' operands, staying close to the
// given order. Pairs that cannot be ordered (a member depends on the other, or two
// pairs on each other crosswise) are dissolved: one at a time, then, after 64 tries,
// every pair still waiting at once.
std::vector<Step> orderWithPairs(const symbolic::Graph& graph, const std::vector<Step>& steps, LanePairs& pairs);

// A function's lane pairs and the order of its steps with them: pairs chosen both ways
// (at one depth only, and at any depth then ordered: symmetric limbs pair better one way
// or the other), the way with more pairs kept, and `steps` reordered with each pair as
// one step. None (and `steps` untouched) when the function has `below` operations or
// more, or when the pairs would compute under `coverage` of its operations.
LanePairs scheduleLanePairs(const symbolic::Graph& graph, const FunctionDefinition& function, double coverage,
                            std::uint32_t below, std::vector<Step>& steps);

// scheduleLanePairs' outcome for one function's steps, kept so that the lowerings of one
// function (readyFirstSums, then its code with and without pairs) choose its pairs once:
// the same steps of the same graph in give the same pairs and order out. The graph a
// lowering pairs is the function's with its sums chained (sum_chains.hpp), which the
// order of the chains' terms changes: a lowering of other steps, or of sums chained
// otherwise, pairs afresh. The Talos Euler step value's pairs took 70 ms a lowering,
// three lowerings a build.
struct LanePairMemo {
  std::vector<Step> steps_in, steps_out;
  LanePairs pairs{0};
  bool ready_first_sums = false;  // how the graph's sums were chained
  std::size_t graph_size = 0;
  bool filled = false;
};

// A function's readyFirstSums and the memo its paired lowering filled: found once for
// all of the function's lowerings, the assembly's and, where that does not apply, the
// C's (each a paired lowering otherwise).
struct FunctionPairing {
  LanePairMemo memo;
  bool ready_first_sums = false;
};

}  // namespace robodiff::codegen::detail
