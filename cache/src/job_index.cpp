// JobIndex: the `jobs` table of the cache's index, and the jobs/ directory beside it.
#include "robodiff/cache/job_index.hpp"

#include <sqlite3.h>

#include "robodiff/cache/cache.hpp"
#include "process_identity.hpp"
#include "sqlite_index.hpp"

namespace robodiff::cache {
namespace {

namespace fs = std::filesystem;

constexpr const char* kJobsSchema = R"(
CREATE TABLE IF NOT EXISTS jobs (
  id TEXT PRIMARY KEY,
  kind TEXT NOT NULL,
  state TEXT NOT NULL,
  params TEXT NOT NULL,
  result TEXT NOT NULL DEFAULT '',
  result_dir TEXT NOT NULL DEFAULT '',
  error TEXT NOT NULL DEFAULT '',
  owner TEXT NOT NULL,
  caller TEXT NOT NULL DEFAULT '',
  submitted_ms INTEGER NOT NULL,
  started_ms INTEGER NOT NULL DEFAULT 0,
  finished_ms INTEGER NOT NULL DEFAULT 0
);
)";

constexpr const char* kColumns =
    "id, kind, state, params, result, result_dir, error, owner, submitted_ms, started_ms, finished_ms, caller";

// An index made before jobs had a caller gets the column (its jobs: caller '').
void addCallerColumn(detail::IndexDatabase& db) {
  detail::Statement columns(db.handle(), "SELECT 1 FROM pragma_table_info('jobs') WHERE name = 'caller'");
  if (!columns.step()) db.exec("ALTER TABLE jobs ADD COLUMN caller TEXT NOT NULL DEFAULT ''");
}

JobRecord rowOf(const detail::Statement& s) {
  JobRecord r;
  r.id = s.text(0);
  r.kind = s.text(1);
  r.state = s.text(2);
  r.params_json = s.text(3);
  r.result_json = s.text(4);
  r.result_dir = s.text(5);
  r.error = s.text(6);
  r.owner = s.text(7);
  r.submitted_ms = s.integer(8);
  r.started_ms = s.integer(9);
  r.finished_ms = s.integer(10);
  r.caller = s.text(11);
  return r;
}

}  // namespace

struct JobIndex::Impl {
  fs::path dir;
  detail::IndexDatabase db;
  Impl(const fs::path& cache_dir) : dir(cache_dir), db(cache_dir / "index.sqlite", std::chrono::seconds(10)) {}
};

JobIndex::JobIndex(const fs::path& cache_dir) {
  std::error_code ec;
  fs::create_directories(cache_dir / "jobs", ec);
  if (ec)
    throw CacheError(CacheError::Kind::Io, "cannot create " + (cache_dir / "jobs").string() + ": " + ec.message());
  fs::permissions(cache_dir / "jobs", fs::perms::owner_all, fs::perm_options::replace, ec);
  impl_ = std::make_unique<Impl>(cache_dir);
  impl_->db.immediate([&] {
    impl_->db.exec(kJobsSchema);
    addCallerColumn(impl_->db);
  });
}

JobIndex::~JobIndex() = default;

fs::path JobIndex::jobsDir() const { return impl_->dir / "jobs"; }
fs::path JobIndex::resultDir(const std::string& id) const { return jobsDir() / id; }
fs::path JobIndex::stagingDir(const std::string& id) const { return jobsDir() / (id + ".partial"); }

void JobIndex::insert(const JobRecord& r) {
  impl_->db.immediate([&] {
    detail::Statement s(impl_->db.handle(),
                        "INSERT INTO jobs (id, kind, state, params, owner, submitted_ms, caller) "
                        "VALUES (?, ?, ?, ?, ?, ?, ?)");
    s.bind(1, r.id).bind(2, r.kind).bind(3, r.state).bind(4, r.params_json).bind(5, r.owner).bind(6, r.submitted_ms);
    s.bind(7, r.caller);
    s.run();
  });
}

void JobIndex::markRunning(const std::string& id, std::int64_t started_ms) {
  impl_->db.immediate([&] {
    detail::Statement s(impl_->db.handle(), "UPDATE jobs SET state = 'RUNNING', started_ms = ? WHERE id = ?");
    s.bind(1, started_ms).bind(2, id);
    s.run();
  });
}

void JobIndex::finish(const std::string& id, const std::string& state, const std::string& result_json,
                      const std::string& result_dir, const std::string& error, std::int64_t finished_ms) {
  impl_->db.immediate([&] {
    detail::Statement s(impl_->db.handle(),
                        "UPDATE jobs SET state = ?, result = ?, result_dir = ?, error = ?, finished_ms = ? WHERE id = ?");
    s.bind(1, state).bind(2, result_json).bind(3, result_dir).bind(4, error).bind(5, finished_ms).bind(6, id);
    s.run();
  });
}

std::optional<JobRecord> JobIndex::find(const std::string& id) {
  detail::Statement s(impl_->db.handle(), (std::string("SELECT ") + kColumns + " FROM jobs WHERE id = ?").c_str());
  s.bind(1, id);
  if (!s.step()) return std::nullopt;
  return rowOf(s);
}

std::vector<JobRecord> JobIndex::list(std::size_t limit) {
  // LIMIT -1 is SQLite's "no limit".
  detail::Statement s(impl_->db.handle(),
                      (std::string("SELECT ") + kColumns + " FROM jobs ORDER BY submitted_ms DESC, id LIMIT ?").c_str());
  s.bind(1, limit == 0 ? std::int64_t{-1} : static_cast<std::int64_t>(limit));
  std::vector<JobRecord> out;
  while (s.step()) out.push_back(rowOf(s));
  return out;
}

int JobIndex::failOrphans(const std::string& current_owner, const std::string& reason) {
  std::vector<std::string> orphans;
  {
    detail::Statement s(impl_->db.handle(), "SELECT id, owner FROM jobs WHERE state IN ('QUEUED', 'RUNNING')");
    while (s.step())
      if (s.text(1) != current_owner && !detail::ownerMayBeAlive(s.text(1))) orphans.push_back(s.text(0));
  }
  for (const std::string& id : orphans) {
    finish(id, "FAILED", "", "", reason, detail::unixMilliseconds());
    std::error_code ignored;
    fs::remove_all(stagingDir(id), ignored);
  }
  return static_cast<int>(orphans.size());
}

std::string currentJobOwner() {
  static const std::string owner = detail::newOwnerToken();
  return owner;
}

}  // namespace robodiff::cache
