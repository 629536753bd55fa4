#pragma once
// Batch jobs in the server: SubmitJob / JobStatus / CancelJob / JobResult.
//
// A job runs in a worker process of its own pool (so builds and jobs do not wait for each
// other), with a memory limit and a timeout. The worker writes the job's files into a
// staging directory (<cache>/jobs/<id>.partial/) and reports progress; when the job
// succeeds the directory is renamed to <cache>/jobs/<id>/ and the row in the cache's
// index says SUCCEEDED with the result summary. A failure, a cancel, a timeout or a
// worker crash removes the staging directory: no partial result is ever visible.
// Jobs of a server that stopped or crashed are marked FAILED when the next one starts.

#include <chrono>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "robodiff/schema/messages.hpp"
#include "robodiff/server/log.hpp"

namespace robodiff::server {

struct JobManagerOptions {
  std::filesystem::path cache_dir;           // the index and jobs/ live here
  unsigned workers = 1;                      // jobs running at once
  std::string worker_executable;             // empty: workers::defaultWorkerExecutable()
  std::chrono::milliseconds timeout = std::chrono::hours(2);
  std::uint64_t memory_limit_bytes = std::uint64_t{8} << 30;
  std::size_t queue_capacity = 64;           // jobs waiting; beyond: RESOURCE_EXHAUSTED
  // Files a job's parameters may name lie under these directories or under jobs/ (the
  // results of earlier jobs); nothing else is readable to a job.
  std::vector<std::filesystem::path> data_dirs;
  // Checks a submission before it is queued (known kind, parameters well formed, files
  // under `readable_dirs`): an INVALID_ARGUMENT status naming the field, or OK. Unset:
  // every kind is accepted.
  std::function<Status(const std::string& kind, const std::string& params_json,
                       const std::vector<std::filesystem::path>& readable_dirs)>
      validate;
};

// Who asks (the service's Caller, deploy/security.md "Ownership"): a job belongs to the
// caller that submitted it; JobStatus, CancelJob and JobResult of another caller's job are
// PERMISSION_DENIED and job listings leave it out, unless the caller is an operator.
struct JobCaller {
  std::string name;
  bool operator_ = false;
};

// A submission's parameters with a "spec_json" object turned into its text in the order
// written: a user spec's inputs and defines are in order (its calling convention), which
// the sorted keys of the JSON parameters would change on the way to the job's worker.
// "" when params_json is not a JSON object.
std::string jobParamsKeepingSpecOrder(const std::string& params_json);

struct JobCounts {
  std::uint32_t queued = 0, running = 0, succeeded = 0, failed = 0, cancelled = 0;
};

class JobManager {
 public:
  // Opens the job index in the cache and starts the job workers. Throws (cache::CacheError,
  // std::runtime_error) with a message a person can act on.
  JobManager(JobManagerOptions options, Logger& log);
  // Cancels what still runs or waits; those jobs end FAILED ("robodiffd stopped").
  ~JobManager();
  JobManager(const JobManager&) = delete;
  JobManager& operator=(const JobManager&) = delete;

  Status submit(const JobCaller& caller, const rpc::SubmitJobRequest& request, rpc::SubmitJobReply& reply);
  // An empty id lists the caller's jobs in the index (this server's and earlier ones'; an
  // operator's: every job).
  Status status(const JobCaller& caller, const rpc::JobStatusRequest& request, rpc::JobStatusReply& reply);
  // The newest `limit` jobs in the index (0: all), newest first; live ones as they run.
  // Every caller's (the dashboard).
  std::vector<rpc::JobInfo> recent(std::size_t limit);
  // Waits (up to 2 s) until a running job's worker is gone, so the reply's state is final.
  Status cancel(const JobCaller& caller, const rpc::CancelJobRequest& request, rpc::CancelJobReply& reply);
  // FAILED_PRECONDITION until the job has succeeded; NOT_FOUND for an unknown id.
  Status result(const JobCaller& caller, const rpc::JobResultRequest& request, rpc::JobResultReply& reply);

  JobCounts counts() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace robodiff::server
