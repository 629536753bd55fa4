// callerOfShmClient: client id -> pid -> owner of /proc/<pid> -> user name.
#include "robodiff/server/shm_caller.hpp"

#include <pwd.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cctype>
#include <mutex>
#include <optional>
#include <string>
#include <unordered_map>

namespace robodiff::server::shm_detail {

namespace {

constexpr std::size_t kMaxKnownClients = 4096;  // then the cache starts afresh

Caller unknownCaller() { return Caller{"shm:?unknown", false, false}; }

std::string hostName() {
  char host[256] = {};
  if (gethostname(host, sizeof host - 1) != 0) return "unknown-host";
  return host;
}

// The pid of "<host>:<pid>:<random>" when <host> is this host (or the end of its name:
// long ids are cut at the front to fit a chunk's id field).
std::optional<pid_t> localPid(std::string_view id) {
  const auto last = id.rfind(':');
  if (last == std::string_view::npos || last == 0) return std::nullopt;
  const auto middle = id.rfind(':', last - 1);
  if (middle == std::string_view::npos || middle == 0) return std::nullopt;
  const std::string_view host = id.substr(0, middle), pid = id.substr(middle + 1, last - middle - 1);
  static const std::string ours = hostName();
  if (host.size() > ours.size() || ours.compare(ours.size() - host.size(), host.size(), host) != 0)
    return std::nullopt;
  if (pid.empty() || pid.size() > 9) return std::nullopt;
  long value = 0;
  for (char c : pid) {
    if (!std::isdigit(static_cast<unsigned char>(c))) return std::nullopt;
    value = value * 10 + (c - '0');
  }
  if (value <= 0) return std::nullopt;
  return static_cast<pid_t>(value);
}

std::string userName(uid_t uid) {
  passwd entry{}, *found = nullptr;
  char buffer[4096];
  std::string name = "uid" + std::to_string(uid);
  if (getpwuid_r(uid, &entry, buffer, sizeof buffer, &found) == 0 && found && found->pw_name) name = found->pw_name;
  for (char& c : name)  // as the open-DDS partition spells it (dds_partitions.cpp)
    if (!std::isalnum(static_cast<unsigned char>(c)) && c != '-' && c != '_' && c != '.') c = '_';
  return name;
}

Caller lookUp(std::string_view client_id) {
  const auto pid = localPid(client_id);
  if (!pid) return unknownCaller();
  struct stat info {};
  if (stat(("/proc/" + std::to_string(*pid)).c_str(), &info) != 0) return unknownCaller();
  return callerOfUid(info.st_uid);
}

}  // namespace

bool shmClientProcessGone(std::string_view client_id) {
  const auto pid = localPid(client_id);
  struct stat info {};
  return pid && stat(("/proc/" + std::to_string(*pid)).c_str(), &info) != 0;
}

Caller callerOfUid(unsigned uid) {
  return Caller{"user:" + userName(uid), uid == 0 || uid == geteuid(), false};
}

Caller callerOfShmClient(std::string_view client_id) {
  static std::mutex mutex;
  static std::unordered_map<std::string, Caller> known;
  {
    std::lock_guard lock(mutex);
    if (const auto it = known.find(std::string(client_id)); it != known.end()) return it->second;
  }
  Caller caller = lookUp(client_id);
  std::lock_guard lock(mutex);
  if (known.size() >= kMaxKnownClients) known.clear();
  known.emplace(std::string(client_id), caller);
  return caller;
}

}  // namespace robodiff::server::shm_detail
