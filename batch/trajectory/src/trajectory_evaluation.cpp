// Evaluating a function over a trajectory, and the read-evaluate-write job.
#include "robodiff/batch/trajectory_evaluation.hpp"

#include <chrono>
#include <cmath>
#include <stdexcept>

#include "robodiff/batch/trajectory_error.hpp"

namespace robodiff::batch {
namespace {

using Clock = std::chrono::steady_clock;

double secondsSince(Clock::time_point start) { return std::chrono::duration<double>(Clock::now() - start).count(); }

}  // namespace

TrajectoryEvaluation evaluateTrajectory(const BatchFunction& function, const TrajectoryTable& table,
                                        const TrajectoryEvaluationOptions& options) {
  if (table.input_count != function.inputCount() || table.inputs.size() != table.knots * table.input_count)
    throw std::invalid_argument("evaluateTrajectory: " + table.source + " was read for " +
                                std::to_string(table.input_count) + " inputs per knot, the function takes " +
                                std::to_string(function.inputCount()));
  TrajectoryEvaluation result;
  TrajectoryOutput& out = result.output;
  out.blocks = function.outputs();
  out.output_count = function.outputCount();
  out.knots = table.knots;
  out.times = table.times;
  out.values.resize(table.knots * out.output_count);

  std::function<void(std::uint64_t)> progress;
  if (options.progress) progress = [&](std::uint64_t done) { options.progress(done, table.knots); };
  const Clock::time_point start = Clock::now();
  const std::uint64_t done =
      function.evaluateMany(table.knots, table.inputs.data(), out.values.data(), options.cancelled, progress);
  result.seconds = secondsSince(start);
  if (done < table.knots)
    throw TrajectoryCancelled("evaluating " + table.source + " was cancelled after " + std::to_string(done) + " of " +
                              std::to_string(table.knots) + " knots");

  for (std::uint64_t k = 0; k < out.knots; ++k) {
    const double* row = out.knot(k);
    for (std::size_t i = 0; i < out.output_count; ++i)
      if (!std::isfinite(row[i])) {
        if (!result.first_non_finite_knot) result.first_non_finite_knot = k;
        ++result.non_finite_knots;
        break;
      }
  }
  return result;
}

TrajectoryReport runTrajectoryJob(const BatchFunction& function, const Model& model, const FunctionSpec& spec,
                                  const TrajectoryJob& job) {
  TrajectoryReport report;
  report.data = job.data;
  report.out = job.out;
  report.format = job.format ? *job.format : outputFormatFor(job.out);  // a bad extension fails before any work

  Clock::time_point start = Clock::now();
  const TrajectoryTable table = readTrajectoryFile(job.data, model, function.inputs(), configurationInputs(spec));
  report.read_seconds = secondsSince(start);
  report.knots = table.knots;
  report.ignored_columns = table.ignored_columns;

  TrajectoryEvaluation evaluation = evaluateTrajectory(function, table, job.evaluation);
  report.evaluate_seconds = evaluation.seconds;
  report.knots_per_second = evaluation.knotsPerSecond();
  report.non_finite_knots = evaluation.non_finite_knots;
  if (evaluation.first_non_finite_knot) {
    const std::uint64_t k = *evaluation.first_non_finite_knot;
    report.first_non_finite = table.lines.empty() ? "knot " + std::to_string(k)
                                                  : table.source + ":" + std::to_string(table.lines[k]);
  }

  TrajectoryOutput& output = evaluation.output;
  output.function = spec.functionName();
  output.model = model.name;
  output.labels = outputAxisLabels(model, spec, function.inputs(), output.blocks);
  output.spec_json = normalizedSpecJson(spec);
  OutputWriteOptions write;
  write.format = report.format;
  write.threads = job.threads;
  write.cancelled = job.evaluation.cancelled;
  start = Clock::now();
  writeTrajectoryOutput(job.out, output, write);
  report.write_seconds = secondsSince(start);
  report.bytes = std::filesystem::file_size(job.out);
  return report;
}

}  // namespace robodiff::batch
