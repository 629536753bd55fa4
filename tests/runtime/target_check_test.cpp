// The loader's CPU check (cache/target_check.hpp, applied by runtime's openCachedFunction): a cached library for an x86-64 level
// this CPU lacks, or built with -march=native on another CPU, is refused before dlopen.
// The levels are checked against /proc/cpuinfo's flags, a second source.
#include "robodiff/cache/target_check.hpp"

#include <gtest/gtest.h>

#include <fstream>
#include <set>
#include <sstream>

#include "robodiff/cache/cache.hpp"
#include "robodiff/cache/cache_key.hpp"
#include "robodiff/model/canonical.hpp"
#include "robodiff/runtime/cached_function.hpp"
#include "support/temp_dir.hpp"

namespace robodiff::runtime {
namespace {

using cache::cpuSupportsLevel;
using cache::targetProblem;

std::set<std::string> cpuinfoFlags() {
  std::ifstream f("/proc/cpuinfo");
  for (std::string line; std::getline(f, line);)
    if (line.rfind("flags", 0) == 0) {
      std::istringstream words(line.substr(line.find(':') + 1));
      std::set<std::string> flags;
      for (std::string w; words >> w;) flags.insert(w);
      return flags;
    }
  return {};
}

bool hasAll(const std::set<std::string>& flags, std::initializer_list<const char*> wanted) {
  for (const char* w : wanted)
    if (!flags.count(w)) return false;
  return true;
}

TEST(TargetCheck, LevelsAgreeWithTheCpuinfoFlags) {
  const std::set<std::string> f = cpuinfoFlags();
  if (f.empty()) GTEST_SKIP() << "no flags line in /proc/cpuinfo";
  const bool v2 = hasAll(f, {"cx16", "lahf_lm", "popcnt", "sse4_1", "sse4_2", "ssse3"});
  const bool v3 = v2 && hasAll(f, {"avx", "avx2", "bmi1", "bmi2", "f16c", "fma", "abm", "movbe", "xsave"});
  const bool v4 = v3 && hasAll(f, {"avx512f", "avx512bw", "avx512cd", "avx512dq", "avx512vl"});
  EXPECT_EQ(cpuSupportsLevel("x86-64-v2"), v2);
  EXPECT_EQ(cpuSupportsLevel("x86-64-v3"), v3);
  EXPECT_EQ(cpuSupportsLevel("x86-64-v4"), v4);
  EXPECT_FALSE(cpuSupportsLevel("x86-64-v9"));
}

TEST(TargetCheck, WhatMayRunHereAndWhatMayNot) {
  const std::string compiler = "cc (test) 1.0 -O2";
  EXPECT_EQ(targetProblem(compiler), "") << "an entry from before targets were recorded";
  EXPECT_EQ(targetProblem(compiler + " target=generic"), "");
  EXPECT_EQ(targetProblem(compiler + " target=" + cache::targetLabel(true)), "") << "native, this CPU";
  const std::string other = targetProblem(compiler + " target=native:0000000000000000");
  EXPECT_NE(other.find("another CPU"), std::string::npos) << other;
  EXPECT_NE(targetProblem(compiler + " target=sparc").find("unknown target 'sparc'"), std::string::npos);
  for (const char* level : {"x86-64-v2", "x86-64-v3", "x86-64-v4"})
    EXPECT_EQ(targetProblem(compiler + " target=" + level).empty(), cpuSupportsLevel(level)) << level;
}

TEST(TargetCheck, ALibraryForAnotherCpuIsRefusedBeforeItIsOpened) {
  testing::TempDir tmp;
  cache::Cache c = cache::Cache::open(tmp.path() / "cache");
  cache::EntryInfo info;
  info.model_hash = sha256Hex("model");
  info.robot = "arm7";
  info.function = "rnea";
  info.spec = R"({"function":"rnea"})";
  info.compiler = "cc (test) 1.0 -O2 -march=native target=native:0000000000000000";
  const std::string key = sha256Hex("another cpu's library");
  cache::ClaimResult claim = c.claim(key, info);
  ASSERT_EQ(claim.state, cache::ClaimResult::State::Claimed);
  cache::ArtifactFiles files;
  // Not an ELF file: were it opened, dlopen's error would say so instead.
  files.library = tmp.file("lib.so", "not a shared library");
  files.description = tmp.file("d.json", "{}");
  const cache::Artifact artifact = c.publish(*claim.claim, info, files);
  try {
    openCachedFunction(artifact, parseFunctionSpec(R"({"function": "rnea", "outputs": [{"kind": "value"}]})"));
    FAIL() << "opened a library built for another CPU";
  } catch (const codegen::LoadError& e) {
    const std::string message = e.what();
    EXPECT_NE(message.find("cannot run on this CPU"), std::string::npos) << message;
    EXPECT_NE(message.find(key), std::string::npos) << message;
    EXPECT_EQ(message.find("ELF"), std::string::npos) << "dlopen was tried: " << message;
  }
}

}  // namespace
}  // namespace robodiff::runtime
