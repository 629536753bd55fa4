// The job manager's bounded queue: with a job running and the queue full, a submission
// is RESOURCE_EXHAUSTED, naming the capacity. That job is recorded FAILED ("the job queue
// was full") and leaves no directory, while the running and the waiting jobs keep theirs.
// The worker is a real process that takes a job and never answers.
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

#include "robodiff/server/job_manager.hpp"
#include "support/temp_dir.hpp"

namespace robodiff::server {
namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;

// A worker program that reads no request and answers none until it is killed.
fs::path silentWorker(const fs::path& dir) {
  const fs::path program = dir / "silent-worker";
  std::ofstream(program) << "#!/bin/sh\nexec sleep 600\n";
  fs::permissions(program, fs::perms::owner_all);
  return program;
}

rpc::JobInfo jobInfo(JobManager& jobs, const JobCaller& caller, const std::string& id) {
  rpc::JobStatusReply reply;
  const Status s = jobs.status(caller, {id}, reply);
  EXPECT_TRUE(s.ok()) << s.message;
  return reply.jobs.empty() ? rpc::JobInfo{} : reply.jobs.front();
}

TEST(JobQueue, ASubmissionBeyondTheQueueIsFailedAndLeavesNoDirectory) {
  robodiff::testing::TempDir dir;
  std::FILE* log_file = std::tmpfile();
  ASSERT_NE(log_file, nullptr);
  Logger log(log_file);
  JobManagerOptions options;
  options.cache_dir = dir.path() / "cache";
  options.workers = 1;
  options.worker_executable = silentWorker(dir.path()).string();
  options.queue_capacity = 1;
  options.timeout = 60s;
  const JobCaller alice{"alice"};
  const fs::path jobs_dir = options.cache_dir / "jobs";
  {
    JobManager jobs(options, log);
    auto submit = [&](rpc::SubmitJobReply& reply) { return jobs.submit(alice, {"queue-test", "{}"}, reply); };
    rpc::SubmitJobReply running, waiting, refused;
    ASSERT_TRUE(submit(running).ok());
    const auto deadline = std::chrono::steady_clock::now() + 20s;
    while (jobInfo(jobs, alice, running.job_id).state != rpc::JobState::Running &&
           std::chrono::steady_clock::now() < deadline)
      std::this_thread::sleep_for(10ms);
    ASSERT_EQ(jobInfo(jobs, alice, running.job_id).state, rpc::JobState::Running) << "the worker never took the job";
    ASSERT_TRUE(submit(waiting).ok());

    const Status full = submit(refused);
    EXPECT_EQ(full.code, StatusCode::ResourceExhausted) << full.message;
    EXPECT_NE(full.message.find("1 jobs are already waiting"), std::string::npos) << full.message;
    EXPECT_TRUE(refused.job_id.empty());

    rpc::JobStatusReply all;
    ASSERT_TRUE(jobs.status(alice, {""}, all).ok());
    ASSERT_EQ(all.jobs.size(), 3u);
    std::vector<std::string> failed;
    for (const rpc::JobInfo& j : all.jobs) {
      if (j.job_id == running.job_id) {
        EXPECT_EQ(j.state, rpc::JobState::Running);
      } else if (j.job_id == waiting.job_id) {
        EXPECT_EQ(j.state, rpc::JobState::Queued);
      } else {
        failed.push_back(j.job_id);
        EXPECT_EQ(j.state, rpc::JobState::Failed);
        EXPECT_NE(j.error.find("the job queue was full"), std::string::npos) << j.error;
      }
    }
    ASSERT_EQ(failed.size(), 1u);
    EXPECT_FALSE(fs::exists(jobs_dir / (failed[0] + ".partial"))) << "the refused job's directory is left";
    EXPECT_TRUE(fs::exists(jobs_dir / (running.job_id + ".partial")));
    EXPECT_TRUE(fs::exists(jobs_dir / (waiting.job_id + ".partial")));
  }  // the manager stops: the silent worker is killed, the two jobs end FAILED
  std::fclose(log_file);
}

}  // namespace
}  // namespace robodiff::server
