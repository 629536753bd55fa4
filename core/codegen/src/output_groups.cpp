#include "output_groups.hpp"

#include <algorithm>

namespace robodiff::codegen::detail {
namespace {

constexpr std::uint32_t kUnwritten = 0xfffffffeu;

// Per element of each block: the StoreOutput writing it, kZeroElement for a structural
// zero of a ZeroOutput run, kUnwritten otherwise (or written twice).
std::vector<std::vector<std::uint32_t>> writers(const FunctionDefinition& f, const Chunk& chunk) {
  std::vector<std::vector<std::uint32_t>> w(f.outputs.size());
  for (std::uint32_t b = 0; b < f.outputs.size(); ++b) w[b].assign(f.outputs[b].size(), kUnwritten);
  for (std::uint32_t i = 0; i < chunk.code.size(); ++i) {
    const Instr& ins = chunk.code[i];
    if (ins.kind == InstrKind::ZeroOutput) {
      for (const ZeroRun& r : chunk.zero_runs.at(ins.index))
        for (std::uint32_t k = r.start; k < r.start + r.length; ++k) w[ins.block][k] = kZeroElement;
    } else if (ins.kind == InstrKind::StoreOutput) {
      std::uint32_t& e = w[ins.block][ins.index];
      e = e == kUnwritten ? i : kUnwritten;
    }
  }
  return w;
}

std::uint32_t zerosOf(const Chunk& chunk, std::uint32_t block) {
  std::uint32_t zeros = 0;
  for (const Instr& ins : chunk.code)
    if (ins.kind == InstrKind::ZeroOutput && ins.block == block)
      for (const ZeroRun& r : chunk.zero_runs.at(ins.index)) zeros += r.length;
  return zeros;
}

// Stores the chunk issues for its outputs as printed without groups: one per StoreOutput;
// for a block's zeros, one memset, or those of forEachZeroStore.
std::uint32_t storesWithoutGroups(const FunctionDefinition& f, const Chunk& chunk, std::uint32_t zeros_stored_maximum) {
  std::uint32_t stores = 0;
  for (const Instr& ins : chunk.code) {
    if (ins.kind == InstrKind::StoreOutput) ++stores;
    if (ins.kind != InstrKind::ZeroOutput) continue;
    if (zerosOf(chunk, ins.block) > zeros_stored_maximum) {
      ++stores;
      continue;
    }
    forEachZeroStore(
        chunk.zero_runs.at(ins.index), f.outputs[ins.block].size(), [&](std::uint32_t) { ++stores; },
        [&](std::uint32_t) { ++stores; });
  }
  return stores;
}

}  // namespace

bool OutputGroupPlan::packs(std::uint32_t block, std::uint32_t start) const {
  return std::any_of(groups.begin(), groups.end(),
                     [&](const OutputGroup& g) { return g.block == block && g.start == start; });
}

OutputGroupPlan planOutputGroups(const FunctionDefinition& f, const Chunk& chunk, std::uint32_t zeros_stored_maximum) {
  OutputGroupPlan plan;
  plan.group_of.assign(chunk.code.size(), kNoGroup);
  const double operations = std::max<std::uint32_t>(chunk.operations, 1);
  if (storesWithoutGroups(f, chunk, zeros_stored_maximum) < kStoresPerOperationPacked * operations) return plan;
  const auto w = writers(f, chunk);
  for (std::uint32_t b = 0; b < f.outputs.size(); ++b) {
    if (zerosOf(chunk, b) > zeros_stored_maximum) continue;  // cleared by a memset
    for (std::uint32_t start = 0; start + 4 <= w[b].size(); start += 4) {
      OutputGroup g{b, start, 0, {}};
      std::uint32_t values = 0, zeros = 0;
      bool whole = true;
      for (std::uint32_t e = 0; e < 4; ++e) {
        const std::uint32_t at = w[b][start + e];
        whole = whole && at != kUnwritten;
        g.store[e] = at;
        if (at == kZeroElement) ++zeros;
        else if (at != kUnwritten) {
          ++values;
          g.last = std::max(g.last, at);
        }
      }
      // Without the group: a store per value and one for the zeros, if any.
      if (!whole || values == 0 || values + (zeros > 0 ? 1 : 0) < 2) continue;
      for (std::uint32_t e = 0; e < 4; ++e)
        if (g.store[e] != kZeroElement) plan.group_of[g.store[e]] = static_cast<std::uint32_t>(plan.groups.size());
      plan.groups.push_back(g);
    }
  }
  return plan;
}

}  // namespace robodiff::codegen::detail
