// Single-knot output values stored four at a time: one 32-byte store for each group of
// four elements (from element 4k of a block) that a chunk otherwise writes with two
// stores or more (a four-zero store and the values over it, or several values), in
// functions bound by their stores (docs/code-generation.md, "Outputs in 32-byte groups").
#pragma once

#include <cstdint>
#include <vector>

#include "lowering.hpp"

namespace robodiff::codegen::detail {

// A function whose chunk issues at least this many stores per operation is taken as bound
// by its stores (one store a cycle, two operations).
inline constexpr double kStoresPerOperationPacked = 0.75;

struct OutputGroup {
  std::uint32_t block = 0, start = 0;  // elements [start, start + 4) of the block
  std::uint32_t last = 0;              // index in chunk.code of the group's last store
  // Per element: the StoreOutput (index in chunk.code) that writes it, or kZeroElement.
  std::uint32_t store[4] = {0, 0, 0, 0};
};

inline constexpr std::uint32_t kZeroElement = 0xffffffffu;

struct OutputGroupPlan {
  std::vector<OutputGroup> groups;
  // Per instruction of chunk.code: the group its StoreOutput belongs to, or kNoGroup.
  std::vector<std::uint32_t> group_of;
  bool packs(std::uint32_t block, std::uint32_t start) const;
};

inline constexpr std::uint32_t kNoGroup = 0xffffffffu;

// The groups of a chunk that holds all of its function's output stores (a function in
// one part), in the blocks whose zeros are stored four at a time (at most
// `zeros_stored_maximum` of them; more are cleared by a memset); none when the chunk is
// not bound by its stores.
OutputGroupPlan planOutputGroups(const FunctionDefinition& f, const Chunk& chunk, std::uint32_t zeros_stored_maximum);

}  // namespace robodiff::codegen::detail
