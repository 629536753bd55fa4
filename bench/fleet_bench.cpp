// Fleet benchmarks (issue 23), one run, printed as tables at the end. One build host
// (robodiffd, fleet.role = build) and fresh robot hosts (fleet.role = robot, compiling
// nothing) on this machine, DDS on loopback in a domain of the run's own:
//   1. Fetch latency: a fresh robot (empty cache) is asked for a function the build host
//      has; from just before GetFunction to the end of the first Evaluate served by the
//      fetched library (ListFunctions polled every 1 ms until `compiled`). Median, min,
//      max over the rounds, with the robot log's transfer + verify + install time and bytes.
//      Targets: Panda RNEA Jacobian <= 30 ms, Talos ABA Jacobian <= 300 ms.
//   2. The same for the largest library with the robots' chunk size at 64, 256, 512 KiB.
//   3. Local-call parity: Client in local mode on a fetched robot cache (the robot's x86-64
//      level) against one on a cache built natively here (`robodiff warmup`), the same
//      inputs, batches alternated. Target: within 1.05x.
// Robots: ../shared's Panda (fixed base) and Talos (floating base) when there, and the
// project's arm7 and humanoid (floating base). Functions: RNEA and ABA with their Jacobians.
//   build/bin/fleet_bench [--rounds N] [--quick] [--robots arm7,humanoid,panda,talos]
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <filesystem>
#include <map>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "fleet_bench_hosts.hpp"

namespace fs = std::filesystem;
using namespace robodiff;
using bench::FleetFunction;
using bench::FleetRobot;
using Clock = std::chrono::steady_clock;

