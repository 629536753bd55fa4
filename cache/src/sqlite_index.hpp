// The cache's SQLite index: the connection (WAL, busy timeout), statements, immediate
// transactions for writers, and the `entries` table with its row mapping.
//
// entries: one row per key. state 'building' is a claim (owner, lease_expires_ms);
// state 'ready' is a published artifact (sizes, library SHA-256, hits, last use).
#pragma once

#include <chrono>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "robodiff/cache/cache.hpp"

struct sqlite3;
struct sqlite3_stmt;

namespace robodiff::cache::detail {

class Statement {
 public:
  Statement(sqlite3* db, const char* sql);
  ~Statement();
  Statement(const Statement&) = delete;
  Statement& operator=(const Statement&) = delete;

  Statement& bind(int index, const std::string& text);
  Statement& bind(int index, std::int64_t value);
  Statement& bind(int index, double value);
  // Steps once: true while a row is available.
  bool step();
  // Runs to completion, returning the number of rows changed.
  int run();

  std::string text(int column) const;
  std::int64_t integer(int column) const;
  double real(int column) const;

 private:
  sqlite3* db_;
  sqlite3_stmt* stmt_ = nullptr;
};

class IndexDatabase {
 public:
  // Opens (creating) the index file, in WAL mode with the busy timeout, and creates the
  // schema when missing. Throws CacheError(Database).
  IndexDatabase(const std::filesystem::path& file, std::chrono::milliseconds busy_timeout);
  ~IndexDatabase();
  IndexDatabase(const IndexDatabase&) = delete;
  IndexDatabase& operator=(const IndexDatabase&) = delete;

  sqlite3* handle() const { return db_; }
  void exec(const char* sql);

  // Runs body inside BEGIN IMMEDIATE ... COMMIT (ROLLBACK when it throws): writers take the
  // write lock up front, so two processes never deadlock upgrading read locks.
  void immediate(const std::function<void()>& body);

  // Row access.
  std::optional<Entry> entry(const std::string& key);
  std::vector<Entry> entries(const char* where_order = "ORDER BY last_used DESC, key");

 private:
  sqlite3* db_ = nullptr;
  std::filesystem::path file_;
  std::chrono::milliseconds busy_timeout_;
};

// Throws CacheError(Database) with SQLite's message when rc is an error.
void checkSqlite(sqlite3* db, int rc, const std::string& what);

std::int64_t unixSeconds();
std::int64_t unixMilliseconds();

}  // namespace robodiff::cache::detail
