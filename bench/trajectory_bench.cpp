// Trajectory evaluation throughput (issue 7), one run, one table: RNEA with its Jacobian
// w.r.t. q, v, a (examples/specs/rnea_jacobian.json, compiled -O2 -march=native) over N
// knots of random states, in knots per second:
//   (a) BatchFunction::evaluateMany on all cores (batched entry point),
//   (b) evaluateMany on 1 thread (batched entry point, no threads),
//   (c) one evaluate() call per knot in a loop (what a caller without batches does),
//   (d) the whole job through files: CSV in, evaluateMany, binary out (.rdb),
//   (e) the same with CSV out,
// each the best of 3 runs, with (a)/(c) and (b)/(c), and the largest difference between
// (a), (b) and (c)'s outputs (they must agree). arm7, and the Panda when ../shared has it.
// Run by hand:
//   build/bin/trajectory_bench [--knots N] [--cache DIR] [--urdf FILE ...]
#include <algorithm>
#include <charconv>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iostream>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include <unistd.h>

#include "output/human_units.hpp"
#include "robodiff/batch/batch_function.hpp"
#include "robodiff/batch/trajectory_evaluation.hpp"
#include "robodiff/batch/trajectory_table.hpp"
#include "robodiff/functions/reference.hpp"
#include "robodiff/model/urdf_loader.hpp"

namespace fs = std::filesystem;
using namespace robodiff;
using Clock = std::chrono::steady_clock;

namespace {

constexpr int kRuns = 3;
constexpr std::uint64_t kDistinctStates = 4096;  // random states, repeated to fill the knots

struct Row {
  std::string robot;
  int nv = 0;
  std::size_t outputs = 0;
  double all = 0, one_thread = 0, loop = 0, job_binary = 0, job_csv = 0;
  double worst_difference = 0;
};

std::string readText(const fs::path& p) {
  std::ifstream in(p);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

// The best knots/s of kRuns runs of `run`.
double bestRate(std::uint64_t knots, const std::function<void()>& run) {
  double best = 0;
  for (int r = 0; r < kRuns; ++r) {
    const Clock::time_point start = Clock::now();
    run();
    const double seconds = std::chrono::duration<double>(Clock::now() - start).count();
    best = std::max(best, static_cast<double>(knots) / seconds);
  }
  return best;
}

double worstDifference(const std::vector<double>& a, const std::vector<double>& b) {
  double worst = 0;
  for (std::size_t i = 0; i < a.size(); ++i) worst = std::max(worst, std::abs(a[i] - b[i]) / (1 + std::abs(b[i])));
  return worst;
}

Row benchRobot(const fs::path& urdf_path, const std::string& label, std::uint64_t knots, const fs::path& cache,
               const fs::path& scratch) {
  const std::string urdf = readText(urdf_path);
  const Model model = loadUrdfString(urdf, RootJoint::Fixed, urdf_path.string());
  const FunctionSpec spec = loadFunctionSpec((fs::path(ROBODIFF_SOURCE_DIR) / "examples/specs/rnea_jacobian.json").string());
  batch::BatchFunctionOptions options;
  options.cache_dir = cache;
  options.worker_executable = ROBODIFF_WORKER_PATH;
  options.on_progress = [&](const std::string& what) {
    if (what == "building") std::cerr << "building rnea + Jacobian for " << label << " ..." << std::endl;
  };
  const batch::BatchFunction all = batch::BatchFunction::open(model, urdf, false, spec, options);
  options.threads = 1;
  const batch::BatchFunction single = batch::BatchFunction::open(model, urdf, false, spec, options);

  // Knots: kDistinctStates random states, repeated.
  const std::size_t n_in = all.inputCount(), n_out = all.outputCount();
  std::vector<double> in(knots * n_in);
  for (std::uint64_t s = 0; s < std::min(knots, kDistinctStates); ++s) {
    const std::vector<Eigen::VectorXd> state = randomRuntimeInputs(model, spec, s + 1);
    std::size_t at = s * n_in;
    for (const Eigen::VectorXd& block : state) at = std::copy(block.data(), block.data() + block.size(), in.begin() + at) - in.begin();
  }
  for (std::uint64_t k = kDistinctStates; k < knots; ++k)
    std::copy_n(in.begin() + (k % kDistinctStates) * n_in, n_in, in.begin() + k * n_in);

  Row row;
  row.robot = label;
  row.nv = model.nv;
  row.outputs = n_out;
  std::vector<double> out_all(knots * n_out), out_single(knots * n_out), out_loop(knots * n_out);
  row.all = bestRate(knots, [&] { all.evaluateMany(knots, in.data(), out_all.data()); });
  row.one_thread = bestRate(knots, [&] { single.evaluateMany(knots, in.data(), out_single.data()); });
  row.loop = bestRate(knots, [&] {
    for (std::uint64_t k = 0; k < knots; ++k) single.evaluate(in.data() + k * n_in, out_loop.data() + k * n_out);
  });
  row.worst_difference = std::max(worstDifference(out_all, out_loop), worstDifference(out_single, out_loop));

  // The file job: a CSV of the same knots (by index columns), then binary and CSV out.
  const fs::path data = scratch / (label + ".csv");
  {
    std::ofstream csv(data);
    std::string header;
    for (const batch::BlockLayout& block : all.inputs())
      for (const std::string& name : batch::indexColumns(block)) header += (header.empty() ? "" : ",") + name;
    csv << "t," << header << "\n";
    char buffer[32];
    for (std::uint64_t k = 0; k < knots; ++k) {
      csv << k * 1e-3;
      for (std::size_t i = 0; i < n_in; ++i) {
        csv << ',';
        csv.write(buffer, std::to_chars(buffer, buffer + sizeof buffer, in[k * n_in + i]).ptr - buffer);
      }
      csv << '\n';
    }
  }
  batch::TrajectoryJob job;
  job.data = data;
  job.out = scratch / (label + ".rdb");
  row.job_binary = bestRate(knots, [&] { batch::runTrajectoryJob(all, model, spec, job); });
  job.out = scratch / (label + "-out.csv");
  row.job_csv = bestRate(knots, [&] { batch::runTrajectoryJob(all, model, spec, job); });
  return row;
}

}  // namespace

int main(int argc, char** argv) {
  std::uint64_t knots = 100000;
  fs::path cache;
  std::vector<std::pair<fs::path, std::string>> robots;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--knots" && i + 1 < argc) knots = std::strtoull(argv[++i], nullptr, 10);
    else if (arg == "--cache" && i + 1 < argc) cache = argv[++i];
    else if (arg == "--urdf" && i + 1 < argc) robots.emplace_back(argv[i + 1], fs::path(argv[i + 1]).stem().string()), ++i;
    else {
      std::cerr << "usage: trajectory_bench [--knots N] [--cache DIR] [--urdf FILE ...]\n";
      return 2;
    }
  }
  if (robots.empty()) {
    robots.emplace_back(fs::path(ROBODIFF_SOURCE_DIR) / "examples/robots/arm7.urdf", "arm7");
    const fs::path panda = fs::path(ROBODIFF_SHARED_DIR) / "robots/panda_arm_fixed_fingers.urdf";
    if (fs::exists(panda)) robots.emplace_back(panda, "panda");
  }
  // Scratch (and, without --cache, the cache): a fresh directory, removed at the end.
  std::string pattern = (fs::temp_directory_path() / "trajectory-bench-XXXXXX").string();
  if (!::mkdtemp(pattern.data())) {
    std::perror("mkdtemp");
    return 1;
  }
  const fs::path scratch = pattern;
  if (cache.empty()) cache = scratch / "cache";

