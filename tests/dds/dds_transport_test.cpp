// The DDS transport end to end on loopback: a DdsServer over a fake ServiceApi and
// DdsConnection clients, in one process (each with its own participant). Every method, batch
// chunking, the server's refusals, addressing one of two servers, deadlines, a missing or
// vanishing server, draining, and many threads at once.

#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <future>
#include <thread>

#include "dds_test_env.hpp"
#include "fake_service.hpp"
#include "robodiff/client/dds_connection.hpp"
#include "robodiff/server/dds_server.hpp"

namespace robodiff {
namespace {

using namespace std::chrono_literals;
using client::CallOptions;
using client::DdsConnection;
using client::DdsConnectionOptions;
using server::DdsServer;
using server::DdsServerOptions;
using testing::FakeService;
using Clock = std::chrono::steady_clock;

class DdsTransport : public testing::DdsTest {
 protected:
  DdsServerOptions serverOptions() const {
    DdsServerOptions o;
    o.domain_id = domain_;
    return o;
  }
  DdsConnectionOptions clientOptions() const {
    DdsConnectionOptions o;
    o.domain_id = domain_;
    o.connection.default_timeout = 10s;
    o.match_timeout = 10s;  // discovery on a loaded machine
    return o;
  }
  std::unique_ptr<DdsServer> startServer(FakeService& service, DdsServerOptions options) {
    auto server = std::make_unique<DdsServer>(service, options, log_);
    server->start();
    return server;
  }

