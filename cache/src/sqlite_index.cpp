#include "sqlite_index.hpp"

#include <sqlite3.h>

#include <chrono>
#include <thread>

namespace robodiff::cache::detail {

void checkSqlite(sqlite3* db, int rc, const std::string& what) {
  if (rc == SQLITE_OK || rc == SQLITE_ROW || rc == SQLITE_DONE) return;
  throw CacheError(CacheError::Kind::Database,
                   "cache index: " + what + ": " + (db ? sqlite3_errmsg(db) : sqlite3_errstr(rc)));
}

std::int64_t unixSeconds() {
  return std::chrono::duration_cast<std::chrono::seconds>(std::chrono::system_clock::now().time_since_epoch()).count();
}

std::int64_t unixMilliseconds() {
  return std::chrono::duration_cast<std::chrono::milliseconds>(std::chrono::system_clock::now().time_since_epoch())
      .count();
}

Statement::Statement(sqlite3* db, const char* sql) : db_(db) {
  checkSqlite(db, sqlite3_prepare_v2(db, sql, -1, &stmt_, nullptr), std::string("preparing ") + sql);
}

Statement::~Statement() { sqlite3_finalize(stmt_); }

Statement& Statement::bind(int index, const std::string& text) {
  checkSqlite(db_, sqlite3_bind_text(stmt_, index, text.data(), static_cast<int>(text.size()), SQLITE_TRANSIENT),
              "binding a value");
  return *this;
}

Statement& Statement::bind(int index, std::int64_t value) {
  checkSqlite(db_, sqlite3_bind_int64(stmt_, index, value), "binding a value");
  return *this;
}

Statement& Statement::bind(int index, double value) {
  checkSqlite(db_, sqlite3_bind_double(stmt_, index, value), "binding a value");
  return *this;
}

bool Statement::step() {
  const int rc = sqlite3_step(stmt_);
  checkSqlite(db_, rc, std::string("running ") + sqlite3_sql(stmt_));
  return rc == SQLITE_ROW;
}

int Statement::run() {
  while (step()) {
  }
  return sqlite3_changes(db_);
}

std::string Statement::text(int column) const {
  const unsigned char* t = sqlite3_column_text(stmt_, column);
  return t ? std::string(reinterpret_cast<const char*>(t), static_cast<std::size_t>(sqlite3_column_bytes(stmt_, column)))
           : std::string();
}

std::int64_t Statement::integer(int column) const { return sqlite3_column_int64(stmt_, column); }
double Statement::real(int column) const { return sqlite3_column_double(stmt_, column); }

namespace {

constexpr const char* kSchema = R"sql(
CREATE TABLE IF NOT EXISTS meta (name TEXT PRIMARY KEY, value TEXT NOT NULL);
INSERT OR IGNORE INTO meta (name, value) VALUES ('schema', '1');
CREATE TABLE IF NOT EXISTS entries (
  key              TEXT PRIMARY KEY,
  state            TEXT NOT NULL CHECK (state IN ('building', 'ready')),
  model_hash       TEXT NOT NULL DEFAULT '',
  robot            TEXT NOT NULL DEFAULT '',
  function         TEXT NOT NULL DEFAULT '',
  spec             TEXT NOT NULL DEFAULT '',
  sizes            TEXT NOT NULL DEFAULT '',
  compiler         TEXT NOT NULL DEFAULT '',
  build_seconds    REAL NOT NULL DEFAULT 0,
  library_bytes    INTEGER NOT NULL DEFAULT 0,
  total_bytes      INTEGER NOT NULL DEFAULT 0,
  library_sha256   TEXT NOT NULL DEFAULT '',
  created          INTEGER NOT NULL DEFAULT 0,
  last_used        INTEGER NOT NULL DEFAULT 0,
  hits             INTEGER NOT NULL DEFAULT 0,
  owner            TEXT NOT NULL DEFAULT '',
  lease_expires_ms INTEGER NOT NULL DEFAULT 0,
  portable_key     TEXT NOT NULL DEFAULT ''
);
CREATE INDEX IF NOT EXISTS entries_by_use ON entries (state, last_used);
)sql";

// Indexes on columns that indexes made by earlier versions lack (added by addMissingColumns
// first).
constexpr const char* kLaterIndexes = R"sql(
CREATE INDEX IF NOT EXISTS entries_by_portable_key ON entries (portable_key);
)sql";

constexpr const char* kColumns =
    "key, state, model_hash, robot, function, spec, sizes, compiler, build_seconds, library_bytes, total_bytes, "
    "library_sha256, created, last_used, hits, owner, lease_expires_ms, portable_key";

