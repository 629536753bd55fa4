// Client benchmarks (issue 6), one run, one table: robodiffd started here on its own
// cache; the Panda RNEA Jacobian (arm7 without ../shared) evaluated
//   - by calling the compiled library directly (the bare function),
//   - through Client in local mode (the same library, loaded from the cache),
//   - through Client over iceoryx (shm) and over DDS,
// reporting each mode's cost per call and its overhead over the bare call; local
// evaluateBatch per knot against as many single calls (1, 20 and 1000 knots: the
// library's batched entry point, SIMD lanes); then the jitter of
// examples/controller/controller_loop at 1 kHz (10 s, local and shm).
//   build/bin/client_bench [--robot URDF] [--calls N] [--loop-seconds S]
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <thread>
#include <vector>

#include "bench_daemon.hpp"
#include "robodiff/cache/cache.hpp"
#include "robodiff/client/client.hpp"
#include "robodiff/codegen/loaded_library.hpp"

namespace fs = std::filesystem;
using namespace robodiff;
using Clock = std::chrono::steady_clock;

namespace {

struct Timing {
  double mean_ns = 0, p50_ns = 0, p99_ns = 0;
};

// Mean over one long loop (no clock read per call: it would cost as much as the local
// call), and percentiles over individually timed calls.
template <class Call>
Timing timeCalls(Call&& call, int calls) {
  for (int i = 0; i < calls / 10; ++i) call();
  const auto start = Clock::now();
  for (int i = 0; i < calls; ++i) call();
  Timing t;
  t.mean_ns = std::chrono::duration<double, std::nano>(Clock::now() - start).count() / calls;
  std::vector<double> ns;
  const int sampled = std::min(calls, 20000);
  ns.reserve(sampled);
  for (int i = 0; i < sampled; ++i) {
    const auto s = Clock::now();
    call();
    ns.push_back(std::chrono::duration<double, std::nano>(Clock::now() - s).count());
  }
  std::sort(ns.begin(), ns.end());
  t.p50_ns = ns[ns.size() / 2];
  t.p99_ns = ns[ns.size() * 99 / 100];
  return t;
}

void check(const Status& s) {
  if (!s.ok()) {
    std::fprintf(stderr, "client_bench: %s: %s\n", toString(s.code).c_str(), s.message.c_str());
    std::exit(1);
  }
}

// Per knot: `knots` single evaluate() calls, and one evaluateBatch of those knots.
struct BatchRow {
  std::size_t knots = 0;
  double single_ns = 0, batch_ns = 0;
  double max_relative = 0;  // the largest relative difference between the two's values
};

// The two paths' values over the same knots: the largest relative difference.
double maxRelativeDifference(const client::Function& f, std::size_t knots, const std::vector<double>& in) {
  const std::size_t in_n = f.inputCount(), out_n = f.outputCount();
  std::vector<double> single(knots * out_n), batch(knots * out_n);
  for (std::size_t k = 0; k < knots; ++k)
    check(f.evaluate({in.data() + k * in_n, in_n}, {single.data() + k * out_n, out_n}));
  check(f.evaluateBatch(knots, in, batch));
  double worst = 0;
  for (std::size_t i = 0; i < batch.size(); ++i)
    if (batch[i] != single[i])
      worst = std::max(worst, std::abs(batch[i] - single[i]) / std::max(std::abs(batch[i]), std::abs(single[i])));
  return worst;
}

// About `total_knots` knots per measurement; rounds interleaved, the best of each (the
// least disturbed by the machine's other work).
BatchRow timeBatch(const client::Function& f, std::size_t knots, int total_knots) {
  const std::size_t in_n = f.inputCount(), out_n = f.outputCount();
  std::vector<double> in(knots * in_n), out(knots * out_n);
  for (std::size_t i = 0; i < in.size(); ++i) in[i] = 0.2 * std::sin(1.0 + 0.37 * i);
  auto singles = [&] {
    for (std::size_t k = 0; k < knots; ++k)
      check(f.evaluate({in.data() + k * in_n, in_n}, {out.data() + k * out_n, out_n}));
  };
  auto batch = [&] { check(f.evaluateBatch(knots, in, out)); };
  const int reps = std::max<int>(1, total_knots / static_cast<int>(knots));
  auto perKnot = [&](auto&& call) {
    const auto start = Clock::now();
    for (int r = 0; r < reps; ++r) call();
    return std::chrono::duration<double, std::nano>(Clock::now() - start).count() / (reps * double(knots));
  };
  singles(), batch();  // warm-up: this thread's buffers
  BatchRow row{knots, 1e30, 1e30, maxRelativeDifference(f, knots, in)};
  for (int round = 0; round < 5; ++round) {
    row.single_ns = std::min(row.single_ns, perKnot(singles));
    row.batch_ns = std::min(row.batch_ns, perKnot(batch));
  }
  return row;
}

}  // namespace

