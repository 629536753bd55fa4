// Service::overview(), what the dashboard shows, against a real Service with real worker
// processes: a function's phase follows its build (queued or compiling while the compiler
// waits, then compiled, then a cache hit for the next server), its calls and batches are
// counted and timed, failed builds are listed with the compiler's message (and stay
// listed after the function is released), a spec failure is listed as invalid-spec (its
// function unloaded at once), the jobs are
// the index's newest, and the method histograms hold every request.
#include <fstream>

#include "robodiff/cache/job_index.hpp"

#include "service_fixtures.hpp"

namespace robodiff::server::testing {
namespace {

const ServiceOverview::Function* functionIn(const ServiceOverview& o, const std::string& id) {
  for (const auto& f : o.functions)
    if (f.id == id) return &f;
  return nullptr;
}

std::string phaseOf(const Service& service, const std::string& id) {
  const ServiceOverview o = service.overview();
  const auto* f = functionIn(o, id);
  return f ? f->phase : "(not listed)";
}

TEST(Overview, AFunctionsPhaseFollowsItsBuildAndItsCallsAreTimed) {
  ServiceWorkspace ws;
  const std::filesystem::path gate = ws.tmp / "compile-now";
  ServiceOptions options = ws.options(true);
  options.compiler = gatedCompiler(ws.tmp, gate).string();
  auto service = ws.start(options);
  const rpc::LoadModelReply model = loadModel(*service, arm7Urdf());

  ServiceOverview o = service->overview();
  ASSERT_EQ(o.models.size(), 1u);
  EXPECT_EQ(o.models[0].id, model.model_id);
  EXPECT_EQ(o.models[0].name, "arm7");  // the URDF's robot name
  EXPECT_EQ(o.models[0].nv, 7u);
  EXPECT_EQ(o.models[0].references, 1u);
  EXPECT_EQ(o.models[0].functions, 0u);
  EXPECT_TRUE(o.functions.empty());

  // Traced: the interpreter serves while the compiler waits at the gate.
  const rpc::GetFunctionReply f = readyFunction(*service, model.model_id, kRneaJacobianSpec);
  EXPECT_TRUE(waitFor([&] { return phaseOf(*service, f.function_id) == "compiling"; }))
      << phaseOf(*service, f.function_id);
  o = service->overview();
  const auto* entry = functionIn(o, f.function_id);
  ASSERT_NE(entry, nullptr);
  EXPECT_EQ(entry->function, "rnea");
  EXPECT_EQ(entry->outputs, "value, jacobian[q,v,a]");
  EXPECT_EQ(entry->model_name, "arm7");
  EXPECT_GT(entry->trace_seconds, 0);
  EXPECT_LT(entry->compile_seconds, 0);  // not compiled yet
  EXPECT_EQ(o.models[0].functions, 1u);
  EXPECT_EQ(o.metrics.builds_running, 1u);

  // The library arrives.
  std::ofstream(gate.string()) << "go\n";
  ASSERT_TRUE(waitFor([&] { return phaseOf(*service, f.function_id) == "compiled"; }))
      << phaseOf(*service, f.function_id);
  o = service->overview();
  entry = functionIn(o, f.function_id);
  ASSERT_NE(entry, nullptr);
  EXPECT_GT(entry->compile_seconds, 0);
  EXPECT_FALSE(entry->from_cache);
  EXPECT_TRUE(entry->message.empty()) << entry->message;
  EXPECT_EQ(entry->calls, 0u);
  EXPECT_EQ(entry->p50_ns, 0u);

  // Calls and a batch, timed per function.
  const std::size_t in = rpc::inputCount(f), out = rpc::outputCount(f);
  for (int i = 0; i < 50; ++i) evaluateOnce(*service, f, someInputs(in, static_cast<std::uint64_t>(i)));
  std::vector<double> batch_out(100 * out);
  ASSERT_TRUE(service->evaluateBatch(context(), f.function_id, 100, someInputs(100 * in, 7), batch_out).ok());
  o = service->overview();
  entry = functionIn(o, f.function_id);
  ASSERT_NE(entry, nullptr);
  EXPECT_EQ(entry->calls, 50u);
  EXPECT_EQ(entry->evaluations, 150u);
  EXPECT_GT(entry->p50_ns, 0u);
  EXPECT_LE(entry->p50_ns, entry->p99_ns);
  EXPECT_LE(entry->p99_ns, entry->max_ns);
  EXPECT_EQ(entry->batch_calls, 1u);
  EXPECT_EQ(entry->batch_knots, 100u);
  EXPECT_GT(entry->batch_ns, 0u);
  EXPECT_EQ(o.metrics.functions_compiled, 1u);
  service.reset();

  // The next server on the same cache: compiled from the start, from the cache.
  auto second = ws.start(options);
  const rpc::LoadModelReply model2 = loadModel(*second, arm7Urdf());
  const rpc::GetFunctionReply hit = readyFunction(*second, model2.model_id, kRneaJacobianSpec);
  o = second->overview();
  entry = functionIn(o, hit.function_id);
  ASSERT_NE(entry, nullptr);
  EXPECT_EQ(entry->phase, "compiled");
  EXPECT_TRUE(entry->from_cache);
  EXPECT_GE(entry->compile_seconds, 0);
  EXPECT_EQ(o.metrics.cache_hits, 1u);
}

TEST(Overview, FailedBuildsAreListedWithTheirMessagesAfterTheFunctionIsGone) {
  ServiceWorkspace ws;
  ServiceOptions options = ws.options(true);
  options.compiler = failingCompiler(ws.tmp).string();
  auto service = ws.start(options);
  const rpc::LoadModelReply model = loadModel(*service, arm7Urdf());
  const rpc::GetFunctionReply f = readyFunction(*service, model.model_id, kRneaValueSpec);
  ASSERT_TRUE(waitFor([&] { return phaseOf(*service, f.function_id) == "build-failed"; }))
      << phaseOf(*service, f.function_id);

  // A spec the model cannot serve fails the function itself.
  rpc::GetFunctionReply bad;
  EXPECT_FALSE(getFunction(*service, model.model_id,
                           R"({"function": "fk", "frame": "no_such_frame", "outputs": [{"kind": "value"}]})", true,
                           bad)
                   .ok());
  ServiceOverview o = service->overview();
  EXPECT_EQ(functionIn(o, bad.function_id), nullptr);  // unloaded at once; its failure is listed
  ASSERT_EQ(o.build_failures.size(), 2u);
  const auto& spec_failure = o.build_failures[0];  // newest first
  EXPECT_EQ(spec_failure.function_id, bad.function_id);
  EXPECT_EQ(spec_failure.function, "fk");
  EXPECT_EQ(spec_failure.stage, "invalid-spec");
  EXPECT_FALSE(spec_failure.interpreter_serves);
  EXPECT_NE(spec_failure.message.find("no_such_frame"), std::string::npos) << spec_failure.message;
  const auto& compile_failure = o.build_failures[1];
  EXPECT_EQ(compile_failure.function_id, f.function_id);
  EXPECT_EQ(compile_failure.model, "arm7");
  EXPECT_EQ(compile_failure.function, "rnea");
  EXPECT_TRUE(compile_failure.interpreter_serves);
  EXPECT_EQ(compile_failure.stage, "compile");
  EXPECT_NE(compile_failure.message.find("simulated failure"), std::string::npos) << compile_failure.message;
  EXPECT_GT(compile_failure.unix_seconds, 1.7e9);
  const auto* entry = functionIn(o, f.function_id);
  ASSERT_NE(entry, nullptr);
  EXPECT_NE(entry->message.find("simulated failure"), std::string::npos) << entry->message;

  // Released: the function leaves the table, its failure stays listed.
  rpc::ReleaseRequest release;
  release.id = f.function_id;
  rpc::ReleaseReply released;
  ASSERT_TRUE(service->release(context(), release, released).ok());
  o = service->overview();
  EXPECT_EQ(functionIn(o, f.function_id), nullptr);
  ASSERT_EQ(o.build_failures.size(), 2u);
  EXPECT_EQ(o.build_failures[1].function_id, f.function_id);
}

TEST(Overview, JobsAreTheNewestFromTheIndex) {
  ServiceWorkspace ws;
  auto service = ws.start(ws.options());
  {
    cache::JobIndex index(ws.tmp / "cache");  // the service's own index.sqlite, as another process would see it
    for (int k = 1; k <= 4; ++k) {
      cache::JobRecord r;
      r.id = "job-" + std::to_string(k);
      r.kind = "trajectory";
      r.state = k == 4 ? "QUEUED" : "SUCCEEDED";
      r.params_json = "{}";
      r.owner = "elsewhere";
      r.submitted_ms = 1000 * k;
      index.insert(r);
    }
  }
  const ServiceOverview o = service->overview(3);
  EXPECT_TRUE(o.jobs_error.empty()) << o.jobs_error;
  ASSERT_EQ(o.jobs.size(), 3u);
  EXPECT_EQ(o.jobs[0].job_id, "job-4");
  EXPECT_EQ(o.jobs[0].state, rpc::JobState::Queued);
  EXPECT_EQ(o.jobs[2].job_id, "job-2");
  EXPECT_EQ(o.jobs[2].state, rpc::JobState::Succeeded);
  EXPECT_EQ(service->overview().jobs.size(), 4u);  // the default keeps 50
}

TEST(Overview, MethodHistogramsHoldEveryRequest) {
  ServiceWorkspace ws;
  auto service = ws.start(ws.options());
  using namespace std::chrono_literals;
  service->recordRequest("iceoryx", rpc::Method::Evaluate, StatusCode::Ok, 3us);
  service->recordRequest("iceoryx", rpc::Method::Evaluate, StatusCode::Ok, 3us);
  service->recordRequest("dds", rpc::Method::Evaluate, StatusCode::Ok, 80us);
  const ServiceOverview o = service->overview();
  ASSERT_EQ(o.latencies.size(), rpc::kMethodCount);
  const auto& evaluate = o.latencies[static_cast<std::size_t>(rpc::Method::Evaluate)];
  EXPECT_EQ(evaluate.method, rpc::Method::Evaluate);
  ASSERT_EQ(evaluate.buckets.size(), 2u);  // 3 us twice, 80 us once
  EXPECT_EQ(evaluate.buckets[0].second, 2u);
  EXPECT_GE(evaluate.buckets[0].first, 3000u);
  EXPECT_LT(evaluate.buckets[0].first, 3300u);  // a bucket is at most 9% wide
  EXPECT_EQ(evaluate.buckets[1].second, 1u);
  EXPECT_GE(evaluate.buckets[1].first, 80000u);
  EXPECT_TRUE(o.latencies[static_cast<std::size_t>(rpc::Method::LoadModel)].buckets.empty());
  EXPECT_FALSE(o.instance_id.empty());
}

}  // namespace
}  // namespace robodiff::server::testing
