#include "options/cache_location.hpp"

#include "output/human_units.hpp"

namespace robodiff::cli {

std::filesystem::path cacheDirFor(const std::string& cache_flag) {
  return cache_flag.empty() ? cache::defaultCacheDir() : std::filesystem::path(cache_flag);
}

cache::Cache openCliCache(const std::filesystem::path& dir, const std::string& budget_flag, bool create,
                          bool repair_empty_index) {
  cache::CacheOptions options;
  options.create = create;
  options.repair_empty_index = repair_empty_index;
  if (!budget_flag.empty()) options.budget_bytes = parseSize(budget_flag);
  try {
    return cache::Cache::open(dir, options);
  } catch (const cache::CacheError& e) {
    const std::string message = e.what();
    if (message.find(dir.string()) != std::string::npos) throw;
    throw cache::CacheError(e.kind(), "cache " + dir.string() + ": " + message);
  }
}

}  // namespace robodiff::cli
