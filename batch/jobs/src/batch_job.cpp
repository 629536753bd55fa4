// runBatchJob / validateBatchJob: the table of job kinds.
#include "robodiff/batch/batch_job.hpp"

#include <algorithm>

#include "job_kinds.hpp"
#include "robodiff/language/bounded_text.hpp"
#include "robodiff/language/suggest.hpp"

namespace robodiff::batch {
namespace {

struct Kind {
  const char* name;
  std::vector<std::string> parameters;  // every key the kind reads; any other is refused
  void (*validate)(const nlohmann::json& params, const FileAccess& files);
  nlohmann::json (*run)(const nlohmann::json& params, const BatchJobContext& context);
};

const std::vector<Kind>& kinds() {
  static const std::vector<Kind> table = {
      {"trajectory",
       {"urdf", "urdf_text", "floating_base", "spec", "spec_json", "data", "out", "format", "backend"},
       validateTrajectoryParams, runTrajectoryKind},
      {"identify",
       {"urdf", "urdf_text", "floating_base", "data", "holdout", "weighted", "physical", "backend"},
       validateIdentifyParams, runIdentifyKind},
      {"trajopt",
       {"urdf", "urdf_text", "floating_base", "q0", "qT", "knots", "duration", "torque_weight", "smoothness_weight",
        "velocity_limits", "torque_limits", "max_iterations", "backend"},
       validateTrajoptParams, runTrajoptKind},
  };
  return table;
}

const Kind& kindOf(const std::string& name) {
  for (const Kind& k : kinds())
    if (name == k.name) return k;
  std::string known;
  for (const Kind& k : kinds()) known += std::string(known.empty() ? "" : ", ") + k.name;
  throw JobParamsError("unknown job kind '" + name + "' (this build runs: " + known + ")");
}

// A misspelt or unknown key would otherwise be ignored and its default used silently.
void refuseUnknownKeys(const Kind& kind, const nlohmann::json& params) {
  for (const auto& [key, value] : params.items()) {
    if (std::find(kind.parameters.begin(), kind.parameters.end(), key) != kind.parameters.end()) continue;
    std::string known;
    for (const std::string& k : kind.parameters) known += (known.empty() ? "" : ", ") + k;
    throw JobParamsError("unknown parameter \"" + language::boundedText(key, 64) + "\" for a job of kind " + kind.name +
                         language::didYouMean(key, kind.parameters) + "; it takes: " + known);
  }
}

}  // namespace

std::vector<std::string> batchJobKinds() {
  std::vector<std::string> names;
  for (const Kind& k : kinds()) names.emplace_back(k.name);
  return names;
}

void validateBatchJob(const std::string& kind, const nlohmann::json& params, const FileAccess& files) {
  if (!params.is_object()) throw JobParamsError("a job's parameters must be a JSON object");
  const Kind& k = kindOf(kind);
  refuseUnknownKeys(k, params);
  k.validate(params, files);
}

nlohmann::json runBatchJob(const std::string& kind, const nlohmann::json& params, const BatchJobContext& context) {
  validateBatchJob(kind, params, context.files);
  return kindOf(kind).run(params, context);
}

}  // namespace robodiff::batch
