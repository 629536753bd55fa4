// What can be wrong with a ready entry's files, checked before it is loaded and by
// `cache verify` and `cache repair` (cache_state.hpp).
#include <filesystem>
#include <string>

#include "artifact_files.hpp"
#include "cache_state.hpp"
#include "permissions.hpp"

namespace robodiff::cache {
namespace {

namespace fs = std::filesystem;

std::string shortKey(const std::string& key) { return key.substr(0, 12); }

}  // namespace

std::string detail::artifactProblem(const Entry& e, const fs::path& dir) {
  std::error_code ec;
  const fs::path library = dir / "library.so";
  if (!fs::is_directory(dir, ec)) return "its directory " + dir.string() + " is missing";
  if (fs::is_symlink(library, ec)) return "library.so is a symbolic link (replaced)";
  if (!fs::is_regular_file(library, ec)) return "library.so is missing";
  if (!fs::is_regular_file(dir / "description.json", ec)) return "description.json is missing";
  const std::uint64_t size = fs::file_size(library, ec);
  if (ec) return "library.so cannot be read: " + ec.message();
  if (size != e.library_bytes)
    return "library.so has " + std::to_string(size) + " bytes, the index recorded " + std::to_string(e.library_bytes) +
           " (truncated or replaced)";
  std::string actual;
  try {
    actual = sha256OfFile(library);
  } catch (const std::exception& ex) {
    return ex.what();
  }
  if (actual != e.library_sha256)
    return "library.so SHA-256 mismatch (index " + shortKey(e.library_sha256) + "..., file " + shortKey(actual) + "...)";
  return {};
}

std::string detail::entryProblem(const Entry& e, const fs::path& dir) {
  std::string problem = artifactProblem(e, dir);
  if (!problem.empty()) return problem;
  try {
    checkNotWritableByOthers(dir);
    checkNotWritableByOthers(dir / "library.so");
  } catch (const CacheError& ex) {
    return ex.what();
  }
  return {};
}

}  // namespace robodiff::cache
