#include "robodiff/workers/cached_builder.hpp"

#include "build_run.hpp"

namespace robodiff::workers {

const char* toString(BuildState state) {
  switch (state) {
    case BuildState::Pending: return "pending";
    case BuildState::Cached: return "cached";
    case BuildState::Waiting: return "waiting";
    case BuildState::Queued: return "queued";
    case BuildState::Building: return "building";
    case BuildState::Done: return "done";
    case BuildState::Failed: return "failed";
  }
  return "?";
}

CachedBuilder::CachedBuilder(cache::Cache& cache, WorkerPool& pool, CachedBuilderOptions options)
    : cache_(cache), pool_(pool), options_(std::move(options)) {}

std::vector<BuildStatus> CachedBuilder::buildAll(const std::vector<BuildTarget>& targets, const Listener& listener) {
  BuildRun run(cache_, pool_, options_, worker_death_retries_, listener);
  return run.execute(targets);
}

}  // namespace robodiff::workers
