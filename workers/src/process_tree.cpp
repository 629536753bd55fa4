#include "process_tree.hpp"

#include <dirent.h>
#include <fcntl.h>
#include <signal.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdlib>
#include <set>
#include <string>
#include <unordered_map>

namespace robodiff::workers::detail {
namespace {

// All processes in /proc, one stat each (processes that vanish meanwhile are skipped).
std::vector<ProcessStat> allProcesses() {
  std::vector<ProcessStat> result;
  DIR* proc = opendir("/proc");
  if (!proc) return result;
  while (const dirent* entry = readdir(proc)) {
    char* end = nullptr;
    const long pid = std::strtol(entry->d_name, &end, 10);
    if (pid <= 0 || *end != '\0') continue;
    if (auto stat = readProcessStat(static_cast<pid_t>(pid))) result.push_back(*stat);
  }
  closedir(proc);
  return result;
}

bool isLive(const ProcessStat& s) { return s.state != 'Z' && s.state != 'X'; }

}  // namespace

std::optional<ProcessStat> readProcessStat(pid_t pid) {
  const std::string path = "/proc/" + std::to_string(pid) + "/stat";
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) return std::nullopt;
  char buffer[1024];
  ssize_t n;
  do n = ::read(fd, buffer, sizeof buffer - 1);
  while (n < 0 && errno == EINTR);
  ::close(fd);
  if (n <= 0) return std::nullopt;
  buffer[n] = '\0';
  // "pid (comm) state ppid pgrp ...": comm may hold spaces and parentheses, so the
  // fields after it start after the last ')'.
  const std::string text(buffer, static_cast<std::size_t>(n));
  const auto close_paren = text.rfind(')');
  if (close_paren == std::string::npos || close_paren + 2 >= text.size()) return std::nullopt;
  ProcessStat stat;
  stat.pid = pid;
  const char* p = text.c_str() + close_paren + 2;
  stat.state = *p++;
  char* end = nullptr;
  stat.ppid = static_cast<pid_t>(std::strtol(p, &end, 10));
  stat.pgid = static_cast<pid_t>(std::strtol(end, &end, 10));
  stat.sid = static_cast<pid_t>(std::strtol(end, &end, 10));
  return stat;
}

std::vector<pid_t> descendantsOf(pid_t root) {
  std::unordered_multimap<pid_t, pid_t> children;  // parent -> child
  std::vector<pid_t> found;
  std::vector<pid_t> frontier{root};
  for (const ProcessStat& s : allProcesses()) {
    if (!isLive(s) || s.pid == root) continue;
    children.emplace(s.ppid, s.pid);
    if (s.sid == root) {  // in the session root leads: an orphan of the tree, or part of it
      found.push_back(s.pid);
      frontier.push_back(s.pid);
    }
  }
  while (!frontier.empty()) {
    const pid_t parent = frontier.back();
    frontier.pop_back();
    const auto [first, last] = children.equal_range(parent);
    for (auto it = first; it != last; ++it) {
      if (std::find(found.begin(), found.end(), it->second) != found.end()) continue;  // pid reuse loops
      found.push_back(it->second);
      frontier.push_back(it->second);
    }
  }
  return found;
}

std::vector<pid_t> killProcessTree(pid_t root) {
  if (root <= 1) return {};
  const pid_t own_group = getpgrp();
  ::kill(root, SIGSTOP);
  // Stopped processes cannot fork; collect until a pass finds nobody new. Each pass
  // stops what it found, so the tree stops growing from the top down.
  std::set<pid_t> stopped;
  std::vector<pid_t> descendants;
  for (int pass = 0; pass < 64; ++pass) {
    bool grew = false;
    for (pid_t pid : descendantsOf(root)) {
      if (!stopped.insert(pid).second) continue;
      ::kill(pid, SIGSTOP);
      descendants.push_back(pid);
      grew = true;
    }
    if (!grew) break;
  }
  auto killGroup = [&](pid_t pgid) {
    if (pgid > 1 && pgid != own_group) ::killpg(pgid, SIGKILL);
  };
  for (pid_t pid : descendants) {
    if (auto stat = readProcessStat(pid)) killGroup(stat->pgid);
    ::kill(pid, SIGKILL);
  }
  if (auto stat = readProcessStat(root)) killGroup(stat->pgid);
  ::kill(root, SIGKILL);
  return descendants;
}

}  // namespace robodiff::workers::detail
