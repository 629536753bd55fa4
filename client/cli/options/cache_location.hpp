// The cache the `warmup` and `cache` commands work on: --cache DIR, else the default
// (cache::defaultCacheDir), opened with --budget when given; errors name the directory.
#pragma once

#include <filesystem>
#include <string>

#include "robodiff/cache/cache.hpp"

namespace robodiff::cli {

std::filesystem::path cacheDirFor(const std::string& cache_flag);

// Opens (creating it when `create`) the cache in dir. Throws cache::CacheError whose
// message names dir.
// `repair_empty_index`: as cache::CacheOptions (off for `cache repair`, which reports it).
cache::Cache openCliCache(const std::filesystem::path& dir, const std::string& budget_flag, bool create,
                          bool repair_empty_index = true);

}  // namespace robodiff::cli
