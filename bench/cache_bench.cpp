// Cache and worker benchmarks (issue 4), one run, one table:
//   - cold warmup of the Panda set {rnea, aba, crba, fk} with Jacobians into a fresh cache,
//     with 1 worker and with 2 workers (real robodiff-worker processes);
//   - warm hit: Cache::find (index lookup, SHA-256 of the library, pin) + dlopen +
//     descriptor check of the RNEA Jacobian library, and each part alone.
// Uses ../shared's Panda when there, else the project's arm7. Run by hand:
//   build/bin/cache_bench [--robot URDF --frame NAME] [--hits N]
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

#include <unistd.h>

#include "robodiff/cache/cache.hpp"
#include "robodiff/codegen/loaded_library.hpp"
#include "robodiff/workers/cached_builder.hpp"
#include "robodiff/workers/worker_pool.hpp"

namespace fs = std::filesystem;
using namespace robodiff;
using Clock = std::chrono::steady_clock;

namespace {

struct Robot {
  fs::path urdf;
  std::string frame, label;
};

Robot defaultRobot() {
  const fs::path panda = fs::path(ROBODIFF_SHARED_DIR) / "robots" / "panda_arm_fixed_fingers.urdf";
  if (fs::exists(panda)) return {panda, "panda_hand", "Panda"};
  return {fs::path(ROBODIFF_SOURCE_DIR) / "examples" / "robots" / "arm7.urdf", "tool", "arm7 (no ../shared)"};
}

std::string readText(const fs::path& p) {
  std::ifstream in(p);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

// The four specs, the fk one with the robot's frame, written into dir.
std::vector<std::string> writeSpecs(const fs::path& dir, const std::string& frame) {
  const fs::path src = ROBODIFF_SOURCE_DIR;
  std::vector<std::string> out;
  for (const fs::path& p : {src / "examples/specs/rnea_jacobian.json", src / "examples/specs/aba_jacobian.json",
                            src / "bench/specs/crba_jacobian.json", src / "bench/specs/fk_jacobian.json"}) {
    std::string text = readText(p);
    if (const auto at = text.find("\"FRAME\""); at != std::string::npos) text.replace(at, 7, "\"" + frame + "\"");
    const fs::path to = dir / p.filename();
    std::ofstream(to) << text;
    out.push_back(to.string());
  }
  return out;
}

struct ColdRun {
  double seconds = 0;
  std::vector<workers::BuildStatus> statuses;
};

ColdRun coldWarmup(const Robot& robot, const std::vector<std::string>& specs, const fs::path& cache_dir,
                   unsigned workers) {
  cache::Cache cache = cache::Cache::open(cache_dir);
  workers::WorkerPoolOptions pool_options;
  pool_options.workers = workers;
  workers::WorkerPool pool(pool_options);
  workers::CachedBuilder builder(cache, pool);
  std::vector<workers::BuildTarget> targets;
  for (const std::string& s : specs) targets.push_back({robot.urdf.string(), false, s, ""});
  const auto t0 = Clock::now();
  ColdRun run;
  run.statuses = builder.buildAll(targets);
  run.seconds = std::chrono::duration<double>(Clock::now() - t0).count();
  for (const workers::BuildStatus& s : run.statuses) {
    if (s.state != workers::BuildState::Done) {
      std::cerr << "cache_bench: " << s.function << " did not build: " << workers::toString(s.state) << " "
                << s.message << "\n";
      std::exit(1);
    }
  }
  return run;
}

struct Percentiles {
  double median = 0, p90 = 0, max = 0;
};

template <class F>
Percentiles timeMs(int n, F&& f) {
  std::vector<double> ms;
  for (int i = 0; i < n; ++i) {
    const auto t0 = Clock::now();
    f();
    ms.push_back(std::chrono::duration<double, std::milli>(Clock::now() - t0).count());
  }
  std::sort(ms.begin(), ms.end());
  return {ms[ms.size() / 2], ms[ms.size() * 9 / 10], ms.back()};
}

}  // namespace

// A new process's first hit: open the cache, find (hash check), dlopen. Prints ms.
int firstHit(const fs::path& dir, const std::string& key, const std::string& name) {
  const auto t0 = Clock::now();
  cache::Cache cache = cache::Cache::open(dir);
  const std::optional<cache::Artifact> a = cache.find(key);
  if (!a) return 1;
  codegen::LoadedLibrary::open(a->library()).function(name);
  std::printf("%.3f\n", std::chrono::duration<double, std::milli>(Clock::now() - t0).count());
  return 0;
}

int main(int argc, char** argv) {
  if (argc == 5 && std::string(argv[1]) == "--first-hit") return firstHit(argv[2], argv[3], argv[4]);
  Robot robot = defaultRobot();
  int hits = 200;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--robot" && i + 1 < argc) robot = {argv[++i], robot.frame, argv[i]};
    else if (a == "--frame" && i + 1 < argc) robot.frame = argv[++i];
    else if (a == "--hits" && i + 1 < argc) hits = std::atoi(argv[++i]);
    else {
      std::cerr << "usage: cache_bench [--robot URDF --frame NAME] [--hits N]\n";
      return 2;
    }
  }
  const fs::path tmp = fs::temp_directory_path() / ("robodiff-cache-bench-" + std::to_string(::getpid()));
  fs::create_directories(tmp);
  const std::vector<std::string> specs = writeSpecs(tmp, robot.frame);

