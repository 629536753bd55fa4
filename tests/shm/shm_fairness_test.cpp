// Fair sharing over iceoryx (issue 19, item 5), with a real RouDi and ShmServer on a
// FakeService: a client flooding garbage chunks, or flooding requests, never starves a
// well-behaved client; a client over its queue quota is refused naming the quota.
#include <gtest/gtest.h>

#include <atomic>
#include <cstring>
#include <random>
#include <thread>
#include <vector>

#include "iceoryx_posh/popo/untyped_client.hpp"
#include "shm_test_support.hpp"

namespace robodiff::testing {
namespace {

using namespace std::chrono_literals;

class ShmFairness : public ::testing::Test {
 protected:
  static void SetUpTestSuite() { sharedRoudi(); }
  void SetUp() override {
    service_ = std::string("fair-") + ::testing::UnitTest::GetInstance()->current_test_info()->name();
  }
  void startServer(unsigned threads, std::size_t queue, server::FairLimits fair = {}) {
    fake_ = std::make_unique<FakeService>(threads, queue);
    server::ShmServerOptions options;
    options.service = service_;
    options.fair = fair;
    server_ = std::make_unique<server::ShmServer>(*fake_, options, quietLog());
    const Status s = server_->start();
    ASSERT_TRUE(s.ok()) << s.message;
  }
  void TearDown() override {
    if (server_) server_->stop();
    server_.reset();
    fake_.reset();
  }

  // A foreign iceoryx client sending random bytes as fast as it can until `stop`, on the
  // shared port ("rpc") or on a session it opened; counts the chunks sent and the
  // replies it got back.
  void floodGarbage(const std::atomic<bool>& stop, std::atomic<std::uint64_t>& sent,
                    std::atomic<std::uint64_t>& replies, bool own_session = false) {
    const std::string event = own_session ? openRawSession(service_) : "rpc";
    ASSERT_FALSE(event.empty());
    auto port = rawClient(service_, event);  // waits while the queue is full, as robodiffd requires
    auto& raw = *port;
    std::mt19937_64 random(7);
    while (!stop.load()) {
      const std::uint32_t size = 16 + static_cast<std::uint32_t>(random() % 200);
      auto loaned = raw.loan(size, 8);
      if (!loaned.has_error()) {
        auto* bytes = static_cast<std::uint8_t*>(loaned.value());
        for (std::uint32_t i = 0; i < size; ++i) bytes[i] = static_cast<std::uint8_t>(random());
        if (!raw.send(loaned.value()).has_error()) ++sent;
      }
      for (auto r = raw.take(); !r.has_error(); r = raw.take()) {
        ++replies;
        raw.releaseResponse(r.value());
      }
    }
  }

