// The canonical form of a user function, part of the cache key: defines are inlined
// into one shared graph of terms (so renaming a define, the order of the "define"
// object and whitespace change nothing), numbers are printed exactly, shapes named in
// distance() are replaced by their geometry. The inputs' order, the outputs' order and
// names stay: they are the generated function's calling convention.
#pragma once

#include <string>

#include "robodiff/functions/function_spec.hpp"

namespace robodiff::detail {

std::string canonicalUserFunctionJson(const FunctionSpec& spec);

}  // namespace robodiff::detail
