// `robodiff health`: what the running server says of itself (Health, then FleetStatus:
// its part in a fleet, docs/fleet.md), readable or JSON.
#include <cstdio>
#include <iostream>
#include <optional>

#include <nlohmann/json.hpp>

#include "robodiff/schema/message_json.hpp"

#include "commands/commands.hpp"
#include "output/human_units.hpp"
#include "output/output_table.hpp"
#include "service/service_connection.hpp"

namespace robodiff::cli {
namespace {

struct HealthArgs {
  ServiceArgs service;
  bool json = false;
};

// A latency for people: "850 ns", "12.3 us", "4.56 ms", "1.20 s".
std::string latency(std::uint64_t ns) {
  char buf[32];
  if (ns < 1000) std::snprintf(buf, sizeof buf, "%llu ns", static_cast<unsigned long long>(ns));
  else if (ns < 1000000) std::snprintf(buf, sizeof buf, "%.1f us", ns / 1e3);
  else if (ns < 1000000000) std::snprintf(buf, sizeof buf, "%.2f ms", ns / 1e6);
  else std::snprintf(buf, sizeof buf, "%.2f s", ns / 1e9);
  return buf;
}

nlohmann::ordered_json healthJson(const rpc::HealthReply& h, const ServiceConnection& c) {
  nlohmann::ordered_json methods = nlohmann::ordered_json::array();
  for (const rpc::MethodStats& m : h.methods)
    methods.push_back({{"method", rpc::toString(m.method)},
                       {"requests", m.requests},
                       {"errors", m.errors},
                       {"p50_ns", m.p50_ns},
                       {"p90_ns", m.p90_ns},
                       {"p99_ns", m.p99_ns},
                       {"max_ns", m.max_ns}});
  nlohmann::ordered_json errors = nlohmann::ordered_json::array();
  for (const rpc::StatusCount& e : h.errors) errors.push_back({{"code", toString(e.code)}, {"count", e.count}});
  nlohmann::ordered_json transports = nlohmann::ordered_json::array();
  for (const rpc::TransportCounts& t : h.transports)
    transports.push_back({{"transport", t.transport}, {"requests", t.requests}, {"errors", t.errors}});
  return {{"state", rpc::toString(h.state)},
          {"version", h.version},
          {"server_instance_id", h.server_instance_id},
          {"uptime_ns", h.uptime_ns},
          {"models_loaded", h.models_loaded},
          {"functions_loaded", h.functions_loaded},
          {"functions_compiled", h.functions_compiled},
          {"builds_queued", h.builds_queued},
          {"builds_running", h.builds_running},
          {"builds_failed", h.builds_failed},
          {"builds_done", h.builds_done},
          {"cache_hits", h.cache_hits},
          {"cache_misses", h.cache_misses},
          {"cache_bytes", h.cache_bytes},
          {"cache_entries", h.cache_entries},
          {"workers_total", h.workers_total},
          {"workers_busy", h.workers_busy},
          {"queue_depth", h.queue_depth},
          {"queue_capacity", h.queue_capacity},
          {"batch_threads", h.batch_threads},
          {"methods", methods},
          {"errors", errors},
          {"transports", transports},
          {"transport", c.transport},
          {"server", c.address}};
}


void printHealth(const rpc::HealthReply& h, const ServiceConnection& c) {
  const double uptime = static_cast<double>(h.uptime_ns) / 1e9;
  std::cout << "robodiffd " << h.version << "  " << rpc::toString(h.state) << "  instance " << h.server_instance_id
            << "  up " << formatClock(uptime) << "  (over " << c.transport << ", " << c.address << ")\n";
  std::cout << "models      " << h.models_loaded << " loaded; functions " << h.functions_loaded << " loaded, "
            << h.functions_compiled << " compiled\n";
  std::cout << "builds      " << h.builds_queued << " queued, " << h.builds_running << " running, " << h.builds_done
            << " done, " << h.builds_failed << " failed\n";
  const std::uint64_t lookups = h.cache_hits + h.cache_misses;
  std::cout << "cache       " << h.cache_hits << " hits, " << h.cache_misses << " misses";
  if (lookups > 0) {
    char rate[32];
    std::snprintf(rate, sizeof rate, "%.0f%%", 100.0 * static_cast<double>(h.cache_hits) / static_cast<double>(lookups));
    std::cout << " (hit rate " << rate << ")";
  }
  std::cout << "; " << h.cache_entries << " entries, " << formatBytes(h.cache_bytes) << "\n";
  std::cout << "workers     " << h.workers_busy << " of " << h.workers_total << " busy\n";
  std::cout << "queue       " << h.queue_depth << " of " << h.queue_capacity << " request slots used; "
            << h.batch_threads << " batch threads\n";
  std::cout << "transports ";
  if (h.transports.empty()) std::cout << " none";
  for (std::size_t i = 0; i < h.transports.size(); ++i)
    std::cout << (i ? ", " : " ") << h.transports[i].transport << " " << h.transports[i].requests << " requests ("
              << h.transports[i].errors << " errors)";
  std::cout << "\nerrors     ";
  if (h.errors.empty()) std::cout << " none";
  for (std::size_t i = 0; i < h.errors.size(); ++i)
    std::cout << (i ? ", " : " ") << toString(h.errors[i].code) << " " << h.errors[i].count;
  std::cout << "\n\n";
  Table table = Table::rows({"method", "requests", "errors", "p50", "p99", "max"},
                            {false, true, true, true, true, true});
  for (const rpc::MethodStats& m : h.methods) {
    const bool any = m.requests > 0;
    table.addRow({rpc::toString(m.method), std::to_string(m.requests), std::to_string(m.errors),
                  any ? latency(m.p50_ns) : "-", any ? latency(m.p99_ns) : "-", any ? latency(m.max_ns) : "-"});
  }
  table.print(std::cout);
}

// One build host as the robot sees it: "build-a (robodiffd-1): reachable; 3 fetched (1.2 MiB), ...".
void printPeer(const rpc::FleetPeer& p) {
  std::cout << p.service << " (" << (p.instance_id.empty() ? "never reached" : p.instance_id) << "): "
            << (p.reachable ? "reachable" : "unreachable") << "; " << p.artifacts_fetched << " fetched ("
            << formatBytes(p.bytes_fetched) << " in " << p.fetch_seconds << " s), " << p.refusals << " refused, " << p.failures << " failed";
  if (!p.last_problem.empty()) std::cout << "; last problem: " << p.last_problem;
  std::cout << "\n";
}

void printFleet(const rpc::FleetFigures& f) {
  std::cout << "\nfleet       role " << f.role;
  if (!f.target.empty()) std::cout << ", target " << f.target;
  std::cout << "\n";
  if (f.role == "robot") {
    std::cout << "            " << f.artifacts_fetched << " artifacts fetched (" << formatBytes(f.bytes_fetched)
              << "), " << f.artifacts_refused << " refused, " << f.fetch_failures << " fetches failed\n";
    std::cout << "peers      ";
    if (f.peers.empty()) std::cout << " none\n";
    for (std::size_t i = 0; i < f.peers.size(); ++i) {
      std::cout << (i ? "            " : " ");
      printPeer(f.peers[i]);
    }
  } else if (f.role == "build") {
    std::cout << "            " << f.artifacts_served << " artifacts served (" << formatBytes(f.bytes_served)
              << " sent), " << f.builds_for_robots << " builds for robots\n";
  }
}

// FleetStatus, asked beside Health; nothing from a server without it (UNIMPLEMENTED, or
// FAILED_PRECONDITION from an older schema), so that health still works there.
std::optional<rpc::FleetFigures> fleetStatus(const ServiceConnection& c) {
  const rpc::FleetStatusRequest request;
  rpc::FleetStatusReply reply;
  const Status s = c->call(client::UnaryCall{client::FleetStatusCall{&request, &reply}}, c.call());
  if (s.code == StatusCode::Unimplemented || s.code == StatusCode::FailedPrecondition) return std::nullopt;
  check(s, "FleetStatus");
  return reply.fleet;
}

void health(const HealthArgs& args) {
  ServiceConnection c = connectService(args.service);
  rpc::HealthRequest request;
  request.verbose = true;
  rpc::HealthReply reply;
  check(c->health(request, reply, c.call()), "Health");
  const std::optional<rpc::FleetFigures> fleet = fleetStatus(c);
  if (args.json) {
    nlohmann::ordered_json out = healthJson(reply, c);
    if (fleet) out["fleet"] = rpc::messageJson(*fleet);
    std::cout << out.dump() << "\n";
    return;
  }
  printHealth(reply, c);
  if (fleet) printFleet(*fleet);
}

}  // namespace

void addHealthCommand(CLI::App& app) {
  auto args = std::make_shared<HealthArgs>();
  CLI::App* cmd = app.add_subcommand("health", "Ask the running server how it is (Health)");
  cmd->add_flag("--json", args->json,
                "Print every field of the reply: {\"state\", \"version\", \"server_instance_id\", \"uptime_ns\", "
                "\"models_loaded\", ..., \"methods\": [{\"method\", \"requests\", \"errors\", \"p50_ns\", "
                "\"p90_ns\", \"p99_ns\", \"max_ns\"}], \"errors\": [{\"code\", \"count\"}], \"transports\": "
                "[{\"transport\", \"requests\", \"errors\"}]}, plus the \"transport\" and \"server\" used, and "
                "\"fleet\": {\"role\", \"target\", ..., \"peers\": [{\"service\", \"instance_id\", \"reachable\", "
                "...}]} (FleetStatus; absent when the server does not answer it)");
  addServiceOptions(*cmd, args->service);
  cmd->footer(std::string("Latencies are the server's own (from taking a request to its reply).\n") + kServiceExitHelp);
  cmd->callback([args] { health(*args); });
}

}  // namespace robodiff::cli
