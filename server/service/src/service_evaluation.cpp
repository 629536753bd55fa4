// The hot path: shape, Evaluate and EvaluateBatch. A lookup under a shared lock, one
// atomic load of the evaluator, checks that allocate nothing unless they fail, and work
// buffers per thread (grown to the largest function seen, then reused).
#include <algorithm>
#include <cstring>

#include "robodiff/language/bounded_text.hpp"
#include "robodiff/runtime/input_check.hpp"
#include "output_check.hpp"
#include "robodiff/server/service.hpp"
#include "service_state.hpp"

namespace robodiff::server {
namespace {

using detail::Evaluator;
using detail::FunctionEntry;
using detail::FunctionLayout;

// A batch is cut into pieces of at least this many knots (fewer: the hand-over to
// another thread costs more than the knots).
constexpr std::uint64_t kMinPieceKnots = 16;
// Pieces per thread: enough for threads that finish early to take more.
constexpr std::uint64_t kPiecesPerThread = 4;
// At most this many knots a piece: keeps the per-thread regrouping buffers small (they
// stay allocated) and the deadline checks frequent.
constexpr std::uint64_t kMaxPieceKnots = 256;

// This thread's buffers: the evaluator's work, and for batches the knots regrouped block
// after block (abi.h's batched layout) on their way in and out.
struct ThreadBuffers {
  std::vector<double> work, in, out;
  std::vector<const double*> in_ptr;
  std::vector<double*> out_ptr;
};
thread_local ThreadBuffers buffers;

double* grown(std::vector<double>& v, std::size_t n) {
  if (v.size() < n) v.resize(n);
  return v.data();
}

// The function and its evaluator, or why it cannot be evaluated.
Status servable(const detail::Registry& registry, std::string_view id, std::shared_ptr<FunctionEntry>& function,
                std::shared_ptr<const Evaluator>& evaluator) {
  function = registry.findFunction(id);
  if (!function)
    return {StatusCode::NotFound, "unknown function id " + language::boundedText(id) +
                                      " (never loaded on this server, released, or failed to build: a failed "
                                      "function is unloaded); call GetFunction first"};
  evaluator = function->evaluator();
  if (evaluator) return {};
  if (function->state() == rpc::FunctionState::Failed)
    return {StatusCode::FailedPrecondition,
            "function " + std::string(id) + " failed to build: " + function->failure().message};
  return {StatusCode::FailedPrecondition,
          "function " + std::string(id) + " is still being built; call GetFunction with wait"};
}

// `knots` knots (knot after knot, as the transport holds them) through the batched entry
// point (block after block).
void evaluatePiece(const Evaluator& e, const FunctionLayout& layout, const double* in, double* out,
                   std::uint64_t knots) {
  ThreadBuffers& b = buffers;
  const std::size_t n_in = layout.inputs.size(), n_out = layout.outputs.size();
  if (b.in_ptr.size() < n_in) b.in_ptr.resize(n_in);
  if (b.out_ptr.size() < n_out) b.out_ptr.resize(n_out);
  double* work = grown(b.work, e.batchWorkSize());

  // One block: knot-major and block-major are the same layout.
  if (n_in == 1) {
    b.in_ptr[0] = in;
  } else if (n_in > 1) {
    double* grouped = grown(b.in, knots * layout.input_count);
    for (std::size_t blk = 0; blk < n_in; ++blk) b.in_ptr[blk] = grouped + knots * layout.input_offsets[blk];
    for (std::uint64_t k = 0; k < knots; ++k) {
      const double* knot = in + k * layout.input_count;
      for (std::size_t blk = 0; blk < n_in; ++blk) {
        const std::uint32_t size = layout.inputs[blk].size;
        std::memcpy(grouped + knots * layout.input_offsets[blk] + k * size, knot + layout.input_offsets[blk],
                    size * sizeof(double));
      }
    }
  }
  if (n_out == 1) {
    b.out_ptr[0] = out;
  } else if (n_out > 1) {
    double* grouped = grown(b.out, knots * layout.output_count);
    for (std::size_t blk = 0; blk < n_out; ++blk) b.out_ptr[blk] = grouped + knots * layout.output_offsets[blk];
  }

  e.evaluateBatch(knots, b.in_ptr.data(), b.out_ptr.data(), work);

  if (n_out > 1) {
    for (std::uint64_t k = 0; k < knots; ++k) {
      double* knot = out + k * layout.output_count;
      for (std::size_t blk = 0; blk < n_out; ++blk) {
        const std::uint32_t size = layout.outputs[blk].nnz;
        std::memcpy(knot + layout.output_offsets[blk], b.out_ptr[blk] + k * size, size * sizeof(double));
      }
    }
  }
}

}  // namespace

Status Service::shape(std::string_view function_id, FunctionShape& shape) {
  State& s = *state_;
  std::shared_ptr<FunctionEntry> function;
  std::shared_ptr<const Evaluator> evaluator;
  if (Status st = servable(s.registry, function_id, function, evaluator); !st.ok()) return st;
  shape.input_count = evaluator->layout().input_count;
  shape.output_count = evaluator->layout().output_count;
  shape.max_batch_knots = s.options.max_batch_knots;
  return {};
}

Status Service::evaluate(const CallContext& ctx, std::string_view function_id, std::span<const double> inputs,
                         std::span<double> outputs) {
  State& s = *state_;
  const InFlight in_flight(s.in_flight);
  const auto started = Clock::now();
  if (ctx.expired()) return detail::deadlineExceeded(ctx, "Evaluate");
  std::shared_ptr<FunctionEntry> function;
  std::shared_ptr<const Evaluator> evaluator;
  if (Status st = servable(s.registry, function_id, function, evaluator); !st.ok()) return st;
  const FunctionLayout& layout = evaluator->layout();
  if (Status st = runtime::checkSizes(function_id, layout, 1, inputs.size(), outputs.size(), false); !st.ok()) return st;
  if (Status st = runtime::checkFinite(layout, inputs, false); !st.ok()) return st;

  ThreadBuffers& b = buffers;
  const std::size_t n_in = layout.inputs.size(), n_out = layout.outputs.size();
  if (b.in_ptr.size() < n_in) b.in_ptr.resize(n_in);
  if (b.out_ptr.size() < n_out) b.out_ptr.resize(n_out);
  for (std::size_t blk = 0; blk < n_in; ++blk) b.in_ptr[blk] = inputs.data() + layout.input_offsets[blk];
  for (std::size_t blk = 0; blk < n_out; ++blk) b.out_ptr[blk] = outputs.data() + layout.output_offsets[blk];
  evaluator->evaluate(b.in_ptr.data(), b.out_ptr.data(), grown(b.work, evaluator->workSize()));
  function->countEvaluations(1);
  function->recordCall(static_cast<std::uint64_t>(
      std::chrono::duration_cast<std::chrono::nanoseconds>(Clock::now() - started).count()));
  return detail::checkFiniteOutputs(layout, outputs, false);
}

// On DEADLINE_EXCEEDED the knots of the pieces finished before the deadline are written;
// on any other error the outputs are untouched.
Status Service::evaluateBatch(const CallContext& ctx, std::string_view function_id, std::uint64_t knots,
                              std::span<const double> inputs, std::span<double> outputs) {
  State& s = *state_;
  const InFlight in_flight(s.in_flight);
  const auto started = Clock::now();
  if (ctx.expired()) return detail::deadlineExceeded(ctx, "EvaluateBatch");
  std::shared_ptr<FunctionEntry> function;
  std::shared_ptr<const Evaluator> evaluator;
  if (Status st = servable(s.registry, function_id, function, evaluator); !st.ok()) return st;
  if (knots > s.options.max_batch_knots)
    return {StatusCode::ResourceExhausted, std::to_string(knots) +
                                               " knots in one EvaluateBatch, more than this server "
                                               "takes (max_batch_knots = " +
                                               std::to_string(s.options.max_batch_knots) + "); split the batch"};
  const FunctionLayout& layout = evaluator->layout();
  if (Status st = runtime::checkSizes(function_id, layout, knots, inputs.size(), outputs.size(), true); !st.ok())
    return st;
  if (Status st = runtime::checkFinite(layout, inputs, true); !st.ok()) return st;
  if (knots == 0) return {};

  // Pieces: a multiple of the batched entry point's width, about kPiecesPerThread per thread.
  const unsigned threads = s.batch.threads();
  const std::uint64_t width = std::max<std::uint32_t>(1, evaluator->batchWidth());
  std::uint64_t piece = (knots + threads * kPiecesPerThread - 1) / (threads * kPiecesPerThread);
  piece = std::clamp(piece, kMinPieceKnots, kMaxPieceKnots);
  piece = (piece + width - 1) / width * width;
  const std::uint64_t pieces = (knots + piece - 1) / piece;

  std::atomic<bool> expired{false};
  std::atomic<std::uint64_t> done{0};
  auto run = [&](std::uint64_t i) {
    if (expired.load(std::memory_order_relaxed) || ctx.expired()) {
      expired.store(true, std::memory_order_relaxed);
      return;
    }
    const std::uint64_t first = i * piece;
    const std::uint64_t count = std::min(piece, knots - first);
    evaluatePiece(*evaluator, layout, inputs.data() + first * layout.input_count,
                  outputs.data() + first * layout.output_count, count);
    done.fetch_add(count, std::memory_order_relaxed);
  };
  if (pieces == 1)
    run(0);
  else
    s.batch.run(pieces, threads - 1, run);

  function->countEvaluations(done.load());
  function->recordBatch(done.load(), static_cast<std::uint64_t>(std::chrono::duration_cast<std::chrono::nanoseconds>(
                                         Clock::now() - started).count()));
  if (expired.load())
    return {StatusCode::DeadlineExceeded, "EvaluateBatch: the deadline passed after " + std::to_string(done.load()) +
                                              " of " + std::to_string(knots) + " knots"};
  return detail::checkFiniteOutputs(layout, outputs.first(knots * layout.output_count), true);
}

}  // namespace robodiff::server
