// The Service's lifetime (construction, draining, destruction) and its request methods
// other than evaluation (service_evaluation.cpp) and Health (service_health.cpp).
#include "robodiff/server/service.hpp"

#include <algorithm>
#include <cstdio>
#include <thread>

#include "identifiers.hpp"
#include "model_loading.hpp"
#include "robodiff/functions/function_spec.hpp"
#include "robodiff/language/bounded_text.hpp"
#include "service_state.hpp"

namespace robodiff::server {
namespace {

namespace fs = std::filesystem;

cache::Cache openCache(const ServiceOptions& o) {
  cache::CacheOptions options;
  options.budget_bytes = o.cache_budget_bytes;
  return cache::Cache::open(o.cache_dir.empty() ? cache::defaultCacheDir() : o.cache_dir, options);
}

workers::WorkerPoolOptions poolOptions(const ServiceOptions& o) {
  workers::WorkerPoolOptions options;
  options.worker_executable = o.worker_executable;  // empty: the pool looks beside us, then in PATH
  options.workers = std::max(1u, o.build_workers);
  options.default_timeout = o.build_timeout;
  return options;
}

detail::BuildSettings buildSettings(const ServiceOptions& o) {
  detail::BuildSettings s;
  s.compile = o.compile;
  s.compiler = o.compiler;
  s.build_timeout = o.build_timeout;
  s.compiler_memory_limit_bytes = o.compiler_memory_limit_bytes;
  s.compile_threads = std::max(1u, o.build_workers);  // one build per worker; the pool queues the rest
  s.trace_threads = 2;  // a long trace (a humanoid's Hessian) does not hold up every other function
  s.urdf_limits = o.urdf_limits;
  s.source = o.artifact_source;
  s.urdf_limits.max_bytes = std::min<std::uint64_t>(s.urdf_limits.max_bytes, o.max_urdf_bytes);
  return s;
}

unsigned batchThreads(const ServiceOptions& o) {
  return o.batch_threads != 0 ? o.batch_threads : std::max(1u, std::thread::hardware_concurrency());
}

void fillFunctionReply(const detail::FunctionEntry& f, rpc::GetFunctionReply& reply) {
  reply.function_id = f.id();
  reply.state = f.state();
  reply.inputs.clear();
  reply.outputs.clear();
  if (reply.state != rpc::FunctionState::Ready) return;  // blocks are known once READY
  if (const std::shared_ptr<const detail::Evaluator> e = f.evaluator()) {
    reply.inputs = e->layout().inputs;
    reply.outputs = e->layout().outputs;
  }
}

// A ListFunctions page stays within this many bytes of summaries (a reply fits one shm
// chunk or DDS sample whatever the functions' messages).
constexpr std::size_t kListFunctionsPageBytes = 256 * 1024;

rpc::FunctionSummary summaryOf(const detail::FunctionEntry& f) {
  rpc::FunctionSummary summary;
  summary.function_id = f.id();
  summary.model_id = f.model().id;
  summary.function_name = f.functionName();
  summary.state = f.state();
  summary.compiled = f.compiled();
  summary.evaluations = f.evaluations();
  summary.message = language::boundedText(f.message(), detail::kMaxErrorBytes);
  return summary;
}

// What a summary costs on the wire, near enough: its strings and ~32 bytes of the rest.
std::size_t approximateBytes(const rpc::FunctionSummary& s) {
  return s.function_id.size() + s.model_id.size() + s.function_name.size() + s.message.size() + 32;
}

// A page token is the creation sequence of the first function of the page (functions
// unloaded meanwhile shift no other function to another page).
Status parsePageToken(const std::string& token, std::uint64_t& first_sequence) {
  first_sequence = 0;
  if (token.empty()) return {};
  const bool digits = token.size() <= 19 && std::all_of(token.begin(), token.end(), [](char c) {
    return c >= '0' && c <= '9';
  });
  if (!digits)
    return {StatusCode::InvalidArgument, "page_token " + language::quote(token) +
                                             " is not a next_page_token of an earlier ListFunctions reply"};
  first_sequence = std::stoull(token);
  return {};
}

}  // namespace

using detail::guarded;

namespace detail {
Status deadlineExceeded(const CallContext& ctx, const char* method) {
  const auto late = std::chrono::duration<double, std::milli>(Clock::now() - ctx.deadline).count();
  char ms[32];
  std::snprintf(ms, sizeof ms, "%.3f", late);
  return {StatusCode::DeadlineExceeded, std::string(method) + ": the request's deadline had passed " + ms +
                                            " ms before the server could serve it"};
}
}  // namespace detail

Service::State::State(ServiceOptions o, Logger& l)
    : options(std::move(o)),
      log(l),
      instance_id(options.instance_id.empty() ? detail::makeInstanceId() : options.instance_id),
      cache(openCache(options)),
      pool(poolOptions(options)),
      builds(buildSettings(options), cache, pool, l,
             [this](const std::shared_ptr<detail::FunctionEntry>& f) { unloadFailed(f); }),
      batch(batchThreads(options), options.background_nice),
      requests(
          "request", std::max(1u, options.request_threads), std::max<std::size_t>(1, options.request_queue_capacity),
          [this](const std::string& what) { log.error("internal_error", {{"message", what}}); },
          options.background_nice) {
  if (options.artifact_serving.enabled)
    artifacts = std::make_unique<detail::ArtifactServing>(options.artifact_serving, buildSettings(options), cache,
                                                          pool, log);
  if (options.job_workers > 0) {
    JobManagerOptions j;
    j.cache_dir = cache.dir();
    j.workers = options.job_workers;
    j.worker_executable = options.worker_executable;
    j.timeout = options.job_timeout;
    j.memory_limit_bytes = options.job_memory_limit_bytes;
    j.data_dirs = options.job_data_dirs;
    j.validate = options.validate_job;
    jobs = std::make_unique<JobManager>(std::move(j), log);
  }
}

void Service::State::unloadFailed(const std::shared_ptr<detail::FunctionEntry>& function) {
  detail::Registry::Released released;
  if (!registry.dropFailed(function, released)) return;
  log.info("function_unloaded", {{"function_id", function->id()}, {"reason", "failed"}});
  if (released.model_unloaded) log.info("model_unloaded", {{"model_id", released.model_unloaded->id}});
}

Service::Service(ServiceOptions options, Logger& log) : state_(std::make_unique<State>(std::move(options), log)) {
  const State& s = *state_;
  log.info("service_started", {{"instance_id", s.instance_id},
                               {"version", s.options.version},
                               {"cache_dir", s.cache.dir().string()},
                               {"build_workers", s.pool.options().workers},
                               {"compile", s.options.compile},
                               {"request_threads", s.requests.threads()},
                               {"request_queue_capacity", s.requests.capacity()},
                               {"batch_threads", s.batch.threads()}});
}

Service::~Service() {
  State& s = *state_;
  s.serving.store(rpc::ServingState::Draining);
  s.requests.stop();  // runs what was posted, then joins the request threads
  while (s.in_flight.load(std::memory_order_acquire) != 0) std::this_thread::sleep_for(std::chrono::milliseconds(1));
  if (s.artifacts) s.artifacts->stop();  // cancels robots' builds still running
  s.builds.stop();  // cancels library builds still running
  s.jobs.reset();   // cancels jobs still running (they end FAILED: robodiffd stopped)
  s.log.info("service_stopped", {{"instance_id", s.instance_id},
                                 {"uptime_seconds", std::chrono::duration<double>(Clock::now() - s.started).count()}});
}

void Service::markServing() {
  rpc::ServingState expected = rpc::ServingState::Starting;
  if (state_->serving.compare_exchange_strong(expected, rpc::ServingState::Serving))
    state_->log.info("service_serving", {{"instance_id", state_->instance_id}});
}

void Service::beginDrain() {
  if (state_->serving.exchange(rpc::ServingState::Draining) != rpc::ServingState::Draining)
    state_->log.info("service_draining", {{"instance_id", state_->instance_id},
                                          {"in_flight", state_->in_flight.load()},
                                          {"queued", state_->requests.depth()}});
}

bool Service::waitIdle(std::chrono::milliseconds timeout) {
  const auto deadline = Clock::now() + timeout;
  for (;;) {
    if (state_->requests.idle() && state_->in_flight.load(std::memory_order_acquire) == 0) return true;
    if (Clock::now() >= deadline) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
}

rpc::ServingState Service::state() const { return state_->serving.load(); }
const ServiceOptions& Service::options() const { return state_->options; }
const std::string& Service::instanceId() const { return state_->instance_id; }

Status Service::admit(const rpc::RequestHeader& header) const {
  if (Status s = checkSchemaVersion(header.schema_version.major, header.schema_version.minor); !s.ok()) return s;
  if (!header.server_instance_id.empty() && header.server_instance_id != state_->instance_id)
    return {StatusCode::NotFound,
            "request addressed to server " + language::boundedText(header.server_instance_id) + ", this is " +
                state_->instance_id};
  if (state_->serving.load() == rpc::ServingState::Draining) return {StatusCode::Unavailable, detail::kShuttingDown};
  return {};
}

Status Service::loadModel(const CallContext& ctx, const rpc::LoadModelRequest& request, rpc::LoadModelReply& reply) {
  State& s = *state_;
  const InFlight in_flight(s.in_flight);
  return guarded(s.log, "LoadModel", [&]() -> Status {
    if (ctx.expired()) return detail::deadlineExceeded(ctx, "LoadModel");
    std::shared_ptr<detail::ModelEntry> candidate;
    if (Status st = detail::loadModelEntry(request, s.options.max_urdf_bytes, s.options.urdf_limits, candidate); !st.ok()) {
      s.log.info("model_rejected", {{"client_id", ctx.client_id}, {"message", st.message}});
      return st;
    }
    detail::Registry::Added added;
    if (Status st = s.registry.addModel(std::move(candidate), s.options.max_models, ctx.caller.name, added); !st.ok())
      return st;
    const detail::ModelEntry& m = *added.model;
    reply.model_id = m.id;
    reply.joint_names = m.joint_names;
    reply.frame_names = m.frame_names;
    reply.nq = static_cast<std::uint32_t>(m.model->nq);
    reply.nv = static_cast<std::uint32_t>(m.model->nv);
    s.log.info("model_loaded", {{"model_id", m.id},
                                {"robot", m.model->name},
                                {"nq", m.model->nq},
                                {"nv", m.model->nv},
                                {"floating_base", m.floating_base},
                                {"new", added.created},
                                {"references", added.references},
                                {"client_id", ctx.client_id},
                                {"caller", ctx.caller.name}});
    return {};
  });
}

Status Service::getFunction(const CallContext& ctx, const rpc::GetFunctionRequest& request,
                            rpc::GetFunctionReply& reply) {
  State& s = *state_;
  const InFlight in_flight(s.in_flight);
  return guarded(s.log, "GetFunction", [&]() -> Status {
    if (ctx.expired()) return detail::deadlineExceeded(ctx, "GetFunction");
    if (request.spec_json.size() > s.options.max_spec_bytes)
      return {StatusCode::ResourceExhausted, "spec_json: " + std::to_string(request.spec_json.size()) +
                                                 " bytes, past the limit of " +
                                                 std::to_string(s.options.max_spec_bytes) + " bytes (max_spec_bytes)"};
    FunctionSpec spec;
    try {
      spec = parseFunctionSpec(request.spec_json, "spec_json");
    } catch (const SpecTooLarge& e) {
      return {StatusCode::ResourceExhausted, language::boundedText(e.what(), detail::kMaxErrorBytes)};
    } catch (const SpecError& e) {
      return {StatusCode::InvalidArgument, language::boundedText(e.what(), detail::kMaxErrorBytes)};
    }
    const std::string id = detail::functionId(request.model_id, normalizedSpecJson(spec));
    // The same spec failed as invalid a moment ago: the same answer, without tracing again.
    std::optional<Status> failed;
    if (s.registry.findModel(request.model_id)) failed = s.builds.recentInvalidSpec(id);
    if (failed) {
      reply.function_id = id;
      reply.state = rpc::FunctionState::Failed;
      return *failed;
    }
    auto make = [&](std::shared_ptr<const detail::ModelEntry> model, std::uint64_t sequence) {
      return std::make_shared<detail::FunctionEntry>(id, std::move(model), spec, request.spec_json, sequence);
    };
    detail::Registry::Added added;
    if (Status st =
            s.registry.addFunction(request.model_id, id, s.options.max_functions, make, ctx.caller.name, added);
        !st.ok())
      return st;
    detail::FunctionEntry& f = *added.function;
    s.log.info("function_requested", {{"function_id", id},
                                      {"model_id", request.model_id},
                                      {"function", f.functionName()},
                                      {"new", added.created},
                                      {"references", added.references},
                                      {"state", rpc::toString(f.state())},
                                      {"client_id", ctx.client_id},
                                      {"caller", ctx.caller.name}});
    if (added.created)
      s.builds.start(added.function);
    else
      s.builds.refillIfMissing(added.function);

    if (request.wait && !f.waitSettled(ctx.deadline)) {
      fillFunctionReply(f, reply);
      return {StatusCode::DeadlineExceeded, "function " + id +
                                                " is still being built at the request's deadline; call GetFunction "
                                                "again (with wait) to keep waiting"};
    }
    fillFunctionReply(f, reply);
    if (reply.state == rpc::FunctionState::Failed) return f.failure();
    return {};
  });
}

Status Service::listFunctions(const CallContext& ctx, const rpc::ListFunctionsRequest& request,
                              rpc::ListFunctionsReply& reply) {
  State& s = *state_;
  const InFlight in_flight(s.in_flight);
  return guarded(s.log, "ListFunctions", [&]() -> Status {
    if (ctx.expired()) return detail::deadlineExceeded(ctx, "ListFunctions");
    std::optional<std::string_view> model;
    if (!request.model_id.empty()) {
      if (!s.registry.findModel(request.model_id))
        return {StatusCode::NotFound,
                "unknown model id " + language::boundedText(request.model_id) +
                    " (never loaded on this server, or released)"};
      model = request.model_id;
    }
    std::uint64_t first_sequence = 0;
    if (Status st = parsePageToken(request.page_token, first_sequence); !st.ok()) return st;
    const std::size_t page_size =
        std::min<std::size_t>(request.page_size == 0 ? rpc::kMaxListFunctionsPage : request.page_size,
                              rpc::kMaxListFunctionsPage);
    // A caller lists the functions it holds; an operator every one.
    std::optional<std::string_view> holder;
    if (!ctx.caller.operator_) holder = ctx.caller.name;
    const std::vector<std::shared_ptr<detail::FunctionEntry>> functions = s.registry.functions(model, holder);
    reply = {};
    reply.total = static_cast<std::uint32_t>(functions.size());
    std::size_t bytes = 0;
    for (const std::shared_ptr<detail::FunctionEntry>& f : functions) {
      if (f->sequence() < first_sequence) continue;
      rpc::FunctionSummary summary = summaryOf(*f);
      const std::size_t summary_bytes = approximateBytes(summary);
      if (reply.functions.size() == page_size ||
          (!reply.functions.empty() && bytes + summary_bytes > kListFunctionsPageBytes)) {
        reply.next_page_token = std::to_string(f->sequence());
        break;
      }
      bytes += summary_bytes;
      reply.functions.push_back(std::move(summary));
    }
    return {};
  });
}

Status Service::release(const CallContext& ctx, const rpc::ReleaseRequest& request, rpc::ReleaseReply& reply) {
  State& s = *state_;
  const InFlight in_flight(s.in_flight);
  return guarded(s.log, "Release", [&]() -> Status {
    if (ctx.expired()) return detail::deadlineExceeded(ctx, "Release");
    detail::Registry::Released released;
    if (Status st = s.registry.release(request.id, ctx.caller, released); !st.ok()) {
      if (st.code == StatusCode::PermissionDenied)
        s.log.warn("release_refused", {{"id", language::boundedText(request.id)}, {"caller", ctx.caller.name}});
      return st;
    }
    reply.references_left = released.references_left;
    s.log.info(released.was_function ? "function_released" : "model_released",
               {{"id", request.id},
                {"references_left", released.references_left},
                {"client_id", ctx.client_id},
                {"caller", ctx.caller.name},
                {"forced", released.forced}});
    if (released.function_unloaded)
      s.log.info("function_unloaded", {{"function_id", released.function_unloaded->id()},
                                       {"evaluations", released.function_unloaded->evaluations()}});
    if (released.model_unloaded) s.log.info("model_unloaded", {{"model_id", released.model_unloaded->id}});
    return {};
  });
}

// The job methods: the JobManager's, with the service's accounting and error guard.
// (A template over the state: Service::State is private, and deduction needs no name.)
template <class State, class Request, class Reply>
static Status jobCall(State& s, const CallContext& ctx, const char* method, const Request& request,
                      Reply& reply, Status (JobManager::*call)(const JobCaller&, const Request&, Reply&)) {
  const InFlight in_flight(s.in_flight);
  return guarded(s.log, method, [&]() -> Status {
    if (ctx.expired()) return detail::deadlineExceeded(ctx, method);
    if (!s.jobs) return ServiceApi::noJobs();
    return ((*s.jobs).*call)(JobCaller{ctx.caller.name, ctx.caller.operator_}, request, reply);
  });
}

Status Service::submitJob(const CallContext& ctx, const rpc::SubmitJobRequest& request, rpc::SubmitJobReply& reply) {
  return jobCall(*state_, ctx, "SubmitJob", request, reply, &JobManager::submit);
}
Status Service::jobStatus(const CallContext& ctx, const rpc::JobStatusRequest& request, rpc::JobStatusReply& reply) {
  return jobCall(*state_, ctx, "JobStatus", request, reply, &JobManager::status);
}
Status Service::cancelJob(const CallContext& ctx, const rpc::CancelJobRequest& request, rpc::CancelJobReply& reply) {
  return jobCall(*state_, ctx, "CancelJob", request, reply, &JobManager::cancel);
}
Status Service::jobResult(const CallContext& ctx, const rpc::JobResultRequest& request, rpc::JobResultReply& reply) {
  return jobCall(*state_, ctx, "JobResult", request, reply, &JobManager::result);
}

bool Service::post(std::function<void()> task) { return state_->requests.post(std::move(task)); }

}  // namespace robodiff::server
