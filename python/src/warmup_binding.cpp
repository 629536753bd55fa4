// robodiff._robodiff.warmup: `robodiff warmup` from Python. The same library code as the
// CLI (warmup_targets.hpp, CachedBuilder over a WorkerPool of robodiff-worker processes);
// the GIL is released while building and re-acquired only to call `progress` as each
// function finishes. robodiff/warmup.py wraps the results.
#include <algorithm>
#include <chrono>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include <nanobind/stl/filesystem.h>
#include <nanobind/stl/optional.h>
#include <nanobind/stl/string.h>
#include <nanobind/stl/vector.h>

#include "bindings.hpp"
#include "cache_open.hpp"
#include "robodiff/client/client.hpp"
#include "robodiff/workers/cached_builder.hpp"
#include "robodiff/workers/warmup_targets.hpp"
#include "robodiff/workers/worker_pool.hpp"

namespace nb = nanobind;
namespace fs = std::filesystem;

namespace robodiff::python {
namespace {

// The worker program: the build tree's when this module was built there and it exists,
// else the pool's search (beside the interpreter, its libexec/robodiff, PATH).
fs::path workerExecutable() {
#ifdef ROBODIFF_PYTHON_BUILD_TREE_WORKER
  std::error_code ec;
  if (fs::is_regular_file(ROBODIFF_PYTHON_BUILD_TREE_WORKER, ec)) return ROBODIFF_PYTHON_BUILD_TREE_WORKER;
#endif
  return {};
}

[[noreturn]] void throwStatus(StatusCode code, const std::string& message) {
  throw client::ClientError({code, message});
}

// One target's final status as the dict robodiff/warmup.py reads.
nb::dict outcomeDict(const workers::BuildTarget& target, const workers::BuildStatus& s) {
  nb::dict d;
  d["urdf"] = target.urdf_path;
  d["spec"] = target.spec_path;
  d["state"] = workers::toString(s.state);
  d["robot"] = s.robot;
  d["function"] = s.function;
  d["key"] = s.key;
  d["message"] = s.message;
  d["seconds"] = s.seconds;
  d["library_bytes"] = s.library_bytes;
  return d;
}

// Calls `progress` once per target as it becomes final, with the GIL; the first
// exception it raises is kept (and raised by warmup at the end) and stops further calls.
struct ProgressRelay {
  ProgressRelay(const std::vector<workers::BuildTarget>& all, nb::object callback)
      : targets(all), progress(std::move(callback)), reported(all.size(), false) {}

  const std::vector<workers::BuildTarget>& targets;
  nb::object progress;  // None: nothing to call
  std::vector<bool> reported;
  std::optional<nb::python_error> error;

  void operator()(std::size_t index, const workers::BuildStatus& status) {
    if (!workers::isFinal(status.state) || reported.at(index)) return;
    reported[index] = true;
    if (progress.is_none()) return;
    nb::gil_scoped_acquire acquire;
    if (error) return;
    try {
      progress(outcomeDict(targets[index], status));
    } catch (nb::python_error& e) {
      error.emplace(std::move(e));
    }
  }
};

std::vector<workers::BuildTarget> checkedTargets(const workers::WarmupRequest& request) {
  if (request.urdf_paths.empty()) throwStatus(StatusCode::InvalidArgument, "warmup: no URDF given");
  if (request.spec_paths.empty()) throwStatus(StatusCode::InvalidArgument, "warmup: no spec given");
  try {
    workers::checkWarmupInputs(request, "urdf", "spec");
    return workers::warmupTargets(request);
  } catch (const std::exception& e) {  // a missing file, a spec that does not parse
    throwStatus(StatusCode::InvalidArgument, e.what());
  }
}

nb::list warmup(const std::vector<std::string>& urdfs, const std::vector<std::string>& specs,
                const std::optional<fs::path>& cache_dir, bool floating_base, std::optional<unsigned> jobs,
                nb::object progress) {
  if (jobs && (*jobs < 1 || *jobs > 256)) throw nb::value_error("jobs must be between 1 and 256");
  if (!progress.is_none() && !PyCallable_Check(progress.ptr()))
    throw nb::type_error("progress must be callable or None");
  const workers::WarmupRequest request{urdfs, specs, floating_base};
  std::vector<workers::BuildTarget> targets;
  std::vector<workers::BuildStatus> finals;
  ProgressRelay relay(targets, progress);
  {
    nb::gil_scoped_release release;
    targets = checkedTargets(request);
    relay.reported.assign(targets.size(), false);
    cache::Cache cache = openCache(cacheDirOr(cache_dir), true);
    workers::WorkerPoolOptions pool_options;
    pool_options.workers = jobs.value_or(workers::defaultWarmupWorkers());
    pool_options.worker_executable = workerExecutable();
    std::optional<workers::WorkerPool> pool;
    try {
      pool.emplace(pool_options);
    } catch (const std::exception& e) {  // no robodiff-worker, or it cannot start
      throwStatus(StatusCode::FailedPrecondition, std::string("warmup: ") + e.what());
    }
    workers::CachedBuilder builder(cache, *pool);
    finals = builder.buildAll(targets, [&relay](std::size_t i, const workers::BuildStatus& s) { relay(i, s); });
  }
  if (relay.error) throw std::move(*relay.error);
  nb::list results;
  for (std::size_t i = 0; i < targets.size(); ++i) results.append(outcomeDict(targets[i], finals[i]));
  return results;
}

}  // namespace

void bindWarmup(nb::module_& m) {
  m.def("warmup", &warmup, nb::arg("urdfs"), nb::arg("specs"), nb::arg("cache_dir").none() = nb::none(),
        nb::arg("floating_base") = false, nb::arg("jobs").none() = nb::none(), nb::arg("progress").none() = nb::none(),
        "Builds every (URDF, spec) pair into the cache; one dict per pair (robodiff.warmup wraps them).");
}

}  // namespace robodiff::python
