// robodiff._robodiff.cache_entries and default_cache_dir: what robodiff.cache (cache.py)
// shows, each entry as `robodiff cache ls --json` prints it (cache::entryJson).
#include <filesystem>
#include <optional>
#include <string>

#include <nanobind/stl/filesystem.h>
#include <nanobind/stl/optional.h>
#include <nanobind/stl/string.h>

#include "bindings.hpp"
#include "cache_open.hpp"
#include "robodiff/cache/entry_json.hpp"
#include "robodiff/client/client.hpp"

namespace nb = nanobind;
namespace fs = std::filesystem;

namespace robodiff::python {

fs::path cacheDirOr(const std::optional<fs::path>& dir) { return dir ? *dir : cache::defaultCacheDir(); }

cache::Cache openCache(const fs::path& dir, bool create) {
  cache::CacheOptions options;
  options.create = create;
  try {
    return cache::Cache::open(dir, options);
  } catch (const cache::CacheError& e) {
    const std::string message = e.what();
    const bool named = message.find(dir.string()) != std::string::npos;
    throw client::ClientError(
        {StatusCode::FailedPrecondition, named ? message : "cache " + dir.string() + ": " + message});
  }
}

namespace {

// The entries of the cache in dir as a JSON array (most recently used first); "[]" when
// the directory does not exist (nothing was built there yet).
std::string cacheEntriesJson(const std::optional<fs::path>& dir_given) {
  const fs::path dir = cacheDirOr(dir_given);
  std::error_code ec;
  if (!fs::exists(dir, ec)) return "[]";
  cache::Cache cache = openCache(dir, false);
  nlohmann::json rows = nlohmann::json::array();
  for (const cache::Entry& e : cache.list()) rows.push_back(cache::entryJson(e));
  return rows.dump();
}

}  // namespace

void bindCache(nb::module_& m) {
  m.def("cache_entries", &cacheEntriesJson, nb::arg("cache_dir").none() = nb::none(),
        nb::call_guard<nb::gil_scoped_release>(),
        "The cache's entries as the JSON text `robodiff cache ls --json` prints (cache_dir None: the default).");
  m.def(
      "default_cache_dir", [] { return cache::defaultCacheDir(); },
      "The cache used when none is given: $ROBODIFF_CACHE_DIR, else $XDG_CACHE_HOME/robodiff, else ~/.cache/robodiff.");
}

}  // namespace robodiff::python
