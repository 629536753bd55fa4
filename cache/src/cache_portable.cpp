// Cache::findPortable: an entry by its portable key (cache_key.hpp), for hosts that cannot
// compute the full key because they lack the build host's compiler.
#include <stdexcept>

#include "cache_state.hpp"
#include "robodiff/cache/cache.hpp"
#include "robodiff/cache/cache_key.hpp"
#include "robodiff/cache/target_check.hpp"

namespace robodiff::cache {

std::optional<Artifact> Cache::findPortable(const std::string& portable_key) {
  // A key is 64 hex digits, so it can stand in the query's text.
  if (!isCacheKey(portable_key))
    throw std::invalid_argument("not a portable key (64 lowercase hex digits): \"" + portable_key + "\"");
  std::vector<Entry> rows;
  {
    std::lock_guard lock(state_->mutex);
    const std::string where = "WHERE state = 'ready' AND portable_key = '" + portable_key + "' ORDER BY last_used DESC, key";
    rows = state_->db->entries(where.c_str());
  }
  for (const Entry& row : rows) {
    if (!targetProblem(row.info.compiler).empty()) continue;  // for another CPU
    if (std::optional<Artifact> artifact = find(row.key)) return artifact;
  }
  return std::nullopt;
}

}  // namespace robodiff::cache
