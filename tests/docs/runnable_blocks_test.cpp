// Every shell block of README.md and docs/*.md marked `<!-- runnable -->` runs as written:
// in a fresh temporary directory that looks like the repository root (examples/ and
// build/ linked in), with build/bin on PATH and a private default cache, one bash per
// block (set -euo pipefail), the page's blocks in order. A block must exit 0.
#include <algorithm>
#include <cctype>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "docs/markdown_blocks.hpp"
#include "support/process.hpp"
#include "support/temp_dir.hpp"
#include "support/test_paths.hpp"

namespace robodiff::testing {
namespace {

namespace fs = std::filesystem;

// README.md and the pages of docs/, relative to the source tree (a page without runnable
// blocks still has its markers checked).
std::vector<std::string> documentationPages() {
  std::vector<std::string> pages = {"README.md"};
  for (const auto& entry : fs::directory_iterator(sourceDir() / "docs"))
    if (entry.path().extension() == ".md") pages.push_back("docs/" + entry.path().filename().string());
  std::sort(pages.begin(), pages.end());
  return pages;
}

fs::path buildDir() { return cliPath().parent_path().parent_path(); }  // <build>/bin/robodiff

// The temporary directory as the repository root appears to a reader of the docs.
void linkRepositoryInto(const TempDir& dir) {
  fs::create_directory_symlink(sourceDir() / "examples", dir / "examples");
  fs::create_directory_symlink(buildDir(), dir / "build");
}

ProcessResult runBlock(const TempDir& dir, const std::string& text) {
  const fs::path script = dir.file(".block.sh", text);
  const std::string command = "cd " + shellQuote(dir.path().string()) +
                          " && env -u ROBODIFF_SERVER -u ROBODIFF_CACHE_DIR -u XDG_CACHE_HOME" +
                          " PATH=" + shellQuote(cliPath().parent_path().string()) + ":\"$PATH\"" +
                          " HOME=" + shellQuote(dir.path().string()) +
                          " timeout 600 bash -euo pipefail " + shellQuote(script.string());
  return runCommand(command);
}

class RunnableBlocks : public ::testing::TestWithParam<std::string> {};

TEST_P(RunnableBlocks, RunAsWritten) {
  const std::string page = GetParam();
  std::vector<MarkedBlock> blocks;
  ASSERT_NO_THROW(blocks = markedBlocks(readFile(sourceDir() / page))) << page;
  const bool any_runnable = std::any_of(blocks.begin(), blocks.end(),
                                        [](const MarkedBlock& b) { return b.kind == MarkedBlock::Kind::Runnable; });
  if (!any_runnable) return;  // nothing to run on this page
  TempDir dir;
  linkRepositoryInto(dir);
  for (const MarkedBlock& block : blocks) {
    if (block.kind == MarkedBlock::Kind::File) {
      dir.file(block.file_name, block.text);
      continue;
    }
    const auto start = std::chrono::steady_clock::now();
    const ProcessResult r = runBlock(dir, block.text);
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    EXPECT_EQ(r.exit_code, 0) << page << ":" << block.line << ": the block exited " << r.exit_code << "\n"
                              << block.text << "--- stdout:\n" << r.out << "--- stderr:\n" << r.err;
    std::printf("%s:%zu: %.1f s\n", page.c_str(), block.line, seconds);
  }
}

std::string pageTestName(const ::testing::TestParamInfo<std::string>& info) {
  std::string name;
  for (char c : info.param) name += std::isalnum(static_cast<unsigned char>(c)) ? c : '_';
  return name;
}

INSTANTIATE_TEST_SUITE_P(Docs, RunnableBlocks, ::testing::ValuesIn(documentationPages()), pageTestName);

// The README's tour is the first thing a newcomer runs: it must stay marked.
TEST(Docs, ReadmeTourIsRunnable) {
  const std::vector<MarkedBlock> blocks = markedBlocks(readFile(sourceDir() / "README.md"));
  int runnable = 0, files = 0;
  for (const MarkedBlock& block : blocks) (block.kind == MarkedBlock::Kind::Runnable ? runnable : files)++;
  EXPECT_GE(runnable, 3) << "the warmup, the CLI and the C++ steps";
  EXPECT_GE(files, 1) << "the C++ program";
}

// The runner itself: the repository's view and PATH are there, and any failing command
// fails the block (set -e), not only the last one.
TEST(Docs, BlocksRunFromTheRepositoryView) {
  TempDir dir;
  linkRepositoryInto(dir);
  const ProcessResult ok = runBlock(dir, "robodiff --help > /dev/null\ntest -f examples/robots/arm7.urdf\ntest -x build/bin/robodiff\n");
  EXPECT_EQ(ok.exit_code, 0) << ok.out << ok.err;
  EXPECT_NE(runBlock(dir, "false\necho still here\n").exit_code, 0);
  EXPECT_NE(runBlock(dir, "echo $UNSET_VARIABLE_OF_NOBODY\n").exit_code, 0);
}

TEST(Docs, MarkersNeedABlock) {
  EXPECT_THROW(markedBlocks("<!-- runnable -->\ntext\n"), std::runtime_error);
  EXPECT_THROW(markedBlocks("<!-- runnable -->\n```sh\necho never closed\n"), std::runtime_error);
  const auto blocks = markedBlocks("x\n<!-- file: a.cpp -->\n\n```cpp\nint main() {}\n```\n```sh\nnot marked\n```\n");
  ASSERT_EQ(blocks.size(), 1u);
  EXPECT_EQ(blocks[0].file_name, "a.cpp");
  EXPECT_EQ(blocks[0].text, "int main() {}\n");
  EXPECT_EQ(blocks[0].line, 4u);
}

}  // namespace
}  // namespace robodiff::testing
