#include "support/dds_domain.hpp"

#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <stdexcept>
#include <string>

namespace robodiff::testing {

// The search starts from a domain derived from the process id, so that processes rarely
// contend for the same lock. The lock's descriptor stays open on purpose: the claim ends
// when the process does. O_CLOEXEC keeps it out of exec'd children.
std::uint32_t claimDdsDomain(std::uint32_t first, std::uint32_t last) {
  const std::filesystem::path dir = std::filesystem::temp_directory_path() / "robodiff-test-dds-domains";
  std::filesystem::create_directories(dir);
  std::error_code ignored;  // another user's directory stays as it is
  std::filesystem::permissions(dir, std::filesystem::perms::all, std::filesystem::perm_options::add, ignored);
  const std::uint32_t count = last - first + 1;
  const std::uint32_t start = static_cast<std::uint32_t>(getpid()) % count;
  for (std::uint32_t k = 0; k < count; ++k) {
    const std::uint32_t domain = first + (start + k) % count;
    const std::string path = (dir / (std::to_string(domain) + ".lock")).string();
    const int fd = open(path.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0666);
    if (fd < 0) continue;
    if (flock(fd, LOCK_EX | LOCK_NB) == 0) return domain;
    close(fd);
  }
  throw std::runtime_error("every DDS test domain " + std::to_string(first) + ".." + std::to_string(last) +
                           " is claimed by a running test process (locks in " + dir.string() + ")");
}

std::uint32_t testDomain(int band) {
  if (band == 1) {
    static const std::uint32_t lingering = claimDdsDomain(201, 229);
    return lingering;
  }
  static const std::uint32_t domain = [] {
    if (const char* fixed = std::getenv("ROBODIFF_TEST_DDS_DOMAIN")) return static_cast<std::uint32_t>(std::atoi(fixed));
    return claimDdsDomain(1, 200);
  }();
  return domain;
}

std::uint32_t emptyTestDomain() {
  static const std::uint32_t domain = claimDdsDomain(1, 200);
  return domain;
}

}  // namespace robodiff::testing