Entry readEntry(const Statement& s) {
  Entry e;
  e.key = s.text(0);
  e.state = s.text(1);
  e.info.model_hash = s.text(2);
  e.info.robot = s.text(3);
  e.info.function = s.text(4);
  e.info.spec = s.text(5);
  e.info.sizes = s.text(6);
  e.info.compiler = s.text(7);
  e.info.build_seconds = s.real(8);
  e.library_bytes = static_cast<std::uint64_t>(s.integer(9));
  e.total_bytes = static_cast<std::uint64_t>(s.integer(10));
  e.library_sha256 = s.text(11);
  e.created = s.integer(12);
  e.last_used = s.integer(13);
  e.hits = static_cast<std::uint64_t>(s.integer(14));
  e.owner = s.text(15);
  e.lease_expires_ms = s.integer(16);
  e.info.portable_key = s.text(17);
  return e;
}

// Columns added since the first schema, added to an index an earlier version made.
void addMissingColumns(sqlite3* db) {
  bool has_portable_key = false;
  {
    Statement columns(db, "PRAGMA table_info(entries)");  // finalised before the ALTER
    while (columns.step()) has_portable_key = has_portable_key || columns.text(1) == "portable_key";
  }
  if (has_portable_key) return;
  checkSqlite(db, sqlite3_exec(db, "ALTER TABLE entries ADD COLUMN portable_key TEXT NOT NULL DEFAULT ''", nullptr,
                               nullptr, nullptr),
              "adding the portable_key column");
}

}  // namespace

namespace {

// Runs sql, retrying while SQLite reports the database busy or locked. The busy handler
// covers most waits, but not all: switching to WAL and recovering a WAL index while
// another process opens the same new database return SQLITE_BUSY at once.
int execRetrying(sqlite3* db, const char* sql, std::chrono::milliseconds timeout, std::string& error) {
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  for (;;) {
    char* message = nullptr;
    const int rc = sqlite3_exec(db, sql, nullptr, nullptr, &message);
    error = message ? message : (rc == SQLITE_OK ? "" : sqlite3_errstr(rc));
    sqlite3_free(message);
    const int primary = rc & 0xff;
    if ((primary != SQLITE_BUSY && primary != SQLITE_LOCKED) || std::chrono::steady_clock::now() >= deadline) return rc;
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
}

}  // namespace

IndexDatabase::IndexDatabase(const std::filesystem::path& file, std::chrono::milliseconds busy_timeout)
    : file_(file), busy_timeout_(busy_timeout) {
  const int rc = sqlite3_open_v2(file.c_str(), &db_,
                                 SQLITE_OPEN_READWRITE | SQLITE_OPEN_CREATE | SQLITE_OPEN_FULLMUTEX, nullptr);
  if (rc != SQLITE_OK) {
    const std::string message = db_ ? sqlite3_errmsg(db_) : sqlite3_errstr(rc);
    sqlite3_close(db_);
    db_ = nullptr;
    throw CacheError(CacheError::Kind::Database, "cannot open cache index " + file.string() + ": " + message);
  }
  sqlite3_busy_timeout(db_, static_cast<int>(busy_timeout.count()));
  try {
    // WAL: readers never block the writer. synchronous=NORMAL: a crash of the process
    // loses nothing; a power cut may lose the last transactions, never consistency (the
    // artifacts themselves are fsynced before they are indexed).
    exec("PRAGMA journal_mode=WAL");
    exec("PRAGMA synchronous=NORMAL");
    immediate([&] {
      exec(kSchema);
      addMissingColumns(db_);
      exec(kLaterIndexes);
    });
  } catch (...) {
    sqlite3_close(db_);
    db_ = nullptr;
    throw;
  }
}

IndexDatabase::~IndexDatabase() { sqlite3_close(db_); }

void IndexDatabase::exec(const char* sql) {
  std::string error;
  if (execRetrying(db_, sql, busy_timeout_, error) != SQLITE_OK)
    throw CacheError(CacheError::Kind::Database, "cache index " + file_.string() + ": " + error);
}

void IndexDatabase::immediate(const std::function<void()>& body) {
  exec("BEGIN IMMEDIATE");
  try {
    body();
    exec("COMMIT");
  } catch (...) {
    sqlite3_exec(db_, "ROLLBACK", nullptr, nullptr, nullptr);
    throw;
  }
}

std::optional<Entry> IndexDatabase::entry(const std::string& key) {
  Statement s(db_, (std::string("SELECT ") + kColumns + " FROM entries WHERE key = ?").c_str());
  s.bind(1, key);
  if (!s.step()) return std::nullopt;
  return readEntry(s);
}

std::vector<Entry> IndexDatabase::entries(const char* where_order) {
  Statement s(db_, (std::string("SELECT ") + kColumns + " FROM entries " + where_order).c_str());
  std::vector<Entry> out;
  while (s.step()) out.push_back(readEntry(s));
  return out;
}

}  // namespace robodiff::cache::detail
