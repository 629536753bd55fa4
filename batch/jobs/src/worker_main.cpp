// robodiff-worker: the program a WorkerPool runs. The worker host (workers/worker_host.hpp)
// does the talking to the pool and runs build requests; this program adds batch jobs
// (trajectory, identify, trajopt: batch_job.hpp) for the server's JobManager. It lives in
// batch/ because it depends on both layers; workers/ never depends on batch/.
#include <filesystem>
#include <new>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "robodiff/batch/batch_job.hpp"
#include "robodiff/workers/worker_host.hpp"

namespace {

using nlohmann::json;
using robodiff::workers::workerFailure;

// Where the job may read: "readable_dirs" when the request has it (a service's job reads
// only under the directories it sends); absent: the caller runs the worker as itself,
// and the job reads anywhere. False when it is not an array.
bool readableDirsOf(const json& request, robodiff::batch::FileAccess& files) {
  const auto dirs = request.find("readable_dirs");
  if (dirs == request.end()) return true;
  if (!dirs->is_array()) return false;
  std::vector<std::filesystem::path> readable;
  for (const json& d : *dirs)
    if (d.is_string()) readable.emplace_back(d.get<std::string>());
  files = robodiff::batch::FileAccess::under(std::move(readable));
  return true;
}

// A batch job: {"request": {"kind", "params", "result_dir", "cache_dir", "readable_dirs"}}.
// Progress goes out as {"fraction", "message"}; the result is {"ok": true, "result":
// {...}} or a failure naming the problem.
json runBatch(std::uint64_t id, const json& envelope, const robodiff::workers::ProgressSink& progress) {
  const auto request = envelope.find("request");
  if (request == envelope.end() || !request->is_object())
    return workerFailure(id, "invalid_request", "a batch request needs a \"request\" object");
  robodiff::batch::BatchJobContext context;
  context.result_dir = request->value("result_dir", std::string());
  context.cache_dir = request->value("cache_dir", std::string());
  if (!readableDirsOf(*request, context.files))
    return workerFailure(id, "invalid_request", "\"readable_dirs\" must be an array of paths");
  context.progress = [&](double fraction, const std::string& message) {
    progress({{"fraction", fraction}, {"message", message}});
  };
  if (context.result_dir.empty()) return workerFailure(id, "invalid_request", "a batch request needs a \"result_dir\"");
  try {
    const json params = request->value("params", json::object());
    json r = robodiff::workers::workerResult(id, true);
    r["result"] = robodiff::batch::runBatchJob(request->value("kind", std::string()), params, context);
    return r;
  } catch (const robodiff::batch::JobParamsError& e) {
    return workerFailure(id, "invalid_params", e.what());
  } catch (const std::bad_alloc&) {
    return workerFailure(id, "memory",
                         "the job ran out of memory (the job's limit: see the server's job memory setting)");
  } catch (const std::exception& e) {
    return workerFailure(id, "failed", e.what());
  }
}

// "runs a batch job (trajectory, identify, trajopt) for the server's jobs"
std::string batchSummary() {
  std::string kinds;
  for (const std::string& kind : robodiff::batch::batchJobKinds()) kinds += (kinds.empty() ? "" : ", ") + kind;
  return "runs a batch job (" + kinds + ") for the server's jobs";
}

}  // namespace

int main(int argc, char** argv) {
  return robodiff::workers::runWorkerHost(argc, argv, {{"batch", {batchSummary(), runBatch}}});
}
