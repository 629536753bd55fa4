// The content-addressed cache of compiled function libraries.
//
// On disk (DIR, created 0700; nothing is loaded from it when it or an artifact is
// writable by other users):
//   DIR/index.sqlite           the index (WAL, busy timeout, BEGIN IMMEDIATE writers)
//   DIR/objects/<kk>/<key>/    one directory per key, never changed once in place:
//       library.so             the compiled library
//       description.json       its description (inputs, outputs, sparsity, build)
//       entry.json             its index row's metadata and library SHA-256 (for repair)
//       src/<file>.zst         the C sources as compiled, zstd-compressed
//       pin                    readers hold a shared flock on it: in use, not evicted
//   DIR/staging/               builds in progress (one directory per claim)
//   DIR/quarantine/            artifacts found missing or corrupt, moved aside (with a
//                              `reason` file), never loaded
//
// A key is built once across processes: claim() records a claim with a lease in the
// index; other processes wait for it (waitOrClaim) and take it over when the lease
// runs out or its owner (same host) is dead. publish() writes the artifact under a
// temporary name, fsyncs it, renames it into place and only then marks it ready, so a
// reader never sees a partial artifact. Every find() checks the library's SHA-256
// against the index before handing it out; a missing, truncated or replaced library is
// moved to quarantine, logged (to stderr) and reported as a miss, so the next build
// replaces it. A lost or empty index is rebuilt from the objects' entry.json (repair()).
#pragma once

#include <chrono>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

namespace robodiff::cache {

class CacheError : public std::runtime_error {
 public:
  enum class Kind : std::uint8_t {
    Permissions,  // the directory or an artifact is unsafe to load from, or not writable
    Io,           // a file operation failed
    Database,     // SQLite failed (the message has its error)
    Budget,       // the size budget cannot make room (everything left is in use)
    ClaimLost,    // another process took over this claim (its lease had run out)
    InUse,        // the entry is loaded by a process (pinned) and cannot be removed
  };
  CacheError(Kind kind, const std::string& message) : std::runtime_error(message), kind_(kind) {}
  Kind kind() const { return kind_; }

 private:
  Kind kind_;
};

struct CacheOptions {
  std::uint64_t budget_bytes = std::uint64_t{4} << 30;  // 0: no budget
  // A claim not renewed for this long is taken over by another process.
  std::chrono::milliseconds lease = std::chrono::seconds(30);
  // How long a writer waits for SQLite's lock before giving up.
  std::chrono::milliseconds busy_timeout = std::chrono::seconds(30);
  bool create = true;  // create DIR (0700) when missing
  // When the index has no entries but objects exist (index.sqlite deleted, emptied):
  // run repair() at open, logging its summary to stderr.
  bool repair_empty_index = true;
};

// What the builder tells the index about an artifact.
struct EntryInfo {
  std::string model_hash;
  std::string robot;        // the model's name, for people
  std::string function;     // the function's C name
  std::string spec;         // normalised spec JSON
  std::string sizes;        // JSON: {"inputs": [...], "outputs": [...]} block sizes
  std::string compiler;     // identity and flags
  double build_seconds = 0;
  // BuildIdentity::portableKey(): how a host without this compiler finds the entry
  // (Cache::findPortable). Empty for entries made before it was recorded.
  std::string portable_key;
};

// One row of the index.
struct Entry {
  std::string key;
  EntryInfo info;
  std::string state;                // "ready" or "building"
  std::uint64_t library_bytes = 0;  // library.so
  std::uint64_t total_bytes = 0;    // everything in the key's directory
  std::string library_sha256;
  std::int64_t created = 0, last_used = 0;  // unix seconds
  std::uint64_t hits = 0;
  std::string owner;                // building: who holds the claim
  std::int64_t lease_expires_ms = 0;  // building: unix milliseconds
};

namespace detail {
struct ArtifactAccess;  // cache.cpp: the only maker of Artifacts
}

// A verified artifact, pinned (never evicted) while this object or a copy lives.
class Artifact {
 public:
  const Entry& entry() const { return entry_; }
  const std::string& key() const { return entry_.key; }
  const std::filesystem::path& dir() const { return dir_; }
  std::filesystem::path library() const { return dir_ / "library.so"; }
  std::filesystem::path description() const { return dir_ / "description.json"; }

