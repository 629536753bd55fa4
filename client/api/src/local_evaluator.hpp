#pragma once
// A function evaluated in this process: the compiled library of a verified cache
// artifact (kept pinned, so the cache never evicts it while loaded), called directly
// with the caller's memory. The block offsets are computed once at load; a call only
// points the per-thread pointer arrays at the caller's spans. Batches go through the
// library's batched entry point (RD_W knots in SIMD lanes), regrouped per chunk.

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "robodiff/cache/cache.hpp"
#include "robodiff/codegen/loaded_library.hpp"
#include "robodiff/functions/function_spec.hpp"
#include "robodiff/schema/messages.hpp"
#include "thread_buffers.hpp"

namespace robodiff::client::detail {

class LocalEvaluator {
 public:
  // Loads the artifact's library and checks its function against what the cache recorded
  // (the C name, block sizes). Throws codegen::LoadError / std::invalid_argument.
  LocalEvaluator(cache::Artifact artifact, const FunctionSpec& spec);

  // The layout as the library describes it (the GetFunction form, kinds from the spec).
  const rpc::GetFunctionReply& layout() const { return layout_; }
  // Empty when the library's layout equals `other`; else what differs.
  std::string differenceFrom(const rpc::GetFunctionReply& other) const;

  // One knot: `in` holds the concatenated input blocks, `out` room for the output blocks
  // (sizes checked by the caller). No lock; no allocation after this thread's first call.
  void evaluate(const double* in, double* out) const noexcept {
    ThreadBuffers& t = threadBuffers();
    if (t.work.size() < work_size_ || t.in.size() < in_offsets_.size() || t.out.size() < out_offsets_.size())
        [[unlikely]]
      t.reserveFor(work_size_, in_offsets_.size(), out_offsets_.size());
    const double** ip = t.in.data();
    for (std::size_t b = 0; b < in_offsets_.size(); ++b) ip[b] = in + in_offsets_[b];
    double** op = t.out.data();
    for (std::size_t b = 0; b < out_offsets_.size(); ++b) op[b] = out + out_offsets_[b];
    eval_(ip, op, t.work.data());
  }

  // `knots` knots, knot after knot (as the client holds them), through the batched entry
  // point: chunks of whole batch widths (the library pads a last partial width itself),
  // each regrouped block after block (abi.h's batched layout) on the way in and out. A
  // library of width 1 (a plain loop) takes the single-knot path, without regrouping.
  // No lock; no allocation after this thread's first batch (the scratch is sized for a
  // whole chunk, whatever `knots`).
  void evaluateBatch(std::uint64_t knots, const double* in, double* out) const noexcept;

  // The same two with each block in its own memory, knot after knot (block b of knot k
  // at in[b] + k * size_b): the library's own batched layout, so nothing is copied. One
  // knot (batch false) goes to the single entry point, else `knots` to the batched one.
  void evaluateBlocks(std::uint64_t knots, const double* const* in, double* const* out, bool batch) const noexcept;

  // Knots the batched entry point evaluates together (1: it is not used).
  std::uint32_t batchWidth() const { return width_; }

  const cache::Artifact& artifact() const { return artifact_; }

 private:
  cache::Artifact artifact_;
  codegen::CompiledFunction function_;
  rpc::GetFunctionReply layout_;
  std::vector<std::uint32_t> in_offsets_, out_offsets_;  // start of each block
  std::vector<std::uint32_t> in_sizes_, out_sizes_;      // doubles of each block
  std::size_t in_count_ = 0, out_count_ = 0;             // doubles per knot
  std::size_t work_size_ = 0, batch_work_size_ = 0;
  std::uint32_t width_ = 1;        // the library's batch width
  std::uint64_t chunk_knots_ = 0;  // knots per batched call: a multiple of width_
  robodiff_eval_fn eval_ = nullptr;
  robodiff_eval_batch_fn eval_batch_ = nullptr;

  void evaluateChunk(std::uint64_t n, const double* in, double* out, ThreadBuffers& t) const noexcept;
};

}  // namespace robodiff::client::detail
