// The fleet for bench/fleet_bench.cpp (issue 23): one build host and fresh robot hosts as
// robodiffd processes on this machine (own caches, DDS on loopback in the benchmark's own
// domain, no iceoryx, no HTTP), the key pair the build host signs with, clients of a robot
// over DDS or in local mode on a cache, and the figures a robot's log reports.
#pragma once

#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <functional>
#include <memory>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "bench_daemon.hpp"
#include "robodiff/cache/artifact_signing.hpp"
#include "robodiff/cache/cache.hpp"
#include "robodiff/client/client.hpp"

namespace bench {

namespace fs = std::filesystem;

// A robot of the run: its URDF and whether it gets a floating base.
struct FleetRobot {
  std::string name;  // what --robots names it
  fs::path urdf;
  bool floating = false;
};

// A function of the run: a spec of examples/specs/ (its default build options: native,
// which a robot host turns into its x86-64 level).
struct FleetFunction {
  std::string label;
  std::string spec;  // the JSON text
};

class BenchFleet {
 public:
  static constexpr const char* kBuildService = "fleet_bench_build";

  BenchFleet(fs::path dir, int domain) : dir_(std::move(dir)), domain_(domain) {
    fs::create_directories(dir_);
    robodiff::cache::SigningKey::generate().writePair(dir_ / "keys", "build");
  }
  const fs::path& dir() const { return dir_; }
  int domain() const { return domain_; }

  // The build host: compiles, signs with the run's key, serves chunks of at most
  // `chunk_size` (robots ask for their own, capped by this).
  std::unique_ptr<Daemon> buildHost(const std::string& chunk_size) const {
    return start("build", {"--set", std::string("dds.service=") + kBuildService, "--set", "fleet.role=build",
                           "--set", "fleet.signing_key=" + (dir_ / "keys/build.key").string(), "--set",
                           "fleet.chunk_size=" + chunk_size});
  }

  // A robot host (service "robodiff", compiles nothing) on a new empty cache named `name`,
  // asking the build host in chunks of `chunk_size` and trusting the run's key.
  std::unique_ptr<Daemon> robot(const std::string& name, const std::string& chunk_size) const {
    fs::remove_all(robotCache(name));
    return start(name, {"--interpreter-only", "--set", "fleet.role=robot", "--set",
                        std::string("fleet.build_hosts=") + kBuildService, "--set",
                        "fleet.trusted_keys=" + (dir_ / "keys/build.pub").string(), "--set",
                        "fleet.chunk_size=" + chunk_size});
  }
  fs::path robotCache(const std::string& name) const { return dir_ / (name + "-cache"); }

 private:
  std::unique_ptr<Daemon> start(const std::string& name, std::vector<std::string> args) const {
    const std::vector<std::string> common = {"--no-iceoryx", "--no-http", "--log-format", "json"};
    args.insert(args.begin(), common.begin(), common.end());
    return std::make_unique<Daemon>(ROBODIFFD_PATH, dir_ / (name + "-cache"), domain_, dir_ / (name + ".log"), args);
  }

  fs::path dir_;
  int domain_;
};

// A client of the robot host over DDS, or in local mode on `cache_dir` with no server
// (an iceoryx service nobody serves, a DDS domain nobody uses: the library is found by
// its portable key, as a robot's controller does when its robodiffd is gone).
inline robodiff::client::ClientOptions fleetClientOptions(int domain, robodiff::client::Mode mode,
                                                          const fs::path& cache_dir = {}) {
  robodiff::client::ClientOptions o;
  o.server.mode = mode;
  o.server.dds_domain = domain;
  o.server.shm_service = "fleet-bench-nobody-" + std::to_string(::getpid());
  o.cache_dir = cache_dir;
  o.timeout = std::chrono::seconds(60);
  return o;
}

// A number field of the first log line of `event` ("seconds", "bytes"); NaN when absent.
inline double logNumber(const std::string& log, const std::string& event, const std::string& field) {
  const std::size_t line = log.find("\"event\":\"" + event + "\"");
  if (line == std::string::npos) return std::nan("");
  const std::size_t end = log.find('\n', line);
  const std::size_t at = log.find("\"" + field + "\":", line);
  if (at == std::string::npos || (end != std::string::npos && at > end)) return std::nan("");
  return std::strtod(log.c_str() + at + field.size() + 3, nullptr);
}

// The target label the first entry of a cache was built for ("x86-64-v4", "native:...").
inline std::string cacheTarget(const fs::path& dir) {
  const std::vector<robodiff::cache::Entry> entries = robodiff::cache::Cache::open(dir).list();
  if (entries.empty()) return "(empty cache)";
  const std::string& compiler = entries[0].info.compiler;
  const std::size_t at = compiler.rfind(" target=");
  return at == std::string::npos ? compiler : compiler.substr(at + 8);
}

// Polls ListFunctions every `poll` until every function in `ids` is compiled; calls
// `progress(compiled, elapsed seconds)` about every 10 s. Exits naming the function when
// one fails or `timeout` passes.
inline void waitAllCompiled(robodiff::client::Client& c, const std::vector<std::string>& ids,
                            std::chrono::seconds timeout, std::chrono::milliseconds poll,
                            const std::function<void(std::size_t, double)>& progress = {}) {
  using Clock = std::chrono::steady_clock;
  const auto start = Clock::now();
  auto next_report = start + std::chrono::seconds(10);
  for (;;) {
    std::size_t compiled = 0;
    for (const robodiff::rpc::FunctionSummary& f : c.functions()) {
      bool wanted = false;
      for (const std::string& id : ids) wanted = wanted || id == f.function_id;
      if (!wanted) continue;
      if (f.state == robodiff::rpc::FunctionState::Failed) {
        std::fprintf(stderr, "fleet_bench: %s (%s) failed on the robot host: %s\n", f.function_name.c_str(),
                     f.function_id.c_str(), f.message.c_str());
        std::exit(1);
      }
      compiled += f.compiled ? 1 : 0;
    }
    if (compiled == ids.size()) return;
    const auto now = Clock::now();
    if (now - start > timeout) {
      std::fprintf(stderr, "fleet_bench: %zu of %zu functions compiled on the robot host after %lld s\n", compiled,
                   ids.size(), static_cast<long long>(timeout.count()));
      std::exit(1);
    }
    if (progress && now >= next_report) {
      progress(compiled, std::chrono::duration<double>(now - start).count());
      next_report = now + std::chrono::seconds(10);
    }
    std::this_thread::sleep_for(poll);
  }
}

}  // namespace bench
