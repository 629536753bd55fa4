// The caller of an iceoryx request: the OS user running the client process (the owner of
// /proc/<pid> for the pid in its client id), an operator when that is root or robodiffd's
// own user. Two uids cannot be had without root here, so the real round trip checks our
// own uid and the rule for other uids is checked on callerOfUid.

#include <gtest/gtest.h>

#include <pwd.h>
#include <unistd.h>

#include "robodiff/server/shm_caller.hpp"
#include "shm_test_support.hpp"

namespace robodiff::testing {
namespace {

using namespace std::chrono_literals;

// LoadModel answers with who called: "<name>[+operator]".
class CallerEchoService : public FakeService {
 public:
  using FakeService::FakeService;
  Status loadModel(const server::CallContext& ctx, const rpc::LoadModelRequest&, rpc::LoadModelReply& reply) override {
    reply.model_id = ctx.caller.name + (ctx.caller.operator_ ? "+operator" : "");
    return {};
  }
};

std::string ourUser() {
  const passwd* entry = getpwuid(geteuid());
  return entry ? entry->pw_name : "uid" + std::to_string(geteuid());
}

class ShmCaller : public ::testing::Test {
 protected:
  static void SetUpTestSuite() { sharedRoudi(); }
  void SetUp() override {
    server::ShmServerOptions options;
    options.service = "test-shm-caller";
    server_ = std::make_unique<server::ShmServer>(service_, options, quietLog());
    const Status s = server_->start();
    ASSERT_TRUE(s.ok()) << s.message;
  }
  void TearDown() override {
    if (server_) server_->stop();
  }
  std::string whoCalls(const std::string& client_id) {
    client::ShmConnectionOptions options;
    options.service = "test-shm-caller";
    options.client_id = client_id;
    options.default_timeout = 10s;
    options.connect_timeout = 3s;
    Status status;
    auto c = client::connectShm(options, status);
    if (!status.ok()) return "connect: " + status.message;
    rpc::LoadModelReply reply;
    status = c->loadModel({"<robot/>", false, ""}, reply);
    return status.ok() ? reply.model_id : "error: " + status.message;
  }

  CallerEchoService service_;
  std::unique_ptr<server::ShmServer> server_;
};

TEST_F(ShmCaller, TheClientProcessesUserCalls) {
  // The default client id ("<host>:<pid>:<random>"), and its pid is ours: our user, who
  // also runs the server, hence an operator.
  EXPECT_EQ(whoCalls(""), "user:" + ourUser() + "+operator");
}

TEST_F(ShmCaller, AnIdNamingNoLocalProcessOwnsNothingOfAnyone) {
  EXPECT_EQ(whoCalls("custom-client"), "shm:?unknown");
  EXPECT_EQ(whoCalls("another-host:1:00000000"), "shm:?unknown");  // not this host
}

TEST(ShmCallerRule, RootAndTheServersUserAreOperators) {
  EXPECT_TRUE(server::shm_detail::callerOfUid(0).operator_);
  EXPECT_EQ(server::shm_detail::callerOfUid(0).name, "user:root");
  EXPECT_TRUE(server::shm_detail::callerOfUid(geteuid()).operator_);
  if (geteuid() != 65534) {
    const server::Caller nobody = server::shm_detail::callerOfUid(65534);
    EXPECT_FALSE(nobody.operator_);
    EXPECT_FALSE(nobody.authenticated);
    EXPECT_EQ(nobody.name.rfind("user:", 0), 0u) << nobody.name;
  }
  EXPECT_EQ(server::shm_detail::callerOfUid(4000123).name, "user:uid4000123");  // no passwd entry
}

}  // namespace
}  // namespace robodiff::testing
