// What a URDF can do to the service: nothing that crashes it (limits answered with
// RESOURCE_EXHAUSTED naming the limit), nothing physically invalid accepted
// (INVALID_ARGUMENT naming the link), and no non-finite result passed off as OK; the
// service serves a good model right after, in the same test.
#include <gtest/gtest.h>

#include <chrono>
#include <regex>

#include "service_fixtures.hpp"

namespace robodiff::server::testing {
namespace {

Status tryLoad(Service& service, const std::string& urdf) {
  rpc::LoadModelRequest request;
  request.urdf = urdf;
  rpc::LoadModelReply reply;
  return service.loadModel(context(), request, reply);
}

// The service still loads arm7 and evaluates its RNEA.
void expectStillServes(Service& service) {
  const rpc::LoadModelReply model = loadModel(service, arm7Urdf());
  const rpc::GetFunctionReply f = readyFunction(service, model.model_id, kRneaValueSpec);
  const std::vector<double> tau = evaluateOnce(service, f, someInputs(rpc::inputCount(f), 1));
  EXPECT_EQ(tau.size(), 7u);
}

std::string deeplyNested(int depth) {
  std::string xml = "<robot name=\"r\"><link name=\"base\"/>";
  for (int i = 0; i < depth; ++i) xml += "<a>";
  for (int i = 0; i < depth; ++i) xml += "</a>";
  return xml + "</robot>";
}

// ~16 MB: tens of thousands of links joined by fixed joints.
std::string fixedJointChain(int links) {
  std::string xml = "<robot name=\"chain\"><link name=\"l0\"/>";
  for (int i = 1; i < links; ++i)
    xml += "<link name=\"l" + std::to_string(i) + "\"/><joint name=\"j" + std::to_string(i) +
           "\" type=\"fixed\"><parent link=\"l" + std::to_string(i - 1) + "\"/><child link=\"l" + std::to_string(i) +
           "\"/><origin xyz=\"0 0 0.001\" rpy=\"0 0 0\"/></joint>\n";
  return xml + "</robot>";
}

TEST(UrdfHardening, DeepNestingAndHugeChainsAreResourceExhaustedAndTheServiceStillServes) {
  ServiceWorkspace ws;
  auto service = ws.start(ws.options());
  const auto start = std::chrono::steady_clock::now();
  Status deep = tryLoad(*service, deeplyNested(100'000));
  EXPECT_EQ(deep.code, StatusCode::ResourceExhausted) << deep.message;
  EXPECT_NE(deep.message.find("nests elements 100001 deep; the limit is max_depth = 64"), std::string::npos)
      << deep.message;

  const std::string chain = fixedJointChain(110'000);
  ASSERT_GT(chain.size(), 15'000'000u);
  ASSERT_LT(chain.size(), std::size_t{16} << 20);
  Status huge = tryLoad(*service, chain);
  EXPECT_EQ(huge.code, StatusCode::ResourceExhausted) << huge.message;
  EXPECT_NE(huge.message.find("max_elements = 400000"), std::string::npos) << huge.message;
  EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(), 3.0);
  expectStillServes(*service);
}

TEST(UrdfHardening, LimitsComeFromServiceOptions) {
  ServiceWorkspace ws;
  ServiceOptions options = ws.options();
  options.urdf_limits.max_links = 3;
  auto service = ws.start(options);
  Status status = tryLoad(*service, arm7Urdf());
  EXPECT_EQ(status.code, StatusCode::ResourceExhausted);
  EXPECT_NE(status.message.find("links; the limit is max_links = 3"), std::string::npos) << status.message;
  options.urdf_limits.max_links = 20;
  service.reset();
  service = ws.start(options);
  expectStillServes(*service);
}

TEST(UrdfHardening, PhysicallyInvalidModelsAreInvalidArgumentNamingTheLink) {
  ServiceWorkspace ws;
  auto service = ws.start(ws.options());
  // Every mass and inertia zero: ABA would give NaN with status OK.
  std::string massless = std::regex_replace(arm7Urdf(), std::regex(R"(<mass value="[^"]*"/>)"), R"(<mass value="0"/>)");
  massless = std::regex_replace(massless, std::regex(R"(<inertia [^>]*/>)"),
                                R"(<inertia ixx="0" ixy="0" ixz="0" iyy="0" iyz="0" izz="0"/>)");
  Status zero = tryLoad(*service, massless);
  EXPECT_EQ(zero.code, StatusCode::InvalidArgument);
  EXPECT_NE(zero.message.find("mass matrix is singular"), std::string::npos) << zero.message;
  EXPECT_TRUE(std::regex_search(zero.message, std::regex("joint '[^']+' moves no mass .*\\(links? '"))) << zero.message;

  Status negative = tryLoad(*service, replaced(arm7Urdf(), R"(<mass value="2.3056640625"/>)", R"(<mass value="-1"/>)"));
  EXPECT_EQ(negative.code, StatusCode::InvalidArgument);
  EXPECT_NE(negative.message.find("negative mass -1"), std::string::npos) << negative.message;

  Status nan = tryLoad(*service, replaced(arm7Urdf(), R"(<origin xyz="-0.011932373046875)", R"(<origin xyz="nan)"));
  EXPECT_EQ(nan.code, StatusCode::InvalidArgument);
  EXPECT_NE(nan.message.find("'nan' is not a finite number"), std::string::npos) << nan.message;
  expectStillServes(*service);
}

TEST(UrdfHardening, NonFiniteOutputsAreOutOfRange) {
  ServiceWorkspace ws;
  auto service = ws.start(ws.options());
  const rpc::LoadModelReply model = loadModel(*service, arm7Urdf());
  const rpc::GetFunctionReply f = readyFunction(*service, model.model_id, kRneaValueSpec);
  const std::size_t in = rpc::inputCount(f), out = rpc::outputCount(f);
  // Finite inputs whose squares overflow: tau is not finite.
  std::vector<double> huge(in, 1e300), outputs(out);
  Status single = service->evaluate(context(), f.function_id, huge, outputs);
  EXPECT_EQ(single.code, StatusCode::OutOfRange) << single.message << " tau[0] = " << outputs[0];
  EXPECT_NE(single.message.find("non-finite"), std::string::npos) << single.message;

  std::vector<double> batch_in = someInputs(3 * in, 2), batch_out(3 * out);
  std::copy(huge.begin(), huge.end(), batch_in.begin() + static_cast<long>(in));  // knot 1
  Status batch = service->evaluateBatch(context(), f.function_id, 3, batch_in, batch_out);
  EXPECT_EQ(batch.code, StatusCode::OutOfRange) << batch.message;
  EXPECT_NE(batch.message.find("of knot 1 is"), std::string::npos) << batch.message;

  EXPECT_TRUE(service->evaluate(context(), f.function_id, someInputs(in, 3), outputs).ok());
}

}  // namespace
}  // namespace robodiff::server::testing
