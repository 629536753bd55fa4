// The assembly's operations reordered for a short critical path (docs/assembly-backend.md):
// a list schedule on a model of the core's pipes, the operation with the longest chain
// of latencies to the function's end first among those ready.
#pragma once

#include "asm_program.hpp"

namespace robodiff::codegen::detail {

// Reorders program.ops (the values stay as they are) where the chains of latencies bound
// the function; false where it keeps its order (the pipes bound it, or sin-cos regions
// in its body).
bool scheduleForLatency(AsmProgram& program);

}  // namespace robodiff::codegen::detail
