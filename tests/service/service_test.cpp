// The Service around its requests: admitting headers (schema version, instance id,
// draining), the bounded request queue, waiting for idleness, references and release,
// and what Health reports after requests are recorded.
#include <future>
#include <regex>

#include "service_fixtures.hpp"

namespace robodiff::server::testing {
namespace {

TEST(Service, InstanceIdAndAdmission) {
  ServiceWorkspace ws;
  auto service = ws.start(ws.options());
  const std::string id = service->instanceId();
  EXPECT_TRUE(std::regex_match(id, std::regex(".+:[0-9]+:[0-9a-f]{8}"))) << id;
  auto other = ws.start(ws.options());
  EXPECT_NE(other->instanceId(), id);
  ServiceOptions named = ws.options();
  named.instance_id = "robodiffd-test-1";
  EXPECT_EQ(ws.start(named)->instanceId(), "robodiffd-test-1");

  rpc::RequestHeader header;
  EXPECT_TRUE(service->admit(header).ok());
  header.server_instance_id = id;
  EXPECT_TRUE(service->admit(header).ok());
  header.server_instance_id = "elsewhere:1:00000000";
  Status status = service->admit(header);
  EXPECT_EQ(status.code, StatusCode::NotFound);
  EXPECT_EQ(status.message, "request addressed to server elsewhere:1:00000000, this is " + id);
  header.server_instance_id.clear();
  header.schema_version.major = kSchemaVersionMajor + 1;
  status = service->admit(header);
  EXPECT_EQ(status.code, StatusCode::FailedPrecondition);
  EXPECT_EQ(status.message, checkSchemaVersion(kSchemaVersionMajor + 1, kSchemaVersionMinor).message);
  header.schema_version.major = kSchemaVersionMajor;

  EXPECT_EQ(service->state(), rpc::ServingState::Starting);
  service->markServing();
  EXPECT_EQ(service->state(), rpc::ServingState::Serving);
  EXPECT_EQ(health(*service).state, rpc::ServingState::Serving);
  service->beginDrain();
  EXPECT_EQ(service->state(), rpc::ServingState::Draining);
  status = service->admit(header);
  EXPECT_EQ(status.code, StatusCode::Unavailable);
  EXPECT_EQ(status.message, "robodiffd is shutting down (SIGTERM); retry against another server or after restart");
  service->markServing();  // draining is for good
  EXPECT_EQ(service->state(), rpc::ServingState::Draining);
}

TEST(Service, PostRefusesWhenTheQueueIsFull) {
  ServiceWorkspace ws;
  ServiceOptions options = ws.options();
  options.request_threads = 1;
  options.request_queue_capacity = 2;
  auto service = ws.start(options);
  std::promise<void> started, release;
  std::shared_future<void> released = release.get_future().share();
  std::atomic<int> ran{0};
  ASSERT_TRUE(service->post([&] {
    started.set_value();
    released.wait();
    ++ran;
  }));
  started.get_future().wait();  // the one request thread is busy from here on
  EXPECT_TRUE(service->post([&] { ++ran; }));
  EXPECT_TRUE(service->post([&] { ++ran; }));
  EXPECT_FALSE(service->post([&] { ran += 100; }));  // two wait already: refused, never run
  const rpc::HealthReply h = health(*service);
  EXPECT_EQ(h.queue_depth, 2u);
  EXPECT_EQ(h.queue_capacity, 2u);
  EXPECT_FALSE(service->waitIdle(std::chrono::milliseconds(20)));
  release.set_value();
  EXPECT_TRUE(service->waitIdle(std::chrono::seconds(10)));
  EXPECT_EQ(ran.load(), 3);
  EXPECT_EQ(health(*service).queue_depth, 0u);
}

TEST(Service, PostedRequestsRunAndTheDestructorWaitsForThem) {
  ServiceWorkspace ws;
  auto service = ws.start(ws.options());
  const rpc::LoadModelReply model = loadModel(*service, arm7Urdf());
  std::promise<Status> done;
  rpc::GetFunctionReply reply;
  Service* raw = service.get();  // service.reset() empties the unique_ptr before the destructor runs
  ASSERT_TRUE(service->post([&, raw] {
    rpc::GetFunctionRequest request{model.model_id, kRneaValueSpec, true};
    done.set_value(raw->getFunction(context(), request, reply));
  }));
  service.reset();  // drains: the posted GetFunction finishes first
  auto result = done.get_future();
  ASSERT_EQ(result.wait_for(std::chrono::seconds(0)), std::future_status::ready);
  EXPECT_TRUE(result.get().ok());
  EXPECT_EQ(reply.state, rpc::FunctionState::Ready);
}

TEST(Service, ReferencesAndRelease) {
  ServiceWorkspace ws;
  auto service = ws.start(ws.options());
  const std::string model_id = loadModel(*service, arm7Urdf()).model_id;
  const rpc::GetFunctionReply f = readyFunction(*service, model_id, kRneaValueSpec);
  EXPECT_EQ(readyFunction(*service, model_id, kRneaValueSpec).function_id, f.function_id);
  // The same function written differently is the same function.
  const std::string respelled =
      R"({"outputs": [{"kind": "value"}], "function": "rnea", "build": {"march_native": false, "optimization": "O0"}})";
  EXPECT_EQ(readyFunction(*service, model_id, respelled).function_id, f.function_id);

  rpc::ReleaseReply r;
  ASSERT_TRUE(service->release(context(), {model_id}, r).ok());
  EXPECT_EQ(r.references_left, 0u);
  // The function keeps its model loaded: listed, and more functions can be asked of it.
  rpc::ListFunctionsReply list;
  ASSERT_TRUE(service->listFunctions(context(), {model_id, 0, ""}, list).ok());
  ASSERT_EQ(list.functions.size(), 1u);
  EXPECT_EQ(list.functions[0].function_name, "rnea");
  EXPECT_EQ(list.functions[0].model_id, model_id);
  EXPECT_EQ(service->release(context(), {model_id}, r).code, StatusCode::NotFound);  // no references left

  std::vector<double> in(21, 0.1), out(7);
  for (std::uint32_t left : {2u, 1u}) {
    ASSERT_TRUE(service->release(context(), {f.function_id}, r).ok());
    EXPECT_EQ(r.references_left, left);
    EXPECT_TRUE(service->evaluate(context(), f.function_id, in, out).ok());  // still loaded
  }
  ASSERT_TRUE(service->release(context(), {f.function_id}, r).ok());
  EXPECT_EQ(r.references_left, 0u);
  EXPECT_EQ(service->evaluate(context(), f.function_id, in, out).code, StatusCode::NotFound);
  EXPECT_EQ(service->release(context(), {f.function_id}, r).code, StatusCode::NotFound);
  // Its last function gone, the unreferenced model goes too.
  const rpc::HealthReply h = health(*service);
  EXPECT_EQ(h.functions_loaded, 0u);
  EXPECT_EQ(h.models_loaded, 0u);
  rpc::GetFunctionReply reply;
  EXPECT_EQ(getFunction(*service, model_id, kRneaValueSpec, false, reply).code, StatusCode::NotFound);
  const std::string log = ws.logText();
  EXPECT_NE(log.find("\"event\":\"function_unloaded\""), std::string::npos) << log;
  EXPECT_NE(log.find("\"event\":\"model_unloaded\""), std::string::npos) << log;
}

TEST(Service, ListFunctionsFiltersByModel) {
  ServiceWorkspace ws;
  auto service = ws.start(ws.options());
  const std::string a = loadModel(*service, arm7Urdf()).model_id;
  const std::string b =
      loadModel(*service, replaced(arm7Urdf(), R"(<mass value="2.3056640625"/>)", R"(<mass value="2.5"/>)")).model_id;
  const std::string fa = readyFunction(*service, a, kRneaValueSpec).function_id;
  const std::string fb = readyFunction(*service, b, kRneaValueSpec).function_id;
  const std::string fa2 = readyFunction(*service, a, kRneaJacobianSpec).function_id;
  rpc::ListFunctionsReply all, of_a;
  ASSERT_TRUE(service->listFunctions(context(), {}, all).ok());
  ASSERT_EQ(all.functions.size(), 3u);
  EXPECT_EQ(all.functions[0].function_id, fa);  // in the order they were asked for
  EXPECT_EQ(all.functions[1].function_id, fb);
  EXPECT_EQ(all.functions[2].function_id, fa2);
  ASSERT_TRUE(service->listFunctions(context(), {a, 0, ""}, of_a).ok());
  ASSERT_EQ(of_a.functions.size(), 2u);
  for (const rpc::FunctionSummary& f : of_a.functions) {
    EXPECT_EQ(f.model_id, a);
    EXPECT_EQ(f.state, rpc::FunctionState::Ready);
    EXPECT_FALSE(f.compiled);
    EXPECT_TRUE(f.message.empty()) << f.message;
  }
}

TEST(Service, HealthCountsRequestsErrorsAndLatencies) {
  ServiceWorkspace ws;
  ServiceOptions options = ws.options();
  options.version = "9.8.7";
  auto service = ws.start(options);
  const std::string model_id = loadModel(*service, arm7Urdf()).model_id;
  readyFunction(*service, model_id, kRneaValueSpec);

  for (int i = 1; i <= 100; ++i)
    service->recordRequest("iceoryx", rpc::Method::Evaluate, StatusCode::Ok, std::chrono::nanoseconds(1000 * i));
  service->recordRequest("iceoryx", rpc::Method::Evaluate, StatusCode::InvalidArgument, std::chrono::microseconds(3));
  service->recordRequest("dds", rpc::Method::LoadModel, StatusCode::Ok, std::chrono::milliseconds(2));
  service->recordRequest("dds", rpc::Method::GetFunction, StatusCode::NotFound, std::chrono::microseconds(50));
  service->recordRequest("dds", rpc::Method::GetFunction, StatusCode::NotFound, std::chrono::microseconds(60));

  const rpc::HealthReply h = health(*service);
  EXPECT_EQ(h.version, "9.8.7");
  EXPECT_EQ(h.server_instance_id, service->instanceId());
  EXPECT_EQ(h.state, rpc::ServingState::Starting);
  EXPECT_GT(h.uptime_ns, 0u);
  EXPECT_EQ(h.models_loaded, 1u);
  EXPECT_EQ(h.functions_loaded, 1u);
  EXPECT_EQ(h.workers_total, 1u);
  EXPECT_EQ(h.workers_busy, 0u);
  EXPECT_EQ(h.batch_threads, 2u);
  EXPECT_EQ(h.queue_capacity, 256u);
  EXPECT_EQ(h.cache_hits + h.cache_misses, 0u);  // compile off: the cache is not consulted

  ASSERT_EQ(h.methods.size(), rpc::kMethodCount);
  for (std::uint32_t m = 0; m < rpc::kMethodCount; ++m) EXPECT_EQ(h.methods[m].method, static_cast<rpc::Method>(m));
  const rpc::MethodStats& ev = h.methods[static_cast<std::size_t>(rpc::Method::Evaluate)];
  EXPECT_EQ(ev.requests, 101u);
  EXPECT_EQ(ev.errors, 1u);
  EXPECT_EQ(ev.max_ns, 100000u);
  // Log-scale buckets: within 10% of the exact percentiles.
  EXPECT_NEAR(static_cast<double>(ev.p50_ns), 50000.0, 5000.0);
  EXPECT_NEAR(static_cast<double>(ev.p90_ns), 90000.0, 9000.0);
  EXPECT_NEAR(static_cast<double>(ev.p99_ns), 99000.0, 9900.0);
  EXPECT_LE(ev.p50_ns, ev.p90_ns);
  EXPECT_LE(ev.p99_ns, ev.max_ns);
  const rpc::MethodStats& get = h.methods[static_cast<std::size_t>(rpc::Method::GetFunction)];
  EXPECT_EQ(get.requests, 2u);
  EXPECT_EQ(get.errors, 2u);
  EXPECT_EQ(h.methods[static_cast<std::size_t>(rpc::Method::LoadModel)].max_ns, 2000000u);
  EXPECT_EQ(h.methods[static_cast<std::size_t>(rpc::Method::Health)].requests, 0u);

  ASSERT_EQ(h.errors.size(), 2u);
  EXPECT_EQ(h.errors[0].code, StatusCode::InvalidArgument);
  EXPECT_EQ(h.errors[0].count, 1u);
  EXPECT_EQ(h.errors[1].code, StatusCode::NotFound);
  EXPECT_EQ(h.errors[1].count, 2u);

  ASSERT_EQ(h.transports.size(), 2u);
  EXPECT_EQ(h.transports[0].transport, "iceoryx");
  EXPECT_EQ(h.transports[0].requests, 101u);
  EXPECT_EQ(h.transports[0].errors, 1u);
  EXPECT_EQ(h.transports[1].transport, "dds");
  EXPECT_EQ(h.transports[1].requests, 3u);
  EXPECT_EQ(h.transports[1].errors, 2u);
}

TEST(Service, ConcurrentEvaluationsAndReleaseDoNotInterfere) {
  ServiceWorkspace ws;
  auto service = ws.start(ws.options());
  const std::string model_id = loadModel(*service, arm7Urdf()).model_id;
  const rpc::GetFunctionReply f = readyFunction(*service, model_id, kRneaJacobianSpec);
  const std::vector<double> x = someInputs(21, 9);
  const std::vector<double> expected = evaluateOnce(*service, f, x);
  std::atomic<bool> wrong{false};
  std::vector<std::thread> threads;
  for (int t = 0; t < 4; ++t)
    threads.emplace_back([&] {
      std::vector<double> out(expected.size());
      for (int i = 0; i < 300; ++i) {
        const Status s = service->evaluate(context(), f.function_id, x, out);
        if (s.code == StatusCode::NotFound) return;  // released meanwhile
        if (!s.ok() || out != expected) wrong = true;
      }
    });
  rpc::ReleaseReply r;
  std::this_thread::sleep_for(std::chrono::milliseconds(5));
  EXPECT_TRUE(service->release(context(), {f.function_id}, r).ok());
  for (std::thread& t : threads) t.join();
  EXPECT_FALSE(wrong.load());
}

}  // namespace
}  // namespace robodiff::server::testing
