#include "support/temp_dir.hpp"

#include <stdlib.h>
#include <sys/stat.h>

#include <fstream>
#include <stdexcept>

namespace robodiff::testing {

namespace fs = std::filesystem;

TempDir::TempDir() {
  std::string pattern = (fs::temp_directory_path() / "robodiff-test-XXXXXX").string();
  if (!mkdtemp(pattern.data())) throw std::runtime_error("mkdtemp failed: " + pattern);
  path_ = pattern;
}

TempDir::~TempDir() {
  std::error_code ec;
  fs::remove_all(path_, ec);
}

fs::path TempDir::file(const std::string& name, const std::string& content) const {
  const fs::path p = path_ / name;
  std::ofstream(p) << content;
  return p;
}

fs::path TempDir::script(const std::string& name, const std::string& body) const {
  const fs::path p = file(name, "#!/bin/sh\n" + body);
  ::chmod(p.c_str(), 0755);
  return p;
}

}  // namespace robodiff::testing
