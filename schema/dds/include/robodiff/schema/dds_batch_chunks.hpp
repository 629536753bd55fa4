#pragma once
// EvaluateBatch replies split at knot boundaries (docs/transports.md, "Large replies"): the
// server plans the chunks so that each sample's doubles stay under a byte limit; the client
// puts each chunk in place in the caller's output span and knows when it has them all.

#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "robodiff.h"
#include "robodiff/schema/status.hpp"

namespace robodiff::dds_codec {

struct ChunkPlan {
  std::uint32_t knots_per_chunk = 1;
  std::uint32_t chunk_count = 1;  // >= 1, also for 0 knots
  std::uint32_t firstKnot(std::uint32_t chunk) const { return chunk * knots_per_chunk; }
  std::uint32_t knotCount(std::uint32_t chunk, std::uint32_t total_knots) const;
};

// At least one knot per chunk, however large a knot is.
ChunkPlan planBatchChunks(std::uint32_t total_knots, std::uint32_t outputs_per_knot, std::size_t max_payload_bytes);

// Collects the chunks of one reply into `outputs` (knots * outputs-per-knot doubles).
class BatchAssembler {
 public:
  BatchAssembler(std::uint64_t knots, std::span<double> outputs);
  // Checks that the chunk fits (total_knots, range, doubles per knot, no chunk twice) and
  // copies it in place; INTERNAL naming the mismatch otherwise.
  Status add(const robodiff_wire_EvaluateBatchReply& chunk);
  bool complete() const { return knots_received_ == knots_; }

 private:
  std::uint64_t knots_;
  std::span<double> outputs_;
  std::uint64_t knots_received_ = 0;
  std::vector<bool> chunk_seen_;
};

}  // namespace robodiff::dds_codec