int main(int argc, char** argv) {
  fs::path robot = fs::path(ROBODIFF_SHARED_DIR) / "robots" / "panda_arm_fixed_fingers.urdf";
  if (!fs::exists(robot)) robot = fs::path(ROBODIFF_SOURCE_DIR) / "examples/robots/arm7.urdf";
  int calls = 200000;
  double loop_seconds = 10;
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string a = argv[i];
    if (a == "--robot") robot = argv[i + 1];
    else if (a == "--calls") calls = std::atoi(argv[i + 1]);
    else if (a == "--loop-seconds") loop_seconds = std::atof(argv[i + 1]);
  }
  const fs::path dir = fs::temp_directory_path() / ("robodiff-client-bench-" + std::to_string(getpid()));
  fs::create_directories(dir);
  const std::string uri = "file://" + (fs::path(ROBODIFF_SOURCE_DIR) / "deploy/cyclonedds-loopback.xml").string();
  setenv("CYCLONEDDS_URI", uri.c_str(), 1);
  const int domain = 1 + getpid() % 200;
  const fs::path cache_dir = dir / "cache";
  const std::string spec = bench::readText(fs::path(ROBODIFF_SOURCE_DIR) / "examples/specs/rnea_jacobian.json");

  struct Row {
    std::string mode;
    Timing t;
  };
  std::vector<Row> rows;
  std::vector<BatchRow> batch_rows;
  std::uint32_t batch_width = 0;
  std::string loop_report;
  {
    bench::Daemon daemon(ROBODIFFD_PATH, cache_dir, domain, dir / "robodiffd.log");
    auto make = [&](const std::string& address) {
      client::ClientOptions options;
      options.server = client::parseServerAddress(address);
      options.cache_dir = cache_dir;
      return client::Client(options);
    };
    client::Client shm = make("shm");
    const client::ModelInfo model = shm.loadModelFile(robot);
    const client::Function f_shm = shm.function(model, spec);
    for (int i = 0;; ++i) {  // until the server has compiled it into the cache
      bool compiled = false;
      for (const rpc::FunctionSummary& s : shm.functions()) compiled = compiled || s.compiled;
      if (compiled) break;
      if (i > 1200) {
        std::fprintf(stderr, "client_bench: not compiled within 120 s\n");
        return 1;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(100));
    }
    client::Client local = make("local");
    const client::Function f_local = local.function(local.loadModelFile(robot), spec);
    client::Client dds = make("dds:" + std::to_string(domain));
    const client::Function f_dds = dds.function(dds.loadModelFile(robot), spec);

    // The bare function: the same library, called directly.
    cache::Cache cache = cache::Cache::open(cache_dir);
    std::optional<cache::Artifact> artifact = cache.find(cache.list().at(0).key);
    const codegen::LoadedLibrary library = codegen::LoadedLibrary::open(artifact->library());
    const codegen::CompiledFunction bare = library.function(library.functionNames().at(0));

    const rpc::GetFunctionReply& layout = f_local.layout();
    std::vector<double> in(f_local.inputCount()), out(f_local.outputCount());
    for (std::size_t i = 0; i < in.size(); ++i) in[i] = 0.2 * std::sin(1.0 + i);
    std::vector<const double*> in_blocks;
    std::vector<double*> out_blocks;
    std::size_t offset = 0;
    for (const rpc::InputBlock& b : layout.inputs) in_blocks.push_back(in.data() + offset), offset += b.size;
    offset = 0;
    for (const rpc::OutputBlock& b : layout.outputs) out_blocks.push_back(out.data() + offset), offset += b.nnz;
    std::vector<double> work(bare.workSize());

    rows.push_back({"bare compiled function", timeCalls([&] { bare.evaluate(in_blocks.data(), out_blocks.data(), work.data()); }, calls)});
    rows.push_back({std::string("Client, ") + client::toString(f_local.mode()) + " mode",
                    timeCalls([&] { check(f_local.evaluate(in, out)); }, calls)});
    rows.push_back({std::string("Client, ") + client::toString(f_shm.mode()) + " mode",
                    timeCalls([&] { check(f_shm.evaluate(in, out)); }, calls / 20)});
    rows.push_back({std::string("Client, ") + client::toString(f_dds.mode()) + " mode",
                    timeCalls([&] { check(f_dds.evaluate(in, out)); }, calls / 200)});

    batch_width = bare.batchWidth();
    for (const std::size_t knots : {1, 20, 1000}) batch_rows.push_back(timeBatch(f_local, knots, calls));

    // The 1 kHz controller loop, as a process of its own, in local and shm modes.
    for (const char* address : {"local --realtime", "local", "shm"}) {
      const std::string command = (fs::path(ROBODIFFD_PATH).parent_path() / "controller_loop").string() +
                                  " --urdf " + robot.string() + " --seconds " + std::to_string(loop_seconds) +
                                  " --server " + address + " --cache " + cache_dir.string() + " 2>&1";
      loop_report += "$ controller_loop --server " + std::string(address) + "\n";
      if (FILE* p = popen(command.c_str(), "r")) {
        char line[512];
        while (fgets(line, sizeof line, p) != nullptr) loop_report += line;
        pclose(p);
      }
    }
  }
  const double bare_ns = rows[0].t.mean_ns;
  std::printf("robot %s: RNEA Jacobian wrt [q, v, a]\n\n", robot.filename().c_str());
  std::printf("| %-28s | %12s | %12s | %12s | %18s |\n", "path", "mean ns", "p50 ns", "p99 ns", "overhead (mean)");
  std::printf("|%s|%s|%s|%s|%s|\n", std::string(30, '-').c_str(), std::string(14, '-').c_str(),
              std::string(14, '-').c_str(), std::string(14, '-').c_str(), std::string(20, '-').c_str());
  for (const Row& r : rows)
    std::printf("| %-28s | %12.1f | %12.1f | %12.1f | %15.1f ns |\n", r.mode.c_str(), r.t.mean_ns, r.t.p50_ns,
                r.t.p99_ns, r.t.mean_ns - bare_ns);
  std::printf("\ntargets: local overhead < 50 ns per call; shm p50 < 10 us, p99 < 50 us\n\n");
  std::printf("local evaluateBatch (batch width %u) against as many single calls, ns per knot:\n\n", batch_width);
  std::printf("| %5s | %18s | %18s | %24s | %18s |\n", "knots", "single calls", "evaluateBatch",
              "ratio (single / batch)", "max rel. diff.");
  std::printf("|%s|%s|%s|%s|%s|\n", std::string(7, '-').c_str(), std::string(20, '-').c_str(),
              std::string(20, '-').c_str(), std::string(26, '-').c_str(), std::string(20, '-').c_str());
  for (const BatchRow& r : batch_rows)
    std::printf("| %5zu | %18.1f | %18.1f | %23.2fx | %18.1e |\n", r.knots, r.single_ns, r.batch_ns,
                r.single_ns / r.batch_ns, r.max_relative);
  std::printf("\n%s", loop_report.c_str());
  fs::remove_all(dir);
  return 0;
}
