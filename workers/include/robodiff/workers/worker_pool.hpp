// A pool of `robodiff-worker` processes.
//
// Jobs are JSON requests; the pool queues them (bounded), hands each to an idle worker
// over the worker's stdin and reads its replies from the worker's stdout (frames: a
// 4-byte little-endian length, then JSON; see worker_protocol.hpp). A worker may send
// progress messages before its one result.
//
// Isolation: each worker leads its own session and process group (so that everything it
// starts can be found and killed, orphans included), runs a job under the job's
// address-space limit (setrlimit, set by the worker itself), and dies with the pool
// (PR_SET_PDEATHSIG: workers are started by the pool's own thread, which lives as long
// as the pool). A job past its timeout, or cancelled while running, gets its worker and
// everything the worker started killed. A worker that dies during a job fails only that
// job (JobState::Crashed, with the signal or exit status), and the pool starts a new
// worker in its place (a second later when the last one exited by itself right after
// it started: a broken install is not restarted in a tight loop).
//
// SIGPIPE: the pool's thread blocks it for itself (a write to a dead worker fails with
// EPIPE instead); the process's own SIGPIPE disposition is left alone.
#pragma once

#include <chrono>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <future>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include <sys/types.h>

namespace robodiff::workers {

struct WorkerPoolOptions {
  // The worker program; empty: defaultWorkerExecutable().
  std::filesystem::path worker_executable;
  unsigned workers = 1;
  std::size_t queue_capacity = 256;  // jobs waiting (not running); submit throws beyond
  std::chrono::milliseconds default_timeout = std::chrono::minutes(15);
  // RLIMIT_AS of a worker while it runs a job (its compilers have their own); 0: none.
  std::uint64_t memory_limit_bytes = std::uint64_t{8} << 30;
};

enum class JobState : std::uint8_t {
  Queued,
  Running,
  Succeeded,  // the worker replied with a result ({"ok": true, ...})
  Failed,     // the worker replied with an error ({"ok": false, "error": ...})
  Crashed,    // the worker died during the job (signal or exit status in `message`)
  TimedOut,   // killed at the job's timeout
  Cancelled,  // cancelled before it ran, or killed while running, or the pool stopped
};
const char* toString(JobState state);

struct JobResult {
  JobState state = JobState::Queued;
  std::string reply;    // the worker's result message (JSON), when it sent one
  std::string message;  // what went wrong, for a person
  pid_t worker_pid = 0;
  double queued_seconds = 0, run_seconds = 0;
};

struct JobCallbacks {
  std::function<void(pid_t worker_pid)> on_start;             // a worker took the job
  std::function<void(const std::string& message)> on_progress;  // a progress message (JSON)
};
// Callbacks run on the pool's supervisor thread: keep them short, never call back into
// the pool from them. A job's result is set after every callback of that job returned.

using JobId = std::uint64_t;

struct JobHandle {
  JobId id = 0;
  std::shared_future<JobResult> result;
};

class QueueFull : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct WorkerInfo {
  pid_t pid = 0;
  std::optional<JobId> job;   // the job it runs
  std::uint64_t jobs_done = 0;
};

struct PoolStats {
  std::size_t queued = 0, running = 0;
  std::uint64_t succeeded = 0, failed = 0, crashed = 0, timed_out = 0, cancelled = 0;
  std::uint64_t workers_started = 0;  // restarts included
};

class WorkerPool {
 public:
  // Starts the workers. Throws std::runtime_error when the worker program cannot be found
  // or started.
  explicit WorkerPool(WorkerPoolOptions options);
  // Cancels queued and running jobs and stops the workers (SIGTERM, then SIGKILL).
  ~WorkerPool();
  WorkerPool(const WorkerPool&) = delete;
  WorkerPool& operator=(const WorkerPool&) = delete;

  // Queues a job. `request_json`: a JSON object with a "type" (worker_protocol.hpp:
  // buildRequestMessage, pingRequest); the pool adds "id", and "limits" from the options
  // unless the request has its own. Throws std::invalid_argument when it is not such an
  // object, ProtocolError when it is larger than a frame may be, QueueFull when
  // queue_capacity jobs already wait (jobs about to go to an idle worker do not count).
  JobHandle submit(std::string request_json, JobCallbacks callbacks = {},
                   std::optional<std::chrono::milliseconds> timeout = std::nullopt);
  // Cancels a queued or running job; false when it has already finished or is unknown.
  // When true, the job's result is Cancelled: at once for a queued job, once its worker
  // is killed for a running one.
  bool cancel(JobId id);

  std::vector<WorkerInfo> workers() const;
  PoolStats stats() const;
  const WorkerPoolOptions& options() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// robodiff-worker beside the running executable (/proc/self/exe: the build tree), else
// where `cmake --install` puts it relative to that executable (../libexec/robodiff), else
// in PATH; empty when none exists.
std::filesystem::path defaultWorkerExecutable();

}  // namespace robodiff::workers
