// The pool with real robodiff-worker processes: jobs spread over workers, the queue's
// bound, timeouts, workers killed mid-job, cancellation, and a clean shutdown. Builds
// that must last use a compiler script that sleeps (tests/workers/worker_fixtures.hpp).
#include <signal.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <future>
#include <set>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "robodiff/workers/worker_pool.hpp"
#include "robodiff/workers/worker_protocol.hpp"
#include "support/process.hpp"
#include "worker_fixtures.hpp"

namespace robodiff::workers {
namespace {

using namespace std::chrono_literals;
using nlohmann::json;
using testing::TempDir;

WorkerPoolOptions workerPoolOptions(unsigned workers, std::size_t queue_capacity = 16) {
  WorkerPoolOptions o;
  o.worker_executable = testing::workerPath();
  o.workers = workers;
  o.queue_capacity = queue_capacity;
  o.default_timeout = 60s;
  return o;
}

// The job's result, or nullopt when it has not come within `timeout` (never blocks for ever).
std::optional<JobResult> resultOf(const JobHandle& handle, std::chrono::seconds timeout = 30s) {
  if (handle.result.wait_for(timeout) != std::future_status::ready) return std::nullopt;
  return handle.result.get();
}

bool textContains(const std::string& text, const std::string& part) { return text.find(part) != std::string::npos; }

// A build whose compiler sleeps for 30 s, claimed in a cache of its own.
struct SleepingBuild {
  TempDir dir;
  std::filesystem::path compiler = testing::sleepingCompiler(dir);
  cache::Cache cache = cache::Cache::open(dir / "cache");
  testing::ClaimedBuild build = testing::claimBuild(cache, testing::arm7Urdf(), testing::kRneaValueSpec, compiler.string());

