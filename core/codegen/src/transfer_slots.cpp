#include "transfer_slots.hpp"

#include "operand_ref.hpp"

namespace robodiff::codegen::detail {
namespace {

using symbolic::Graph;
using symbolic::NodeId;

// The last chunk reading each value (kNoSlot: none).
std::vector<std::uint32_t> lastChunkReading(const Graph& g, const std::vector<Step>& steps) {
  std::vector<std::uint32_t> last(g.size(), kNoSlot);
  for (const Step& s : steps)
    for (NodeId id : {s.first, s.lane1}) {
      if (id == kNoPair) continue;
      const symbolic::Node& n = g.node(id);
      for (int a = 0; a < symbolic::arity(n.op); ++a) {
        const Ref r = resolve(g, n.args[a]);
        if (r.is_constant) continue;
        if (last[r.base] == kNoSlot || s.chunk > last[r.base]) last[r.base] = s.chunk;
      }
    }
  return last;
}

}  // namespace

TransferSlots assignTransferSlots(const Graph& g, const std::vector<Step>& steps, const std::vector<NodeId>& twin,
                                  std::uint32_t chunk_count) {
  TransferSlots out;
  out.slot.assign(g.size(), kNoSlot);
  if (chunk_count == 1) return out;
  const std::vector<std::uint32_t> last = lastChunkReading(g, steps);
  // Slots free again from a chunk on: single ones, and two adjacent ones (the first).
  std::vector<std::vector<std::uint32_t>> release_at(chunk_count + 1), release_two_at(chunk_count + 1);
  std::vector<std::uint32_t> free_one, free_two;
  auto take = [&](std::vector<std::uint32_t>& list, std::uint32_t width) {
    if (list.empty()) return (out.count += width) - width;
    const std::uint32_t slot = list.back();
    list.pop_back();
    return slot;
  };
  auto handedOver = [&](NodeId d, std::uint32_t chunk) {
    return d != kNoPair && last[d] != kNoSlot && last[d] > chunk;
  };
  std::uint32_t current = kNoSlot;
  for (const Step& s : steps) {
    if (s.chunk != current) {
      current = s.chunk;
      free_one.insert(free_one.end(), release_at[current].begin(), release_at[current].end());
      free_two.insert(free_two.end(), release_two_at[current].begin(), release_two_at[current].end());
    }
    for (NodeId d : {s.first, s.lane1, s.second}) {
      if (!handedOver(d, s.chunk) || out.slot[d] != kNoSlot) continue;
      const NodeId lane1 = twin.empty() ? kNoPair : twin[d];
      if (!handedOver(lane1, s.chunk)) {
        out.slot[d] = take(free_one, 1);
        release_at[last[d] + 1].push_back(out.slot[d]);
        continue;
      }
      const std::uint32_t slot = take(free_two, 2);
      out.slot[d] = slot;
      out.slot[lane1] = slot + 1;
      if (last[d] == last[lane1]) {
        release_two_at[last[d] + 1].push_back(slot);
      } else {
        release_at[last[d] + 1].push_back(slot);
        release_at[last[lane1] + 1].push_back(slot + 1);
      }
    }
  }
  return out;
}

}  // namespace robodiff::codegen::detail
