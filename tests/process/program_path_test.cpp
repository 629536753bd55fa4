// Finding a program: a path is checked to be an executable file, a name is looked up
// in PATH, entry by entry.
#include "robodiff/process/program_path.hpp"

#include <cstdlib>
#include <filesystem>
#include <fstream>

#include <gtest/gtest.h>

#include "support/temp_dir.hpp"

namespace robodiff::process {
namespace {

namespace fs = std::filesystem;
using robodiff::testing::TempDir;

void writeScript(const fs::path& path, bool executable) {
  std::ofstream(path) << "#!/bin/sh\nexit 0\n";
  fs::permissions(path, executable ? fs::perms::owner_all : fs::perms::owner_read | fs::perms::owner_write);
}

// PATH set for the test's scope.
class ScopedPath {
 public:
  explicit ScopedPath(const std::string& value) {
    const char* old = std::getenv("PATH");
    had_ = old != nullptr;
    if (had_) old_ = old;
    ::setenv("PATH", value.c_str(), 1);
  }
  ~ScopedPath() { had_ ? ::setenv("PATH", old_.c_str(), 1) : ::unsetenv("PATH"); }

 private:
  bool had_ = false;
  std::string old_;
};

TEST(ProgramPath, ANameIsTheFirstExecutableMatchInPath) {
  TempDir first, second;
  writeScript(first / "tool", false);  // not executable: skipped
  fs::create_directory(first / "subdir-tool");
  writeScript(second / "tool", true);
  ScopedPath path(first.path().string() + ":" + second.path().string());
  EXPECT_EQ(findProgram("tool"), (second / "tool").string());
  EXPECT_EQ(findProgram("subdir-tool"), "") << "a directory is not a program";
  EXPECT_EQ(findProgram("missing-tool"), "");
  EXPECT_EQ(findProgram(""), "");
}

TEST(ProgramPath, APathIsCheckedNotSearched) {
  TempDir dir;
  writeScript(dir / "run", true);
  writeScript(dir / "data", false);
  ScopedPath path(dir.path().string());
  EXPECT_EQ(findProgram((dir / "run").string()), (dir / "run").string());
  EXPECT_EQ(findProgram((dir / "data").string()), "");
  EXPECT_EQ(findProgram("./nonexistent/run"), "");
  EXPECT_TRUE(isExecutableFile(dir / "run"));
  EXPECT_FALSE(isExecutableFile(dir / "data"));
  EXPECT_FALSE(isExecutableFile(dir.path()));
}

TEST(ProgramPath, WhyNotFoundNamesTheCase) {
  TempDir dir;
  writeScript(dir / "data", false);
  ScopedPath path("/nonexistent-a:/nonexistent-b");
  EXPECT_EQ(whyNotFound((dir / "data").string()), "'" + (dir / "data").string() + "' is not an executable file");
  EXPECT_EQ(whyNotFound((dir / "gone").string()), "'" + (dir / "gone").string() + "' does not exist");
  EXPECT_EQ(whyNotFound("tool"), "'tool' is not in PATH (/nonexistent-a:/nonexistent-b)");
}

}  // namespace
}  // namespace robodiff::process
