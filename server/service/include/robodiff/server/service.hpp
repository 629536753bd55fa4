#pragma once
// The service itself: a registry of models and functions, evaluation on the cached
// libraries (the interpreter serves a function from the moment it is traced until its
// compiled library is ready, then the library is swapped in), builds through the cache
// and the worker pool, batches spread over threads, a bounded request queue, deadlines,
// draining, and the figures Health reports. Transports call it through ServiceApi.

#include <chrono>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "robodiff/model/urdf_limits.hpp"
#include "robodiff/server/artifact_source.hpp"
#include "robodiff/server/job_manager.hpp"
#include "robodiff/server/log.hpp"
#include "robodiff/server/service_api.hpp"

namespace robodiff::server {

// A build host's side of a fleet (fleet.role = build).
struct ArtifactServingOptions {
  bool enabled = false;
  std::filesystem::path signing_key;  // Ed25519 private key (robodiff keygen); required when enabled
  bool build_for_robots = true;       // build what a robot asks for and this host lacks
  std::uint32_t max_builds_per_caller = 4;     // robots' builds queued or running, per caller
  std::uint32_t chunk_bytes = 256 * 1024;      // FetchArtifactChunk's most bytes per reply
  std::size_t signed_entries_kept = 16;        // signed payloads kept in memory for chunk requests
  // Sleeps this long before each chunk it serves: failover drills and tests (a build host
  // that is killed mid-transfer). 0 in production.
  std::chrono::milliseconds chunk_delay{0};
};

struct ServiceOptions {
  std::filesystem::path cache_dir;           // empty: cache::defaultCacheDir()
  std::uint64_t cache_budget_bytes = std::uint64_t{4} << 30;
  unsigned build_workers = 1;                // worker processes compiling libraries
  std::string worker_executable;             // empty: workers::defaultWorkerExecutable()
  std::string compiler;                      // empty: $CC or cc
  std::chrono::milliseconds build_timeout = std::chrono::minutes(15);
  std::uint64_t compiler_memory_limit_bytes = std::uint64_t{4} << 30;
  bool compile = true;                       // false: the interpreter serves every function
  unsigned request_threads = 2;              // run posted requests (LoadModel, GetFunction, ...)
  std::size_t request_queue_capacity = 256;  // posted requests waiting; beyond: RESOURCE_EXHAUSTED
  unsigned batch_threads = 0;                // EvaluateBatch pieces in parallel; 0: the cores
  // Request and batch threads run this much nicer (Linux nice, per thread) than the
  // transports' receive threads, which serve Evaluate inline: a client flooding expensive
  // requests then cannot take the CPU from the others' Evaluate calls (docs/limits.md).
  unsigned background_nice = 10;
  std::uint32_t max_batch_knots = 100000;    // beyond: RESOURCE_EXHAUSTED
  std::size_t max_models = 64;               // beyond: RESOURCE_EXHAUSTED
  std::size_t max_functions = 1024;          // loaded or being built; failed ones are unloaded
  // Per caller (CallContext::caller): models and functions held (loaded, not released);
  // beyond: RESOURCE_EXHAUSTED naming the limit. So one client cannot take every slot.
  std::size_t max_models_per_client = 32;
  std::size_t max_functions_per_client = 512;
  std::size_t max_spec_bytes = std::size_t{1} << 20;  // a GetFunction spec; beyond: RESOURCE_EXHAUSTED
  std::size_t max_urdf_bytes = std::size_t{16} << 20;  // beyond: RESOURCE_EXHAUSTED
  // Depth, elements, links, joints, name and attribute lengths of a URDF, checked before
  // it is parsed (its max_bytes is capped by max_urdf_bytes); beyond: RESOURCE_EXHAUSTED.
  UrdfLimits urdf_limits;
  std::string instance_id;                   // empty: "<host>:<pid>:<random>"
  std::string version = "0.1.0";             // reported by Health
  // Batch jobs (job_manager.hpp): worker processes of their own; 0: no jobs (UNIMPLEMENTED).
  unsigned job_workers = 1;
  std::chrono::milliseconds job_timeout = std::chrono::hours(2);
  std::uint64_t job_memory_limit_bytes = std::uint64_t{8} << 30;
  // Files a job may read lie under these (or under the cache's jobs/, earlier results).
  std::vector<std::filesystem::path> job_data_dirs;
  // Checks a job's kind and parameters at SubmitJob (robodiffd: batch::validateBatchJob),
  // the files they name under `readable_dirs`.
  std::function<Status(const std::string& kind, const std::string& params_json,
                       const std::vector<std::filesystem::path>& readable_dirs)>
      validate_job;

