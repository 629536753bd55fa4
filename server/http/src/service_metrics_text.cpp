// Service::metrics() rendered family by family.
#include "robodiff/server/service_metrics_text.hpp"

#include <algorithm>

#include "robodiff/server/metrics_text.hpp"

namespace robodiff::server {
namespace {

double d(std::uint64_t v) { return static_cast<double>(v); }

const char* lowerState(rpc::ServingState s) {
  switch (s) {
    case rpc::ServingState::Starting: return "starting";
    case rpc::ServingState::Serving: return "serving";
    case rpc::ServingState::Draining: return "draining";
  }
  return "unknown";
}

// A robot's counters: its own totals, then per build host (label build_host = its service).
void robotFleetFamilies(MetricsText& t, const rpc::FleetFigures& f) {
  t.family("robodiff_fleet_artifacts_fetched_total", MetricType::Counter,
           "Libraries fetched from the build hosts, verified and filed in the cache.");
  t.sample("robodiff_fleet_artifacts_fetched_total", {}, d(f.artifacts_fetched));
  t.family("robodiff_fleet_bytes_fetched_total", MetricType::Counter, "Bytes of the libraries fetched and filed.");
  t.sample("robodiff_fleet_bytes_fetched_total", {}, d(f.bytes_fetched));
  t.family("robodiff_fleet_artifacts_refused_total", MetricType::Counter,
           "Libraries fetched that failed verification (signature, digest, key) and were thrown away.");
  t.sample("robodiff_fleet_artifacts_refused_total", {}, d(f.artifacts_refused));
  t.family("robodiff_fleet_fetch_failures_total", MetricType::Counter,
           "Libraries no build host could deliver: this host compiled them (or the interpreter serves).");
  t.sample("robodiff_fleet_fetch_failures_total", {}, d(f.fetch_failures));

  const auto per_peer = [&](const char* name, const char* help, MetricType type, auto value) {
    t.family(name, type, help);
    for (const rpc::FleetPeer& p : f.peers) t.sample(name, {{"build_host", p.service}}, value(p));
  };
  per_peer("robodiff_fleet_peer_artifacts_fetched_total", "Libraries fetched from a build host and filed.",
           MetricType::Counter, [](const rpc::FleetPeer& p) { return d(p.artifacts_fetched); });
  per_peer("robodiff_fleet_peer_bytes_fetched_total", "Bytes of the libraries fetched from a build host.",
           MetricType::Counter, [](const rpc::FleetPeer& p) { return d(p.bytes_fetched); });
  per_peer("robodiff_fleet_peer_fetch_seconds_total",
           "Seconds spent transferring, verifying and filing the libraries fetched from a build host.",
           MetricType::Counter, [](const rpc::FleetPeer& p) { return p.fetch_seconds; });
  per_peer("robodiff_fleet_peer_refusals_total",
           "Libraries from a build host that failed verification (thrown away).", MetricType::Counter,
           [](const rpc::FleetPeer& p) { return d(p.refusals); });
  per_peer("robodiff_fleet_peer_failures_total",
           "Fetches from a build host that went wrong otherwise: no answer, its build failed, the transfer broke off.",
           MetricType::Counter, [](const rpc::FleetPeer& p) { return d(p.failures); });
  per_peer("robodiff_fleet_peer_reachable", "1 when a build host's last call got an answer, else 0.",
           MetricType::Gauge, [](const rpc::FleetPeer& p) { return p.reachable ? 1.0 : 0.0; });
}

void buildHostFleetFamilies(MetricsText& t, const rpc::FleetFigures& f) {
  t.family("robodiff_fleet_artifacts_served_total", MetricType::Counter,
           "Libraries served whole to robot hosts (the last chunk of a signed payload sent).");
  t.sample("robodiff_fleet_artifacts_served_total", {}, d(f.artifacts_served));
  t.family("robodiff_fleet_bytes_served_total", MetricType::Counter, "Chunk bytes served to robot hosts.");
  t.sample("robodiff_fleet_bytes_served_total", {}, d(f.bytes_served));
  t.family("robodiff_fleet_builds_for_robots_total", MetricType::Counter,
           "Library builds started because a robot host asked for a library this host lacked.");
  t.sample("robodiff_fleet_builds_for_robots_total", {}, d(f.builds_for_robots));
}

// This server's part in a fleet (docs/fleet.md): its role, and the counters of that role
// only (a standalone server has none).
void fleetFamilies(MetricsText& t, const rpc::FleetFigures& f) {
  const std::string role = f.role.empty() ? "standalone" : f.role;
  t.family("robodiff_fleet_role", MetricType::Gauge,
           "This server's part in a fleet: 1 for its role (standalone, build host or robot host).");
  t.sample("robodiff_fleet_role", {{"role", role}}, 1);
  if (role == "robot") robotFleetFamilies(t, f);
  if (role == "build") buildHostFleetFamilies(t, f);
}

}  // namespace

std::string serviceMetricsText(const ServiceMetrics& m) {
  MetricsText t;
  t.family("robodiff_up", MetricType::Gauge, "1 while robodiffd answers (this page).");
  t.sample("robodiff_up", {}, 1);
  t.family("robodiff_serving_state", MetricType::Gauge,
           "The service's state: 1 for the current one of starting, serving, draining (after SIGTERM).");
  for (const auto s : {rpc::ServingState::Starting, rpc::ServingState::Serving, rpc::ServingState::Draining})
    t.sample("robodiff_serving_state", {{"state", lowerState(s)}}, m.state == s ? 1 : 0);
  t.family("robodiff_uptime_seconds", MetricType::Gauge, "Seconds since the service started.");
  t.sample("robodiff_uptime_seconds", {}, m.uptime_seconds);

  t.family("robodiff_requests_total", MetricType::Counter,
           "Requests answered, by method and reply status (gRPC code names), over every transport.");
  for (const auto& f : m.methods)
    for (const auto& [code, n] : f.replies)
      t.sample("robodiff_requests_total", {{"method", rpc::toString(f.method)}, {"status", toString(code)}}, d(n));
  t.family("robodiff_request_duration_seconds", MetricType::Histogram,
           "Time from taking a request to its reply, by method (buckets within 9% of their bound).");
  for (const auto& f : m.methods)
    t.histogram("robodiff_request_duration_seconds", {{"method", rpc::toString(f.method)}}, m.latency_bounds_seconds,
                f.latency_buckets, f.latency_count, f.latency_sum_seconds);
  t.family("robodiff_transport_requests_total", MetricType::Counter, "Requests answered, by transport.");
  for (const auto& tr : m.transports)
    t.sample("robodiff_transport_requests_total", {{"transport", tr.transport}}, d(tr.requests));
  t.family("robodiff_transport_errors_total", MetricType::Counter,
           "Requests answered with a non-OK status, by transport.");
  for (const auto& tr : m.transports)
    t.sample("robodiff_transport_errors_total", {{"transport", tr.transport}}, d(tr.errors));

  t.family("robodiff_models_loaded", MetricType::Gauge, "Robot models loaded.");
  t.sample("robodiff_models_loaded", {}, m.models_loaded);
  t.family("robodiff_functions_loaded", MetricType::Gauge, "Functions loaded (interpreted or compiled).");
  t.sample("robodiff_functions_loaded", {}, m.functions_loaded);
  t.family("robodiff_functions_compiled", MetricType::Gauge, "Functions served by a compiled library.");
  t.sample("robodiff_functions_compiled", {}, m.functions_compiled);

  t.family("robodiff_builds", MetricType::Gauge,
           "Library builds: queued and running now; done and failed since the service started.");
  t.sample("robodiff_builds", {{"state", "queued"}}, m.builds_queued);
  t.sample("robodiff_builds", {{"state", "running"}}, m.builds_running);
  t.sample("robodiff_builds", {{"state", "done"}}, m.builds_done);
  t.sample("robodiff_builds", {{"state", "failed"}}, m.builds_failed);
  t.family("robodiff_builds_failed_total", MetricType::Counter,
           "Library builds that failed (the compiler or its worker); the interpreter serves those functions.");
  t.sample("robodiff_builds_failed_total", {}, d(m.builds_failed));
  t.family("robodiff_specs_invalid_total", MetricType::Counter,
           "Functions whose spec never built: it does not fit the model (unknown frame, bad expression, ...) "
           "or is too large. Not counted as failed builds.");
  t.sample("robodiff_specs_invalid_total", {}, d(m.specs_invalid));

  t.family("robodiff_cache_hits_total", MetricType::Counter, "Functions found compiled in the cache.");
  t.sample("robodiff_cache_hits_total", {}, d(m.cache_hits));
  t.family("robodiff_cache_misses_total", MetricType::Counter, "Functions not in the cache (traced and built).");
  t.sample("robodiff_cache_misses_total", {}, d(m.cache_misses));
  if (m.cache_stats_ok) {  // absent rather than a false 0 when the cache could not be read
    t.family("robodiff_cache_bytes", MetricType::Gauge, "Bytes of libraries in the cache.");
    t.sample("robodiff_cache_bytes", {}, d(m.cache_bytes));
    t.family("robodiff_cache_entries", MetricType::Gauge, "Libraries in the cache.");
    t.sample("robodiff_cache_entries", {}, d(m.cache_entries));
    t.family("robodiff_cache_quarantined", MetricType::Gauge,
             "Cache entries in quarantine/: found missing, truncated or altered, kept for inspection.");
    t.sample("robodiff_cache_quarantined", {}, d(m.cache_quarantined));
  }
  t.family("robodiff_build_retries_total", MetricType::Counter,
           "Builds tried again because their worker process died (killed, crashed, out of memory).");
  t.sample("robodiff_build_retries_total", {}, d(m.build_retries));

  t.family("robodiff_workers", MetricType::Gauge, "Build worker processes, busy (building) or idle.");
  t.sample("robodiff_workers", {{"state", "busy"}}, m.workers_busy);
  t.sample("robodiff_workers", {{"state", "idle"}}, m.workers_total - std::min(m.workers_busy, m.workers_total));
  t.family("robodiff_request_queue_depth", MetricType::Gauge, "Posted requests waiting for a request thread.");
  t.sample("robodiff_request_queue_depth", {}, m.queue_depth);
  t.family("robodiff_request_queue_capacity", MetricType::Gauge,
           "Posted requests that may wait; beyond, RESOURCE_EXHAUSTED.");
  t.sample("robodiff_request_queue_capacity", {}, m.queue_capacity);

  t.family("robodiff_jobs", MetricType::Gauge,
           "Batch jobs of this server by state; no samples when jobs are off (jobs.workers = 0).");
  if (m.jobs_enabled) {
    t.sample("robodiff_jobs", {{"state", "queued"}}, m.jobs.queued);
    t.sample("robodiff_jobs", {{"state", "running"}}, m.jobs.running);
    t.sample("robodiff_jobs", {{"state", "succeeded"}}, m.jobs.succeeded);
    t.sample("robodiff_jobs", {{"state", "failed"}}, m.jobs.failed);
    t.sample("robodiff_jobs", {{"state", "cancelled"}}, m.jobs.cancelled);
  }
  fleetFamilies(t, m.fleet);
  return t.text();
}

}  // namespace robodiff::server
