// The text every generated translation unit starts with: includes, attribute macros,
// the pair type of single-knot code and the batched entry point's vector helpers.
#pragma once

#include <string>

#include "robodiff/codegen/c_emitter.hpp"

namespace robodiff::codegen::detail {

std::string prologue(const CodegenOptions& options);

}  // namespace robodiff::codegen::detail
