#pragma once
// A cache entry as JSON: every field of an index row, the spec and sizes (JSON text in
// the index) embedded as JSON. What `robodiff cache ls --json` prints and what the Python
// module's robodiff.cache.ls() returns, so that both show the same thing.
#include <nlohmann/json.hpp>

#include "robodiff/cache/cache.hpp"

namespace robodiff::cache {

// {"key", "robot", "function", "state", "model_hash", "spec", "sizes", "compiler",
//  "build_seconds", "library_bytes", "total_bytes", "library_sha256", "created",
//  "last_used", "hits", "owner", "lease_expires_ms"}; times in unix seconds (the lease in
// milliseconds).
nlohmann::json entryJson(const Entry& entry);

}  // namespace robodiff::cache
