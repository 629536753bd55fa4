#include "function_builds.hpp"

#include <new>
#include <optional>
#include <thread>

#include "robodiff/functions/function_builder.hpp"
#include "robodiff/functions/function_library.hpp"
#include "robodiff/language/bounded_text.hpp"
#include "robodiff/symbolic/graph.hpp"
#include "robodiff/cache/prepared_build.hpp"

namespace robodiff::server::detail {
namespace {

double secondsSince(Clock::time_point start) { return std::chrono::duration<double>(Clock::now() - start).count(); }

}  // namespace

workers::CachedBuilderOptions builderOptions(const BuildSettings& s) {
  workers::CachedBuilderOptions o;
  o.compiler = s.compiler;
  o.compiler_memory_limit_bytes = s.compiler_memory_limit_bytes;
  o.job_timeout = s.build_timeout;
  o.urdf_limits = s.urdf_limits;
  return o;
}

const char* toString(FailureStage stage) {
  switch (stage) {
    case FailureStage::InvalidSpec: return "invalid-spec";
    case FailureStage::Trace: return "trace";
    case FailureStage::Compile: return "compile";
  }
  return "unknown";
}

FunctionBuilds::FunctionBuilds(BuildSettings settings, cache::Cache& cache, workers::WorkerPool& pool, Logger& log,
                               FailedCallback failed)
    : settings_(std::move(settings)),
      cache_(cache),
      pool_(pool),
      builder_(cache, pool, builderOptions(settings_)),
      log_(log),
      failed_(std::move(failed)),
      compile_queue_("compile", std::max(1u, settings_.compile_threads), 0,
                     [this](const std::string& what) {
                       log_.error("internal_error", {{"message", what}});
                     }),
      fetch_queue_("fetch", settings_.source ? std::max(1u, settings_.fetch_threads) : 1u, 0,
                   [this](const std::string& what) { log_.error("internal_error", {{"message", what}}); }),
      trace_queue_("trace", std::max(1u, settings_.trace_threads), 0, [this](const std::string& what) {
        log_.error("internal_error", {{"message", what}});
      }) {}

FunctionBuilds::~FunctionBuilds() { stop(); }

void FunctionBuilds::start(std::shared_ptr<FunctionEntry> function) {
  if (!trace_queue_.post([this, function] { trace(function); }))
    failFunction(function,
                 {StatusCode::Unavailable, "the server is stopping; function " + function->id() + " was not built"},
                 FailureStage::Trace);
}

void FunctionBuilds::stop() {
  if (stopping_.exchange(true)) return;
  trace_queue_.stop();  // traces not started fail at once (stopping_)
  fetch_queue_.stop();  // fetches see stopping_ and give up
  // Builds not started are skipped (stopping_); running ones are cancelled (their workers
  // are killed, the builder abandons their claims) until none is left.
  while (!compile_queue_.idle()) {
    cancelRunningBuilds();
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  compile_queue_.stop();
}

void FunctionBuilds::cancelRunningBuilds() {
  for (const workers::WorkerInfo& w : pool_.workers())
    if (w.job) pool_.cancel(*w.job);
}

BuildFigures FunctionBuilds::figures() const {
  BuildFigures f;
  f.cache_hits = cache_hits_.load(std::memory_order_relaxed);
  f.cache_misses = cache_misses_.load(std::memory_order_relaxed);
  f.builds_queued = builds_queued_.load(std::memory_order_relaxed);
  f.builds_running = builds_running_.load(std::memory_order_relaxed);
  f.builds_failed = builds_failed_.load(std::memory_order_relaxed);
  f.builds_done = builds_done_.load(std::memory_order_relaxed);
  f.build_retries = builder_.workerDeathRetries();
  f.specs_invalid = specs_invalid_.load(std::memory_order_relaxed);
  f.libraries_fetched = libraries_fetched_.load(std::memory_order_relaxed);
  return f;
}

std::vector<BuildFailureRecord> FunctionBuilds::recentFailures() const {
  std::lock_guard lock(failures_mutex_);
  return {failures_.begin(), failures_.end()};
}

std::optional<Status> FunctionBuilds::recentInvalidSpec(std::string_view function_id) const {
  std::lock_guard lock(failures_mutex_);
  for (const BuildFailureRecord& r : failures_)
    if (r.stage == FailureStage::InvalidSpec && r.function_id == function_id) return r.status;
  return std::nullopt;
}

void FunctionBuilds::keepFailure(const FunctionEntry& function, const std::string& message, FailureStage stage,
                                 Status status) {
  BuildFailureRecord r;
  r.when = std::chrono::system_clock::now();
  r.function_id = function.id();
  r.model = language::boundedText(function.model().displayName());
  r.function = language::boundedText(function.functionName());
  r.message = language::boundedText(message, kFailureMessageBytes);
  r.stage = stage;
  status.message = language::boundedText(status.message, kFailureMessageBytes);
  r.status = std::move(status);
  std::lock_guard lock(failures_mutex_);
  failures_.push_front(std::move(r));
  if (failures_.size() > kKeptFailures) failures_.pop_back();
}

void FunctionBuilds::failFunction(const std::shared_ptr<FunctionEntry>& function, Status status, FailureStage stage) {
  FunctionEntry& f = *function;
  status.message = language::boundedText(status.message, kFailureMessageBytes);
  log_.warn("function_failed", {{"function_id", f.id()},
                                {"stage", toString(stage)},
                                {"code", toString(status.code)},
                                {"message", status.message}});
  if (stage == FailureStage::InvalidSpec) specs_invalid_.fetch_add(1, std::memory_order_relaxed);
  keepFailure(f, status.message, stage, status);
  if (failed_) failed_(function);  // unloaded before waiters wake: none sees it still loaded
  f.fail(status.code, status.message);
}

bool FunctionBuilds::refusedBeforeTrace(const std::shared_ptr<FunctionEntry>& function) {
  FunctionEntry& f = *function;
  if (stopping_) {
    failFunction(function,
                 {StatusCode::Unavailable,
                  "the server stopped before function " + f.id() + " was built; retry after restart"},
                 FailureStage::Trace);
    return true;
  }
  if (f.unloaded()) {
    f.fail(StatusCode::Cancelled, "function " + f.id() + " was released before it was built");  // already unloaded
    return true;
  }
  return false;
}

bool FunctionBuilds::servedFromCache(const std::shared_ptr<FunctionEntry>& function, std::string& key_problem) {
  FunctionEntry& f = *function;
  // Compiling: the library may be in the cache already (built by an earlier run, or by
  // another server sharing the cache).
  if (settings_.compile) {
    std::optional<cache::PreparedBuild> prepared;
    try {
      prepared = cache::prepareBuild(*f.model().model, f.model().id, f.spec(), "", settings_.compiler);
    } catch (const std::exception& e) {
      key_problem = e.what();  // e.g. the compiler cannot be run: the interpreter serves
    }
    if (prepared && loadFromCache(function, prepared->key)) return true;
  }
  // Built elsewhere (imported, or by another version of the compiler): found by its
  // portable key, which needs no compiler, so a server that compiles nothing serves it too.
  return loadPortable(function);
}

void FunctionBuilds::trace(const std::shared_ptr<FunctionEntry>& function) {
  FunctionEntry& f = *function;
  if (refusedBeforeTrace(function)) return;
  std::string key_problem;
  if (servedFromCache(function, key_problem)) return;
  if (settings_.compile && key_problem.empty()) cache_misses_.fetch_add(1, std::memory_order_relaxed);

  // A robot host asks its build hosts at once, while it traces: a library that arrives
  // first serves before the interpreter would.
  const bool build = settings_.compile && key_problem.empty();
  const bool fetching = settings_.source != nullptr;
  if (fetching) {
    f.setCompileStage(CompileStage::Fetching);
    fetch_queue_.post([this, function, build] { fetch(function, build); });
  }
  const auto started = Clock::now();
  std::shared_ptr<const Evaluator> evaluator;
  std::size_t instructions = 0, nodes = 0;
  FailureStage stage = FailureStage::Trace;
  Status failure = interpret(f, evaluator, instructions, nodes, stage);
  if (!failure.ok() && f.state() == rpc::FunctionState::Ready) {  // the fetched library serves it
    log_.warn("trace_failed", {{"function_id", f.id()}, {"message", failure.message}, {"serves", "the library"}});
    return;
  }
  if (!failure.ok()) {
    failFunction(function, std::move(failure), stage);
    return;
  }
  // Counted as queued before it is READY: whoever sees it READY sees its library coming.
  if (!fetching && build) {
    builds_queued_.fetch_add(1, std::memory_order_relaxed);
    f.setCompileStage(CompileStage::Queued);
  }
  f.setTraceSeconds(secondsSince(started));
  f.ready(evaluator);  // ignored when a fetched library made it READY first
  log_.info("function_traced", {{"function_id", f.id()},
                                {"function", f.functionName()},
                                {"seconds", secondsSince(started)},
                                {"instructions", instructions},
                                {"nodes", nodes}});

  if (fetching || !settings_.compile) return;
  if (!build) {
    buildFailed(function, "the library cannot be built: " + key_problem);
    return;
  }
  if (!compile_queue_.post([this, function] { compile(function); }))
    builds_queued_.fetch_sub(1, std::memory_order_relaxed);
}

Status FunctionBuilds::interpret(const FunctionEntry& f, std::shared_ptr<const Evaluator>& evaluator,
                                 std::size_t& instructions, std::size_t& nodes, FailureStage& stage) {
  try {
    // The builder's defaults, as the build workers use them: same graph, same layout.
    const BuiltFunction built = buildFunction(*f.model().model, f.spec(), LibraryOptions{}.builder);
    codegen::Interpreter interpreter(*built.graph, built.definition);
    instructions = interpreter.instructionCount();
    nodes = built.graph->size();
    FunctionLayout layout = FunctionLayout::fromDefinition(built.definition, f.spec());
    evaluator = std::make_shared<const InterpretedEvaluator>(std::move(layout), std::move(interpreter));
    return {};
  } catch (const SpecTooLarge& e) {
    stage = FailureStage::InvalidSpec;
    return {StatusCode::ResourceExhausted, e.what()};
  } catch (const SpecError& e) {
    stage = FailureStage::InvalidSpec;
    return {StatusCode::InvalidArgument, e.what()};
  } catch (const symbolic::GraphTooLarge& e) {
    stage = FailureStage::InvalidSpec;
    return {StatusCode::ResourceExhausted, std::string("the function is too large to build: ") + e.what() +
                                               "; ask for fewer outputs or derivatives, or use a smaller robot"};
  } catch (const std::bad_alloc&) {
    return {StatusCode::ResourceExhausted, "out of memory while tracing function " + f.id()};
  } catch (const std::exception& e) {
    return {StatusCode::Internal, std::string("tracing failed: ") + e.what()};
  }
}

void FunctionBuilds::fetch(const std::shared_ptr<FunctionEntry>& function, bool may_compile) {
  FunctionEntry& f = *function;
  const auto started = Clock::now();
  const ArtifactOrder order{f.id(), f.model().id, f.model().urdf, f.model().floating_base, &f.spec()};
  ArtifactDelivery delivery;
  try {
    delivery = settings_.source->fetch(order, cache_, [&] { return stopping_.load() || f.unloaded(); });
  } catch (const std::exception& e) {
    delivery.message = std::string("the fetch failed inside the server: ") + e.what();
  }
  if (stopping_ || f.unloaded()) return;
  if (delivery.delivered()) {
    workers::BuildStatus status;
    status.key = delivery.key;
    status.state = workers::BuildState::Cached;
    status.seconds = secondsSince(started);
    swapIn(function, status, true);
    return;
  }
  log_.warn("fetch_failed", {{"function_id", f.id()},
                             {"message", delivery.message},
                             {"next", may_compile ? "building it here" : "the interpreter keeps serving"}});
  if (may_compile) {
    builds_queued_.fetch_add(1, std::memory_order_relaxed);
    f.setCompileStage(CompileStage::Queued);
    if (!compile_queue_.post([this, function] { compile(function); }))
      builds_queued_.fetch_sub(1, std::memory_order_relaxed);
    return;
  }
  buildFailed(function, "no build host delivered the library (" + delivery.message + ")" +
                            (settings_.compile ? "" : "; this host compiles nothing (build.compile = false)"));
}

bool FunctionBuilds::loadFromCache(const std::shared_ptr<FunctionEntry>& function, const std::string& key) {
  return loadArtifact(function, "cache", [&] { return cache_.find(key); });
}

bool FunctionBuilds::loadPortable(const std::shared_ptr<FunctionEntry>& function) {
  const FunctionEntry& f = *function;
  // The spec's own portable key, then the x86-64 levels this CPU runs (what a fleet's
  // build host compiled for this robot).
  return loadArtifact(function, "cache by portable key", [&]() -> std::optional<cache::Artifact> {
    for (const std::string& key : cache::portableKeysFor(f.model().id, f.spec(), ""))
      if (std::optional<cache::Artifact> artifact = cache_.findPortable(key)) return artifact;
    return std::nullopt;
  });
}

bool FunctionBuilds::loadArtifact(const std::shared_ptr<FunctionEntry>& function, const char* source,
                                  const std::function<std::optional<cache::Artifact>()>& lookUp) {
  FunctionEntry& f = *function;
  std::string key;
  try {
    const auto started = Clock::now();
    const std::optional<cache::Artifact> artifact = lookUp();
    if (!artifact) return false;
    key = artifact->key();
    std::shared_ptr<const CompiledEvaluator> compiled = loadCompiled(*artifact, f.spec());
    cache_hits_.fetch_add(1, std::memory_order_relaxed);
    f.setCompileSeconds(secondsSince(started), true);
    f.setCacheKey(key);
    f.setCompileStage(CompileStage::Compiled);
    f.ready(std::move(compiled));
    log_.info("function_loaded",
              {{"function_id", f.id()}, {"function", f.functionName()}, {"key", key}, {"source", source}});
    return true;
  } catch (const std::exception& e) {
    log_.warn("cache_entry_unusable", {{"function_id", f.id()}, {"key", key}, {"message", e.what()}});
    return false;
  }
}

void FunctionBuilds::compile(const std::shared_ptr<FunctionEntry>& function) {
  FunctionEntry& f = *function;
  if (stopping_ || f.unloaded()) {
    builds_queued_.fetch_sub(1, std::memory_order_relaxed);
    return;
  }
  const workers::BuildTarget target = buildTarget(f);
  std::atomic<bool> running{false};
  auto listener = [&](std::size_t, const workers::BuildStatus& s) {
    if (s.state == workers::BuildState::Building && !running.exchange(true)) {
      builds_queued_.fetch_sub(1, std::memory_order_relaxed);
      builds_running_.fetch_add(1, std::memory_order_relaxed);
      f.setCompileStage(CompileStage::Compiling);
    }
  };
  workers::BuildStatus status;
  try {
    status = builder_.buildAll({target}, listener).at(0);
  } catch (const std::exception& e) {
    status.state = workers::BuildState::Failed;
    status.message = e.what();
  }
  if (running)
    builds_running_.fetch_sub(1, std::memory_order_relaxed);
  else
    builds_queued_.fetch_sub(1, std::memory_order_relaxed);

  if (status.state != workers::BuildState::Done && status.state != workers::BuildState::Cached) {
    buildFailed(function,
                status.message.empty() ? std::string("the build ended ") + toString(status.state) : status.message);
    return;
  }
  swapIn(function, status);
}

workers::BuildTarget FunctionBuilds::buildTarget(const FunctionEntry& f) {
  workers::BuildTarget target;
  target.urdf_path = f.model().source_name;  // names the URDF in the worker's messages
  target.floating_base = f.model().floating_base;
  target.spec_path = "spec of function " + f.id();
  target.urdf_text = f.model().urdf;
  target.model = f.model().model;  // parsed and hashed once, at LoadModel
  target.model_hash = f.model().id;
  target.spec_text = f.specText();
  return target;
}

void FunctionBuilds::refillIfMissing(const std::shared_ptr<FunctionEntry>& function) {
  FunctionEntry& f = *function;
  if (!settings_.compile || stopping_ || f.compileStage() != CompileStage::Compiled) return;
  const std::string key = f.cacheKey();
  if (key.empty()) return;
  try {
    if (cache_.intact(key)) return;
    const std::optional<cache::Entry> entry = cache_.entry(key);
    if (entry && entry->state == "building") return;  // someone rebuilds it already
  } catch (const std::exception& e) {
    log_.warn("cache_lookup_failed", {{"function_id", f.id()}, {"key", key}, {"message", e.what()}});
    return;
  }
  if (!f.beginRefill()) return;
  log_.warn("cache_entry_lost", {{"function_id", f.id()}, {"key", key}, {"action", "rebuilding it"}});
  if (!compile_queue_.post([this, function, key] { refill(function, key); })) f.endRefill();
}

void FunctionBuilds::refill(const std::shared_ptr<FunctionEntry>& function, const std::string& key) {
  FunctionEntry& f = *function;
  workers::BuildStatus status;
  if (!stopping_ && !f.unloaded()) {
    try {
      // find() verifies the entry: files missing or changed are quarantined and unindexed,
      // so the build below makes it again instead of taking the row for a hit.
      if (cache_.find(key)) {
        status.key = key;
        status.state = workers::BuildState::Cached;
      } else {
        status = builder_.buildAll({buildTarget(f)}).at(0);
      }
    } catch (const std::exception& e) {
      status.state = workers::BuildState::Failed;
      status.message = e.what();
    }
    const bool built = status.state == workers::BuildState::Done || status.state == workers::BuildState::Cached;
    if (built && status.key != key) status.message = "the rebuilt library has another key: " + status.key;
    if (built && status.key == key)
      log_.info("cache_entry_rebuilt", {{"function_id", f.id()}, {"key", key}, {"seconds", status.seconds}});
    else
      log_.warn("cache_refill_failed", {{"function_id", f.id()}, {"key", key}, {"message", status.message}});
  }
  f.endRefill();
}

void FunctionBuilds::swapIn(const std::shared_ptr<FunctionEntry>& function, const workers::BuildStatus& status,
                            bool fetched) {
  FunctionEntry& f = *function;
  try {
    const std::optional<cache::Artifact> artifact = cache_.find(status.key);
    if (!artifact)
      throw std::runtime_error("the library " + status.key +
                               " was built but is no longer in the cache (is the cache budget too small?)");
    std::shared_ptr<const CompiledEvaluator> compiled = loadCompiled(*artifact, f.spec());
    if (const std::shared_ptr<const Evaluator> current = f.evaluator()) {
      const std::string difference = compiled->layout().differenceFrom(current->layout());
      if (!difference.empty()) throw std::runtime_error("its blocks differ from the traced function's: " + difference);
    }
    // The times first: whoever sees the compiled phase must see them too.
    f.setCompileSeconds(status.seconds, status.state == workers::BuildState::Cached);
    f.setCacheKey(status.key);
    f.swap(std::move(compiled));
    f.setCompileStage(CompileStage::Compiled);
  } catch (const std::exception& e) {
    buildFailed(function, std::string("the built library cannot be used: ") + e.what());
    return;
  }
  if (fetched) {
    libraries_fetched_.fetch_add(1, std::memory_order_relaxed);
    log_.info("function_fetched", {{"function_id", f.id()}, {"key", status.key}, {"seconds", status.seconds}});
    log_.info("function_swapped", {{"function_id", f.id()}, {"from", "interpreter"}, {"to", "compiled"}});
    return;
  }
  builds_done_.fetch_add(1, std::memory_order_relaxed);
  log_.info("function_compiled", {{"function_id", f.id()},
                                  {"key", status.key},
                                  {"seconds", status.seconds},
                                  {"library_bytes", status.library_bytes},
                                  {"built_here", status.state == workers::BuildState::Done}});
  log_.info("function_swapped", {{"function_id", f.id()}, {"from", "interpreter"}, {"to", "compiled"}});
}

void FunctionBuilds::buildFailed(const std::shared_ptr<FunctionEntry>& function, const std::string& full_message) {
  FunctionEntry& f = *function;
  const std::string message = language::boundedText(full_message, kFailureMessageBytes);
  builds_failed_.fetch_add(1, std::memory_order_relaxed);
  f.setCompileStage(CompileStage::Failed);
  keepFailure(f, message, FailureStage::Compile, {});
  f.setMessage("building the library failed (the interpreter serves this function): " + message);
  log_.warn("build_failed", {{"function_id", f.id()}, {"function", f.functionName()}, {"message", message}});
}

}  // namespace robodiff::server::detail
