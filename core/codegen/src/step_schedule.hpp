// Lowering's first stage: which of a function's nodes are computed, in which order, and
// in which chunk (part). Each step is a node; sin and cos of one argument; or a lane
// pair (lane_pairs.hpp). Sin and cos of inputs come first, then the trace's order (or
// output by output, emission_order.hpp), and the steps are cut into chunks of at most
// split_threshold operations.
#pragma once

#include <cstdint>
#include <vector>

#include "lane_pairs.hpp"
#include "lowering.hpp"

namespace robodiff::codegen::detail {

struct StepSchedule {
  explicit StepSchedule(std::size_t nodes) : pairs(nodes) {}

  std::vector<Step> steps;           // in order of their chunks
  std::uint32_t chunks = 1;
  std::uint32_t sincos_pairs = 0;    // steps computing sin and cos of one argument
  LanePairs pairs;                   // none with LanePairMode::Off or Order
  std::vector<symbolic::NodeId> twin;  // a pair's lane-0 node -> its lane-1 node; empty without pairs
};

// The steps of the nodes with needed[id] (needed_count of them): those an output reads.
StepSchedule scheduleSteps(const symbolic::Graph& graph, const FunctionDefinition& function,
                           const LoweringOptions& options, const std::vector<char>& needed,
                           std::uint32_t needed_count);

}  // namespace robodiff::codegen::detail
