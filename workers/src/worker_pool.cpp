#include "robodiff/workers/worker_pool.hpp"

#include <fcntl.h>
#include <poll.h>
#include <pthread.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <deque>
#include <mutex>
#include <thread>

#include <nlohmann/json.hpp>

#include "robodiff/process/program_path.hpp"
#include "process_tree.hpp"
#include "worker_records.hpp"
#include "worker_process.hpp"
#include "robodiff/workers/worker_protocol.hpp"

namespace robodiff::workers {

namespace fs = std::filesystem;
using nlohmann::json;
using namespace pool;

struct WorkerPool::Impl {
  WorkerPoolOptions options;
  fs::path executable;

  mutable std::mutex mutex;  // everything below
  std::deque<std::shared_ptr<Job>> queue;
  std::vector<std::unique_ptr<Worker>> workers;  // alive, feeding on the queue
  std::vector<Departing> departing;
  PoolStats counters;
  bool stopping = false;
  std::string spawn_error;  // why the last worker start failed; empty: it did not
  Clock::time_point next_spawn_attempt{};
  JobId next_id = 1;

  int wake_read = -1, wake_write = -1;  // self-pipe: submit, cancel and stop wake the supervisor
  std::thread supervisor;

  // Work for outside the lock, in order: callbacks and deliveries of results.
  std::vector<std::function<void()>> deferred;

  void wake() const {
    const char byte = 1;
    ssize_t n;
    do n = ::write(wake_write, &byte, 1);
    while (n < 0 && errno == EINTR);  // EAGAIN: a wake-up is pending already
  }

  void drainWake() const {
    char buffer[256];
    while (::read(wake_read, buffer, sizeof buffer) > 0) {
    }
  }

  // --- starting workers (on the supervisor thread only: PR_SET_PDEATHSIG follows the
  // thread that forked, and that thread lives as long as the pool) ---

  std::unique_ptr<Worker> spawnWorker() {
    const WorkerProcess process = startWorkerProcess(executable);
    setNonBlocking(process.to_worker);
    setNonBlocking(process.from_worker);
    auto worker = std::make_unique<Worker>();
    worker->pid = process.pid;
    worker->to_worker = process.to_worker;
    worker->from_worker = process.from_worker;
    worker->started = Clock::now();
    ++counters.workers_started;
    return worker;
  }

  // Starts workers until there are options.workers. When none can be started and none
  // runs, queued jobs fail at once rather than wait for ever.
  void replaceWorkers(Clock::time_point now) {
    if (stopping || now < next_spawn_attempt) return;
    // A worker that left by itself right after its start: how it ended decides whether
    // the next start waits (reapDeparting), so none starts before it is reaped.
    if (std::any_of(departing.begin(), departing.end(), [](const Departing& d) { return d.young; })) return;
    while (workers.size() < options.workers) {
      try {
        workers.push_back(spawnWorker());
        spawn_error.clear();
      } catch (const std::exception& e) {
        spawn_error = e.what();
        next_spawn_attempt = now + kSpawnRetry;
        std::fprintf(stderr, "robodiff: worker pool: %s (retrying in 1 s)\n", e.what());
        break;
      }
    }
    if (workers.empty() && !spawn_error.empty()) {
      while (!queue.empty()) {
        auto job = queue.front();
        queue.pop_front();
        finish(job, JobState::Crashed, {}, "no worker is running: " + spawn_error);
      }
    }
  }

  // --- results ---

  // Decides a job's result; it is delivered (the future set) after the callbacks that
  // came before it.
  void finish(const std::shared_ptr<Job>& job, JobState state, std::string reply, std::string message) {
    if (job->finished) return;
    deferred.push_back(decide(job, state, std::move(reply), std::move(message)));
  }

  // Marks a job finished, counts it, and returns what delivers its result.
  std::function<void()> decide(const std::shared_ptr<Job>& job, JobState state, std::string reply,
                               std::string message) {
    job->finished = true;
    const auto now = Clock::now();
    JobResult result;
    result.state = state;
    result.reply = std::move(reply);
    result.message = std::move(message);
    result.worker_pid = job->worker_pid;
    const bool ran = job->worker_pid != 0;
    result.queued_seconds = secondsBetween(job->submitted, ran ? job->started : now);
    result.run_seconds = ran ? secondsBetween(job->started, now) : 0.0;
    switch (state) {
      case JobState::Succeeded: ++counters.succeeded; break;
      case JobState::Failed: ++counters.failed; break;
      case JobState::Crashed: ++counters.crashed; break;
      case JobState::TimedOut: ++counters.timed_out; break;
      case JobState::Cancelled: ++counters.cancelled; break;
      default: break;
    }
    return [job, result = std::move(result)]() mutable { job->promise.set_value(std::move(result)); };
  }

