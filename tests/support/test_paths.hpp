// Where tests find their inputs: ../shared (robots and golden values produced by other
// tools; absent on some machines, then the tests that need it skip) and the project's
// own example robots.
#pragma once

#include <filesystem>
#include <optional>
#include <string>

#include <gtest/gtest.h>

namespace robodiff::testing {

// The shared folder: $ROBODIFF_SHARED if set, else ../shared beside the source tree.
std::optional<std::filesystem::path> sharedDir();
std::filesystem::path sourceDir();
std::filesystem::path cliPath();     // the built `robodiff` executable
std::filesystem::path workerPath();  // the built `robodiff-worker` executable

std::string readFile(const std::filesystem::path& path);

// An executable named `program` in PATH, or nothing (optional compilers: tcc, clang).
std::optional<std::filesystem::path> programInPath(const std::string& program);

}  // namespace robodiff::testing

// Skips the current test with a clear message when ../shared is not there.
#define ROBODIFF_REQUIRE_SHARED(dir_variable)                                              \
  auto dir_variable##_opt = ::robodiff::testing::sharedDir();                              \
  if (!dir_variable##_opt)                                                                 \
    GTEST_SKIP() << "no shared data (robots/, golden/): neither $ROBODIFF_SHARED nor "   \
                    "../shared beside the source tree has it; skipping this comparison";      \
  const std::filesystem::path dir_variable = *dir_variable##_opt
