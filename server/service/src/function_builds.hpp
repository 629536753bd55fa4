#pragma once
// How a new function becomes servable, off the request threads:
//   1. trace stage (its own threads): with compiling on, look in the cache first; a hit
//      loads the library (READY, compiled). A miss traces the function and serves it with
//      the interpreter at once (READY, interpreted), then hands it to
//   1b. fetch stage (a robot host of a fleet, its own threads): the build hosts are asked
//      for the library; one delivered is loaded and swapped in like a built one; when
//      none can deliver, the compile stage builds it here (if compiling is on).
//   2. compile stage (one thread per build worker, one library build per function; the
//      worker pool queues them): the CachedBuilder builds the library into the cache;
//      on success it is loaded and swapped in, on failure the interpreter keeps serving
//      and the failure is logged, counted and kept as the function's message.
// stop() fails functions not traced yet (UNAVAILABLE), skips builds not started and
// cancels the running ones. A function that fails (never becomes READY) is handed to the
// `failed` callback, which unloads it: a failed function holds no slot; the bounded list
// of recent failures remembers it for the dashboard and for GetFunction's answer.

#include <atomic>
#include <chrono>
#include <cstdint>
#include <deque>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "function_entry.hpp"
#include "robodiff/server/artifact_source.hpp"
#include "robodiff/cache/cache.hpp"
#include "robodiff/model/urdf_limits.hpp"
#include "robodiff/server/log.hpp"
#include "robodiff/workers/cached_builder.hpp"
#include "robodiff/workers/worker_pool.hpp"
#include "task_queue.hpp"

namespace robodiff::server::detail {

struct BuildSettings {
  bool compile = true;
  std::string compiler;
  std::chrono::milliseconds build_timeout = std::chrono::minutes(15);
  std::uint64_t compiler_memory_limit_bytes = std::uint64_t{4} << 30;
  unsigned trace_threads = 2;
  unsigned compile_threads = 1;
  UrdfLimits urdf_limits;  // LoadModel's (max_bytes capped by max_urdf_bytes), for the workers
  // A robot host's build hosts (artifact_source.hpp): asked before this host compiles.
  std::shared_ptr<ArtifactSource> source;
  unsigned fetch_threads = 2;
};

struct BuildFigures {
  std::uint64_t cache_hits = 0, cache_misses = 0;
  std::uint32_t builds_queued = 0, builds_running = 0, builds_failed = 0, builds_done = 0;
  std::uint64_t build_retries = 0;  // builds tried again after their worker died
  std::uint64_t specs_invalid = 0;  // functions failed as invalid specs (never built; not in builds_failed)
  std::uint64_t libraries_fetched = 0;  // delivered by a build host (robot host)
};

// Where a function failed.
enum class FailureStage : std::uint8_t {
  InvalidSpec,  // the spec never built: it does not fit the model (unknown frame, ...) or is too large
  Trace,        // tracing failed for another reason (out of memory, stopping, internal)
  Compile,      // only the library failed: the interpreter still serves the function
};
const char* toString(FailureStage stage);  // "invalid-spec" | "trace" | "compile"

// A build that failed, kept for the dashboard after its function is gone.
struct BuildFailureRecord {
  std::chrono::system_clock::time_point when;
  std::string function_id, model, function, message;  // message: at most kFailureMessageBytes
  FailureStage stage = FailureStage::Trace;
  Status status;  // what GetFunction answered (not OK unless stage is Compile)
  bool interpreter_serves() const { return stage == FailureStage::Compile; }
};

// The CachedBuilder's options for these settings (the service's and a build host's builds).
workers::CachedBuilderOptions builderOptions(const BuildSettings& settings);

class FunctionBuilds {
 public:
  // Called with a function that failed (it never became READY), on a build thread.
  using FailedCallback = std::function<void(const std::shared_ptr<FunctionEntry>&)>;
  FunctionBuilds(BuildSettings settings, cache::Cache& cache, workers::WorkerPool& pool, Logger& log,
                 FailedCallback failed = {});
  ~FunctionBuilds();  // stop()
  FunctionBuilds(const FunctionBuilds&) = delete;
  FunctionBuilds& operator=(const FunctionBuilds&) = delete;

