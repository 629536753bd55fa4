// Health and the accounting behind it.
#include "robodiff/server/service.hpp"
#include "service_state.hpp"

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

void Service::recordRequest(std::string_view transport, rpc::Method method, StatusCode code,
                            std::chrono::nanoseconds latency) {
  state_->stats.record(transport, method, code, latency);
}

}  // namespace robodiff::server
