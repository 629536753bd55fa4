#pragma once
// Evaluation's argument checks, with messages that name the problem: sizes (expected and
// given) and the first NaN or infinite input (its block, its index within the block, and
// for a batch its knot). Nothing is allocated unless a check fails.

#include <cstdint>
#include <span>
#include <string_view>

#include "function_layout.hpp"
#include "robodiff/schema/status.hpp"

namespace robodiff::server::detail {

Status checkSizes(std::string_view function_id, const FunctionLayout& layout, std::uint64_t knots, std::size_t inputs,
                  std::size_t outputs, bool batch);

// `inputs` holds knot after knot (input_count doubles each).
Status checkFinite(const FunctionLayout& layout, std::span<const double> inputs, bool batch);

}  // namespace robodiff::server::detail
