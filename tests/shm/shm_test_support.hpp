// What the iceoryx transport tests share: a server with a FakeService on the shared RouDi,
// connections to it, and running this test binary again as a child process (a fresh
// process: iceoryx allows one runtime per process).
#pragma once

#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <memory>
#include <string>
#include <thread>

#include "fake_service.hpp"
#include "robodiff/client/shm_connection.hpp"
#include "robodiff/server/shm_server.hpp"
#include "roudi_fixture.hpp"

namespace robodiff::testing {

// Set in a child started by startChild(); the child-only tests skip without it.
inline const char* childMode() { return std::getenv("ROBODIFF_SHM_TEST_CHILD"); }

// Runs this binary with --gtest_filter=<test> and ROBODIFF_SHM_TEST_CHILD=<mode>.
inline pid_t startChild(const std::string& test, const std::string& mode) {
  const pid_t pid = ::fork();
  if (pid == 0) {
    ::setenv("ROBODIFF_SHM_TEST_CHILD", mode.c_str(), 1);
    const std::string filter = "--gtest_filter=" + test;
    ::execl("/proc/self/exe", "shm_tests", filter.c_str(), static_cast<char*>(nullptr));
    ::_exit(127);
  }
  return pid;
}

inline int waitChild(pid_t pid) {
  int status = 0;
  ::waitpid(pid, &status, 0);
  return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
}

inline bool waitUntil(const std::function<bool()>& condition, std::chrono::milliseconds timeout) {
  const auto until = std::chrono::steady_clock::now() + timeout;
  while (!condition()) {
    if (std::chrono::steady_clock::now() > until) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  return true;
}

inline server::Logger& quietLog() {
  static server::Logger log(stderr, server::LogLevel::Warn, server::LogFormat::Text);
  return log;
}

inline std::unique_ptr<client::ShmConnection> connect(std::string service,
                                                      std::chrono::milliseconds timeout = std::chrono::seconds(10)) {
  client::ShmConnectionOptions options;
  options.service = std::move(service);
  options.default_timeout = timeout;
  options.connect_timeout = std::chrono::seconds(3);
  Status status;
  auto c = client::connectShm(options, status);
  EXPECT_TRUE(status.ok()) << toString(status.code) << ": " << status.message;
  return c;
}

}  // namespace robodiff::testing
