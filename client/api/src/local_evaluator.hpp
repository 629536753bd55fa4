#pragma once
// A function evaluated in this process: the compiled library of a verified cache
// artifact (kept pinned, so the cache never evicts it while loaded), called directly
// with the caller's memory. The block offsets are computed once at load; a call only
// points the per-thread pointer arrays at the caller's spans.

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

  const cache::Artifact& artifact() const { return artifact_; }

 private:
  cache::Artifact artifact_;
  codegen::CompiledFunction function_;
  rpc::GetFunctionReply layout_;
  std::vector<std::uint32_t> in_offsets_, out_offsets_;  // start of each block
  std::size_t work_size_ = 0;
  robodiff_eval_fn eval_ = nullptr;
};

}  // namespace robodiff::client::detail