  const std::uint32_t domain_ = testing::testDomain();
  server::Logger log_{stderr, server::LogLevel::Warn};
};

std::vector<double> ramp(std::size_t n, double scale = 1.0) {
  std::vector<double> v(n);
  for (std::size_t i = 0; i < n; ++i) v[i] = scale * (std::sin(0.1 * double(i)) + double(i));
  return v;
}

TEST_F(DdsTransport, EveryMethodRoundTrips) {
  FakeService service("srv-a");
  auto server = startServer(service, serverOptions());
  DdsConnection client(clientOptions());
  EXPECT_EQ(client.transport(), "dds");

  rpc::LoadModelReply model;
  Status s = client.loadModel({"<robot/>", true, R"({"g":1})"}, model);
  ASSERT_TRUE(s.ok()) << s.message;
  EXPECT_EQ(model.model_id, R"(model:8:floating:{"g":1})");
  EXPECT_EQ(model.joint_names, (std::vector<std::string>{"shoulder", "elbow", "wrist \xc3\xa4"}));
  EXPECT_EQ(model.frame_names, (std::vector<std::string>{"base", "tool"}));
  EXPECT_EQ(model.nq, 7u);
  EXPECT_EQ(model.nv, 6u);

  rpc::GetFunctionReply function;
  s = client.getFunction({"model-1", "tau", true}, function);
  ASSERT_TRUE(s.ok()) << s.message;
  EXPECT_EQ(function.function_id, "fn-double");
  EXPECT_EQ(function.state, rpc::FunctionState::Ready);
  ASSERT_EQ(function.inputs.size(), 3u);
  EXPECT_EQ(function.inputs[2].name, "tau");
  ASSERT_EQ(function.outputs.size(), 2u);
  EXPECT_EQ(function.outputs[1].layout, rpc::OutputLayout::SparseCsr);
  EXPECT_EQ(function.outputs[1].row_offsets, (std::vector<std::uint32_t>{0, 1, 1}));
  EXPECT_EQ(function.outputs[1].col_indices, (std::vector<std::uint32_t>{2}));

  rpc::ListFunctionsReply list;
  s = client.listFunctions({"model-1", 0, ""}, list);
  ASSERT_TRUE(s.ok()) << s.message;
  ASSERT_EQ(list.functions.size(), 2u);
  EXPECT_EQ(list.functions[0].evaluations, 12345678901ull);
  EXPECT_EQ(list.functions[1].message, "compiler said no");
  EXPECT_EQ(list.functions[1].model_id, "model-1");

  rpc::HealthReply health;
  s = client.health({false}, health);
  ASSERT_TRUE(s.ok()) << s.message;
  EXPECT_EQ(health.server_instance_id, "srv-a");
  EXPECT_EQ(health.state, rpc::ServingState::Serving);
  EXPECT_EQ(health.batch_threads, 16u);
  ASSERT_EQ(health.methods.size(), rpc::kMethodCount);
  EXPECT_EQ(health.methods[6].max_ns, 4006u);
  ASSERT_EQ(health.transports.size(), 2u);
  EXPECT_EQ(health.transports[1].transport, "iceoryx");

  rpc::ReleaseReply released;
  s = client.release({"fn-double"}, released);
  ASSERT_TRUE(s.ok()) << s.message;
  EXPECT_EQ(released.references_left, 2u);

  const std::vector<double> in = {1.5, -2.25, 1e-300};
  std::vector<double> out(3);
  s = client.evaluate("fn-double", in, out);
  ASSERT_TRUE(s.ok()) << s.message;
  EXPECT_EQ(out, (std::vector<double>{3.0, -4.5, 2e-300}));

  const auto batch_in = ramp(40 * 3);
  std::vector<double> batch_out(40 * 3);
  s = client.evaluateBatch("fn-double", 40, batch_in, batch_out);
  ASSERT_TRUE(s.ok()) << s.message;
  for (std::size_t i = 0; i < batch_in.size(); ++i) ASSERT_EQ(batch_out[i], 2 * batch_in[i]) << i;

  // Every reply was accounted, as "dds", with its method and status. Not in call order:
  // a request thread records a call after sending its reply, so the next call (on the
  // other request thread) can be recorded first. The Health probe(s) a connection sends
  // before its first call come on top of the Health call.
  auto countOf = [](const std::vector<FakeService::Record>& records, bool health) {
    return std::count_if(records.begin(), records.end(),
                         [&](const auto& r) { return (r.method == rpc::Method::Health) == health; });
  };
  ASSERT_TRUE(testing::eventually(
      [&] {
        const auto records = service.records();
        return countOf(records, false) >= 6 && countOf(records, true) >= 2;
      },
      2s));
  std::vector<rpc::Method> methods;
  for (const auto& r : service.records()) {
    EXPECT_EQ(r.transport, "dds");
    EXPECT_EQ(r.code, StatusCode::Ok);
    if (r.method != rpc::Method::Health) methods.push_back(r.method);
  }
  std::sort(methods.begin(), methods.end());
  std::vector<rpc::Method> expected = {rpc::Method::LoadModel, rpc::Method::GetFunction, rpc::Method::ListFunctions,
                                       rpc::Method::Release,   rpc::Method::Evaluate,    rpc::Method::EvaluateBatch};
  std::sort(expected.begin(), expected.end());
  EXPECT_EQ(methods, expected);
}

// The fleet methods: FleetStatus and QueryArtifact answered by ServiceApi's defaults, an
// artifact's bytes (zeros and 0xff among them) fetched chunk by chunk and put back together.
TEST_F(DdsTransport, FleetMethodsRoundTrip) {
  FakeService service("srv-fleet");
  auto server = startServer(service, serverOptions());
  DdsConnection connection(clientOptions());

  const rpc::FleetStatusRequest status_request;
  rpc::FleetStatusReply status;
  Status s = connection.call(client::UnaryCall{client::FleetStatusCall{&status_request, &status}}, {});
  ASSERT_TRUE(s.ok()) << s.message;
  EXPECT_EQ(status.fleet.role, "standalone");
  EXPECT_TRUE(status.fleet.peers.empty());

  const rpc::QueryArtifactRequest query{"pk", "<robot/>", false, "{}", true, false};
  rpc::QueryArtifactReply queried;
  s = connection.call(client::UnaryCall{client::QueryArtifactCall{&query, &queried}}, {});
  EXPECT_EQ(s.code, StatusCode::FailedPrecondition);
  EXPECT_NE(s.message.find("not a build host"), std::string::npos) << s.message;

  std::vector<std::uint8_t> fetched;
  for (int chunks = 0; chunks < 10; ++chunks) {
    const rpc::FetchArtifactChunkRequest fetch{"key-1", false, fetched.size(), 128};
    rpc::FetchArtifactChunkReply chunk;
    s = connection.call(client::UnaryCall{client::FetchArtifactChunkCall{&fetch, &chunk}}, {});
    ASSERT_TRUE(s.ok()) << s.message;
    EXPECT_EQ(chunk.offset, fetched.size());
    EXPECT_EQ(chunk.payload_bytes, 300u);
    if (chunk.data.empty()) break;
    fetched.insert(fetched.end(), chunk.data.begin(), chunk.data.end());
  }
  EXPECT_EQ(fetched, testing::fakeArtifactPayload());
  const rpc::FetchArtifactChunkRequest unknown{"key-2", false, 0, 0};
  rpc::FetchArtifactChunkReply none;
  EXPECT_EQ(connection.call(client::UnaryCall{client::FetchArtifactChunkCall{&unknown, &none}}, {}).code,
            StatusCode::NotFound);
}

TEST_F(DdsTransport, BatchSplitIntoChunksIsReassembled) {
  FakeService service("srv-chunks");
  DdsServerOptions options = serverOptions();
  options.max_sample_bytes = 7 * FakeService::kOutputs * sizeof(double);  // 7 knots per chunk
  auto server = startServer(service, options);
  DdsConnection client(clientOptions());
  for (std::uint64_t knots : {1u, 7u, 8u, 100u, 0u}) {
    const auto in = ramp(knots * 3, 0.5);
    std::vector<double> out(knots * 3, std::nan(""));
    const Status s = client.evaluateBatch("fn-double", knots, in, out);
    ASSERT_TRUE(s.ok()) << knots << " knots: " << s.message;
    for (std::size_t i = 0; i < in.size(); ++i) ASSERT_EQ(out[i], 2 * in[i]) << knots << " knots, index " << i;
  }
}

TEST_F(DdsTransport, ServiceErrorsAndBadSizesComeBackAsStatuses) {
  FakeService service("srv-errors");
  auto server = startServer(service, serverOptions());
  DdsConnection client(clientOptions());
  std::vector<double> out(3);
  Status s = client.evaluate("fn-missing", std::vector<double>{1, 2, 3}, out);
  EXPECT_EQ(s.code, StatusCode::NotFound);
  EXPECT_NE(s.message.find("fn-missing"), std::string::npos) << s.message;
  s = client.evaluate("fn-double", std::vector<double>{1, 2}, out);
  EXPECT_EQ(s.code, StatusCode::InvalidArgument) << s.message;
  // knot_count that does not match the inputs: the transport refuses it before the service.
  std::vector<double> batch_out(5 * 3);
  s = client.evaluateBatch("fn-double", 5, std::vector<double>(14, 1.0), batch_out);
  EXPECT_EQ(s.code, StatusCode::InvalidArgument);
  EXPECT_NE(s.message.find("knot_count 5"), std::string::npos) << s.message;
  // A reply that does not fit the caller's span is the client's INTERNAL.
  std::vector<double> too_small(2);
  s = client.evaluate("fn-double", std::vector<double>{1, 2, 3}, too_small);
  EXPECT_EQ(s.code, StatusCode::Internal) << s.message;
  rpc::ReleaseReply released;
  s = client.release({"nothing"}, released);
  EXPECT_EQ(s.code, StatusCode::NotFound);
  rpc::GetFunctionReply function;
  EXPECT_EQ(client.getFunction({"", "", false}, function).code, StatusCode::InvalidArgument);
  // And the server still answers.
  EXPECT_TRUE(client.evaluate("fn-double", std::vector<double>{1, 2, 3}, out).ok());
}

TEST_F(DdsTransport, IncompatibleSchemaVersionIsRefused) {
  FakeService service("srv-version");
  auto server = startServer(service, serverOptions());
  DdsConnectionOptions options = clientOptions();
  options.connection.schema_version = {static_cast<std::uint16_t>(kSchemaVersionMajor + 1), 0};
  DdsConnection client(options);
  rpc::HealthReply health;
  const Status s = client.health({}, health);
  EXPECT_EQ(s.code, StatusCode::FailedPrecondition);
  EXPECT_NE(s.message.find(std::to_string(kSchemaVersionMajor + 1)), std::string::npos) << s.message;
  std::vector<double> batch_out(3);
  EXPECT_EQ(client.evaluateBatch("fn-double", 1, std::vector<double>{1, 2, 3}, batch_out).code,
            StatusCode::FailedPrecondition);
  // The probe, the Health and the EvaluateBatch: all refused the same way.
  ASSERT_TRUE(testing::eventually([&] { return service.records().size() >= 3; }, 2s));
  for (const auto& r : service.records()) EXPECT_EQ(r.code, StatusCode::FailedPrecondition);
}

TEST_F(DdsTransport, RequestForAnotherInstanceIsLeftToIt) {
  FakeService a("srv-one"), b("srv-two");
  auto server_a = startServer(a, serverOptions());
  auto server_b = startServer(b, serverOptions());
  DdsConnectionOptions options = clientOptions();
  options.connection.server_instance_id = "srv-two";
  DdsConnection to_b(options);
  for (int i = 0; i < 3; ++i) {
    rpc::HealthReply health;
    const Status s = to_b.health({}, health);
    ASSERT_TRUE(s.ok()) << s.message;
    EXPECT_EQ(health.server_instance_id, "srv-two");
  }
  rpc::LoadModelReply model;
  ASSERT_TRUE(to_b.loadModel({"<robot/>", false, ""}, model).ok());
  options.connection.server_instance_id = "srv-one";
  DdsConnection to_a(options);
  rpc::HealthReply health;
  ASSERT_TRUE(to_a.health({}, health).ok());
  EXPECT_EQ(health.server_instance_id, "srv-one");
  // srv-two answered its 3 Health and the LoadModel (besides its client's probe);
  // srv-one never saw them: only its own client's probe and Health.
  auto count = [](const FakeService& service, rpc::Method method) {
    std::size_t n = 0;
    for (const auto& r : service.records()) n += r.method == method;
    return n;
  };
  ASSERT_TRUE(testing::eventually([&] { return count(b, rpc::Method::LoadModel) == 1; }, 2s));
  EXPECT_GE(count(b, rpc::Method::Health), 4u);
  EXPECT_EQ(count(a, rpc::Method::LoadModel), 0u);
  EXPECT_LT(count(a, rpc::Method::Health), 4u);
  EXPECT_TRUE(a.loadModelClients().empty());
}

TEST_F(DdsTransport, SlowCallEndsDeadlineExceededAndTheLateReplyIsDropped) {
  FakeService service("srv-slow");
  auto server = startServer(service, serverOptions());
  DdsConnection client(clientOptions());
  rpc::HealthReply health;
  ASSERT_TRUE(client.health({}, health).ok());  // matched
  rpc::LoadModelReply model;
  const auto start = Clock::now();
  const Status s = client.loadModel({"sleep:800", false, ""}, model, CallOptions{300ms});
  const auto took = Clock::now() - start;
  EXPECT_EQ(s.code, StatusCode::DeadlineExceeded) << s.message;
  EXPECT_NE(s.message.find("LoadModel"), std::string::npos) << s.message;
  EXPECT_GE(took, 290ms);
  EXPECT_LT(took, 1500ms);
  EXPECT_TRUE(model.model_id.empty());
  // The reply comes while the next call waits; it must not be taken for that one.
  std::vector<double> out(3);
  for (int i = 0; i < 40; ++i) {
    ASSERT_TRUE(client.evaluate("fn-double", std::vector<double>{1, 2, double(i)}, out).ok());
    EXPECT_EQ(out[2], 2.0 * i);
    std::this_thread::sleep_for(20ms);
  }
  EXPECT_TRUE(model.model_id.empty());
}

TEST_F(DdsTransport, FullRequestQueueIsResourceExhausted) {
  FakeService service("srv-busy", /*threads=*/1, /*queue_capacity=*/1);
  auto server = startServer(service, serverOptions());
  DdsConnection client(clientOptions());
  rpc::HealthReply health;
  ASSERT_TRUE(client.health({}, health).ok());
  // One runs, one waits, the rest find the queue full.
  std::vector<std::future<Status>> calls;
  for (int i = 0; i < 4; ++i) {
    calls.push_back(std::async(std::launch::async, [&] {
      rpc::LoadModelReply model;
      return client.loadModel({"sleep:400", false, ""}, model);
    }));
    std::this_thread::sleep_for(50ms);
  }
  int ok = 0, exhausted = 0;
  for (auto& c : calls) {
    const Status s = c.get();
    if (s.ok()) ++ok;
    if (s.code == StatusCode::ResourceExhausted) {
      ++exhausted;
      EXPECT_NE(s.message.find("request queue full"), std::string::npos) << s.message;
    }
  }
  EXPECT_EQ(ok + exhausted, 4);
  EXPECT_GE(exhausted, 1);
  EXPECT_GE(ok, 1);
  // Evaluate is not queued: it is answered at once while the queue is full.
}

TEST_F(DdsTransport, NoServerIsUnavailableQuickly) {
  DdsConnectionOptions options = clientOptions();
  options.match_timeout = 300ms;
  DdsConnection client(options);
  rpc::HealthReply health;
  const auto start = Clock::now();
  const Status s = client.health({}, health);
  EXPECT_EQ(s.code, StatusCode::Unavailable);
  EXPECT_LT(Clock::now() - start, 1500ms);
  EXPECT_NE(s.message.find("DDS domain " + std::to_string(domain_)), std::string::npos) << s.message;
  EXPECT_NE(s.message.find("robodiff_request"), std::string::npos) << s.message;
  EXPECT_NE(s.message.find("is it running?"), std::string::npos) << s.message;
}

TEST_F(DdsTransport, ServerStoppedMidCallIsUnavailableThenANewServerWorks) {
  FakeService service("srv-dies");
  auto server = startServer(service, serverOptions());
  DdsConnection client(clientOptions());
  rpc::HealthReply health;
  ASSERT_TRUE(client.health({}, health).ok());
  auto slow = std::async(std::launch::async, [&] {
    rpc::LoadModelReply model;
    return client.loadModel({"sleep:1500", false, ""}, model);
  });
  ASSERT_TRUE(service.waitLoadModelFrom(client.clientId(), 5s));
  const auto stopped = Clock::now();
  server->stop();
  const Status s = slow.get();
  EXPECT_EQ(s.code, StatusCode::Unavailable) << s.message;
  EXPECT_NE(s.message.find("went away"), std::string::npos) << s.message;
  EXPECT_LT(Clock::now() - stopped, 1500ms);
  EXPECT_FALSE(client.connected());

  FakeService again("srv-again");
  auto server2 = startServer(again, serverOptions());
  ASSERT_TRUE(client.health({}, health).ok());
  EXPECT_EQ(health.server_instance_id, "srv-again");
  std::vector<double> out(3);
  ASSERT_TRUE(client.evaluate("fn-double", std::vector<double>{1, 2, 3}, out).ok());
  EXPECT_EQ(out[2], 6.0);
}

TEST_F(DdsTransport, DrainingAnswersNewRequestsUnavailableAndFinishesInFlight) {
  FakeService service("srv-drain");
  auto server = startServer(service, serverOptions());
  DdsConnection client(clientOptions());
  rpc::HealthReply health;
  ASSERT_TRUE(client.health({}, health).ok());
  auto slow = std::async(std::launch::async, [&] {
    rpc::LoadModelReply model;
    return client.loadModel({"sleep:500", false, ""}, model);
  });
  ASSERT_TRUE(service.waitLoadModelFrom(client.clientId(), 5s));
  // The Health before it was answered, but its task may still be ending (a loaded machine).
  EXPECT_TRUE(testing::eventually([&] { return server->inFlight() == 1u; }, 2000ms)) << server->inFlight();
  server->stopAccepting();
  const Status refused = client.health({}, health);
  EXPECT_EQ(refused.code, StatusCode::Unavailable);
  EXPECT_NE(refused.message.find("draining"), std::string::npos) << refused.message;
  EXPECT_TRUE(server->waitIdle(5s));
  EXPECT_TRUE(slow.get().ok());
  EXPECT_EQ(server->inFlight(), 0u);
}

TEST_F(DdsTransport, ManyThreadsShareOneConnection) {
  FakeService service("srv-many", /*threads=*/2, /*queue_capacity=*/256);
  auto server = startServer(service, serverOptions());
  DdsConnection client(clientOptions());
  constexpr int kThreads = 8, kCalls = 150;
  std::atomic<int> failures{0};
  std::vector<std::thread> threads;
  for (int t = 0; t < kThreads; ++t) {
    threads.emplace_back([&, t] {
      std::vector<double> out(3), batch_out(4 * 3);
      for (int i = 0; i < kCalls; ++i) {
        const double x = t * 1000.0 + i;
        const std::vector<double> in = {x, -x, 0.5};
        if (i % 10 == 9) {
          const auto batch_in = ramp(4 * 3, x);
          const Status s = client.evaluateBatch("fn-double", 4, batch_in, batch_out);
          if (!s.ok()) {
            ++failures;
            ADD_FAILURE() << s.message;
            continue;
          }
          for (std::size_t k = 0; k < batch_in.size(); ++k)
            if (batch_out[k] != 2 * batch_in[k]) ++failures;
        } else {
          const Status s = client.evaluate("fn-double", in, out);
          if (!s.ok() || out[0] != 2 * x || out[1] != -2 * x || out[2] != 1.0) {
            ++failures;
            ADD_FAILURE() << "thread " << t << " call " << i << ": " << s.message;
          }
        }
      }
    });
  }
  for (auto& th : threads) th.join();
  EXPECT_EQ(failures.load(), 0);
}

}  // namespace
}  // namespace robodiff
