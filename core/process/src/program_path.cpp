#include "robodiff/process/program_path.hpp"

#include <sys/stat.h>
#include <unistd.h>

#include <cstdlib>

namespace robodiff::process {

bool isExecutableFile(const std::filesystem::path& path) {
  struct stat st;
  return ::stat(path.c_str(), &st) == 0 && S_ISREG(st.st_mode) && ::access(path.c_str(), X_OK) == 0;
}

std::string findProgram(const std::string& name) {
  if (name.empty()) return {};
  if (name.find('/') != std::string::npos) return isExecutableFile(name) ? name : std::string();
  const char* path = std::getenv("PATH");
  const std::string dirs = path ? path : "/usr/local/bin:/usr/bin:/bin";
  std::size_t start = 0;
  while (start <= dirs.size()) {
    std::size_t end = dirs.find(':', start);
    if (end == std::string::npos) end = dirs.size();
    const std::string dir = dirs.substr(start, end - start);
    const std::string candidate = (dir.empty() ? std::string(".") : dir) + "/" + name;
    if (isExecutableFile(candidate)) return candidate;
    start = end + 1;
  }
  return {};
}

std::string whyNotFound(const std::string& name) {
  if (name.empty()) return "no program named";
  const std::string quoted = "'" + name + "'";
  if (name.find('/') == std::string::npos) {
    const char* path = std::getenv("PATH");
    return quoted + " is not in PATH (" + (path ? path : "unset") + ")";
  }
  std::error_code ec;
  if (!std::filesystem::exists(name, ec)) return quoted + " does not exist";
  return quoted + " is not an executable file";
}

}  // namespace robodiff::process
