// The caller of each job in the cache's index (ownership survives a restart), and an index
// made before jobs had callers: opened, it gains the column, its jobs have caller ''.
#include <gtest/gtest.h>
#include <sqlite3.h>

#include "robodiff/cache/job_index.hpp"
#include "support/temp_dir.hpp"

namespace robodiff::cache {
namespace {

JobRecord job(const std::string& id, const std::string& caller) {
  JobRecord r;
  r.id = id;
  r.kind = "trajectory";
  r.state = "QUEUED";
  r.params_json = "{}";
  r.owner = "test";
  r.caller = caller;
  r.submitted_ms = 1000;
  return r;
}

TEST(JobIndexCaller, TheCallerIsKept) {
  testing::TempDir dir;
  {
    JobIndex index(dir / "cache");
    index.insert(job("job-a", "dds:alice"));
  }
  JobIndex reopened(dir / "cache");
  ASSERT_TRUE(reopened.find("job-a"));
  EXPECT_EQ(reopened.find("job-a")->caller, "dds:alice");
  EXPECT_EQ(reopened.list().at(0).caller, "dds:alice");
}

TEST(JobIndexCaller, AnOlderIndexGainsTheColumn) {
  testing::TempDir dir;
  std::filesystem::create_directories(dir / "cache");
  sqlite3* db = nullptr;
  ASSERT_EQ(sqlite3_open((dir / "cache" / "index.sqlite").c_str(), &db), SQLITE_OK);
  ASSERT_EQ(sqlite3_exec(db,
                         "CREATE TABLE jobs (id TEXT PRIMARY KEY, kind TEXT NOT NULL, state TEXT NOT NULL, "
                         "params TEXT NOT NULL, result TEXT NOT NULL DEFAULT '', result_dir TEXT NOT NULL DEFAULT '', "
                         "error TEXT NOT NULL DEFAULT '', owner TEXT NOT NULL, submitted_ms INTEGER NOT NULL, "
                         "started_ms INTEGER NOT NULL DEFAULT 0, finished_ms INTEGER NOT NULL DEFAULT 0);"
                         "INSERT INTO jobs (id, kind, state, params, owner, submitted_ms) "
                         "VALUES ('job-old', 'trajectory', 'SUCCEEDED', '{}', 'gone', 500);",
                         nullptr, nullptr, nullptr),
            SQLITE_OK);
  sqlite3_close(db);
  JobIndex index(dir / "cache");
  ASSERT_TRUE(index.find("job-old"));
  EXPECT_EQ(index.find("job-old")->caller, "");
  index.insert(job("job-new", "user:bob"));
  EXPECT_EQ(index.find("job-new")->caller, "user:bob");
}

}  // namespace
}  // namespace robodiff::cache
