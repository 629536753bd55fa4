// Service::overview() as JSON for the dashboard.
#include <chrono>

#include <nlohmann/json.hpp>

#include "robodiff/schema/message_json.hpp"

#include "robodiff/server/dashboard.hpp"

namespace robodiff::server {
namespace {

using nlohmann::json;

double micros(std::uint64_t ns) { return static_cast<double>(ns) * 1e-3; }

json seconds(double s) { return s < 0 ? json(nullptr) : json(s); }

json modelJson(const ServiceOverview::Model& m) {
  return {{"id", m.id},           {"name", m.name}, {"floating_base", m.floating_base}, {"nq", m.nq},
          {"nv", m.nv},           {"joints", m.joints}, {"frames", m.frames}, {"references", m.references},
          {"functions", m.functions}};
}

json functionJson(const ServiceOverview::Function& f) {
  return {{"id", f.id},
          {"model_id", f.model_id},
          {"model_name", f.model_name},
          {"function", f.function},
          {"outputs", f.outputs},
          {"phase", f.phase},
          {"message", f.message},
          {"references", f.references},
          {"evaluations", f.evaluations},
          {"calls", f.calls},
          {"p50_us", micros(f.p50_ns)},
          {"p99_us", micros(f.p99_ns)},
          {"max_us", micros(f.max_ns)},
          {"batch_calls", f.batch_calls},
          {"batch_knots", f.batch_knots},
          {"batch_us_per_knot", f.batch_knots == 0 ? json(nullptr)
                                                   : json(micros(f.batch_ns) / static_cast<double>(f.batch_knots))},
          {"trace_seconds", seconds(f.trace_seconds)},
          {"compile_seconds", seconds(f.compile_seconds)},
          {"from_cache", f.from_cache}};
}

json jobJson(const rpc::JobInfo& j) {
  return {{"id", j.job_id},
          {"kind", j.kind},
          {"state", rpc::toString(j.state)},
          {"progress", j.progress},
          {"elapsed_seconds", j.elapsed_seconds},
          {"eta_seconds", j.eta_seconds < 0 ? json(nullptr) : json(j.eta_seconds)},
          {"messages", j.messages},
          {"error", j.error}};
}

// This server's part in a fleet: every FleetFigures field, the peers (a robot's build
// hosts) as objects. A ServiceMetrics made without a role is standalone.
json fleetJson(const rpc::FleetFigures& f) {
  json j = rpc::messageJson(f);
  if (f.role.empty()) j["role"] = "standalone";
  return j;
}

}  // namespace

std::string overviewJson(const ServiceOverview& o) {
  const ServiceMetrics& m = o.metrics;
  json out;
  out["instance_id"] = o.instance_id;
  out["version"] = o.version;
  out["state"] = rpc::toString(m.state);
  out["uptime_seconds"] = m.uptime_seconds;
  out["unix_seconds"] = std::chrono::duration<double>(std::chrono::system_clock::now().time_since_epoch()).count();

  out["models"] = json::array();
  for (const auto& model : o.models) out["models"].push_back(modelJson(model));
  out["functions"] = json::array();
  for (const auto& f : o.functions) out["functions"].push_back(functionJson(f));

  out["builds"] = {{"queued", m.builds_queued},
                   {"running", m.builds_running},
                   {"failed", m.builds_failed},
                   {"done", m.builds_done}};
  out["specs_invalid"] = m.specs_invalid;  // never built: apart from builds.failed
  out["build_failures"] = json::array();
  for (const auto& f : o.build_failures)
    out["build_failures"].push_back({{"unix_seconds", f.unix_seconds},
                                     {"function_id", f.function_id},
                                     {"model", f.model},
                                     {"function", f.function},
                                     {"message", f.message},
                                     {"stage", f.stage},
                                     {"interpreter_serves", f.interpreter_serves}});

  const std::uint64_t lookups = m.cache_hits + m.cache_misses;
  out["cache"] = {{"hits", m.cache_hits},
                  {"misses", m.cache_misses},
                  {"hit_rate", lookups == 0 ? json(nullptr)
                                            : json(static_cast<double>(m.cache_hits) / static_cast<double>(lookups))},
                  {"bytes", m.cache_bytes},
                  {"entries", m.cache_entries},
                  {"stats_ok", m.cache_stats_ok}};
  out["workers"] = {{"total", m.workers_total}, {"busy", m.workers_busy}};
  out["queue"] = {{"depth", m.queue_depth}, {"capacity", m.queue_capacity}};

  out["jobs_enabled"] = m.jobs_enabled;
  out["job_counts"] = {{"QUEUED", m.jobs.queued},
                       {"RUNNING", m.jobs.running},
                       {"SUCCEEDED", m.jobs.succeeded},
                       {"FAILED", m.jobs.failed},
                       {"CANCELLED", m.jobs.cancelled}};
  out["jobs"] = json::array();
  for (const auto& j : o.jobs) out["jobs"].push_back(jobJson(j));
  out["jobs_error"] = o.jobs_error;
  out["fleet"] = fleetJson(m.fleet);

  // Per method: figures since start, and the fine histogram since start (a reader that
  // differences two polls gets the latency in between; the page's charts come from
  // /api/history, which does that on the server every second).
  out["methods"] = json::array();
  for (const rpc::MethodStats& s : o.methods) {
    json buckets = json::array();
    for (const auto& l : o.latencies)
      if (l.method == s.method)
        for (const auto& [upper_ns, count] : l.buckets) buckets.push_back({upper_ns, count});
    out["methods"].push_back({{"name", rpc::toString(s.method)},
                              {"requests", s.requests},
                              {"errors", s.errors},
                              {"p50_us", micros(s.p50_ns)},
                              {"p90_us", micros(s.p90_ns)},
                              {"p99_us", micros(s.p99_ns)},
                              {"max_us", micros(s.max_ns)},
                              {"buckets", std::move(buckets)}});
  }
  out["transports"] = json::array();
  for (const auto& t : m.transports)
    out["transports"].push_back({{"name", t.transport}, {"requests", t.requests}, {"errors", t.errors}});
  return out.dump();
}

}  // namespace robodiff::server
