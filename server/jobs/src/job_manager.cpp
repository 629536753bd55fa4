// JobManager: jobs queued to a pool of robodiff-worker processes, their progress, their
// results published atomically and recorded in the cache's index.
#include "robodiff/server/job_manager.hpp"

#include <algorithm>
#include <atomic>
#include <cstdio>
#include <deque>
#include <map>
#include <mutex>
#include <random>
#include <thread>

#include <nlohmann/json.hpp>

#include "robodiff/cache/job_index.hpp"
#include "robodiff/workers/worker_pool.hpp"

namespace robodiff::server {
namespace {

namespace fs = std::filesystem;
using json = nlohmann::json;
using Clock = std::chrono::steady_clock;

constexpr std::size_t kMessagesKept = 8;  // per job, the latest

std::int64_t unixMs() {
  return std::chrono::duration_cast<std::chrono::milliseconds>(std::chrono::system_clock::now().time_since_epoch())
      .count();
}

// "job-" and 16 hex digits: unique enough across restarts, short enough to type.
std::string newJobId() {
  static std::mutex mutex;
  static std::mt19937_64 rng(std::random_device{}() ^ static_cast<std::uint64_t>(unixMs()));
  std::lock_guard lock(mutex);
  char text[32];
  std::snprintf(text, sizeof text, "job-%016llx", static_cast<unsigned long long>(rng()));
  return text;
}

// The refusal for another caller's job: names neither the owner nor anything of the job.
Status notYours(const std::string& job_id) {
  return {StatusCode::PermissionDenied,
          "job " + job_id.substr(0, 64) + " belongs to another caller (only its submitter or an operator may see or "
                                          "cancel it)"};
}

bool mayActOn(const JobCaller& caller, const std::string& owner) { return caller.operator_ || caller.name == owner; }

rpc::JobState stateFromText(const std::string& s) {
  if (s == "QUEUED") return rpc::JobState::Queued;
  if (s == "RUNNING") return rpc::JobState::Running;
  if (s == "SUCCEEDED") return rpc::JobState::Succeeded;
  if (s == "CANCELLED") return rpc::JobState::Cancelled;
  return rpc::JobState::Failed;
}

}  // namespace

std::string jobParamsKeepingSpecOrder(const std::string& params_json) {
  auto ordered = nlohmann::ordered_json::parse(params_json.empty() ? "{}" : params_json, nullptr, false);
  if (!ordered.is_object()) return "";
  if (auto it = ordered.find("spec_json"); it != ordered.end() && it->is_object()) *it = it->dump();
  return ordered.dump();
}

struct JobManager::Impl {
  // A job this server accepted (finished ones stay, for status and result).
  struct Job {
    rpc::JobInfo info;
    workers::JobId pool_id = 0;
    std::shared_future<workers::JobResult> done;
    Clock::time_point started{};
    std::string caller;  // who submitted it
    bool cancel_requested = false;
    std::string result_json, result_dir;
    std::thread finisher;
  };

  JobManagerOptions options;
  Logger& log;
  cache::JobIndex index;
  std::string owner = cache::currentJobOwner();
  std::unique_ptr<workers::WorkerPool> pool;
  mutable std::mutex mutex;
  std::map<std::string, std::shared_ptr<Job>> jobs;
  std::atomic<bool> stopping{false};

  Impl(JobManagerOptions o, Logger& l) : options(std::move(o)), log(l), index(options.cache_dir) {
    const int orphans = index.failOrphans(owner, "robodiffd stopped before the job finished");
    if (orphans > 0) log.warn("jobs_orphaned", {{"count", orphans}});
    workers::WorkerPoolOptions pool_options;
    pool_options.worker_executable = options.worker_executable;
    pool_options.workers = std::max(1u, options.workers);
    pool_options.queue_capacity = options.queue_capacity;
    pool_options.default_timeout = options.timeout;
    pool_options.memory_limit_bytes = options.memory_limit_bytes;
    pool = std::make_unique<workers::WorkerPool>(pool_options);
  }

  // Progress from the worker: {"fraction": f, "message": "..."}.
  void onProgress(Job& job, const std::string& text) {
    const json m = json::parse(text, nullptr, false);
    if (!m.is_object()) return;
    std::lock_guard lock(mutex);
    if (const auto f = m.find("fraction"); f != m.end() && f->is_number())
      job.info.progress = std::clamp(f->get<double>(), 0.0, 1.0);
    if (const auto msg = m.find("message"); msg != m.end() && msg->is_string()) {
      job.info.messages.push_back(msg->get<std::string>());
      if (job.info.messages.size() > kMessagesKept) job.info.messages.erase(job.info.messages.begin());
    }
  }

