// A user function through the service exactly like a built-in one: traced and served by
// the interpreter, built by a real worker into the cache and swapped in with the same
// results, batched, found again by a second server; a spec written differently (renamed
// defines, another order, other whitespace) is the same function; bad and oversized
// specs are refused with INVALID_ARGUMENT and RESOURCE_EXHAUSTED.
#include <fstream>

#include "robodiff/functions/reference.hpp"
#include "robodiff/model/urdf_loader.hpp"
#include "service_fixtures.hpp"

namespace robodiff::server::testing {
namespace {

namespace fs = std::filesystem;

const char* kStep = R"js({"name": "euler_step",
  "inputs": {"q": "configuration", "v": "nv", "u": "nv", "dt": {"fixed": [0.01]}},
  "define": {"v_next": "v + dt * aba(q, v, u)", "q_next": "integrate(q, dt * v_next)"},
  "outputs": [
    {"name": "q_next", "kind": "value", "of": "q_next"},
    {"name": "v_next", "kind": "value", "of": "v_next"},
    {"name": "dv_next", "kind": "jacobian", "of": "v_next", "wrt": ["q", "v", "u"]}]})js";

const char* kStepRewritten = R"js({"name":"euler_step","inputs":{"q":"configuration","v":"nv","u":"nv","dt":{"fixed":[1e-2]}},
  "define":{"qn":"integrate(q,dt*vn)","vn":"v+dt*aba(q,v,u)"},
  "outputs":[{"name":"q_next","kind":"value","of":"qn"},{"name":"v_next","kind":"value","of":"vn"},
             {"name":"dv_next","kind":"jacobian","of":"vn","wrt":["q","v","u"]}]})js";

TEST(UserFunctionService, ServedInterpretedThenCompiledThenFromTheCache) {
  ServiceWorkspace ws;
  const fs::path gate = ws.tmp / "compile-now";
  ServiceOptions options = ws.options(true);
  options.compiler = gatedCompiler(ws.tmp, gate).string();
  auto service = ws.start(options);
  const rpc::LoadModelReply model = loadModel(*service, arm7Urdf());
  const rpc::GetFunctionReply traced = readyFunction(*service, model.model_id, kStep);
  ASSERT_EQ(traced.inputs.size(), 3u);
  EXPECT_EQ(traced.inputs[2].name, "u");
  ASSERT_EQ(traced.outputs.size(), 3u);
  EXPECT_EQ(traced.outputs[2].name, "dv_next");
  EXPECT_EQ(traced.outputs[2].rows, 7u);
  EXPECT_EQ(traced.outputs[2].cols, 21u);

  // The interpreter's values against the double evaluation of the expressions.
  const Model arm = loadUrdfString(arm7Urdf());
  const FunctionSpec spec = parseFunctionSpec(kStep);
  const std::size_t knots = 40, in = rpc::inputCount(traced), out = rpc::outputCount(traced);
  std::vector<double> inputs;
  for (std::size_t k = 0; k < knots; ++k)
    for (const Eigen::VectorXd& x : randomRuntimeInputs(arm, spec, k)) inputs.insert(inputs.end(), x.begin(), x.end());
  std::vector<double> interpreted(knots * out);
  ASSERT_TRUE(service->evaluateBatch(context(), traced.function_id, knots, inputs, interpreted).ok());
  const std::vector<Eigen::MatrixXd> expected = userReferenceOutputs(arm, spec, completeInputs(spec, randomRuntimeInputs(arm, spec, 0)));
  for (int i = 0; i < 7; ++i) EXPECT_NEAR(interpreted[7 + i], expected[1](i, 0), 1e-12);

  // The compiled library arrives, is swapped in and gives the same numbers, batched or not.
  std::ofstream(gate.string()) << "go\n";
  ASSERT_TRUE(waitFor([&] { return summaryOf(*service, traced.function_id).compiled; }))
      << summaryOf(*service, traced.function_id).message;
  std::vector<double> compiled(knots * out);
  ASSERT_TRUE(service->evaluateBatch(context(), traced.function_id, knots, inputs, compiled).ok());
  EXPECT_TRUE(closeTo(compiled, interpreted, 1e-12));
  const std::vector<double> first(inputs.begin(), inputs.begin() + static_cast<long>(in));
  EXPECT_TRUE(closeTo(evaluateOnce(*service, traced, first), std::vector<double>(compiled.begin(), compiled.begin() + static_cast<long>(out)), 1e-12));
  EXPECT_EQ(health(*service).cache_entries, 1u);
  service.reset();

  // A second server on the same cache, asked for the same function written differently.
  auto second = ws.start(options);
  const rpc::LoadModelReply model2 = loadModel(*second, arm7Urdf());
  const rpc::GetFunctionReply hit = readyFunction(*second, model2.model_id, kStepRewritten);
  EXPECT_EQ(hit.function_id, traced.function_id);
  EXPECT_TRUE(summaryOf(*second, hit.function_id).compiled);
  EXPECT_EQ(health(*second).cache_hits, 1u);
  std::vector<double> from_cache(knots * out);
  ASSERT_TRUE(second->evaluateBatch(context(), hit.function_id, knots, inputs, from_cache).ok());
  EXPECT_TRUE(closeTo(from_cache, interpreted, 1e-12));
}

TEST(UserFunctionService, BadAndOversizedSpecsAreRefusedWithTheirReason) {
  ServiceWorkspace ws;
  auto service = ws.start(ws.options());
  const rpc::LoadModelReply model = loadModel(*service, arm7Urdf());
  rpc::GetFunctionReply reply;
  const Status unknown = getFunction(*service, model.model_id, replaced(kStep, "aba(q", "abba(q"), true, reply);
  EXPECT_EQ(unknown.code, StatusCode::InvalidArgument);
  EXPECT_NE(unknown.message.find("'aba'"), std::string::npos) << unknown.message;
  const Status frame = getFunction(
      *service, model.model_id, replaced(kStep, "aba(q, v, u)", "aba(q, v, u) + frame_position(q, 'tol')[0]"), true, reply);
  EXPECT_EQ(frame.code, StatusCode::InvalidArgument);
  EXPECT_NE(frame.message.find("'tool'"), std::string::npos) << frame.message;
  const Status deep = getFunction(*service, model.model_id,
                                  replaced(kStep, "aba(q, v, u)", std::string(5000, '(') + "u" + std::string(5000, ')')), true, reply);
  EXPECT_EQ(deep.code, StatusCode::ResourceExhausted) << deep.message;
  // The service still serves.
  EXPECT_TRUE(readyFunction(*service, model.model_id, kStep).function_id.size());
}

}  // namespace
}  // namespace robodiff::server::testing
