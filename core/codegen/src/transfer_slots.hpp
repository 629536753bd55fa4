// Transfer slots: where the parts of a split function hand values to later parts, in the
// work buffer. Internal to the lowering.
#pragma once

#include <cstdint>
#include <vector>

#include "lane_pairs.hpp"
#include "robodiff/symbolic/graph.hpp"

namespace robodiff::codegen::detail {

inline constexpr std::uint32_t kNoSlot = 0xFFFFFFFFu;

struct TransferSlots {
  std::vector<std::uint32_t> slot;  // per node: its slot in the work buffer, or kNoSlot
  std::uint32_t count = 0;          // slots used
};

// For each value read by a later chunk than its own (steps in order, each with its
// chunk): a slot, free again after the last chunk reading it. The two lanes of a pair
// (twin[lane 0] = lane 1; empty: no pairs) handed over together get adjacent slots, lane
// 0 first, so that one 16-byte store and one load move both.
TransferSlots assignTransferSlots(const symbolic::Graph& graph, const std::vector<Step>& steps,
                                  const std::vector<symbolic::NodeId>& twin, std::uint32_t chunk_count);

}  // namespace robodiff::codegen::detail