namespace {

struct Args {
  int rounds = 10;
  bool quick = false;
  std::vector<std::string> robots = {"arm7", "humanoid", "panda", "talos"};
};

std::vector<std::string> splitNames(const std::string& text) {
  std::vector<std::string> names;
  std::stringstream in(text);
  for (std::string name; std::getline(in, name, ',');)
    if (!name.empty()) names.push_back(name);
  return names;
}

Args parseArgs(int argc, char** argv) {
  Args a;
  bool rounds_given = false;
  for (int i = 1; i < argc; ++i) {
    const std::string flag = argv[i];
    const bool has_value = i + 1 < argc;
    if (flag == "--quick") a.quick = true;
    else if (flag == "--rounds" && has_value) a.rounds = std::max(1, std::atoi(argv[++i])), rounds_given = true;
    else if (flag == "--robots" && has_value) a.robots = splitNames(argv[++i]);
    else {
      std::fprintf(stderr, "usage: fleet_bench [--rounds N] [--quick] [--robots arm7,humanoid,panda,talos]\n");
      std::exit(2);
    }
  }
  if (a.quick && !rounds_given) a.rounds = 3;
  return a;
}

// The robots asked for that exist here (../shared's are skipped with a message when absent).
std::vector<FleetRobot> robotsOf(const Args& args) {
  const fs::path shared = fs::path(ROBODIFF_SHARED_DIR) / "robots";
  const fs::path own = fs::path(ROBODIFF_SOURCE_DIR) / "examples/robots";
  const std::map<std::string, FleetRobot> known = {
      {"arm7", {"arm7", own / "arm7.urdf", false}},
      {"humanoid", {"humanoid", own / "humanoid.urdf", true}},
      {"panda", {"panda", shared / "panda_arm_fixed_fingers.urdf", false}},
      {"talos", {"talos", shared / "talos_reduced.urdf", true}},
  };
  std::vector<FleetRobot> robots;
  for (const std::string& name : args.robots) {
    const auto it = known.find(name);
    if (it == known.end()) {
      std::fprintf(stderr, "fleet_bench: unknown robot '%s' (arm7, humanoid, panda, talos)\n", name.c_str());
      std::exit(2);
    }
    if (!fs::exists(it->second.urdf)) {
      std::fprintf(stderr, "fleet_bench: skipping %s: %s is absent (../shared not here)\n", name.c_str(),
                   it->second.urdf.c_str());
      continue;
    }
    robots.push_back(it->second);
  }
  return robots;
}

struct SpecFile {
  FleetFunction function;
  fs::path path;
};

std::vector<SpecFile> functionsOfTheRun() {
  const fs::path specs = fs::path(ROBODIFF_SOURCE_DIR) / "examples/specs";
  std::vector<SpecFile> functions;
  for (const auto& [label, file] : {std::pair{"RNEA Jacobian", "rnea_jacobian.json"}, {"ABA Jacobian", "aba_jacobian.json"}})
    functions.push_back({{label, bench::readText(specs / file)}, specs / file});
  return functions;
}

void check(const Status& s, const char* what) {
  if (s.ok()) return;
  std::fprintf(stderr, "fleet_bench: %s: %s: %s\n", what, toString(s.code).c_str(), s.message.c_str());
  std::exit(1);
}

double msBetween(Clock::time_point a, Clock::time_point b) {
  return std::chrono::duration<double, std::milli>(b - a).count();
}

// Inputs every knot uses: small values, a unit quaternion left as the solver finds it.
std::vector<double> inputsFor(const client::Function& f) {
  std::vector<double> in(f.inputCount());
  for (std::size_t i = 0; i < in.size(); ++i) in[i] = 0.1 * std::sin(1.0 + 0.37 * i);
  return in;
}

// One fresh robot's fetch of one function, in milliseconds from just before GetFunction.
struct Sample {
  double first_eval_ms = 0;  // t1 - t0: the first Evaluate by the fetched library returned
  double get_ms = 0;         // GetFunction returned (the interpreter serves from then on)
  double compiled_ms = 0;    // ListFunctions said `compiled`
  double fetch_ms = 0;       // the robot log's fleet_artifact_fetched "seconds"
  double bytes = 0;          // ... and "bytes"
};

// `name`: the robot host's cache and log (dir/<name>-cache, dir/<name>.log), made anew.
Sample fetchOnce(const bench::BenchFleet& fleet, const FleetRobot& robot, const FleetFunction& function,
                 const std::string& chunk, const std::string& name = "robot") {
  Sample s;
  std::unique_ptr<bench::Daemon> host = fleet.robot(name, chunk);
  {
    client::Client c(bench::fleetClientOptions(fleet.domain(), client::Mode::Dds));
    const client::ModelInfo model = c.loadModelFile(robot.urdf, robot.floating);
    const Clock::time_point t0 = Clock::now();
    const client::Function f = c.function(model, function.spec);
    const Clock::time_point got = Clock::now();
    bench::waitAllCompiled(c, {f.id()}, std::chrono::seconds(120), std::chrono::milliseconds(1));
    const Clock::time_point compiled = Clock::now();
    const std::vector<double> in = inputsFor(f);
    std::vector<double> out(f.outputCount());
    check(f.evaluate(in, out), "Evaluate");
    const Clock::time_point t1 = Clock::now();
    s = {msBetween(t0, t1), msBetween(t0, got), msBetween(t0, compiled), 0, 0};
  }
  host.reset();  // stopped: its log is complete
  const std::string log = bench::readText(fleet.dir() / (name + ".log"));
  s.fetch_ms = 1000 * bench::logNumber(log, "fleet_artifact_fetched", "seconds");
  s.bytes = bench::logNumber(log, "fleet_artifact_fetched", "bytes");
  return s;
}

// The build host builds every function of the run for this CPU's level: a first robot
// asks for them all and waits (the Talos ABA Jacobian takes minutes on 2 cores).
void warmBuildHost(const bench::BenchFleet& fleet, const std::vector<FleetRobot>& robots,
                   const std::vector<SpecFile>& functions) {
  std::fprintf(stderr, "warm-up: the build host builds %zu functions for the robots' level...\n",
               robots.size() * functions.size());
  const Clock::time_point start = Clock::now();
  std::unique_ptr<bench::Daemon> host = fleet.robot("warm", "256KiB");
  client::Client c(bench::fleetClientOptions(fleet.domain(), client::Mode::Dds));
  std::vector<std::string> ids;
  for (const FleetRobot& r : robots) {
    const client::ModelInfo model = c.loadModelFile(r.urdf, r.floating);
    for (const SpecFile& f : functions) ids.push_back(c.function(model, f.function.spec).id());
  }
  bench::waitAllCompiled(c, ids, std::chrono::minutes(60), std::chrono::milliseconds(200),
                         [&](std::size_t compiled, double seconds) {
                           std::fprintf(stderr, "warm-up: %zu of %zu fetched by the first robot (%.0f s)\n", compiled,
                                        ids.size(), seconds);
                         });
  std::fprintf(stderr, "warm-up: done in %.0f s; the robots run %s\n", msBetween(start, Clock::now()) / 1000,
               bench::cacheTarget(fleet.robotCache("warm")).c_str());
}

struct Stats {
  double median = 0, min = 0, max = 0;
};

Stats statsOf(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return {v[v.size() / 2], v.front(), v.back()};
}

template <class Field>
Stats statsOf(const std::vector<Sample>& samples, Field field) {
  std::vector<double> v;
  for (const Sample& s : samples) v.push_back(s.*field);
  return statsOf(v);
}

struct FetchRow {
  std::string robot, function, target;  // target: the bound, or empty
  std::vector<Sample> samples;
};

std::string targetOf(const FleetRobot& robot, const std::string& function) {
  if (robot.name == "panda" && function == "RNEA Jacobian") return "<= 30 ms";
  if (robot.name == "talos" && function == "ABA Jacobian") return "<= 300 ms";
  return "";
}

std::string verdict(const std::string& target, double median_ms) {
  if (target.empty()) return "";
  const double bound = std::atof(target.c_str() + 3);
  return target + (median_ms <= bound ? ": met" : ": MISSED");
}

void printFetchTable(const std::vector<FetchRow>& rows, int rounds) {
  std::printf("fetch to first evaluation on a fresh robot host, %d rounds (ms; chunks of 256 KiB):\n\n", rounds);
  std::printf("| %-9s | %-13s | %8s | %8s | %8s | %13s | %10s | %9s | %s\n", "robot", "function", "median", "min",
              "max", "GetFunction", "fetch (log)", "KiB", "target (median)");
  std::printf("|%s|%s|%s|%s|%s|%s|%s|%s|---\n", std::string(11, '-').c_str(), std::string(15, '-').c_str(),
              std::string(10, '-').c_str(), std::string(10, '-').c_str(), std::string(10, '-').c_str(),
              std::string(15, '-').c_str(), std::string(13, '-').c_str(), std::string(11, '-').c_str());
  for (const FetchRow& r : rows) {
    const Stats total = statsOf(r.samples, &Sample::first_eval_ms);
    std::printf("| %-9s | %-13s | %8.1f | %8.1f | %8.1f | %13.1f | %11.1f | %9.0f | %s\n", r.robot.c_str(),
                r.function.c_str(), total.median, total.min, total.max, statsOf(r.samples, &Sample::get_ms).median,
                statsOf(r.samples, &Sample::fetch_ms).median, statsOf(r.samples, &Sample::bytes).median / 1024,
                verdict(r.target, total.median).c_str());
  }
  std::printf("\nGetFunction: t0 to the interpreter serving (median); fetch (log): the robot's own\n"
              "transfer + verify + install time (fleet_artifact_fetched \"seconds\", median).\n\n");
}

struct ChunkRow {
  std::string chunk;
  std::vector<Sample> samples;
};

void printChunkTable(const std::string& what, const std::vector<ChunkRow>& rows) {
  std::printf("chunk size, %s (ms, median of %zu rounds each):\n\n", what.c_str(), rows.at(0).samples.size());
  std::printf("| %-10s | %8s | %8s | %8s | %11s | %7s |\n", "chunk", "median", "min", "max", "fetch (log)", "chunks");
  std::printf("|%s|%s|%s|%s|%s|%s|\n", std::string(12, '-').c_str(), std::string(10, '-').c_str(),
              std::string(10, '-').c_str(), std::string(10, '-').c_str(), std::string(13, '-').c_str(),
              std::string(9, '-').c_str());
  for (const ChunkRow& r : rows) {
    const Stats total = statsOf(r.samples, &Sample::first_eval_ms);
    const double chunk_bytes = 1024.0 * std::atof(r.chunk.c_str());
    std::printf("| %-10s | %8.1f | %8.1f | %8.1f | %11.1f | %7.0f |\n", r.chunk.c_str(), total.median, total.min,
                total.max, statsOf(r.samples, &Sample::fetch_ms).median,
                std::ceil(statsOf(r.samples, &Sample::bytes).median / chunk_bytes));
  }
  std::printf("\n");
}

// Local-call parity: one Function evaluating in-process from a cache (no server).
struct ParityRow {
  std::string robot, function, fetched_target, native_target;
  double fetched_ns = 0, native_ns = 0, max_relative = 0;
};

// Builds `spec` for `robot` natively into `cache_dir` with `robodiff warmup` (workers here).
void buildNatively(const FleetRobot& robot, const fs::path& spec, const fs::path& cache_dir) {
  const fs::path cli = fs::path(ROBODIFFD_PATH).parent_path() / "robodiff";
  const std::string command = cli.string() + " warmup --cache " + cache_dir.string() + " --urdf " +
                              robot.urdf.string() + (robot.floating ? " --floating-base" : "") + " --spec " +
                              spec.string() + " > " + (cache_dir.string() + ".log") + " 2>&1";
  if (std::system(command.c_str()) != 0) {
    std::fprintf(stderr, "fleet_bench: the native build failed: %s\n%s\n", command.c_str(),
                 bench::readText(cache_dir.string() + ".log").c_str());
    std::exit(1);
  }
}

// ns per call of `calls` evaluations.
double nsPerCall(const client::Function& f, const std::vector<double>& in, std::vector<double>& out, int calls) {
  const Clock::time_point start = Clock::now();
  for (int i = 0; i < calls; ++i) check(f.evaluate(in, out), "local Evaluate");
  return std::chrono::duration<double, std::nano>(Clock::now() - start).count() / calls;
}

ParityRow parity(const FleetRobot& robot, const SpecFile& spec, const fs::path& fetched_cache,
                 const fs::path& native_cache) {
  const int nobody = 231;  // a DDS domain without a server: both clients load the library themselves
  client::Client fetched(bench::fleetClientOptions(nobody, client::Mode::Local, fetched_cache));
  client::Client native(bench::fleetClientOptions(nobody, client::Mode::Local, native_cache));
  const client::Function a = fetched.function(fetched.loadModelFile(robot.urdf, robot.floating), spec.function.spec);
  const client::Function b = native.function(native.loadModelFile(robot.urdf, robot.floating), spec.function.spec);
  if (a.mode() != client::Mode::Local || b.mode() != client::Mode::Local) {
    std::fprintf(stderr, "fleet_bench: parity needs both functions in local mode\n");
    std::exit(1);
  }
  const std::vector<double> in = inputsFor(a);
  std::vector<double> out_a(a.outputCount()), out_b(b.outputCount());
  ParityRow row{robot.name, spec.function.label, bench::cacheTarget(fetched_cache), bench::cacheTarget(native_cache)};
  check(a.evaluate(in, out_a), "local Evaluate"), check(b.evaluate(in, out_b), "local Evaluate");
  for (std::size_t i = 0; i < out_a.size(); ++i)
    if (out_a[i] != out_b[i])
      row.max_relative = std::max(row.max_relative, std::abs(out_a[i] - out_b[i]) /
                                                        std::max(std::abs(out_a[i]), std::abs(out_b[i])));
  constexpr int kBatches = 20, kCalls = 10000;
  nsPerCall(a, in, out_a, kCalls), nsPerCall(b, in, out_b, kCalls);  // warm: caches, this thread's buffers
  std::vector<double> ns_a, ns_b;
  for (int batch = 0; batch < kBatches; ++batch) {  // alternated, each first every other batch
    if (batch % 2 == 0) ns_a.push_back(nsPerCall(a, in, out_a, kCalls));
    ns_b.push_back(nsPerCall(b, in, out_b, kCalls));
    if (batch % 2 == 1) ns_a.push_back(nsPerCall(a, in, out_a, kCalls));
  }
  row.fetched_ns = statsOf(ns_a).median, row.native_ns = statsOf(ns_b).median;
  return row;
}

void printParityTable(const std::vector<ParityRow>& rows) {
  std::printf("local-mode call after the fetch vs a library built natively here (ns per call, median of 20\n"
              "alternated batches of 10,000 calls; target: fetched / native <= 1.05x):\n\n");
  std::printf("| %-9s | %-13s | %-22s | %12s | %12s | %7s | %14s |\n", "robot", "function", "fetched (target)",
              "fetched ns", "native ns", "ratio", "max rel. diff.");
  std::printf("|%s|%s|%s|%s|%s|%s|%s|\n", std::string(11, '-').c_str(), std::string(15, '-').c_str(),
              std::string(24, '-').c_str(), std::string(14, '-').c_str(), std::string(14, '-').c_str(),
              std::string(9, '-').c_str(), std::string(16, '-').c_str());
  for (const ParityRow& r : rows)
    std::printf("| %-9s | %-13s | %-22s | %12.1f | %12.1f | %6.3fx | %14.1e |\n", r.robot.c_str(),
                r.function.c_str(), r.fetched_target.c_str(), r.fetched_ns, r.native_ns, r.fetched_ns / r.native_ns,
                r.max_relative);
  if (!rows.empty()) std::printf("\nnative: %s\n", rows[0].native_target.c_str());
}

const FleetRobot& largestRobot(const std::vector<FleetRobot>& robots) {
  for (const char* name : {"talos", "humanoid"})
    for (const FleetRobot& r : robots)
      if (r.name == name) return r;
  return robots.back();
}

std::string cpuModel() {
  std::stringstream in(bench::readText("/proc/cpuinfo"));
  for (std::string line; std::getline(in, line);)
    if (line.rfind("model name", 0) == 0) return line.substr(line.find(':') + 2);
  return "unknown CPU";
}

}  // namespace

