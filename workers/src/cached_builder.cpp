#include "robodiff/workers/cached_builder.hpp"

#include <algorithm>
#include <atomic>
#include <condition_variable>
#include <fstream>
#include <iostream>
#include <map>
#include <mutex>
#include <optional>
#include <sstream>
#include <thread>
#include <tuple>

#include <nlohmann/json.hpp>

#include "robodiff/model/urdf_loader.hpp"
#include "robodiff/workers/build_job.hpp"
#include "robodiff/workers/worker_protocol.hpp"

namespace robodiff::workers {

const char* toString(BuildState state) {
  switch (state) {
    case BuildState::Pending: return "pending";
    case BuildState::Cached: return "cached";
    case BuildState::Waiting: return "waiting";
    case BuildState::Queued: return "queued";
    case BuildState::Building: return "building";
    case BuildState::Done: return "done";
    case BuildState::Failed: return "failed";
  }
  return "?";
}

CachedBuilder::CachedBuilder(cache::Cache& cache, WorkerPool& pool, CachedBuilderOptions options)
    : cache_(cache), pool_(pool), options_(std::move(options)) {}

namespace {

using Clock = std::chrono::steady_clock;

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

// One target on its way through the cache and the pool.
struct Work {
  BuildTarget target;
  BuildStatus status;
  Clock::time_point started;
  std::optional<PreparedBuild> prepared;
  BuildRequest request;             // all but the claim, filled when prepared
  std::optional<cache::Claim> claim;  // held by this process while a worker builds
  std::optional<JobHandle> job;
  unsigned attempts = 0;                    // jobs submitted for it
  std::optional<Clock::time_point> retry_at;  // its worker died: submit again then (claim kept)
};

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

}  // namespace

std::vector<BuildStatus> CachedBuilder::buildAll(const std::vector<BuildTarget>& targets, const Listener& listener) {
  std::mutex mutex;  // guards every Work and serialises the listener
  std::condition_variable changed;
  std::vector<Work> work(targets.size());

  auto publishStatus = [&](std::size_t i) {  // caller holds mutex
    work[i].status.seconds = std::chrono::duration<double>(Clock::now() - work[i].started).count();
    if (listener) listener(i, work[i].status);
  };
  auto setState = [&](std::size_t i, BuildState state, std::string message = {}) {  // caller holds mutex
    work[i].status.state = state;
    if (!message.empty() || isFinal(state)) work[i].status.message = std::move(message);
    publishStatus(i);
  };

  // 1. Read every robot and spec, and compute the keys. Robots are loaded once each
  // (by path, or by text when given as text).
  std::map<std::tuple<std::string, bool, std::string>, std::pair<std::string, std::shared_ptr<Model>>> robots;
  for (std::size_t i = 0; i < targets.size(); ++i) {
    Work& w = work[i];
    w.target = targets[i];
    w.started = Clock::now();
    w.status.robot = targets[i].urdf_path;
    w.status.function = targets[i].spec_path;
    std::lock_guard lock(mutex);
    try {
      auto& robot = robots[{targets[i].urdf_path, targets[i].floating_base, targets[i].urdf_text}];
      if (!robot.second) {
        robot.first = targets[i].urdf_text.empty() ? readText(targets[i].urdf_path, "URDF") : targets[i].urdf_text;
        robot.second = std::make_shared<Model>(
            loadUrdfString(robot.first, targets[i].floating_base ? RootJoint::FreeFlyer : RootJoint::Fixed,
                           targets[i].urdf_path));
      }
      const std::string spec_text =
          targets[i].spec_text.empty() ? readText(targets[i].spec_path, "spec") : targets[i].spec_text;
      const FunctionSpec spec = parseFunctionSpec(spec_text, targets[i].spec_path);
      w.prepared = prepareBuild(*robot.second, spec, targets[i].function_name, options_.compiler);
      w.status.robot = w.prepared->info.robot;
      w.status.function = w.prepared->info.function;
      w.status.key = w.prepared->key;
      BuildRequest& r = w.request;
      r.urdf = robot.first;
      r.urdf_source = targets[i].urdf_path;
      r.floating_base = targets[i].floating_base;
      r.spec = spec_text;
      r.spec_source = targets[i].spec_path;
      r.function_name = targets[i].function_name;
      r.compiler = options_.compiler;
      r.compiler_memory_limit_bytes = options_.compiler_memory_limit_bytes;
      r.compiler_timeout = options_.job_timeout;
      // Each build may compile as many parts at once as there are cores, even with several
      // workers: while one worker traces (one core), another's compilers use the rest.
      // Measured (bench/cache_bench, Panda set, 2 cores, 2 workers): cores/workers parts
      // at once 4.45 s, cores parts at once 3.74 s; 1 worker 4.0 s.
      const unsigned cores = std::max(1u, std::thread::hardware_concurrency());
      r.compiler_jobs = cores;
      r.cache_dir = cache_.dir().string();
      r.cache_budget_bytes = cache_.options().budget_bytes;
      r.info = w.prepared->info;
      publishStatus(i);
    } catch (const std::exception& e) {
      setState(i, BuildState::Failed, e.what());
    }
  }

  // 2. Lease renewal for the claims workers are building under, stopped (and joined) on
  // every way out of this function.
  std::atomic<bool> stop_renewing{false};
  struct Joiner {
    std::thread thread;
    std::mutex& mutex;
    std::atomic<bool>& stop;
    std::condition_variable& wake;
    ~Joiner() {
      {
        std::lock_guard lock(mutex);
        stop = true;
      }
      wake.notify_all();
      if (thread.joinable()) thread.join();
    }
  };
  Joiner renewer{std::thread(), mutex, stop_renewing, changed};
  renewer.thread = std::thread([&] {
    const auto period = std::max<std::chrono::milliseconds>(cache_.options().lease / 3, std::chrono::milliseconds(20));
    std::unique_lock lock(mutex);
    while (!stop_renewing) {
      changed.wait_for(lock, period);
      if (stop_renewing) break;
      std::vector<cache::Claim> claims;
      for (const Work& w : work)
        if (w.claim) claims.push_back(*w.claim);
      lock.unlock();
      for (const cache::Claim& c : claims) {
        try {
          cache_.renew(c);
        } catch (const std::exception& e) {
          // The worker still publishes the same content; another process may now too.
          std::cerr << "robodiff: " << e.what() << "\n";
        }
      }
      lock.lock();
    }
  });

  // 3. Claim, wait or hand to a worker, until every target is final.
  const unsigned max_attempts = 1 + static_cast<unsigned>(options_.worker_death_backoff.size());
  auto finishJob = [&](std::size_t i, const JobResult& r) {  // caller holds mutex
    Work& w = work[i];
    w.job.reset();
    // The worker died (killed, crashed, out of memory): not the build's fault, so it is
    // tried again under the same claim after a pause; a build that failed is not.
    if (r.state == JobState::Crashed && w.attempts < max_attempts) {
      const std::chrono::milliseconds pause = options_.worker_death_backoff[w.attempts - 1];
      w.retry_at = Clock::now() + pause;
      worker_death_retries_.fetch_add(1, std::memory_order_relaxed);
      std::cerr << "robodiff: building " << w.status.robot << "/" << w.status.function << ": " << r.message
                << "; trying again in " << secondsText(pause) << " (attempt " << w.attempts + 1 << " of "
                << max_attempts << ")\n";
      setState(i, BuildState::Queued,
               r.message + "; trying again in " + secondsText(pause) + " (attempt " + std::to_string(w.attempts + 1) +
                   " of " + std::to_string(max_attempts) + ")");
      return;
    }
    const cache::Claim claim = *w.claim;
    w.claim.reset();
    if (r.state == JobState::Succeeded) {
      try {
        const BuildOutcome o = buildOutcomeFromJson(r.reply);
        w.status.library_bytes = o.library_bytes;
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
  };

  // Hands a claimed target to the pool. Caller holds `lock` (on mutex); it is released
  // while submitting.
  auto submitBuild = [&](std::size_t i, std::unique_lock<std::mutex>& lock) {
    Work& w = work[i];
    w.request.claim = *w.claim;
    JobCallbacks callbacks;
    callbacks.on_start = [&, i](pid_t) {
      std::lock_guard inner(mutex);
      if (isFinal(work[i].status.state)) return;
      work[i].started = Clock::now();  // from here on, seconds is the build's own time
      setState(i, BuildState::Building);
    };
    callbacks.on_progress = [&, i](const std::string& message) {
      std::string stage;
      try {
        stage = nlohmann::json::parse(message).value("stage", "");
      } catch (const std::exception&) {
        return;
      }
      std::lock_guard inner(mutex);
      if (isFinal(work[i].status.state)) return;
      work[i].status.stage = stage;
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
  };

  // A target whose worker died, once its pause is over: done already if the dead worker
  // had published it, else submitted again. Caller holds `lock`.
  auto retryBuild = [&](std::size_t i, std::unique_lock<std::mutex>& lock) {
    Work& w = work[i];
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
  };

  for (;;) {
    bool all_final = true;
    for (std::size_t i = 0; i < work.size(); ++i) {
      std::unique_lock lock(mutex);
      Work& w = work[i];
      if (isFinal(w.status.state)) continue;
      all_final = false;
      if (w.job) {
        if (w.job->result.wait_for(std::chrono::seconds(0)) == std::future_status::ready) {
          const JobResult result = w.job->result.get();  // a copy: finishJob drops the future
          finishJob(i, result);
        }
        continue;
      }
      if (w.retry_at) {
        if (Clock::now() >= *w.retry_at) retryBuild(i, lock);
        continue;
      }
      lock.unlock();
      cache::ClaimResult claimed;
      try {
        claimed = cache_.claim(w.prepared->key, w.prepared->info);
      } catch (const std::exception& e) {
        lock.lock();
        setState(i, BuildState::Failed, e.what());
        continue;
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
    if (all_final) break;
    // Sleep until a job finishes (checked every 10 ms, so the display never shows a
    // finished job as building) or the next poll of keys other processes build.
    const auto next_poll = Clock::now() + options_.poll_interval;
    while (Clock::now() < next_poll) {
      bool finished = false;
      {
        std::lock_guard lock(mutex);
        for (const Work& w : work)
          if (w.job && w.job->result.wait_for(std::chrono::seconds(0)) == std::future_status::ready) finished = true;
      }
      if (finished) break;
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
  }

  std::vector<BuildStatus> out;
  out.reserve(work.size());
  for (const Work& w : work) out.push_back(w.status);
  return out;
}

}  // namespace robodiff::workers
