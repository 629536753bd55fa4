// The lean link (src/lean_link.hpp): which compilers get it, read from their --version;
// a gcc build's library needs libm and nothing else, loads, and computes sin inside and
// beyond the sin-cos kernel's range (libm's sincos, resolved at load time), single and
// split; clang builds link without start files, tcc builds as before; loading a
// -ffast-math library leaves the floating-point mode alone.
#include "lean_link.hpp"

#if defined(__x86_64__)
#include <xmmintrin.h>
#endif

#include <algorithm>
#include <cmath>

#include <gtest/gtest.h>

#include "codegen_fixtures.hpp"
#include "robodiff/codegen/compiler.hpp"
#include "robodiff/codegen/loaded_library.hpp"

namespace robodiff::codegen {
namespace {

using namespace testing;
using detail::linkArguments;
using Strings = std::vector<std::string>;

bool mentions(const Strings& commands, const std::string& flag) {
  return std::any_of(commands.begin(), commands.end(),
                     [&](const std::string& c) { return c.find(" " + flag) != std::string::npos; });
}

TEST(LeanLink, GnuGccLinksWithoutStartFilesOrTheCLibrary) {
  const auto gcc = linkArguments("cc (Debian 12.2.0-14+deb12u1) 12.2.0\n"
                                 "Copyright (C) 2022 Free Software Foundation, Inc.\n");
  EXPECT_EQ(gcc.before_inputs, Strings{"-nostdlib"});
  EXPECT_EQ(gcc.libraries, (Strings{"-lm", "-lgcc"}));
  EXPECT_EQ(gcc.single_command, Strings{"-pipe"});
}

TEST(LeanLink, ClangLinksWithoutStartFilesAndOthersAsBefore) {
  const auto clang = linkArguments("Debian clang version 14.0.6\nTarget: x86_64-pc-linux-gnu\n");
  EXPECT_EQ(clang.before_inputs, Strings{"-nostartfiles"});
  EXPECT_EQ(clang.libraries, Strings{"-lm"});
  EXPECT_TRUE(clang.single_command.empty());
  for (const char* text : {"tcc version 0.9.27 (x86_64 Linux)\n", ""}) {
    const auto other = linkArguments(text);
    EXPECT_TRUE(other.before_inputs.empty()) << text;
    EXPECT_EQ(other.libraries, Strings{"-lm"}) << text;
    EXPECT_TRUE(other.single_command.empty()) << text;
  }
}

TEST(LeanLink, AGccLibraryNeedsLibmAloneAndComputesSinEverywhere) {
  Graph g;
  TempDir dir;
  const CompileReport r = compileLibrary(sinLibrary(g), dir / "lib.so", withCompiler("gcc"));
  ASSERT_EQ(r.commands.size(), 1u);
  EXPECT_TRUE(mentions(r.commands, "-nostdlib")) << r.commands[0];
  EXPECT_TRUE(mentions(r.commands, "-pipe")) << r.commands[0];
  EXPECT_EQ(neededLibraries(r.library), Strings{"libm.so.6"});
  for (const double x : {0.5, -2.5, 1e6, -3.0e7}) EXPECT_NEAR(evaluateAt(r.library, x), std::sin(x), 1e-15) << x;
}

TEST(LeanLink, ASplitGccLibraryLinksLeanAndItsPartsCompileApart) {
  Graph g;
  const FunctionDefinition f = chainFunction(g, "fk", 4);
  CodegenOptions options;
  options.split_threshold = 30;
  const GeneratedLibrary lib = generateLibrary(g, {f}, options);
  ASSERT_GE(lib.sources.size(), 3u);
  TempDir dir;
  const CompileReport r = compileLibrary(lib, dir / "lib.so", withCompiler("gcc"));
  ASSERT_EQ(r.commands.size(), lib.sources.size() + 1);
  EXPECT_NE(r.commands.back().find(" -nostdlib"), std::string::npos) << r.commands.back();
  const Strings compiles(r.commands.begin(), r.commands.end() - 1);
  EXPECT_FALSE(mentions(compiles, "-pipe")) << "parallel compiles fill the cores already";
  EXPECT_FALSE(mentions(compiles, "-nostdlib"));
  EXPECT_EQ(neededLibraries(r.library), Strings{"libm.so.6"});
  expectCompiledAsTheGraph(g, f, lib, 1e-12);
}

#if defined(__x86_64__)
// gcc 12 and clang 14 link crtfastmath.o into a -ffast-math -shared library: its
// constructor turns on flush-to-zero and denormals-are-zero in the thread that loads it,
// for every library that thread runs. Without start files it is not linked.
TEST(LeanLink, LoadingAFastMathLibraryLeavesTheFloatingPointModeAlone) {
  CompilerOptions fast;
  fast.fast_math = true;
  forEachInstalledCompiler({"gcc", "clang"}, fast, [](const std::string& compiler, const CompileReport& r) {
    const unsigned before = _mm_getcsr();
    const LoadedLibrary lib = LoadedLibrary::open(r.library);
    EXPECT_EQ(_mm_getcsr(), before) << compiler << ": loading the library changed MXCSR (0x8000 flush-to-zero, "
                                    << "0x40 denormals-are-zero)";
    _mm_setcsr(before);
    EXPECT_NEAR(evaluateAt(r.library, 0.5), std::sin(0.5), 1e-14) << compiler;
  });
}
#endif

TEST(LeanLink, ClangAndTccBuildsKeepTheCLibrary) {
  forEachInstalledCompiler({"clang", "tcc"}, {}, [](const std::string& compiler, const CompileReport& r) {
    EXPECT_FALSE(mentions(r.commands, "-nostdlib")) << compiler;
    EXPECT_EQ(mentions(r.commands, "-nostartfiles"), compiler == "clang") << compiler;
    const Strings needed = neededLibraries(r.library);
    EXPECT_NE(std::find(needed.begin(), needed.end(), "libc.so.6"), needed.end()) << compiler;
    EXPECT_NEAR(evaluateAt(r.library, 1e6), std::sin(1e6), 1e-15) << compiler;
  });
}

}  // namespace
}  // namespace robodiff::codegen
