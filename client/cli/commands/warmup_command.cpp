// `robodiff warmup`: builds every (robot, spec) pair into the cache through a pool of
// worker processes, each key once across every process sharing the cache, and shows
// the progress (warmup_progress.hpp).
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <iostream>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "commands/commands.hpp"
#include "robodiff/cache/cache.hpp"
#include "robodiff/workers/cached_builder.hpp"
#include "robodiff/workers/warmup_targets.hpp"
#include "robodiff/workers/worker_pool.hpp"
#include "options/cache_location.hpp"
#include "output/human_units.hpp"
#include "service/service_connection.hpp"
#include "output/warmup_progress.hpp"
#include "service/warmup_server.hpp"

namespace robodiff::cli {
namespace {

struct WarmupArgs {
  std::vector<std::string> urdfs, specs;
  bool floating_base = false;
  unsigned jobs = workers::defaultWarmupWorkers();
  std::string cache_dir, compiler, budget;
  std::optional<double> timeout_seconds;
  bool json = false;
  bool on_server = false;  // --server given: the running server builds
  std::string server;      // its value; empty: $ROBODIFF_SERVER, else auto
};

// The files named on the command line, checked (missing files and specs that do not
// parse are reported before anything is built) and paired (warmup_targets.hpp).
std::vector<workers::BuildTarget> targetsOf(const WarmupArgs& args) {
  const workers::WarmupRequest request{args.urdfs, args.specs, args.floating_base};
  workers::checkWarmupInputs(request, "--urdf", "--spec");
  return workers::warmupTargets(request);
}

cache::Cache openCache(const WarmupArgs& args) { return openCliCache(cacheDirFor(args.cache_dir), args.budget, true); }

void warmup(const WarmupArgs& args) {
  const std::vector<workers::BuildTarget> targets = targetsOf(args);
  if (args.on_server) {
    warmupOnServer(targets, {args.server, args.timeout_seconds, args.json});
    return;
  }
  cache::Cache cache = openCache(args);

  workers::WorkerPoolOptions pool_options;
  pool_options.workers = args.jobs;
  workers::CachedBuilderOptions builder_options;
  builder_options.compiler = args.compiler;
  if (args.timeout_seconds) {
    const auto timeout = std::chrono::milliseconds(std::llround(*args.timeout_seconds * 1000.0));
    builder_options.job_timeout = timeout;
    pool_options.default_timeout = timeout;
  }
  workers::WorkerPool pool(pool_options);
  workers::CachedBuilder builder(cache, pool, builder_options);

  std::vector<std::string> spec_paths;
  for (const workers::BuildTarget& t : targets) spec_paths.push_back(t.spec_path);
  WarmupProgress progress(chooseProgressStyle(args.json), std::cout, spec_paths, args.jobs);
  const std::vector<workers::BuildStatus> finals = builder.buildAll(
      targets, [&progress](std::size_t index, const workers::BuildStatus& status) { progress.update(index, status); });
  progress.finish(finals);

  const bool failed = std::any_of(finals.begin(), finals.end(),
                                  [](const workers::BuildStatus& s) { return s.state == workers::BuildState::Failed; });
  if (failed) throw CLI::RuntimeError(1);  // each failure is listed already; main returns the status
}

}  // namespace

void addWarmupCommand(CLI::App& app) {
  auto args = std::make_shared<WarmupArgs>();
  CLI::App* cmd = app.add_subcommand(
      "warmup", "Build every (robot, spec) pair into the cache, in worker processes, so that later loads are instant");
  cmd->add_option("--urdf", args->urdfs, "Robot descriptions (URDF files); every one is built with every spec")
      ->required()
      ->type_name("FILE");
  cmd->add_flag("--floating-base", args->floating_base, "Add a free-flyer root joint to every robot");
  cmd->add_option("--spec", args->specs,
                  "Function specs (JSON, schema/function-spec.schema.json; examples in examples/specs/)")
      ->required()
      ->type_name("SPEC.json");
  CLI::Option* jobs = cmd->add_option(
         "--jobs,-j", args->jobs,
         "Worker processes building at once (default " + std::to_string(workers::defaultWarmupWorkers()) + ": the cores, at most 2)")
      ->check(CLI::Range(1u, 256u))
      ->type_name("N");
  CLI::Option* cache = cmd->add_option("--cache", args->cache_dir,
                  "Cache directory (default: $ROBODIFF_CACHE_DIR, else $XDG_CACHE_HOME/robodiff, else "
                  "~/.cache/robodiff); created 0700; refused when other users may write to it")
      ->type_name("DIR");
  CLI::Option* compiler = cmd->add_option("--compiler", args->compiler, "C compiler to run, a path or a name in PATH (default: $CC, else cc)")
      ->type_name("CC");
  cmd->add_option("--timeout", args->timeout_seconds,
                  "Longest one function's build may take; past it the worker is killed and the function fails "
                  "(default 900). With --server: how long to wait for every function to be compiled")
      ->check(CLI::PositiveNumber)
      ->type_name("SECONDS");
  CLI::Option* budget = cmd->add_option("--budget", args->budget,
                  "Size budget of the cache; the least recently used entries not in use are evicted to keep it "
                  "(e.g. 500M, 2G, 1.5GiB, or bytes; default 4G)")
      ->type_name("SIZE");
  CLI::Option* server =
      cmd->add_option("--server", args->server,
                      "Ask the running robodiffd to build them instead (LoadModel and GetFunction for each pair, then "
                      "ListFunctions until each is compiled or its build failed). ADDR: auto, shm, shm:<service>, dds, "
                      "dds:<domain>; without it $ROBODIFF_SERVER, else auto")
          ->expected(0, 1)
          ->check(serverAddressValidator())
          ->type_name("[ADDR]");
  server->excludes(jobs)->excludes(cache)->excludes(compiler)->excludes(budget);
  cmd->add_flag("--json", args->json,
                "Print JSON lines: {\"event\": \"state\", ...} at each state change, then {\"event\": \"summary\", "
                "...}");
  cmd->footer(
      "Each function is cached (already built, library hash checked), waiting (another process builds it), "
      "queued, building (model, trace, compile, publish), done (built here) or failed. On a terminal the "
      "functions are redrawn in place under a progress bar with an ETA; otherwise one line per change.\n"
      "Exit status: 0 when every function is cached or built; 1 when one or more failed (each is listed with "
      "its reason at the end, on stderr too), or on errors (missing file, bad spec, unusable cache directory). With "
      "--server: 2 bad usage, 3 no server reachable (UNAVAILABLE); a function served but not compiled (the server's "
      "build failed, or it compiles nothing) counts as failed.");
  cmd->callback([args, server] {
    args->on_server = server->count() > 0;
    warmup(*args);
  });
}

}  // namespace robodiff::cli
