// The dashboard's server side: overviewJson renders every field the page reads (units,
// nulls for what has not happened), the page holds the elements the page's script and
// the browser test rely on and loads nothing from elsewhere, and the routes serve both
// from a real Service over a real HTTP listener. (The page itself runs in Chromium in
// tests/dashboard.)
#include <gtest/gtest.h>

#include <cstdio>
#include <nlohmann/json.hpp>
#include <regex>

#include "http/http_client.hpp"
#include "http/serving_service.hpp"
#include "robodiff/server/dashboard.hpp"
#include "support/temp_dir.hpp"
#include "support/test_paths.hpp"

namespace robodiff::testing {
namespace {

using nlohmann::json;

server::ServiceOverview sampleOverview() {
  server::ServiceOverview o;
  o.instance_id = "host:1:abc";
  o.version = "9.9.9";
  o.metrics.state = rpc::ServingState::Serving;
  o.metrics.uptime_seconds = 12.5;
  o.metrics.cache_hits = 3;
  o.metrics.cache_misses = 1;
  o.metrics.cache_bytes = 4096;
  o.metrics.builds_failed = 1;
  o.metrics.specs_invalid = 2;
  o.metrics.jobs_enabled = true;
  o.metrics.jobs.running = 1;
  o.models.push_back({"m1", "arm7 (arm.urdf)", false, 7, 7, 7, 18, 2, 1});
  server::ServiceOverview::Function f;
  f.id = "f1";
  f.model_id = "m1";
  f.model_name = "arm7";
  f.function = "rnea";
  f.outputs = "value, jacobian[q,v,a]";
  f.phase = "compiled";
  f.calls = 10;
  f.p50_ns = 1500;
  f.p99_ns = 2500;
  f.max_ns = 9000;
  f.batch_calls = 1;
  f.batch_knots = 4;
  f.batch_ns = 2000;
  f.trace_seconds = 0.25;
  f.compile_seconds = -1;  // not compiled: null
  o.functions.push_back(f);
  o.build_failures.push_back({1.8e9, "f0", "arm7", "crba", "cc: error: boom", true, "compile"});
  rpc::JobInfo job;
  job.job_id = "j1";
  job.kind = "trajectory";
  job.state = rpc::JobState::Running;
  job.progress = 0.25;
  job.eta_seconds = -1;  // unknown: null
  job.messages = {"reading", "evaluating"};
  o.jobs.push_back(job);
  rpc::MethodStats evaluate;
  evaluate.method = rpc::Method::Evaluate;
  evaluate.requests = 10;
  evaluate.p50_ns = 4000;
  o.methods.push_back(evaluate);
  o.latencies.push_back({rpc::Method::Evaluate, {{4095, 7}, {8191, 3}}});
  return o;
}

TEST(Dashboard, OverviewJsonCarriesEveryFieldInItsUnit) {
  const json j = json::parse(server::overviewJson(sampleOverview()));
  EXPECT_EQ(j["instance_id"], "host:1:abc");
  EXPECT_EQ(j["state"], "SERVING");
  EXPECT_DOUBLE_EQ(j["uptime_seconds"].get<double>(), 12.5);
  EXPECT_GT(j["unix_seconds"].get<double>(), 1.7e9);

  ASSERT_EQ(j["models"].size(), 1u);
  EXPECT_EQ(j["models"][0]["name"], "arm7 (arm.urdf)");
  EXPECT_EQ(j["models"][0]["frames"], 18);
  EXPECT_EQ(j["models"][0]["references"], 2);

  ASSERT_EQ(j["functions"].size(), 1u);
  const json& f = j["functions"][0];
  EXPECT_EQ(f["phase"], "compiled");
  EXPECT_DOUBLE_EQ(f["p50_us"].get<double>(), 1.5);
  EXPECT_DOUBLE_EQ(f["p99_us"].get<double>(), 2.5);
  EXPECT_DOUBLE_EQ(f["batch_us_per_knot"].get<double>(), 0.5);
  EXPECT_DOUBLE_EQ(f["trace_seconds"].get<double>(), 0.25);
  EXPECT_TRUE(f["compile_seconds"].is_null());

  EXPECT_DOUBLE_EQ(j["cache"]["hit_rate"].get<double>(), 0.75);
  EXPECT_EQ(j["cache"]["bytes"], 4096);
  EXPECT_EQ(j["builds"]["failed"], 1);
  EXPECT_EQ(j["specs_invalid"], 2);  // apart from the failed builds
  ASSERT_EQ(j["build_failures"].size(), 1u);
  EXPECT_EQ(j["build_failures"][0]["message"], "cc: error: boom");
  EXPECT_TRUE(j["build_failures"][0]["interpreter_serves"].get<bool>());
  EXPECT_EQ(j["build_failures"][0]["stage"], "compile");

  ASSERT_EQ(j["jobs"].size(), 1u);
  EXPECT_EQ(j["jobs"][0]["state"], "RUNNING");
  EXPECT_DOUBLE_EQ(j["jobs"][0]["progress"].get<double>(), 0.25);
  EXPECT_TRUE(j["jobs"][0]["eta_seconds"].is_null());
  EXPECT_EQ(j["jobs"][0]["messages"][1], "evaluating");
  EXPECT_EQ(j["job_counts"]["RUNNING"], 1);

  ASSERT_EQ(j["methods"].size(), 1u);
  EXPECT_EQ(j["methods"][0]["name"], "Evaluate");
  EXPECT_DOUBLE_EQ(j["methods"][0]["p50_us"].get<double>(), 4.0);
  EXPECT_EQ(j["methods"][0]["buckets"], json::parse("[[4095, 7], [8191, 3]]"));
}

TEST(Dashboard, NoLookupsMeansNoHitRateRatherThanZero) {
  server::ServiceOverview o;
  const json j = json::parse(server::overviewJson(o));
  EXPECT_TRUE(j["cache"]["hit_rate"].is_null());
  EXPECT_TRUE(j["models"].is_array() && j["models"].empty());
  EXPECT_TRUE(j["jobs"].is_array() && j["jobs"].empty());
  EXPECT_EQ(j["fleet"]["role"], "standalone");  // no role set: not in a fleet (the page hides its panel)
  EXPECT_TRUE(j["fleet"]["peers"].is_array() && j["fleet"]["peers"].empty());
}

TEST(Dashboard, ThePageHoldsItsElementsAndLoadsNothingFromElsewhere) {
  const std::string page(server::dashboardPage());
  ASSERT_EQ(page.rfind("<!DOCTYPE html>", 0), 0u);
  for (const char* id : {"id=\"models\"", "id=\"functions\"", "id=\"jobs\"", "id=\"build-queue\"",
                         "id=\"build-failures\"", "id=\"latency-chart\"", "id=\"rate-chart\"", "id=\"cache-hit-rate\"",
                         "id=\"cache-bytes\"", "id=\"refresh-status\"", "id=\"builds-failed\"", "id=\"specs-invalid\"",
                         "id=\"fleet\" hidden", "id=\"fleet-role\"", "id=\"fleet-counts\"", "id=\"fleet-peers\"",
                         "/api/overview", "/api/history", "robodiffDashboard"})
    EXPECT_NE(page.find(id), std::string::npos) << id;
  // Every src/href is local (robot computers have no internet; nothing may be fetched).
  const std::regex external(R"((src|href)\s*=\s*["']?(https?:)?//)");
  EXPECT_FALSE(std::regex_search(page, external));
  EXPECT_EQ(page.find("<script src"), std::string::npos);
  EXPECT_EQ(page.find("<link"), std::string::npos);
}

TEST(Dashboard, RoutesServeThePageAndTheOverviewOfARealService) {
  ServingService service;
  rpc::LoadModelRequest load;
  load.urdf = readFile(sourceDir() / "examples/robots/arm7.urdf");
  load.options_json = R"({"source_name": "arm7.urdf"})";
  rpc::LoadModelReply model;
  server::CallContext ctx;
  ASSERT_TRUE(service->loadModel(ctx, load, model).ok());

  server::HttpServerOptions options;
  options.port = 0;
  server::HttpServer http(options);
  server::routeDashboard(http, *service);
  http.start();

  for (const char* path : {"/", "/dashboard"}) {
    const HttpReply page = httpGet(http.port(), path);
    EXPECT_EQ(page.status, 200) << path;
    EXPECT_EQ(page.header("Content-Type"), "text/html; charset=utf-8") << path;
    EXPECT_EQ(page.body, std::string(server::dashboardPage())) << path;
  }
  const HttpReply overview = httpGet(http.port(), "/api/overview");
  ASSERT_EQ(overview.status, 200);
  EXPECT_EQ(overview.header("Content-Type"), "application/json");
  const json j = json::parse(overview.body);
  EXPECT_EQ(j["state"], "SERVING");
  ASSERT_EQ(j["models"].size(), 1u);
  EXPECT_EQ(j["models"][0]["id"], model.model_id);
  EXPECT_EQ(j["models"][0]["name"], "arm7 (arm7.urdf)");
  EXPECT_FALSE(j["jobs_enabled"].get<bool>());
  EXPECT_EQ(httpGet(http.port(), "/dashboard.js").status, 404);
  http.stop();
}

}  // namespace
}  // namespace robodiff::testing
