#include "robodiff/runtime/input_check.hpp"

#include <cmath>
#include <string>

namespace robodiff::runtime {

Status checkSizes(std::string_view function_id, const FunctionLayout& layout, std::uint64_t knots, std::size_t inputs,
                  std::size_t outputs, bool batch) {
  const std::uint64_t want_in = knots * layout.input_count;
  const std::uint64_t want_out = knots * layout.output_count;
  if (inputs == want_in && outputs == want_out) return {};
  const std::string per_knot = batch ? " (" + std::to_string(knots) + " knots of " : " (";
  auto describe = [&](const char* what, std::uint64_t want, std::size_t given, std::uint32_t count) {
    return std::string(what) + ": expected " + std::to_string(want) + " doubles" + per_knot + std::to_string(count) +
           (batch ? " each)" : " per knot)") + ", given " + std::to_string(given);
  };
  std::string message = "function " + std::string(function_id) + " ";
  if (inputs != want_in) message += describe("inputs", want_in, inputs, layout.input_count);
  if (inputs != want_in && outputs != want_out) message += "; ";
  if (outputs != want_out) message += describe("outputs", want_out, outputs, layout.output_count);
  if (inputs != want_in) {
    message += "; the input blocks are";
    for (const rpc::InputBlock& b : layout.inputs) message += " " + b.name + "[" + std::to_string(b.size) + "]";
  }
  return {StatusCode::InvalidArgument, message};
}

Status checkFinite(const FunctionLayout& layout, std::span<const double> inputs, bool batch) {
  std::size_t i = 0;
  const std::size_t n = inputs.size();
  for (; i < n; ++i)
    if (!std::isfinite(inputs[i])) break;
  if (i == n) return {};
  const std::uint64_t knot = layout.input_count == 0 ? 0 : i / layout.input_count;
  const auto within = static_cast<std::uint32_t>(layout.input_count == 0 ? 0 : i % layout.input_count);
  const std::size_t block = layout.inputBlockOf(within);
  const std::uint32_t index = within - layout.input_offsets[block];
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

}  // namespace robodiff::runtime
