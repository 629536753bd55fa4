// robodiffd killed (SIGKILL) and restarted under load: remote calls report UNAVAILABLE
// while it is down and work again once it is back (the client registers its model and
// function on the new server), Local calls keep working throughout, and no call ever
// returns a wrong value.
#include <atomic>
#include <mutex>
#include <thread>

#include "client/client_fixture.hpp"

namespace robodiff::testing {
namespace {

using client::Client;
using client::Mode;
using std::chrono::milliseconds;
using std::chrono::seconds;

struct Counts {
  std::atomic<int> ok_before{0}, ok_during{0}, ok_after{0};
  std::atomic<int> unavailable{0}, deadline{0}, wrong{0};
  std::string first_wrong;
  std::mutex mutex;
  std::string last_failure;  // the latest non-OK status, for a failing test's message
  std::string last() {
    std::lock_guard lock(mutex);
    return last_failure;
  }
};

TEST(ClientRestart, ServerKilledAndRestartedUnderLoad) {
  SharedServer& shared = SharedServer::get();
  TestServer& server = shared.server();
  Client local(server.options(Mode::Local));
  Client shm(server.options(Mode::Shm, seconds(1)));
  Client dds(server.options(Mode::Dds, seconds(1)));
  const std::vector<const Client*> clients = {&local, &shm, &dds};
  std::vector<client::Function> functions;
  for (Client* c : {&local, &shm, &dds}) functions.push_back(c->function(c->loadModel(arm7Text()), kRneaJacobianSpec));
  ASSERT_EQ(functions[0].mode(), Mode::Local);
  ASSERT_EQ(functions[1].mode(), Mode::Shm);
  ASSERT_EQ(functions[2].mode(), Mode::Dds);
  std::vector<RneaReference> refs;
  for (int k = 0; k < 4; ++k) refs.push_back(RneaReference::at(shared.model(), 400 + k));

  std::atomic<int> phase{0};  // 0: serving, 1: killed, 2: restarted
  std::atomic<bool> stop{false};
  std::vector<Counts> counts(3);
  std::vector<std::thread> threads;
  for (std::size_t k = 0; k < functions.size(); ++k)
    threads.emplace_back([&, k] {
      const client::Function& f = functions[k];
      Counts& c = counts[k];
      std::vector<double> out(154);
      for (int i = 0; !stop.load(); ++i) {
        const RneaReference& r = refs[i % refs.size()];
        std::fill(out.begin(), out.end(), std::nan(""));
        const int p = phase.load();
        const Status s = f.evaluate(spanOf(r.inputs), out);
        if (!s.ok()) {
          std::lock_guard lock(c.mutex);
          c.last_failure = toString(s.code) + ": " + s.message;
        }
        if (s.ok() && r.matches(out)) {
          (p == 0 ? c.ok_before : p == 1 ? c.ok_during : c.ok_after)++;
        } else if (s.code == StatusCode::Unavailable && p >= 1) {
          c.unavailable++;
        } else if (s.code == StatusCode::DeadlineExceeded && p >= 1) {
          c.deadline++;  // a call in flight when the server died, before the transport noticed
        } else if (c.wrong++ == 0) {
          c.first_wrong = std::to_string(p) + ": " + toString(s.code) + ": " + s.message;
        }
        std::this_thread::sleep_for(k == 0 ? std::chrono::microseconds(100) : std::chrono::microseconds(2000));
      }
    });
  auto all = [&](auto predicate) {
    for (std::size_t k = 0; k < counts.size(); ++k)
      if (!predicate(k)) return false;
    return true;
  };
  EXPECT_TRUE(waitFor([&] { return all([&](std::size_t k) { return counts[k].ok_before.load() >= 10; }); }));

  phase = 1;
  server.kill();
  EXPECT_TRUE(waitFor([&] { return counts[1].unavailable > 0 && counts[2].unavailable > 0; }, seconds(20)))
      << "shm: " << counts[1].unavailable << " unavailable, " << counts[1].deadline << " deadline; dds: "
      << counts[2].unavailable << " unavailable, " << counts[2].deadline << " deadline; latest: " << counts[1].last()
      << " / " << counts[2].last() << "; log:\n"
      << server.log();
  std::this_thread::sleep_for(milliseconds(200));
  const int local_during = counts[0].ok_during.load();

  server.start();
  phase = 2;  // calls between the start and here count as during the outage (any outcome but a wrong one)
  EXPECT_TRUE(waitFor([&] { return counts[1].ok_after >= 10 && counts[2].ok_after >= 10; }, seconds(30)))
      << "shm " << counts[1].ok_after << ", dds " << counts[2].ok_after
      << " good calls after the restart; latest: " << counts[1].last() << " / " << counts[2].last() << "; log:\n"
      << server.log();
  stop = true;
  for (std::thread& t : threads) t.join();

  for (std::size_t k = 0; k < counts.size(); ++k)
    std::printf("%s: %d good before, %d during, %d after; %d UNAVAILABLE, %d DEADLINE_EXCEEDED, %d wrong\n",
                client::toString(functions[k].mode()), counts[k].ok_before.load(), counts[k].ok_during.load(),
                counts[k].ok_after.load(), counts[k].unavailable.load(), counts[k].deadline.load(),
                counts[k].wrong.load());
  EXPECT_GT(local_during, 100) << "Local calls while the server was down";
  EXPECT_GT(counts[0].ok_after.load(), 0);
  EXPECT_EQ(counts[0].unavailable + counts[0].deadline, 0) << "Local never depends on the server";
  for (std::size_t k = 0; k < counts.size(); ++k)
    EXPECT_EQ(counts[k].wrong.load(), 0) << client::toString(functions[k].mode()) << ": " << counts[k].first_wrong;
  EXPECT_EQ(functions[0].mode(), Mode::Local);
  // The new server knows the function again (registered by the clients), from the cache.
  EXPECT_TRUE(serverCompiled(shm, functions[1].id()));
  (void)clients;
}

}  // namespace
}  // namespace robodiff::testing
