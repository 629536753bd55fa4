// Job kind "trajectory": a function evaluated at every knot of a trajectory file.
//
// Parameters: "urdf" (path) or "urdf_text", "floating_base", "spec" (path) or "spec_json",
// "data" (a CSV or JSON trajectory, batch/trajectory/trajectory_table.hpp), "out" (the
// output's file name in the job's directory, default outputs.csv; .rdb for the binary
// format), "format" (csv | binary; default by extension), "backend" (compiled |
// interpreted; default compiled).
#include <algorithm>

#include "job_kinds.hpp"
#include "job_params.hpp"
#include "robodiff/batch/batch_function.hpp"
#include "robodiff/batch/trajectory_evaluation.hpp"

namespace robodiff::batch {

void validateTrajectoryParams(const nlohmann::json& p, const FileAccess& files) {
  params::checkRobotFields(p, files);
  params::checkSpecFields(p, files);
  params::existingFile(p, "data", files);
  params::resultFileName(p, "out", "outputs.csv");
  if (const auto format = params::optionalString(p, "format")) {
    try {
      parseOutputFormat(*format);
    } catch (const std::invalid_argument& e) {
      throw JobParamsError(std::string("format: ") + e.what());
    }
  }
  params::backend(p);
}

nlohmann::json runTrajectoryKind(const nlohmann::json& p, const BatchJobContext& context) {
  auto progress = [&](double fraction, const std::string& message) {
    if (context.progress) context.progress(fraction, message);
  };
  const params::Robot robot = params::robot(p, context.files);
  const FunctionSpec spec = params::spec(p, context.files);
  BatchFunctionOptions options;
  options.backend = params::backend(p);
  options.cache_dir = context.cache_dir;
  options.on_progress = [&](const std::string& what) { progress(0.0, "function " + what); };
  progress(0.0, "building the function");
  const BatchFunction function = BatchFunction::open(robot.model, robot.urdf_text, robot.floating_base, spec, options);

  TrajectoryJob job;
  job.data = params::existingFile(p, "data", context.files);
  job.out = context.result_dir / params::resultFileName(p, "out", "outputs.csv");
  if (const auto format = params::optionalString(p, "format")) job.format = parseOutputFormat(*format);
  double reported = -1;
  job.evaluation.progress = [&](std::uint64_t done, std::uint64_t total) {
    const double fraction = total > 0 ? 0.05 + 0.9 * static_cast<double>(done) / static_cast<double>(total) : 0.95;
    if (fraction - reported >= 0.05 || done == total) {  // at most ~20 messages
      reported = fraction;
      progress(fraction, "evaluated " + std::to_string(done) + " of " + std::to_string(total) + " knots");
    }
  };
  const TrajectoryReport report = runTrajectoryJob(function, robot.model, spec, job);
  progress(1.0, "wrote " + report.out.filename().string());
  return {{"kind", "trajectory"},
          {"function", spec.functionName()},
          {"backend", toString(function.backend())},
          {"knots", report.knots},
          {"out", report.out.filename().string()},
          {"format", toString(report.format)},
          {"bytes", report.bytes},
          {"knots_per_second", report.knots_per_second},
          {"seconds", {{"read", report.read_seconds}, {"evaluate", report.evaluate_seconds}, {"write", report.write_seconds}}},
          {"non_finite_knots", report.non_finite_knots},
          {"ignored_columns", report.ignored_columns}};
}

}  // namespace robodiff::batch
