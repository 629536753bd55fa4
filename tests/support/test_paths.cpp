#include "support/test_paths.hpp"

#include <unistd.h>

#include <algorithm>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <stdexcept>

namespace robodiff::testing {

std::optional<std::filesystem::path> sharedDir() {
  std::filesystem::path dir = ROBODIFF_SHARED_DIR;
  if (const char* env = std::getenv("ROBODIFF_SHARED")) dir = env;
  if (std::filesystem::is_directory(dir / "golden") && std::filesystem::is_directory(dir / "robots"))
    return std::filesystem::canonical(dir);
  return std::nullopt;
}

std::filesystem::path sourceDir() { return ROBODIFF_SOURCE_DIR; }
std::filesystem::path cliPath() { return ROBODIFF_CLI_PATH; }
std::filesystem::path workerPath() { return ROBODIFF_WORKER_PATH; }

std::string readFile(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error("cannot open " + path.string());
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

std::optional<std::filesystem::path> programInPath(const std::string& program) {
  const char* path = std::getenv("PATH");
  if (!path) return std::nullopt;
  const std::string dirs = path;
  for (std::size_t start = 0; start <= dirs.size();) {
    const std::size_t end = std::min(dirs.find(':', start), dirs.size());
    const std::filesystem::path candidate = std::filesystem::path(dirs.substr(start, end - start)) / program;
    if (end > start && ::access(candidate.c_str(), X_OK) == 0) return candidate;
    start = end + 1;
  }
  return std::nullopt;
}

}  // namespace robodiff::testing
