#include "local_evaluator.hpp"

#include <algorithm>
#include <cstring>

#include "robodiff/runtime/cached_function.hpp"
#include "robodiff/runtime/function_layout.hpp"

namespace robodiff::client::detail {
namespace {

// A batched call regroups about this many doubles (its knots' inputs and outputs): small
// enough to stay in L2 with the library's work, large enough that per-call costs vanish.
constexpr std::uint64_t kChunkDoubles = 32768;  // 256 KiB
constexpr std::uint64_t kMaxChunkWidths = 32;

std::vector<std::uint32_t> sizesOf(const std::vector<std::uint32_t>& offsets) {
  std::vector<std::uint32_t> sizes(offsets.size() - 1);
  for (std::size_t b = 0; b + 1 < offsets.size(); ++b) sizes[b] = offsets[b + 1] - offsets[b];
  return sizes;
}

}  // namespace

LocalEvaluator::LocalEvaluator(cache::Artifact artifact, const FunctionSpec& spec)
    : artifact_(std::move(artifact)), function_(runtime::openCachedFunction(artifact_, spec)) {
  const robodiff_function_desc& d = function_.descriptor();
  // The same layout the server makes from the same descriptor (throws when the blocks do
  // not match the spec's outputs).
  const runtime::FunctionLayout blocks = runtime::FunctionLayout::fromDescriptor(d, spec);
  layout_.inputs = blocks.inputs;
  layout_.outputs = blocks.outputs;
  layout_.state = rpc::FunctionState::Ready;
  in_offsets_.assign(blocks.input_offsets.begin(), blocks.input_offsets.end() - 1);
  out_offsets_.assign(blocks.output_offsets.begin(), blocks.output_offsets.end() - 1);
  in_sizes_ = sizesOf(blocks.input_offsets);
  out_sizes_ = sizesOf(blocks.output_offsets);
  in_count_ = blocks.input_count;
  out_count_ = blocks.output_count;
  work_size_ = function_.workSize();
  eval_ = d.eval;
  eval_batch_ = d.eval_batch;  // never null: the loader checks the descriptor
  width_ = std::max<std::uint32_t>(function_.batchWidth(), 1);
  batch_work_size_ = width_ > 1 ? function_.batchWorkSize() : 0;
  const std::uint64_t per_width = std::uint64_t{width_} * std::max<std::size_t>(in_count_ + out_count_, 1);
  chunk_knots_ = std::clamp<std::uint64_t>(kChunkDoubles / per_width, 1, kMaxChunkWidths) * width_;
}

std::string LocalEvaluator::differenceFrom(const rpc::GetFunctionReply& other) const {
  return runtime::FunctionLayout::fromReply(layout_).differenceFrom(runtime::FunctionLayout::fromReply(other));
}

void LocalEvaluator::evaluateBatch(std::uint64_t knots, const double* in, double* out) const noexcept {
  if (width_ <= 1) {  // the batched entry would be this same loop, plus the regrouping
    for (std::uint64_t k = 0; k < knots; ++k) evaluate(in + k * in_count_, out + k * out_count_);
    return;
  }
  ThreadBuffers& t = threadBuffers();
  // Sized for a whole chunk at once, so a later, longer batch allocates nothing either.
  t.reserveFor(std::max(work_size_, batch_work_size_), in_offsets_.size(), out_offsets_.size());
  t.reserveBatch(in_offsets_.size() > 1 ? chunk_knots_ * in_count_ : 0,
                 out_offsets_.size() > 1 ? chunk_knots_ * out_count_ : 0);
  for (std::uint64_t first = 0; first < knots; first += chunk_knots_)
    evaluateChunk(std::min(chunk_knots_, knots - first), in + first * in_count_, out + first * out_count_, t);
}

void LocalEvaluator::evaluateBlocks(std::uint64_t knots, const double* const* in, double* const* out,
                                    bool batch) const noexcept {
  ThreadBuffers& t = threadBuffers();
  t.reserveFor(std::max(work_size_, batch_work_size_), in_offsets_.size(), out_offsets_.size());
  if (!batch) {
    eval_(in, out, t.work.data());
  } else if (width_ > 1) {
    eval_batch_(knots, in, out, t.work.data());
  } else {  // a plain loop: point at each knot in turn
    const double** ip = t.in.data();
    double** op = t.out.data();
    for (std::uint64_t k = 0; k < knots; ++k) {
      for (std::size_t b = 0; b < in_offsets_.size(); ++b) ip[b] = in[b] + k * in_sizes_[b];
      for (std::size_t b = 0; b < out_offsets_.size(); ++b) op[b] = out[b] + k * out_sizes_[b];
      eval_(ip, op, t.work.data());
    }
  }
}

// n knots: regroup the inputs (one block: knot after knot already is block after block),
// one batched call, the outputs back knot after knot.
void LocalEvaluator::evaluateChunk(std::uint64_t n, const double* in, double* out, ThreadBuffers& t) const noexcept {
  const std::size_t n_in = in_offsets_.size(), n_out = out_offsets_.size();
  const double** ip = t.in.data();
  double** op = t.out.data();
  if (n_in == 1) {
    ip[0] = in;
  } else {
    double* grouped = t.batch_in.data();
    for (std::size_t b = 0; b < n_in; ++b) ip[b] = grouped + n * in_offsets_[b];
    for (std::uint64_t k = 0; k < n; ++k)
      for (std::size_t b = 0; b < n_in; ++b)
        std::memcpy(grouped + n * in_offsets_[b] + k * in_sizes_[b], in + k * in_count_ + in_offsets_[b],
                    in_sizes_[b] * sizeof(double));
  }
  if (n_out == 1) {
    op[0] = out;
  } else {
    for (std::size_t b = 0; b < n_out; ++b) op[b] = t.batch_out.data() + n * out_offsets_[b];
  }
  eval_batch_(n, ip, op, t.work.data());
  if (n_out > 1)
    for (std::uint64_t k = 0; k < n; ++k)
      for (std::size_t b = 0; b < n_out; ++b)
        std::memcpy(out + k * out_count_ + out_offsets_[b], op[b] + k * out_sizes_[b], out_sizes_[b] * sizeof(double));
}

}  // namespace robodiff::client::detail
