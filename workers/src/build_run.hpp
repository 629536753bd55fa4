// One CachedBuilder::buildAll call: every target's way through the cache and the worker
// pool (prepare, claim or wait, submit, retry a dead worker's build, finish), the thread
// that renews the claims workers build under, and the statuses reported to the listener.
#pragma once

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <mutex>
#include <optional>
#include <thread>
#include <vector>

#include "robodiff/workers/build_job.hpp"
#include "robodiff/workers/cached_builder.hpp"

namespace robodiff::workers {

class BuildRun {
 public:
  BuildRun(cache::Cache& cache, WorkerPool& pool, const CachedBuilderOptions& options,
           std::atomic<std::uint64_t>& worker_death_retries, const CachedBuilder::Listener& listener);
  ~BuildRun();  // stops and joins the renewal thread
  BuildRun(const BuildRun&) = delete;
  BuildRun& operator=(const BuildRun&) = delete;

  // Builds every target; returns their final statuses in order.
  std::vector<BuildStatus> execute(const std::vector<BuildTarget>& targets);

 private:
  using Clock = std::chrono::steady_clock;
  // One target on its way through the cache and the pool.
  struct Work {
    BuildTarget target;
    BuildStatus status;
    Clock::time_point started;
    std::optional<cache::PreparedBuild> prepared;
    BuildRequest request;               // all but the claim, filled when prepared
    std::optional<cache::Claim> claim;  // held by this process while a worker builds
    std::optional<JobHandle> job;
    unsigned attempts = 0;                      // jobs submitted for it
    std::optional<Clock::time_point> retry_at;  // its worker died: submit again then (claim kept)
  };
  struct Robot {
    std::string urdf;
    std::shared_ptr<const Model> model;
    std::string hash;  // canonicalHash(*model), once per robot
  };

  // The "caller holds mutex_" helpers.
  void publishStatus(std::size_t i);
  void setState(std::size_t i, BuildState state, std::string message = {});

  void prepareAll(const std::vector<BuildTarget>& targets);
  void prepare(std::size_t i, const BuildTarget& target, Robot& robot);
  void startRenewing();
  void renewClaims();
  // One look at a target that is not final; returns false once it is.
  bool advance(std::size_t i);
  void claimAndSubmit(std::size_t i, std::unique_lock<std::mutex>& lock);
  void finishJob(std::size_t i, const JobResult& result);
  void submitBuild(std::size_t i, std::unique_lock<std::mutex>& lock);
  void retryBuild(std::size_t i, std::unique_lock<std::mutex>& lock);
  void waitForProgress();

  cache::Cache& cache_;
  WorkerPool& pool_;
  const CachedBuilderOptions& options_;
  std::atomic<std::uint64_t>& worker_death_retries_;
  const CachedBuilder::Listener& listener_;
  unsigned max_attempts_;

  std::mutex mutex_;  // guards every Work and serialises the listener
  std::condition_variable changed_;
  std::vector<Work> work_;
  bool stop_renewing_ = false;
  std::thread renewer_;
};

}  // namespace robodiff::workers
