// Health and the accounting behind it.
#include "robodiff/server/service.hpp"
#include "service_state.hpp"

#include <algorithm>

namespace robodiff::server {

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

    reply.models_loaded = static_cast<std::uint32_t>(s.registry.modelCount());
    const auto functions = s.registry.functions();
    reply.functions_loaded = static_cast<std::uint32_t>(functions.size());
    reply.functions_compiled = 0;
    for (const auto& f : functions) reply.functions_compiled += f->compiled() ? 1 : 0;

    const detail::BuildFigures builds = s.builds.figures();
    reply.builds_queued = builds.builds_queued;
    reply.builds_running = builds.builds_running;
    reply.builds_failed = builds.builds_failed;
    reply.builds_done = builds.builds_done;
    reply.cache_hits = builds.cache_hits;
    reply.cache_misses = builds.cache_misses;
    try {
      const cache::CacheStats stats = s.cache.stats();
      reply.cache_bytes = stats.bytes;
      reply.cache_entries = stats.entries;
    } catch (const std::exception& e) {
      s.log.warn("cache_stats_failed", {{"message", e.what()}});  // Health still answers
    }

    const std::vector<workers::WorkerInfo> workers = s.pool.workers();
    reply.workers_total = static_cast<std::uint32_t>(workers.size());
    reply.workers_busy = 0;
    for (const workers::WorkerInfo& w : workers) reply.workers_busy += w.job ? 1 : 0;

    reply.queue_depth = static_cast<std::uint32_t>(s.requests.depth());
    reply.queue_capacity = static_cast<std::uint32_t>(s.requests.capacity());
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

  m.models_loaded = static_cast<std::uint32_t>(s.registry.modelCount());
  const auto functions = s.registry.functions();
  m.functions_loaded = static_cast<std::uint32_t>(functions.size());
  for (const auto& f : functions) m.functions_compiled += f->compiled() ? 1 : 0;

  const detail::BuildFigures builds = s.builds.figures();
  m.builds_queued = builds.builds_queued;
  m.builds_running = builds.builds_running;
  m.builds_failed = builds.builds_failed;
  m.builds_done = builds.builds_done;
  m.cache_hits = builds.cache_hits;
  m.cache_misses = builds.cache_misses;
  try {
    const cache::CacheStats stats = s.cache.stats();
    m.cache_bytes = stats.bytes;
    m.cache_entries = stats.entries;
  } catch (const std::exception& e) {
    m.cache_stats_ok = false;
    s.log.warn("cache_stats_failed", {{"message", e.what()}});
  }

  const std::vector<workers::WorkerInfo> workers = s.pool.workers();
  m.workers_total = static_cast<std::uint32_t>(workers.size());
  for (const workers::WorkerInfo& w : workers) m.workers_busy += w.job ? 1 : 0;
  m.queue_depth = static_cast<std::uint32_t>(s.requests.depth());
  m.queue_capacity = static_cast<std::uint32_t>(s.requests.capacity());
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
