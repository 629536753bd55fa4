// A user spec (an expression-language function: examples/specs/arm7_mpc_knot.json) in
// batch work with the compiled backend: the library is built by a real robodiff-worker
// from the spec the batch layer sends it, and every knot's outputs equal the
// interpreter's to 1e-12, both through BatchFunction and through a trajectory job as a
// service's job worker runs it (runBatchJob, the spec read from its file).
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <sstream>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "robodiff/batch/batch_function.hpp"
#include "robodiff/batch/batch_job.hpp"
#include "robodiff/functions/reference.hpp"
#include "robodiff/model/urdf_loader.hpp"
#include "support/temp_dir.hpp"
#include "support/test_paths.hpp"

namespace robodiff::testing {
namespace {

namespace fs = std::filesystem;

// The example MPC knot compiled at -O0 for the generic target (a short build); the
// inputs keep the order written (ordered_json), as the file has them.
std::string quickKnotSpec() {
  nlohmann::ordered_json spec = nlohmann::ordered_json::parse(readFile(sourceDir() / "examples/specs/arm7_mpc_knot.json"));
  spec["build"] = {{"optimization", "O0"}, {"march_native", false}};
  return spec.dump(2);
}

// Entry by entry, relative to 1 + |expected|.
void expectClose(const std::vector<double>& actual, const std::vector<double>& expected, std::size_t per_knot) {
  ASSERT_EQ(actual.size(), expected.size());
  for (std::size_t i = 0; i < expected.size(); ++i)
    ASSERT_NEAR(actual[i], expected[i], 1e-12 * (1 + std::abs(expected[i])))
        << "knot " << i / per_knot << " entry " << i % per_knot;
}

// A CSV file's numbers after its header, row by row (the outputs' CSV: shortest
// round-trip numbers).
std::vector<double> csvNumbers(const fs::path& path, std::size_t* columns) {
  std::ifstream in(path);
  std::string line;
  std::getline(in, line);
  *columns = static_cast<std::size_t>(std::count(line.begin(), line.end(), ',')) + 1;
  std::vector<double> numbers;
  while (std::getline(in, line)) {
    std::istringstream fields(line);
    for (std::string field; std::getline(fields, field, ',');) numbers.push_back(std::stod(field));
  }
  return numbers;
}

class BatchUserSpec : public ::testing::Test {
 protected:
  // One cache for the suite: the library is built once, by the first test that needs it.
  static void SetUpTestSuite() {
    dir_ = new TempDir;
    spec_path_ = dir_->file("arm7_mpc_knot_quick.json", quickKnotSpec());
    // Jobs find robodiff-worker beside their program or in PATH, as a service's job worker does.
    const char* path = std::getenv("PATH");
    setenv("PATH", (workerPath().parent_path().string() + ":" + (path ? path : "")).c_str(), 1);
  }
  static void TearDownTestSuite() {
    delete dir_;
    dir_ = nullptr;
  }

  batch::BatchFunction open(batch::Backend backend) const {
    batch::BatchFunctionOptions options;
    options.backend = backend;
    options.cache_dir = *dir_ / "cache";
    options.worker_executable = workerPath();
    options.threads = 2;
    return batch::BatchFunction::open(model_, urdf_, false, spec_, options);
  }

  static TempDir* dir_;
  static fs::path spec_path_;
  std::string urdf_ = readFile(sourceDir() / "examples/robots/arm7.urdf");
  Model model_ = loadUrdfString(urdf_, RootJoint::Fixed, "arm7.urdf");
  FunctionSpec spec_ = loadFunctionSpec(spec_path_.string());
};

TempDir* BatchUserSpec::dir_ = nullptr;
fs::path BatchUserSpec::spec_path_;

TEST_F(BatchUserSpec, CompiledEqualsTheInterpreterOnEveryKnot) {
  const batch::BatchFunction compiled = open(batch::Backend::Compiled);
  const batch::BatchFunction interpreted = open(batch::Backend::Interpreted);
  ASSERT_EQ(compiled.inputCount(), interpreted.inputCount());
  ASSERT_EQ(compiled.outputCount(), interpreted.outputCount());
  EXPECT_EQ(compiled.inputCount(), 7u + 7u + 7u + 3u);  // q, v, u, target; dt, k, d_safe are fixed
  EXPECT_EQ(compiled.output("dq_next").cols, 21u);

  const std::uint64_t knots = 203;  // not a multiple of the batch width
  std::vector<double> in;
  for (std::uint64_t k = 1; k <= knots; ++k)
    for (const Eigen::VectorXd& block : randomRuntimeInputs(model_, spec_, k)) in.insert(in.end(), block.begin(), block.end());
  ASSERT_EQ(in.size(), knots * compiled.inputCount());
  std::vector<double> by_compiled(knots * compiled.outputCount(), std::nan(""));
  std::vector<double> by_interpreter(knots * interpreted.outputCount(), std::nan(""));
  EXPECT_EQ(compiled.evaluateMany(knots, in.data(), by_compiled.data()), knots);
  EXPECT_EQ(interpreted.evaluateMany(knots, in.data(), by_interpreter.data()), knots);
  expectClose(by_compiled, by_interpreter, compiled.outputCount());
}

// The job a service's worker runs for SubmitJob("trajectory"): the spec is read from its
// file and the compiled backend builds it through the cache.
TEST_F(BatchUserSpec, TrajectoryJobBuildsTheUserSpecAndEqualsTheInterpreter) {
  std::ostringstream csv;
  csv.precision(17);
  csv << "t";
  for (const char* block : {"q", "v", "u"})
    for (int i = 0; i < 7; ++i) csv << "," << block << "_" << i;
  csv << ",target_0,target_1,target_2\n";
  for (std::uint64_t k = 1; k <= 50; ++k) {
    csv << 0.01 * static_cast<double>(k);
    for (const Eigen::VectorXd& block : randomRuntimeInputs(model_, spec_, k))
      for (double x : block) csv << "," << x;
    csv << "\n";
  }
  const fs::path data = dir_->file("knots.csv", csv.str());

  auto run = [&](const std::string& backend) {
    const fs::path result = *dir_ / ("job-" + backend);
    fs::create_directories(result);
    const nlohmann::json params = {{"urdf", (sourceDir() / "examples/robots/arm7.urdf").string()},
                                   {"spec", spec_path_.string()},
                                   {"data", data.string()},
                                   {"out", "out.csv"},
                                   {"backend", backend}};
    batch::validateBatchJob("trajectory", params);
    batch::BatchJobContext context;
    context.result_dir = result;
    context.cache_dir = *dir_ / "cache";
    const nlohmann::json summary = batch::runBatchJob("trajectory", params, context);
    EXPECT_EQ(summary["function"], "arm7_mpc_knot");
    EXPECT_EQ(summary["backend"], backend);
    EXPECT_EQ(summary["knots"], 50);
    return result / "out.csv";
  };
  std::size_t compiled_columns = 0, interpreted_columns = 0;
  const std::vector<double> compiled = csvNumbers(run("compiled"), &compiled_columns);
  const std::vector<double> interpreted = csvNumbers(run("interpreted"), &interpreted_columns);
  ASSERT_EQ(compiled_columns, interpreted_columns);
  EXPECT_EQ(compiled.size(), 50 * compiled_columns);
  expectClose(compiled, interpreted, compiled_columns);
}

}  // namespace
}  // namespace robodiff::testing
