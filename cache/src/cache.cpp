#include "robodiff/cache/cache.hpp"

#include <fcntl.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <iostream>
#include <mutex>
#include <thread>

#include "artifact_files.hpp"
#include "cache_state.hpp"
#include "entry_sidecar.hpp"
#include "permissions.hpp"
#include "process_identity.hpp"
#include "robodiff/cache/cache_key.hpp"
#include "sqlite_index.hpp"

namespace robodiff::cache {

namespace fs = std::filesystem;
using namespace detail;

namespace {

void requireKey(const std::string& key) {
  if (!isCacheKey(key))
    throw std::invalid_argument("not a cache key (64 lowercase hex digits): \"" + key + "\"");
}

void makePrivateSubdirectory(const fs::path& dir) {
  if (::mkdir(dir.c_str(), 0700) != 0 && errno != EEXIST)
    throw CacheError(CacheError::Kind::Io, "cannot create " + dir.string() + ": " + std::strerror(errno));
  checkNotWritableByOthers(dir);
}

// A held flock on an entry's pin file; the fd closes (and the lock goes) with the last copy.
std::shared_ptr<int> holdPin(int fd) {
  return std::shared_ptr<int>(new int(fd), [](int* p) {
    ::close(*p);
    delete p;
  });
}

// Opens dir/pin and takes the lock; -1 when the file is missing or (non-blocking) the lock
// is held in a conflicting mode.
int lockPin(const fs::path& object_dir, int operation) {
  const int fd = ::open((object_dir / "pin").c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) return -1;
  while (::flock(fd, operation) != 0) {
    if (errno == EINTR) continue;
    ::close(fd);
    return -1;
  }
  return fd;
}

// Binds the six text fields of EntryInfo, in their column order, from `first` on.
Statement& bindInfo(Statement& st, int first, const EntryInfo& info) {
  return st.bind(first, info.model_hash)
      .bind(first + 1, info.robot)
      .bind(first + 2, info.function)
      .bind(first + 3, info.spec)
      .bind(first + 4, info.sizes)
      .bind(first + 5, info.compiler);
}

}  // namespace

Cache::Cache(std::unique_ptr<State> state) : state_(std::move(state)) {}
Cache::~Cache() = default;
Cache::Cache(Cache&&) noexcept = default;
Cache& Cache::operator=(Cache&&) noexcept = default;

Cache Cache::open(const fs::path& dir, const CacheOptions& options) {
  if (dir.empty()) throw CacheError(CacheError::Kind::Permissions, "no cache directory given");
  auto state = std::make_unique<State>();
  state->dir = fs::absolute(dir).lexically_normal();
  state->options = options;
  preparePrivateDirectory(state->dir, options.create);
  makePrivateSubdirectory(state->objects());
  makePrivateSubdirectory(state->staging());
  makePrivateSubdirectory(state->quarantine());
  const fs::path index = state->dir / "index.sqlite";
  state->db = std::make_unique<IndexDatabase>(index, options.busy_timeout);
  ::chmod(index.c_str(), 0600);
  if (options.repair_empty_index) repairWhenIndexEmpty(*state);
  return Cache(std::move(state));
}

const fs::path& Cache::dir() const { return state_->dir; }
const CacheOptions& Cache::options() const { return state_->options; }

void detail::recordPortableKey(sqlite3* db, const std::string& key, const EntryInfo& info) {
  Statement(db, "UPDATE entries SET portable_key = ? WHERE key = ?").bind(1, info.portable_key).bind(2, key).run();
}

void detail::indexReadyRow(Cache::State& s, const Entry& e, ExistingRow existing) {
  const std::string sql =
      std::string("INSERT INTO entries (key, state, model_hash, robot, function, spec, sizes, compiler, build_seconds, "
                  "library_bytes, total_bytes, library_sha256, created, last_used, hits, owner, lease_expires_ms) "
                  "VALUES (?, 'ready', ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, 0, '', 0) ON CONFLICT (key) ") +
      (existing == ExistingRow::Keep
           ? "DO NOTHING"
           : "DO UPDATE SET state = 'ready', model_hash = excluded.model_hash, robot = excluded.robot, "
             "function = excluded.function, spec = excluded.spec, sizes = excluded.sizes, "
             "compiler = excluded.compiler, build_seconds = excluded.build_seconds, "
             "library_bytes = excluded.library_bytes, total_bytes = excluded.total_bytes, "
             "library_sha256 = excluded.library_sha256, created = excluded.created, "
             "last_used = excluded.last_used, hits = 0, owner = '', lease_expires_ms = 0");
  s.db->immediate([&] {
    Statement insert(s.db->handle(), sql.c_str());
    bindInfo(insert.bind(1, e.key), 2, e.info)
        .bind(8, e.info.build_seconds)
        .bind(9, static_cast<std::int64_t>(e.library_bytes))
        .bind(10, static_cast<std::int64_t>(e.total_bytes))
        .bind(11, e.library_sha256)
        .bind(12, e.created)
        .bind(13, e.last_used)
        .run();
    recordPortableKey(s.db->handle(), e.key, e.info);
  });
}

void detail::quarantineEntry(Cache::State& s, const std::string& key, const std::string& reason) {
  s.db->immediate([&] { Statement(s.db->handle(), "DELETE FROM entries WHERE key = ? AND state = 'ready'").bind(1, key).run(); });
  const fs::path from = s.objectDir(key);
  const fs::path to = s.quarantine() / (key + "." + std::to_string(unixMilliseconds()));
  std::error_code ec;
  if (fs::exists(from, ec)) {
    fs::rename(from, to, ec);
  } else {
    fs::create_directory(to, ec);  // a record of what was lost, counted in stats().quarantined
  }
  if (!ec) {
    try {
      writeFileSynced(to / "reason", reason + "\n");
    } catch (const std::exception&) {
      // The move is what matters; the note is for people.
    }
  }
  std::cerr << "robodiff cache: entry " << key << ": " << reason << "; "
            << (ec ? "could not move it aside (" + ec.message() + "), " : "moved to " + to.string() + "; ")
            << "it will be rebuilt when next needed\n";
}

struct detail::ArtifactAccess {
  static Artifact make(Entry entry, fs::path dir, std::shared_ptr<int> pin) {
    Artifact a;
    a.entry_ = std::move(entry);
    a.dir_ = std::move(dir);
    a.pin_ = std::move(pin);
    return a;
  }
};

namespace {

// The verified, pinned artifact of a ready key (a hit counted when asked); nullopt when
// absent, being built, or corrupt (then quarantined). Caller holds the mutex.
std::optional<Artifact> loadArtifact(Cache::State& s, const std::string& key, bool count_hit) {
  std::optional<Entry> row = s.db->entry(key);
  if (!row || row->state != "ready") return std::nullopt;
  const fs::path dir = s.objectDir(key);
  const int fd = lockPin(dir, LOCK_SH);
  if (fd < 0) {
    std::error_code ec;
    quarantineEntry(s, key,
                    fs::is_directory(dir, ec) ? "its pin file is missing" : "its directory " + dir.string() + " is missing");
    return std::nullopt;
  }
  std::shared_ptr<int> pin = holdPin(fd);
  row = s.db->entry(key);  // eviction may have removed it before the lock was ours
  if (!row || row->state != "ready") return std::nullopt;
  // Missing, truncated or replaced files: quarantined, a miss (the caller rebuilds).
  if (const std::string problem = artifactProblem(*row, dir); !problem.empty()) {
    pin.reset();
    quarantineEntry(s, key, problem);
    return std::nullopt;
  }
  // Files another user may have written: refused, never loaded (the cache is not trusted).
  checkNotWritableByOthers(dir);
  checkNotWritableByOthers(dir / "library.so");
  if (count_hit) {
    const std::int64_t now = unixSeconds();
    s.db->immediate([&] {
      Statement(s.db->handle(), "UPDATE entries SET hits = hits + 1, last_used = ? WHERE key = ?").bind(1, now).bind(2, key).run();
    });
    row->hits += 1;
    row->last_used = now;
  }
  return detail::ArtifactAccess::make(std::move(*row), dir, std::move(pin));
}

}  // namespace

std::optional<Artifact> Cache::find(const std::string& key) {
  requireKey(key);
  std::lock_guard lock(state_->mutex);
  return loadArtifact(*state_, key, true);
}

ClaimResult Cache::claim(const std::string& key, const EntryInfo& info) {
  requireKey(key);
  // A ready row whose files turn out corrupt is quarantined by find(); then claim again.
  for (int attempt = 0; attempt < 3; ++attempt) {
    ClaimResult result;
    bool ready = false;
    {
      std::lock_guard lock(state_->mutex);
      State& s = *state_;
      const std::int64_t now_ms = unixMilliseconds();
      const std::int64_t lease_end = now_ms + state_->options.lease.count();
      s.db->immediate([&] {
        const std::optional<Entry> row = s.db->entry(key);
        if (row && row->state == "ready") {
          ready = true;
          return;
        }
        if (row && row->lease_expires_ms > now_ms && ownerMayBeAlive(row->owner)) {
          result.state = ClaimResult::State::Busy;
          result.holder = row->owner;
          return;
        }
        // Free, or left by a process that is dead or stopped renewing: ours now.
        const Claim c{key, newOwnerToken()};
        Statement insert(s.db->handle(),
                         "INSERT INTO entries (key, state, model_hash, robot, function, spec, sizes, compiler, created, "
                         "last_used, owner, lease_expires_ms) VALUES (?, 'building', ?, ?, ?, ?, ?, ?, ?, ?, ?, ?) "
                         "ON CONFLICT (key) DO UPDATE SET owner = excluded.owner, "
                         "lease_expires_ms = excluded.lease_expires_ms, created = excluded.created");
        bindInfo(insert.bind(1, key), 2, info)
            .bind(8, now_ms / 1000)
            .bind(9, now_ms / 1000)
            .bind(10, c.owner)
            .bind(11, lease_end)
            .run();
        recordPortableKey(s.db->handle(), key, info);
        if (row) removeTreeQuietly(s.stagingDir(Claim{key, row->owner}));
        result.state = ClaimResult::State::Claimed;
        result.claim = c;
      });
    }
    if (!ready) return result;
    if (std::optional<Artifact> a = find(key)) {
      result.state = ClaimResult::State::Ready;
      result.artifact = std::move(a);
      return result;
    }
  }
  throw CacheError(CacheError::Kind::Io, "cache entry " + key + " keeps turning out corrupt; see the messages above");
}

ClaimResult Cache::waitOrClaim(const std::string& key, const EntryInfo& info,
                               std::chrono::steady_clock::time_point deadline) {
  for (;;) {
    ClaimResult r = claim(key, info);
    if (r.state != ClaimResult::State::Busy) return r;
    const auto now = std::chrono::steady_clock::now();
    if (now >= deadline) return r;
    std::this_thread::sleep_for(std::min<std::chrono::steady_clock::duration>(std::chrono::milliseconds(50), deadline - now));
  }
}

void Cache::renew(const Claim& claim) {
  std::lock_guard lock(state_->mutex);
  State& s = *state_;
  int changed = 0;
  s.db->immediate([&] {
    changed = Statement(s.db->handle(),
                        "UPDATE entries SET lease_expires_ms = ? WHERE key = ? AND owner = ? AND state = 'building'")
                  .bind(1, unixMilliseconds() + s.options.lease.count())
                  .bind(2, claim.key)
                  .bind(3, claim.owner)
                  .run();
  });
  if (changed) return;
  const std::optional<Entry> row = s.db->entry(claim.key);
  if (row && row->state == "ready") return;  // published meanwhile: nothing left to renew
  throw CacheError(CacheError::Kind::ClaimLost,
                   "the claim on cache entry " + claim.key + " was lost" +
                       (row ? " to " + row->owner + " (the lease had run out)" : " (the entry was removed)"));
}

fs::path Cache::stagingDir(const Claim& claim) {
  requireKey(claim.key);
  const fs::path dir = state_->stagingDir(claim);
  removeTreeQuietly(dir);
  if (::mkdir(dir.c_str(), 0700) != 0)
    throw CacheError(CacheError::Kind::Io, "cannot create staging directory " + dir.string() + ": " + std::strerror(errno));
  return dir;
}

namespace {

// Removes a ready entry whose pin we hold exclusively (fd, or -1 when it has no pin
// file): unindexed first, then its files, so a reader never finds a row without them.
void dropEntry(Cache::State& s, const std::string& key, int fd) {
  s.db->immediate([&] { Statement(s.db->handle(), "DELETE FROM entries WHERE key = ?").bind(1, key).run(); });
  const fs::path dir = s.objectDir(key);
  const fs::path doomed = s.staging() / (key + ".evicted." + std::to_string(unixMilliseconds()));
  std::error_code ec;
  fs::rename(dir, doomed, ec);
  if (fd >= 0) ::close(fd);
  removeTreeQuietly(ec ? dir : doomed);
}

// Evicts least-recently-used, unpinned ready entries (never `keep`) until `bytes_needed`
// more fit in `budget`. Returns whether they fit. Caller holds the mutex.
bool makeRoom(Cache::State& s, std::uint64_t budget, std::uint64_t bytes_needed, const std::string& keep,
              GcReport& report) {
  std::vector<Entry> ready = s.db->entries("WHERE state = 'ready' ORDER BY last_used ASC, created ASC");
  std::uint64_t total = 0;
  for (const Entry& e : ready) total += e.total_bytes;
  for (const Entry& e : ready) {
    if (budget == 0 || total + bytes_needed <= budget) break;
    if (e.key == keep) continue;
    const fs::path dir = s.objectDir(e.key);
    const int fd = lockPin(dir, LOCK_EX | LOCK_NB);
    if (fd < 0 && fs::exists(dir / "pin")) {
      ++report.kept_in_use;
      continue;
    }
    dropEntry(s, e.key, fd);
    total -= std::min(total, e.total_bytes);
    report.freed_bytes += e.total_bytes;
    report.evicted.push_back(e.key);
  }
  report.bytes_after = total;
  return budget == 0 || total + bytes_needed <= budget;
}

std::string mib(std::uint64_t bytes) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.1f MiB", static_cast<double>(bytes) / (1024.0 * 1024.0));
  return buf;
}

// publish, step 1: the artifact, complete and durable, under a temporary name, with the
// sidecar `cache repair` needs to re-create its row should the index be lost.
Entry stageArtifact(const fs::path& artifact, const std::string& key, const EntryInfo& info, const ArtifactFiles& files) {
  removeTreeQuietly(artifact);
  if (::mkdir(artifact.c_str(), 0700) != 0)
    throw CacheError(CacheError::Kind::Io, "cannot create " + artifact.string() + ": " + std::strerror(errno));
  copyFileSynced(files.library, artifact / "library.so", 0500);
  copyFileSynced(files.description, artifact / "description.json", 0400);
  if (!files.sources.empty()) {
    ::mkdir((artifact / "src").c_str(), 0700);
    for (const fs::path& source : files.sources)
      compressFileSynced(source, artifact / "src" / (source.filename().string() + ".zst"));
    fsyncDirectory(artifact / "src");
  }
  writeFileSynced(artifact / "pin", "");
  Entry sidecar;
  sidecar.key = key;
  sidecar.info = info;
  sidecar.library_bytes = fs::file_size(artifact / "library.so");
  sidecar.library_sha256 = sha256OfFile(artifact / "library.so");
  sidecar.created = unixSeconds();
  writeFileSynced(artifact / kSidecarName, sidecarText(sidecar));
  fsyncDirectory(artifact);
  sidecar.total_bytes = directoryBytes(artifact);
  sidecar.last_used = sidecar.created;  // the row's, as entry.json's created
  return sidecar;
}

// Step 2: room within the budget, without touching entries in use. Caller holds the mutex.
void requireRoom(Cache::State& s, const Entry& staged) {
  const std::uint64_t budget = s.options.budget_bytes;
  const std::string what = staged.info.robot + "/" + staged.info.function;
  if (budget != 0 && staged.total_bytes > budget)
    throw CacheError(CacheError::Kind::Budget, "the library for " + what + " needs " + mib(staged.total_bytes) +
                                                   ", more than the whole cache budget of " + mib(budget) +
                                                   "; raise the budget");
  GcReport room;
  if (!makeRoom(s, budget, staged.total_bytes, staged.key, room))
    throw CacheError(CacheError::Kind::Budget,
                     "the cache budget of " + mib(budget) + " is full: " + std::to_string(room.kept_in_use) +
                         " entries in use hold " + mib(room.bytes_after) + " and cannot be evicted, and " + what +
                         " needs " + mib(staged.total_bytes) + "; raise the budget or release the functions in use");
}

// Step 3: into place, then indexed as ready; a copy someone published first is kept
// instead. Caller holds the mutex.
void placeAndIndex(Cache::State& s, const fs::path& artifact, const Entry& staged) {
  std::optional<Entry> row = s.db->entry(staged.key);
  if (row && row->state == "ready") {
    removeTreeQuietly(artifact);
    return;
  }
  const fs::path target = s.objectDir(staged.key);
  makePrivateSubdirectory(target.parent_path());
  std::error_code ec;
  if (fs::exists(target, ec)) {
    // Left by a process that died between its rename and its index update: unverified.
    fs::rename(target, s.quarantine() / (staged.key + "." + std::to_string(unixMilliseconds()) + ".unindexed"), ec);
  }
  if (::rename(artifact.c_str(), target.c_str()) != 0)
    throw CacheError(CacheError::Kind::Io, "cannot move " + artifact.string() + " into place as " + target.string() +
                                               ": " + std::strerror(errno));
  fsyncDirectory(target.parent_path());
  detail::indexReadyRow(s, staged, detail::ExistingRow::Replace);
}

}  // namespace