  // --- workers leaving ---

  // Takes a worker out of service. `job_state` set: it was killed on purpose and its job
  // (if any) ends so now; unset: it died by itself, and its job ends as Crashed once the
  // exit status is known.
  void retire(std::size_t index, std::optional<JobState> job_state, const std::string& message) {
    std::unique_ptr<Worker> worker = std::move(workers[index]);
    workers.erase(workers.begin() + static_cast<std::ptrdiff_t>(index));
    closeFd(worker->to_worker);
    closeFd(worker->from_worker);
    const auto now = Clock::now();
    Departing d;
    d.pid = worker->pid;
    if (job_state) {
      detail::killProcessTree(worker->pid);
      d.killed = true;
      d.kill_at = now;
      d.give_up_at = now + kKillGrace;
      if (worker->job) finish(worker->job, *job_state, {}, message);
    } else {
      d.job = worker->job;
      d.young = now - worker->started < kSpawnRetry;
      d.kill_at = now + kExitGrace;
      d.give_up_at = d.kill_at + kKillGrace;
    }
    departing.push_back(std::move(d));
  }

  // Reaps departed workers without blocking; kills those that linger.
  void reapDeparting(Clock::time_point now) {
    for (std::size_t i = 0; i < departing.size();) {
      Departing& d = departing[i];
      siginfo_t info{};
      int got;
      do got = ::waitid(P_PID, static_cast<id_t>(d.pid), &info, WEXITED | WNOHANG | WNOWAIT);
      while (got < 0 && errno == EINTR);
      std::optional<std::string> outcome;
      if (got == 0 && info.si_pid == d.pid) {
        // Exited, not reaped: its pid and session still stand for it, so whatever it
        // left running (orphaned compilers) is swept before the pid is given back.
        detail::killProcessTree(d.pid);
        int status = 0;
        while (::waitpid(d.pid, &status, 0) < 0 && errno == EINTR) {
        }
        outcome = describeWorkerExit(d.pid, status);
        if (d.young && WIFEXITED(status) && !stopping) {
          std::fprintf(stderr,
                       "robodiff: worker pool: worker %d (%s) exited with status %d right after it started; "
                       "starting another in 1 s\n",
                       static_cast<int>(d.pid), executable.c_str(), WEXITSTATUS(status));
          next_spawn_attempt = now + kSpawnRetry;
        }
      } else if (got < 0) {  // ECHILD: someone else reaped it (SIGCHLD ignored?)
        outcome = "worker " + std::to_string(d.pid) + " ended during the job (its exit status is not available)";
      } else if (!d.killed && now >= d.kill_at) {
        detail::killProcessTree(d.pid);
        d.killed = true;
        d.give_up_at = now + kKillGrace;
      } else if (d.killed && now >= d.give_up_at) {
        std::fprintf(stderr, "robodiff: worker pool: worker %d did not exit after SIGKILL\n", static_cast<int>(d.pid));
        outcome = "worker " + std::to_string(d.pid) + " stopped answering during the job and did not exit after SIGKILL";
      }
      if (!outcome) {
        ++i;
        continue;
      }
      if (d.job) finish(d.job, JobState::Crashed, {}, *outcome);
      departing.erase(departing.begin() + static_cast<std::ptrdiff_t>(i));
    }
  }

  // --- jobs to workers ---

  void checkRunningJobs(Clock::time_point now) {
    for (std::size_t i = 0; i < workers.size();) {
      Worker& w = *workers[i];
      if (w.job && w.job->cancel_requested) {
        retire(i, JobState::Cancelled,
               "cancelled while running on worker " + std::to_string(w.pid) + "; the worker and its processes were killed");
      } else if (w.job && now >= w.deadline) {
        retire(i, JobState::TimedOut,
               "timed out: the limit is " + describeDuration(w.job->timeout) + "; worker " + std::to_string(w.pid) +
                   " and every process it started were killed");
      } else {
        ++i;
      }
    }
  }

  void dispatch(Clock::time_point now) {
    while (!queue.empty()) {
      // The idle worker that has done the least, so work spreads over the pool.
      Worker* idle = nullptr;
      for (auto& w : workers)
        if (!w->job && (!idle || w->jobs_done < idle->jobs_done)) idle = w.get();
      if (!idle) return;
      std::shared_ptr<Job> job = queue.front();
      queue.pop_front();
      job->started = now;
      job->worker_pid = idle->pid;
      idle->job = job;
      idle->deadline = job->timeout.count() > 0 ? now + job->timeout : Clock::time_point::max();
      idle->unsent = job->frame;
      if (job->callbacks.on_start)
        deferred.push_back([on_start = job->callbacks.on_start, pid = idle->pid] { on_start(pid); });
    }
  }

