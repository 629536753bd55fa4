// Functions on their way to a compiled library, with real worker processes and a real
// cache: the interpreter serves from the moment the function is traced, the library
// (built by a worker) is swapped in with identical results; a second Service on the same
// cache finds the library (a cache hit) and reports the same layout as the trace; a
// compiler that fails leaves the interpreter serving with the compiler's message kept;
// a spec that does not fit the model fails the function.
#include <fstream>

#include "service_fixtures.hpp"

namespace robodiff::server::testing {
namespace {

namespace fs = std::filesystem;

void expectSameLayout(const rpc::GetFunctionReply& a, const rpc::GetFunctionReply& b) {
  ASSERT_EQ(a.inputs.size(), b.inputs.size());
  for (std::size_t i = 0; i < a.inputs.size(); ++i) {
    EXPECT_EQ(a.inputs[i].name, b.inputs[i].name);
    EXPECT_EQ(a.inputs[i].size, b.inputs[i].size);
  }
  ASSERT_EQ(a.outputs.size(), b.outputs.size());
  for (std::size_t k = 0; k < a.outputs.size(); ++k) {
    const rpc::OutputBlock &x = a.outputs[k], &y = b.outputs[k];
    EXPECT_EQ(x.name, y.name) << k;
    EXPECT_EQ(x.kind, y.kind) << k;
    EXPECT_EQ(x.rows, y.rows) << k;
    EXPECT_EQ(x.cols, y.cols) << k;
    EXPECT_EQ(x.layout, y.layout) << k;
    EXPECT_EQ(x.nnz, y.nnz) << k;
    EXPECT_EQ(x.row_offsets, y.row_offsets) << k;
    EXPECT_EQ(x.col_indices, y.col_indices) << k;
  }
}

TEST(Builds, InterpreterFirstThenTheCompiledLibraryThenACacheHitWithTheSameLayout) {
  ServiceWorkspace ws;
  const fs::path gate = ws.tmp / "compile-now";
  ServiceOptions options = ws.options(true);
  options.compiler = gatedCompiler(ws.tmp, gate).string();
  auto service = ws.start(options);
  const rpc::LoadModelReply model = loadModel(*service, arm7Urdf());

  // Traced and served by the interpreter while the compiler waits for the gate.
  const rpc::GetFunctionReply traced = readyFunction(*service, model.model_id, kRneaSparseSpec);
  ASSERT_EQ(traced.outputs.size(), 2u);
  EXPECT_EQ(traced.outputs[1].layout, rpc::OutputLayout::SparseCsr);
  EXPECT_EQ(traced.outputs[1].row_offsets.size(), 8u);
  EXPECT_EQ(traced.outputs[1].col_indices.size(), traced.outputs[1].nnz);
  EXPECT_FALSE(summaryOf(*service, traced.function_id).compiled);
  const std::size_t knots = 300, in = rpc::inputCount(traced), out = rpc::outputCount(traced);
  const std::vector<double> inputs = someInputs(knots * in, 11);
  std::vector<double> interpreted(knots * out);
  ASSERT_TRUE(service->evaluateBatch(context(), traced.function_id, knots, inputs, interpreted).ok());
  rpc::HealthReply h = health(*service);
  EXPECT_EQ(h.cache_misses, 1u);
  EXPECT_EQ(h.functions_compiled, 0u);
  EXPECT_EQ(h.builds_queued + h.builds_running, 1u);

  // The library arrives and takes over.
  std::ofstream(gate.string()) << "go\n";
  ASSERT_TRUE(waitFor([&] { return summaryOf(*service, traced.function_id).compiled; }))
      << summaryOf(*service, traced.function_id).message;
  std::vector<double> compiled(knots * out);
  ASSERT_TRUE(service->evaluateBatch(context(), traced.function_id, knots, inputs, compiled).ok());
  EXPECT_TRUE(closeTo(compiled, interpreted, 1e-12));
  for (std::size_t k = 0; k < knots; k += 37) {  // the single-knot entry point agrees too
    const std::vector<double> x(inputs.begin() + static_cast<long>(k * in),
                                inputs.begin() + static_cast<long>((k + 1) * in));
    const std::vector<double> one = evaluateOnce(*service, traced, x);
    EXPECT_TRUE(closeTo(one,
                        std::vector<double>(compiled.begin() + static_cast<long>(k * out),
                                            compiled.begin() + static_cast<long>((k + 1) * out)),
                        1e-12))
        << "knot " << k;
  }
  h = health(*service);
  EXPECT_EQ(h.builds_done, 1u);
  EXPECT_EQ(h.builds_failed, 0u);
  EXPECT_EQ(h.builds_queued + h.builds_running, 0u);
  EXPECT_EQ(h.functions_compiled, 1u);
  EXPECT_EQ(h.cache_entries, 1u);
  EXPECT_GT(h.cache_bytes, 0u);
  const std::string log = ws.logText();
  EXPECT_NE(log.find("\"event\":\"function_traced\""), std::string::npos) << log;
  EXPECT_NE(log.find("\"event\":\"function_compiled\""), std::string::npos) << log;
  EXPECT_NE(log.find("\"event\":\"function_swapped\""), std::string::npos) << log;
  service.reset();

  // Another server on the same cache: a hit, compiled from the start, same layout.
  auto second = ws.start(options);
  const rpc::LoadModelReply model2 = loadModel(*second, arm7Urdf());
  EXPECT_EQ(model2.model_id, model.model_id);
  const rpc::GetFunctionReply hit = readyFunction(*second, model2.model_id, kRneaSparseSpec);
  EXPECT_EQ(hit.function_id, traced.function_id);  // ids are the same on every server
  expectSameLayout(hit, traced);
  EXPECT_TRUE(summaryOf(*second, hit.function_id).compiled);
  h = health(*second);
  EXPECT_EQ(h.cache_hits, 1u);
  EXPECT_EQ(h.cache_misses, 0u);
  EXPECT_EQ(h.builds_done + h.builds_queued + h.builds_running, 0u);
  std::vector<double> from_cache(knots * out);
  ASSERT_TRUE(second->evaluateBatch(context(), hit.function_id, knots, inputs, from_cache).ok());
  EXPECT_TRUE(closeTo(from_cache, interpreted, 1e-12));
}

TEST(Builds, AFailingCompilerLeavesTheInterpreterServingAndKeepsTheMessage) {
  ServiceWorkspace ws;
  ServiceOptions options = ws.options(true);
  options.compiler = failingCompiler(ws.tmp).string();
  auto service = ws.start(options);
  const rpc::LoadModelReply model = loadModel(*service, arm7Urdf());
  const rpc::GetFunctionReply f = readyFunction(*service, model.model_id, kRneaValueSpec);
  ASSERT_TRUE(waitFor([&] { return health(*service).builds_failed == 1; }));
  const rpc::FunctionSummary summary = summaryOf(*service, f.function_id);
  EXPECT_EQ(summary.state, rpc::FunctionState::Ready);
  EXPECT_FALSE(summary.compiled);
  EXPECT_NE(summary.message.find("simulated failure"), std::string::npos) << summary.message;
  const rpc::HealthReply h = health(*service);
  EXPECT_EQ(h.builds_done, 0u);
  EXPECT_EQ(h.functions_compiled, 0u);
  EXPECT_EQ(h.cache_entries, 0u);
  // Still served.
  const std::vector<double> tau = evaluateOnce(*service, f, someInputs(21, 5));
  EXPECT_EQ(tau.size(), 7u);
  EXPECT_NE(ws.logText().find("\"event\":\"build_failed\""), std::string::npos);
  EXPECT_EQ(summaryOf(*service, f.function_id).evaluations, 1u);
}

TEST(Builds, ASpecThatDoesNotFitTheModelFailsTheFunction) {
  ServiceWorkspace ws;
  auto service = ws.start(ws.options());
  const rpc::LoadModelReply model = loadModel(*service, arm7Urdf());
  const std::string spec = R"({"function": "fk", "frame": "no_such_frame", "outputs": [{"kind": "value"}]})";
  rpc::GetFunctionReply reply;
  Status status = getFunction(*service, model.model_id, spec, true, reply);
  EXPECT_EQ(status.code, StatusCode::InvalidArgument);
  EXPECT_NE(status.message.find("no_such_frame"), std::string::npos) << status.message;
  EXPECT_EQ(reply.state, rpc::FunctionState::Failed);
  ASSERT_FALSE(reply.function_id.empty());
  // A failed function holds no slot: it is unloaded at once, and not listed.
  rpc::ListFunctionsReply list;
  ASSERT_TRUE(service->listFunctions(context(), {}, list).ok());
  EXPECT_TRUE(list.functions.empty());
  std::vector<double> in(7, 0.0), out(12, 0.0);
  status = service->evaluate(context(), reply.function_id, in, out);
  EXPECT_EQ(status.code, StatusCode::NotFound);
  EXPECT_NE(status.message.find("failed to build"), std::string::npos) << status.message;
  // Asked again (with or without wait), the same answer, from the record of recent failures.
  for (const bool wait : {true, false}) {
    rpc::GetFunctionReply again;
    status = getFunction(*service, model.model_id, spec, wait, again);
    EXPECT_EQ(status.code, StatusCode::InvalidArgument);
    EXPECT_NE(status.message.find("no_such_frame"), std::string::npos) << status.message;
    EXPECT_EQ(again.state, rpc::FunctionState::Failed);
    EXPECT_EQ(again.function_id, reply.function_id);
  }

  // A spec that is not a spec at all is refused before anything is made.
  status =
      getFunction(*service, model.model_id, R"({"function": "rnea", "outputs": [{"kind": "nonsense"}]})", false, reply);
  EXPECT_EQ(status.code, StatusCode::InvalidArgument);
  EXPECT_NE(status.message.find("outputs[0]"), std::string::npos) << status.message;
  EXPECT_EQ(health(*service).functions_loaded, 0u);
}

TEST(Builds, WithoutWaitTheReplyComesAtOnceAndEvaluationWaitsForReady) {
  ServiceWorkspace ws;
  auto service = ws.start(ws.options());
  const rpc::LoadModelReply model = loadModel(*service, arm7Urdf());
  rpc::GetFunctionReply first;
  ASSERT_TRUE(getFunction(*service, model.model_id, kRneaJacobianSpec, false, first).ok());
  ASSERT_EQ(first.function_id.size(), 32u);
  if (first.state == rpc::FunctionState::Building) {
    EXPECT_TRUE(first.outputs.empty());
    std::vector<double> in(21, 0.0), out(168, 0.0);
    const Status status = service->evaluate(context(), first.function_id, in, out);
    // Either still building (the usual case) or traced meanwhile.
    if (!status.ok()) {
      EXPECT_EQ(status.code, StatusCode::FailedPrecondition);
      EXPECT_NE(status.message.find("still being built"), std::string::npos) << status.message;
    }
  }
  const rpc::GetFunctionReply ready = readyFunction(*service, model.model_id, kRneaJacobianSpec);
  EXPECT_EQ(ready.function_id, first.function_id);
  rpc::ReleaseReply released;
  ASSERT_TRUE(service->release(context(), {ready.function_id}, released).ok());
  EXPECT_EQ(released.references_left, 1u);  // two GetFunction calls, one released
}

TEST(Builds, WaitingPastTheDeadlineIsDeadlineExceededWhileBuilding) {
  ServiceWorkspace ws;
  auto service = ws.start(ws.options());
  const rpc::LoadModelReply model = loadModel(*service, readFile(sourceDir() / "examples/robots/humanoid.urdf"));
  rpc::GetFunctionRequest request{model.model_id, kRneaJacobianSpec, true};
  CallContext ctx = context();
  ctx.deadline = Clock::now() + std::chrono::milliseconds(1);  // a 30-joint Jacobian takes longer to trace
  rpc::GetFunctionReply reply;
  const Status status = service->getFunction(ctx, request, reply);
  EXPECT_EQ(status.code, StatusCode::DeadlineExceeded) << status.message;
  EXPECT_EQ(reply.state, rpc::FunctionState::Building);
  EXPECT_EQ(reply.function_id.size(), 32u);
  const rpc::GetFunctionReply ready = readyFunction(*service, model.model_id, kRneaJacobianSpec);
  EXPECT_EQ(ready.function_id, reply.function_id);
  EXPECT_EQ(rpc::inputCount(ready), 90u);
}

TEST(Builds, StoppingTheServiceCancelsARunningBuild) {
  ServiceWorkspace ws;
  ServiceOptions options = ws.options(true);
  options.compiler = gatedCompiler(ws.tmp, ws.tmp / "never").string();  // the compile never ends by itself
  auto service = ws.start(options);
  const rpc::LoadModelReply model = loadModel(*service, arm7Urdf());
  readyFunction(*service, model.model_id, kRneaValueSpec);
  ASSERT_TRUE(waitFor([&] { return health(*service).builds_running == 1; }));
  EXPECT_EQ(health(*service).workers_busy, 1u);
  const auto started = Clock::now();
  service.reset();
  EXPECT_LT(Clock::now() - started, std::chrono::seconds(10));
  // Nothing of the cancelled build is left in the cache.
  options.compile = false;
  EXPECT_EQ(health(*ws.start(options)).cache_entries, 0u);
  EXPECT_NE(ws.logText().find("\"event\":\"build_failed\""), std::string::npos);
}

}  // namespace
}  // namespace robodiff::server::testing
