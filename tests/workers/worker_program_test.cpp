// The robodiff-worker program as its pool sees it: the worker host (workers/worker_host.hpp)
// with the batch jobs its main (batch/jobs/src/worker_main.cpp) adds. --help and errors
// name every request type; batch requests reach the batch jobs, whose progress and
// results travel back as frames.
#include <fstream>
#include <future>
#include <mutex>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "robodiff/workers/worker_pool.hpp"
#include "support/process.hpp"
#include "worker_fixtures.hpp"

namespace robodiff::workers {
namespace worker_program_test {

using namespace std::chrono_literals;
using nlohmann::json;
using testing::TempDir;

class WorkerHost : public ::testing::Test {
 protected:
  WorkerPoolOptions options() const {
    WorkerPoolOptions o;
    o.worker_executable = testing::workerPath();
    o.workers = 1;
    o.default_timeout = 60s;
    return o;
  }

  // The result of one request; fails the test when none comes within 60 s.
  JobResult answer(const json& request, JobCallbacks callbacks = {}) {
    const JobHandle handle = pool_.submit(request.dump(), std::move(callbacks));
    if (handle.result.wait_for(60s) != std::future_status::ready) {
      ADD_FAILURE() << "no answer to " << request.dump() << " within 60 s";
      return {};
    }
    return handle.result.get();
  }

  // A batch request's failure message (the job must fail).
  std::string batchFailure(const json& request) {
    const JobResult r = answer({{"type", "batch"}, {"request", request}});
    EXPECT_EQ(r.state, JobState::Failed) << r.reply;
    return r.message;
  }

  WorkerPool pool_{options()};
};

TEST_F(WorkerHost, HelpListsEveryRequestType) {
  const testing::ProcessResult help = testing::runCommand(testing::shellQuote(testing::workerPath()) + " --help");
  EXPECT_EQ(help.exit_code, 0) << help.err;
  EXPECT_NE(help.out.find("Usage: robodiff-worker"), std::string::npos) << help.out;
  for (const char* line : {"\n  batch   runs a batch job (trajectory, identify, trajopt)", "\n  build   compiles a function",
                           "\n  ping    a health check"})
    EXPECT_NE(help.out.find(line), std::string::npos) << "no line '" << line << "' in:\n" << help.out;
}

TEST_F(WorkerHost, AnUnknownTypeIsAnsweredWithEveryKnownType) {
  const JobResult r = answer({{"type", "frobnicate"}});
  EXPECT_EQ(r.state, JobState::Failed);
  EXPECT_NE(r.message.find("unknown request type \"frobnicate\" (this worker knows: batch, build, ping)"),
            std::string::npos)
      << r.message;
  EXPECT_EQ(answer({{"type", "ping"}}).state, JobState::Succeeded);  // the worker is still there
}

TEST_F(WorkerHost, BadBatchRequestsAreRefusedByName) {
  TempDir dir;
  EXPECT_NE(answer({{"type", "batch"}}).message.find("a batch request needs a \"request\" object"), std::string::npos);
  EXPECT_NE(batchFailure({{"kind", "trajectory"}}).find("a batch request needs a \"result_dir\""), std::string::npos);
  EXPECT_NE(batchFailure({{"kind", "trajectory"}, {"result_dir", dir.path().string()}, {"readable_dirs", "/"}})
                .find("\"readable_dirs\" must be an array of paths"),
            std::string::npos);
  const std::string unknown = batchFailure({{"kind", "frobnicate"}, {"result_dir", dir.path().string()}});
  EXPECT_NE(unknown.find("unknown job kind 'frobnicate' (this build runs: trajectory, identify, trajopt)"),
            std::string::npos)
      << unknown;
  EXPECT_EQ(answer({{"type", "ping"}}).state, JobState::Succeeded);
}

// arm7's RNEA (interpreted) at three knots: the job's files, result and progress.
TEST_F(WorkerHost, ABatchJobRunsAndReportsItsProgress) {
  TempDir dir;
  std::string header;  // q_0..q_6, v_0..v_6, a_0..a_6
  for (const char* block : {"q", "v", "a"})
    for (int i = 0; i < 7; ++i) header += (header.empty() ? "" : ",") + std::string(block) + "_" + std::to_string(i);
  std::ofstream csv(dir / "trajectory.csv");
  csv << header << "\n";
  for (int k = 1; k <= 3; ++k) {
    for (int i = 0; i < 21; ++i) csv << (i ? "," : "") << 0.1 * k;
    csv << "\n";
  }
  csv.close();
  std::filesystem::create_directories(dir / "result");
  const json request = {{"kind", "trajectory"},
                        {"params",
                         {{"urdf", (testing::sourceDir() / "examples/robots/arm7.urdf").string()},
                          {"spec_json", json::parse(testing::kRneaValueSpec)},
                          {"data", (dir / "trajectory.csv").string()},
                          {"backend", "interpreted"}}},
                        {"result_dir", (dir / "result").string()},
                        {"readable_dirs", {testing::sourceDir().string(), dir.path().string()}}};
  std::mutex mutex;
  std::vector<json> progress;
  JobCallbacks callbacks;
  callbacks.on_progress = [&](const std::string& message) {
    const std::lock_guard lock(mutex);
    progress.push_back(json::parse(message));
  };
  const JobResult r = answer({{"type", "batch"}, {"request", request}}, callbacks);
  ASSERT_EQ(r.state, JobState::Succeeded) << r.message << "\n" << r.reply;
  const json result = json::parse(r.reply).at("result");
  EXPECT_EQ(result.at("knots"), 3);
  EXPECT_EQ(result.at("backend"), "interpreted");
  EXPECT_TRUE(std::filesystem::exists(dir / "result" / result.at("out").get<std::string>()));
  const std::lock_guard lock(mutex);
  ASSERT_FALSE(progress.empty());
  EXPECT_EQ(progress.back().at("type"), "progress");
  EXPECT_EQ(progress.back().at("fraction"), 1.0);
  EXPECT_EQ(progress.back().at("message"), "wrote outputs.csv");
}

}  // namespace worker_program_test
}  // namespace robodiff::workers
