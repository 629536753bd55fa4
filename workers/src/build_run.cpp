#include "build_run.hpp"

#include <algorithm>
#include <fstream>
#include <iostream>
#include <map>
#include <sstream>
#include <tuple>

#include <nlohmann/json.hpp>

#include "robodiff/model/canonical.hpp"
#include "robodiff/model/urdf_loader.hpp"
#include "robodiff/workers/worker_protocol.hpp"

namespace robodiff::workers {
namespace {

std::string readText(const std::string& path, const char* what) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error("cannot read " + std::string(what) + " " + path);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

// The first lines of a compiler's output: enough to see the error, short enough to print.
std::string firstLines(const std::string& text, int lines) {
  std::string out;
  std::istringstream in(text);
  std::string line;
  for (int i = 0; i < lines && std::getline(in, line); ++i) {
    if (!out.empty()) out += '\n';
    out += line;
  }
  return out;
}

std::string secondsText(std::chrono::milliseconds d) {
  std::ostringstream s;
  s << std::chrono::duration<double>(d).count() << " s";
  return s.str();
}

std::string failureMessage(const JobResult& r) {
  if (r.state == JobState::Succeeded || r.state == JobState::Failed) {
    try {
      const BuildOutcome o = buildOutcomeFromJson(r.reply);
      std::string m = o.message.empty() ? std::string("the build failed") : o.message;
      if (!o.error_kind.empty()) m.insert(0, o.error_kind + ": ");
      if (!o.compiler_output.empty()) {
        m += '\n';
        m += firstLines(o.compiler_output, 12);
      }
      return m;
    } catch (const std::exception& e) {
      return std::string("the worker's reply cannot be read: ") + e.what();
    }
  }
  return std::string(toString(r.state)) + ": " + r.message;
}

// The stage a worker's progress message names ("trace", "compile", ...); empty when the
// message is not one.
std::string stageOf(const std::string& message) {
  try {
    return nlohmann::json::parse(message).value("stage", "");
  } catch (const std::exception&) {
    return {};
  }
}

}  // namespace

BuildRun::BuildRun(cache::Cache& cache, WorkerPool& pool, const CachedBuilderOptions& options,
                   std::atomic<std::uint64_t>& worker_death_retries, const CachedBuilder::Listener& listener)
    : cache_(cache),
      pool_(pool),
      options_(options),
      worker_death_retries_(worker_death_retries),
      listener_(listener),
      max_attempts_(1 + static_cast<unsigned>(options.worker_death_backoff.size())) {}

BuildRun::~BuildRun() {
  {
    std::lock_guard lock(mutex_);
    stop_renewing_ = true;
  }
  changed_.notify_all();
  if (renewer_.joinable()) renewer_.join();
}

std::vector<BuildStatus> BuildRun::execute(const std::vector<BuildTarget>& targets) {
  prepareAll(targets);
  startRenewing();
  for (;;) {
    bool all_final = true;
    for (std::size_t i = 0; i < work_.size(); ++i)
      if (advance(i)) all_final = false;
    if (all_final) break;
    waitForProgress();
  }
  std::vector<BuildStatus> out;
  out.reserve(work_.size());
  for (const Work& w : work_) out.push_back(w.status);
  return out;
}

void BuildRun::publishStatus(std::size_t i) {
  work_[i].status.seconds = std::chrono::duration<double>(Clock::now() - work_[i].started).count();
  if (listener_) listener_(i, work_[i].status);
}

void BuildRun::setState(std::size_t i, BuildState state, std::string message) {
  work_[i].status.state = state;
  if (!message.empty() || isFinal(state)) work_[i].status.message = std::move(message);
  publishStatus(i);
}

// Reads every robot and spec and computes the keys. A robot is loaded once (by path, or
// by text when given as text) however many targets name it.
void BuildRun::prepareAll(const std::vector<BuildTarget>& targets) {
  work_.resize(targets.size());
  std::map<std::tuple<std::string, bool, std::string>, Robot> robots;
  for (std::size_t i = 0; i < targets.size(); ++i) {
    const BuildTarget& t = targets[i];
    Work& w = work_[i];
    w.target = t;
    w.started = Clock::now();
    w.status.robot = t.urdf_path;
    w.status.function = t.spec_path;
    std::lock_guard lock(mutex_);
    try {
      prepare(i, t, robots[{t.urdf_path, t.floating_base, t.urdf_text}]);
      publishStatus(i);
    } catch (const std::exception& e) {
      setState(i, BuildState::Failed, e.what());
    }
  }
}

void BuildRun::prepare(std::size_t i, const BuildTarget& t, Robot& robot) {
  if (!robot.model && t.model && !t.urdf_text.empty() && !t.model_hash.empty()) {
    robot = {t.urdf_text, t.model, t.model_hash};  // parsed and hashed by the caller
  } else if (!robot.model) {
    robot.urdf = t.urdf_text.empty() ? readText(t.urdf_path, "URDF") : t.urdf_text;
    robot.model = std::make_shared<const Model>(
        loadUrdfString(robot.urdf, t.floating_base ? RootJoint::FreeFlyer : RootJoint::Fixed, t.urdf_path,
                       options_.urdf_limits));
    robot.hash = canonicalHash(*robot.model);
  }
  const std::string spec_text = t.spec_text.empty() ? readText(t.spec_path, "spec") : t.spec_text;
  const FunctionSpec spec = parseFunctionSpec(spec_text, t.spec_path);
  Work& w = work_[i];
  w.prepared = cache::prepareBuild(*robot.model, robot.hash, spec, t.function_name, options_.compiler);
  w.status.robot = w.prepared->info.robot;
  w.status.function = w.prepared->info.function;
  w.status.key = w.prepared->key;
  BuildRequest& r = w.request;
  r.urdf = robot.urdf;
  r.urdf_source = t.urdf_path;
  r.urdf_limits = options_.urdf_limits;
  r.floating_base = t.floating_base;
  r.spec = spec_text;
  r.spec_source = t.spec_path;
  r.function_name = t.function_name;
  r.compiler = options_.compiler;
  r.compiler_memory_limit_bytes = options_.compiler_memory_limit_bytes;
  r.compiler_timeout = options_.job_timeout;
  // Each build may compile as many parts at once as there are cores, even with several
  // workers: while one worker traces (one core), another's compilers use the rest
  // (docs/cache.md, "The build workers").
  r.compiler_jobs = std::max(1u, std::thread::hardware_concurrency());
  r.cache_dir = cache_.dir().string();
  r.cache_budget_bytes = cache_.options().budget_bytes;
  r.info = w.prepared->info;
}

// Renews the claims workers build under, every third of the lease, until the run ends.
void BuildRun::startRenewing() {
  renewer_ = std::thread([this] {
    const auto period = std::max<std::chrono::milliseconds>(cache_.options().lease / 3, std::chrono::milliseconds(20));
    std::unique_lock lock(mutex_);
    while (!stop_renewing_) {
      changed_.wait_for(lock, period);
      if (stop_renewing_) break;
      lock.unlock();
      renewClaims();
      lock.lock();
    }
  });
}

void BuildRun::renewClaims() {
  std::vector<cache::Claim> claims;
  {
    std::lock_guard lock(mutex_);
    for (const Work& w : work_)
      if (w.claim) claims.push_back(*w.claim);
  }
  for (const cache::Claim& c : claims) {
    try {
      cache_.renew(c);
    } catch (const std::exception& e) {
      // The worker still publishes the same content; another process may now too.
      std::cerr << "robodiff: " << e.what() << "\n";
    }
  }
}

bool BuildRun::advance(std::size_t i) {
  std::unique_lock lock(mutex_);
  Work& w = work_[i];
  if (isFinal(w.status.state)) return false;
  if (w.job) {
    if (w.job->result.wait_for(std::chrono::seconds(0)) == std::future_status::ready) {
      const JobResult result = w.job->result.get();  // a copy: finishJob drops the future
      finishJob(i, result);
    }
  } else if (w.retry_at) {
    if (Clock::now() >= *w.retry_at) retryBuild(i, lock);
  } else {
    claimAndSubmit(i, lock);
  }
  return true;
}

// Ready in the cache: Cached; another process builds it: Waiting; else claimed here and
// handed to the pool. Caller holds `lock`; it is released while the cache is asked.
void BuildRun::claimAndSubmit(std::size_t i, std::unique_lock<std::mutex>& lock) {
  Work& w = work_[i];
  lock.unlock();
  cache::ClaimResult claimed;
  try {
    claimed = cache_.claim(w.prepared->key, w.prepared->info);
  } catch (const std::exception& e) {
    lock.lock();
    setState(i, BuildState::Failed, e.what());
    return;
  }
  lock.lock();
  if (claimed.state == cache::ClaimResult::State::Ready) {
    w.status.library_bytes = claimed.artifact->entry().library_bytes;
    setState(i, BuildState::Cached);
  } else if (claimed.state == cache::ClaimResult::State::Busy) {
    if (w.status.state != BuildState::Waiting) setState(i, BuildState::Waiting, "built by " + claimed.holder);
  } else {
    w.claim = claimed.claim;
    submitBuild(i, lock);
  }
}

// The worker died (killed, crashed, out of memory): not the build's fault, so it is tried
// again under the same claim after a pause; a build that failed is not. Caller holds mutex_.
void BuildRun::finishJob(std::size_t i, const JobResult& r) {
  Work& w = work_[i];
  w.job.reset();
  if (r.state == JobState::Crashed && w.attempts < max_attempts_) {
    const std::chrono::milliseconds pause = options_.worker_death_backoff[w.attempts - 1];
    w.retry_at = Clock::now() + pause;
    worker_death_retries_.fetch_add(1, std::memory_order_relaxed);
    const std::string retry = r.message + "; trying again in " + secondsText(pause) + " (attempt " +
                              std::to_string(w.attempts + 1) + " of " + std::to_string(max_attempts_) + ")";
    std::cerr << "robodiff: building " << w.status.robot << "/" << w.status.function << ": " << retry << "\n";
    setState(i, BuildState::Queued, retry);
    return;
  }
  const cache::Claim claim = *w.claim;
  w.claim.reset();
  if (r.state == JobState::Succeeded) {
    try {
      w.status.library_bytes = buildOutcomeFromJson(r.reply).library_bytes;
    } catch (const std::exception&) {
    }
    setState(i, BuildState::Done);
    return;
  }
  cache_.abandon(claim);  // nothing of a failed build stays: no row, no staging
  std::string message = failureMessage(r);
  if (r.state == JobState::Crashed && w.attempts > 1)
    message += " (" + std::to_string(w.attempts) + " attempts; the worker died in each)";
  setState(i, BuildState::Failed, message);
}

// Hands a claimed target to the pool. Caller holds `lock`; it is released while submitting.
void BuildRun::submitBuild(std::size_t i, std::unique_lock<std::mutex>& lock) {
  Work& w = work_[i];
  w.request.claim = *w.claim;
  JobCallbacks callbacks;
  callbacks.on_start = [this, i](pid_t) {
    std::lock_guard inner(mutex_);
    if (isFinal(work_[i].status.state)) return;
    work_[i].started = Clock::now();  // from here on, seconds is the build's own time
    setState(i, BuildState::Building);
  };
  callbacks.on_progress = [this, i](const std::string& message) {
    std::string stage = stageOf(message);
    if (stage.empty()) return;
    std::lock_guard inner(mutex_);
    if (isFinal(work_[i].status.state)) return;
    work_[i].status.stage = std::move(stage);
    setState(i, BuildState::Building);
  };
  try {
    const std::string request = buildRequestMessage(toJson(w.request));
    lock.unlock();
    JobHandle handle = pool_.submit(request, callbacks, options_.job_timeout);
    lock.lock();
    w.job = handle;
    ++w.attempts;
    if (w.status.state == BuildState::Pending || w.status.state == BuildState::Waiting)
      setState(i, BuildState::Queued);
  } catch (const QueueFull&) {
    if (!lock.owns_lock()) lock.lock();
    cache_.abandon(*w.claim);  // try again on a later round
    w.claim.reset();
  } catch (const std::exception& e) {
    if (!lock.owns_lock()) lock.lock();
    cache_.abandon(*w.claim);
    w.claim.reset();
    setState(i, BuildState::Failed, e.what());
  }
}

// A target whose worker died, once its pause is over: done already if the dead worker had
// published it, else submitted again. Caller holds `lock`.
void BuildRun::retryBuild(std::size_t i, std::unique_lock<std::mutex>& lock) {
  Work& w = work_[i];
  w.retry_at.reset();
  std::optional<cache::Entry> row;
  try {
    row = cache_.entry(w.prepared->key);
  } catch (const std::exception&) {
  }
  if (row && row->state == "ready") {
    w.claim.reset();
    w.status.library_bytes = row->library_bytes;
    setState(i, BuildState::Done);
    return;
  }
  submitBuild(i, lock);
}

// Sleeps until a job finishes (checked every 10 ms, so the display never shows a finished
// job as building) or the next poll of keys other processes build.
void BuildRun::waitForProgress() {
  const auto next_poll = Clock::now() + options_.poll_interval;
  while (Clock::now() < next_poll) {
    {
      std::lock_guard lock(mutex_);
      for (const Work& w : work_)
        if (w.job && w.job->result.wait_for(std::chrono::seconds(0)) == std::future_status::ready) return;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
}

}  // namespace robodiff::workers
