// Service benchmarks (issue 5), one run, one table: robodiffd started here (real process,
// its own cache, RouDi: the running one or embedded), then
//   - round trip of Evaluate (RNEA Jacobian wrt [q, v, a]) over iceoryx and over DDS
//     (loopback configuration), against calling the compiled library in this process;
//   - EvaluateBatch of 1,000 knots over both, against the library's batched entry point
//     in this process (one thread);
//   - 1, 4 and 8 concurrent clients (threads, one connection each) over both.
// Uses ../shared's Panda when there, else the project's arm7. Run by hand:
//   build/bin/service_bench [--robot URDF] [--calls N] [--knots K]
#include <fcntl.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <optional>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "bench_daemon.hpp"
#include "robodiff/cache/cache.hpp"
#include "robodiff/client/dds_connection.hpp"
#include "robodiff/client/shm_connection.hpp"
#include "robodiff/codegen/loaded_library.hpp"

namespace fs = std::filesystem;
using namespace robodiff;
using Clock = std::chrono::steady_clock;

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

void check(const Status& s, const char* what) {
  if (!s.ok()) {
    std::fprintf(stderr, "service_bench: %s failed: %s: %s\n", what, toString(s.code).c_str(), s.message.c_str());
    std::exit(1);
  }
}

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

}  // namespace

