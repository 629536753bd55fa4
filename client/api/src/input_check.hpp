#pragma once
// The checks the server makes on Evaluate / EvaluateBatch inputs (server/service
// input_check.cpp), made here for Local evaluation with the same statuses and messages,
// so that every mode answers a wrong call the same way.

#include <cstdint>
#include <span>
#include <string_view>
#include <vector>

#include "robodiff/schema/messages.hpp"

namespace robodiff::client::detail {

// Doubles per knot and block offsets of a function's layout.
struct BlockOffsets {
  std::vector<std::uint32_t> inputs;   // blocks + 1
  std::vector<std::uint32_t> outputs;  // blocks + 1
  std::uint32_t input_count = 0, output_count = 0;

  static BlockOffsets of(const rpc::GetFunctionReply& layout);
};

// INVALID_ARGUMENT naming what was expected and what was given; OK when the sizes fit.
Status checkSizes(std::string_view function_id, const rpc::GetFunctionReply& layout, const BlockOffsets& offsets,
                  std::uint64_t knots, std::size_t inputs, std::size_t outputs, bool batch);

// INVALID_ARGUMENT naming the first input (block, index, knot) that is NaN or infinite.
Status checkFinite(const rpc::GetFunctionReply& layout, const BlockOffsets& offsets, std::span<const double> inputs,
                   bool batch);

// True when every value is finite: the cheap test done first on the hot path.
inline bool allFinite(std::span<const double> values) {
  // x - x is 0 for finite x and NaN for NaN or inf; summing keeps the loop branch-free.
  double acc = 0;
  for (const double v : values) acc += v - v;
  return acc == 0;
}

}  // namespace robodiff::client::detail