Artifact Cache::publish(const Claim& claim, const EntryInfo& info, const ArtifactFiles& files) {
  requireKey(claim.key);
  State& s = *state_;
  const fs::path artifact = s.artifactStagingDir(claim);
  try {
    const Entry staged = stageArtifact(artifact, claim.key, info, files);
    std::lock_guard lock(s.mutex);
    requireRoom(s, staged);
    placeAndIndex(s, artifact, staged);
    removeTreeQuietly(s.stagingDir(claim));
  } catch (...) {
    removeTreeQuietly(artifact);
    abandon(claim);
    throw;
  }
  std::optional<Artifact> published;
  {
    std::lock_guard lock(s.mutex);
    published = loadArtifact(s, claim.key, false);
  }
  if (!published)
    throw CacheError(CacheError::Kind::Io, "cache entry " + claim.key + " was published but cannot be loaded back");
  return *published;
}

void Cache::abandon(const Claim& claim) noexcept {
  try {
    std::lock_guard lock(state_->mutex);
    State& s = *state_;
    s.db->immediate([&] {
      Statement(s.db->handle(), "DELETE FROM entries WHERE key = ? AND owner = ? AND state = 'building'")
          .bind(1, claim.key)
          .bind(2, claim.owner)
          .run();
    });
  } catch (const std::exception& e) {
    std::cerr << "robodiff cache: could not drop the claim on " << claim.key << ": " << e.what() << "\n";
  }
  removeTreeQuietly(state_->stagingDir(claim));
  removeTreeQuietly(state_->artifactStagingDir(claim));
}

