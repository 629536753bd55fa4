// runBatchJob / validateBatchJob: the table of job kinds.
#include "robodiff/batch/batch_job.hpp"

#include "job_kinds.hpp"

namespace robodiff::batch {
namespace {

struct Kind {
  const char* name;
  void (*validate)(const nlohmann::json& params, const FileAccess& files);
  nlohmann::json (*run)(const nlohmann::json& params, const BatchJobContext& context);
};

const std::vector<Kind>& kinds() {
  static const std::vector<Kind> table = {
      {"trajectory", validateTrajectoryParams, runTrajectoryKind},
      {"identify", validateIdentifyParams, runIdentifyKind},
      {"trajopt", validateTrajoptParams, runTrajoptKind},
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

}  // namespace

std::vector<std::string> batchJobKinds() {
  std::vector<std::string> names;
  for (const Kind& k : kinds()) names.emplace_back(k.name);
  return names;
}

void validateBatchJob(const std::string& kind, const nlohmann::json& params, const FileAccess& files) {
  if (!params.is_object()) throw JobParamsError("a job's parameters must be a JSON object");
  kindOf(kind).validate(params, files);
}

nlohmann::json runBatchJob(const std::string& kind, const nlohmann::json& params, const BatchJobContext& context) {
  validateBatchJob(kind, params, context.files);
  return kindOf(kind).run(params, context);
}

}  // namespace robodiff::batch