  std::vector<Row> rows;
  try {
    for (const auto& [urdf, label] : robots) rows.push_back(benchRobot(urdf, label, knots, cache, scratch));
  } catch (const std::exception& e) {
    std::cerr << "trajectory_bench: " << e.what() << "\n";
    fs::remove_all(scratch);
    return 1;
  }
  fs::remove_all(scratch);

  std::printf("Trajectory evaluation: RNEA + Jacobian d tau / d[q, v, a] (compiled -O2 -march=native), %s knots, "
              "%u hardware threads, best of %d runs, knots/s\n\n",
              cli::formatGrouped(static_cast<double>(knots)).c_str(), std::thread::hardware_concurrency(), kRuns);
  std::printf("| robot | nv | doubles out/knot | (a) evaluateMany, all cores | (b) evaluateMany, 1 thread | "
              "(c) evaluate() per knot | (a)/(c) | (b)/(c) | (d) CSV in -> .rdb out | (e) CSV in -> CSV out | "
              "max rel. diff |\n");
  std::printf("|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n");
  for (const Row& r : rows)
    std::printf("| %s | %d | %zu | %s | %s | %s | %.1fx | %.2fx | %s | %s | %.1e |\n", r.robot.c_str(), r.nv,
                r.outputs, cli::formatGrouped(r.all).c_str(), cli::formatGrouped(r.one_thread).c_str(), cli::formatGrouped(r.loop).c_str(),
                r.all / r.loop, r.one_thread / r.loop, cli::formatGrouped(r.job_binary).c_str(), cli::formatGrouped(r.job_csv).c_str(),
                r.worst_difference);
  return 0;
}
