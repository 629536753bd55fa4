// Function: the handle controllers evaluate through, Local or remote.
#include <stdexcept>

#include "client_impl.hpp"
#include "robodiff/runtime/input_check.hpp"

namespace robodiff::client {
namespace {

const Status kEmpty{StatusCode::FailedPrecondition, "an empty Function (default-constructed): get one from Client::function"};

Function::Impl& checked(const std::shared_ptr<Function::Impl>& impl) {
  if (!impl) throw ClientError(kEmpty);
  return *impl;
}

}  // namespace

const std::string& Function::id() const { return checked(impl_).id; }
const rpc::GetFunctionReply& Function::layout() const { return checked(impl_).layout; }
std::size_t Function::inputCount() const { return checked(impl_).blocks.input_count; }
std::size_t Function::outputCount() const { return checked(impl_).blocks.output_count; }
Mode Function::mode() const { return checked(impl_).mode(); }

Status Function::Impl::evaluateLocal(const detail::LocalEvaluator& evaluator, std::uint64_t knots,
                                     std::span<const double> inputs, std::span<double> outputs, bool batch) const {
  const std::uint32_t in_n = blocks.input_count, out_n = blocks.output_count;
  if (inputs.size() != knots * in_n || outputs.size() != knots * out_n) [[unlikely]]
    return runtime::checkSizes(id, blocks, knots, inputs.size(), outputs.size(), batch);
  if (!runtime::allFinite(inputs)) [[unlikely]]
    return runtime::checkFinite(blocks, inputs, batch);
  if (batch)
    evaluator.evaluateBatch(knots, inputs.data(), outputs.data());  // the library's batched entry point
  else
    evaluator.evaluate(inputs.data(), outputs.data());
  return {};
}

Status Function::Impl::evaluateRemote(std::uint64_t knots, std::span<const double> inputs, std::span<double> outputs,
                                      bool batch, std::chrono::nanoseconds timeout) {
  Client::Impl& c = *client;
  // Sizes are checked here as in Local mode: the transports do not send the output size,
  // so the server could not say that the outputs do not fit.
  if (inputs.size() != knots * blocks.input_count || outputs.size() != knots * blocks.output_count)
    return runtime::checkSizes(id, blocks, knots, inputs.size(), outputs.size(), batch);
  if (!c.connection) return c.noServer();
  const CallOptions options = c.callOptions(timeout);
  auto call = [&] {
    return batch ? c.connection->evaluateBatch(id, knots, inputs, outputs, options)
                 : c.connection->evaluate(id, inputs, outputs, options);
  };
  const std::uint64_t generation = c.generation.load();
  Status s = call();
  if ((s.code == StatusCode::NotFound || s.code == StatusCode::FailedPrecondition) && c.knowsFunction(id)) {
    // A server that does not know this function (a restarted one), or knows it only as
    // still being built (another client registered it there a moment ago): register
    // everything again, which waits until it is ready, then retry once.
    const Status r = c.reregister(generation);
    if (!r.ok()) return r;
    s = call();
  }
  return s;
}

Status Function::evaluate(std::span<const double> inputs, std::span<double> outputs) const {
  if (!impl_) [[unlikely]]
    return kEmpty;
  if (const detail::LocalEvaluator* local = impl_->local.load(std::memory_order_acquire)) [[likely]]
    return impl_->evaluateLocal(*local, 1, inputs, outputs, false);
  impl_->maybeSwitchToLocal();
  if (const detail::LocalEvaluator* local = impl_->local.load(std::memory_order_acquire))
    return impl_->evaluateLocal(*local, 1, inputs, outputs, false);
  return impl_->evaluateRemote(1, inputs, outputs, false, std::chrono::nanoseconds(0));
}

Status Function::evaluate(std::span<const double> inputs, std::span<double> outputs,
                          std::chrono::nanoseconds timeout) const {
  if (!impl_) return kEmpty;
  if (const detail::LocalEvaluator* local = impl_->local.load(std::memory_order_acquire))
    return impl_->evaluateLocal(*local, 1, inputs, outputs, false);
  impl_->maybeSwitchToLocal();
  if (const detail::LocalEvaluator* local = impl_->local.load(std::memory_order_acquire))
    return impl_->evaluateLocal(*local, 1, inputs, outputs, false);
  return impl_->evaluateRemote(1, inputs, outputs, false, timeout);
}

Status Function::evaluateBatch(std::size_t knots, std::span<const double> inputs, std::span<double> outputs,
                               std::chrono::nanoseconds timeout) const {
  if (!impl_) return kEmpty;
  if (const detail::LocalEvaluator* local = impl_->local.load(std::memory_order_acquire))
    return impl_->evaluateLocal(*local, knots, inputs, outputs, true);
  impl_->maybeSwitchToLocal();
  if (const detail::LocalEvaluator* local = impl_->local.load(std::memory_order_acquire))
    return impl_->evaluateLocal(*local, knots, inputs, outputs, true);
  return impl_->evaluateRemote(knots, inputs, outputs, true, timeout);
}

std::future<Status> Function::evaluateAsync(std::span<const double> inputs, std::span<double> outputs) const {
  if (!impl_) {
    std::promise<Status> empty;
    empty.set_value(kEmpty);
    return empty.get_future();
  }
  // The Function is copied into the call, so it outlives this handle if need be.
  return impl_->client->asyncExecutor().submit(*this, inputs, outputs);
}

namespace {

// The block's values in `outputs`, or ClientError naming what does not fit.
const double* blockValues(const Function::Impl& f, std::size_t block, std::span<const double> outputs,
                          rpc::OutputLayout want) {
  auto fail = [&](const std::string& what) -> const double* {
    throw ClientError({StatusCode::InvalidArgument, "function " + f.id + ": " + what});
  };
  if (block >= f.layout.outputs.size())
    return fail("output block " + std::to_string(block) + " does not exist (it has " +
                std::to_string(f.layout.outputs.size()) + ")");
  const rpc::OutputBlock& b = f.layout.outputs[block];
  if (b.layout != want)
    return fail("output block " + b.name + " is " +
                (b.layout == rpc::OutputLayout::SparseCsr ? "sparse: use sparseBlock" : "dense: use denseBlock"));
  if (outputs.size() < f.blocks.output_count)
    return fail("outputs hold " + std::to_string(outputs.size()) + " doubles, one knot has " +
                std::to_string(f.blocks.output_count));
  return outputs.data() + f.blocks.output_offsets[block];
}

}  // namespace

Function::SparseBlock Function::sparseBlock(std::size_t block, std::span<const double> outputs) const {
  const Impl& f = checked(impl_);
  const double* values = blockValues(f, block, outputs, rpc::OutputLayout::SparseCsr);
  const rpc::OutputBlock& b = f.layout.outputs[block];
  return SparseBlock(b.rows, b.cols, b.nnz, f.csr_rows[block].data(), f.csr_cols[block].data(), values);
}

Function::DenseBlock Function::denseBlock(std::size_t block, std::span<const double> outputs) const {
  const Impl& f = checked(impl_);
  const double* values = blockValues(f, block, outputs, rpc::OutputLayout::DenseRowMajor);
  const rpc::OutputBlock& b = f.layout.outputs[block];
  return DenseBlock(values, b.rows, b.cols);
}

Outputs Function::operator()(const std::vector<Eigen::VectorXd>& inputs) const {
  const Impl& f = checked(impl_);
  if (inputs.size() != f.layout.inputs.size()) {
    std::string names;
    for (const rpc::InputBlock& b : f.layout.inputs) names += " " + b.name + "[" + std::to_string(b.size) + "]";
    throw ClientError({StatusCode::InvalidArgument, "function " + f.id + ": expected " +
                                                        std::to_string(f.layout.inputs.size()) +
                                                        " input blocks (" + names.substr(1) + "), given " +
                                                        std::to_string(inputs.size())});
  }
  std::vector<double> in;
  in.reserve(f.blocks.input_count);
  for (std::size_t b = 0; b < inputs.size(); ++b) {
    if (inputs[b].size() != static_cast<Eigen::Index>(f.layout.inputs[b].size))
      throw ClientError({StatusCode::InvalidArgument, "function " + f.id + ": input block " + f.layout.inputs[b].name +
                                                          " has " + std::to_string(f.layout.inputs[b].size) +
                                                          " doubles, given " + std::to_string(inputs[b].size())});
    in.insert(in.end(), inputs[b].data(), inputs[b].data() + inputs[b].size());
  }
  std::vector<double> out(f.blocks.output_count);
  const Status s = evaluate(in, out);
  if (!s.ok()) throw ClientError(s);
  Outputs result;
  for (std::size_t k = 0; k < f.layout.outputs.size(); ++k) {
    const rpc::OutputBlock& b = f.layout.outputs[k];
    const double* values = out.data() + f.blocks.output_offsets[k];
    Eigen::MatrixXd m = Eigen::MatrixXd::Zero(b.rows, b.cols);
    if (b.layout == rpc::OutputLayout::SparseCsr) {
      for (std::uint32_t r = 0; r < b.rows; ++r)
        for (std::uint32_t i = b.row_offsets[r]; i < b.row_offsets[r + 1]; ++i) m(r, b.col_indices[i]) = values[i];
    } else {
      for (std::uint32_t r = 0; r < b.rows; ++r)
        for (std::uint32_t col = 0; col < b.cols; ++col) m(r, col) = values[r * b.cols + col];
    }
    result.blocks.push_back(std::move(m));
  }
  return result;
}

}  // namespace robodiff::client