int main(int argc, char** argv) {
  fs::path robot = fs::path(ROBODIFF_SHARED_DIR) / "robots" / "panda_arm_fixed_fingers.urdf";
  std::string label = "Panda";
  if (!fs::exists(robot)) {
    robot = fs::path(ROBODIFF_SOURCE_DIR) / "examples/robots/arm7.urdf";
    label = "arm7 (no ../shared)";
  }
  int calls = 20000, knots = 1000;
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string a = argv[i];
    if (a == "--robot") robot = argv[i + 1], label = fs::path(argv[i + 1]).stem().string();
    else if (a == "--calls") calls = std::atoi(argv[i + 1]);
    else if (a == "--knots") knots = std::atoi(argv[i + 1]);
  }

  const fs::path dir = fs::temp_directory_path() / ("robodiff-service-bench-" + std::to_string(getpid()));
  fs::create_directories(dir);
  const std::string uri = "file://" + (fs::path(ROBODIFF_SOURCE_DIR) / "deploy/cyclonedds-loopback.xml").string();
  setenv("CYCLONEDDS_URI", uri.c_str(), 1);
  const int domain = 1 + getpid() % 200;

  std::vector<Row> rows;
  {
    bench::Daemon daemon(ROBODIFFD_PATH, dir / "cache", domain, dir / "robodiffd.log");
    client::ShmConnectionOptions shm_options;
    auto shm = client::connectShm(shm_options);
    client::DdsConnectionOptions dds_options;
    dds_options.domain_id = static_cast<std::uint32_t>(domain);
    auto dds = client::connectDds(dds_options);

    rpc::LoadModelRequest load;
    load.urdf = bench::readText(robot);
    rpc::LoadModelReply model;
    check(shm->loadModel(load, model), "LoadModel");
    rpc::GetFunctionRequest get;
    get.model_id = model.model_id;
    get.spec_json = bench::readText(fs::path(ROBODIFF_SOURCE_DIR) / "examples/specs/rnea_jacobian.json");
    get.wait = true;
    rpc::GetFunctionReply function;
    check(shm->getFunction(get, function), "GetFunction");
    // Wait for the compiled library to replace the interpreter.
    for (int i = 0;; ++i) {
      rpc::ListFunctionsReply list;
      check(shm->listFunctions({}, list), "ListFunctions");
      if (!list.functions.empty() && list.functions[0].compiled) break;
      if (i > 1200) {
        std::fprintf(stderr, "service_bench: the library was not compiled within 120 s\n");
        return 1;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(100));
    }
    const std::size_t in_n = rpc::inputCount(function), out_n = rpc::outputCount(function);
    std::printf("robot %s: RNEA Jacobian, %zu inputs, %zu outputs per knot; %d calls per row\n\n", label.c_str(), in_n,
                out_n, calls);

    // The same library, called in this process.
    cache::Cache cache = cache::Cache::open(dir / "cache");
    const std::vector<cache::Entry> entries = cache.list();
    std::optional<cache::Artifact> artifact = cache.find(entries.at(0).key);
    const codegen::LoadedLibrary library = codegen::LoadedLibrary::open(artifact->library());
    const codegen::CompiledFunction direct = library.function(library.functionNames().at(0));

    std::vector<double> in(in_n * knots), out(out_n * knots);
    for (std::size_t i = 0; i < in.size(); ++i) in[i] = 0.1 * std::sin(0.37 * i);
    std::vector<double> work(std::max(direct.workSize(), direct.batchWorkSize()) * 2);
    std::vector<const double*> in_blocks;
    std::vector<double*> out_blocks;

    // Bare call: blocks point into the concatenated buffers.
    auto blocks = [&](double* in_base, double* out_base) {
      in_blocks.clear();
      out_blocks.clear();
      std::size_t offset = 0;
      for (const rpc::InputBlock& b : function.inputs) in_blocks.push_back(in_base + offset), offset += b.size;
      offset = 0;
      for (const rpc::OutputBlock& b : function.outputs) out_blocks.push_back(out_base + offset), offset += b.nnz;
    };
    blocks(in.data(), out.data());
    std::vector<double> us;
    for (int i = 0; i < calls; ++i) {
      const auto t = Clock::now();
      direct.evaluate(in_blocks.data(), out_blocks.data(), work.data());
      us.push_back(microsSince(t));
    }
    const Percentiles bare = percentiles(us);
    rows.push_back({"in-process call of the compiled library", bare, "reference"});

    auto roundTrips = [&](client::Connection& c, int n) {
      std::vector<double> lat;
      std::vector<double> o(out_n);
      for (int i = 0; i < n; ++i) {
        const auto t = Clock::now();
        check(c.evaluate(function.function_id, {in.data(), in_n}, o), "Evaluate");
        lat.push_back(microsSince(t));
      }
      return lat;
    };
    // Warm up well: right after the compile the host is still settling (the worker
    // exits, caches are cold); the first 10k calls measured ~30% slower.
    roundTrips(*shm, 10000);
    const Percentiles shm_rt = percentiles(roundTrips(*shm, calls));
    rows.push_back({"Evaluate over iceoryx, 1 client", shm_rt, "target p50 < 10, p99 < 50"});
    roundTrips(*dds, 1000);
    const Percentiles dds_rt = percentiles(roundTrips(*dds, calls / 4));
    rows.push_back({"Evaluate over DDS (loopback), 1 client", dds_rt, "target p50 < 100"});

    // Batches: in-process batched entry point (one thread), then over each transport.
    const int repeats = 30;
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
    {
      std::size_t offset = 0;
      for (const rpc::InputBlock& b : function.inputs) bin.push_back(in.data() + offset * knots), offset += b.size;
      offset = 0;
      for (const rpc::OutputBlock& b : function.outputs) bout.push_back(out.data() + offset * knots), offset += b.nnz;
    }
    std::vector<double> bwork(direct.batchWorkSize());
    const Percentiles local_batch =
        batchIn([&] { direct.evaluateBatch(knots, bin.data(), bout.data(), bwork.data()); });
    rows.push_back({"EvaluateBatch " + std::to_string(knots) + " knots, in process (1 thread)", local_batch, "reference"});
    const Percentiles shm_batch =
        batchIn([&] { check(shm->evaluateBatch(function.function_id, knots, in, out), "EvaluateBatch"); });
    rows.push_back({"EvaluateBatch " + std::to_string(knots) + " knots over iceoryx", shm_batch,
                    ratio(shm_batch.p50, local_batch.p50) + " of in-process (target <= 1.5x)"});
    const Percentiles dds_batch =
        batchIn([&] { check(dds->evaluateBatch(function.function_id, knots, in, out), "EvaluateBatch"); });
    rows.push_back({"EvaluateBatch " + std::to_string(knots) + " knots over DDS", dds_batch,
                    ratio(dds_batch.p50, local_batch.p50) + " of in-process"});

    // Concurrent clients, each its own connection and thread.
    for (const char* transport : {"iceoryx", "dds"}) {
      for (int clients : {1, 4, 8}) {
        const int per_client = (std::string(transport) == "dds" ? calls / 8 : calls / 2) / clients;
        std::vector<std::vector<double>> lat(clients);
        std::vector<std::thread> threads;
        const auto start = Clock::now();
        for (int k = 0; k < clients; ++k)
          threads.emplace_back([&, k] {
            std::unique_ptr<client::Connection> c;
            if (std::string(transport) == "dds") c = client::connectDds(dds_options);
            else c = client::connectShm(shm_options);
            roundTrips(*c, 200);
            lat[k] = roundTrips(*c, per_client);
          });
        for (std::thread& t : threads) t.join();
        const double seconds = std::chrono::duration<double>(Clock::now() - start).count();
        std::vector<double> all;
        for (auto& l : lat) all.insert(all.end(), l.begin(), l.end());
        char note[96];
        std::snprintf(note, sizeof note, "%.0f calls/s in all (incl. connecting)", all.size() / seconds);
        rows.push_back({std::string("Evaluate over ") + transport + ", " + std::to_string(clients) + " concurrent clients",
                        percentiles(all), note});
      }
    }
  }
  printRows(rows);
  fs::remove_all(dir);
  return 0;
}
