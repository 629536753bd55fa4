// Process faults: robodiffd stopped (SIGSTOP) long enough for RouDi to drop it. iceoryx
// 2.0 frees a dropped process's ports, and robodiffd used to abort on them at its next
// SIGTERM (POPO__CHUNK_LOCKING_ERROR) while /readyz still said ok. Now it notices the
// pause, says so, drains what it can and exits with 4 for its supervisor to restart it.
#include <signal.h>

#include <chrono>
#include <thread>

#include "robodiffd/service_fixture.hpp"

namespace robodiff::testing {
namespace {

using namespace std::chrono_literals;

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

}  // namespace
}  // namespace robodiff::testing
