// A fresh directory under the system's temporary directory (mkdtemp), removed with
// everything in it when the TempDir goes; helpers to put files in it.
#pragma once

#include <filesystem>
#include <string>

namespace robodiff::testing {

class TempDir {
 public:
  TempDir();
  ~TempDir();
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;

  const std::filesystem::path& path() const { return path_; }
  std::filesystem::path operator/(const std::string& name) const { return path_ / name; }

  // Writes `content` to path()/name and returns the path.
  std::filesystem::path file(const std::string& name, const std::string& content) const;
  // An executable shell script path()/name running `body`.
  std::filesystem::path script(const std::string& name, const std::string& body) const;

 private:
  std::filesystem::path path_;
};

}  // namespace robodiff::testing
