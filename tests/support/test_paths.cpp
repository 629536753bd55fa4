#include "support/test_paths.hpp"

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

}  // namespace robodiff::testing
