// Process faults: robodiffd stopped (SIGSTOP) long enough for RouDi to drop it. iceoryx
// 2.0 frees a dropped process's ports, and robodiffd used to abort on them at its next
// SIGTERM (POPO__CHUNK_LOCKING_ERROR) while /readyz still said ok. Now it notices the
// pause, says so, drains what it can and exits with 4 for its supervisor to restart it.
// And at start: a RouDi it must start but cannot (no iox-roudi) is named at once.
#include <signal.h>

#include <chrono>
#include <thread>

#include "robodiffd/service_fixture.hpp"
#include "support/cache_workspace.hpp"
#include "support/process.hpp"
#include "robodiff/schema/shm_runtime.hpp"

namespace robodiff::testing {
namespace {

using namespace std::chrono_literals;

// A RouDi robodiffd must start (roudi = embedded) with no iox-roudi in PATH: it says so
// at once and exits non-zero, rather than failing an exec it cannot tell apart.
TEST(ProcessFaults, AMissingIoxRoudiIsNamedAtStart) {
  if (shm::roudiRunning()) GTEST_SKIP() << "a RouDi is already running on this host; embedded mode would refuse first";
  TempDir dir;
  std::filesystem::create_directory(dir / "empty-bin");
  useLoopbackDds();
  const std::string command = "PATH=" + shellQuote((dir / "empty-bin").string()) + " " +
                              shellQuote(robodiffdPath().string()) + " --cache " + shellQuote((dir / "cache").string()) +
                              " --dds-domain " + std::to_string(testDomain()) +
                              " --roudi embedded --no-http --log-format json";
  const ProcessResult r = runCommand(command);
  EXPECT_NE(r.exit_code, 0) << r.out << r.err;
  const nlohmann::json failed = logEvent(r.out + r.err, "startup_failed");
  ASSERT_FALSE(failed.is_null()) << r.out << r.err;
  EXPECT_EQ(failed.value("message", ""), "cannot start a RouDi: iox-roudi is not in PATH (package iceoryx)");
  EXPECT_FALSE(shm::roudiRunning());
}

TEST(ProcessFaults, APauseLongEnoughForRouDiToDropItEndsInExitCode4) {
  signal(SIGTERM, SIG_IGN);  // see end_to_end_test.cpp
  RoudiProcess& roudi = sharedRoudi();
  (void)roudi;
  TempDir dir;
  RobodiffdProcess server(dir / "cache", dir / "robodiffd.log",
                          {"--roudi", "external", "--no-http", "--drain-timeout", "2"});
  ASSERT_TRUE(server.running());
  ::kill(server.pid(), SIGSTOP);
  std::this_thread::sleep_for(3s);  // past RouDi's keep-alive timeout: it drops the process
  ::kill(server.pid(), SIGCONT);

  const int code = server.waitExit(5s);  // the drain timeout (2 s) and a margin
  EXPECT_EQ(code, 4) << server.log();
  const std::string log = server.log();
  EXPECT_NE(log.find("\"event\":\"iceoryx_lost\""), std::string::npos) << log;
  EXPECT_EQ(log.find("POPO__CHUNK_LOCKING_ERROR"), std::string::npos) << log;
  EXPECT_EQ(log.find("Assertion"), std::string::npos) << log;

  // RouDi still serves a new robodiffd (the supervisor's restart).
  RobodiffdProcess restarted(dir / "cache", dir / "robodiffd-2.log", {"--roudi", "external", "--no-http"});
  ASSERT_TRUE(restarted.running());
  auto client = connectTo("iceoryx");
  rpc::HealthReply health;
  EXPECT_TRUE(client->health({}, health).ok());
  EXPECT_EQ(restarted.terminate(std::chrono::seconds(30)), 0) << restarted.log();
}

// A RouDi restart (the supervisor's remedy when a process killed while holding a port's
// mutex hangs RouDi, deploy/README.md): the running robodiffd's iceoryx runtime belongs to
// the old RouDi, so it must exit 4 and a new one serve. Clients run as CLI processes: this
// test process must not register with a RouDi that it then kills.
TEST(ProcessFaults, ARouDiRestartEndsInExitCode4AndANewRobodiffdServes) {
  signal(SIGTERM, SIG_IGN);
  if (shm::roudiRunning()) GTEST_SKIP() << "this test must own RouDi: run it alone (ctest runs each test alone)";
  TempDir dir;
  const std::string health = cli("health --server shm --timeout 5");
  auto first = std::make_unique<RoudiProcess>();
  RobodiffdProcess server(dir / "cache", dir / "robodiffd.log",
                          {"--roudi", "external", "--no-http", "--drain-timeout", "2"});
  ASSERT_TRUE(server.running());
  ProcessResult r = runCommand(health);
  ASSERT_EQ(r.exit_code, 0) << r.out << r.err;

  first->stop();  // SIGKILL, leftovers removed: as a supervisor ends a hung RouDi
  std::this_thread::sleep_for(1s);
  EXPECT_EQ(server.waitExit(0s), -1) << "no RouDi is not a reason to exit: DDS still serves\n" << server.log();
  RoudiProcess second;

  const int code = server.waitExit(6s);  // noticed within 250 ms, then the 2 s drain
  EXPECT_EQ(code, 4) << server.log();
  const std::string log = server.log();
  EXPECT_NE(log.find("\"event\":\"iceoryx_lost\""), std::string::npos) << log;
  EXPECT_NE(log.find("RouDi was restarted"), std::string::npos) << log;

  RobodiffdProcess restarted(dir / "cache", dir / "robodiffd-2.log", {"--roudi", "external", "--no-http"});
  ASSERT_TRUE(restarted.running());
  r = runCommand(health);
  EXPECT_EQ(r.exit_code, 0) << r.out << r.err << restarted.log();
  EXPECT_EQ(restarted.terminate(std::chrono::seconds(30)), 0) << restarted.log();
}

}  // namespace
}  // namespace robodiff::testing
