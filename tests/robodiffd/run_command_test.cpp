// The README's run command after its build step (scripts/run-service.sh) in a terminal:
// robodiffd starts, the Panda (or arm7) is warmed through it, a client prints its
// timings, the dashboard's address is shown, then it serves until the terminal's Ctrl-C
// and stops cleanly: exit status 0, robodiffd drained ("stopped clean=true") and gone.
// Run through a pseudo-terminal (forkpty), as a person would; robodiffd gets this test's
// cache, DDS domain, RouDi and an ephemeral HTTP port through the script's test hooks.
#include <poll.h>
#include <pty.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <regex>
#include <string>
#include <thread>

#include "robodiffd/service_fixture.hpp"

namespace robodiff::testing {
namespace {

using namespace std::chrono_literals;
using Clock = std::chrono::steady_clock;

// Reads what the terminal shows into `out` until `until` holds, the child closes it, or
// `timeout` passes; true when `until` held.
template <class Until>
bool readTerminal(int master, std::string& out, std::chrono::milliseconds timeout, Until until) {
  const auto deadline = Clock::now() + timeout;
  char buffer[4096];
  while (!until(out)) {
    const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(deadline - Clock::now()).count();
    if (left <= 0) return false;
    pollfd p{master, POLLIN, 0};
    if (::poll(&p, 1, static_cast<int>(std::min<long long>(left, 200))) <= 0) continue;
    const ssize_t n = ::read(master, buffer, sizeof buffer);
    if (n <= 0) return until(out);  // EIO: the child side closed
    out.append(buffer, static_cast<std::size_t>(n));
  }
  return true;
}

TEST(RunCommand, ServesUntilCtrlCThenStopsRobodiffdCleanly) {
  signal(SIGTERM, SIG_IGN);  // as the other robodiffd tests
  sharedRoudi();             // the script's robodiffd uses it (--roudi external)
  useLoopbackDds();
  TempDir dir;
  const std::filesystem::path build = robodiffdPath().parent_path().parent_path();
  const std::filesystem::path log = dir / "run-robodiffd.log";
  const std::string domain = std::to_string(testDomain());

  int master = -1;
  const pid_t pid = ::forkpty(&master, nullptr, nullptr, nullptr);
  ASSERT_GE(pid, 0) << "forkpty failed";
  if (pid == 0) {
    signal(SIGTERM, SIG_DFL);
    if (::chdir(sourceDir().c_str()) != 0) _exit(126);
    const std::string robodiffd_args = "--cache " + (dir / "cache").string() + " --http 127.0.0.1:0 --dds-domain " +
                                       domain + " --roudi external";
    setenv("ROBODIFFD_ARGS", robodiffd_args.c_str(), 1);
    setenv("SERVICE_DEMO_ARGS", ("--dds-domain " + domain).c_str(), 1);
    setenv("ROBODIFF_SERVER", ("dds:" + domain).c_str(), 1);
    setenv("ROBODIFF_RUN_LOG", log.c_str(), 1);
    unsetenv("ROBODIFF_RUN_HOLD");
    execl("/bin/bash", "bash", "scripts/run-service.sh", build.c_str(), static_cast<char*>(nullptr));
    _exit(127);
  }

  // Whatever happens below, nothing of the script is left running: its session (the
  // script, robodiffd) gets SIGTERM, then SIGKILL.
  bool reaped_script = false;
  struct StopSession {
    pid_t pid;
    bool& reaped;
    ~StopSession() {
      if (reaped) return;
      ::kill(-pid, SIGTERM);
      std::this_thread::sleep_for(2s);
      ::kill(-pid, SIGKILL);
      ::waitpid(pid, nullptr, 0);
    }
  } stop_session{pid, reaped_script};

  std::string screen;
  const bool waiting = readTerminal(master, screen, 180s, [](const std::string& s) {
    return s.find("press Ctrl-C") != std::string::npos || s.find("exited with status") != std::string::npos;
  });
  ASSERT_TRUE(waiting) << "the script did not reach its wait for Ctrl-C; terminal:\n" << screen;
  EXPECT_NE(screen.find("press Ctrl-C"), std::string::npos) << screen;
  EXPECT_TRUE(std::regex_search(screen, std::regex(R"(Dashboard: http://127\.0\.0\.1:[1-9][0-9]*/)"))) << screen;
  EXPECT_TRUE(std::regex_search(screen, std::regex(R"(Evaluate x2000 \(compiled library\): p50 [0-9.]+ us)")))
      << screen;
  EXPECT_NE(screen.find("3 functions:"), std::string::npos) << screen;  // warmed through the server
  // A user function's 20-knot horizon in one batch call.
  EXPECT_TRUE(std::regex_search(screen, std::regex(R"(20 knots in one evaluateBatch via [a-z]+[^\n]*\s+horizon: p50 [0-9.]+ us)")))
      << screen;

  // The terminal's Ctrl-C: SIGINT to the foreground process group (the script, robodiffd).
  const char ctrl_c = '\x03';
  ASSERT_EQ(::write(master, &ctrl_c, 1), 1);
  readTerminal(master, screen, 60s, [](const std::string&) { return false; });  // until it closes
  int status = 0;
  const auto deadline = Clock::now() + 30s;
  pid_t reaped = 0;
  while ((reaped = ::waitpid(pid, &status, WNOHANG)) == 0 && Clock::now() < deadline)
    std::this_thread::sleep_for(50ms);
  ::close(master);
  ASSERT_EQ(reaped, pid) << "the script did not end after Ctrl-C; terminal:\n" << screen;
  reaped_script = true;
  EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << "status " << status << "; terminal:\n" << screen;
  EXPECT_NE(screen.find("robodiffd exited with status 0"), std::string::npos) << screen;
  const std::string robodiffd_log = readFile(log);
  EXPECT_NE(robodiffd_log.find("stopped clean=true"), std::string::npos) << robodiffd_log;
  // Nothing of it left: robodiffd's pid (from its log) no longer exists.
  std::smatch pid_match;
  ASSERT_TRUE(std::regex_search(robodiffd_log, pid_match, std::regex(R"(instance_id=[^:\s]+:([0-9]+):)")))
      << robodiffd_log;
  const pid_t daemon = static_cast<pid_t>(std::stol(pid_match[1]));
  EXPECT_NE(::kill(daemon, 0), 0) << "robodiffd (pid " << daemon << ") still runs";
}

}  // namespace
}  // namespace robodiff::testing
