// gcc's pass toggles (src/gcc_passes.hpp): which compilers get them, read from their
// --version; a build with gcc passes them to every command and still computes the
// graph's values; a build with clang or tcc, which would reject or ignore them, does not.
#include "gcc_passes.hpp"

#include <algorithm>
#include <cmath>

#include <gtest/gtest.h>

#include "codegen_fixtures.hpp"
#include "robodiff/codegen/compiler.hpp"
#include "robodiff/codegen/loaded_library.hpp"

namespace robodiff::codegen {
namespace {

using namespace testing;
using detail::gccPassToggles;

const char* const kDebianGcc12 =
    "cc (Debian 12.2.0-14+deb12u1) 12.2.0\n"
    "Copyright (C) 2022 Free Software Foundation, Inc.\n"
    "This is free software; see the source for copying conditions.\n";

bool contains(const std::vector<std::string>& v, const std::string& s) {
  return std::find(v.begin(), v.end(), s) != v.end();
}

TEST(GccPasses, GnuGccElevenOrNewerGetsThemWhateverItsName) {
  const std::vector<std::string> toggles = gccPassToggles(kDebianGcc12);
  ASSERT_GE(toggles.size(), 10u);
  for (const std::string& t : toggles) EXPECT_EQ(t.rfind("-fno-", 0), 0u) << t;
  EXPECT_TRUE(contains(toggles, "-fno-tree-pre"));
  EXPECT_TRUE(contains(toggles, "-fno-tree-slp-vectorize"));
  EXPECT_EQ(gccPassToggles("gcc (GCC) 13.2.1 20231011 (Red Hat 13.2.1-4)\n"
                           "Copyright (C) 2023 Free Software Foundation, Inc.\n"),
            toggles);
  EXPECT_EQ(gccPassToggles("x86_64-linux-gnu-gcc-11 (Ubuntu 11.4.0-1ubuntu1~22.04) 11.4.0\n"
                           "Copyright (C) 2021 Free Software Foundation, Inc.\n"),
            toggles);
}

TEST(GccPasses, OtherCompilersOlderGccAndUnreadableTextsGetNone) {
  EXPECT_TRUE(gccPassToggles("gcc (Debian 10.2.1-6) 10.2.1 20210110\n"
                             "Copyright (C) 2020 Free Software Foundation, Inc.\n")
                  .empty());
  EXPECT_TRUE(gccPassToggles("Debian clang version 14.0.6\nTarget: x86_64-pc-linux-gnu\n").empty());
  EXPECT_TRUE(gccPassToggles("tcc version 0.9.27 (x86_64 Linux)\n").empty());
  EXPECT_TRUE(gccPassToggles("").empty());
  EXPECT_TRUE(gccPassToggles("Free Software Foundation\n").empty()) << "no version on the first line";
  EXPECT_NO_THROW(gccPassToggles("cc 123456789012345678901234567890.1.1\nFree Software Foundation\n"));
}

TEST(GccPasses, AGccBuildPassesThemToEveryCommand) {
  Graph g;
  TempDir dir;
  const CompileReport r = compileLibrary(sinLibrary(g), dir / "lib.so", withCompiler("gcc"));
  const std::vector<std::string> base = compilerFlags(withCompiler("gcc"));
  ASSERT_GT(r.flags.size(), base.size() + 10) << "gcc's toggles were not added";
  EXPECT_TRUE(std::equal(base.begin(), base.end(), r.flags.begin()));
  for (std::size_t i = base.size(); i < r.flags.size(); ++i) {
    for (const std::string& command : r.commands) EXPECT_NE(command.find(r.flags[i]), std::string::npos) << command;
  }
  EXPECT_NEAR(evaluateAt(r.library, 0.5), std::sin(0.5), 1e-15);
}

TEST(GccPasses, ClangAndTccBuildsDoNotGetThem) {
  forEachInstalledCompiler({"clang", "tcc"}, {}, [](const std::string& compiler, const CompileReport& r) {
    EXPECT_EQ(r.flags, compilerFlags(withCompiler(compiler))) << compiler;
    EXPECT_NEAR(evaluateAt(r.library, 0.5), std::sin(0.5), 1e-15) << compiler;
  });
}

}  // namespace
}  // namespace robodiff::codegen
