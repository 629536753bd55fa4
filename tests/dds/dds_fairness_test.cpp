// Fair sharing over DDS (issue 19, item 5): requests wait in one lane per writer and are
// served in turn; a writer flooding slow requests keeps at most max_running of them in the
// service, and one over its quota of pending requests is refused naming the quota.

#include <gtest/gtest.h>

#include <atomic>
#include <mutex>
#include <thread>
#include <vector>

#include "dds_test_env.hpp"
#include "fake_service.hpp"
#include "robodiff/client/dds_connection.hpp"
#include "robodiff/server/dds_server.hpp"

namespace robodiff {
namespace {

using namespace std::chrono_literals;
using client::DdsConnection;
using client::DdsConnectionOptions;
using server::DdsServer;
using server::DdsServerOptions;
using testing::FakeService;

class DdsFairness : public testing::DdsTest {
 protected:
  std::unique_ptr<DdsServer> startServer(FakeService& service, server::FairLimits fair) {
    DdsServerOptions o;
    o.domain_id = domain_;
    o.fair = fair;
    auto server = std::make_unique<DdsServer>(service, o, log_);
    server->start();
    return server;
  }
  DdsConnectionOptions clientOptions() const {
    DdsConnectionOptions o;
    o.domain_id = domain_;
    o.connection.default_timeout = 10s;
    o.match_timeout = 10s;
    return o;
  }
  const std::uint32_t domain_ = testing::testDomain();
  server::Logger log_{stderr, server::LogLevel::Error};
};

TEST_F(DdsFairness, AWriterOverItsQueueQuotaIsRefusedNamingTheQuota) {
  FakeService service("srv-fair", /*threads=*/1);
  auto server = startServer(service, {3, 1});
  DdsConnection c(clientOptions());
  std::atomic<int> ok{0}, exhausted{0};
  std::string message;
  std::mutex message_mutex;
  std::vector<std::thread> callers;
  for (int i = 0; i < 6; ++i)
    callers.emplace_back([&] {
      rpc::LoadModelReply model;
      const Status s = c.loadModel({"sleep:300", false, ""}, model);
      if (s.ok()) ++ok;
      if (s.code == StatusCode::ResourceExhausted) {
        ++exhausted;
        std::lock_guard lock(message_mutex);
        message = s.message;
      }
    });
  for (auto& t : callers) t.join();
  EXPECT_GE(ok.load(), 3);
  EXPECT_GE(exhausted.load(), 1);
  EXPECT_EQ(ok + exhausted, 6);
  EXPECT_NE(message.find("limits.max_queued_requests_per_client = 3"), std::string::npos) << message;
}

TEST_F(DdsFairness, APostedFloodDoesNotStarveAnotherWriter) {
  FakeService service("srv-fair", /*threads=*/1);
  auto server = startServer(service, {64, 1});
  DdsConnection flood(clientOptions()), other(clientOptions());
  std::vector<std::thread> flooders;
  std::atomic<int> flood_ok{0};
  for (int i = 0; i < 10; ++i)
    flooders.emplace_back([&] {
      rpc::LoadModelReply model;
      if (flood.loadModel({"sleep:100", false, ""}, model).ok()) ++flood_ok;
    });
  std::this_thread::sleep_for(150ms);  // the flood is queued by now
  rpc::HealthReply health;
  const auto t0 = std::chrono::steady_clock::now();
  const Status s = other.health({}, health);
  const auto waited = std::chrono::steady_clock::now() - t0;
  EXPECT_TRUE(s.ok()) << s.message;
  // Behind at most the flooder's running LoadModel (100 ms), not its queue (~1 s).
  EXPECT_LT(waited, 450ms) << "Health waited behind the flood";
  for (auto& t : flooders) t.join();
  EXPECT_EQ(flood_ok.load(), 10);
}

}  // namespace
}  // namespace robodiff
