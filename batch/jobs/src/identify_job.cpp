// Job kind "identify": inertial parameters from measured samples.
//
// Parameters: "urdf" (path) or "urdf_text", "floating_base", "data" (samples CSV,
// batch/identification/measured_samples.hpp), "holdout" (fraction held out, default 0.2),
// "weighted" (WLS), "physical" (the physically consistent fit with Ipopt), "backend"
// (compiled | interpreted). Files: identification.json (the full report) and
// identified.urdf (the URDF with the identified inertials, when every body can be written).
#include <algorithm>
#include <cmath>

#include "job_kinds.hpp"
#include "job_params.hpp"
#include "robodiff/batch/atomic_file.hpp"
#include "robodiff/batch/identification.hpp"
#include "robodiff/batch/identification_json.hpp"
#include "robodiff/batch/physical_identification.hpp"
#include "robodiff/batch/urdf_inertials.hpp"

namespace robodiff::batch {
namespace {

void writeText(const std::filesystem::path& path, const std::string& text) {
  AtomicFile file(path);
  file.write(text);
  file.commit();
}

}  // namespace

void validateIdentifyParams(const nlohmann::json& p, const FileAccess& files) {
  params::checkRobotFields(p, files);
  params::existingFile(p, "data", files);
  const double holdout = params::optionalNumber(p, "holdout", 0.2);
  if (!(holdout >= 0 && holdout < 1)) throw JobParamsError("holdout " + std::to_string(holdout) + " is not in [0, 1)");
  params::optionalBool(p, "weighted", false);
  params::optionalBool(p, "physical", false);
  params::backend(p);
}

nlohmann::json runIdentifyKind(const nlohmann::json& p, const BatchJobContext& context) {
  auto progress = [&](double fraction, const std::string& message) {
    if (context.progress) context.progress(fraction, message);
  };
  const params::Robot robot = params::robot(p, context.files);
  const std::filesystem::path data = params::existingFile(p, "data", context.files);
  progress(0.0, "reading " + data.filename().string());
  const MeasuredSamples samples = readMeasuredSamples(data, robot.model);

  IdentificationOptions options;
  options.holdout = params::optionalNumber(p, "holdout", 0.2);
  options.weighted = params::optionalBool(p, "weighted", false);
  options.function.backend = params::backend(p);
  options.function.cache_dir = context.cache_dir;
  double fraction = 0.05;
  options.on_phase = [&](const std::string& phase) {
    progress(fraction, phase);
    fraction = std::min(0.9, fraction + 0.15);
  };
  const IdentificationProblem problem =
      prepareIdentification(robot.model, robot.urdf_text, robot.source, robot.floating_base, samples, options);
  const bool physical = params::optionalBool(p, "physical", false);
  const IdentificationResult result =
      physical ? identifyPhysical(problem, options) : identifyLeastSquares(problem, options);

  nlohmann::json report = identificationJson(problem, result);
  writeText(context.result_dir / "identification.json", report.dump(2) + "\n");
  std::string urdf_note;
  try {
    const UrdfRewrite urdf = rewriteUrdfInertials(problem.urdf_text, problem.urdf_source, problem.model, result.parameters);
    writeText(context.result_dir / "identified.urdf", urdf.text);
    urdf_note = "identified.urdf";
  } catch (const std::exception& e) {
    urdf_note = std::string("not written: ") + e.what();  // least squares may give a body no URDF can hold
  }
  progress(1.0, "identified " + std::to_string(problem.base.independent.size()) + " base parameters");
  double worst_held_out = 0;
  for (Eigen::Index i = 0; i < result.rms_held_out.size(); ++i)
    if (std::isfinite(result.rms_held_out[i])) worst_held_out = std::max(worst_held_out, result.rms_held_out[i]);
  return {{"kind", "identify"},
          {"method", result.method},
          {"samples", samples.size()},
          {"base_parameters", problem.base.independent.size()},
          {"sigma", result.sigma},
          {"worst_held_out_rms", worst_held_out},
          {"report", "identification.json"},
          {"urdf", urdf_note},
          {"warnings", result.warnings}};
}

}  // namespace robodiff::batch
