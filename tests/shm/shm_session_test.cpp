// Sessions over iceoryx (issue 19, item 5): every connection gets its own request queue on
// the server. Opened and closed many times without growth; the shared port answers only
// session opens; the number of sessions is capped, naming the limit.
#include <gtest/gtest.h>

#include <chrono>
#include <cstring>
#include <vector>

#include "shm_test_support.hpp"

namespace robodiff::testing {
namespace {

using namespace std::chrono_literals;

class ShmSessions : public ::testing::Test {
 protected:
  static void SetUpTestSuite() { sharedRoudi(); }
  void SetUp() override {
    service_ = std::string("sess-") + ::testing::UnitTest::GetInstance()->current_test_info()->name();
  }
  void startServer(std::uint32_t max_sessions = 64) {
    fake_ = std::make_unique<FakeService>(2, 64);
    server::ShmServerOptions options;
    options.service = service_;
    options.sessions.max_sessions = max_sessions;
    server_ = std::make_unique<server::ShmServer>(*fake_, options, quietLog());
    const Status s = server_->start();
    ASSERT_TRUE(s.ok()) << s.message;
  }
  void TearDown() override {
    if (server_) server_->stop();
    server_.reset();
    fake_.reset();
  }
  static bool evaluates(client::ShmConnection& c) {
    std::vector<double> in{1, 2, 3}, out(3);
    return c.evaluate("double", in, out).ok() && out[2] == 6.0;
  }

  std::string service_;
  std::unique_ptr<FakeService> fake_;
  std::unique_ptr<server::ShmServer> server_;
};

// 200 connections opened, used and closed one after another: every session is closed
// again (its iceoryx server port freed), and RouDi still serves a new connection.
TEST_F(ShmSessions, OpenAndCloseManyWithoutLeak) {
  startServer();
  auto keeper = connect(service_);
  ASSERT_TRUE(keeper && evaluates(*keeper));
  ASSERT_TRUE(waitUntil([&] { return server_->openSessions() == 1; }, 2s));
  const auto t0 = std::chrono::steady_clock::now();
  for (int i = 0; i < 200; ++i) {
    auto c = connect(service_);
    ASSERT_TRUE(c) << "connection " << i;
    ASSERT_TRUE(evaluates(*c)) << "connection " << i;
    c.reset();
    // Closed sessions are swept every 200 ms: let them go before the cap (64) is reached.
    if (i % 20 == 19) {
      ASSERT_TRUE(waitUntil([&] { return server_->openSessions() == 1; }, 5s)) << i;
    }
  }
  const double per_connection_ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count() / 200;
  EXPECT_TRUE(waitUntil([&] { return server_->openSessions() == 1; }, 5s)) << server_->openSessions() << " open";
  auto last = connect(service_);
  ASSERT_TRUE(last && evaluates(*last));
  EXPECT_TRUE(evaluates(*keeper));
  std::printf("200 sessions opened and closed, %.1f ms per connection\n", per_connection_ms);
}

// A request sent straight to the shared port (a client library without sessions) is
// refused with a clear error; the port still opens sessions.
TEST_F(ShmSessions, SharedPortRefusesARequestWithAClearError) {
  startServer();
  auto raw = rawClient(service_, "rpc");
  ASSERT_EQ(raw->getConnectionState(), iox::ConnectionState::CONNECTED);
  const Status s = rawExchange(*raw, static_cast<std::uint32_t>(shm::chunkSize(0, 0)), [](std::byte* chunk) {
    rpc::RequestHeader h;
    h.client_id = "old-client";
    shm::writeRequestHeader(chunk, h, rpc::Method::Health, 0);
  });
  EXPECT_EQ(s.code, StatusCode::FailedPrecondition) << s.message;
  EXPECT_NE(s.message.find("session"), std::string::npos) << s.message;
  EXPECT_NE(s.message.find("robodiff/" + service_ + "/rpc"), std::string::npos) << s.message;
  Status opened;
  EXPECT_FALSE(openRawSession(service_, &opened).empty()) << opened.message;
}

// At max_sessions the next open is RESOURCE_EXHAUSTED naming the limit; once a
// connection closes, its session is freed and a new one opens.
TEST_F(ShmSessions, SessionCapIsResourceExhaustedNamingTheLimit) {
  startServer(/*max_sessions=*/3);
  std::vector<std::unique_ptr<client::ShmConnection>> held;
  for (int i = 0; i < 3; ++i) {
    held.push_back(connect(service_));
    ASSERT_TRUE(held.back() && evaluates(*held.back()));
  }
  client::ShmConnectionOptions options;
  options.service = service_;
  Status status;
  EXPECT_EQ(client::connectShm(options, status), nullptr);
  EXPECT_EQ(status.code, StatusCode::ResourceExhausted) << status.message;
  EXPECT_NE(status.message.find("limits.max_shm_sessions = 3"), std::string::npos) << status.message;
  EXPECT_TRUE(evaluates(*held[0]));  // the others are unaffected

  held.pop_back();
  ASSERT_TRUE(waitUntil([&] { return server_->openSessions() == 2; }, 5s));
  auto again = connect(service_);
  ASSERT_TRUE(again && evaluates(*again));
}

// A session whose client never connects is closed after the grace period.
TEST_F(ShmSessions, UnusedSessionIsClosed) {
  fake_ = std::make_unique<FakeService>(2, 64);
  server::ShmServerOptions options;
  options.service = service_;
  options.sessions.connect_grace = 300ms;
  server_ = std::make_unique<server::ShmServer>(*fake_, options, quietLog());
  ASSERT_TRUE(server_->start().ok());
  ASSERT_FALSE(openRawSession(service_).empty());
  EXPECT_EQ(server_->openSessions(), 1u);
  EXPECT_TRUE(waitUntil([&] { return server_->openSessions() == 0; }, 3s));
}

}  // namespace
}  // namespace robodiff::testing