std::vector<Entry> Cache::list() {
  std::lock_guard lock(state_->mutex);
  return state_->db->entries();
}

std::optional<Entry> Cache::entry(const std::string& key) {
  std::lock_guard lock(state_->mutex);
  return state_->db->entry(key);
}

bool Cache::intact(const std::string& key) {
  std::lock_guard lock(state_->mutex);
  const std::optional<Entry> e = state_->db->entry(key);
  if (!e || e->state != "ready") return false;
  std::error_code ec;
  const std::uintmax_t size = fs::file_size(state_->objectDir(key) / "library.so", ec);
  return !ec && size == e->library_bytes;
}

CacheStats Cache::stats() {
  std::lock_guard lock(state_->mutex);
  CacheStats st;
  st.dir = state_->dir;
  st.budget_bytes = state_->options.budget_bytes;
  for (const Entry& e : state_->db->entries()) {
    if (e.state == "ready") {
      ++st.entries;
      st.bytes += e.total_bytes;
      st.hits += e.hits;
    } else {
      ++st.building;
    }
  }
  std::error_code ec;
  for (fs::directory_iterator it(state_->quarantine(), ec), end; !ec && it != end; it.increment(ec)) ++st.quarantined;
  return st;
}

VerifyReport Cache::verify() {
  std::lock_guard lock(state_->mutex);
  State& s = *state_;
  VerifyReport report;
  for (const Entry& e : s.db->entries("WHERE state = 'ready' ORDER BY key")) {
    ++report.checked;
    const std::string problem = entryProblem(e, s.objectDir(e.key));
    if (problem.empty()) continue;
    report.problems.push_back({e.key, problem});
    quarantineEntry(s, e.key, problem);
  }
  return report;
}

