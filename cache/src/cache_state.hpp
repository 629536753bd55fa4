// What a Cache is made of (its directory, options, index connection) and the checks and
// moves its parts share: verifying an entry's files, quarantining a bad entry.
#pragma once

#include <filesystem>
#include <memory>
#include <mutex>
#include <string>

#include "robodiff/cache/cache.hpp"
#include "sqlite_index.hpp"

namespace robodiff::cache {

struct Cache::State {
  std::filesystem::path dir;
  CacheOptions options;
  std::unique_ptr<detail::IndexDatabase> db;
  std::mutex mutex;  // one SQLite connection and one set of files per Cache: one user at a time

  std::filesystem::path objects() const { return dir / "objects"; }
  std::filesystem::path staging() const { return dir / "staging"; }
  std::filesystem::path quarantine() const { return dir / "quarantine"; }
  std::filesystem::path objectDir(const std::string& key) const { return objects() / key.substr(0, 2) / key; }
  std::filesystem::path stagingDir(const Claim& c) const { return staging() / (c.key + "@" + c.owner); }
  std::filesystem::path artifactStagingDir(const Claim& c) const {
    return staging() / (c.key + "@" + c.owner + ".artifact");
  }
};

namespace detail {

// What is wrong with a ready entry's files (missing, a symbolic link, truncated,
// replaced: size or SHA-256 differs from `e`), or empty when nothing is.
std::string artifactProblem(const Entry& e, const std::filesystem::path& dir);
// artifactProblem, then the permission checks done before loading (owner, mode).
std::string entryProblem(const Entry& e, const std::filesystem::path& dir);

// Moves a bad entry's directory to DIR/quarantine/<key>.<ms> (with a `reason` file;
// a bare record of the reason when the directory is gone), drops its ready row and
// logs the reason to stderr, so it is never loaded and the next use rebuilds it.
// Caller holds the mutex.
void quarantineEntry(Cache::State& s, const std::string& key, const std::string& reason);

// Sets the row's portable key (EntryInfo::portable_key); run in the transaction that
// inserted the row.
void recordPortableKey(sqlite3* db, const std::string& key, const EntryInfo& info);

// Indexes `e` as ready, with its portable key, in one transaction. A row already there
// for its key is replaced (a publish), or kept (`cache repair`: the index wins).
enum class ExistingRow : std::uint8_t { Replace, Keep };
void indexReadyRow(Cache::State& s, const Entry& e, ExistingRow existing);

}  // namespace detail
}  // namespace robodiff::cache

namespace robodiff::cache::detail {

// Cache::repair() with the mutex held.
RepairReport repairIndex(Cache::State& s);
// At open: when the index has no entries but objects exist, repairs it and logs the
// summary to stderr.
void repairWhenIndexEmpty(Cache::State& s);

}  // namespace robodiff::cache::detail
