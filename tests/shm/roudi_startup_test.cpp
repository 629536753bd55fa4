// Starting up without a RouDi: the client and server fail fast (never iceoryx's 60-second
// block), and robodiffd's ensureRoudi starts its own RouDi when none runs. These run
// before the other iceoryx tests of this binary (file order), which keep a RouDi running.
#include <gtest/gtest.h>

#include "robodiff/server/shm_roudi.hpp"
#include "shm_test_support.hpp"

namespace robodiff::testing {
namespace {

using namespace std::chrono_literals;

#define SKIP_IF_ROUDI_RUNS()                                                                   \
  if (shm::roudiRunning())                                                                     \
  GTEST_SKIP() << "a RouDi is running on this host (" << shm::roudiSocketPath()               \
               << "); this test needs none (run it alone: ctest -R " << ::testing::UnitTest::GetInstance()->current_test_info()->name() << ")"

TEST(ShmNoRoudi, ConnectAndStartFailFast) {
  SKIP_IF_ROUDI_RUNS();
  const auto t0 = std::chrono::steady_clock::now();
  Status status;
  auto c = client::connectShm({}, status);
  EXPECT_EQ(c, nullptr);
  EXPECT_EQ(status.code, StatusCode::Unavailable);
  EXPECT_NE(status.message.find("RouDi"), std::string::npos) << status.message;
  EXPECT_THROW(client::connectShm(), client::ShmConnectError);

  FakeService fake;
  server::ShmServer server(fake, {}, quietLog());
  EXPECT_EQ(server.start().code, StatusCode::Unavailable);
  EXPECT_THROW(server::ensureRoudi(server::RoudiMode::External, quietLog()), std::runtime_error);
  EXPECT_LT(std::chrono::steady_clock::now() - t0, 3s);
}

TEST(ShmNoRoudi, RoudiModesParse) {
  EXPECT_EQ(server::parseRoudiMode("auto"), server::RoudiMode::Auto);
  EXPECT_EQ(server::parseRoudiMode("external"), server::RoudiMode::External);
  EXPECT_EQ(server::parseRoudiMode("embedded"), server::RoudiMode::Embedded);
  EXPECT_THROW(server::parseRoudiMode("sometimes"), std::invalid_argument);
}

TEST(ShmNoRoudi, OwnRoudiIsStartedWhenNoneRuns) {
  SKIP_IF_ROUDI_RUNS();
  // In a fresh child process: its runtime dies with the RouDi it started.
  const pid_t child = startChild("ShmChild.OwnRoudiRoundTrip", "own-roudi");
  EXPECT_EQ(waitChild(child), 0);
  EXPECT_TRUE(waitUntil([] { return !shm::roudiRunning(); }, 5s)) << "the child's RouDi outlived it";
}

TEST(ShmChild, OwnRoudiRoundTrip) {
  if (childMode() == nullptr) GTEST_SKIP() << "runs only as a child process of the iceoryx tests";
  auto roudi = server::ensureRoudi(server::RoudiMode::Auto, quietLog());
  ASSERT_TRUE(roudi->embedded());
  ASSERT_TRUE(shm::roudiRunning());
  {
    FakeService fake;
    server::ShmServerOptions options;
    options.service = "own-roudi";
    server::ShmServer server(fake, options, quietLog());
    ASSERT_TRUE(server.start().ok());
    auto c = connect("own-roudi");
    ASSERT_TRUE(c);
    rpc::HealthReply health;
    ASSERT_TRUE(c->health({}, health).ok());
    EXPECT_EQ(health.server_instance_id, "fake-server-1");
    // The largest pool is there: a 22 MB reply fits.
    std::vector<double> in(700, 1.0), out(700 * 4000);
    ASSERT_TRUE(c->evaluateBatch("big", 700, in, out).ok());
    // A second ensureRoudi finds it.
    EXPECT_FALSE(server::ensureRoudi(server::RoudiMode::Auto, quietLog())->embedded());
    EXPECT_THROW(server::ensureRoudi(server::RoudiMode::Embedded, quietLog()), std::runtime_error);
    server.stop();
  }
  std::fflush(nullptr);
  // Stop RouDi and leave at once: this process's iceoryx runtime must not outlive it.
  roudi.reset();
  ::_exit(::testing::Test::HasFailure() ? 1 : 0);
}

}  // namespace
}  // namespace robodiff::testing