 private:
  friend struct detail::ArtifactAccess;
  Entry entry_;
  std::filesystem::path dir_;
  std::shared_ptr<int> pin_;  // the shared flock on dir/pin, released with the last copy
};

// The right to build one key. Plain data, so it can travel to a worker process.
struct Claim {
  std::string key;
  std::string owner;  // host:pid:start-time:nonce of the process that claimed it
};

// The files a build made, anywhere on disk; publish() copies them into place.
struct ArtifactFiles {
  std::filesystem::path library;
  std::filesystem::path description;
  std::vector<std::filesystem::path> sources;
};

struct ClaimResult {
  enum class State : std::uint8_t {
    Ready,    // built already: `artifact`
    Claimed,  // this process builds it: `claim`; renew() it, then publish() or abandon()
    Busy,     // another live process builds it: `holder`
  };
  State state = State::Busy;
  std::optional<Artifact> artifact;
  std::optional<Claim> claim;
  std::string holder;
};

struct CacheStats {
  std::filesystem::path dir;
  std::uint64_t entries = 0, building = 0;
  std::uint64_t bytes = 0, budget_bytes = 0;
  std::uint64_t hits = 0;  // sum over entries
  std::uint64_t quarantined = 0;
};

struct VerifyProblem {
  std::string key;
  std::string problem;  // e.g. "library.so: SHA-256 mismatch (index 3f2a..., file 9c1b...)"
};

struct VerifyReport {
  std::uint64_t checked = 0;
  std::vector<VerifyProblem> problems;  // each one was moved to quarantine and unindexed
};

struct RepairReport {
  std::uint64_t scanned = 0;        // object directories looked at
  std::uint64_t already_indexed = 0;  // with a good ready row: left alone
  std::uint64_t recovered = 0;      // good, unindexed: their rows re-created
  std::vector<VerifyProblem> quarantined;  // bad (or unverifiable): moved to quarantine
};

struct GcReport {
  std::vector<std::string> evicted;  // keys, least recently used first
  std::uint64_t freed_bytes = 0, bytes_after = 0;
  std::uint64_t kept_in_use = 0;     // entries over budget left because in use
  std::uint64_t stale_claims = 0, stale_staging = 0;  // left by dead processes, removed
  std::uint64_t quarantine_removed = 0;              // corrupt artifacts kept for inspection, removed
};

class Cache {
 public:
  // Opens (creating, 0700) the cache in `dir`. Throws CacheError(Permissions) when dir is
  // not a directory, is owned by another user, is writable by group or others, or is not
  // writable; the message names the path, its mode and what to do.
  static Cache open(const std::filesystem::path& dir, const CacheOptions& options = {});
  ~Cache();
  Cache(Cache&&) noexcept;
  Cache& operator=(Cache&&) noexcept;

  const std::filesystem::path& dir() const;
  const CacheOptions& options() const;

  // The verified artifact for key, counted as a hit; nullopt when absent, building, or
  // found missing or corrupt (then quarantined and unindexed, so the caller rebuilds it).
  // Throws CacheError(Permissions) when its files are another user's or writable by others.
  std::optional<Artifact> find(const std::string& key);
  // A verified artifact whose portable key (EntryInfo::portable_key) is `portable_key` and
  // whose target this CPU can run (target_check.hpp), the most recently used first, as
  // find() returns it; nullopt when there is none. How a host without the build host's
  // compiler finds a library it imported or fetched (cache_portable.cpp).
  std::optional<Artifact> findPortable(const std::string& portable_key);

  // Ready artifact, or a claim for this process, or Busy. A claim whose lease ran out or
  // whose owner is dead is taken over. `info` is recorded with the claim.
  ClaimResult claim(const std::string& key, const EntryInfo& info);
  // Waits (polling the index) while another process builds key; returns Ready or Claimed,
  // or Busy when `deadline` passes first.
  ClaimResult waitOrClaim(const std::string& key, const EntryInfo& info,
                          std::chrono::steady_clock::time_point deadline = std::chrono::steady_clock::time_point::max());
  // Extends the lease. Throws CacheError(ClaimLost) when the claim is no longer ours.
  void renew(const Claim& claim);
  // A fresh, empty directory (0700) under DIR/staging for this claim's build.
  std::filesystem::path stagingDir(const Claim& claim);
  // Copies files into place (sources compressed), fsyncs, renames, marks the key ready,
  // then trims the cache to its budget (never evicting pinned entries). Throws
  // CacheError(Budget) when the artifact cannot fit; the claim is abandoned then.
  Artifact publish(const Claim& claim, const EntryInfo& info, const ArtifactFiles& files);
  // Drops the claim (if still ours) and its staging directory. Never throws.
  void abandon(const Claim& claim) noexcept;

  std::vector<Entry> list();  // every row, most recently used first
  std::optional<Entry> entry(const std::string& key);
  // Whether key is ready and its library file is in place with the indexed size: a cheap
  // look (no hash, no hit counted) for a holder of the library to see that the entry was
  // lost; find() is what verifies it.
  bool intact(const std::string& key);
  CacheStats stats();
  // Checks every ready artifact's files and library hash.
  VerifyReport verify();
  // Re-creates the index from the objects on disk: verifies every indexed entry (as
  // verify()), then every object directory without a row against its entry.json (size,
  // SHA-256, key); good ones are indexed again, bad or unverifiable ones quarantined.
  RepairReport repair();
  // Evicts least-recently-used unpinned entries until the total fits `budget_bytes`
  // (the configured budget when unset); removes claims and staging left by dead processes.
  GcReport gc(std::optional<std::uint64_t> budget_bytes = std::nullopt);
  // Removes one entry. False when there is none; throws CacheError(InUse) naming it
  // when it is in use.
  bool remove(const std::string& key);

  struct State;  // opaque: defined in cache.cpp

 private:
  explicit Cache(std::unique_ptr<State> state);
  std::unique_ptr<State> state_;
};

// The cache directory used when none is given: $ROBODIFF_CACHE_DIR, else
// $XDG_CACHE_HOME/robodiff, else ~/.cache/robodiff.
std::filesystem::path defaultCacheDir();

}  // namespace robodiff::cache
