#pragma once
// A batch job as a worker process runs it: a kind, its parameters (a JSON object), a
// directory for its files. The server's JobManager (server/jobs) queues jobs to
// robodiff-worker processes, which call runBatchJob; the CLI runs the same work in
// process. Kinds and their parameters: schema/README.md ("Jobs").

#include <filesystem>
#include <functional>
#include <stdexcept>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace robodiff::batch {

// Bad parameters: the message names the field and the value.
class JobParamsError : public std::invalid_argument {
 public:
  using std::invalid_argument::invalid_argument;
};

// Where a job may read the files its parameters name. The CLI runs jobs as its own user
// and reads anywhere; a service's jobs run as the service's user for callers who may not
// read what it can, so they read only under the directories it is configured with
// (symbolic links followed before the check). A path outside gets one message whether
// or not it exists, and no file outside is ever opened.
struct FileAccess {
  bool restricted = false;
  std::vector<std::filesystem::path> readable_dirs;  // when restricted

  static FileAccess anywhere() { return {}; }
  static FileAccess under(std::vector<std::filesystem::path> dirs) { return {true, std::move(dirs)}; }
};

struct BatchJobContext {
  std::filesystem::path result_dir;  // an empty directory for the job's files
  std::filesystem::path cache_dir;   // where compiled functions are found or built
  FileAccess files;                  // where the parameters' paths may point
  // Progress: a fraction 0..1 and a line for a person (either may repeat).
  std::function<void(double fraction, const std::string& message)> progress;
};

// The kinds this build knows, e.g. {"trajectory", "identify", "trajopt"}.
std::vector<std::string> batchJobKinds();

// Checks a kind and its parameters without running anything (cheap: at SubmitJob).
// Throws JobParamsError naming the problem.
void validateBatchJob(const std::string& kind, const nlohmann::json& params,
                      const FileAccess& files = FileAccess::anywhere());

// Runs the job; its files go into context.result_dir. Returns the result summary (a JSON
// object). Throws JobParamsError for bad parameters, std::exception when the work fails.
nlohmann::json runBatchJob(const std::string& kind, const nlohmann::json& params, const BatchJobContext& context);

}  // namespace robodiff::batch
