// Service benchmarks (issue 5), one run, one table: robodiffd started here (real process,
// its own cache, RouDi: the running one or embedded), then
//   - round trip of Evaluate (RNEA Jacobian wrt [q, v, a]) over iceoryx and over DDS
//     (loopback configuration), against calling the compiled library in this process;
//   - EvaluateBatch of 1,000 knots over both, against the library's batched entry point
//     in this process (one thread);
//   - 1, 4 and 8 concurrent clients (threads, one connection each) over both.
// Uses ../shared's Panda when there, else the project's arm7. Run by hand:
//   build/bin/service_bench [--robot URDF] [--calls N] [--knots K]
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "bench_daemon.hpp"
#include "bench_function.hpp"
#include "robodiff/cache/cache.hpp"
#include "robodiff/client/dds_connection.hpp"
#include "robodiff/client/shm_connection.hpp"
#include "robodiff/codegen/loaded_library.hpp"

namespace fs = std::filesystem;
using namespace robodiff;
using Clock = std::chrono::steady_clock;
using bench::check;

namespace {

struct Percentiles {
  double p50 = 0, p99 = 0, max = 0;  // microseconds
};

Percentiles percentiles(std::vector<double> us) {
  if (us.empty()) return {};
  std::sort(us.begin(), us.end());
  auto at = [&](double q) { return us[std::min(us.size() - 1, static_cast<std::size_t>(q * (us.size() - 1) + 0.5))]; };
  return {at(0.5), at(0.99), us.back()};
}

double microsSince(Clock::time_point t) { return std::chrono::duration<double, std::micro>(Clock::now() - t).count(); }

struct Row {
  std::string what;
  Percentiles t;
  std::string note;
};

void printRows(const std::vector<Row>& rows) {
  std::printf("| %-52s | %9s | %9s | %9s | %s\n", "measurement", "p50 us", "p99 us", "max us", "note");
  std::printf("|%s|%s|%s|%s|---\n", std::string(54, '-').c_str(), std::string(11, '-').c_str(),
              std::string(11, '-').c_str(), std::string(11, '-').c_str());
  for (const Row& r : rows)
    std::printf("| %-52s | %9.2f | %9.2f | %9.2f | %s\n", r.what.c_str(), r.t.p50, r.t.p99, r.t.max, r.note.c_str());
}

std::string ratio(double a, double b) {
  char s[64];
  std::snprintf(s, sizeof s, "%.2fx", a / b);
  return s;
}

struct Args {
  fs::path robot = fs::path(ROBODIFF_SHARED_DIR) / "robots" / "panda_arm_fixed_fingers.urdf";
  std::string label = "Panda";
  int calls = 20000, knots = 1000;
};

Args parseArgs(int argc, char** argv) {
  Args a;
  if (!fs::exists(a.robot)) {
    a.robot = fs::path(ROBODIFF_SOURCE_DIR) / "examples/robots/arm7.urdf";
    a.label = "arm7 (no ../shared)";
  }
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string flag = argv[i];
    if (flag == "--robot") a.robot = argv[i + 1], a.label = fs::path(argv[i + 1]).stem().string();
    else if (flag == "--calls") a.calls = std::atoi(argv[i + 1]);
    else if (flag == "--knots") a.knots = std::atoi(argv[i + 1]);
  }
  return a;
}

// One run against a robodiffd started on its own cache and DDS domain: the compiled
// function, called in this process and over both transports.
class ServiceBench {
 public:
  ServiceBench(const Args& args, const fs::path& dir, int domain)
      : args_(args),
        dir_(dir),
        daemon_(ROBODIFFD_PATH, dir / "cache", domain, dir / "robodiffd.log"),
        shm_(client::connectShm(shm_options_)) {
    dds_options_.domain_id = static_cast<std::uint32_t>(domain);
    dds_ = client::connectDds(dds_options_);
    function_ = bench::compiledFunction(*shm_, args.robot,
                                        fs::path(ROBODIFF_SOURCE_DIR) / "examples/specs/rnea_jacobian.json");
    in_n_ = rpc::inputCount(function_), out_n_ = rpc::outputCount(function_);
    in_.resize(in_n_ * args.knots), out_.resize(out_n_ * args.knots);
    for (std::size_t i = 0; i < in_.size(); ++i) in_[i] = 0.1 * std::sin(0.37 * i);
    openLibraryInProcess();
  }

  void run() {
    std::printf("robot %s: RNEA Jacobian, %zu inputs, %zu outputs per knot; %d calls per row\n\n",
                args_.label.c_str(), in_n_, out_n_, args_.calls);
    timeInProcess();
    timeRoundTrips();
    timeBatches();
    for (const char* transport : {"iceoryx", "dds"})
      for (int clients : {1, 4, 8}) timeConcurrent(transport, clients);
  }
  const std::vector<Row>& rows() const { return rows_; }

 private:
  // The same library the service serves, from its cache.
  void openLibraryInProcess() {
    cache::Cache cache = cache::Cache::open(dir_ / "cache");
    const std::vector<cache::Entry> entries = cache.list();
    std::optional<cache::Artifact> artifact = cache.find(entries.at(0).key);
    library_ = std::make_unique<codegen::LoadedLibrary>(codegen::LoadedLibrary::open(artifact->library()));
    direct_ = std::make_unique<codegen::CompiledFunction>(library_->function(library_->functionNames().at(0)));
  }

  // Per block, a pointer into the concatenated buffers (`knots` knots per block).
  void blocks(std::vector<const double*>& in, std::vector<double*>& out, std::size_t knots) {
    std::size_t offset = 0;
    for (const rpc::InputBlock& b : function_.inputs) in.push_back(in_.data() + offset * knots), offset += b.size;
    offset = 0;
    for (const rpc::OutputBlock& b : function_.outputs) out.push_back(out_.data() + offset * knots), offset += b.nnz;
  }

