// Ownership through the service API (what every transport calls), with callers as the
// transports set them: models, functions and jobs belong to the caller that made them;
// another caller can neither see nor release nor cancel them, an operator can; a function
// two callers asked for is held by both, and one's Release never drops the other's hold.

#include <gtest/gtest.h>

#include "service_fixtures.hpp"

namespace robodiff::server::testing {
namespace {

CallContext asCaller(const std::string& name, bool operator_ = false) {
  CallContext ctx = context();
  ctx.caller = Caller{name, operator_, true};
  return ctx;
}

const CallContext alice = asCaller("dds:alice"), bob = asCaller("dds:bob"), ops = asCaller("dds:ops", true);

std::vector<std::string> listed(Service& service, const CallContext& who) {
  rpc::ListFunctionsReply reply;
  const Status s = service.listFunctions(who, {}, reply);
  EXPECT_TRUE(s.ok()) << s.message;
  std::vector<std::string> ids;
  for (const auto& f : reply.functions) ids.push_back(f.function_id);
  EXPECT_EQ(reply.total, ids.size());
  return ids;
}

Status release(Service& service, const CallContext& who, const std::string& id, std::uint32_t* left = nullptr) {
  rpc::ReleaseReply reply;
  const Status s = service.release(who, {id}, reply);
  if (left) *left = reply.references_left;
  return s;
}

// LoadModel and GetFunction (waiting until READY) as `who`.
rpc::GetFunctionReply functionAsCaller(Service& service, const CallContext& who, std::string& model_id) {
  rpc::LoadModelReply model;
  EXPECT_TRUE(service.loadModel(who, {arm7Urdf(), false, ""}, model).ok());
  model_id = model.model_id;
  rpc::GetFunctionRequest request;
  request.model_id = model_id;
  request.spec_json = kRneaValueSpec;
  request.wait = true;
  rpc::GetFunctionReply reply;
  const Status s = service.getFunction(who, request, reply);
  EXPECT_TRUE(s.ok()) << s.message;
  return reply;
}

void expectRefusedWithoutNames(const Status& s) {
  EXPECT_EQ(s.code, StatusCode::PermissionDenied) << s.message;
  EXPECT_NE(s.message.find("belongs to another caller"), std::string::npos) << s.message;
  EXPECT_EQ(s.message.find("alice"), std::string::npos) << "the refusal names the owner: " << s.message;
}

TEST(Ownership, AnotherCallerNeitherSeesNorReleasesAFunction) {
  ServiceWorkspace ws;
  auto service = ws.start(ws.options());
  std::string model_id;
  const auto f = functionAsCaller(*service, alice, model_id);

  EXPECT_EQ(listed(*service, alice), std::vector<std::string>{f.function_id});
  EXPECT_TRUE(listed(*service, bob).empty());
  EXPECT_EQ(listed(*service, ops), std::vector<std::string>{f.function_id});
  expectRefusedWithoutNames(release(*service, bob, f.function_id));
  expectRefusedWithoutNames(release(*service, bob, model_id));
  // Still there for alice.
  const auto in = someInputs(3 * 7, 1);
  std::vector<double> out(7);
  EXPECT_TRUE(service->evaluate(alice, f.function_id, in, out).ok());
  EXPECT_NE(ws.logText().find("\"release_refused\""), std::string::npos);
}

TEST(Ownership, ASharedFunctionIsHeldPerCaller) {
  ServiceWorkspace ws;
  auto service = ws.start(ws.options());
  std::string model_id;
  const auto f = functionAsCaller(*service, alice, model_id);
  const auto g = functionAsCaller(*service, bob, model_id);  // the same spec: one function, two holders
  ASSERT_EQ(f.function_id, g.function_id);
  EXPECT_EQ(listed(*service, bob), std::vector<std::string>{f.function_id});

  std::uint32_t left = 0;
  ASSERT_TRUE(release(*service, bob, f.function_id, &left).ok());
  EXPECT_EQ(left, 1u);  // alice's hold
  EXPECT_TRUE(listed(*service, bob).empty());
  EXPECT_EQ(listed(*service, alice), std::vector<std::string>{f.function_id});
  // bob has nothing left to release: his second Release cannot take alice's hold.
  expectRefusedWithoutNames(release(*service, bob, f.function_id));
  std::vector<double> out(7);
  EXPECT_TRUE(service->evaluate(alice, f.function_id, someInputs(21, 2), out).ok());
  ASSERT_TRUE(release(*service, alice, f.function_id, &left).ok());
  EXPECT_EQ(left, 0u);
  EXPECT_EQ(service->evaluate(alice, f.function_id, someInputs(21, 2), out).code, StatusCode::NotFound);
}

TEST(Ownership, AnOperatorSeesAndReleasesEveryFunction) {
  ServiceWorkspace ws;
  auto service = ws.start(ws.options());
  std::string model_id;
  const auto f = functionAsCaller(*service, alice, model_id);
  functionAsCaller(*service, alice, model_id);  // a second hold
  std::uint32_t left = 7;
  ASSERT_TRUE(release(*service, ops, f.function_id, &left).ok());  // holds none: every hold goes
  EXPECT_EQ(left, 0u);
  EXPECT_TRUE(listed(*service, ops).empty());
  ASSERT_TRUE(release(*service, ops, model_id, &left).ok());
  EXPECT_EQ(left, 0u);
  EXPECT_EQ(release(*service, alice, model_id).code, StatusCode::NotFound);  // unloaded
}

class JobOwnership : public ::testing::Test {
 protected:
  ServiceOptions jobOptions() const {
    ServiceOptions o = ws.options();
    o.job_workers = 1;
    return o;
  }
  // A job (of a kind the worker does not know: it fails at once, which is all it needs to do).
  static std::string submit(Service& service, const CallContext& who) {
    rpc::SubmitJobReply reply;
    const Status s = service.submitJob(who, {"ownership-test", "{}"}, reply);
    EXPECT_TRUE(s.ok()) << s.message;
    return reply.job_id;
  }
  static Status status(Service& service, const CallContext& who, const std::string& id,
                       rpc::JobStatusReply* out = nullptr) {
    rpc::JobStatusReply reply;
    const Status s = service.jobStatus(who, {id}, reply);
    if (out) *out = reply;
    return s;
  }
  static std::vector<std::string> jobsOf(Service& service, const CallContext& who) {
    rpc::JobStatusReply reply;
    EXPECT_TRUE(service.jobStatus(who, {""}, reply).ok());
    std::vector<std::string> ids;
    for (const auto& j : reply.jobs) ids.push_back(j.job_id);
    return ids;
  }

