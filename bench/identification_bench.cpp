// Issue 7: wall time of inertial parameter identification for 10,000 samples of the Panda
// (../shared; arm7 when it is absent), by phase: the CSV read, the base parameters, the
// regressor built into a fresh cache (once) and opened from it, stacked with the compiled
// function on all cores (and with the interpreter, for comparison), ordinary and weighted
// least squares, the report, and the physically consistent fit (normal equations, Ipopt).
// Synthetic samples from a perturbed model (the truth), with noise; the identified base
// parameters' errors are printed in standard errors.
//
//   identification_bench [samples (default 10000)] [threads (default: all cores)]
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <thread>
#include <vector>

#include <unistd.h>

#include "robodiff/batch/identification.hpp"
#include "robodiff/batch/physical_identification.hpp"
#include "robodiff/batch/synthetic_samples.hpp"
#include "robodiff/model/urdf_loader.hpp"

namespace {

using namespace robodiff;
using Clock = std::chrono::steady_clock;
namespace fs = std::filesystem;

struct Row {
  std::string phase;
  double seconds;
  std::string note;
};

std::string readText(const fs::path& path) {
  std::FILE* f = std::fopen(path.c_str(), "rb");
  if (!f) throw std::runtime_error("cannot open " + path.string());
  std::string text;
  char buffer[65536];
  for (std::size_t n; (n = std::fread(buffer, 1, sizeof buffer, f)) > 0;) text.append(buffer, n);
  std::fclose(f);
  return text;
}

double phaseSeconds(const batch::IdentificationResult& r, const std::string& phase) {
  for (const batch::PhaseTime& t : r.times)
    if (t.phase == phase) return t.seconds;
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  const std::size_t samples = argc > 1 ? std::strtoull(argv[1], nullptr, 10) : 10000;
  const unsigned threads = argc > 2 ? static_cast<unsigned>(std::atoi(argv[2])) : std::thread::hardware_concurrency();
  fs::path shared = ROBODIFF_SHARED_DIR;
  if (const char* env = std::getenv("ROBODIFF_SHARED")) shared = env;
  fs::path urdf_path = shared / "robots/panda_arm_fixed_fingers.urdf";
  if (!fs::exists(urdf_path)) {
    std::fprintf(stderr, "note: %s not found, using arm7\n", urdf_path.c_str());
    urdf_path = fs::path(ROBODIFF_SOURCE_DIR) / "examples/robots/arm7.urdf";
  }
  const std::string urdf = readText(urdf_path);
  const Model model = loadUrdfString(urdf, RootJoint::Fixed, urdf_path.string());

  // The data: a perturbed truth, smooth exciting motion at 100 Hz, 0.02 N m noise.
  const Model truth = batch::perturbInertias(model, 0.25, 1);
  batch::SyntheticOptions data;
  data.samples = samples;
  data.noise = 0.02;
  const fs::path dir = fs::temp_directory_path() / ("robodiff-identification-bench-" + std::to_string(::getpid()));
  fs::create_directories(dir);
  const fs::path csv = dir / "samples.csv";
  batch::writeMeasuredSamples(csv, batch::syntheticSamples(truth, data), model);

  std::vector<Row> rows;
  auto t0 = Clock::now();
  const batch::MeasuredSamples measured = batch::readMeasuredSamples(csv, model);
  rows.push_back({"read CSV", batch::secondsSince(t0),
                  std::to_string(measured.size()) + " rows, " + std::to_string(fs::file_size(csv) >> 20) + " MiB"});

  batch::IdentificationOptions options;
  options.function.backend = batch::Backend::Compiled;
  options.function.cache_dir = dir / "cache";
  options.function.worker_executable = ROBODIFF_WORKER_PATH;
  options.function.threads = threads;
  options.holdout = 0.2;

  // Cold: the regressor built into the fresh cache (a worker process, the C compiler).
  t0 = Clock::now();
  batch::openRegressor(model, urdf, false, options.function);
  rows.push_back({"regressor: build into a fresh cache (once per robot)", batch::secondsSince(t0), "worker + cc"});

  // Warm: the whole identification, by phase.
  t0 = Clock::now();
  const batch::IdentificationProblem problem =
      batch::prepareIdentification(model, urdf, urdf_path.string(), false, measured, options);
  const batch::IdentificationResult ols = batch::identifyLeastSquares(problem, options);
  const double total = batch::secondsSince(t0);
  const std::size_t equations = static_cast<std::size_t>(problem.fit.W.rows());
  rows.push_back({"base parameters (QR with pivoting, random states)", phaseSeconds(ols, "base parameters"),
                  std::to_string(problem.base.standard_count) + " -> " + std::to_string(problem.base.size())});
  rows.push_back({"regressor: open from the cache", phaseSeconds(ols, "regressor function"), ""});
  const double stack = phaseSeconds(ols, "stacking the regressor");
  char note[96];
  std::snprintf(note, sizeof note, "%zu samples, %u threads, %.2f us/sample", measured.size(), threads,
                1e6 * stack / static_cast<double>(measured.size()));
  rows.push_back({"stack the regressor (compiled)", stack, note});
  std::snprintf(note, sizeof note, "%zu x %d", equations, problem.base.size());
  rows.push_back({"ordinary least squares (QR, covariance)", phaseSeconds(ols, "least squares"), note});
  rows.push_back({"report (completion, residuals, std errors)", phaseSeconds(ols, "report"), ""});
  rows.push_back({"total, warm (OLS)", total, "everything after the CSV read"});

  options.weighted = true;
  t0 = Clock::now();
  const batch::IdentificationResult wls = batch::identifyLeastSquares(problem, options);
  rows.push_back({"weighted least squares (OLS, weights, refit)", phaseSeconds(wls, "weighted least squares"), ""});

  // The physically consistent fit on the same problem (OLS weighting, the default regularisation).
  options.weighted = false;
  const batch::IdentificationResult physical = batch::identifyPhysical(problem, options);
  std::snprintf(note, sizeof note, "%zu x %d into %d x %d", equations, problem.base.standard_count,
                problem.base.standard_count, problem.base.standard_count);
  rows.push_back({"physical: normal equations (streamed)", phaseSeconds(physical, "normal equations"), note});
  std::snprintf(note, sizeof note, "%s, %d iterations, setup %.3f s", physical.solver->status.c_str(),
                physical.solver->iterations, physical.solver->setup_seconds);
  rows.push_back({"physical: fit with Ipopt", phaseSeconds(physical, "physically consistent fit (Ipopt)"), note});

  // The interpreter, for comparison.
  batch::BatchFunctionOptions interpreted = options.function;
  interpreted.backend = batch::Backend::Interpreted;
  t0 = Clock::now();
  const batch::BatchFunction f = batch::openRegressor(model, urdf, false, interpreted);
  const double open_interpreted = batch::secondsSince(t0);
  t0 = Clock::now();
  batch::stackRegressor(f, model, measured);
  const double stack_interpreted = batch::secondsSince(t0);
  std::snprintf(note, sizeof note, "%.2f us/sample; building it %.2f s", 1e6 * stack_interpreted / measured.size(),
                open_interpreted);
  rows.push_back({"stack the regressor (interpreted)", stack_interpreted, note});

  std::printf("Identification of %s: %zu samples (%zu fit, %zu held out), %d standard -> %d base parameters\n\n",
              model.name.c_str(), measured.size(), problem.fit.samples(), problem.held_out.samples(),
              problem.base.standard_count, problem.base.size());
  std::printf("%-52s %10s  %s\n", "phase", "seconds", "");
  for (const Row& r : rows) std::printf("%-52s %10.4f  %s\n", r.phase.c_str(), r.seconds, r.note.c_str());

  // How good the estimate is: errors in standard errors, held-out RMS against the noise.
  const Eigen::VectorXd truth_base = problem.base.fromStandard(batch::modelParameters(truth));
  const Eigen::VectorXd z = (ols.base_values - truth_base).cwiseQuotient(ols.base_std_errors).cwiseAbs();
  std::printf("\nOLS: largest |error| / std error %.2f, mean %.2f; held-out RMS %.4f..%.4f N m (noise %.3f)\n",
              z.maxCoeff(), z.mean(), ols.rms_held_out.minCoeff(), ols.rms_held_out.maxCoeff(), data.noise);
  int valid = 0, ols_valid = 0;
  for (const batch::BodyResult& b : physical.bodies) valid += b.validity.valid;
  for (const batch::BodyResult& b : ols.bodies) ols_valid += b.validity.valid;
  std::printf("physical: held-out RMS %.4f..%.4f N m; valid bodies %d of %zu (OLS: %d)\n",
              physical.rms_held_out.minCoeff(), physical.rms_held_out.maxCoeff(), valid, physical.bodies.size(),
              ols_valid);
  fs::remove_all(dir);
  return 0;
}
