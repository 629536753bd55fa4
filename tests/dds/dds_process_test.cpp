// Processes killed mid-request. A client: the server finishes the request, its reply goes
// nowhere, and other clients are served all along. A server: its clients' pending calls end
// UNAVAILABLE within about its lease. The child is this test binary started again (fork +
// exec, so it gets a clean DDS runtime) with ROBODIFF_DDS_TEST_CHILD or _SERVER set; it then
// plays its part from a static initialiser, before gtest runs anything.

#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <future>
#include <thread>
#include <string>
#include <vector>

#include "dds_test_env.hpp"
#include "fake_service.hpp"
#include "robodiff/client/dds_connection.hpp"
#include "robodiff/server/dds_server.hpp"

extern char** environ;

namespace robodiff {
namespace {

using namespace std::chrono_literals;
constexpr const char* kChildVariable = "ROBODIFF_DDS_TEST_CHILD";  // "<domain>"
constexpr const char* kServerVariable = "ROBODIFF_DDS_TEST_SERVER";  // "<domain>"
constexpr const char* kChildClientId = "dds-test-child-to-be-killed";

// In the child: one LoadModel that takes seconds; the parent kills the process meanwhile.
int runChildIfAsked() {
  const char* domain = std::getenv(kChildVariable);
  if (!domain) return 0;
  try {
    client::DdsConnectionOptions options;
    options.domain_id = static_cast<std::uint32_t>(std::stoul(domain));
    options.connection.client_id = kChildClientId;
    options.match_timeout = 20s;
    auto connection = client::connectDds(options);
    rpc::LoadModelReply reply;
    connection->loadModel({"sleep:1500", false, ""}, reply, client::CallOptions{30s});
  } catch (...) {
    _exit(3);
  }
  _exit(0);
}
const int child_ran = runChildIfAsked();

// In the child: a server (lease 1 s) that runs until it is killed.
int runServerIfAsked() {
  const char* domain = std::getenv(kServerVariable);
  if (!domain) return 0;
  try {
    testing::FakeService service("srv-child");
    server::Logger log(stderr, server::LogLevel::Warn);
    server::DdsServerOptions options;
    options.domain_id = static_cast<std::uint32_t>(std::stoul(domain));
    options.lease = 1s;
    server::DdsServer server(service, options, log);
    server.start();
    std::this_thread::sleep_for(60s);  // the parent kills it long before
  } catch (...) {
    _exit(3);
  }
  _exit(0);
}
const int server_ran = runServerIfAsked();

// Starts this test binary again with `variable`=`value`; the environment and arguments are
// built before fork, so that only exec runs in the child.
pid_t spawnSelf(const char* variable, const std::string& value) {
  std::vector<std::string> env_strings;
  for (char** e = environ; *e; ++e) env_strings.emplace_back(*e);
  env_strings.push_back(std::string(variable) + "=" + value);
  std::vector<char*> envp;
  for (auto& s : env_strings) envp.push_back(s.data());
  envp.push_back(nullptr);
  std::string self = "/proc/self/exe", filter = "--gtest_filter=-*";
  char* argv[] = {self.data(), filter.data(), nullptr};
  const pid_t child = fork();
  if (child == 0) {
    execve("/proc/self/exe", argv, envp.data());
    _exit(127);
  }
  return child;
}

TEST(DdsProcess, ClientKilledMidRequestDoesNotDisturbTheServer) {
  (void)child_ran;
  (void)server_ran;
  testing::useLoopbackConfig();
  // A domain of its own: the killed participant lingers there until its lease expires.
  const std::uint32_t domain = testing::testDomain(1);
  testing::FakeService service("srv-survivor");
  server::Logger log(stderr, server::LogLevel::Warn);
  server::DdsServerOptions server_options;
  server_options.domain_id = domain;
  server::DdsServer server(service, server_options, log);
  server.start();

  const pid_t child = spawnSelf(kChildVariable, std::to_string(domain));
  ASSERT_GT(child, 0);

  const bool started = service.waitLoadModelFrom(kChildClientId, 15s);
  kill(child, SIGKILL);
  int status = 0;
  waitpid(child, &status, 0);
  ASSERT_TRUE(started) << "the child's request never reached the server";
  EXPECT_TRUE(WIFSIGNALED(status));

  client::DdsConnectionOptions options;
  options.domain_id = domain;
  options.match_timeout = 10s;
  client::DdsConnection survivor(options);
  std::vector<double> out(3), batch_out(50 * 3), batch_in(50 * 3, 1.25);
  for (int i = 0; i < 50; ++i) {
    const Status s = survivor.evaluate("fn-double", std::vector<double>{1, 2, double(i)}, out);
    ASSERT_TRUE(s.ok()) << s.message;
    EXPECT_EQ(out[2], 2.0 * i);
  }
  const Status s = survivor.evaluateBatch("fn-double", 50, batch_in, batch_out);
  ASSERT_TRUE(s.ok()) << s.message;
  EXPECT_EQ(batch_out[149], 2.5);
  rpc::HealthReply health;
  ASSERT_TRUE(survivor.health({}, health).ok());
  // The dead client's request finished too (its reply went nowhere).
  EXPECT_TRUE(server.waitIdle(5s));
  EXPECT_EQ(server.inFlight(), 0u);
}

TEST(DdsProcess, ServerKilledMidCallIsUnavailableWithinItsLease) {
  testing::useLoopbackConfig();
  const std::uint32_t domain = testing::testDomain(1);
  const pid_t child = spawnSelf(kServerVariable, std::to_string(domain));
  ASSERT_GT(child, 0);
  client::DdsConnectionOptions options;
  options.domain_id = domain;
  options.match_timeout = 15s;
  options.connection.server_instance_id = "srv-child";
  client::DdsConnection connection(options);
  rpc::HealthReply health;
  const Status first = connection.health({}, health);
  if (!first.ok()) {
    kill(child, SIGKILL);
    waitpid(child, nullptr, 0);
    FAIL() << first.message;
  }
  EXPECT_EQ(health.server_instance_id, "srv-child");
  auto slow = std::async(std::launch::async, [&] {
    rpc::LoadModelReply model;
    return connection.loadModel({"sleep:5000", false, ""}, model, client::CallOptions{20s});
  });
  std::this_thread::sleep_for(300ms);  // the request reaches the server
  const auto killed = std::chrono::steady_clock::now();
  kill(child, SIGKILL);
  waitpid(child, nullptr, 0);
  const Status s = slow.get();
  const auto took = std::chrono::steady_clock::now() - killed;
  EXPECT_EQ(s.code, StatusCode::Unavailable) << s.message;
  EXPECT_LT(took, 3s) << "the server's lease is 1 s";
  RecordProperty("unavailable_after_ms",
                 std::to_string(std::chrono::duration_cast<std::chrono::milliseconds>(took).count()));

  // A new server process: the same connection finds it.
  const pid_t again = spawnSelf(kServerVariable, std::to_string(domain));
  ASSERT_GT(again, 0);
  const auto restarted = std::chrono::steady_clock::now();
  const Status back = connection.health({}, health, client::CallOptions{10s});
  const auto rematch = std::chrono::steady_clock::now() - restarted;
  kill(again, SIGKILL);
  waitpid(again, nullptr, 0);
  ASSERT_TRUE(back.ok()) << back.message;
  std::fprintf(stderr, "restarted server answered after %lld ms\n",
               static_cast<long long>(std::chrono::duration_cast<std::chrono::milliseconds>(rematch).count()));
}

}  // namespace
}  // namespace robodiff
