#pragma once
// Whether this CPU may run a cached library, decided from what the cache's index recorded
// (the " target=<label>" that ends EntryInfo::compiler, cache_key.hpp's targetLabel)
// before the library is opened: code for an x86-64 level this CPU lacks, or built with
// -march=native on another CPU, would die of an illegal instruction in the first call.

#include <string>

namespace robodiff::cache {

// The problem ("built for x86-64-v4, which this CPU does not support"), or empty when the
// library may run here. An entry that records no target (made before targets were
// recorded) was keyed with this CPU's identity and may run.
std::string targetProblem(const std::string& entry_compiler);

// True when this CPU supports the x86-64 level ("x86-64-v2" .. "x86-64-v4").
bool cpuSupportsLevel(const std::string& level);

}  // namespace robodiff::cache