GcReport Cache::gc(std::optional<std::uint64_t> budget_bytes) {
  std::lock_guard lock(state_->mutex);
  State& s = *state_;
  GcReport report;
  const std::int64_t now_ms = unixMilliseconds();
  // Claims whose owner is gone or stopped renewing.
  for (const Entry& e : s.db->entries("WHERE state = 'building'")) {
    if (e.lease_expires_ms > now_ms && ownerMayBeAlive(e.owner)) continue;
    s.db->immediate([&] {
      Statement(s.db->handle(), "DELETE FROM entries WHERE key = ? AND owner = ? AND state = 'building'")
          .bind(1, e.key)
          .bind(2, e.owner)
          .run();
    });
    ++report.stale_claims;
  }
  // Staging left by dead processes: "<key>@<owner>[.artifact]", or eviction leftovers.
  std::error_code ec;
  for (fs::directory_iterator it(s.staging(), ec), end; !ec && it != end; it.increment(ec)) {
    std::string name = it->path().filename().string();
    bool stale = name.find(".evicted.") != std::string::npos;
    if (const auto at = name.find('@'); !stale && at != std::string::npos) {
      std::string owner = name.substr(at + 1);
      if (owner.size() > 9 && owner.ends_with(".artifact")) owner.resize(owner.size() - 9);
      const std::optional<Entry> row = s.db->entry(name.substr(0, at));
      const bool claimed = row && row->state == "building" && row->owner == owner;
      stale = !claimed && !ownerMayBeAlive(owner);
    }
    if (!stale) continue;
    removeTreeQuietly(it->path());
    ++report.stale_staging;
  }
  for (fs::directory_iterator it(s.quarantine(), ec), end; !ec && it != end; it.increment(ec)) {
    removeTreeQuietly(it->path());
    ++report.quarantine_removed;
  }
  // An explicit budget of 0 means "as small as possible"; the configured 0 means "no budget".
  const std::uint64_t budget = budget_bytes ? std::max<std::uint64_t>(*budget_bytes, 1) : s.options.budget_bytes;
  makeRoom(s, budget, 0, {}, report);
  return report;
}

