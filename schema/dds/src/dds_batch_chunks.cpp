// Planning (server) and assembling (client) the chunks of an EvaluateBatch reply.
#include "robodiff/schema/dds_batch_chunks.hpp"

#include <algorithm>
#include <cstring>
#include <string>

namespace robodiff::dds_codec {

std::uint32_t ChunkPlan::knotCount(std::uint32_t chunk, std::uint32_t total_knots) const {
  const std::uint64_t first = std::uint64_t{chunk} * knots_per_chunk;
  if (first >= total_knots) return 0;
  return static_cast<std::uint32_t>(std::min<std::uint64_t>(knots_per_chunk, total_knots - first));
}

ChunkPlan planBatchChunks(std::uint32_t total_knots, std::uint32_t outputs_per_knot, std::size_t max_payload_bytes) {
  ChunkPlan plan;
  const std::size_t knot_bytes = std::size_t{outputs_per_knot} * sizeof(double);
  std::size_t per_chunk = knot_bytes == 0 ? total_knots : max_payload_bytes / knot_bytes;
  per_chunk = std::clamp<std::size_t>(per_chunk, 1, std::max<std::uint32_t>(total_knots, 1));
  plan.knots_per_chunk = static_cast<std::uint32_t>(per_chunk);
  plan.chunk_count = total_knots == 0 ? 1 : static_cast<std::uint32_t>((total_knots + per_chunk - 1) / per_chunk);
  return plan;
}

BatchAssembler::BatchAssembler(std::uint64_t knots, std::span<double> outputs) : knots_(knots), outputs_(outputs) {}

Status BatchAssembler::add(const robodiff_wire_EvaluateBatchReply& chunk) {
  auto fail = [](std::string what) {
    return Status{StatusCode::Internal, "EvaluateBatch reply chunk does not fit the request: " + what};
  };
  if (chunk.total_knots != knots_)
    return fail("total_knots " + std::to_string(chunk.total_knots) + ", the request had " + std::to_string(knots_));
  if (chunk.chunk_count == 0 || chunk.chunk_index >= chunk.chunk_count)
    return fail("chunk_index " + std::to_string(chunk.chunk_index) + " of chunk_count " +
                std::to_string(chunk.chunk_count));
  if (std::uint64_t{chunk.first_knot} + chunk.knot_count > knots_)
    return fail("knots [" + std::to_string(chunk.first_knot) + ", +" + std::to_string(chunk.knot_count) +
                ") beyond " + std::to_string(knots_));
  if (chunk_seen_.empty()) chunk_seen_.assign(chunk.chunk_count, false);
  if (chunk_seen_.size() != chunk.chunk_count) return fail("chunk_count changed between chunks");
  if (chunk_seen_[chunk.chunk_index]) return fail("chunk " + std::to_string(chunk.chunk_index) + " arrived twice");
  const std::uint64_t per_knot = knots_ ? outputs_.size() / knots_ : 0;
  if (knots_ && outputs_.size() % knots_ != 0)
    return fail("the caller's outputs (" + std::to_string(outputs_.size()) + " doubles) are not a multiple of " +
                std::to_string(knots_) + " knots");
  const std::uint64_t length = chunk.outputs._buffer ? chunk.outputs._length : 0;
  if (length != per_knot * chunk.knot_count)
    return fail(std::to_string(length) + " doubles for " + std::to_string(chunk.knot_count) + " knots, expected " +
                std::to_string(per_knot) + " per knot (the caller's outputs span)");
  if (length) std::memcpy(outputs_.data() + chunk.first_knot * per_knot, chunk.outputs._buffer, length * sizeof(double));
  chunk_seen_[chunk.chunk_index] = true;
  knots_received_ += chunk.knot_count;
  return {};
}

}  // namespace robodiff::dds_codec