  // Writes what the workers can take now. A worker whose stdin is gone is retired.
  void flushRequests() {
    for (std::size_t i = 0; i < workers.size();) {
      Worker& w = *workers[i];
      bool broken = false;
      while (!w.unsent.empty()) {
        const ssize_t n = ::write(w.to_worker, w.unsent.data(), w.unsent.size());
        if (n > 0) {
          w.unsent.erase(0, static_cast<std::size_t>(n));
        } else if (n < 0 && errno == EINTR) {
          continue;
        } else {
          const int error = n < 0 ? errno : EIO;
          if (error == EPIPE) consumePendingSigpipe();
          broken = error != EAGAIN && error != EWOULDBLOCK;  // full: POLLOUT tells when to go on
          break;
        }
      }
      if (broken) {
        w.unsent.clear();
        retire(i, std::nullopt, {});
      } else {
        ++i;
      }
    }
  }

  // --- replies ---

  // Reads what a worker wrote. Returns false when the worker was retired.
  bool readReplies(std::size_t index) {
    Worker& w = *workers[index];
    char buffer[65536];
    bool eof = false;
    while (true) {
      const ssize_t n = ::read(w.from_worker, buffer, sizeof buffer);
      if (n > 0) {
        w.decoder.append(buffer, static_cast<std::size_t>(n));
        continue;
      }
      if (n < 0 && errno == EINTR) continue;
      eof = n == 0 || (errno != EAGAIN && errno != EWOULDBLOCK);
      break;
    }
    try {
      while (auto frame = w.decoder.next()) {
        if (!handleMessage(w, *frame)) {
          retire(index, JobState::Crashed,
                 "worker " + std::to_string(w.pid) + " broke the protocol: unexpected message " + frame->substr(0, 200));
          return false;
        }
      }
    } catch (const ProtocolError& e) {
      retire(index, JobState::Crashed, "worker " + std::to_string(w.pid) + " broke the protocol: " + e.what());
      return false;
    }
    if (eof) {
      retire(index, std::nullopt, {});
      return false;
    }
    return true;
  }

  // One message from a worker; false when it makes no sense (then the worker goes).
  bool handleMessage(Worker& w, const std::string& text) {
    json message = json::parse(text, nullptr, false);
    if (!message.is_object() || !w.job) return false;
    const auto id = message.find("id");
    const auto type = message.find("type");
    if (id == message.end() || !id->is_number_unsigned() || id->get<JobId>() != w.job->id) return false;
    if (type == message.end() || !type->is_string()) return false;
    if (*type == "progress") {
      if (w.job->callbacks.on_progress)
        deferred.push_back([on_progress = w.job->callbacks.on_progress, text] { on_progress(text); });
      return true;
    }
    if (*type != "result") return false;
    const auto ok = message.find("ok");
    if (ok == message.end() || !ok->is_boolean()) return false;
    std::shared_ptr<Job> job = std::move(w.job);
    ++w.jobs_done;
    if (job->cancel_requested) {
      finish(job, JobState::Cancelled, text, "cancelled; the worker had finished the job");
    } else if (ok->get<bool>()) {
      finish(job, JobState::Succeeded, text, {});
    } else {
      const auto why = message.find("message");
      finish(job, JobState::Failed, text,
             why != message.end() && why->is_string() ? why->get<std::string>() : "the worker reported a failure");
    }
    return true;
  }

  // --- the supervisor ---

  // How long poll may sleep: until the next deadline, at most 1 s.
  int pollTimeoutMs(Clock::time_point now) const {
    Clock::time_point next = now + std::chrono::seconds(1);
    for (const auto& w : workers)
      if (w->job) next = std::min(next, w->deadline);
    for (const Departing& d : departing)  // exits are seen by waitpid only: look often
      next = std::min({next, now + std::chrono::milliseconds(5), d.killed ? d.give_up_at : d.kill_at});
    if (workers.size() < options.workers && next_spawn_attempt > now) next = std::min(next, next_spawn_attempt);
    const auto ms = std::chrono::ceil<std::chrono::milliseconds>(next - now).count();
    return static_cast<int>(std::clamp<long long>(ms, 0, 1000));
  }

