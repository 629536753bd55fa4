// A real robodiffd for the end-to-end tests: started as a child process on a temporary
// cache and a DDS domain of this test's own, waited for until it logs "serving", stopped
// by PID (SIGTERM to drain, SIGKILL to simulate a crash). Its log (JSON lines) is kept in
// a file so a failing test can show it.
#pragma once

#include <fcntl.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "support/dds_domain.hpp"
#include "support/test_paths.hpp"

namespace robodiff::testing {

inline std::filesystem::path robodiffdPath() { return ROBODIFFD_PATH; }

// Points Cyclone DDS at the loopback configuration of deploy/ for this process and its
// children.
inline void useLoopbackDds() {
  const std::string uri = "file://" + (sourceDir() / "deploy/cyclonedds-loopback.xml").string();
  setenv("CYCLONEDDS_URI", uri.c_str(), 1);
}

// The first JSON log line of `event` in `log` (robodiffd --log-format json), parsed;
// null when there is none yet.
inline nlohmann::json logEvent(const std::string& log, const std::string& event) {
  std::istringstream lines(log);
  std::string line;
  while (std::getline(lines, line)) {
    if (line.find("\"event\":\"" + event + "\"") == std::string::npos) continue;
    try {
      return nlohmann::json::parse(line);
    } catch (const std::exception&) {
    }
  }
  return nullptr;
}

class RobodiffdProcess {
 public:
  // Starts robodiffd with `args` (besides --cache, --dds-domain and the log file) and
  // waits up to `timeout` for it to serve. Fails the test (and returns) if it exits first.
  RobodiffdProcess(const std::filesystem::path& cache_dir, const std::filesystem::path& log_path,
                   std::vector<std::string> args = {}, std::chrono::seconds timeout = std::chrono::seconds(60))
      : log_path_(log_path) {
    useLoopbackDds();
    std::vector<std::string> argv_strings = {robodiffdPath().string(), "--cache", cache_dir.string(),
                                             "--dds-domain", std::to_string(testDomain()), "--log-format", "json"};
    argv_strings.insert(argv_strings.end(), args.begin(), args.end());
    pid_ = fork();
    if (pid_ == 0) {
      signal(SIGTERM, SIG_DFL);  // the test process may ignore it; robodiffd must not
      const int fd = open(log_path.c_str(), O_WRONLY | O_CREAT | O_APPEND, 0600);
      if (fd >= 0) {
        dup2(fd, STDERR_FILENO);
        dup2(fd, STDOUT_FILENO);
      }
      std::vector<char*> argv;
      for (std::string& s : argv_strings) argv.push_back(s.data());
      argv.push_back(nullptr);
      execv(argv[0], argv.data());
      _exit(127);
    }
    const auto deadline = std::chrono::steady_clock::now() + timeout;
    while (std::chrono::steady_clock::now() < deadline) {
      if (log().find("\"event\":\"serving\"") != std::string::npos) return;
      int status = 0;
      if (waitpid(pid_, &status, WNOHANG) == pid_) {
        pid_ = -1;
        ADD_FAILURE() << "robodiffd exited before serving (status " << status << "); log:\n" << log();
        return;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
    ADD_FAILURE() << "robodiffd did not serve within " << timeout.count() << " s; log:\n" << log();
  }

  // SIGTERM, not SIGKILL: a robodiffd killed while one of its threads holds an iceoryx
  // port's inter-process mutex (sending a reply) leaves that mutex locked, and RouDi then
  // deadlocks cleaning up after it (iceoryx 2.0). Tests that mean a crash call kill().
  ~RobodiffdProcess() { terminate(std::chrono::seconds(30)); }
  RobodiffdProcess(const RobodiffdProcess&) = delete;
  RobodiffdProcess& operator=(const RobodiffdProcess&) = delete;

  pid_t pid() const { return pid_; }
  bool running() const { return pid_ > 0; }
  std::string log() const {
    std::error_code ec;
    return std::filesystem::exists(log_path_, ec) ? readFile(log_path_) : std::string();
  }

  // SIGTERM, then waits for the exit; returns the exit code (-1 on a timeout or a signal).
  // Waits up to `timeout` for robodiffd to exit by itself and reaps it: its exit code, or
  // -1 (killed by a signal, or still running at the timeout).
  int waitExit(std::chrono::milliseconds timeout) {
    const auto deadline = std::chrono::steady_clock::now() + timeout;
    while (pid_ > 0 && std::chrono::steady_clock::now() < deadline) {
      int status = 0;
      if (waitpid(pid_, &status, WNOHANG) == pid_) {
        pid_ = -1;
        return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
    return -1;
  }

  int terminate(std::chrono::seconds timeout = std::chrono::seconds(60)) {
    if (pid_ <= 0) return -1;
    ::kill(pid_, SIGTERM);
    const auto deadline = std::chrono::steady_clock::now() + timeout;
    while (std::chrono::steady_clock::now() < deadline) {
      int status = 0;
      if (waitpid(pid_, &status, WNOHANG) == pid_) {
        pid_ = -1;
        return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
    kill();
    return -1;
  }

  // SIGKILL (a crash), and reap. After `settle` first, so that the kill finds robodiffd
  // idle: killed in the middle of an iceoryx send it would leave a port's mutex locked
  // and RouDi hung (iceoryx 2.0), which no test here means to exercise.
  void kill(std::chrono::milliseconds settle = std::chrono::milliseconds(100)) {
    if (pid_ <= 0) return;
    std::this_thread::sleep_for(settle);
    ::kill(pid_, SIGKILL);
    int status = 0;
    waitpid(pid_, &status, 0);
    pid_ = -1;
  }

 private:
  std::filesystem::path log_path_;
  pid_t pid_ = -1;
};

}  // namespace robodiff::testing
