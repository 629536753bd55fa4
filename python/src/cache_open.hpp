#pragma once
// Opening the cache for warmup and robodiff.cache (cache_binding.cpp), with errors that
// name the directory, as the CLI's --cache does.
#include <filesystem>
#include <optional>

#include "robodiff/cache/cache.hpp"

namespace robodiff::python {

// dir, or the default cache (cache::defaultCacheDir: $ROBODIFF_CACHE_DIR, ...).
std::filesystem::path cacheDirOr(const std::optional<std::filesystem::path>& dir);

// Opens the cache in dir (created 0700 when `create`). Throws client::ClientError
// FAILED_PRECONDITION "cache DIR: ..." for a directory that cannot be used.
cache::Cache openCache(const std::filesystem::path& dir, bool create);

}  // namespace robodiff::python