  std::string message() const { return buildRequestMessage(toJson(build.request)); }
  std::optional<pid_t> compilerPid() const { return testing::pidFromFile(dir / "compiler.pid"); }
  std::optional<pid_t> sleepPid() const { return testing::pidFromFile(dir / "sleep.pid"); }
  bool compilerStarted() const { return compilerPid() && sleepPid(); }
  // The compiler and its child are gone (the pid files were written, so they did run).
  void expectCompilerGone() const {
    ASSERT_TRUE(compilerStarted()) << "the compiler never started";
    EXPECT_TRUE(testing::waitFor([&] { return testing::processIsDead(*compilerPid()); }, 5s))
        << "the compiler " << *compilerPid() << " outlived its worker";
    EXPECT_TRUE(testing::waitFor([&] { return testing::processIsDead(*sleepPid()); }, 5s))
        << "the compiler's child " << *sleepPid() << " outlived its worker";
  }
};

// A ping on the pool succeeds; returns the pid of the worker that answered.
pid_t expectPing(WorkerPool& pool) {
  const auto r = resultOf(pool.submit(pingRequest()));
  EXPECT_TRUE(r.has_value()) << "no answer to a ping within 30 s";
  if (!r) return 0;
  EXPECT_EQ(r->state, JobState::Succeeded) << r->message;
  EXPECT_EQ(json::parse(r->reply).at("pid").get<pid_t>(), r->worker_pid);
  return r->worker_pid;
}

TEST(WorkerProgram, SaysWhatItIsAndLeavesAtEndOfInput) {
  const std::string worker = testing::shellQuote(testing::workerPath().string());
  const testing::ProcessResult help = testing::runCommand(worker + " --help");
  EXPECT_EQ(help.exit_code, 0);
  EXPECT_TRUE(textContains(help.out, "started by the pool")) << help.out;
  const testing::ProcessResult wrong = testing::runCommand(worker + " --frobnicate");
  EXPECT_EQ(wrong.exit_code, 2);
  EXPECT_TRUE(textContains(wrong.err, "unknown argument '--frobnicate'")) << wrong.err;
  const testing::ProcessResult idle = testing::runCommand(worker);  // stdin: /dev/null
  EXPECT_EQ(idle.exit_code, 0) << idle.err;
  EXPECT_EQ(idle.out, "");
}

TEST(WorkerPool, AWorkerProgramThatCannotRunIsAClearError) {
  TempDir dir;
  WorkerPoolOptions options = workerPoolOptions(1);
  options.worker_executable = "/nonexistent/robodiff-worker";
  try {
    WorkerPool pool(options);
    FAIL() << "a pool started without its worker program";
  } catch (const std::runtime_error& e) {
    EXPECT_TRUE(textContains(e.what(), "/nonexistent/robodiff-worker is not an executable file")) << e.what();
  }
  options.worker_executable = dir.file("not-executable", "#!/bin/sh\n");
  EXPECT_THROW(WorkerPool{options}, std::runtime_error);
  options = workerPoolOptions(0);
  EXPECT_THROW(WorkerPool{options}, std::invalid_argument);
}

TEST(WorkerPool, AWorkerThatExitsAtOnceCrashesJobsButIsNotRestartedInATightLoop) {
  TempDir dir;
  WorkerPoolOptions options = workerPoolOptions(1);
  options.worker_executable = dir.script("broken-worker", "exit 3\n");
  WorkerPool pool(options);
  const auto r = resultOf(pool.submit(pingRequest()));
  ASSERT_TRUE(r.has_value());
  EXPECT_EQ(r->state, JobState::Crashed);
  EXPECT_TRUE(textContains(r->message, "exited with status 3 during the job")) << r->message;
  // Observing a rate over a window: restarts are at least 1 s apart.
  std::this_thread::sleep_for(1500ms);
  EXPECT_LE(pool.stats().workers_started, 4u);
}

TEST(WorkerPool, PingsSpreadOverTwoWorkers) {
  WorkerPool pool(workerPoolOptions(2));
  std::set<pid_t> started;
  for (const WorkerInfo& w : pool.workers()) started.insert(w.pid);
  ASSERT_EQ(started.size(), 2u);

  std::vector<JobHandle> handles;
  for (int i = 0; i < 8; ++i) handles.push_back(pool.submit(pingRequest()));
  std::set<pid_t> answered;
  for (const JobHandle& h : handles) {
    const auto r = resultOf(h);
    ASSERT_TRUE(r.has_value()) << "ping " << h.id << " got no answer";
    EXPECT_EQ(r->state, JobState::Succeeded) << r->message;
    const json reply = json::parse(r->reply);
    EXPECT_EQ(reply.at("id").get<JobId>(), h.id);
    EXPECT_EQ(reply.at("pid").get<pid_t>(), r->worker_pid);
    answered.insert(r->worker_pid);
  }
  EXPECT_EQ(answered, started) << "the jobs did not go to both workers";
  const PoolStats stats = pool.stats();
  EXPECT_EQ(stats.succeeded, 8u);
  EXPECT_EQ(stats.workers_started, 2u);
  EXPECT_EQ(stats.queued + stats.running, 0u);
}

TEST(WorkerPool, UnknownRequestsFailAndBadOnesAreRefused) {
  WorkerPool pool(workerPoolOptions(1));
  const auto r = resultOf(pool.submit(R"({"type": "frobnicate"})"));
  ASSERT_TRUE(r.has_value());
  EXPECT_EQ(r->state, JobState::Failed);
  EXPECT_TRUE(textContains(r->message, "unknown request type \"frobnicate\"")) << r->message;
  EXPECT_THROW(pool.submit("not json"), std::invalid_argument);
  EXPECT_THROW(pool.submit(R"({"no": "type"})"), std::invalid_argument);
  expectPing(pool);  // the worker is still there
  EXPECT_EQ(pool.stats().workers_started, 1u);
}

TEST(WorkerPool, ABuildThroughAWorkerIsPublished) {
  WorkerPool pool(workerPoolOptions(1));
  TempDir dir;
  cache::Cache cache = cache::Cache::open(dir / "cache");
  const testing::ClaimedBuild b = testing::claimBuild(cache, testing::arm7Urdf(), testing::kRneaValueSpec);
  std::vector<std::string> stages;  // written on the pool's thread before the result is set
  JobCallbacks callbacks;
  callbacks.on_progress = [&](const std::string& message) { stages.push_back(json::parse(message).at("stage")); };
  const auto r = resultOf(pool.submit(buildRequestMessage(toJson(b.request)), callbacks), 120s);
  ASSERT_TRUE(r.has_value()) << "no result within 120 s";
  ASSERT_EQ(r->state, JobState::Succeeded) << r->message << "\n" << r->reply;
  const BuildOutcome outcome = buildOutcomeFromJson(r->reply);
  EXPECT_TRUE(outcome.ok);
  EXPECT_EQ(outcome.key, b.prepared.key);
  EXPECT_EQ(stages, (std::vector<std::string>{"model", "trace", "compile", "publish"}));
  EXPECT_TRUE(cache.find(b.prepared.key).has_value()) << "the worker's build is not in the cache";
}

TEST(WorkerPool, AFailedBuildIsReportedAndTheWorkerGoesOn) {
  WorkerPool pool(workerPoolOptions(1));
  BuildRequest request;
  request.urdf = "<robot name='broken'><link name='a'/><joint name='j' type='revolute'><parent link='a'/></joint>";
  request.urdf_source = "broken.urdf";
  request.spec = testing::kRneaValueSpec;
  request.cache_dir = "/nonexistent";
  request.claim = {std::string(64, '0'), "test"};
  const auto r = resultOf(pool.submit(buildRequestMessage(toJson(request))));
  ASSERT_TRUE(r.has_value());
  EXPECT_EQ(r->state, JobState::Failed);
  const BuildOutcome outcome = buildOutcomeFromJson(r->reply);
  EXPECT_EQ(outcome.error_kind, "invalid_urdf") << outcome.message;
  EXPECT_EQ(r->message, outcome.message);
  EXPECT_TRUE(textContains(r->message, "broken.urdf")) << r->message;
  EXPECT_EQ(expectPing(pool), r->worker_pid) << "the worker did not survive a failed build";

  const auto bad = resultOf(pool.submit(R"({"type": "build", "request": {"urdf": 1}})"));
  ASSERT_TRUE(bad.has_value());
  EXPECT_EQ(bad->state, JobState::Failed);
  EXPECT_TRUE(textContains(bad->message, "field \"urdf\" must be a string")) << bad->message;
}

// What a ping says about the address-space limit it ran under.
std::uint64_t pingLimit(WorkerPool& pool, std::optional<std::uint64_t> job_limit, pid_t* worker = nullptr) {
  json request = json::parse(pingRequest());
  if (job_limit) request["limits"] = {{"memory_bytes", *job_limit}};
  const auto r = resultOf(pool.submit(request.dump()));
  if (!r || r->state != JobState::Succeeded) throw std::runtime_error("a ping failed");
  if (worker) *worker = r->worker_pid;
  return json::parse(r->reply).at("address_space_limit_bytes").get<std::uint64_t>();
}

TEST(WorkerPool, EachJobRunsUnderItsMemoryLimitWhichIsLiftedAfterIt) {
  WorkerPoolOptions options = workerPoolOptions(1);
  options.memory_limit_bytes = std::uint64_t{3} << 30;
  WorkerPool pool(options);
  pid_t first = 0, second = 0, third = 0;
  EXPECT_EQ(pingLimit(pool, std::nullopt, &first), std::uint64_t{3} << 30) << "the pool's limit";
  EXPECT_EQ(pingLimit(pool, std::uint64_t{123} << 20, &second), std::uint64_t{123} << 20) << "the job's own limit";
  EXPECT_EQ(pingLimit(pool, std::nullopt, &third), std::uint64_t{3} << 30) << "the job's limit stayed";
  EXPECT_EQ(first, second);
  EXPECT_EQ(second, third);

  struct rlimit own {};
  ASSERT_EQ(::getrlimit(RLIMIT_AS, &own), 0);
  const std::uint64_t unlimited = own.rlim_cur == RLIM_INFINITY ? 0 : own.rlim_cur;
  EXPECT_EQ(pingLimit(pool, std::uint64_t{0}), unlimited) << "limit 0: the worker's own";
}

TEST(WorkerPool, ABuildOverItsMemoryLimitFailsAndTheWorkerGoesOn) {
  WorkerPool pool(workerPoolOptions(1));
  TempDir dir;
  cache::Cache cache = cache::Cache::open(dir / "cache");
  // The humanoid's RNEA Hessian traces a graph of well over 32 MiB; an idle worker maps ~32 MiB (it links
  // Ipopt, MUMPS and LAPACK for batch jobs), so 48 MiB leaves the build ~16.
  json hessian = json::parse(testing::readFile(testing::sourceDir() / "examples/specs/rnea_hessian.json"));
  hessian["build"] = {{"optimization", "O0"}, {"march_native", false}};
  const testing::ClaimedBuild big = testing::claimBuild(
      cache, testing::readFile(testing::sourceDir() / "examples/robots/humanoid.urdf"), hessian.dump());
  json starved = json::parse(buildRequestMessage(toJson(big.request)));
  starved["limits"] = {{"memory_bytes", std::uint64_t{48} << 20}};
  const auto r = resultOf(pool.submit(starved.dump()), 60s);
  ASSERT_TRUE(r.has_value());
  EXPECT_EQ(r->state, JobState::Failed) << r->message;
  EXPECT_TRUE(textContains(r->message, "out of memory")) << r->message;
  EXPECT_FALSE(cache.find(big.prepared.key).has_value());
  cache.abandon(big.request.claim);
  testing::expectNothingLeft(cache, big.prepared.key);

  // The same worker, under the pool's limit again, goes on building.
  const testing::ClaimedBuild small = testing::claimBuild(cache, testing::arm7Urdf(), testing::kRneaValueSpec);
  const auto again = resultOf(pool.submit(buildRequestMessage(toJson(small.request))), 120s);
  ASSERT_TRUE(again.has_value());
  EXPECT_EQ(again->state, JobState::Succeeded) << again->message << "\n" << again->reply;
  EXPECT_EQ(again->worker_pid, r->worker_pid) << "the worker did not survive its starved job";
}

TEST(WorkerPool, TheQueueIsBounded) {
  WorkerPool pool(workerPoolOptions(1, 2));
  SleepingBuild busy;
  std::promise<void> started;
  JobCallbacks callbacks;
  callbacks.on_start = [&](pid_t) { started.set_value(); };
  const JobHandle running = pool.submit(busy.message(), callbacks);
  ASSERT_EQ(started.get_future().wait_for(30s), std::future_status::ready);

  const JobHandle first = pool.submit(pingRequest());
  const JobHandle second = pool.submit(pingRequest());
  try {
    pool.submit(pingRequest());
    FAIL() << "a third job was queued behind a busy worker with queue_capacity 2";
  } catch (const QueueFull& e) {
    EXPECT_TRUE(textContains(e.what(), "queue_capacity 2")) << e.what();
  }
  EXPECT_EQ(pool.stats().queued, 2u);
  EXPECT_EQ(pool.stats().running, 1u);

  ASSERT_TRUE(pool.cancel(running.id));
  for (const JobHandle* h : {&first, &second}) {
    const auto r = resultOf(*h);
    ASSERT_TRUE(r.has_value());
    EXPECT_EQ(r->state, JobState::Succeeded) << r->message;
  }
  busy.cache.abandon(busy.build.request.claim);
}

TEST(WorkerPool, ATimeoutKillsTheWorkerAndTheCompilerItStarted) {
  WorkerPool pool(workerPoolOptions(1));
  const pid_t first_worker = pool.workers().at(0).pid;
  SleepingBuild build;
  const auto r = resultOf(pool.submit(build.message(), {}, 3s));
  ASSERT_TRUE(r.has_value());
  EXPECT_EQ(r->state, JobState::TimedOut) << r->message;
  EXPECT_TRUE(textContains(r->message, "the limit is 3 s")) << r->message;
  EXPECT_TRUE(textContains(r->message, "worker " + std::to_string(first_worker))) << r->message;
  EXPECT_LT(r->run_seconds, 10.0);
  build.expectCompilerGone();
  EXPECT_TRUE(testing::waitFor([&] { return testing::processIsDead(first_worker); }, 5s));

  build.cache.abandon(build.build.request.claim);  // what the requester does with a failed job
  testing::expectNothingLeft(build.cache, build.build.prepared.key);
  const pid_t next = expectPing(pool);
  EXPECT_NE(next, first_worker);
  EXPECT_EQ(pool.stats().timed_out, 1u);
  EXPECT_EQ(pool.stats().workers_started, 2u);
}

TEST(WorkerPool, AWorkerThatNeverAnswersTimesOut) {
  TempDir dir;
  WorkerPoolOptions options = workerPoolOptions(1);
  options.worker_executable = dir.script("silent-worker", "exec sleep 60\n");
  WorkerPool pool(options);
  const pid_t silent = pool.workers().at(0).pid;
  const auto r = resultOf(pool.submit(pingRequest(), {}, 300ms));
  ASSERT_TRUE(r.has_value());
  EXPECT_EQ(r->state, JobState::TimedOut);
  EXPECT_TRUE(textContains(r->message, "the limit is 0.3 s")) << r->message;
  EXPECT_TRUE(testing::waitFor([&] { return testing::processIsDead(silent); }, 5s));
  EXPECT_TRUE(testing::waitFor([&] {
    const auto w = pool.workers();
    return w.size() == 1 && w[0].pid != silent;
  })) << "no worker replaced the one killed";
}

TEST(WorkerPool, AWorkerKilledAsItTakesAJobCrashesOnlyThatJob) {
  WorkerPool pool(workerPoolOptions(1));
  JobCallbacks callbacks;
  std::atomic<pid_t> killed{0};
  callbacks.on_start = [&](pid_t worker) {
    killed = worker;
    ::kill(worker, SIGKILL);
  };
  const auto r = resultOf(pool.submit(pingRequest(), callbacks));
  ASSERT_TRUE(r.has_value());
  EXPECT_EQ(r->state, JobState::Crashed);
  EXPECT_EQ(r->message,
            "worker " + std::to_string(killed.load()) + " was killed by signal 9 (SIGKILL) during the job");
  EXPECT_EQ(r->worker_pid, killed.load());
  const pid_t next = expectPing(pool);
  EXPECT_NE(next, killed.load());
  EXPECT_EQ(pool.stats().crashed, 1u);
  EXPECT_EQ(pool.stats().workers_started, 2u);
}

TEST(WorkerPool, AWorkerKilledMidCompileLeavesNothingBehind) {
  WorkerPool pool(workerPoolOptions(1));
  SleepingBuild build;
  std::atomic<pid_t> worker{0};
  std::atomic<bool> compiling{false};
  JobCallbacks callbacks;
  callbacks.on_start = [&](pid_t pid) { worker = pid; };
  callbacks.on_progress = [&](const std::string& message) {
    if (json::parse(message).at("stage") == "compile") compiling = true;
  };
  const JobHandle handle = pool.submit(build.message(), callbacks);
  ASSERT_TRUE(testing::waitFor([&] { return build.compilerStarted(); })) << "the compiler did not start";
  EXPECT_TRUE(testing::waitFor([&] { return compiling.load(); })) << "no \"compile\" progress message came";
  ASSERT_EQ(::kill(worker, SIGKILL), 0);

  const auto r = resultOf(handle);
  ASSERT_TRUE(r.has_value());
  EXPECT_EQ(r->state, JobState::Crashed);
  EXPECT_TRUE(textContains(r->message, "worker " + std::to_string(worker.load()) + " was killed by signal 9 (SIGKILL)"))
      << r->message;
  build.expectCompilerGone();
  build.cache.abandon(build.build.request.claim);
  testing::expectNothingLeft(build.cache, build.build.prepared.key);
  EXPECT_NE(expectPing(pool), worker.load());
}

TEST(WorkerPool, CancelsQueuedAndRunningJobs) {
  WorkerPool pool(workerPoolOptions(1));
  SleepingBuild build;
  const JobHandle running = pool.submit(build.message());
  const JobHandle queued = pool.submit(pingRequest());
  ASSERT_TRUE(testing::waitFor([&] { return build.compilerStarted(); })) << "the compiler did not start";

  EXPECT_TRUE(pool.cancel(queued.id));
  ASSERT_EQ(queued.result.wait_for(0s), std::future_status::ready) << "a queued job's cancellation is immediate";
  EXPECT_EQ(queued.result.get().state, JobState::Cancelled);
  EXPECT_EQ(queued.result.get().message, "cancelled before it ran");

  const pid_t worker = pool.workers().at(0).pid;
  EXPECT_TRUE(pool.cancel(running.id));
  const auto r = resultOf(running);
  ASSERT_TRUE(r.has_value());
  EXPECT_EQ(r->state, JobState::Cancelled);
  EXPECT_TRUE(textContains(r->message, "cancelled while running on worker " + std::to_string(worker))) << r->message;
  build.expectCompilerGone();

  EXPECT_FALSE(pool.cancel(running.id)) << "a finished job cannot be cancelled";
  EXPECT_FALSE(pool.cancel(queued.id));
  EXPECT_FALSE(pool.cancel(987654321));
  build.cache.abandon(build.build.request.claim);
  testing::expectNothingLeft(build.cache, build.build.prepared.key);
  EXPECT_NE(expectPing(pool), worker);
  EXPECT_EQ(pool.stats().cancelled, 2u);
}

TEST(WorkerPool, StoppingThePoolCancelsJobsAndLeavesNoProcess) {
  SleepingBuild build;
  JobHandle running, queued;
  {
    WorkerPool pool(workerPoolOptions(1));
    running = pool.submit(build.message());
    queued = pool.submit(pingRequest());
    ASSERT_TRUE(testing::waitFor([&] { return build.compilerStarted(); })) << "the compiler did not start";
  }
  for (const JobHandle* h : {&running, &queued})
    ASSERT_EQ(h->result.wait_for(0s), std::future_status::ready) << "the pool stopped without setting a result";
  EXPECT_EQ(running.result.get().state, JobState::Cancelled);
  EXPECT_TRUE(textContains(running.result.get().message, "the pool stopped while the job ran"))
      << running.result.get().message;
  EXPECT_EQ(queued.result.get().state, JobState::Cancelled);
  EXPECT_EQ(queued.result.get().message, "the pool stopped before the job ran");
  build.expectCompilerGone();
  build.cache.abandon(build.build.request.claim);

  { WorkerPool idle(workerPoolOptions(2)); }  // idle workers leave on end of input

  int status;
  errno = 0;
  EXPECT_EQ(::waitpid(-1, &status, WNOHANG), -1) << "a child process (or zombie) is left";
  EXPECT_EQ(errno, ECHILD);
}

}  // namespace
}  // namespace robodiff::workers