  void timeInProcess() {
    std::vector<const double*> in;
    std::vector<double*> out;
    blocks(in, out, 1);
    std::vector<double> work(direct_->workSize());
    std::vector<double> us;
    for (int i = 0; i < args_.calls; ++i) {
      const auto t = Clock::now();
      direct_->evaluate(in.data(), out.data(), work.data());
      us.push_back(microsSince(t));
    }
    rows_.push_back({"in-process call of the compiled library", percentiles(us), "reference"});
  }

  std::vector<double> roundTrips(client::Connection& c, int n) {
    std::vector<double> lat;
    std::vector<double> o(out_n_);
    for (int i = 0; i < n; ++i) {
      const auto t = Clock::now();
      check(c.evaluate(function_.function_id, {in_.data(), in_n_}, o), "Evaluate");
      lat.push_back(microsSince(t));
    }
    return lat;
  }

  void timeRoundTrips() {
    // Warm up well: right after the compile the host is still settling (the worker
    // exits, caches are cold); the first 10k calls measured ~30% slower.
    roundTrips(*shm_, 10000);
    rows_.push_back({"Evaluate over iceoryx, 1 client", percentiles(roundTrips(*shm_, args_.calls)),
                     "target p50 < 10, p99 < 50"});
    roundTrips(*dds_, 1000);
    rows_.push_back({"Evaluate over DDS (loopback), 1 client", percentiles(roundTrips(*dds_, args_.calls / 4)),
                     "target p50 < 100"});
  }

  // The batched entry point in this process (one thread), then EvaluateBatch over each transport.
  void timeBatches() {
    const int knots = args_.knots, repeats = 30;
    auto batchIn = [&](auto&& run) {
      std::vector<double> lat;
      run();
      for (int r = 0; r < repeats; ++r) {
        const auto t = Clock::now();
        run();
        lat.push_back(microsSince(t));
      }
      return percentiles(lat);
    };
    std::vector<const double*> bin;
    std::vector<double*> bout;
    blocks(bin, bout, knots);
    std::vector<double> bwork(direct_->batchWorkSize());
    const std::string what = "EvaluateBatch " + std::to_string(knots) + " knots";
    const Percentiles local = batchIn([&] { direct_->evaluateBatch(knots, bin.data(), bout.data(), bwork.data()); });
    rows_.push_back({what + ", in process (1 thread)", local, "reference"});
    const Percentiles shm =
        batchIn([&] { check(shm_->evaluateBatch(function_.function_id, knots, in_, out_), "EvaluateBatch"); });
    rows_.push_back({what + " over iceoryx", shm, ratio(shm.p50, local.p50) + " of in-process (target <= 1.5x)"});
    const Percentiles dds =
        batchIn([&] { check(dds_->evaluateBatch(function_.function_id, knots, in_, out_), "EvaluateBatch"); });
    rows_.push_back({what + " over DDS", dds, ratio(dds.p50, local.p50) + " of in-process"});
  }

  // Concurrent clients, each its own connection and thread.
  void timeConcurrent(const std::string& transport, int clients) {
    const int per_client = (transport == "dds" ? args_.calls / 8 : args_.calls / 2) / clients;
    std::vector<std::vector<double>> lat(clients);
    std::vector<std::thread> threads;
    const auto start = Clock::now();
    for (int k = 0; k < clients; ++k)
      threads.emplace_back([&, k] {
        std::unique_ptr<client::Connection> c =
            transport == "dds" ? client::connectDds(dds_options_) : client::connectShm(shm_options_);
        roundTrips(*c, 200);
        lat[k] = roundTrips(*c, per_client);
      });
    for (std::thread& t : threads) t.join();
    const double seconds = std::chrono::duration<double>(Clock::now() - start).count();
    std::vector<double> all;
    for (auto& l : lat) all.insert(all.end(), l.begin(), l.end());
    char note[96];
    std::snprintf(note, sizeof note, "%.0f calls/s in all (incl. connecting)", all.size() / seconds);
    rows_.push_back(
        {"Evaluate over " + transport + ", " + std::to_string(clients) + " concurrent clients", percentiles(all), note});
  }

  const Args& args_;
  const fs::path dir_;
  bench::Daemon daemon_;
  client::ShmConnectionOptions shm_options_;
  client::DdsConnectionOptions dds_options_;
  std::unique_ptr<client::Connection> shm_, dds_;
  rpc::GetFunctionReply function_;
  std::size_t in_n_ = 0, out_n_ = 0;
  std::vector<double> in_, out_;
  std::unique_ptr<codegen::LoadedLibrary> library_;
  std::unique_ptr<codegen::CompiledFunction> direct_;
  std::vector<Row> rows_;
};

}  // namespace

int main(int argc, char** argv) {
  const Args args = parseArgs(argc, argv);
  const fs::path dir = fs::temp_directory_path() / ("robodiff-service-bench-" + std::to_string(getpid()));
  fs::create_directories(dir);
  const std::string uri = "file://" + (fs::path(ROBODIFF_SOURCE_DIR) / "deploy/cyclonedds-loopback.xml").string();
  setenv("CYCLONEDDS_URI", uri.c_str(), 1);
  std::vector<Row> rows;
  {
    ServiceBench bench(args, dir, 1 + getpid() % 200);
    bench.run();
    rows = bench.rows();
  }
  printRows(rows);
  fs::remove_all(dir);
  return 0;
}
