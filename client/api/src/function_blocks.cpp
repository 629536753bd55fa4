// Function::evaluateBlocks: knots whose input and output blocks each live in their own
// array (as numpy holds them). In process the arrays go to the library as they are; for
// a server, or for inputs to refuse, they are packed knot after knot and take evaluate's
// path (its checks and messages).
#include <cstring>
#include <vector>

#include "client_impl.hpp"
#include "robodiff/runtime/input_check.hpp"

namespace robodiff::client {
namespace {

std::size_t blockSize(const std::vector<std::uint32_t>& offsets, std::size_t b) { return offsets[b + 1] - offsets[b]; }

bool blocksFinite(const runtime::FunctionLayout& l, std::size_t knots, std::span<const double* const> inputs) {
  for (std::size_t b = 0; b < inputs.size(); ++b)
    if (!runtime::allFinite({inputs[b], knots * blockSize(l.input_offsets, b)})) return false;
  return true;
}

void pack(const runtime::FunctionLayout& l, std::size_t knots, std::span<const double* const> inputs,
          std::vector<double>& packed) {
  packed.resize(knots * l.input_count);
  for (std::size_t b = 0; b < inputs.size(); ++b) {
    const std::size_t size = blockSize(l.input_offsets, b);
    for (std::size_t k = 0; k < knots; ++k)
      std::memcpy(packed.data() + k * l.input_count + l.input_offsets[b], inputs[b] + k * size, size * sizeof(double));
  }
}

void unpack(const runtime::FunctionLayout& l, std::size_t knots, const std::vector<double>& packed,
            std::span<double* const> outputs) {
  for (std::size_t b = 0; b < outputs.size(); ++b) {
    const std::size_t size = blockSize(l.output_offsets, b);
    for (std::size_t k = 0; k < knots; ++k)
      std::memcpy(outputs[b] + k * size, packed.data() + k * l.output_count + l.output_offsets[b], size * sizeof(double));
  }
}

}  // namespace

Status Function::evaluateBlocks(std::size_t knots, std::span<const double* const> inputs,
                                std::span<double* const> outputs, bool batch) const {
  if (!impl_) return evaluate({}, {});  // the empty handle's status
  const Impl& f = *impl_;
  const std::size_t n = batch ? knots : 1;
  const detail::LocalEvaluator* local = f.local.load(std::memory_order_acquire);
  if (local == nullptr) [[unlikely]] {
    impl_->maybeSwitchToLocal();
    local = f.local.load(std::memory_order_acquire);
  }
  if (local != nullptr && blocksFinite(f.blocks, n, inputs)) [[likely]] {
    local->evaluateBlocks(n, inputs.data(), outputs.data(), batch);
    return {};
  }
  thread_local std::vector<double> in, out;  // grows to a thread's largest call, then reused
  pack(f.blocks, n, inputs, in);
  out.resize(n * f.blocks.output_count);
  const Status s = batch ? evaluateBatch(n, in, out) : evaluate(in, out);
  if (s.ok()) unpack(f.blocks, n, out, outputs);
  return s;
}

}  // namespace robodiff::client
