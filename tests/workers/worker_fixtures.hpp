// Helpers shared by the worker tests: small, fast builds (arm7, O0, no -march=native),
// fake compilers as scripts, and waiting for a condition with a deadline.
#pragma once

#include <signal.h>

#include <chrono>
#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <thread>

#include <gtest/gtest.h>

#include "robodiff/cache/cache.hpp"
#include "robodiff/cache/prepared_build.hpp"
#include "robodiff/functions/function_spec.hpp"
#include "robodiff/model/canonical.hpp"
#include "robodiff/model/urdf_loader.hpp"
#include "robodiff/workers/build_job.hpp"
#include "support/temp_dir.hpp"
#include "support/test_paths.hpp"

namespace robodiff::testing {

// RNEA's value only: the smallest build that still goes through every stage.
inline const char* kRneaValueSpec =
    R"({"function": "rnea", "outputs": [{"kind": "value"}], "build": {"optimization": "O0", "march_native": false}})";

inline std::string arm7Urdf() { return readFile(sourceDir() / "examples/robots/arm7.urdf"); }

// Polls `condition` until it holds or `timeout` passes; returns whether it held.
inline bool waitFor(const std::function<bool()>& condition,
                    std::chrono::milliseconds timeout = std::chrono::seconds(20)) {
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  while (!condition()) {
    if (std::chrono::steady_clock::now() >= deadline) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  return true;
}

// The pid written in a file by a script, once the file holds a whole line.
inline std::optional<pid_t> pidFromFile(const std::filesystem::path& path) {
  std::error_code ec;
  if (!std::filesystem::exists(path, ec)) return std::nullopt;
  const std::string text = readFile(path);
  if (text.empty() || text.back() != '\n') return std::nullopt;
  return static_cast<pid_t>(std::stol(text));
}

// True when no process `pid` runs: gone, or a zombie nobody has reaped yet (dead all the
// same; its parent was killed and whoever inherits it reaps it when it does).
inline bool processIsDead(pid_t pid) {
  const std::string stat_path = "/proc/" + std::to_string(pid) + "/stat";
  std::error_code ec;
  if (!std::filesystem::exists(stat_path, ec)) return true;
  std::string text;
  try {
    text = readFile(stat_path);
  } catch (const std::exception&) {
    return true;  // vanished meanwhile
  }
  const auto paren = text.rfind(')');
  return paren != std::string::npos && paren + 2 < text.size() && (text[paren + 2] == 'Z' || text[paren + 2] == 'X');
}

// A compiler that says who it is, then writes its pid to DIR/compiler.pid, starts a
// child that sleeps (its pid in DIR/sleep.pid) and waits for it.
inline std::filesystem::path sleepingCompiler(const TempDir& dir) {
  const std::string d = dir.path().string();
  return dir.script("sleeping-cc", "case \"$1\" in --version|-v) echo 'sleeping-cc 1.0'; exit 0;; esac\n"
                                   "echo $$ > '" + d + "/compiler.pid.tmp' && mv '" + d + "/compiler.pid.tmp' '" + d +
                                       "/compiler.pid'\n"
                                       "sleep 30 &\n"
                                       "echo $! > '" + d + "/sleep.pid.tmp' && mv '" + d + "/sleep.pid.tmp' '" + d +
                                       "/sleep.pid'\n"
                                       "wait\n");
}

// A compiler that fails like a real one.
inline std::filesystem::path failingCompiler(const TempDir& dir) {
  return dir.script("failing-cc", "case \"$1\" in --version|-v) echo 'failing-cc 1.0'; exit 0;; esac\n"
                                  "echo 'model.c:1:1: error: simulated failure' >&2\n"
                                  "exit 1\n");
}

// A build request for (urdf, spec) claimed in `cache`, as the requesting process makes it.
struct ClaimedBuild {
  cache::PreparedBuild prepared;
  workers::BuildRequest request;
};

inline ClaimedBuild claimBuild(cache::Cache& cache, const std::string& urdf, const std::string& spec_text,
                               const std::string& compiler = {}) {
  const Model model = loadUrdfString(urdf, RootJoint::Fixed, "arm7.urdf");
  const FunctionSpec spec = parseFunctionSpec(spec_text, "test spec");
  ClaimedBuild b{cache::prepareBuild(model, canonicalHash(model), spec, "", compiler), {}};
  const cache::ClaimResult claimed = cache.claim(b.prepared.key, b.prepared.info);
  if (claimed.state != cache::ClaimResult::State::Claimed)
    throw std::runtime_error("claimBuild: the key " + b.prepared.key + " is not free in the test cache");
  workers::BuildRequest& r = b.request;
  r.urdf = urdf;
  r.urdf_source = "arm7.urdf";
  r.spec = spec_text;
  r.spec_source = "test spec";
  r.compiler = compiler;
  r.compiler_timeout = std::chrono::seconds(60);
  r.compiler_jobs = 1;
  r.cache_dir = cache.dir().string();
  r.cache_budget_bytes = cache.options().budget_bytes;
  r.claim = *claimed.claim;
  r.info = b.prepared.info;
  return b;
}

// Nothing of a key left in the cache: no index row, no directory, no staging.
inline void expectNothingLeft(cache::Cache& cache, const std::string& key) {
  EXPECT_FALSE(cache.entry(key).has_value()) << "an index row is left for " << key;
  const auto object_dir = cache.dir() / "objects" / key.substr(0, 2) / key;
  EXPECT_FALSE(std::filesystem::exists(object_dir)) << object_dir << " exists";
  const auto staging = cache.dir() / "staging";
  if (std::filesystem::exists(staging)) {
    EXPECT_TRUE(std::filesystem::is_empty(staging)) << "files are left under " << staging;
  }
}

}  // namespace robodiff::testing