bool Cache::remove(const std::string& key) {
  requireKey(key);
  std::lock_guard lock(state_->mutex);
  State& s = *state_;
  const std::optional<Entry> row = s.db->entry(key);
  if (!row) return false;
  if (row->state == "building") {
    throw CacheError(CacheError::Kind::InUse, "cache entry " + key + " (" + row->info.robot + "/" + row->info.function +
                                                  ") is being built by " + row->owner + "; try again when it is done");
  }
  const fs::path dir = s.objectDir(key);
  const int fd = lockPin(dir, LOCK_EX | LOCK_NB);
  if (fd < 0 && fs::exists(dir / "pin"))
    throw CacheError(CacheError::Kind::InUse, "cache entry " + key + " (" + row->info.robot + "/" + row->info.function +
                                                  ") is loaded by a running process; it can be removed once released");
  dropEntry(s, key, fd);
  return true;
}

fs::path defaultCacheDir() {
  if (const char* d = std::getenv("ROBODIFF_CACHE_DIR"); d && *d) return d;
  if (const char* x = std::getenv("XDG_CACHE_HOME"); x && *x) return fs::path(x) / "robodiff";
  if (const char* h = std::getenv("HOME"); h && *h) return fs::path(h) / ".cache" / "robodiff";
  return fs::temp_directory_path() / ("robodiff-cache-" + std::to_string(geteuid()));
}

}  // namespace robodiff::cache
