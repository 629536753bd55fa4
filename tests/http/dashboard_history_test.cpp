// The dashboard's history kept by the server: one point per interval from the difference
// of two fine-histogram samples (latency percentiles and rates of that interval alone),
// and GET /api/history from a real Service sampled by its own thread: points appear one
// per interval, in order, never more than the capacity, `after` selects the newer ones,
// and a bad `after` is a 400 naming it.
#include <gtest/gtest.h>

#include <chrono>
#include <thread>

#include <nlohmann/json.hpp>

#include "http/http_client.hpp"
#include "http/serving_service.hpp"
#include "robodiff/server/dashboard.hpp"
#include "robodiff/server/dashboard_history.hpp"

namespace robodiff::testing {
namespace {

using namespace std::chrono_literals;
using nlohmann::json;
using Latencies = std::vector<server::ServiceOverview::MethodLatency>;

TEST(DashboardHistory, APointIsTheIntervalBetweenTwoSamples) {
  const Latencies before = {{rpc::Method::Evaluate, {{1000, 5}}}, {rpc::Method::Health, {{500, 2}}}};
  // In 2 s: 100 more Evaluates (90 under 2 us, 10 under 4 us), none batched, 2 Health.
  const Latencies now = {{rpc::Method::Evaluate, {{1000, 5}, {2000, 90}, {4000, 10}}},
                         {rpc::Method::EvaluateBatch, {}},
                         {rpc::Method::Health, {{500, 4}}}};
  const server::HistoryPoint p = server::historyPoint(before, now, 2.0, 1.8e9);
  EXPECT_DOUBLE_EQ(p.unix_seconds, 1.8e9);
  EXPECT_DOUBLE_EQ(p.evaluate_per_second, 50.0);
  ASSERT_TRUE(p.evaluate_p50_us && p.evaluate_p99_us);
  EXPECT_DOUBLE_EQ(*p.evaluate_p50_us, 2.0);  // not 1: the 5 calls before the interval are not in it
  EXPECT_DOUBLE_EQ(*p.evaluate_p99_us, 4.0);
  EXPECT_DOUBLE_EQ(p.batch_per_second, 0.0);
  EXPECT_FALSE(p.batch_p50_us.has_value());  // no call: no latency rather than 0
  EXPECT_DOUBLE_EQ(p.other_per_second, 1.0);
}

TEST(DashboardHistory, AQuietIntervalHasRatesOfZeroAndNoLatency) {
  const Latencies same = {{rpc::Method::Evaluate, {{1000, 5}}}};
  const server::HistoryPoint p = server::historyPoint(same, same, 1.0, 1.8e9);
  EXPECT_DOUBLE_EQ(p.evaluate_per_second, 0.0);
  EXPECT_FALSE(p.evaluate_p50_us.has_value());
  EXPECT_FALSE(p.evaluate_p99_us.has_value());
}

TEST(DashboardHistory, AZeroIntervalOrCapacityIsRefused) {
  ServingService service;
  EXPECT_THROW(server::DashboardHistory(*service, {0ms, 10}), std::invalid_argument);
  EXPECT_THROW(server::DashboardHistory(*service, {10ms, 0}), std::invalid_argument);
}

json getHistory(std::uint16_t port, const std::string& query = "") {
  const HttpReply reply = httpGet(port, "/api/history" + query);
  EXPECT_EQ(reply.status, 200) << reply.head << reply.body;
  EXPECT_EQ(reply.header("Content-Type"), "application/json");
  return reply.status == 200 ? json::parse(reply.body) : json::object({{"points", json::array()}});
}

// Polls /api/history until `done(history)` or 10 s.
template <class Done>
json waitForHistory(std::uint16_t port, Done done) {
  const auto deadline = std::chrono::steady_clock::now() + 10s;
  json h = getHistory(port);
  while (!done(h) && std::chrono::steady_clock::now() < deadline) {
    std::this_thread::sleep_for(10ms);
    h = getHistory(port);
  }
  return h;
}

TEST(DashboardHistory, ServedOverHttpOnePointPerIntervalBoundedAndInOrder) {
  ServingService service;
  server::HttpServerOptions options;
  options.port = 0;
  server::HttpServer http(options);
  constexpr std::size_t kCapacity = 5;
  server::routeDashboard(http, *service, {20ms, kCapacity});
  http.start();

  // The first point: the sampler has its baseline, so calls from now on land in a point.
  json h = waitForHistory(http.port(), [](const json& j) { return !j["points"].empty(); });
  ASSERT_FALSE(h["points"].empty()) << h;
  EXPECT_DOUBLE_EQ(h["interval_seconds"].get<double>(), 0.02);
  EXPECT_EQ(h["capacity"], kCapacity);
  for (int i = 0; i < 10; ++i) service->recordRequest("test", rpc::Method::Evaluate, StatusCode::Ok, 40us);
  auto evaluatePoint = [](const json& j) {
    for (const json& p : j["points"])
      if (p["rate"]["Evaluate"].get<double>() > 0) return p;
    return json();
  };
  h = waitForHistory(http.port(), [&](const json& j) { return !evaluatePoint(j).is_null(); });
  const json p = evaluatePoint(h);
  ASSERT_FALSE(p.is_null()) << h;
  EXPECT_GE(p["latency"]["Evaluate p50"].get<double>(), 40.0);  // the bucket's bound: within 9% above
  EXPECT_LE(p["latency"]["Evaluate p50"].get<double>(), 40.0 * 1.1);
  EXPECT_TRUE(p["latency"]["EvaluateBatch p50"].is_null());
  EXPECT_GT(p["rate"]["Evaluate"].get<double>(), 0.0);

  // After more than `capacity` samples: exactly `capacity` points, the newest, in order,
  // about one interval apart.
  h = waitForHistory(http.port(), [](const json& j) { return j["points"].size() == kCapacity; });
  std::this_thread::sleep_for(200ms);  // ~10 more samples
  h = getHistory(http.port());
  ASSERT_EQ(h["points"].size(), kCapacity) << h;
  for (std::size_t i = 1; i < kCapacity; ++i) {
    const double gap = h["points"][i]["t"].get<double>() - h["points"][i - 1]["t"].get<double>();
    EXPECT_GT(gap, 0.0) << h;
    EXPECT_LT(gap, 1.0) << h;  // 20 ms apart, generously (a loaded machine)
  }
  EXPECT_GT(h["points"][0]["t"].get<double>(), p["t"].get<double>()) << "the oldest points were dropped";

  // after=<t>: the points after that time only (t as the JSON wrote it: exact).
  const std::string third = h["points"][2]["t"].dump();
  const json newer = getHistory(http.port(), "?after=" + third);
  ASSERT_FALSE(newer["points"].empty());
  for (const json& q : newer["points"]) EXPECT_GT(q["t"].get<double>(), h["points"][2]["t"].get<double>());

  for (const char* bad : {"?after=soon", "?after=", "?after=1e999", "?after=12abc"}) {
    const HttpReply reply = httpGet(http.port(), std::string("/api/history") + bad);
    EXPECT_EQ(reply.status, 400) << bad;
    EXPECT_NE(reply.body.find("after="), std::string::npos) << bad << ": " << reply.body;
  }
  http.stop();
}

}  // namespace
}  // namespace robodiff::testing