  void runDeferred(std::unique_lock<std::mutex>& lock) {
    if (deferred.empty()) return;
    std::vector<std::function<void()>> calls;
    calls.swap(deferred);
    lock.unlock();
    for (auto& call : calls) {
      try {
        call();
      } catch (const std::exception& e) {
        std::fprintf(stderr, "robodiff: worker pool: a job callback threw: %s\n", e.what());
      } catch (...) {
        std::fprintf(stderr, "robodiff: worker pool: a job callback threw\n");
      }
    }
    lock.lock();
  }

  void supervise(std::promise<void>& started) {
    // A write to a worker that died raises SIGPIPE in the writing thread: blocked here
    // (and taken off after EPIPE), so the pool's process is not killed by it and the
    // rest of the process keeps its own SIGPIPE handling.
    sigset_t pipe_only;
    sigemptyset(&pipe_only);
    sigaddset(&pipe_only, SIGPIPE);
    pthread_sigmask(SIG_BLOCK, &pipe_only, nullptr);

    std::unique_lock lock(mutex);
    try {
      while (workers.size() < options.workers) workers.push_back(spawnWorker());
    } catch (...) {
      stopAll(lock);
      started.set_exception(std::current_exception());
      return;
    }
    started.set_value();

    std::vector<pollfd> fds;
    std::vector<pid_t> polled;  // the worker behind each fds entry (after the wake pipe)
    while (!stopping) {
      auto now = Clock::now();
      reapDeparting(now);
      replaceWorkers(now);
      checkRunningJobs(now);
      dispatch(now);
      runDeferred(lock);  // on_start before the worker can see the request, results in order
      if (stopping) break;
      flushRequests();
      runDeferred(lock);

      fds.assign(1, pollfd{wake_read, POLLIN, 0});
      polled.clear();
      for (const auto& w : workers) {
        fds.push_back({w->from_worker, POLLIN, 0});
        polled.push_back(w->pid);
        if (!w->unsent.empty()) {
          fds.push_back({w->to_worker, POLLOUT, 0});
          polled.push_back(w->pid);
        }
      }
      const int timeout_ms = pollTimeoutMs(Clock::now());
      lock.unlock();
      ::poll(fds.data(), fds.size(), timeout_ms);
      lock.lock();

      if (fds[0].revents) drainWake();
      for (std::size_t k = 1; k < fds.size(); ++k) {
        if (!fds[k].revents || fds[k].events != POLLIN) continue;  // POLLOUT: flushRequests next round
        const pid_t pid = polled[k - 1];
        const auto it = std::find_if(workers.begin(), workers.end(), [&](const auto& w) { return w->pid == pid; });
        if (it != workers.end()) readReplies(static_cast<std::size_t>(it - workers.begin()));
      }
    }
    stopAll(lock);
  }