  ServiceWorkspace ws;
};

TEST_F(JobOwnership, AnotherCallersJobIsRefusedAndNotListed) {
  auto service = ws.start(jobOptions());
  const std::string id = submit(*service, alice);
  EXPECT_TRUE(status(*service, alice, id).ok());
  expectRefusedWithoutNames(status(*service, bob, id));
  rpc::CancelJobReply cancelled;
  expectRefusedWithoutNames(service->cancelJob(bob, {id}, cancelled));
  rpc::JobResultReply result;
  expectRefusedWithoutNames(service->jobResult(bob, {id}, result));
  EXPECT_EQ(jobsOf(*service, alice), std::vector<std::string>{id});
  EXPECT_TRUE(jobsOf(*service, bob).empty());
  // An operator sees, reads and cancels it.
  EXPECT_EQ(jobsOf(*service, ops), std::vector<std::string>{id});
  EXPECT_TRUE(status(*service, ops, id).ok());
  EXPECT_TRUE(service->cancelJob(ops, {id}, cancelled).ok());
  EXPECT_NE(service->jobResult(ops, {id}, result).code, StatusCode::PermissionDenied);
}

TEST_F(JobOwnership, OwnershipOutlivesTheServer) {
  std::string id;
  {
    auto service = ws.start(jobOptions());
    id = submit(*service, alice);
    ASSERT_TRUE(waitFor([&] {
      rpc::JobStatusReply reply;
      return status(*service, alice, id, &reply).ok() && !reply.jobs.empty() && rpc::isFinal(reply.jobs[0].state);
    }));
  }
  auto service = ws.start(jobOptions());  // the job is now only in the index
  rpc::JobStatusReply reply;
  ASSERT_TRUE(status(*service, alice, id, &reply).ok());
  EXPECT_EQ(reply.jobs.at(0).job_id, id);
  expectRefusedWithoutNames(status(*service, bob, id));
  EXPECT_TRUE(jobsOf(*service, bob).empty());
  EXPECT_EQ(jobsOf(*service, alice), std::vector<std::string>{id});
}

}  // namespace
}  // namespace robodiff::server::testing