  std::cerr << "cold warmup, 1 worker...\n";
  const ColdRun one = coldWarmup(robot, specs, tmp / "cache1", 1);
  std::cerr << "cold warmup, 2 workers...\n";
  const ColdRun two = coldWarmup(robot, specs, tmp / "cache2", 2);

  // Warm hits on the RNEA Jacobian library of the second cache.
  cache::Cache cache = cache::Cache::open(tmp / "cache2");
  const std::string key = two.statuses[0].key;
  const std::string name = two.statuses[0].function;
  const Percentiles find = timeMs(hits, [&] {
    if (!cache.find(key)) std::abort();
  });
  const fs::path library = cache.find(key)->library();
  const Percentiles open = timeMs(hits, [&] { codegen::LoadedLibrary::open(library).function(name); });
  const Percentiles hit = timeMs(hits, [&] {
    const std::optional<cache::Artifact> a = cache.find(key);
    codegen::LoadedLibrary::open(a->library()).function(name);
  });
  const std::uint64_t bytes = cache.find(key)->entry().library_bytes;
  // The same in fresh processes (cache opened, index read, library hashed and loaded).
  std::vector<double> fresh;
  for (int i = 0; i < 20; ++i) {
    const std::string command = "/proc/" + std::to_string(::getpid()) + "/exe --first-hit '" + (tmp / "cache2").string() +
                                "' " + key + " " + name;
    FILE* p = ::popen(command.c_str(), "r");
    double ms = 0;
    if (!p || std::fscanf(p, "%lf", &ms) != 1) std::abort();
    ::pclose(p);
    fresh.push_back(ms);
  }
  std::sort(fresh.begin(), fresh.end());

  std::printf("## Cache and workers (%s)\n\n", robot.label.c_str());
  std::printf("Cold warmup of {rnea, aba, crba, fk} with Jacobians, gcc, fresh cache each:\n\n");
  std::printf("| function | 1 worker: s | 2 workers: s |\n|---|---:|---:|\n");
  for (std::size_t i = 0; i < specs.size(); ++i)
    std::printf("| %s | %.2f | %.2f |\n", one.statuses[i].function.c_str(), one.statuses[i].seconds,
                two.statuses[i].seconds);
  std::printf("| **all (wall clock)** | **%.2f** | **%.2f** |\n\n", one.seconds, two.seconds);
  std::printf("Speed-up with 2 workers: %.2fx (2 cores).\n\n", one.seconds / two.seconds);
  std::printf("Warm hit of %s (library %.0f KiB), %d repetitions in this process:\n\n", name.c_str(),
              static_cast<double>(bytes) / 1024.0, hits);
  std::printf("| measurement | median ms | p90 ms | max ms | target | median / target |\n|---|---:|---:|---:|---:|---:|\n");
  std::printf("| find (index + SHA-256 + pin) | %.3f | %.3f | %.3f | | |\n", find.median, find.p90, find.max);
  std::printf("| dlopen + descriptor check | %.3f | %.3f | %.3f | | |\n", open.median, open.p90, open.max);
  std::printf("| **warm hit (both)** | **%.3f** | %.3f | %.3f | < 5 | %.3f |\n", hit.median, hit.p90, hit.max,
              hit.median / 5.0);
  std::printf("| **first hit in a new process** (open cache + find + dlopen; 20 processes) | **%.3f** | %.3f | %.3f | < 5 | %.3f |\n",
              fresh[fresh.size() / 2], fresh[fresh.size() * 9 / 10], fresh.back(), fresh[fresh.size() / 2] / 5.0);
  fs::remove_all(tmp);
  return 0;
}
