// robodiffd for the benchmarks: started as a child process on its own cache and DDS
// domain (loopback configuration), waited for until it serves, stopped with SIGTERM.
#pragma once

#include <fcntl.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

namespace bench {

inline std::string readText(const std::filesystem::path& p) {
  std::ifstream in(p);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

// robodiffd as a child process, stopped with SIGTERM at the end.
struct Daemon {
  pid_t pid = -1;
  std::filesystem::path log;
  // `extra`: more robodiffd arguments after --cache and --dds-domain (e.g. --set k=v).
  Daemon(const std::filesystem::path& exe, const std::filesystem::path& cache, int domain,
         const std::filesystem::path& log_path, const std::vector<std::string>& extra = {})
      : log(log_path) {
    // The arguments are made before fork: the child of a threaded process must not allocate.
    std::vector<std::string> args = {exe.string(), "--cache", cache.string(), "--dds-domain", std::to_string(domain)};
    args.insert(args.end(), extra.begin(), extra.end());
    std::vector<char*> argv;
    for (std::string& a : args) argv.push_back(a.data());
    argv.push_back(nullptr);
    pid = fork();
    if (pid == 0) {
      const int fd = open(log_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0600);
      dup2(fd, STDERR_FILENO);
      dup2(fd, STDOUT_FILENO);
      execv(argv[0], argv.data());
      _exit(127);
    }
    for (int i = 0; i < 3000; ++i) {
      if (readText(log).find("\"event\":\"serving\"") != std::string::npos) return;
      if (waitpid(pid, nullptr, WNOHANG) == pid) break;
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
    std::fprintf(stderr, "robodiffd did not start; its log:\n%s\n", readText(log).c_str());
    kill(pid, SIGTERM);
    waitpid(pid, nullptr, 0);
    std::exit(1);
  }
  ~Daemon() {
    kill(pid, SIGTERM);
    waitpid(pid, nullptr, 0);
  }
};

}  // namespace bench
