// Caller partitions: their names, the one a signed permissions document grants, and the
// open-DDS one of this process's user.
#include "robodiff/schema/dds_partitions.hpp"

#include <pwd.h>
#include <unistd.h>

#include <cctype>
#include <fstream>
#include <sstream>
#include <stdexcept>

namespace robodiff::dds_codec {

namespace {

// A name safe in a partition: no DDS wildcard ('*', '?', '['), no separator surprises.
std::string partitionSafe(std::string_view name) {
  std::string out(name.substr(0, 64));
  for (char& c : out)
    if (!std::isalnum(static_cast<unsigned char>(c)) && c != '-' && c != '_' && c != '.') c = '_';
  return out.empty() ? std::string("_") : out;
}

}  // namespace

std::string callerPartition(std::string_view name, bool operator_) {
  return std::string(operator_ ? kOperatorPartitionPrefix : kCallerPartitionPrefix) + std::string(name);
}

std::vector<std::string> serverRequestPartitions() {
  return {std::string(kCallerPartitionPrefix) + "*", std::string(kOperatorPartitionPrefix) + "*"};
}

std::string permittedCallerPartition(const std::filesystem::path& permissions) {
  std::ifstream in(permissions);
  std::stringstream text;
  text << in.rdbuf();
  const std::string document = text.str();
  for (std::string_view prefix : {kOperatorPartitionPrefix, kCallerPartitionPrefix}) {
    const std::string open = "<partition>" + std::string(prefix);
    for (auto at = document.find(open); at != std::string::npos; at = document.find(open, at + 1)) {
      const auto begin = at + std::string_view("<partition>").size();
      const auto end = document.find('<', begin);
      if (end == std::string::npos) break;
      const std::string partition = document.substr(begin, end - begin);
      if (partition.find_first_of("*?[") != std::string::npos) continue;  // a pattern: a server's grant
      return partition;
    }
  }
  throw std::invalid_argument("DDS security: the permissions " + permissions.string() +
                              " grant no robodiff caller partition (robodiff.caller.<name>): it is a server identity "
                              "(which calls other services only when made with `robodiff security add-server "
                              "--also-calls SERVICE`), or was made by an older `robodiff security`");
}

std::string openCallerPartition() {
  const uid_t uid = geteuid();
  std::string name = "uid" + std::to_string(uid);
  passwd entry{}, *found = nullptr;
  char buffer[4096];
  if (getpwuid_r(uid, &entry, buffer, sizeof buffer, &found) == 0 && found && found->pw_name) name = found->pw_name;
  return callerPartition(partitionSafe(name), false);
}

std::optional<PartitionCaller> callerOfPartition(std::string_view partition) {
  for (const bool operator_ : {false, true}) {
    const std::string_view prefix = operator_ ? kOperatorPartitionPrefix : kCallerPartitionPrefix;
    if (partition.size() <= prefix.size() || partition.substr(0, prefix.size()) != prefix) continue;
    const std::string_view name = partition.substr(prefix.size());
    if (name.find_first_of("*?[]\\") != std::string_view::npos) return std::nullopt;  // a pattern, not a name
    return PartitionCaller{std::string(name), operator_};
  }
  return std::nullopt;
}

}  // namespace robodiff::dds_codec
