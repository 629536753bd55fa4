// A function over a whole trajectory: every knot's value and Jacobian equal core/dynamics
// and central differences (a fixed arm and a floating-base humanoid), the compiled and
// interpreted backends agree through files, and a cancelled job leaves no output.
#include <cmath>
#include <filesystem>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "robodiff/batch/csv_table.hpp"
#include "robodiff/batch/trajectory_error.hpp"
#include "robodiff/batch/trajectory_evaluation.hpp"
#include "trajectory/trajectory_fixtures.hpp"

namespace robodiff::testing {
namespace {

namespace fs = std::filesystem;

// Every knot of `out` against the reference: value (1e-10) and Jacobian w.r.t. q, v, a (1e-5).
void expectReference(const Model& model, const FunctionSpec& spec, const std::vector<std::vector<Eigen::VectorXd>>& states,
                     const batch::TrajectoryOutput& out) {
  ASSERT_EQ(out.knots, states.size());
  const batch::BlockLayout* value = nullptr;
  const batch::BlockLayout* jacobian = nullptr;
  for (const batch::BlockLayout& b : out.blocks) (b.name == "value" ? value : jacobian) = &b;
  ASSERT_TRUE(value && jacobian);
  for (std::size_t k = 0; k < states.size(); ++k) {
    const std::vector<Eigen::VectorXd> all = completeInputs(spec, states[k]);
    const Eigen::VectorXd tau = referenceValue(model, spec, all);
    const Eigen::MatrixXd jac = finiteDifferenceJacobian(model, spec, all, {"q", "v", "a"});
    ASSERT_EQ(value->size, tau.size());
    ASSERT_EQ(jacobian->rows * jacobian->cols, jac.size());
    const double* row = out.knot(k);
    for (Eigen::Index i = 0; i < tau.size(); ++i)
      ASSERT_NEAR(row[value->offset + i], tau[i], 1e-10 * (1 + std::abs(tau[i]))) << "knot " << k << " value " << i;
    for (Eigen::Index r = 0; r < jac.rows(); ++r)
      for (Eigen::Index c = 0; c < jac.cols(); ++c)
        ASSERT_NEAR(row[jacobian->offset + r * jac.cols() + c], jac(r, c), 1e-5 * (1 + std::abs(jac(r, c))))
            << "knot " << k << " jacobian " << r << "," << c;
  }
}

TEST(TrajectoryEvaluation, EveryKnotMatchesTheReferenceOnTheArm) {
  const Robot arm("arm7");
  const FunctionSpec spec = parseFunctionSpec(kRneaJacobian);
  TempDir tmp;
  const batch::BatchFunction f = arm.open(spec, batch::Backend::Interpreted, tmp / "cache");
  const auto states = randomKnots(arm.model, spec, 40);
  const batch::TrajectoryTable table =
      batch::parseTrajectoryCsv(trajectoryCsv(arm.model, f, states), "arm.csv", arm.model, f.inputs());
  EXPECT_EQ(table.ignored_columns, (std::vector<std::string>{"note"}));
  std::uint64_t last_done = 0, total = 0;
  batch::TrajectoryEvaluationOptions options;
  options.progress = [&](std::uint64_t done, std::uint64_t of) { last_done = done, total = of; };
  const batch::TrajectoryEvaluation result = batch::evaluateTrajectory(f, table, options);
  EXPECT_EQ(last_done, 40u);
  EXPECT_EQ(total, 40u);
  EXPECT_EQ(result.output.times, table.times);
  EXPECT_EQ(result.non_finite_knots, 0u);
  EXPECT_GT(result.knotsPerSecond(), 0.0);
  expectReference(arm.model, spec, states, result.output);
}

TEST(TrajectoryEvaluation, EveryKnotMatchesTheReferenceOnAFloatingBase) {
  const Robot humanoid("humanoid", true);
  const FunctionSpec spec = parseFunctionSpec(kRneaJacobian);
  TempDir tmp;
  const batch::BatchFunction f = humanoid.open(spec, batch::Backend::Interpreted, tmp / "cache");
  const auto states = randomKnots(humanoid.model, spec, 6);
  const std::string csv = trajectoryCsv(humanoid.model, f, states);
  EXPECT_EQ(csv.rfind("t,q_root_joint_x,q_root_joint_y,q_root_joint_z,q_root_joint_qx", 0), 0u);
  const batch::TrajectoryTable table = batch::parseTrajectoryCsv(csv, "humanoid.csv", humanoid.model, f.inputs());
  expectReference(humanoid.model, spec, states, batch::evaluateTrajectory(f, table).output);
}

// The compiled function (batched entry point, several threads) through the whole job,
// CSV and binary, against the interpreter on the same file read by index columns.
TEST(TrajectoryEvaluation, CompiledJobFilesEqualTheInterpreter) {
  const Robot arm("arm7");
  const FunctionSpec spec = parseFunctionSpec(kRneaJacobianQuickBuild);
  TempDir tmp;
  const batch::BatchFunction compiled = arm.open(spec, batch::Backend::Compiled, tmp / "cache", 3);
  const batch::BatchFunction interpreted = arm.open(spec, batch::Backend::Interpreted, tmp / "cache");
  const auto states = randomKnots(arm.model, spec, 1001);
  const fs::path data = tmp.file("traj.csv", trajectoryCsv(arm.model, compiled, states, /*by_index=*/true));

  batch::TrajectoryJob job;
  job.data = data;
  job.out = tmp / "out.csv";
  const batch::TrajectoryReport csv_report = batch::runTrajectoryJob(compiled, arm.model, spec, job);
  EXPECT_EQ(csv_report.knots, 1001u);
  EXPECT_EQ(csv_report.format, batch::OutputFormat::Csv);
  EXPECT_EQ(csv_report.bytes, fs::file_size(job.out));
  EXPECT_GT(csv_report.knots_per_second, 0.0);
  EXPECT_TRUE(csv_report.first_non_finite.empty());
  job.out = tmp / "out.rdb";
  batch::runTrajectoryJob(compiled, arm.model, spec, job);

  const batch::TrajectoryOutput binary = batch::readTrajectoryBinary(tmp / "out.rdb");
  EXPECT_EQ(binary.function, "rnea");
  EXPECT_EQ(binary.model, arm.model.name);
  EXPECT_EQ(binary.spec_json, nlohmann::json::parse(normalizedSpecJson(spec)).dump());
  const batch::CsvTable csv = batch::CsvTable::readFile(tmp / "out.csv");
  ASSERT_EQ(csv.rows(), 1001u);
  ASSERT_EQ(csv.columns(), 1 + compiled.outputCount());

  const batch::TrajectoryTable table = batch::readTrajectoryFile(data, arm.model, interpreted.inputs());
  const batch::TrajectoryOutput reference = batch::evaluateTrajectory(interpreted, table).output;
  for (std::uint64_t k = 0; k < binary.knots; ++k) {
    ASSERT_EQ(binary.times[k], csv.number(k, 0));
    for (std::size_t i = 0; i < binary.output_count; ++i) {
      ASSERT_EQ(binary.knot(k)[i], csv.number(k, i + 1)) << "knot " << k << " entry " << i;
      const double expected = reference.knot(k)[i];
      ASSERT_NEAR(binary.knot(k)[i], expected, 1e-9 * (1 + std::abs(expected))) << "knot " << k << " entry " << i;
    }
  }
}

TEST(TrajectoryEvaluation, ACancelledJobLeavesNoOutputFile) {
  const Robot arm("arm7");
  const FunctionSpec spec = parseFunctionSpec(kRneaJacobian);
  TempDir tmp;
  const batch::BatchFunction f = arm.open(spec, batch::Backend::Interpreted, tmp / "cache");
  const fs::path data = tmp.file("traj.csv", trajectoryCsv(arm.model, f, randomKnots(arm.model, spec, 3000)));
  fs::create_directories(tmp / "out");
  batch::TrajectoryJob job;
  job.data = data;
  job.out = tmp / "out" / "result.csv";
  int polls = 0;
  job.evaluation.cancelled = [&] { return ++polls > 3; };
  EXPECT_THROW(batch::runTrajectoryJob(f, arm.model, spec, job), batch::TrajectoryCancelled);
  EXPECT_TRUE(fs::is_empty(tmp / "out"));
}

TEST(TrajectoryEvaluation, AHeaderWithoutRowsGivesAnEmptyOutput) {
  const Robot arm("arm7");
  const FunctionSpec spec = parseFunctionSpec(kRneaJacobian);
  TempDir tmp;
  const batch::BatchFunction f = arm.open(spec, batch::Backend::Interpreted, tmp / "cache");
  batch::TrajectoryJob job;
  job.data = tmp.file("empty.csv", trajectoryCsv(arm.model, f, {}) + "\n");
  job.out = tmp / "out.rdb";
  EXPECT_EQ(batch::runTrajectoryJob(f, arm.model, spec, job).knots, 0u);
  EXPECT_EQ(batch::readTrajectoryBinary(job.out).knots, 0u);
  job.out = tmp / "out.csv";
  batch::runTrajectoryJob(f, arm.model, spec, job);
  EXPECT_EQ(batch::CsvTable::readFile(job.out).rows(), 0u);
}

TEST(TrajectoryEvaluation, ReadingErrorsComeBeforeAnyWork) {
  const Robot arm("arm7");
  const FunctionSpec spec = parseFunctionSpec(kRneaJacobian);
  TempDir tmp;
  const batch::BatchFunction f = arm.open(spec, batch::Backend::Interpreted, tmp / "cache");
  std::string csv = trajectoryCsv(arm.model, f, randomKnots(arm.model, spec, 20));
  // Line 17 is knot 15: its note field becomes two fields.
  std::size_t at = 0;
  for (int line = 1; line < 17; ++line) at = csv.find('\n', at) + 1;
  csv.insert(csv.find('\n', at), ",extra");
  batch::TrajectoryJob job;
  job.data = tmp.file("traj.csv", csv);
  job.out = tmp / "out.csv";
  try {
    batch::runTrajectoryJob(f, arm.model, spec, job);
    ADD_FAILURE() << "no error";
  } catch (const batch::TrajectoryError& e) {
    EXPECT_EQ(std::string(e.what()), job.data.string() + ":17: 24 fields, the header (line 1) has 23");
  }
  EXPECT_FALSE(fs::exists(job.out));
  job.out = tmp / "out.txt";
  EXPECT_THROW(batch::runTrajectoryJob(f, arm.model, spec, job), batch::TrajectoryError);
}

}  // namespace
}  // namespace robodiff::testing