  std::string service_;
  std::unique_ptr<FakeService> fake_;
  std::unique_ptr<server::ShmServer> server_;
};

// The case: one local process flooding malformed iceoryx requests starved the
// others (55k -> 500 calls/s, deadlines missed: a full iceoryx queue dropped their
// requests). A well-behaved client keeps being served, correctly and within its 2 s
// deadline, and the flooder gets at most its error budget of replies. Here the flooder
// floods the shared port (where sessions open; the client's requests go to its own).
TEST_F(ShmFairness, MalformedFloodDoesNotStarveAWellBehavedClient) {
  startServer(2, 64);
  auto c = connect(service_);
  ASSERT_TRUE(c);
  std::atomic<bool> stop{false};
  std::atomic<std::uint64_t> sent{0}, replies{0};
  std::thread flooder([&] { floodGarbage(stop, sent, replies); });
  // Past its error budget (100 replies a second) every dropped chunk pauses the shared
  // port for 10 ms, so the flooder settles near 200 chunks a second: wait until it is
  // past its budget, not for a count that only an unthrottled flooder reaches.
  if (!waitUntil([&] { return sent.load() > 300; }, 10s)) {
    stop = true;
    flooder.join();
    FAIL() << "the flooder did not get going: " << sent.load() << " chunks sent in 10 s";
  }

  int calls = 0, failures = 0;
  std::string first_failure;
  const auto start = std::chrono::steady_clock::now();
  while (std::chrono::steady_clock::now() - start < 3s) {
    const double base = calls;
    const std::vector<double> in{base, base + 0.5, -base};
    std::vector<double> out(3);
    const Status s = c->evaluate("double", in, out, {2s});
    if (!s.ok() || out[0] != 2 * base || out[1] != 2 * base + 1 || out[2] != -2 * base) {
      if (failures++ == 0) first_failure = toString(s.code) + ": " + s.message;
    } else {
      ++calls;
    }
  }
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  stop = true;
  flooder.join();
  EXPECT_EQ(failures, 0) << "first failure: " << first_failure;
  EXPECT_GE(calls, 100) << "the well-behaved client was starved";
  EXPECT_GT(sent.load(), replies.load()) << "every chunk of the flooder was answered: its error budget did not engage";
  // 100 error replies per client per second, the rest dropped unanswered.
  EXPECT_LE(replies.load(), static_cast<std::uint64_t>(100 * (seconds + 6))) << sent.load() << " garbage chunks sent";
  // A client that will not wait while the queue is full (the iceoryx default: drop the
  // oldest request) is not connected at all.
  iox::popo::UntypedClient dropper(
      {"robodiff", iox::capro::IdString_t(iox::cxx::TruncateToCapacity, service_.c_str()), "rpc"});
  std::this_thread::sleep_for(200ms);
  EXPECT_NE(dropper.getConnectionState(), iox::ConnectionState::CONNECTED);
  std::printf("well-behaved: %d calls in %.1f s while the flooder sent %llu garbage chunks (%llu answered)\n", calls,
              seconds, static_cast<unsigned long long>(sent.load()), static_cast<unsigned long long>(replies.load()));
}

// A flooder on its own session (what a connection's port is) fills only its own queue:
// past its error budget the server stops taking from it for the rest of the second. A
// well-behaved client misses no deadline (50 ms) and a client connecting meanwhile opens
// its session at once.
TEST_F(ShmFairness, GarbageFloodOnItsOwnSessionDoesNotDelayOthers) {
  startServer(2, 64);
  auto c = connect(service_);
  ASSERT_TRUE(c);
  std::atomic<bool> stop{false};
  std::atomic<std::uint64_t> sent{0}, replies{0};
  std::thread flooder([&] { floodGarbage(stop, sent, replies, /*own_session=*/true); });
  // Past its 100 error replies the flooder's session is paused: it sends its queue full
  // (16) and then waits in its send until the next second.
  if (!waitUntil([&] { return sent.load() > 110; }, 5s)) {
    stop = true;
    flooder.join();
    FAIL() << "the flooder did not get going";
  }

  int calls = 0, misses = 0, errors = 0;
  std::string first_failure;
  const auto start = std::chrono::steady_clock::now();
  while (std::chrono::steady_clock::now() - start < 2s) {
    const double base = calls;
    const std::vector<double> in{base, 1, 2};
    std::vector<double> out(3);
    const Status s = c->evaluate("double", in, out, {50ms});
    if (s.code == StatusCode::DeadlineExceeded) ++misses;
    else if (!s.ok() || out[0] != 2 * base) ++errors, first_failure = toString(s.code) + ": " + s.message;
    else ++calls;
  }
  const auto t0 = std::chrono::steady_clock::now();
  auto late = connect(service_);
  const auto connect_time = std::chrono::steady_clock::now() - t0;
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  stop = true;
  flooder.join();
  EXPECT_EQ(misses, 0);
  EXPECT_EQ(errors, 0) << first_failure;
  EXPECT_GE(calls, 200) << "the well-behaved client was slowed down";
  ASSERT_TRUE(late);
  EXPECT_LT(connect_time, 1s);
  EXPECT_LE(replies.load(), static_cast<std::uint64_t>(100 * (seconds + 3))) << sent.load() << " garbage chunks sent";
  EXPECT_LE(sent.load(), static_cast<std::uint64_t>(150 * (seconds + 3))) << "the paused session was drained";
  std::printf("well-behaved: %d calls in 2 s while the flooder sent %llu garbage chunks on its session (%llu answered)\n",
              calls, static_cast<unsigned long long>(sent.load()), static_cast<unsigned long long>(replies.load()));
}

// A client flooding slow posted requests keeps at most max_running of them in the
// service: another client's request waits for at most those, not for the whole flood.
TEST_F(ShmFairness, PostedFloodDoesNotStarveAnotherClient) {
  startServer(/*threads=*/1, /*queue=*/64, {64, 1});
  auto flood = connect(service_, 30s);
  ASSERT_TRUE(flood);
  std::vector<std::thread> flooders;
  std::atomic<int> flood_done{0};
  for (int i = 0; i < 12; ++i)
    flooders.emplace_back([&] {
      rpc::LoadModelReply model;
      if (flood->loadModel({"slow:100", false, ""}, model).ok()) ++flood_done;
    });
  ASSERT_TRUE(waitUntil([&] { return fake_->loadModelsStarted() >= 1; }, 5s));
  std::this_thread::sleep_for(20ms);  // the flood is queued by now
  auto other = connect(service_);
  ASSERT_TRUE(other);
  rpc::HealthReply health;
  const auto t0 = std::chrono::steady_clock::now();
  const Status s = other->health({}, health);
  const auto waited = std::chrono::steady_clock::now() - t0;
  EXPECT_TRUE(s.ok()) << s.message;
  // Behind at most the flooder's running LoadModel (100 ms), not its 12 (1.2 s).
  EXPECT_LT(waited, 400ms) << "Health waited behind the flood";
  for (auto& t : flooders) t.join();
  EXPECT_EQ(flood_done.load(), 12);
}

// Over its quota of pending requests, a client is refused RESOURCE_EXHAUSTED naming the
// limit and its value; other clients are unaffected.
TEST_F(ShmFairness, ClientOverItsQueueQuotaIsRefusedNamingTheQuota) {
  startServer(/*threads=*/1, /*queue=*/64, {3, 1});
  auto c = connect(service_);
  ASSERT_TRUE(c);
  std::atomic<int> ok{0}, exhausted{0};
  std::string message;
  std::mutex message_mutex;
  std::vector<std::thread> callers;
  for (int i = 0; i < 6; ++i)
    callers.emplace_back([&] {
      rpc::LoadModelReply model;
      const Status s = c->loadModel({"slow:200", false, ""}, model);
      if (s.ok()) ++ok;
      if (s.code == StatusCode::ResourceExhausted) {
        ++exhausted;
        std::lock_guard lock(message_mutex);
        message = s.message;
      }
    });
  std::this_thread::sleep_for(50ms);
  auto other = connect(service_);
  std::vector<double> in{1, 2, 3}, out(3);
  EXPECT_TRUE(other->evaluate("double", in, out).ok());
  for (auto& t : callers) t.join();
  EXPECT_GE(ok.load(), 3);
  EXPECT_GE(exhausted.load(), 1);
  EXPECT_EQ(ok + exhausted, 6);
  EXPECT_NE(message.find("limits.max_queued_requests_per_client = 3"), std::string::npos) << message;
}

}  // namespace
}  // namespace robodiff::testing