  // The pool stops: queued jobs and running ones are cancelled, idle workers leave on
  // end of input, then SIGTERM, then SIGKILL (their trees); every worker is reaped.
  void stopAll(std::unique_lock<std::mutex>& lock) {
    while (!queue.empty()) {
      auto job = queue.front();
      queue.pop_front();
      finish(job, JobState::Cancelled, {}, "the pool stopped before the job ran");
    }
    for (std::size_t i = workers.size(); i-- > 0;) {
      if (workers[i]->job)
        retire(i, JobState::Cancelled,
               "the pool stopped while the job ran on worker " + std::to_string(workers[i]->pid) +
                   "; the worker and its processes were killed");
    }
    const auto term_at = Clock::now() + kEofGrace;
    const auto kill_at = term_at + kExitGrace;
    // Idle workers: end of input asks them to leave.
    while (!workers.empty()) retire(workers.size() - 1, std::nullopt, {});
    for (Departing& d : departing) d.kill_at = std::min(d.kill_at, kill_at);

    bool terminated = false;
    while (!departing.empty()) {
      const auto now = Clock::now();
      if (!terminated && now >= term_at) {
        for (const Departing& d : departing)
          if (!d.killed) ::killpg(d.pid, SIGTERM);
        terminated = true;
      }
      reapDeparting(now);
      if (departing.empty()) break;
      lock.unlock();
      ::poll(nullptr, 0, 5);  // exits cannot be polled for without pidfds: look every 5 ms
      lock.lock();
    }
    runDeferred(lock);
  }
};

WorkerPool::WorkerPool(WorkerPoolOptions options) : impl_(std::make_unique<Impl>()) {
  if (options.workers == 0) throw std::invalid_argument("WorkerPool: workers must be at least 1");
  impl_->executable = options.worker_executable.empty() ? defaultWorkerExecutable() : options.worker_executable;
  if (impl_->executable.empty())
    throw std::runtime_error("cannot find robodiff-worker: it is neither beside the running program, nor in "
                             ROBODIFF_WORKER_FROM_BINDIR " from it, nor in PATH");
  if (!process::isExecutableFile(impl_->executable))
    throw std::runtime_error("the worker program " + impl_->executable.string() + " is not an executable file");
  impl_->options = std::move(options);

  int wake[2];
  if (::pipe2(wake, O_CLOEXEC | O_NONBLOCK) != 0)
    throw std::runtime_error(std::string("WorkerPool: pipe: ") + std::strerror(errno));
  impl_->wake_read = wake[0];
  impl_->wake_write = wake[1];

  // Shared with the thread: the promise must outlive its set_value call.
  auto started = std::make_shared<std::promise<void>>();
  std::future<void> ready = started->get_future();
  try {
    impl_->supervisor = std::thread([this, started] { impl_->supervise(*started); });
    ready.get();  // the workers started, or why not
  } catch (...) {
    if (impl_->supervisor.joinable()) impl_->supervisor.join();
    ::close(impl_->wake_read);
    ::close(impl_->wake_write);
    throw;
  }
}

WorkerPool::~WorkerPool() {
  {
    std::lock_guard lock(impl_->mutex);
    impl_->stopping = true;
  }
  impl_->wake();
  impl_->supervisor.join();
  ::close(impl_->wake_read);
  ::close(impl_->wake_write);
}

JobHandle WorkerPool::submit(std::string request_json, JobCallbacks callbacks,
                             std::optional<std::chrono::milliseconds> timeout) {
  json request = json::parse(request_json, nullptr, false);
  if (!request.is_object() || !request.contains("type") || !request["type"].is_string())
    throw std::invalid_argument("WorkerPool::submit: a request is a JSON object with a \"type\" string, not: " +
                                request_json.substr(0, 200));
  auto job = std::make_shared<Job>();
  job->callbacks = std::move(callbacks);
  job->timeout = timeout.value_or(impl_->options.default_timeout);
  JobHandle handle;
  handle.result = job->promise.get_future().share();

  std::lock_guard lock(impl_->mutex);
  if (impl_->stopping) throw std::runtime_error("WorkerPool::submit: the pool is stopping");
  // Jobs about to go to an idle worker are not waiting.
  std::size_t idle = 0;
  for (const auto& w : impl_->workers) idle += w->job ? 0 : 1;
  if (impl_->queue.size() >= impl_->options.queue_capacity + idle)
    throw QueueFull("the job queue is full: " + std::to_string(impl_->queue.size()) + " jobs wait (queue_capacity " +
                    std::to_string(impl_->options.queue_capacity) + ")");
  job->id = impl_->next_id++;
  request["id"] = job->id;
  if (impl_->options.memory_limit_bytes > 0 && !request.contains("limits"))
    request["limits"] = {{"memory_bytes", impl_->options.memory_limit_bytes}};
  job->frame = encodeFrame(request.dump());
  job->submitted = Clock::now();
  handle.id = job->id;
  impl_->queue.push_back(std::move(job));
  impl_->wake();
  return handle;
}

bool WorkerPool::cancel(JobId id) {
  std::lock_guard lock(impl_->mutex);
  auto& queue = impl_->queue;
  const auto queued = std::find_if(queue.begin(), queue.end(), [&](const auto& job) { return job->id == id; });
  if (queued != queue.end()) {
    std::shared_ptr<Job> job = *queued;
    queue.erase(queued);
    // Nothing of it is pending on the supervisor: delivered at once.
    impl_->decide(job, JobState::Cancelled, {}, "cancelled before it ran")();
    return true;
  }
  for (const auto& w : impl_->workers) {
    if (w->job && w->job->id == id && !w->job->cancel_requested) {
      w->job->cancel_requested = true;
      impl_->wake();
      return true;
    }
  }
  return false;
}

std::vector<WorkerInfo> WorkerPool::workers() const {
  std::lock_guard lock(impl_->mutex);
  std::vector<WorkerInfo> result;
  for (const auto& w : impl_->workers) {
    WorkerInfo info;
    info.pid = w->pid;
    if (w->job) info.job = w->job->id;
    info.jobs_done = w->jobs_done;
    result.push_back(info);
  }
  return result;
}

PoolStats WorkerPool::stats() const {
  std::lock_guard lock(impl_->mutex);
  PoolStats s = impl_->counters;
  s.queued = impl_->queue.size();
  s.running = 0;
  for (const auto& w : impl_->workers) s.running += w->job ? 1 : 0;
  return s;
}

const WorkerPoolOptions& WorkerPool::options() const { return impl_->options; }

}  // namespace robodiff::workers
