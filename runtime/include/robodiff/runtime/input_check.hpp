#pragma once
// Evaluation's argument checks (the server's, and a client's in local mode, so that every
// mode answers a wrong call with the same status and message), with messages that name the problem: sizes (expected and
// given) and the first NaN or infinite input (its block, its index within the block, and
// for a batch its knot). Nothing is allocated unless a check fails.

#include <cstdint>
#include <span>
#include <string_view>

#include "robodiff/runtime/function_layout.hpp"
#include "robodiff/schema/status.hpp"

namespace robodiff::runtime {

Status checkSizes(std::string_view function_id, const FunctionLayout& layout, std::uint64_t knots, std::size_t inputs,
                  std::size_t outputs, bool batch);

// `inputs` holds knot after knot (input_count doubles each).
Status checkFinite(const FunctionLayout& layout, std::span<const double> inputs, bool batch);

// True when every value is finite: the cheap, branch-free test made first on a hot path
// (x - x is 0 for a finite x, NaN for NaN or inf), checkFinite then says which.
inline bool allFinite(std::span<const double> values) {
  double acc = 0;
  for (const double v : values) acc += v - v;
  return acc == 0;
}

}  // namespace robodiff::runtime