  void onStart(Job& job) {
    {
      std::lock_guard lock(mutex);
      job.info.state = rpc::JobState::Running;
      job.started = Clock::now();
    }
    try {
      index.markRunning(job.info.job_id, unixMs());
    } catch (const std::exception& e) {
      log.error("job_index_failed", {{"job", job.info.job_id}, {"message", e.what()}});
    }
  }

  // The worker's outcome to the job's final state: publish or discard its files, record it.
  void finish(Job& job, const workers::JobResult& r) {
    const std::string& id = job.info.job_id;
    const fs::path staging = index.stagingDir(id), final_dir = index.resultDir(id);
    rpc::JobState state = rpc::JobState::Failed;
    std::string error, result_json;
    if (r.state == workers::JobState::Succeeded) {
      const json reply = json::parse(r.reply, nullptr, false);
      result_json = reply.is_object() && reply.contains("result") ? reply["result"].dump() : "{}";
      std::error_code ec;
      fs::remove_all(final_dir, ec);
      fs::rename(staging, final_dir, ec);
      if (ec) {
        error = "the job's results could not be published (" + staging.string() + " -> " + final_dir.string() +
                "): " + ec.message();
      } else {
        state = rpc::JobState::Succeeded;
      }
    } else if (r.state == workers::JobState::Failed) {
      const json reply = json::parse(r.reply, nullptr, false);
      error = reply.is_object() ? reply.value("message", r.message) : r.message;
    } else if (r.state == workers::JobState::Cancelled) {
      state = rpc::JobState::Cancelled;
      error = stopping ? "robodiffd stopped before the job finished" : "cancelled by a client";
      if (stopping) state = rpc::JobState::Failed;
    } else if (r.state == workers::JobState::TimedOut) {
      error = "the job ran past its time limit and its worker was killed (" + r.message + ")";
    } else {  // Crashed
      error = "the worker running the job died: " + r.message;
    }
    if (state != rpc::JobState::Succeeded) {
      std::error_code ignored;
      fs::remove_all(staging, ignored);
    }
    try {
      index.finish(id, toString(state), result_json, state == rpc::JobState::Succeeded ? final_dir.string() : "",
                   error, unixMs());
    } catch (const std::exception& e) {
      log.error("job_index_failed", {{"job", id}, {"message", e.what()}});
    }
    {
      std::lock_guard lock(mutex);
      job.info.state = state;
      job.info.error = error;
      job.info.elapsed_seconds = r.run_seconds;
      job.info.eta_seconds = 0;
      if (state == rpc::JobState::Succeeded) job.info.progress = 1.0;
      job.result_json = result_json;
      job.result_dir = state == rpc::JobState::Succeeded ? final_dir.string() : "";
    }
    log.info("job_finished", {{"job", id}, {"kind", job.info.kind}, {"state", toString(state)},
                              {"seconds", r.run_seconds}, {"error", error}});
  }

  // A job from the index (another server's, or finished before this one started).
  rpc::JobInfo infoFromRecord(const cache::JobRecord& r) const {
    rpc::JobInfo info;
    info.job_id = r.id;
    info.kind = r.kind;
    info.state = stateFromText(r.state);
    info.progress = info.state == rpc::JobState::Succeeded ? 1.0 : 0.0;
    if (r.started_ms > 0 && r.finished_ms >= r.started_ms) info.elapsed_seconds = (r.finished_ms - r.started_ms) / 1e3;
    info.error = r.error;
    return info;
  }

  // The live view of a job of this server (callers hold mutex).
  rpc::JobInfo snapshot(const Job& job) const {
    rpc::JobInfo info = job.info;
    if (info.state == rpc::JobState::Running) {
      info.elapsed_seconds = std::chrono::duration<double>(Clock::now() - job.started).count();
      info.eta_seconds = info.progress > 0.01 ? info.elapsed_seconds * (1 - info.progress) / info.progress : -1;
    }
    return info;
  }

  // A job of the index: the live view when this server runs it.
  rpc::JobInfo infoOf(const cache::JobRecord& r) const {
    if (const auto job = live(r.id)) {
      std::lock_guard lock(mutex);
      return snapshot(*job);
    }
    return infoFromRecord(r);
  }

  std::shared_ptr<Job> live(const std::string& id) const {
    std::lock_guard lock(mutex);
    const auto it = jobs.find(id);
    return it == jobs.end() ? nullptr : it->second;
  }

