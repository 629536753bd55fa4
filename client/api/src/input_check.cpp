#include "input_check.hpp"

#include <algorithm>
#include <cmath>
#include <string>

namespace robodiff::client::detail {

BlockOffsets BlockOffsets::of(const rpc::GetFunctionReply& layout) {
  BlockOffsets o;
  o.inputs.assign(1, 0);
  for (const rpc::InputBlock& b : layout.inputs) o.inputs.push_back(o.inputs.back() + b.size);
  o.outputs.assign(1, 0);
  for (const rpc::OutputBlock& b : layout.outputs) o.outputs.push_back(o.outputs.back() + b.nnz);
  o.input_count = o.inputs.back();
  o.output_count = o.outputs.back();
  return o;
}

Status checkSizes(std::string_view function_id, const rpc::GetFunctionReply& layout, const BlockOffsets& offsets,
                  std::uint64_t knots, std::size_t inputs, std::size_t outputs, bool batch) {
  const std::uint64_t want_in = knots * offsets.input_count;
  const std::uint64_t want_out = knots * offsets.output_count;
  if (inputs == want_in && outputs == want_out) return {};
  const std::string per_knot = batch ? " (" + std::to_string(knots) + " knots of " : " (";
  auto describe = [&](const char* what, std::uint64_t want, std::size_t given, std::uint32_t count) {
    return std::string(what) + ": expected " + std::to_string(want) + " doubles" + per_knot + std::to_string(count) +
           (batch ? " each)" : " per knot)") + ", given " + std::to_string(given);
  };
  std::string message = "function " + std::string(function_id) + " ";
  if (inputs != want_in) message += describe("inputs", want_in, inputs, offsets.input_count);
  if (inputs != want_in && outputs != want_out) message += "; ";
  if (outputs != want_out) message += describe("outputs", want_out, outputs, offsets.output_count);
  if (inputs != want_in) {
    message += "; the input blocks are";
    for (const rpc::InputBlock& b : layout.inputs) message += " " + b.name + "[" + std::to_string(b.size) + "]";
  }
  return {StatusCode::InvalidArgument, message};
}

Status checkFinite(const rpc::GetFunctionReply& layout, const BlockOffsets& offsets, std::span<const double> inputs,
                   bool batch) {
  std::size_t i = 0;
  const std::size_t n = inputs.size();
  for (; i < n; ++i)
    if (!std::isfinite(inputs[i])) break;
  if (i == n) return {};
  const std::uint32_t count = offsets.input_count;
  const std::uint64_t knot = count == 0 ? 0 : i / count;
  const auto within = static_cast<std::uint32_t>(count == 0 ? 0 : i % count);
  const auto it = std::upper_bound(offsets.inputs.begin(), offsets.inputs.end(), within);
  const std::size_t block = static_cast<std::size_t>(it - offsets.inputs.begin()) - 1;
  const std::uint32_t index = within - offsets.inputs[block];
  const double value = inputs[i];
  std::string message = "input " + layout.inputs[block].name + "[" + std::to_string(index) + "]";
  if (batch) message += " of knot " + std::to_string(knot);
  message += std::string(" is ") +
             (std::isnan(value) ? "NaN"
              : value > 0       ? "+inf"
                                : "-inf") +
             ": every input must be a finite number";
  return {StatusCode::InvalidArgument, message};
}

}  // namespace robodiff::client::detail
