// Health and the accounting behind it.
#include "robodiff/server/service.hpp"
#include "service_state.hpp"

#include <algorithm>

namespace robodiff::server {
namespace {

// The figures Health and metrics() both report (their structs name them alike): models and
// functions, builds, cache, workers, queue. Returns false when the cache's stats could not
// be read (the rest is filled in anyway).
template <class State, class Out>
bool fillServiceFigures(State& s, Out& out) {
  out.models_loaded = static_cast<std::uint32_t>(s.registry.modelCount());
  const auto functions = s.registry.functions();
  out.functions_loaded = static_cast<std::uint32_t>(functions.size());
  out.functions_compiled = 0;
  for (const auto& f : functions) out.functions_compiled += f->compiled() ? 1 : 0;

  const detail::BuildFigures builds = s.builds.figures();
  out.builds_queued = builds.builds_queued;
  out.builds_running = builds.builds_running;
  out.builds_failed = builds.builds_failed;
  out.builds_done = builds.builds_done;
  out.cache_hits = builds.cache_hits;
  out.cache_misses = builds.cache_misses;
  if constexpr (requires { out.build_retries; }) out.build_retries = builds.build_retries;
  if constexpr (requires { out.specs_invalid; }) out.specs_invalid = builds.specs_invalid;
  bool cache_ok = true;
  try {
    const cache::CacheStats stats = s.cache.stats();
    out.cache_bytes = stats.bytes;
    out.cache_entries = stats.entries;
    if constexpr (requires { out.cache_quarantined; }) out.cache_quarantined = stats.quarantined;
  } catch (const std::exception& e) {
    cache_ok = false;
    s.log.warn("cache_stats_failed", {{"message", e.what()}});  // the figures still answer
  }

  const std::vector<workers::WorkerInfo> workers = s.pool.workers();
  out.workers_total = static_cast<std::uint32_t>(workers.size());
  out.workers_busy = 0;
  for (const workers::WorkerInfo& w : workers) out.workers_busy += w.job ? 1 : 0;
  out.queue_depth = static_cast<std::uint32_t>(s.requests.depth());
  out.queue_capacity = static_cast<std::uint32_t>(s.requests.capacity());
  return cache_ok;
}

}  // namespace

Status Service::health(const CallContext& ctx, const rpc::HealthRequest& request, rpc::HealthReply& reply) {
  State& s = *state_;
  const InFlight in_flight(s.in_flight);
  if (ctx.expired()) return detail::deadlineExceeded(ctx, "Health");
  try {
    reply.state = s.serving.load();
    reply.version = s.options.version;
    reply.server_instance_id = s.instance_id;
    reply.uptime_ns = static_cast<std::uint64_t>(
        std::chrono::duration_cast<std::chrono::nanoseconds>(Clock::now() - s.started).count());

    fillServiceFigures(s, reply);
    reply.batch_threads = s.batch.threads();
    reply.methods = s.stats.methods();
    reply.errors = s.stats.errors();
    reply.transports = s.stats.transports();
    (void)request;  // verbose adds nothing yet: every figure is cheap
    return {};
  } catch (const std::exception& e) {
    s.log.error("internal_error", {{"method", "Health"}, {"message", e.what()}});
    return {StatusCode::Internal, std::string("Health failed inside the server: ") + e.what()};
  }
}

ServiceMetrics Service::metrics() const {
  // Prometheus-style latency buckets: 5 us to 60 s.
  static constexpr std::uint64_t kBoundsNs[] = {
      5'000,       10'000,      25'000,      50'000,        100'000,       250'000,        500'000,       1'000'000,
      2'500'000,   5'000'000,   10'000'000,  25'000'000,    50'000'000,    100'000'000,    250'000'000,   500'000'000,
      1'000'000'000, 2'500'000'000, 5'000'000'000, 10'000'000'000, 30'000'000'000, 60'000'000'000};
  State& s = *state_;  // the cache's stats() is not const
  ServiceMetrics m;
  m.state = s.serving.load();
  m.uptime_seconds = std::chrono::duration<double>(Clock::now() - s.started).count();
  for (const std::uint64_t ns : kBoundsNs) m.latency_bounds_seconds.push_back(static_cast<double>(ns) * 1e-9);
  for (std::uint32_t i = 0; i < rpc::kMethodCount; ++i) {
    const auto method = static_cast<rpc::Method>(i);
    ServiceMetrics::MethodFigures f;
    f.method = method;
    for (std::size_t code = 0; code < kStatusCodeCount; ++code)
      if (const std::uint64_t n = s.stats.replies(method, code); n != 0 || code == 0)
        f.replies.emplace_back(static_cast<StatusCode>(code), n);
    if (const std::uint64_t n = s.stats.replies(method, kStatusCodeCount); n != 0) {  // codes unknown to this build
      auto it = std::find_if(f.replies.begin(), f.replies.end(),
                             [](const auto& r) { return r.first == StatusCode::Unknown; });
      if (it != f.replies.end()) it->second += n;
      else f.replies.emplace_back(StatusCode::Unknown, n);
    }
    const auto latency = s.stats.latency(method).cumulative(kBoundsNs);
    f.latency_buckets = latency.counts;
    f.latency_count = latency.total;
    f.latency_sum_seconds = static_cast<double>(latency.sum_ns) * 1e-9;
    m.methods.push_back(std::move(f));
  }
  m.transports = s.stats.transports();
  m.fleet = fleet();

  m.cache_stats_ok = fillServiceFigures(s, m);
  if (s.jobs) {
    m.jobs_enabled = true;
    m.jobs = s.jobs->counts();
  }
  return m;
}

void Service::recordRequest(std::string_view transport, rpc::Method method, StatusCode code,
                            std::chrono::nanoseconds latency) {
  state_->stats.record(transport, method, code, latency);
}

}  // namespace robodiff::server
