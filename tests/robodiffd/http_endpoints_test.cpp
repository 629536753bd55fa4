// robodiffd's HTTP endpoints end to end: a RouDi of this test's own, robodiffd with
// --http 127.0.0.1:0 (the port read from its http_listening log line), calls over DDS,
// then /metrics parsed as the Prometheus text format with the calls counted, /healthz,
// /readyz; RouDi killed: /readyz turns 503 naming roudi while /healthz stays 200, and
// robodiffd still stops on SIGTERM. Also: the listener's defaults (127.0.0.1:9464), the
// settings' errors, and a robodiffd on its defaults listening on loopback.
#include <signal.h>

#include <cmath>
#include <nlohmann/json.hpp>
#include <sstream>
#include <thread>

#include "http/http_client.hpp"
#include "robodiffd/service_fixture.hpp"
#include "server_config.hpp"
#include "support/prometheus_text.hpp"

namespace robodiff::testing {
namespace {

using namespace std::chrono_literals;

// Polls `path` until its status is `status` (or `timeout` passes); the last reply.
HttpReply waitForStatus(std::uint16_t port, const std::string& path, int status, std::chrono::milliseconds timeout) {
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  HttpReply r = httpGet(port, path);
  while (r.status != status && std::chrono::steady_clock::now() < deadline) {
    std::this_thread::sleep_for(50ms);
    r = httpGet(port, path);
  }
  return r;
}

TEST(HttpEndpoints, MetricsCountCallsAndReadinessFlipsWhenRoudiStops) {
  signal(SIGTERM, SIG_IGN);  // as the other robodiffd tests: this process is no iceoryx user, but be safe
  RoudiProcess roudi;        // this test's own: it is killed below (not sharedRoudi(), others use that)
  if (!roudi.started()) GTEST_SKIP() << "a RouDi of someone else's runs; this test must not kill it";
  TempDir dir;
  RobodiffdProcess server(dir / "cache", dir / "robodiffd.log",
                          {"--roudi", "external", "--http", "127.0.0.1:0", "--interpreter-only"});
  ASSERT_TRUE(server.running());
  const nlohmann::json listening = logEvent(server.log(), "http_listening");
  ASSERT_TRUE(listening.is_object()) << server.log();
  const auto port = listening["port"].get<std::uint16_t>();
  ASSERT_NE(port, 0);
  EXPECT_EQ(listening["address"].get<std::string>(), "127.0.0.1:" + std::to_string(port));

  // Calls over DDS (this process stays off iceoryx: its RouDi is killed below).
  constexpr int kEvaluations = 5;
  {
    auto c = connectTo("dds");
    rpc::LoadModelRequest load;
    load.urdf = arm7Text();
    rpc::LoadModelReply model;
    ASSERT_TRUE(c->loadModel(load, model).ok());
    rpc::GetFunctionRequest get;
    get.model_id = model.model_id;
    get.spec_json = kRneaJacobianSpec;
    get.wait = true;
    rpc::GetFunctionReply function;
    const Status got = c->getFunction(get, function);
    ASSERT_TRUE(got.ok()) << got.message;
    const std::vector<double> in(21, 0.1);
    std::vector<double> out(7 + 7 * 21);
    for (int i = 0; i < kEvaluations; ++i) {
      const Status s = c->evaluate(function.function_id, in, out);
      ASSERT_TRUE(s.ok()) << toString(s.code) << ": " << s.message;
    }
    const Status unknown = c->evaluate(std::string(64, 'f'), in, out);
    EXPECT_EQ(unknown.code, StatusCode::NotFound) << unknown.message;
  }

  // /metrics: the text format, the calls counted (a reply is counted just after it is
  // sent, and its request slot freed after that: poll for both).
  PromText metrics;
  HttpReply page;
  for (int attempt = 0; attempt < 40; ++attempt) {
    page = httpGet(port, "/metrics");
    metrics = parsePrometheusText(page.body);
    if (metrics.value("robodiff_requests_total", {{"method", "Evaluate"}, {"status", "NOT_FOUND"}}) == 1.0 &&
        metrics.value("robodiff_request_queue_depth") == 0.0)
      break;
    std::this_thread::sleep_for(50ms);
  }
  ASSERT_EQ(page.status, 200) << page.head;
  EXPECT_EQ(page.header("Content-Type").rfind("text/plain; version=0.0.4", 0), 0u) << page.head;
  ASSERT_TRUE(metrics.errors.empty()) << metrics.errorText() << page.body;
  EXPECT_EQ(metrics.value("robodiff_requests_total", {{"method", "Evaluate"}, {"status", "OK"}}), kEvaluations)
      << page.body;
  EXPECT_EQ(metrics.value("robodiff_requests_total", {{"method", "Evaluate"}, {"status", "NOT_FOUND"}}), 1.0);
  EXPECT_EQ(metrics.value("robodiff_requests_total", {{"method", "LoadModel"}, {"status", "OK"}}), 1.0);
  EXPECT_EQ(metrics.value("robodiff_requests_total", {{"method", "GetFunction"}, {"status", "OK"}}), 1.0);
  // Each method's histogram counts what its request counters count.
  const PromFamily* requests = metrics.family("robodiff_requests_total");
  ASSERT_NE(requests, nullptr);
  std::map<std::string, double> per_method;
  for (const PromSample& s : requests->samples) per_method[s.labels.at("method")] += s.value;
  for (const auto& [method, n] : per_method)
    EXPECT_EQ(metrics.value("robodiff_request_duration_seconds_count", {{"method", method}}), n) << method;
  EXPECT_EQ(per_method["Evaluate"], kEvaluations + 1);
  const auto evaluate_sum = metrics.value("robodiff_request_duration_seconds_sum", {{"method", "Evaluate"}});
  ASSERT_TRUE(evaluate_sum.has_value());
  EXPECT_GT(*evaluate_sum, 0.0);
  EXPECT_LT(*evaluate_sum, 10.0);
  EXPECT_GE(metrics.value("robodiff_transport_requests_total", {{"transport", "dds"}}).value_or(0), kEvaluations + 3);
  EXPECT_EQ(metrics.value("robodiff_serving_state", {{"state", "serving"}}), 1.0);
  EXPECT_EQ(metrics.value("robodiff_models_loaded"), 1.0);
  EXPECT_EQ(metrics.value("robodiff_functions_loaded"), 1.0);
  EXPECT_TRUE(metrics.value("robodiff_cache_entries").has_value());
  EXPECT_TRUE(metrics.value("robodiff_workers", {{"state", "idle"}}).has_value());
  EXPECT_EQ(metrics.value("robodiff_request_queue_depth"), 0.0);
  EXPECT_EQ(metrics.value("robodiff_jobs", {{"state", "running"}}), 0.0);
  EXPECT_GT(metrics.value("robodiff_uptime_seconds").value_or(0), 0.0);

  // Probes while everything is up.
  const HttpReply live = httpGet(port, "/healthz");
  EXPECT_EQ(live.status, 200);
  EXPECT_EQ(live.body, "ok\n");
  const HttpReply ready = httpGet(port, "/readyz");
  EXPECT_EQ(ready.status, 200) << ready.body;
  EXPECT_NE(ready.body.find("service: ok\n"), std::string::npos) << ready.body;
  EXPECT_NE(ready.body.find("roudi: ok\n"), std::string::npos) << ready.body;
  EXPECT_NE(ready.body.find("dds: ok\n"), std::string::npos) << ready.body;
  EXPECT_NE(ready.body.find("cache: ok (writable"), std::string::npos) << ready.body;
  EXPECT_EQ(httpGet(port, "/metrics", "POST").status, 405);
  EXPECT_EQ(httpGet(port, "/nothing").status, 404);

  // RouDi goes (robodiffd idle: nothing in an iceoryx call): not ready, naming roudi; still live.
  std::this_thread::sleep_for(200ms);
  roudi.stop();
  const HttpReply unready = waitForStatus(port, "/readyz", 503, 5s);
  EXPECT_EQ(unready.status, 503) << unready.body;
  EXPECT_NE(unready.body.find("roudi: failed ("), std::string::npos) << unready.body;
  EXPECT_NE(unready.body.find("dds: ok\n"), std::string::npos) << unready.body;
  EXPECT_NE(unready.body.find("cache: ok"), std::string::npos) << unready.body;
  EXPECT_EQ(httpGet(port, "/healthz").status, 200);

  // SIGTERM still stops it (no iceoryx request in flight to wait for).
  const int code = server.terminate(std::chrono::seconds(30));
  EXPECT_GE(code, 0) << "robodiffd did not exit on SIGTERM after RouDi went; log:\n" << server.log();
  EXPECT_EQ(connectLocal(port), -1);  // the listener is gone with it
}

TEST(HttpEndpoints, ListenerDefaultsToLoopback9464) {
  const server::ServerConfig defaults;
  EXPECT_TRUE(defaults.http.enabled);
  EXPECT_EQ(defaults.http.host, "127.0.0.1");
  EXPECT_EQ(defaults.http.port, 9464);
  const std::string printed = server::formatConfig(defaults);
  EXPECT_NE(printed.find("[http]\nenabled = true\nlisten = \"127.0.0.1:9464\"\n"), std::string::npos) << printed;
}

TEST(HttpEndpoints, ListenSettingErrorsNameKeyAndValue) {
  auto errorOf = [](const std::string& value) -> std::string {
    server::ServerConfig config;
    try {
      server::applySetting(config, "http.listen", value, "--http");
    } catch (const server::ConfigError& e) {
      return e.what();
    }
    return "";
  };
  for (const std::string bad :
       {"9464", "localhost:9464", "127.0.0.1:65536", "127.0.0.1:http", "::1:9464", "1.2.3:80"}) {
    const std::string e = errorOf(bad);
    EXPECT_NE(e.find("--http: http.listen = '" + bad + "'"), std::string::npos) << bad << ": " << e;
  }
  server::ServerConfig config;
  server::applySetting(config, "http.listen", "0.0.0.0:0", "--set");
  EXPECT_EQ(config.http.host, "0.0.0.0");
  EXPECT_EQ(config.http.port, 0);
  server::applyConfigText(config, "[http]\nenabled = false\nlisten = \"10.1.2.3:8080\"\n", "test.conf");
  EXPECT_FALSE(config.http.enabled);
  EXPECT_EQ(config.http.host, "10.1.2.3");
  EXPECT_EQ(config.http.port, 8080);
}

// A robodiffd with no HTTP flag listens on 127.0.0.1:9464 (or, when another process holds
// that port, says so naming the same address and keeps serving).
TEST(HttpEndpoints, RobodiffdOnItsDefaultsListensOnLoopback) {
  TempDir dir;
  RobodiffdProcess server(dir / "cache", dir / "robodiffd.log", {"--no-iceoryx", "--interpreter-only"});
  ASSERT_TRUE(server.running());
  const nlohmann::json listening = logEvent(server.log(), "http_listening");
  if (listening.is_object()) {
    EXPECT_EQ(listening["address"].get<std::string>(), "127.0.0.1:9464");
    EXPECT_EQ(httpGet(9464, "/healthz").status, 200);
  } else {
    const nlohmann::json failed = logEvent(server.log(), "http_failed");
    ASSERT_TRUE(failed.is_object()) << server.log();
    EXPECT_NE(failed["message"].get<std::string>().find("127.0.0.1:9464"), std::string::npos) << server.log();
  }
  EXPECT_EQ(server.terminate(), 0);
}

// --no-http: no listener, no log line.
TEST(HttpEndpoints, NoHttpFlagTurnsItOff) {
  TempDir dir;
  RobodiffdProcess server(dir / "cache", dir / "robodiffd.log", {"--no-iceoryx", "--interpreter-only", "--no-http"});
  ASSERT_TRUE(server.running());
  EXPECT_TRUE(logEvent(server.log(), "http_listening").is_null()) << server.log();
  EXPECT_TRUE(logEvent(server.log(), "http_failed").is_null()) << server.log();
  EXPECT_EQ(server.terminate(), 0);
}

}  // namespace
}  // namespace robodiff::testing