  // A fleet (docs/fleet.md). Robot host: the build hosts its libraries come from; this
  // host compiles only when they cannot deliver (and `compile` is on).
  std::shared_ptr<ArtifactSource> artifact_source;
  // Build host: serves its libraries to robot hosts (QueryArtifact, FetchArtifactChunk).
  ArtifactServingOptions artifact_serving;
};

// A snapshot of the service's figures for a metrics endpoint (server/http renders it in
// the Prometheus text format): what Health reports, plus replies by method and status and
// the latency histograms as cumulative buckets.
struct ServiceMetrics {
  struct MethodFigures {
    rpc::Method method = rpc::Method::LoadModel;
    std::vector<std::pair<StatusCode, std::uint64_t>> replies;  // OK always, other codes once seen
    std::vector<std::uint64_t> latency_buckets;  // cumulative, one per latency_bounds_seconds
    std::uint64_t latency_count = 0;             // every reply (the +Inf bucket)
    double latency_sum_seconds = 0;
  };
  rpc::ServingState state = rpc::ServingState::Starting;
  double uptime_seconds = 0;
  std::vector<double> latency_bounds_seconds;  // ascending upper bounds ("le")
  std::vector<MethodFigures> methods;          // one per method, in Method order
  std::vector<rpc::TransportCounts> transports;
  std::uint32_t models_loaded = 0, functions_loaded = 0, functions_compiled = 0;
  // builds_failed: library builds that failed (the compiler or its worker); done and failed since start.
  std::uint32_t builds_queued = 0, builds_running = 0, builds_failed = 0, builds_done = 0;
  // Functions whose spec never built since start: it does not fit the model (unknown
  // frame, bad expression, ...) or is too large. Counted apart from builds_failed.
  std::uint64_t specs_invalid = 0;
  std::uint64_t cache_hits = 0, cache_misses = 0, cache_bytes = 0, cache_entries = 0;
  bool cache_stats_ok = true;  // false: the cache's figures could not be read (bytes, entries 0)
  std::uint64_t cache_quarantined = 0;  // entries moved to the cache's quarantine/ (on disk now)
  std::uint64_t build_retries = 0;      // builds tried again after their worker died
  std::uint32_t workers_total = 0, workers_busy = 0;
  std::uint32_t queue_depth = 0, queue_capacity = 0;
  bool jobs_enabled = false;
  JobCounts jobs;
  rpc::FleetFigures fleet;  // role "standalone": no fleet figures
};

// What the dashboard shows (server/http renders it as JSON for GET /api/overview): the
// metrics, and per model, function, failed build and job what a person needs to see.
struct ServiceOverview {
  struct Model {
    std::string id, name;  // name: the URDF's robot name (with the source name when given)
    bool floating_base = false;
    std::uint32_t nq = 0, nv = 0, joints = 0, frames = 0;
    std::uint32_t references = 0, functions = 0;
  };
  struct Function {
    std::string id, model_id, model_name;
    std::string function;  // "rnea"
    std::string outputs;   // "value, jacobian[q,v,a]"
    // tracing | fetching | queued | compiling | compiled | interpreted | build-failed | failed
    std::string phase;
    std::string message;   // why it failed, or why the interpreter serves
    std::uint32_t references = 0;
    std::uint64_t evaluations = 0;  // knots, single and batched
    std::uint64_t calls = 0, p50_ns = 0, p99_ns = 0, max_ns = 0;  // single Evaluate calls, timed in the service
    std::uint64_t batch_calls = 0, batch_knots = 0, batch_ns = 0;
    double trace_seconds = -1, compile_seconds = -1;  // -1: not (yet) done
    bool from_cache = false;                          // the library came from the cache
  };
  struct BuildFailure {
    double unix_seconds = 0;
    std::string function_id, model, function, message;  // message: at most 1 KiB
    bool interpreter_serves = false;
    std::string stage;  // invalid-spec (never built: does not fit the model) | trace | compile
  };
  struct MethodLatency {
    rpc::Method method = rpc::Method::Health;
    std::vector<std::pair<std::uint64_t, std::uint64_t>> buckets;  // (upper bound ns, count), since start
  };
  std::string instance_id, version;
  ServiceMetrics metrics;
  std::vector<rpc::MethodStats> methods;     // p50/p90/p99 since start, per method
  std::vector<MethodLatency> latencies;      // fine histograms: a reader differences two
  std::vector<Model> models;
  std::vector<Function> functions;           // in order of creation
  std::vector<BuildFailure> build_failures;  // newest first, the latest 64
  std::vector<rpc::JobInfo> jobs;            // newest first, at most max_jobs
  std::string jobs_error;                    // the job index could not be read
};

class Service final : public ServiceApi {
 public:
  // Opens the cache and starts the worker pool and the threads. Throws
  // cache::CacheError / std::runtime_error with a message a person can act on.
  Service(ServiceOptions options, Logger& log);
  ~Service() override;  // drains (waits for in-flight work) and stops everything
  Service(const Service&) = delete;
  Service& operator=(const Service&) = delete;

