#include "process_identity.hpp"

#include <unistd.h>

#include <fstream>
#include <random>
#include <sstream>
#include <vector>

namespace robodiff::cache::detail {
namespace {

std::string hostName() {
  char buf[256] = {};
  if (gethostname(buf, sizeof buf - 1) != 0) return "unknown-host";
  return buf;
}

// Field 22 of /proc/PID/stat: the start time in clock ticks since boot; empty when the
// process does not exist.
std::string startTicks(int pid) {
  std::ifstream f("/proc/" + std::to_string(pid) + "/stat");
  std::string text;
  if (!std::getline(f, text)) return {};
  // The command name (field 2) is in parentheses and may contain spaces: skip past it.
  const auto close = text.rfind(')');
  if (close == std::string::npos) return {};
  std::istringstream rest(text.substr(close + 2));
  std::string field;
  for (int i = 3; i <= 22 && (rest >> field); ++i) {
    if (i == 22) return field;
  }
  return {};
}

std::vector<std::string> splitColons(const std::string& s) {
  std::vector<std::string> parts;
  std::string part;
  std::istringstream in(s);
  while (std::getline(in, part, ':')) parts.push_back(part);
  return parts;
}

}  // namespace

std::string newOwnerToken() {
  static thread_local std::mt19937_64 rng{std::random_device{}()};
  std::ostringstream s;
  s << hostName() << ':' << getpid() << ':' << startTicks(getpid()) << ':' << std::hex << rng();
  return s.str();
}

bool ownerMayBeAlive(const std::string& owner) {
  const std::vector<std::string> parts = splitColons(owner);
  if (parts.size() != 4) return true;
  if (parts[0] != hostName()) return true;
  int pid = 0;
  try {
    pid = std::stoi(parts[1]);
  } catch (...) {
    return true;
  }
  const std::string ticks = startTicks(pid);
  return !ticks.empty() && ticks == parts[2];
}

int ownerPid(const std::string& owner) {
  const std::vector<std::string> parts = splitColons(owner);
  if (parts.size() != 4) return 0;
  try {
    return std::stoi(parts[1]);
  } catch (...) {
    return 0;
  }
}

}  // namespace robodiff::cache::detail