  // A job's parameters, a JSON object the job kind's validation accepts with the data
  // directories and earlier jobs' results readable (`readable`).
  Status checkedParams(const rpc::SubmitJobRequest& request, json& params, std::vector<fs::path>& readable) const {
    if (request.kind.empty()) return {StatusCode::InvalidArgument, "SubmitJob: the job's kind is empty"};
    const std::string params_text = jobParamsKeepingSpecOrder(request.params_json);
    params = params_text.empty() ? json() : json::parse(params_text);
    if (!params.is_object())
      return {StatusCode::InvalidArgument, "SubmitJob: params_json is not a JSON object: '" +
                                               request.params_json.substr(0, 120) + "'"};
    readable = options.data_dirs;
    readable.push_back(index.resultDir("_").parent_path());  // earlier jobs' results
    if (options.validate) return options.validate(request.kind, params.dump(), readable);
    return {};
  }

  // Joins finished jobs' finisher threads, so that they do not pile up.
  void joinFinished() {
    std::lock_guard lock(mutex);
    for (auto& [id, job] : jobs)
      if (rpc::isFinal(job->info.state) && job->finisher.joinable()) job->finisher.join();
  }

  // The job queued in the job index.
  Status indexQueued(const Job& job, const json& params) {
    cache::JobRecord record;
    record.id = job.info.job_id;
    record.kind = job.info.kind;
    record.state = "QUEUED";
    record.params_json = params.dump();
    record.owner = owner;
    record.caller = job.caller;
    record.submitted_ms = unixMs();
    try {
      index.insert(record);
    } catch (const std::exception& e) {
      return {StatusCode::Internal, std::string("SubmitJob: the job index refused the job: ") + e.what()};
    }
    return {};
  }

