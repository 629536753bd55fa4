// A real Service's metrics(): requests recorded by method and status land in the counters
// and in cumulative latency buckets that agree with them, and the page renders validly;
// invalid specs and failed library builds are two counters, each counting only its own;
// the fleet's figures: a standalone server shows its role and no fleet counters, a robot
// host its counts and per build host (labels escaped), a build host what it served.
#include <gtest/gtest.h>

#include <chrono>
#include <cstdio>
#include <map>
#include <string>
#include <thread>
#include <vector>

#include <nlohmann/json.hpp>

#include "http/serving_service.hpp"
#include "robodiff/server/dashboard.hpp"
#include "robodiff/server/service.hpp"
#include "robodiff/server/service_metrics_text.hpp"
#include "support/prometheus_text.hpp"
#include "support/temp_dir.hpp"
#include "support/test_paths.hpp"

namespace robodiff::testing {
namespace {

using namespace std::chrono_literals;

TEST(ServiceMetrics, RecordedRequestsBecomeCountersAndBuckets) {
  ServingService service;
  // 3 fast OK Evaluates (2 us, 40 us, 3 ms), one NOT_FOUND, one LoadModel of 2 s.
  service->recordRequest("iceoryx", rpc::Method::Evaluate, StatusCode::Ok, 2us);
  service->recordRequest("iceoryx", rpc::Method::Evaluate, StatusCode::Ok, 40us);
  service->recordRequest("dds", rpc::Method::Evaluate, StatusCode::Ok, 3ms);
  service->recordRequest("dds", rpc::Method::Evaluate, StatusCode::NotFound, 1us);
  service->recordRequest("dds", rpc::Method::LoadModel, StatusCode::Ok, 2s);

  const server::ServiceMetrics m = service->metrics();
  ASSERT_EQ(m.methods.size(), rpc::kMethodCount);
  const auto& evaluate = m.methods[static_cast<std::size_t>(rpc::Method::Evaluate)];
  EXPECT_EQ(evaluate.latency_count, 4u);
  EXPECT_NEAR(evaluate.latency_sum_seconds, 3.043e-3, 1e-9);
  ASSERT_EQ(evaluate.latency_buckets.size(), m.latency_bounds_seconds.size());
  auto bucketAt = [&](double le) {
    for (std::size_t i = 0; i < m.latency_bounds_seconds.size(); ++i)
      if (std::abs(m.latency_bounds_seconds[i] - le) < 1e-12) return evaluate.latency_buckets[i];
    ADD_FAILURE() << "no bound " << le;
    return std::uint64_t{0};
  };
  EXPECT_EQ(bucketAt(5e-6), 2u);    // 1 us, 2 us
  EXPECT_EQ(bucketAt(5e-5), 3u);    // + 40 us
  EXPECT_EQ(bucketAt(2.5e-3), 3u);  // 3 ms is above
  EXPECT_EQ(bucketAt(5e-3), 4u);
  EXPECT_EQ(m.state, rpc::ServingState::Serving);

  const PromText p = parsePrometheusText(server::serviceMetricsText(m));
  ASSERT_TRUE(p.errors.empty()) << p.errorText();
  EXPECT_EQ(p.value("robodiff_requests_total", {{"method", "Evaluate"}, {"status", "OK"}}), 3.0);
  EXPECT_EQ(p.value("robodiff_requests_total", {{"method", "Evaluate"}, {"status", "NOT_FOUND"}}), 1.0);
  EXPECT_EQ(p.value("robodiff_requests_total", {{"method", "Health"}, {"status", "OK"}}), 0.0);
  EXPECT_EQ(p.value("robodiff_request_duration_seconds_bucket", {{"method", "LoadModel"}, {"le", "1"}}), 0.0);
  EXPECT_EQ(p.value("robodiff_request_duration_seconds_bucket", {{"method", "LoadModel"}, {"le", "2.5"}}), 1.0);
  EXPECT_EQ(p.value("robodiff_transport_requests_total", {{"transport", "dds"}}), 3.0);
  EXPECT_EQ(p.value("robodiff_transport_errors_total", {{"transport", "dds"}}), 1.0);
  EXPECT_EQ(p.value("robodiff_cache_entries"), 0.0);
  EXPECT_EQ(p.value("robodiff_cache_quarantined"), 0.0);
  EXPECT_EQ(p.value("robodiff_build_retries_total"), 0.0);
  EXPECT_EQ(p.value("robodiff_builds_failed_total"), 0.0);
  EXPECT_EQ(p.value("robodiff_specs_invalid_total"), 0.0);
  EXPECT_EQ(p.value("robodiff_workers", {{"state", "idle"}}), 1.0);
  EXPECT_EQ(p.family("robodiff_jobs")->samples.size(), 0u);  // jobs off
}

Status getFunction(server::Service& service, const std::string& model_id, const std::string& spec) {
  rpc::GetFunctionRequest request;
  request.model_id = model_id;
  request.spec_json = spec;
  request.wait = true;
  rpc::GetFunctionReply reply;
  server::CallContext ctx;
  ctx.deadline = server::Clock::now() + 30s;
  return service.getFunction(ctx, request, reply);
}

TEST(ServiceMetrics, InvalidSpecsAreCountedApartFromFailedBuilds) {
  // Compiling on with a "compiler" that cannot even tell its version: every library build
  // fails (the interpreter serves the function), while a spec naming a frame the model
  // lacks never builds at all.
  ServingService service([](server::ServiceOptions& o) {
    o.compile = true;
    o.compiler = "/bin/false";
  });
  rpc::LoadModelRequest load;
  load.urdf = readFile(sourceDir() / "examples/robots/arm7.urdf");
  rpc::LoadModelReply model;
  server::CallContext ctx;
  ASSERT_TRUE(service->loadModel(ctx, load, model).ok());

  const Status served = getFunction(*service, model.model_id, R"({"function": "rnea", "outputs": [{"kind": "value"}]})");
  EXPECT_TRUE(served.ok()) << served.message;  // the interpreter serves it
  const auto deadline = std::chrono::steady_clock::now() + 10s;
  while (service->metrics().builds_failed == 0 && std::chrono::steady_clock::now() < deadline)
    std::this_thread::sleep_for(10ms);
  EXPECT_EQ(service->metrics().builds_failed, 1u);
  EXPECT_EQ(service->metrics().specs_invalid, 0u);

  const std::string bad = R"({"function": "fk", "frame": "no_such_frame", "outputs": [{"kind": "value"}]})";
  EXPECT_EQ(getFunction(*service, model.model_id, bad).code, StatusCode::InvalidArgument);
  // Asked again: answered from the recent failure, not traced (nor counted) again.
  EXPECT_EQ(getFunction(*service, model.model_id, bad).code, StatusCode::InvalidArgument);
  const std::string other = R"({"function": "fk", "frame": "nor_this_one", "outputs": [{"kind": "value"}]})";
  EXPECT_EQ(getFunction(*service, model.model_id, other).code, StatusCode::InvalidArgument);

  const server::ServiceMetrics m = service->metrics();
  EXPECT_EQ(m.specs_invalid, 2u);
  EXPECT_EQ(m.builds_failed, 1u);  // unchanged by the invalid specs
  const PromText p = parsePrometheusText(server::serviceMetricsText(m));
  ASSERT_TRUE(p.errors.empty()) << p.errorText();
  EXPECT_EQ(p.value("robodiff_specs_invalid_total"), 2.0);
  EXPECT_EQ(p.value("robodiff_builds_failed_total"), 1.0);
  EXPECT_EQ(p.family("robodiff_specs_invalid_total")->type, "counter");
  const nlohmann::json overview = nlohmann::json::parse(server::overviewJson(service->overview()));
  EXPECT_EQ(overview["specs_invalid"], 2);
  EXPECT_EQ(overview["builds"]["failed"], 1);
}

// Every fleet family this page may carry besides robodiff_fleet_role.
const std::vector<std::string> kFleetRobotFamilies = {
    "robodiff_fleet_artifacts_fetched_total",      "robodiff_fleet_bytes_fetched_total",
    "robodiff_fleet_artifacts_refused_total",      "robodiff_fleet_fetch_failures_total",
    "robodiff_fleet_peer_artifacts_fetched_total", "robodiff_fleet_peer_bytes_fetched_total",
    "robodiff_fleet_peer_refusals_total",          "robodiff_fleet_peer_failures_total",
    "robodiff_fleet_peer_fetch_seconds_total",
    "robodiff_fleet_peer_reachable"};
const std::vector<std::string> kFleetBuildFamilies = {"robodiff_fleet_artifacts_served_total",
                                                      "robodiff_fleet_bytes_served_total",
                                                      "robodiff_fleet_builds_for_robots_total"};

TEST(ServiceMetrics, AStandaloneServerShowsItsRoleAndNoFleetCounters) {
  ServingService service;
  const server::ServiceMetrics m = service->metrics();
  EXPECT_EQ(m.fleet.role, "standalone");
  const PromText p = parsePrometheusText(server::serviceMetricsText(m));
  ASSERT_TRUE(p.errors.empty()) << p.errorText();
  ASSERT_NE(p.family("robodiff_fleet_role"), nullptr);
  EXPECT_EQ(p.family("robodiff_fleet_role")->type, "gauge");
  ASSERT_EQ(p.family("robodiff_fleet_role")->samples.size(), 1u);  // info-style: the role only
  EXPECT_EQ(p.value("robodiff_fleet_role", {{"role", "standalone"}}), 1.0);
  for (const auto& names : {kFleetRobotFamilies, kFleetBuildFamilies})
    for (const std::string& name : names) EXPECT_EQ(p.family(name), nullptr) << name;

  const nlohmann::json fleet = nlohmann::json::parse(server::overviewJson(service->overview()))["fleet"];
  EXPECT_EQ(fleet["role"], "standalone");
  EXPECT_EQ(fleet["artifacts_fetched"], 0);
  EXPECT_TRUE(fleet["peers"].is_array() && fleet["peers"].empty()) << fleet;
}

// A robot host with two build hosts: one reachable, one whose service name needs escaping.
server::ServiceMetrics fleetRobotMetrics() {
  server::ServiceMetrics m;
  rpc::FleetFigures& f = m.fleet;
  f.role = "robot";
  f.target = "x86-64-v3";
  f.artifacts_fetched = 5;
  f.bytes_fetched = 123456789;
  f.artifacts_refused = 1;
  f.fetch_failures = 2;
  f.peers.push_back({"robodiff_build_a", "builder-a:42:x", true, 4, 100000000, 0, 1, 2.5, "lost after 0 of 9 bytes"});
  f.peers.push_back({"odd \"host\"\\b\nz", "", false, 1, 23456789, 1, 7, 0.125, "refused: signature does not verify"});
  return m;
}

TEST(ServiceMetrics, ARobotHostShowsItsFleetCountsPerBuildHost) {
  const std::string text = server::serviceMetricsText(fleetRobotMetrics());
  const PromText p = parsePrometheusText(text);
  ASSERT_TRUE(p.errors.empty()) << p.errorText() << text;
  EXPECT_EQ(p.value("robodiff_fleet_role", {{"role", "robot"}}), 1.0);
  EXPECT_EQ(p.family("robodiff_fleet_role")->samples.size(), 1u);
  EXPECT_EQ(p.value("robodiff_fleet_artifacts_fetched_total"), 5.0);
  EXPECT_EQ(p.value("robodiff_fleet_bytes_fetched_total"), 123456789.0);
  EXPECT_EQ(p.value("robodiff_fleet_artifacts_refused_total"), 1.0);
  EXPECT_EQ(p.value("robodiff_fleet_fetch_failures_total"), 2.0);
  for (const std::string& name : kFleetRobotFamilies) {
    ASSERT_NE(p.family(name), nullptr) << name;
    EXPECT_EQ(p.family(name)->type, name.ends_with("_total") ? "counter" : "gauge") << name;
    EXPECT_FALSE(p.family(name)->help.empty()) << name;
  }
  for (const std::string& name : kFleetBuildFamilies) EXPECT_EQ(p.family(name), nullptr) << name;

  const std::map<std::string, std::string> a = {{"build_host", "robodiff_build_a"}};
  const std::map<std::string, std::string> b = {{"build_host", "odd \"host\"\\b\nz"}};  // as parsed back
  EXPECT_EQ(p.value("robodiff_fleet_peer_artifacts_fetched_total", a), 4.0);
  EXPECT_EQ(p.value("robodiff_fleet_peer_bytes_fetched_total", a), 100000000.0);
  EXPECT_EQ(p.value("robodiff_fleet_peer_refusals_total", a), 0.0);
  EXPECT_EQ(p.value("robodiff_fleet_peer_failures_total", a), 1.0);
  EXPECT_EQ(p.value("robodiff_fleet_peer_fetch_seconds_total", a), 2.5);
  EXPECT_EQ(p.value("robodiff_fleet_peer_fetch_seconds_total", b), 0.125);
  EXPECT_EQ(p.value("robodiff_fleet_peer_reachable", a), 1.0);
  EXPECT_EQ(p.value("robodiff_fleet_peer_artifacts_fetched_total", b), 1.0);
  EXPECT_EQ(p.value("robodiff_fleet_peer_bytes_fetched_total", b), 23456789.0);
  EXPECT_EQ(p.value("robodiff_fleet_peer_refusals_total", b), 1.0);
  EXPECT_EQ(p.value("robodiff_fleet_peer_failures_total", b), 7.0);
  EXPECT_EQ(p.value("robodiff_fleet_peer_reachable", b), 0.0);
  EXPECT_EQ(p.family("robodiff_fleet_peer_reachable")->samples.size(), 2u);
  // On the page itself: the quote, backslash and newline escaped as the format says.
  EXPECT_NE(text.find("robodiff_fleet_peer_reachable{build_host=\"odd \\\"host\\\"\\\\b\\nz\"} 0\n"),
            std::string::npos)
      << text;
}

TEST(ServiceMetrics, ABuildHostShowsWhatItServed) {
  server::ServiceMetrics m;
  m.fleet.role = "build";
  m.fleet.artifacts_served = 3;
  m.fleet.bytes_served = 7340032;
  m.fleet.builds_for_robots = 2;
  const PromText p = parsePrometheusText(server::serviceMetricsText(m));
  ASSERT_TRUE(p.errors.empty()) << p.errorText();
  EXPECT_EQ(p.value("robodiff_fleet_role", {{"role", "build"}}), 1.0);
  EXPECT_EQ(p.value("robodiff_fleet_artifacts_served_total"), 3.0);
  EXPECT_EQ(p.value("robodiff_fleet_bytes_served_total"), 7340032.0);
  EXPECT_EQ(p.value("robodiff_fleet_builds_for_robots_total"), 2.0);
  for (const std::string& name : kFleetBuildFamilies) EXPECT_EQ(p.family(name)->type, "counter") << name;
  for (const std::string& name : kFleetRobotFamilies) EXPECT_EQ(p.family(name), nullptr) << name;
}

TEST(ServiceMetrics, TheOverviewCarriesTheFleetAndItsBuildHosts) {
  server::ServiceOverview o;
  o.metrics = fleetRobotMetrics();
  const nlohmann::json f = nlohmann::json::parse(server::overviewJson(o))["fleet"];
  EXPECT_EQ(f["role"], "robot");
  EXPECT_EQ(f["target"], "x86-64-v3");
  EXPECT_EQ(f["artifacts_fetched"], 5);
  EXPECT_EQ(f["bytes_fetched"], 123456789);
  EXPECT_EQ(f["artifacts_refused"], 1);
  EXPECT_EQ(f["fetch_failures"], 2);
  EXPECT_EQ(f["artifacts_served"], 0);
  EXPECT_EQ(f["bytes_served"], 0);
  EXPECT_EQ(f["builds_for_robots"], 0);
  ASSERT_EQ(f["peers"].size(), 2u);
  const nlohmann::json& a = f["peers"][0];
  EXPECT_EQ(a["service"], "robodiff_build_a");
  EXPECT_EQ(a["instance_id"], "builder-a:42:x");
  EXPECT_EQ(a["reachable"], true);
  EXPECT_EQ(a["artifacts_fetched"], 4);
  EXPECT_EQ(a["bytes_fetched"], 100000000);
  EXPECT_EQ(a["refusals"], 0);
  EXPECT_EQ(a["failures"], 1);
  EXPECT_EQ(a["last_problem"], "lost after 0 of 9 bytes");
  const nlohmann::json& b = f["peers"][1];
  EXPECT_EQ(b["service"], "odd \"host\"\\b\nz");
  EXPECT_EQ(b["instance_id"], "");
  EXPECT_EQ(b["reachable"], false);
  EXPECT_EQ(b["failures"], 7);
  EXPECT_EQ(b["last_problem"], "refused: signature does not verify");
}

}  // namespace
}  // namespace robodiff::testing
