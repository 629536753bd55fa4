#pragma once
// Opening a cache artifact's compiled function, checked against what the cache's index
// recorded for it (its C name, its block sizes) before anything in it is called.

#include "robodiff/cache/cache.hpp"
#include "robodiff/codegen/loaded_library.hpp"
#include "robodiff/functions/function_spec.hpp"

namespace robodiff::runtime {

// Throws codegen::LoadError naming what differs.
codegen::CompiledFunction openCachedFunction(const cache::Artifact& artifact, const FunctionSpec& spec);

}  // namespace robodiff::runtime
