// Outputs that are not finite numbers: the model or the inputs give NaN or inf (e.g. a
// singular mass matrix), which a caller must not take for a result.
#pragma once

#include <span>

#include "robodiff/runtime/function_layout.hpp"
#include "robodiff/schema/status.hpp"

namespace robodiff::server::detail {

// One pass over the outputs: OK when all are finite, else OUT_OF_RANGE naming the first
// non-finite one (output block, entry and, for a batch, the knot) and how many there are.
Status checkFiniteOutputs(const runtime::FunctionLayout& layout, std::span<const double> outputs, bool batch);

}  // namespace robodiff::server::detail
