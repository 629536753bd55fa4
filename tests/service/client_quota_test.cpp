// Per-client quotas (issue 19, item 5): one caller holds at most max_models_per_client
// models and max_functions_per_client functions (loaded, not released); beyond, its
// LoadModel / GetFunction is RESOURCE_EXHAUSTED naming the limit and its value, while
// other callers are unaffected and another reference to what it holds is still fine.

#include <gtest/gtest.h>

#include "service_fixtures.hpp"

namespace robodiff::server::testing {
namespace {

CallContext as(const std::string& name) {
  CallContext ctx = context();
  ctx.caller = Caller{name, false, true};
  return ctx;
}

Status loadAs(Service& service, const CallContext& who, const std::string& urdf, std::string* model_id = nullptr) {
  rpc::LoadModelRequest request;
  request.urdf = urdf;
  rpc::LoadModelReply reply;
  const Status s = service.loadModel(who, request, reply);
  if (model_id) *model_id = reply.model_id;
  return s;
}

Status functionAs(Service& service, const CallContext& who, const std::string& model_id, const std::string& spec) {
  rpc::GetFunctionRequest request;
  request.model_id = model_id;
  request.spec_json = spec;
  request.wait = true;
  rpc::GetFunctionReply reply;
  return service.getFunction(who, request, reply);
}

TEST(ClientQuotas, ACallerPastItsModelQuotaIsRefusedNamingTheLimit) {
  ServiceWorkspace ws;
  ServiceOptions options = ws.options();
  options.max_models_per_client = 2;
  auto service = ws.start(options);
  const CallContext alice = as("user:alice"), bob = as("user:bob");
  // Three models: the same arm with three masses of its first moving link.
  const std::string one = arm7Urdf();
  const std::string two = replaced(arm7Urdf(), "<mass value=\"2.3056640625\"/>", "<mass value=\"2.5\"/>");
  const std::string three = replaced(arm7Urdf(), "<mass value=\"2.3056640625\"/>", "<mass value=\"2.75\"/>");
  std::string first;
  ASSERT_TRUE(loadAs(*service, alice, one, &first).ok());
  std::string second;
  ASSERT_TRUE(loadAs(*service, alice, two, &second).ok());
  ASSERT_NE(first, second);
  const Status refused = loadAs(*service, alice, three);
  EXPECT_EQ(refused.code, StatusCode::ResourceExhausted);
  EXPECT_NE(refused.message.find("limits.max_models_per_client = 2"), std::string::npos) << refused.message;
  // Another reference to a model it holds is no new model; another caller is not counted.
  EXPECT_TRUE(loadAs(*service, alice, one).ok());
  EXPECT_TRUE(loadAs(*service, bob, three).ok());
  // Released (both references), a slot is free again.
  rpc::ReleaseReply released;
  ASSERT_TRUE(service->release(alice, {first}, released).ok());
  ASSERT_TRUE(service->release(alice, {first}, released).ok());
  EXPECT_TRUE(loadAs(*service, alice, three).ok());
}

TEST(ClientQuotas, ACallerPastItsFunctionQuotaIsRefusedNamingTheLimit) {
  ServiceWorkspace ws;
  ServiceOptions options = ws.options();
  options.max_functions_per_client = 1;
  auto service = ws.start(options);
  const CallContext alice = as("user:alice"), bob = as("user:bob");
  std::string model_id;
  ASSERT_TRUE(loadAs(*service, alice, arm7Urdf(), &model_id).ok());
  ASSERT_TRUE(loadAs(*service, bob, arm7Urdf()).ok());
  ASSERT_TRUE(functionAs(*service, alice, model_id, kRneaValueSpec).ok());
  const Status refused = functionAs(*service, alice, model_id, kRneaJacobianSpec);
  EXPECT_EQ(refused.code, StatusCode::ResourceExhausted);
  EXPECT_NE(refused.message.find("limits.max_functions_per_client = 1"), std::string::npos) << refused.message;
  EXPECT_TRUE(functionAs(*service, alice, model_id, kRneaValueSpec).ok());  // the one it holds
  EXPECT_TRUE(functionAs(*service, bob, model_id, kRneaJacobianSpec).ok());
}

}  // namespace
}  // namespace robodiff::server::testing
