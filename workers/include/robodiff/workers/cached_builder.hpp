// Builds (robot, spec) pairs through the cache and the worker pool, each key once
// across every process sharing the cache:
//   - ready in the cache: reported Cached at once (hash checked);
//   - being built by another process: Waiting until it is ready (Cached), or until that
//     process's claim lapses (then this process claims it);
//   - otherwise claimed here, queued to a worker (Queued, Building), published by the
//     worker (Done); a failed job drops the claim and leaves nothing behind; a job whose
//     worker died is retried (bounded, with backoff) before it counts as failed.
// Claims in flight are renewed by a thread of their own while workers build.
// Used by `robodiff warmup` now and the server later.
#pragma once

#include <atomic>
#include <chrono>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "robodiff/cache/cache.hpp"
#include "robodiff/model/model.hpp"
#include "robodiff/model/urdf_limits.hpp"
#include "robodiff/workers/worker_pool.hpp"

namespace robodiff::workers {

// A robot and a spec to build, read from files, or given as text (a server has them
// in memory): when urdf_text / spec_text is set it is used, and the path then only names
// the source in messages. A caller that has parsed the robot already (robodiffd) passes
// the model and its canonical hash too, so that it is neither parsed nor hashed again
// here (the worker still parses the text: it is another process). (The fields after the
// first four have initialisers so that brace-initialising only those stays free of
// -Wmissing-field-initializers.)
struct BuildTarget {
  std::string urdf_path;
  bool floating_base = false;
  std::string spec_path;
  std::string function_name;  // C name; empty: the spec's function
  std::string urdf_text = {};  // set: the URDF itself (urdf_path is not read)
  std::string spec_text = {};  // set: the spec's JSON itself (spec_path is not read)
  std::shared_ptr<const Model> model = {};  // set (with urdf_text and model_hash): urdf_text parsed
  std::string model_hash = {};              // canonicalHash(*model)
};

enum class BuildState : std::uint8_t {
  Pending,   // not looked at yet
  Cached,    // was in the cache (or another process built it while we waited)
  Waiting,   // another process is building it
  Queued,    // claimed here, waiting for a worker
  Building,  // a worker builds it (`stage` says where it is)
  Done,      // built here and published
  Failed,    // `message` says why; nothing was published
};
const char* toString(BuildState state);
inline bool isFinal(BuildState s) { return s == BuildState::Cached || s == BuildState::Done || s == BuildState::Failed; }

struct BuildStatus {
  BuildState state = BuildState::Pending;
  std::string robot;     // the model's name, or the URDF path before it is loaded
  std::string function;  // the function's C name, or the spec path before it is read
  std::string key;
  std::string stage;     // Building: "model", "trace", "compile", "publish"
  std::string message;   // Failed: the reason (the compiler's first lines included); Waiting: who builds it
  double seconds = 0;    // since a worker took it (before: since buildAll began); final: how long it took
  std::uint64_t library_bytes = 0;
};

struct CachedBuilderOptions {
  std::string compiler;  // empty: $CC or cc
  // The limits URDFs are read under, here and in the workers: a server passes the ones
  // its LoadModel applies, so that a robot it accepted is never refused by its builds.
  UrdfLimits urdf_limits;
  std::uint64_t compiler_memory_limit_bytes = std::uint64_t{4} << 30;
  std::chrono::milliseconds job_timeout = std::chrono::minutes(15);
  std::chrono::milliseconds poll_interval = std::chrono::milliseconds(100);  // while Waiting
  // A build whose worker died (killed, crashed, out of memory: JobState::Crashed) is
  // submitted again, under the same claim, after each of these pauses in turn; then it
  // fails naming the last death and the number of attempts. A build that failed (a
  // compiler error, a timeout) is never retried.
  std::vector<std::chrono::milliseconds> worker_death_backoff = {std::chrono::milliseconds(500),
                                                                 std::chrono::seconds(2)};
};

class CachedBuilder {
 public:
  CachedBuilder(cache::Cache& cache, WorkerPool& pool, CachedBuilderOptions options = {});

  // Called on every change of a target's status (index into the targets), from the
  // calling thread or the pool's thread; never concurrently.
  using Listener = std::function<void(std::size_t index, const BuildStatus& status)>;

  // Builds every target and returns their final statuses (same order). Returns when all
  // are final.
  std::vector<BuildStatus> buildAll(const std::vector<BuildTarget>& targets, const Listener& listener = {});

  // Builds tried again because their worker died, since this builder was made.
  std::uint64_t workerDeathRetries() const { return worker_death_retries_.load(std::memory_order_relaxed); }

 private:
  cache::Cache& cache_;
  WorkerPool& pool_;
  CachedBuilderOptions options_;
  std::atomic<std::uint64_t> worker_death_retries_{0};
};

}  // namespace robodiff::workers
