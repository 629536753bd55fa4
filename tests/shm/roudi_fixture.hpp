// A real RouDi for tests: `iox-roudi -c <source>/deploy/roudi.toml` as a child process.
// Include as "shm/roudi_fixture.hpp" from any test folder.
//
//   RoudiProcess roudi;            // started (or an already running RouDi reused), ready
//   roudi.stop();                  // or at destruction: SIGINT, SIGKILL after 5 s
//   sharedRoudi();                 // one RouDi for the rest of this test process
//
// iceoryx allows one runtime per process and one RouDi per host, and a runtime does not
// survive its RouDi: a test process that has talked to one RouDi must not use the next.
// So tests in one process share sharedRoudi(); ctest runs each test in its own process,
// and the "roudi" RESOURCE_LOCK keeps RouDi tests from running side by side.
//
// Trap: RouDi 2.0.3 aborts at shutdown (POSH__ROUDI_PROCESS_SHUTDOWN_FAILED) while a
// process killed with SIGKILL is still registered; its monitoring removes such a process
// ~1.5 s after death, so a test that kills an iceoryx process waits that long before it
// ends. Set ROBODIFF_KEEP_ROUDI_LOG=1 to keep RouDi's output (/tmp/robodiff-test-roudi-<pid>.log).
#pragma once

#include <fcntl.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <memory>
#include <sstream>
#include <stdexcept>
#include <string>
#include <thread>

#include <gtest/gtest.h>

#include "robodiff/schema/shm_runtime.hpp"
#include "support/test_paths.hpp"

namespace robodiff::testing {

class RoudiProcess {
 public:
  explicit RoudiProcess(std::filesystem::path config = sourceDir() / "deploy" / "roudi.toml",
                        std::chrono::milliseconds timeout = std::chrono::seconds(10)) {
    using namespace std::chrono_literals;
    if (shm::roudiRunning()) return;  // someone else's RouDi: use it, leave it alone
    log_ = std::filesystem::temp_directory_path() / ("robodiff-test-roudi-" + std::to_string(::getpid()) + ".log");
    owner_ = ::getpid();
    pid_ = ::fork();
    if (pid_ < 0) throw std::runtime_error("fork for iox-roudi failed");
    if (pid_ == 0) {
      const int fd = ::open(log_.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
      if (fd >= 0) {
        ::dup2(fd, STDOUT_FILENO);
        ::dup2(fd, STDERR_FILENO);
      }
      sigset_t none;  // a test that blocks signals must not pass that on to RouDi
      ::sigemptyset(&none);
      ::sigprocmask(SIG_SETMASK, &none, nullptr);
      ::execlp("iox-roudi", "iox-roudi", "-c", config.c_str(), static_cast<char*>(nullptr));
      ::_exit(127);
    }
    const auto until = std::chrono::steady_clock::now() + timeout;
    while (!(logSays("RouDi is ready for clients") && shm::roudiRunning())) {
      int status = 0;
      if (::waitpid(pid_, &status, WNOHANG) == pid_) {
        pid_ = -1;
        throw std::runtime_error("iox-roudi exited before it was ready: " + logText());
      }
      if (std::chrono::steady_clock::now() > until) {
        stop();
        throw std::runtime_error("iox-roudi was not ready within the timeout: " + logText());
      }
      std::this_thread::sleep_for(5ms);
    }
  }
  ~RoudiProcess() { stop(); }
  RoudiProcess(const RoudiProcess&) = delete;
  RoudiProcess& operator=(const RoudiProcess&) = delete;

  // SIGKILL, then its socket and shared memory removed. Not SIGINT: a RouDi shutting down
  // sends SIGTERM to every process still registered with it (this test process's runtime
  // lives to its end), and it hangs for good when a killed robodiffd left a port's mutex
  // locked (iceoryx 2.0). Only the process that started it stops it (not a forked child).
  void stop() {
    if (pid_ <= 0 || ::getpid() != owner_) return;
    ::kill(pid_, SIGKILL);
    int status = 0;
    ::waitpid(pid_, &status, 0);
    pid_ = -1;
    shm::removeRoudiLeftovers();
    std::error_code ignored;
    if (std::getenv("ROBODIFF_KEEP_ROUDI_LOG") == nullptr) std::filesystem::remove(log_, ignored);
  }

  pid_t pid() const { return pid_; }
  bool started() const { return pid_ > 0; }  // false: an already running RouDi is used

 private:
  std::string logText() const {
    std::ifstream in(log_);
    std::stringstream s;
    s << in.rdbuf();
    return s.str();
  }
  bool logSays(const std::string& text) const { return logText().find(text) != std::string::npos; }

  pid_t pid_ = -1;
  pid_t owner_ = -1;
  std::filesystem::path log_;
};

// One RouDi for the rest of this test process, stopped when the tests are done (by the
// process that started it).
inline RoudiProcess*& sharedRoudiIfMade() {  // null until sharedRoudi() is first called
  static RoudiProcess* made = nullptr;
  return made;
}
inline RoudiProcess& sharedRoudi() {
  static RoudiProcess roudi;
  sharedRoudiIfMade() = &roudi;
  return roudi;
}

// Stops the shared RouDi after the last test, before the process exits: this process's
// iceoryx runtime unregisters at exit and waits for RouDi's answer without a timeout, so
// a RouDi still there but hung (a killed process left a port's mutex locked, iceoryx 2.0)
// would hang the test process; a RouDi already gone refuses at once.
class StopSharedRoudiAtEnd : public ::testing::Environment {
 public:
  void TearDown() override {
    if (RoudiProcess* roudi = sharedRoudiIfMade()) roudi->stop();
  }
};
inline const bool kStopSharedRoudiAtEndRegistered =
    (::testing::AddGlobalTestEnvironment(new StopSharedRoudiAtEnd), true);

}  // namespace robodiff::testing