  // Starts making `function` (BUILDING) servable.
  void start(std::shared_ptr<FunctionEntry> function);
  // A compiled function whose cache entry is gone (quarantined by a process that found
  // its files missing or changed, or lost with the index): its library in memory keeps
  // serving, and the entry is built again in the background, so that local clients and
  // the next start find it. Cheap when the entry is there (one index lookup).
  void refillIfMissing(const std::shared_ptr<FunctionEntry>& function);
  void stop();

  BuildFigures figures() const;
  // The latest failures (tracing or compiling), newest first; at most kKeptFailures.
  std::vector<BuildFailureRecord> recentFailures() const;
  // The answer kept for function `function_id` when its spec recently failed as invalid
  // (the same spec fails the same way: GetFunction answers without tracing again).
  std::optional<Status> recentInvalidSpec(std::string_view function_id) const;
  static constexpr std::size_t kKeptFailures = 64;
  static constexpr std::size_t kFailureMessageBytes = 1024;

 private:
  void trace(const std::shared_ptr<FunctionEntry>& function);
  // Ends `function` without tracing when the server is stopping or it was released (true).
  bool refusedBeforeTrace(const std::shared_ptr<FunctionEntry>& function);
  // Serves `function` from a library built before (true): by its key, when this server
  // compiles and the key can be made (else `key_problem` says why not), or by its
  // portable key.
  bool servedFromCache(const std::shared_ptr<FunctionEntry>& function, std::string& key_problem);
  // Serves `function` from a cached library (true), by its key or by its portable key
  // (built elsewhere: cache::preparePortableKey needs no compiler).
  bool loadFromCache(const std::shared_ptr<FunctionEntry>& function, const std::string& key);
  bool loadPortable(const std::shared_ptr<FunctionEntry>& function);
  bool loadArtifact(const std::shared_ptr<FunctionEntry>& function, const char* source,
                    const std::function<std::optional<cache::Artifact>()>& lookUp);
  // The interpreter for `f` (OK), or why it cannot be traced (`stage` says where).
  static Status interpret(const FunctionEntry& f, std::shared_ptr<const Evaluator>& evaluator,
                          std::size_t& instructions, std::size_t& nodes, FailureStage& stage);
  void compile(const std::shared_ptr<FunctionEntry>& function);
  void fetch(const std::shared_ptr<FunctionEntry>& function, bool may_compile);
  void refill(const std::shared_ptr<FunctionEntry>& function, const std::string& key);
  static workers::BuildTarget buildTarget(const FunctionEntry& function);
  // `fetched`: delivered by a build host, not built here.
  void swapIn(const std::shared_ptr<FunctionEntry>& function, const workers::BuildStatus& status,
              bool fetched = false);
  void buildFailed(const std::shared_ptr<FunctionEntry>& function, const std::string& message);
  void cancelRunningBuilds();
  void keepFailure(const FunctionEntry& function, const std::string& message, FailureStage stage, Status status);
  // Fails `function` (BUILDING -> FAILED), records and logs why, and hands it to failed_.
  void failFunction(const std::shared_ptr<FunctionEntry>& function, Status status, FailureStage stage);

  BuildSettings settings_;
  cache::Cache& cache_;
  workers::WorkerPool& pool_;
  workers::CachedBuilder builder_;
  Logger& log_;
  FailedCallback failed_;
  std::atomic<bool> stopping_{false};

  std::atomic<std::uint64_t> cache_hits_{0}, cache_misses_{0};
  std::atomic<std::uint32_t> builds_queued_{0}, builds_running_{0}, builds_failed_{0}, builds_done_{0};
  std::atomic<std::uint64_t> specs_invalid_{0}, libraries_fetched_{0};
  mutable std::mutex failures_mutex_;
  std::deque<BuildFailureRecord> failures_;  // newest first

  // Last: their threads use everything above and are joined first.
  TaskQueue compile_queue_;
  TaskQueue fetch_queue_;  // posts to compile_queue_
  TaskQueue trace_queue_;  // posts to both
};

}  // namespace robodiff::server::detail
