#pragma once
// The jobs' part of the cache's index (index.sqlite, table `jobs`): one row per batch job
// a server accepted, from QUEUED to its final state, with where its result files are.
// Result files live under <cache>/jobs/<id>/, written first into <id>.partial/ and
// renamed into place when the job succeeds, so a row that says SUCCEEDED always points
// at complete files, and no failed, cancelled or crashed job leaves any.

#include <chrono>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace robodiff::cache {

struct JobRecord {
  std::string id;
  std::string kind;
  std::string state;        // QUEUED, RUNNING, SUCCEEDED, FAILED, CANCELLED
  std::string params_json;
  std::string result_json;  // SUCCEEDED: the job's result summary
  std::string result_dir;   // SUCCEEDED: its files
  std::string error;        // FAILED / CANCELLED: why
  std::string owner;        // the server process that ran it (host:pid:start-time:nonce)
  std::string caller;       // who submitted it ("dds:alice", "user:bob"; '' before callers were recorded)
  std::int64_t submitted_ms = 0, started_ms = 0, finished_ms = 0;  // Unix milliseconds; 0: not yet
};

class JobIndex {
 public:
  // Opens <cache_dir>/index.sqlite (created if needed, WAL) and the jobs table, and
  // <cache_dir>/jobs/. Throws CacheError.
  explicit JobIndex(const std::filesystem::path& cache_dir);
  ~JobIndex();
  JobIndex(const JobIndex&) = delete;
  JobIndex& operator=(const JobIndex&) = delete;

  std::filesystem::path jobsDir() const;                   // <cache_dir>/jobs
  std::filesystem::path resultDir(const std::string& id) const;   // jobs/<id>
  std::filesystem::path stagingDir(const std::string& id) const;  // jobs/<id>.partial

  void insert(const JobRecord& record);  // throws CacheError when the id exists
  void markRunning(const std::string& id, std::int64_t started_ms);
  // The final state; SUCCEEDED needs result_json and result_dir.
  void finish(const std::string& id, const std::string& state, const std::string& result_json,
              const std::string& result_dir, const std::string& error, std::int64_t finished_ms);
  std::optional<JobRecord> find(const std::string& id);
  // Newest first; at most `limit` of them when it is not 0 (the dashboard's poll reads
  // the newest few, not the whole history).
  std::vector<JobRecord> list(std::size_t limit = 0);

  // Jobs left QUEUED or RUNNING by an owner that is gone (a server that stopped or
  // crashed): marked FAILED with `reason`, and their staging directories removed.
  // Returns how many.
  int failOrphans(const std::string& current_owner, const std::string& reason);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// This process as an owner: host:pid:start-time:nonce (as cache claims use).
std::string currentJobOwner();

}  // namespace robodiff::cache
