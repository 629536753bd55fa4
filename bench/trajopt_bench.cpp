// Trajectory optimisation benchmark (issue 7), one run, one table: T = 50 knots for the
// Panda (../shared's, else the project's arm7), from a ready pose to a far one in 2 s,
// torque weight 1e-3, velocity limits on. For each way of solving, the wall time of the
// Ipopt solve (median of --repeat runs), Ipopt's iterations, and the solve split into the
// time in the generated functions (evaluating all knots and assembling the derivatives)
// and the rest (Ipopt itself: MUMPS factorisations, line search, bookkeeping).
//   - compiled, exact Hessian: the library built into a fresh cache (setup = the build),
//     then opened again from the cache (setup = a warm hit);
//   - compiled, exact Hessian, with the URDF's effort limits as nonlinear constraints;
//   - compiled, limited-memory quasi-Newton (no Hessian asked for): what exact
//     second derivatives buy (one run: it is slow to give up);
//   - interpreted, exact Hessian: no compiler.
// Run by hand:  build/bin/trajopt_bench [--robot URDF] [--knots T] [--repeat N] [--cache DIR]
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <unistd.h>

#include "robodiff/batch/trajectory_optimization.hpp"
#include "robodiff/batch/trajectory_optimization_functions.hpp"
#include "robodiff/model/urdf_loader.hpp"

namespace fs = std::filesystem;
using namespace robodiff;
using Clock = std::chrono::steady_clock;

namespace {

struct Args {
  fs::path urdf;
  std::string label;
  int knots = 50, repeat = 5;
  fs::path cache;  // empty: a fresh temporary cache
};

Args parseArgs(int argc, char** argv) {
  Args args;
  const fs::path panda = fs::path(ROBODIFF_SHARED_DIR) / "robots" / "panda_arm_fixed_fingers.urdf";
  if (fs::exists(panda)) args.urdf = panda, args.label = "Panda";
  else
    args.urdf = fs::path(ROBODIFF_SOURCE_DIR) / "examples" / "robots" / "arm7.urdf", args.label = "arm7 (no ../shared)";
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto value = [&]() -> std::string {
      if (i + 1 >= argc) {
        std::fprintf(stderr, "%s needs a value\n", a.c_str());
        std::exit(2);
      }
      return argv[++i];
    };
    if (a == "--robot") args.urdf = value(), args.label = args.urdf.stem().string();
    else if (a == "--knots") args.knots = std::stoi(value());
    else if (a == "--repeat") args.repeat = std::max(1, std::stoi(value()));
    else if (a == "--cache") args.cache = value();
    else {
      std::fprintf(stderr, "usage: trajopt_bench [--robot URDF] [--knots T] [--repeat N] [--cache DIR]\n");
      std::exit(2);
    }
  }
  return args;
}

std::string readText(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

// Start and goal at 25% and 70% of every joint's range: a long move, within the limits.
Eigen::VectorXd atFraction(const Model& model, double fraction) {
  const Eigen::VectorXd lo = model.lowerPositionLimit(), hi = model.upperPositionLimit();
  Eigen::VectorXd q(model.nq);
  for (int i = 0; i < model.nq; ++i)
    q[i] = std::isfinite(lo[i]) && std::isfinite(hi[i]) ? lo[i] + fraction * (hi[i] - lo[i]) : fraction - 0.5;
  return q;
}

struct Row {
  std::string way;
  double setup = 0;
  batch::TrajectoryOptimizationResult result;  // the median run's
};

double seconds(Clock::time_point since) { return std::chrono::duration<double>(Clock::now() - since).count(); }

// Opens the functions (timed), then solves `repeat` times; keeps the median solve.
Row measure(const std::string& way, const Model& model, const std::string& urdf_text,
            const batch::BatchFunctionOptions& function_options, const batch::TrajectoryOptimizationOptions& options,
            int repeat) {
  Row row;
  row.way = way;
  const auto start = Clock::now();
  const batch::TrajectoryFunctions functions = batch::TrajectoryFunctions::open(model, urdf_text, function_options);
  row.setup = seconds(start);
  std::vector<batch::TrajectoryOptimizationResult> runs;
  for (int r = 0; r < repeat; ++r) runs.push_back(batch::optimizeTrajectory(model, functions, options));
  std::sort(runs.begin(), runs.end(), [](const auto& a, const auto& b) { return a.solve_seconds < b.solve_seconds; });
  row.result = runs[runs.size() / 2];
  return row;
}

}  // namespace