int main(int argc, char** argv) {
  const Args args = parseArgs(argc, argv);
  const std::vector<FleetRobot> robots = robotsOf(args);
  if (robots.empty()) return std::fprintf(stderr, "fleet_bench: no robot to run\n"), 1;
  const std::vector<SpecFile> functions = functionsOfTheRun();
  const fs::path dir = fs::temp_directory_path() / ("robodiff-fleet-bench-" + std::to_string(getpid()));
  const std::string uri = "file://" + (fs::path(ROBODIFF_SOURCE_DIR) / "deploy/cyclonedds-loopback.xml").string();
  setenv("CYCLONEDDS_URI", uri.c_str(), 1);
  const bench::BenchFleet fleet(dir, 150 + getpid() % 50);

  std::vector<FetchRow> fetch_rows;
  std::vector<ChunkRow> chunk_rows;
  std::vector<ParityRow> parity_rows;
  std::string sweep_what, robot_target;
  {
    const std::unique_ptr<bench::Daemon> build = fleet.buildHost("512KiB");  // robots' asks are capped by it
    warmBuildHost(fleet, robots, functions);
    robot_target = bench::cacheTarget(fleet.robotCache("warm"));
    for (const FleetRobot& r : robots)
      for (const SpecFile& f : functions) fetch_rows.push_back({r.name, f.function.label, targetOf(r, f.function.label), {}});
    for (int round = 0; round < args.rounds; ++round) {
      std::fprintf(stderr, "fetch round %d of %d\n", round + 1, args.rounds);
      for (std::size_t r = 0; r < robots.size(); ++r)
        for (std::size_t f = 0; f < functions.size(); ++f)
          fetch_rows[r * functions.size() + f].samples.push_back(fetchOnce(fleet, robots[r], functions[f].function, "256KiB"));
    }
    if (!args.quick) {  // the largest library: Talos's ABA Jacobian, else the humanoid's
      const FleetRobot& big = largestRobot(robots);
      sweep_what = big.name + " " + functions[1].function.label;
      for (const char* chunk : {"64KiB", "256KiB", "512KiB"}) {
        std::fprintf(stderr, "chunk sweep: %s\n", chunk);
        chunk_rows.push_back({chunk, {}});
        for (int round = 0; round < std::min(args.rounds, 5); ++round)
          chunk_rows.back().samples.push_back(fetchOnce(fleet, big, functions[1].function, chunk));
      }
    }
    for (const FleetRobot& r : robots)  // a robot cache holding that one fetched library
      if (r.name == "panda" || r.name == "arm7") fetchOnce(fleet, r, functions[0].function, "256KiB", "parity-" + r.name);
  }
  for (const FleetRobot& r : robots) {
    if (r.name != "panda" && r.name != "arm7") continue;
    std::fprintf(stderr, "parity: %s, a native build, then the calls\n", r.name.c_str());
    const fs::path native = dir / ("native-" + r.name);
    buildNatively(r, functions[0].path, native);
    parity_rows.push_back(parity(r, functions[0], fleet.robotCache("parity-" + r.name), native));
  }

  std::time_t now = std::time(nullptr);
  char date[32];
  std::strftime(date, sizeof date, "%Y-%m-%d", std::localtime(&now));
  std::printf("fleet_bench %s, %s, %u cores; robots run %s; one build host, DDS loopback domain %d\n\n", date,
              cpuModel().c_str(), std::thread::hardware_concurrency(), robot_target.c_str(), fleet.domain());
  printFetchTable(fetch_rows, args.rounds);
  if (!chunk_rows.empty()) printChunkTable(sweep_what, chunk_rows);
  printParityTable(parity_rows);
  fs::remove_all(dir);
  return 0;
}
