// A real Service's metrics(): requests recorded by method and status land in the counters
// and in cumulative latency buckets that agree with them, and the page renders validly;
// invalid specs and failed library builds are two counters, each counting only its own.
#include <gtest/gtest.h>

#include <chrono>
#include <cstdio>
#include <thread>

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

}  // namespace
}  // namespace robodiff::testing