int main(int argc, char** argv) {
  const Args args = parseArgs(argc, argv);
  const std::string urdf_text = readText(args.urdf);
  const Model model = loadUrdfString(urdf_text, RootJoint::Fixed, args.urdf.string());

  fs::path cache = args.cache;
  bool remove_cache = false;
  if (cache.empty()) {
    std::string pattern = (fs::temp_directory_path() / "trajopt_bench_XXXXXX").string();
    if (!mkdtemp(pattern.data())) {
      std::perror("mkdtemp");
      return 1;
    }
    cache = pattern;
    remove_cache = true;
  }

  batch::TrajectoryOptimizationOptions options;
  options.knots = args.knots;
  options.duration = 2.0;
  options.torque_weight = 1e-3;
  options.q0 = atFraction(model, 0.25);
  options.qT = atFraction(model, 0.70);

  batch::BatchFunctionOptions compiled;
  compiled.backend = batch::Backend::Compiled;
  compiled.cache_dir = cache;
  batch::BatchFunctionOptions interpreted;
  interpreted.backend = batch::Backend::Interpreted;
  batch::TrajectoryOptimizationOptions quasi_newton = options;
  quasi_newton.ipopt.exact_hessian = false;
  batch::TrajectoryOptimizationOptions with_torque_limits = options;
  with_torque_limits.torque_limits = true;

  std::vector<Row> rows;
  try {
    rows.push_back(measure("compiled, exact Hessian (cold build)", model, urdf_text, compiled, options, args.repeat));
    rows.push_back(measure("compiled, exact Hessian (warm cache)", model, urdf_text, compiled, options, args.repeat));
    rows.push_back(measure("compiled, exact Hessian, torque limits", model, urdf_text, compiled, with_torque_limits,
                           args.repeat));
    // Slow to give up: measured once.
    rows.push_back(measure("compiled, quasi-Newton (L-BFGS), 1 run", model, urdf_text, compiled, quasi_newton, 1));
    rows.push_back(measure("interpreted, exact Hessian", model, urdf_text, interpreted, options, args.repeat));
  } catch (const std::exception& e) {
    std::fprintf(stderr, "trajopt_bench: %s\n", e.what());
    if (remove_cache) fs::remove_all(cache);
    return 1;
  }
  if (remove_cache) fs::remove_all(cache);

  std::printf("Trajectory optimisation, %s (nv = %d): T = %d knots over %.1f s, torque weight %g, velocity limits on\n",
              args.label.c_str(), model.nv, options.knots, options.duration, options.torque_weight);
  std::printf("%d variables; solve times are the median of %d runs\n\n", options.knots * model.nv, args.repeat);
  std::printf("| %-40s | %8s | %8s | %5s | %12s | %10s | %9s | %12s | %-22s |\n", "way", "setup s", "solve ms",
              "iters", "functions ms", "Ipopt ms", "ms/iter", "cost", "status");
  std::printf("|%s|%s|%s|%s|%s|%s|%s|%s|%s|\n", std::string(42, '-').c_str(), std::string(10, '-').c_str(),
              std::string(10, '-').c_str(), std::string(7, '-').c_str(), std::string(14, '-').c_str(),
              std::string(12, '-').c_str(), std::string(11, '-').c_str(), std::string(14, '-').c_str(),
              std::string(24, '-').c_str());
  for (const Row& row : rows) {
    const batch::TrajectoryOptimizationResult& r = row.result;
    const double solve_ms = r.solve_seconds * 1e3, functions_ms = r.evaluation_seconds * 1e3;
    std::printf("| %-40s | %8.3f | %8.1f | %5d | %12.1f | %10.1f | %9.2f | %12.6g | %-22s |\n", row.way.c_str(),
                row.setup, solve_ms, r.iterations, functions_ms, solve_ms - functions_ms,
                r.iterations ? solve_ms / r.iterations : 0.0, r.cost.total, r.status.c_str());
  }
  const batch::TrajectoryOptimizationResult& best = rows[1].result;
  std::printf("\ncompiled, exact Hessian: %d first-order and %d second-order batches of %d knots; straight line cost "
              "%.6g -> %.6g; max violation position %.2g, velocity %.2g\n",
              best.first_order_evaluations, best.second_order_evaluations, options.knots, best.initial_cost.total,
              best.cost.total, best.violation.position, best.violation.velocity);
  return 0;
}
