// A server that cannot compile (compile off, or its compiler missing) still serves a
// library built elsewhere, found by its portable key (cache::preparePortableKey): what a
// robot does with libraries it imported. Real cache, real worker for the first build.
#include "service_fixtures.hpp"

namespace robodiff::server::testing {
namespace {

// Builds kRneaJacobianSpec on arm7 with the default compiler; returns its outputs at `x`.
std::vector<double> buildElsewhere(ServiceWorkspace& ws, const std::vector<double>& x) {
  auto builder = ws.start(ws.options(true));
  const rpc::LoadModelReply model = loadModel(*builder, arm7Urdf());
  const rpc::GetFunctionReply f = readyFunction(*builder, model.model_id, kRneaJacobianSpec);
  EXPECT_TRUE(waitFor([&] { return summaryOf(*builder, f.function_id).compiled; }));
  return evaluateOnce(*builder, f, x);
}

TEST(PortableCache, AServerWithoutACompilerServesALibraryBuiltElsewhere) {
  ServiceWorkspace ws;
  const std::vector<double> x = someInputs(21, 5);
  const std::vector<double> expected = buildElsewhere(ws, x);
  for (bool compile : {false, true}) {
    SCOPED_TRACE(compile ? "compile on, compiler missing" : "compile off");
    ServiceOptions options = ws.options(compile);
    options.compiler = "/nonexistent/cc";  // the full key cannot be computed here
    auto robot = ws.start(options);
    const rpc::LoadModelReply model = loadModel(*robot, arm7Urdf());
    const rpc::GetFunctionReply f = readyFunction(*robot, model.model_id, kRneaJacobianSpec);
    EXPECT_TRUE(summaryOf(*robot, f.function_id).compiled) << summaryOf(*robot, f.function_id).message;
    EXPECT_EQ(health(*robot).cache_hits, 1u);
    EXPECT_EQ(health(*robot).cache_misses, 0u);
    EXPECT_TRUE(closeTo(evaluateOnce(*robot, f, x), expected, 0.0));  // the same library, the same bits
    // Another function, in no cache: the interpreter serves it.
    const rpc::GetFunctionReply other = readyFunction(*robot, model.model_id, kRneaValueSpec);
    EXPECT_FALSE(summaryOf(*robot, other.function_id).compiled);
  }
  EXPECT_NE(ws.logText().find("\"source\":\"cache by portable key\""), std::string::npos);
}

}  // namespace
}  // namespace robodiff::server::testing
