#pragma once
// Service::State: everything a Service owns, in the order it is built (and the reverse
// of the order it goes): the cache, the worker pool, the registry, the builds, the
// batch threads, the jobs, the request threads. Shared by service.cpp (requests, lifetime),
// service_evaluation.cpp (the hot path) and service_health.cpp (figures).

#include <atomic>
#include <memory>
#include <string>

#include "artifact_serving.hpp"
#include "batch_runner.hpp"
#include "function_builds.hpp"
#include "registry.hpp"
#include "request_stats.hpp"
#include "robodiff/cache/cache.hpp"
#include "robodiff/language/bounded_text.hpp"
#include "robodiff/server/job_manager.hpp"
#include "robodiff/server/service.hpp"
#include "robodiff/workers/worker_pool.hpp"
#include "task_queue.hpp"

namespace robodiff::server {

struct Service::State {
  State(ServiceOptions options, Logger& log);
  // A function that failed is unloaded at once: it holds no slot (FunctionBuilds' callback).
  void unloadFailed(const std::shared_ptr<detail::FunctionEntry>& function);

  ServiceOptions options;
  Logger& log;
  std::string instance_id;
  Clock::time_point started = Clock::now();
  std::atomic<rpc::ServingState> serving{rpc::ServingState::Starting};
  std::atomic<std::uint64_t> in_flight{0};  // requests being served (posted ones included)

  cache::Cache cache;
  workers::WorkerPool pool;
  detail::Registry registry{{options.max_models_per_client, options.max_functions_per_client}};
  detail::RequestStats stats;
  detail::FunctionBuilds builds;
  std::unique_ptr<detail::ArtifactServing> artifacts;  // null: not a build host
  detail::BatchRunner batch;
  std::unique_ptr<JobManager> jobs;  // null: options.job_workers == 0
  detail::TaskQueue requests;  // last: its threads call into everything above
};

// Counts a request in flight for as long as it lives (waitIdle and draining wait for 0).
class InFlight {
 public:
  explicit InFlight(std::atomic<std::uint64_t>& count) : count_(count) {
    count_.fetch_add(1, std::memory_order_acq_rel);
  }
  ~InFlight() { count_.fetch_sub(1, std::memory_order_acq_rel); }
  InFlight(const InFlight&) = delete;
  InFlight& operator=(const InFlight&) = delete;

 private:
  std::atomic<std::uint64_t>& count_;
};

namespace detail {
inline constexpr const char* kShuttingDown =
    "robodiffd is shutting down (SIGTERM); retry against another server or after restart";
Status deadlineExceeded(const CallContext& ctx, const char* method);
// The most of an error message a reply carries (a message quoting client input is cut).
inline constexpr std::size_t kMaxErrorBytes = 1024;

// Every request method answers with a status, never an exception: a transport's thread
// must survive whatever goes wrong inside.
template <class Body>
Status guarded(Logger& log, const char* method, Body&& body) {
  try {
    return body();
  } catch (const std::exception& e) {
    const std::string what = language::boundedText(e.what(), kMaxErrorBytes);
    log.error("internal_error", {{"method", method}, {"message", what}});
    return {StatusCode::Internal, std::string(method) + " failed inside the server: " + what};
  } catch (...) {
    log.error("internal_error", {{"method", method}, {"message", "unknown exception"}});
    return {StatusCode::Internal, std::string(method) + " failed inside the server (unknown exception)"};
  }
}
}  // namespace detail

}  // namespace robodiff::server
