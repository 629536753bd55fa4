// A user function's spec JSON from its parsed form: what parseFunctionSpec reads back to
// the same function (the same normalizedSpecJson, so the same cache key). The canonical
// form (user_function_canonical.hpp) is a key, not a spec; this is what is sent to a
// process that builds the function from the spec alone (a robodiff-worker).
#pragma once

#include <string>

#include "robodiff/functions/function_spec.hpp"

namespace robodiff::detail {

std::string userFunctionSpecJson(const FunctionSpec& spec);

}  // namespace robodiff::detail