  // The job handed to the worker pool and listed; a full queue fails it in the index.
  Status queue(const std::shared_ptr<Job>& job, const json& worker_request) {
    workers::JobCallbacks callbacks;
    Job* raw = job.get();
    callbacks.on_start = [this, raw](pid_t) { onStart(*raw); };
    callbacks.on_progress = [this, raw](const std::string& text) { onProgress(*raw, text); };
    try {
      std::lock_guard lock(mutex);  // the finisher must find the job in the table
      const workers::JobHandle handle = pool->submit(worker_request.dump(), std::move(callbacks));
      job->pool_id = handle.id;
      job->done = handle.result;
      jobs[job->info.job_id] = job;
    } catch (const workers::QueueFull&) {
      index.finish(job->info.job_id, "FAILED", "", "", "the job queue was full", unixMs());
      return {StatusCode::ResourceExhausted, "SubmitJob: " + std::to_string(options.queue_capacity) +
                                                 " jobs are already waiting; try again later"};
    }
    job->finisher = std::thread([this, job] { finish(*job, job->done.get()); });
    return {};
  }
};

JobManager::JobManager(JobManagerOptions options, Logger& log) : impl_(std::make_unique<Impl>(std::move(options), log)) {}

JobManager::~JobManager() {
  impl_->stopping = true;
  std::vector<std::shared_ptr<Impl::Job>> all;
  {
    std::lock_guard lock(impl_->mutex);
    for (auto& [id, job] : impl_->jobs) all.push_back(job);
  }
  for (auto& job : all)
    if (!rpc::isFinal(job->info.state)) impl_->pool->cancel(job->pool_id);
  for (auto& job : all)
    if (job->finisher.joinable()) job->finisher.join();
  impl_->pool.reset();
}

Status JobManager::submit(const JobCaller& caller, const rpc::SubmitJobRequest& request, rpc::SubmitJobReply& reply) {
  Impl& m = *impl_;
  json params;
  std::vector<fs::path> readable;
  if (Status s = m.checkedParams(request, params, readable); !s.ok()) return s;
  json readable_json = json::array();
  for (const fs::path& dir : readable) readable_json.push_back(dir.string());
  m.joinFinished();

  auto job = std::make_shared<Impl::Job>();
  job->info.job_id = newJobId();
  job->info.kind = request.kind;
  job->caller = caller.name;
  const std::string& id = job->info.job_id;
  const fs::path staging = m.index.stagingDir(id);
  std::error_code ec;
  fs::create_directories(staging, ec);
  if (ec) return {StatusCode::Internal, "cannot create the job's directory " + staging.string() + ": " + ec.message()};
  Status queued = m.indexQueued(*job, params);
  if (queued.ok()) {
    const json worker_request = {{"type", "batch"},
                                 {"request",
                                  {{"kind", request.kind},
                                   {"params", params},
                                   {"result_dir", staging.string()},
                                   {"readable_dirs", readable_json},
                                   {"cache_dir", m.options.cache_dir.string()}}}};
    queued = m.queue(job, worker_request);
  }
  if (!queued.ok()) {
    fs::remove_all(staging, ec);
    return queued;
  }
  m.log.info("job_submitted", {{"job", id}, {"kind", request.kind}, {"caller", caller.name}});
  reply.job_id = id;
  return {};
}

Status JobManager::status(const JobCaller& caller, const rpc::JobStatusRequest& request, rpc::JobStatusReply& reply) {
  Impl& m = *impl_;
  if (!request.job_id.empty()) {
    if (const auto job = m.live(request.job_id)) {
      if (!mayActOn(caller, job->caller)) return notYours(request.job_id);
      std::lock_guard lock(m.mutex);
      reply.jobs.push_back(m.snapshot(*job));
      return {};
    }
    const auto record = m.index.find(request.job_id);
    if (!record) return {StatusCode::NotFound, "no job " + request.job_id + " (JobStatus with no id lists yours)"};
    if (!mayActOn(caller, record->caller)) return notYours(request.job_id);
    reply.jobs.push_back(m.infoFromRecord(*record));
    return {};
  }
  for (const cache::JobRecord& r : m.index.list(0))
    if (mayActOn(caller, r.caller)) reply.jobs.push_back(m.infoOf(r));
  return {};
}

std::vector<rpc::JobInfo> JobManager::recent(std::size_t limit) {
  Impl& m = *impl_;
  std::vector<rpc::JobInfo> jobs;
  for (const cache::JobRecord& r : m.index.list(limit)) jobs.push_back(m.infoOf(r));
  return jobs;
}

Status JobManager::cancel(const JobCaller& caller, const rpc::CancelJobRequest& request, rpc::CancelJobReply& reply) {
  Impl& m = *impl_;
  const auto job = m.live(request.job_id);
  if (!job) {
    const auto record = m.index.find(request.job_id);
    if (!record) return {StatusCode::NotFound, "no job " + request.job_id};
    if (!mayActOn(caller, record->caller)) return notYours(request.job_id);
    reply.state = stateFromText(record->state);  // finished under an earlier server
    return {};
  }
  if (!mayActOn(caller, job->caller)) return notYours(request.job_id);
  {
    std::lock_guard lock(m.mutex);
    job->cancel_requested = true;
  }
  m.pool->cancel(job->pool_id);
  // The worker is killed (SIGTERM, then SIGKILL); the finisher then records the state.
  const auto until = Clock::now() + std::chrono::seconds(2);
  while (Clock::now() < until) {
    {
      std::lock_guard lock(m.mutex);
      if (rpc::isFinal(job->info.state)) break;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  std::lock_guard lock(m.mutex);
  reply.state = job->info.state;
  m.log.info("job_cancel", {{"job", request.job_id}, {"state", toString(reply.state)}, {"caller", caller.name}});
  return {};
}

Status JobManager::result(const JobCaller& caller, const rpc::JobResultRequest& request, rpc::JobResultReply& reply) {
  Impl& m = *impl_;
  if (const auto job = m.live(request.job_id)) {
    if (!mayActOn(caller, job->caller)) return notYours(request.job_id);
    std::lock_guard lock(m.mutex);
    reply.info = m.snapshot(*job);
    reply.result_json = job->result_json;
    reply.result_dir = job->result_dir;
  } else {
    const auto record = m.index.find(request.job_id);
    if (!record) return {StatusCode::NotFound, "no job " + request.job_id};
    if (!mayActOn(caller, record->caller)) return notYours(request.job_id);
    reply.info = m.infoFromRecord(*record);
    reply.result_json = record->result_json;
    reply.result_dir = record->result_dir;
  }
  if (reply.info.state != rpc::JobState::Succeeded)
    return {StatusCode::FailedPrecondition,
            "job " + request.job_id + " is " + toString(reply.info.state) +
                (reply.info.error.empty() ? std::string(": no result yet") : ": " + reply.info.error)};
  return {};
}

JobCounts JobManager::counts() const {
  JobCounts c;
  std::lock_guard lock(impl_->mutex);
  for (const auto& [id, job] : impl_->jobs) {
    switch (job->info.state) {
      case rpc::JobState::Queued: ++c.queued; break;
      case rpc::JobState::Running: ++c.running; break;
      case rpc::JobState::Succeeded: ++c.succeeded; break;
      case rpc::JobState::Failed: ++c.failed; break;
      case rpc::JobState::Cancelled: ++c.cancelled; break;
    }
  }
  return c;
}

}  // namespace robodiff::server