  // Serving from now on (Health: STARTING -> SERVING).
  void markServing();
  // SIGTERM: from now on admit() answers UNAVAILABLE; in-flight requests continue.
  void beginDrain();
  // True when no request is in flight or queued (waits up to `timeout` for that).
  bool waitIdle(std::chrono::milliseconds timeout);
  rpc::ServingState state() const;

  const ServiceOptions& options() const;
  // The figures for a metrics endpoint; cheap (atomics, a cache stats query), any thread.
  ServiceMetrics metrics() const;
  // The dashboard's snapshot; any thread (reads the cache's stats and the job index).
  ServiceOverview overview(std::size_t max_jobs = 50) const;
  // Every method's fine latency histogram since start (its count: the method's requests);
  // cheap (atomics only), any thread. A sampler differences two of them (the dashboard's history).
  std::vector<ServiceOverview::MethodLatency> requestLatencies() const;
  // This server's part in a fleet (FleetStatus's answer); cheap, any thread.
  rpc::FleetFigures fleet() const;

  // ServiceApi
  const std::string& instanceId() const override;
  Status admit(const rpc::RequestHeader& header) const override;
  Status loadModel(const CallContext& ctx, const rpc::LoadModelRequest& request, rpc::LoadModelReply& reply) override;
  Status getFunction(const CallContext& ctx, const rpc::GetFunctionRequest& request,
                     rpc::GetFunctionReply& reply) override;
  Status listFunctions(const CallContext& ctx, const rpc::ListFunctionsRequest& request,
                       rpc::ListFunctionsReply& reply) override;
  Status health(const CallContext& ctx, const rpc::HealthRequest& request, rpc::HealthReply& reply) override;
  Status release(const CallContext& ctx, const rpc::ReleaseRequest& request, rpc::ReleaseReply& reply) override;
  Status submitJob(const CallContext& ctx, const rpc::SubmitJobRequest& request, rpc::SubmitJobReply& reply) override;
  Status jobStatus(const CallContext& ctx, const rpc::JobStatusRequest& request, rpc::JobStatusReply& reply) override;
  Status cancelJob(const CallContext& ctx, const rpc::CancelJobRequest& request, rpc::CancelJobReply& reply) override;
  Status jobResult(const CallContext& ctx, const rpc::JobResultRequest& request, rpc::JobResultReply& reply) override;
  Status queryArtifact(const CallContext& ctx, const rpc::QueryArtifactRequest& request,
                       rpc::QueryArtifactReply& reply) override;
  Status fetchArtifactChunk(const CallContext& ctx, const rpc::FetchArtifactChunkRequest& request,
                            rpc::FetchArtifactChunkReply& reply) override;
  Status fleetStatus(const CallContext& ctx, const rpc::FleetStatusRequest& request,
                     rpc::FleetStatusReply& reply) override;
  Status shape(std::string_view function_id, FunctionShape& shape) override;
  Status evaluate(const CallContext& ctx, std::string_view function_id, std::span<const double> inputs,
                  std::span<double> outputs) override;
  Status evaluateBatch(const CallContext& ctx, std::string_view function_id, std::uint64_t knots,
                       std::span<const double> inputs, std::span<double> outputs) override;
  bool post(std::function<void()> task) override;
  void recordRequest(std::string_view transport, rpc::Method method, StatusCode code,
                     std::chrono::nanoseconds latency) override;

 private:
  struct State;  // service.cpp
  std::unique_ptr<State> state_;
};

}  // namespace robodiff::server
